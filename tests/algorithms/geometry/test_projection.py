"""projection: world → pixel, pixel → ray, ray at height."""

from __future__ import annotations

import numpy as np

from photodem.algorithms.geometry.orientation import ExteriorOrientation
from photodem.algorithms.geometry.projection import (
    pixel_to_ray,
    ray_at_height,
    world_to_camera,
    world_to_pixel,
)


def test_nadir_closed_form(plain_camera):
    # nadir, κ = 0: x = c·(X − X0)/H, pixel col = x/px + centre
    eo = ExteriorOrientation.from_opk([1000.0, 2000.0, 1100.0], 0, 0, 0)
    X = np.array([[1050.0, 1980.0, 100.0]])
    col, row = world_to_pixel(X, plain_camera, eo)
    assert col[0] == np.float64(999.5 + 100.0 * 50.0 / 1000.0 / 0.01)
    np.testing.assert_allclose(row, 749.5 + 100.0 * 20.0 / 1000.0 / 0.01)


def test_world_pixel_ray_round_trip(distorted_camera, tilted_eo):
    cam, eo = distorted_camera, tilted_eo
    rng = np.random.default_rng(5)
    c, r = rng.uniform(0, 1999, 3000), rng.uniform(0, 1499, 3000)
    h = rng.uniform(50.0, 200.0, 3000)
    X = ray_at_height(c, r, h, cam, eo)
    np.testing.assert_allclose(X[:, 2], h, atol=1e-9)
    c2, r2 = world_to_pixel(X, cam, eo)
    np.testing.assert_allclose(c2, c, atol=1e-6)
    np.testing.assert_allclose(r2, r, atol=1e-6)
    origin, d = pixel_to_ray(c, r, cam, eo)
    np.testing.assert_allclose(origin, eo.position)
    np.testing.assert_allclose(np.linalg.norm(d, axis=1), 1.0, atol=1e-14)
    # the ray direction points at the world point
    u = (X - origin) / np.linalg.norm(X - origin, axis=1, keepdims=True)
    np.testing.assert_allclose(u, d, atol=1e-12)


def test_behind_camera_is_nan(plain_camera):
    eo = ExteriorOrientation.from_opk([0.0, 0.0, 100.0], 0, 0, 0)
    col, _ = world_to_pixel([[0.0, 0.0, 200.0]], plain_camera, eo)
    assert np.isnan(col[0])
    assert world_to_camera([[0.0, 0.0, 0.0]], eo)[0, 2] == -100.0
    assert np.isnan(ray_at_height(0.0, 0.0, 300.0, plain_camera, eo)).all()
