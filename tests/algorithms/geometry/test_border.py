"""projection: the image outline (border pixels, border rays, border on a plane) and the two
footprints built on it (the polygon of geometry.stereo, the ortho's box on a DEM)."""

from __future__ import annotations

import numpy as np
import rasterio

from photodem.algorithms.geometry.orientation import ExteriorOrientation
from photodem.algorithms.geometry.projection import (
    border_at_height,
    border_pixels,
    border_rays,
    pixel_to_ray,
    world_to_pixel,
)
from photodem.algorithms.geometry.stereo import image_footprint
from photodem.algorithms.ortho.rectify import dem_footprint_box


def test_border_pixels_run_clockwise_through_the_corners(plain_camera):
    n = 5
    px = border_pixels(plain_camera, n)
    assert px.shape == (4 * n, 2)
    # every edge starts at its corner: top left, top right, bottom right, bottom left
    assert np.array_equal(px[::n], plain_camera.corners())
    w, h = plain_camera.width - 0.5, plain_camera.height - 0.5
    assert np.array_equal(px[:n, 1], np.full(n, -0.5))  # top edge, left to right
    assert np.all(np.diff(px[:n, 0]) > 0)
    assert np.array_equal(px[n:2 * n, 0], np.full(n, w))  # right edge, downwards
    assert np.array_equal(px[2 * n:3 * n, 1], np.full(n, h))  # bottom edge, leftwards
    assert np.all(np.diff(px[2 * n:3 * n, 0]) < 0)
    assert np.array_equal(px[3 * n:, 0], np.full(n, -0.5))  # left edge, upwards
    # even spacing t = k / n along each edge
    np.testing.assert_allclose(px[:n, 0], -0.5 + np.arange(n) / n * plain_camera.width)


def test_border_rays_unit_and_unscaled(distorted_camera, tilted_eo):
    px, origin, d = border_rays(distorted_camera, tilted_eo, 7)
    o2, d2 = pixel_to_ray(px[:, 0], px[:, 1], distorted_camera, tilted_eo)
    assert np.array_equal(origin, o2) and np.array_equal(d, d2)
    _, _, raw = border_rays(distorted_camera, tilted_eo, 7, unit=False)
    # the same directions, scaled by the length of (x, y, −c) in mm
    np.testing.assert_allclose(raw / np.linalg.norm(raw, axis=1, keepdims=True), d,
                               atol=1e-12)
    assert np.all(np.linalg.norm(raw, axis=1) >= distorted_camera.focal_length)


def test_border_at_height_nadir_closed_form(plain_camera):
    # nadir at H = 1000 m over Z = 100: the outline is the sensor (20 mm × 15 mm) × H / c
    eo = ExteriorOrientation.from_opk([500.0, 800.0, 1100.0], 0, 0, 0)
    pts = border_at_height(plain_camera, eo, 100.0, per_edge=4)
    assert np.array_equal(pts[:, 2], np.full(16, 100.0))
    np.testing.assert_allclose(pts[0, :2], [500.0 - 100.0, 800.0 + 75.0], atol=1e-9)
    np.testing.assert_allclose(pts[8, :2], [500.0 + 100.0, 800.0 - 75.0], atol=1e-9)
    # every outline point projects back onto the image border
    col, row = world_to_pixel(pts, plain_camera, eo)
    np.testing.assert_allclose(np.stack([col, row], 1), border_pixels(plain_camera, 4),
                               atol=1e-6)


def test_ortho_box_holds_the_footprint_over_the_dem_height_range(distorted_camera, tilted_eo,
                                                                  rough_dem, tmp_path):
    path = tmp_path / "dem.tif"
    with rasterio.open(path, "w", driver="GTiff", width=rough_dem.shape[1],
                       height=rough_dem.shape[0], count=1, dtype="float32",
                       transform=rough_dem.transform) as dst:
        dst.write(rough_dem.array.astype(np.float32), 1)
    with rasterio.open(path) as ds:
        box, mean_z, max_z = dem_footprint_box(distorted_camera, tilted_eo, ds, "a")
    assert rough_dem.min <= mean_z <= max_z <= rough_dem.max
    # the polygon at one height lies inside the box (as far as the DEM reaches)
    b = rough_dem.bounds
    poly = image_footprint(distorted_camera, tilted_eo, height=mean_z)
    x0, y0, x1, y1 = poly.bounds
    assert box[0] <= max(x0, b[0]) + 1.0 and box[2] >= min(x1, b[2]) - 1.0
    assert box[1] <= max(y0, b[1]) + 1.0 and box[3] >= min(y1, b[3]) - 1.0

