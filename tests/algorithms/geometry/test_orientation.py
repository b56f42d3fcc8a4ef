"""orientation: ω-φ-κ, angle units, axis-angle and OpenSfM conversion."""

from __future__ import annotations

import numpy as np
import pytest

from photodem.algorithms.errors import InputError
from photodem.algorithms.geometry.orientation import (
    ExteriorOrientation,
    axis_angle_to_matrix,
    from_radians,
    matrix_to_axis_angle,
    matrix_to_opk,
    opensfm_to_patb,
    opk_to_matrix,
    to_radians,
)


def _rx(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def _ry(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def _rz(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def test_opk_matrix_is_rx_ry_rz_and_round_trips():
    rng = np.random.default_rng(3)
    opk = np.column_stack([rng.uniform(-179, 179, 200), rng.uniform(-89, 89, 200),
                           rng.uniform(-179, 179, 200)])
    R = opk_to_matrix(opk[:, 0], opk[:, 1], opk[:, 2], "degrees")
    w, p, k = np.radians(opk[7])
    np.testing.assert_allclose(R[7], _rx(w) @ _ry(p) @ _rz(k), atol=1e-14)
    np.testing.assert_allclose(R @ np.transpose(R, (0, 2, 1)), np.broadcast_to(np.eye(3), R.shape),
                               atol=1e-13)
    np.testing.assert_allclose(np.linalg.det(R), 1.0, atol=1e-13)
    np.testing.assert_allclose(matrix_to_opk(R, "degrees"), opk, atol=1e-10)


@pytest.mark.parametrize("unit, full", [("degrees", 360.0), ("gon", 400.0),
                                        ("radians", 2 * np.pi)])
def test_angle_units(unit, full):
    assert to_radians(full, unit) == pytest.approx(2 * np.pi)
    assert from_radians(np.pi / 2, unit) == pytest.approx(full / 4)
    a = np.array([0.1, -0.7, 1.3])
    np.testing.assert_allclose(to_radians(from_radians(a, unit), unit), a, atol=1e-15)
    R1 = opk_to_matrix(*from_radians(a, unit), unit=unit)
    np.testing.assert_allclose(R1, opk_to_matrix(*a, unit="radians"), atol=1e-15)
    with pytest.raises(InputError):
        to_radians(1.0, "grad")


def test_axis_angle_round_trip_including_near_pi():
    rng = np.random.default_rng(4)
    v = rng.normal(size=(300, 3))
    v *= (rng.uniform(0, np.pi - 1e-3, 300) / np.linalg.norm(v, axis=1))[:, None]
    v = np.vstack([v, [[np.pi, 0, 0], [0, 0, np.pi], [0, 0, 0], [1e-9, 0, 0]]])
    R = axis_angle_to_matrix(v)
    back = matrix_to_axis_angle(R)
    np.testing.assert_allclose(axis_angle_to_matrix(back), R, atol=1e-9)
    np.testing.assert_allclose(back[:300], v[:300], atol=1e-8)


def test_opensfm_round_trip_and_projection_agree():
    eo = ExteriorOrientation.from_opk([500.0, -200.0, 1500.0], 2.5, -1.5, 123.0)
    rot, t = eo.to_opensfm()
    back = opensfm_to_patb(rot, t)
    np.testing.assert_allclose(back.position, eo.position, atol=1e-9)
    np.testing.assert_allclose(back.rotation, eo.rotation, atol=1e-14)
    np.testing.assert_allclose(back.opk("gon"), eo.opk("gon"), atol=1e-10)
    # OpenCV camera (y down, z forward) sees the point where PATB says it is
    X = np.array([620.0, -130.0, 80.0])
    xc = axis_angle_to_matrix(rot) @ X + t
    p = eo.rotation.T @ (X - eo.position)
    assert xc[2] > 0 and p[2] < 0
    np.testing.assert_allclose(xc[:2] / xc[2], [-p[0] / p[2], p[1] / p[2]], atol=1e-14)


def test_viewing_direction_nadir():
    eo = ExteriorOrientation.from_opk([0, 0, 1000], 0.0, 0.0, 77.0)
    np.testing.assert_allclose(eo.viewing_direction, [0, 0, -1], atol=1e-15)
