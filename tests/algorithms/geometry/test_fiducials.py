"""fiducials: interior orientation of scanned film by a least-squares affine."""

from __future__ import annotations

import numpy as np
import pytest

from photodem.algorithms.errors import InputError
from photodem.algorithms.geometry.fiducials import camera_from_fiducials, fit_fiducials

# 8 marks of a 23 cm film camera: 4 corners and 4 side midpoints (mm, fiducial frame)
CAL = np.array([[-106.0, -106.0], [106.0, 106.0], [-106.0, 106.0], [106.0, -106.0],
                [-112.0, 0.0], [112.0, 0.0], [0.0, 112.0], [0.0, -112.0]])
# a scan at 20 µm, rotated by 0.3°, slightly sheared, x right / row down
ANG = np.radians(0.3)
A_TRUE = np.array([[0.02 * np.cos(ANG), 0.0201 * np.sin(ANG) + 1e-6, -115.0],
                   [0.02 * np.sin(ANG), -0.0201 * np.cos(ANG), 115.3]])


def _pixels(cal):
    lin, off = A_TRUE[:, :2], A_TRUE[:, 2]
    return (cal - off) @ np.linalg.inv(lin).T


def test_recovers_known_affine_exactly():
    fit = fit_fiducials(_pixels(CAL), CAL)
    np.testing.assert_allclose(fit.affine, A_TRUE, rtol=1e-10, atol=1e-10)
    assert fit.rms_um < 1e-6 and fit.sigma0_um < 1e-6
    assert fit.pixel_size_mm[0] == pytest.approx(0.02, rel=1e-6)
    assert fit.pixel_size_mm[1] == pytest.approx(0.0201, rel=1e-3)


def test_planted_errors_show_in_residuals():
    px = _pixels(CAL)
    px[2] += [1.5, -1.0]  # a mis-measured mark (1.8 px ≈ 36 µm)
    fit = fit_fiducials(px, CAL)
    assert fit.n == 8
    assert np.argmax(fit.residual_norms_um) == 2
    assert fit.residual_norms_um[2] > 15.0
    assert fit.sigma0_um > 5.0
    # residuals in px are the µm residuals through the inverse affine
    np.testing.assert_allclose(fit.residuals_px @ A_TRUE[:, :2].T, fit.residuals_mm, atol=1e-6)
    rms = np.sqrt(np.mean(np.sum(fit.residuals_um ** 2, axis=1)))
    assert fit.rms_um == pytest.approx(rms)
    # Gaussian measuring noise of 0.25 px: σ0 estimates it
    rng = np.random.default_rng(0)
    cal = np.vstack([CAL] * 10)
    px = _pixels(cal) + rng.normal(0, 0.25, (80, 2))
    fit = fit_fiducials(px, cal)
    assert fit.sigma0_um == pytest.approx(0.25 * 20.0, rel=0.2)
    assert set(fit.to_dict()) >= {"affine", "residuals_um", "rms_um", "sigma0_um"}


def test_needs_four_marks_not_collinear():
    with pytest.raises(InputError, match="at least 4"):
        fit_fiducials(_pixels(CAL[:3]), CAL[:3])
    line = np.column_stack([np.linspace(-100, 100, 5), np.zeros(5)])
    with pytest.raises(InputError, match="line"):
        fit_fiducials(_pixels(line), line)
    with pytest.raises(InputError):
        fit_fiducials(np.zeros((4, 3)), np.zeros((4, 3)))


def test_camera_from_fiducials_maps_pixels_to_calibrated_frame():
    fit = fit_fiducials(_pixels(CAL), CAL)
    cam = camera_from_fiducials(fit, "rc30", 11500, 11500, 153.0, principal_point=(0.01, -0.02),
                                k1=1e-3)
    px = _pixels(CAL)
    x, y = cam.pixel_to_image(px[:, 0], px[:, 1])
    # image coordinates are relative to the principal point given in the fiducial frame
    np.testing.assert_allclose(np.column_stack([x, y]), CAL - [0.01, -0.02], atol=1e-9)
    c, r = cam.image_to_pixel(x, y)
    np.testing.assert_allclose(np.column_stack([c, r]), px, atol=1e-8)
    assert cam.k1 == 1e-3
    assert cam.focal_length_px == pytest.approx(153.0 / 0.02, rel=1e-6)
