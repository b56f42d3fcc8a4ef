"""camera: pixel ↔ image mm, Brown distortion both ways, pixel ↔ camera frame."""

from __future__ import annotations

import numpy as np
import pytest

from photodem.algorithms.errors import InputError
from photodem.algorithms.geometry.camera import Camera


def test_pixel_image_frame_and_centre(plain_camera):
    cam = plain_camera
    x, y = cam.pixel_to_image((cam.width - 1) / 2, (cam.height - 1) / 2)
    assert x == pytest.approx(0.0) and y == pytest.approx(0.0)
    x, y = cam.pixel_to_image(cam.width - 1, 0)  # top right: x > 0, y > 0 (y up)
    assert x > 0 and y > 0
    assert cam.focal_length_px == pytest.approx(10000.0)
    assert cam.gsd(1000.0) == pytest.approx(0.1)


def test_pixel_image_round_trip_with_principal_point(distorted_camera):
    cam = distorted_camera
    rng = np.random.default_rng(0)
    c, r = rng.uniform(-0.5, 1999.5, 1000), rng.uniform(-0.5, 1499.5, 1000)
    x, y = cam.pixel_to_image(c, r)
    c2, r2 = cam.image_to_pixel(x, y)
    np.testing.assert_allclose(c2, c, atol=1e-10)
    np.testing.assert_allclose(r2, r, atol=1e-10)
    xc, yc = cam.pixel_to_image((cam.width - 1) / 2, (cam.height - 1) / 2)
    assert (xc, yc) == pytest.approx((-0.12, 0.08))


def test_distortion_both_ways(distorted_camera):
    cam = distorted_camera
    rng = np.random.default_rng(1)
    x, y = rng.uniform(-10, 10, 5000), rng.uniform(-7.5, 7.5, 5000)
    xd, yd = cam.distort(x, y)
    shift_px = np.hypot(xd - x, yd - y) / 0.01
    assert shift_px.max() > 2.0  # the distortion is substantial
    xu, yu = cam.undistort(xd, yd)
    np.testing.assert_allclose(xu, x, atol=1e-9)  # 1e-9 mm = 1e-7 px
    np.testing.assert_allclose(yu, y, atol=1e-9)
    xd2, yd2 = cam.distort(*cam.undistort(x, y))
    np.testing.assert_allclose(xd2, x, atol=1e-9)
    np.testing.assert_allclose(yd2, y, atol=1e-9)


def test_distortion_matches_opencv_formula():
    # y up in image mm, y down in the normalised OpenCV frame
    cam = Camera("c", 100, 100, 50.0, (0.01, 0.01), k1=0.1, p1=0.01, p2=0.02)
    x, y = 2.0, 3.0
    xn, yn = x / 50.0, -y / 50.0
    r2 = xn * xn + yn * yn
    xe = xn * (1 + 0.1 * r2) + 2 * 0.01 * xn * yn + 0.02 * (r2 + 2 * xn * xn)
    ye = yn * (1 + 0.1 * r2) + 0.01 * (r2 + 2 * yn * yn) + 2 * 0.02 * xn * yn
    assert cam.distort(x, y) == pytest.approx((xe * 50.0, -ye * 50.0), abs=1e-12)


def test_pixel_camera_round_trip(distorted_camera):
    cam = distorted_camera
    rng = np.random.default_rng(2)
    c, r = rng.uniform(0, 1999, 2000), rng.uniform(0, 1499, 2000)
    p = cam.pixel_to_camera(c, r) * rng.uniform(0.5, 20.0, 2000)[:, None]
    c2, r2 = cam.camera_to_pixel(p)
    np.testing.assert_allclose(c2, c, atol=1e-7)
    np.testing.assert_allclose(r2, r, atol=1e-7)
    assert np.isnan(cam.camera_to_pixel([0.0, 0.0, 1.0])[0])  # behind the camera


def test_dict_round_trip_and_validation(distorted_camera):
    d = distorted_camera.to_dict()
    assert Camera.from_dict("dist", d) == distorted_camera
    with pytest.raises(InputError):
        Camera("bad", 0, 10, 100.0, (0.01, 0.01))
    with pytest.raises(InputError):
        Camera("bad", 10, 10, -1.0, (0.01, 0.01))
