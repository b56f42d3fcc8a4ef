"""dem_intersection: monoplotting on a rough, steep DEM."""

from __future__ import annotations

import numpy as np
from affine import Affine

from photodem.algorithms.geometry.dem_intersection import (
    intersect_rays_dem,
    pixel_to_ground,
)
from photodem.algorithms.geometry.projection import pixel_to_ray, world_to_pixel
from photodem.algorithms.raster.sample import DemSampler


def test_pixel_ground_pixel_round_trip(distorted_camera, tilted_eo, rough_dem):
    cam, eo, dem = distorted_camera, tilted_eo, rough_dem
    rng = np.random.default_rng(11)
    c, r = rng.uniform(0, 1999, 5000), rng.uniform(0, 1499, 5000)
    P = pixel_to_ground(c, r, cam, eo, dem)
    ok = np.isfinite(P[:, 0])
    assert ok.mean() > 0.85
    c2, r2 = world_to_pixel(P[ok], cam, eo)
    assert np.max(np.abs(c2 - c[ok])) < 1e-6
    assert np.max(np.abs(r2 - r[ok])) < 1e-6
    # on the surface to < 1 mm
    assert np.max(np.abs(P[ok, 2] - dem.height(P[ok, 0], P[ok, 1]))) < 1e-3


def test_world_pixel_ray_dem_round_trip(distorted_camera, tilted_eo, rough_dem):
    cam, eo, dem = distorted_camera, tilted_eo, rough_dem
    rng = np.random.default_rng(12)
    x, y = rng.uniform(1060, 1240, 5000), rng.uniform(5060, 5240, 5000)
    X = np.column_stack([x, y, dem.height(x, y)])
    c, r = world_to_pixel(X, cam, eo)
    inside = (c >= 0) & (c <= 1999) & (r >= 0) & (r <= 1499)
    X, c, r = X[inside], c[inside], r[inside]
    P = pixel_to_ground(c, r, cam, eo, dem)
    err = np.linalg.norm(P - X, axis=1)
    match = err < 1e-3
    # where they differ, the truth is hidden: the ray met the DEM earlier, nearer to the camera
    dist_truth = np.linalg.norm(X - eo.position, axis=1)
    dist_found = np.linalg.norm(P - eo.position, axis=1)
    assert np.all(dist_found[~match] < dist_truth[~match])
    assert match.mean() > 0.9  # most points are visible
    c2, r2 = world_to_pixel(P[match], cam, eo)
    assert np.max(np.hypot(c2 - c[match], r2 - r[match])) < 1e-6


def test_first_intersection_against_brute_force(distorted_camera, tilted_eo, rough_dem):
    # a dense march (1 cm steps) finds the same first crossing on cliffs and walls
    cam, eo, dem = distorted_camera, tilted_eo, rough_dem
    rng = np.random.default_rng(13)
    c, r = rng.uniform(0, 1999, 150), rng.uniform(0, 1499, 150)
    origin, d = pixel_to_ray(c, r, cam, eo)
    P = intersect_rays_dem(origin, d, dem)
    lam0 = (dem.max + 0.01 - origin[2]) / d[:, 2]
    lam = lam0[:, None] + np.arange(0, 9000) * 0.01
    pts = origin + lam[..., None] * d[:, None, :]
    f = pts[..., 2] - dem.height(pts[..., 0], pts[..., 1])
    stop = ~(f > 0)
    first = np.argmax(stop, axis=1)
    has = stop.any(axis=1) & np.isfinite(f[np.arange(150), first])
    lam_true = lam[np.arange(150), first]
    lam_found = np.linalg.norm(P - origin, axis=1)
    assert np.array_equal(has, np.isfinite(lam_found))
    np.testing.assert_allclose(lam_found[has], lam_true[has], atol=0.011)


def test_thin_wall_is_not_missed():
    # a 1-cell wide, 40 m high wall in flat terrain, seen by a low oblique ray
    z = np.zeros((50, 200))
    z[:, 100] = 40.0
    dem = DemSampler(z, Affine(1.0, 0, 0, 0, -1.0, 50.0))
    origin = np.array([[10.0, 25.0, 60.0]])
    target = np.array([[190.0, 25.0, 0.0]])  # behind the wall
    P = intersect_rays_dem(origin, target - origin, dem)
    assert P[0, 0] < 100.5  # stopped at the wall, not at the target
    assert abs(P[0, 2] - dem.height(P[0, 0], P[0, 1])) < 1e-3


def test_nan_where_ray_leaves_dem_or_meets_nodata():
    z = np.full((20, 20), 10.0)
    z[5:15, 5:15] = np.nan
    dem = DemSampler(z, Affine(1.0, 0, 0, 0, -1.0, 20.0))
    o = np.array([10.0, 10.0, 100.0])
    d = np.array([[0.0, 0.0, -1.0],  # into the hole
                  [0.0, 0.0, 1.0],  # upwards
                  [2.0, 0.0, -1.0],  # leaves the DEM sideways
                  [-0.07, 0.08, -1.0]])
    P = intersect_rays_dem(o, d, dem)
    assert np.isnan(P[:3]).all()
    z[5:15, 5:15] = 10.0
    P = intersect_rays_dem(o, d, DemSampler(z, dem.transform))
    np.testing.assert_allclose(P[3], o + 90.0 * d[3], atol=1e-6)
