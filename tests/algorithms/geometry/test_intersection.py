"""intersection: forward intersection of 2…N rays with precision."""

from __future__ import annotations

import numpy as np
import pytest

from photodem.algorithms.geometry.camera import Camera
from photodem.algorithms.geometry.intersection import (
    forward_intersection,
    intersect_pair,
    normal_case_sigma_z,
)
from photodem.algorithms.geometry.orientation import ExteriorOrientation
from photodem.algorithms.geometry.projection import world_to_pixel


def _observe(X, cams, eos):
    cols, rows = [], []
    for cam, eo in zip(cams, eos):
        c, r = world_to_pixel(X, cam, eo)
        inside = (c >= 0) & (c <= cam.width - 1) & (r >= 0) & (r <= cam.height - 1)
        cols.append(np.where(inside, c, np.nan))
        rows.append(np.where(inside, r, np.nan))
    return np.column_stack(cols), np.column_stack(rows)


def test_noise_free_multi_ray_reproduces_truth(distorted_camera):
    cam = distorted_camera
    eos = [ExteriorOrientation.from_opk([x, y, 1100.0 + dz], w, p, k) for x, y, dz, w, p, k in [
        (0.0, 0.0, 0.0, 2.0, -1.5, 3.0), (80.0, 4.0, 5.0, -2.5, 2.0, -4.0),
        (160.0, -3.0, -8.0, 1.0, 3.0, 10.0), (80.0, 110.0, 2.0, 3.0, -2.0, 181.0)]]
    cams = [cam] * 4
    rng = np.random.default_rng(21)
    X = np.column_stack([rng.uniform(30, 130, 3000), rng.uniform(-20, 60, 3000),
                         rng.uniform(50, 150, 3000)])
    cols, rows = _observe(X, cams, eos)
    res = forward_intersection(cols, rows, cams, eos)
    ok = res.n_rays >= 2
    assert ok.mean() > 0.9 and (res.n_rays[ok] >= 3).any()
    assert np.all(np.isnan(res.xyz[~ok]))
    err = np.abs(res.xyz[ok] - X[ok])
    assert np.max(err[:, 2] / np.abs(X[ok, 2])) < 1e-6
    assert np.max(err) < 1e-4
    assert np.nanmax(np.abs(res.residuals)) < 1e-6


def test_normal_case_sigma_z_confirmed_with_noise():
    cam = Camera("n", 6000, 4000, 100.0, (0.01, 0.01))  # 600 m × 400 m footprint at H
    H, B = 1000.0, 360.0  # 60 % forward overlap
    gsd = float(cam.gsd(H))
    eos = [ExteriorOrientation.from_opk([0.0, 0.0, H], 0, 0, 0),
           ExteriorOrientation.from_opk([B, 0.0, H], 0, 0, 0)]
    rng = np.random.default_rng(22)
    n = 4000
    X = np.column_stack([rng.uniform(70, 290, n), rng.uniform(-190, 190, n), np.zeros(n)])
    cols, rows = _observe(X, [cam, cam], eos)
    sigma = 0.3
    cols_n = cols + rng.normal(0, sigma, cols.shape)
    rows_n = rows + rng.normal(0, sigma, rows.shape)
    res = intersect_pair(cols_n[:, 0], rows_n[:, 0], cols_n[:, 1], rows_n[:, 1], (cam, cam),
                         (eos[0], eos[1]), sigma_px=sigma)
    assert np.isfinite(res.xyz).all()
    dz = res.xyz[:, 2] - X[:, 2]
    emp = np.std(dz)
    # σ_Z = (H/B)·GSD·σ_p with σ_p = √2·σ for the x-parallax of two independent measurements
    theory = float(normal_case_sigma_z(H, B, gsd, np.sqrt(2) * sigma))
    assert emp == pytest.approx(theory, rel=0.1)
    # reported σ's: a priori and a posteriori match the empirical ones
    emp_xyz = np.std(res.xyz - X, axis=0)
    np.testing.assert_allclose(np.sqrt(np.mean(res.sigma_apriori ** 2, axis=0)), emp_xyz,
                               rtol=0.1)
    np.testing.assert_allclose(np.sqrt(np.mean(res.sigma_aposteriori ** 2, axis=0)), emp_xyz,
                               rtol=0.1)
    assert np.sqrt(np.mean(res.sigma0 ** 2)) == pytest.approx(sigma, rel=0.1)


def test_sigma_reported_matches_empirical_tilted_three_rays(distorted_camera):
    cam = distorted_camera
    eos = [ExteriorOrientation.from_opk([x, 0.0, 1000.0], w, p, k) for x, w, p, k in [
        (0.0, 2.0, -1.0, 5.0), (70.0, -1.0, 2.0, -3.0), (140.0, 1.5, 1.0, 2.0)]]
    rng = np.random.default_rng(23)
    n = 3000
    X = np.column_stack([rng.uniform(45, 95, n), rng.uniform(-40, 40, n),
                         rng.uniform(-30, 30, n)])
    cols, rows = _observe(X, [cam] * 3, eos)
    keep = np.isfinite(cols).all(axis=1) & np.isfinite(rows).all(axis=1)
    X, cols, rows = X[keep], cols[keep], rows[keep]
    sigma = 0.5
    res = forward_intersection(cols + rng.normal(0, sigma, cols.shape),
                               rows + rng.normal(0, sigma, rows.shape), [cam] * 3, eos,
                               sigma_px=sigma)
    emp = np.std(res.xyz - X, axis=0)
    # σ per point varies with the point: compare normalised errors
    z_score = (res.xyz - X) / res.sigma_apriori
    np.testing.assert_allclose(np.std(z_score, axis=0), 1.0, rtol=0.1)
    np.testing.assert_allclose(np.sqrt(np.mean(res.sigma_apriori ** 2, axis=0)), emp, rtol=0.1)
    assert np.sqrt(np.mean(res.sigma0 ** 2)) == pytest.approx(sigma, rel=0.1)
    # mask: dropping the third image still intersects with two rays
    mask = np.ones(cols.shape, bool)
    mask[:, 2] = False
    res2 = forward_intersection(cols, rows, [cam] * 3, eos, mask=mask)
    assert np.all(res2.n_rays == 2)
    assert np.all(np.isnan(res2.residuals[:, 2]))


def test_degenerate_rays_give_nan_not_an_error(plain_camera):
    cam = plain_camera
    eo = ExteriorOrientation.from_opk([0.0, 0.0, 1000.0], 0, 0, 0)
    eo2 = ExteriorOrientation.from_opk([50.0, 0.0, 1000.0], 0, 0, 0)
    cols = np.array([[1000.0, 1000.0], [1000.0, 500.0], [1000.0, np.nan]])
    rows = np.array([[700.0, 700.0], [700.0, 700.0], [700.0, 700.0]])
    res = forward_intersection(cols, rows, [cam, cam], [eo, eo])  # same centre twice
    assert np.isnan(res.xyz).all()
    res = forward_intersection(cols, rows, [cam, cam], [eo, eo2])
    assert np.isnan(res.xyz[[0, 2]]).all() and np.isfinite(res.xyz[1]).all()
    assert list(res.n_rays) == [2, 2, 1]
