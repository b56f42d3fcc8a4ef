"""Least-squares matching on synthetic textured patches with known affine + radiometric change."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage

from photodem.algorithms.matching.lsm import (
    FLAG_DIVERGED,
    FLAG_LOW_CORRELATION,
    FLAG_TEXTURELESS,
    describe_flags,
    lsm_match,
)

SIZE = 400


def _pair(M, t, gain=0.9, offset=10.0, noise=3.0, seed=0):
    """Left texture (σ 30) and right image R(x2) = offset + gain·L(M·x2 + t) + noise.

    Returns left, right and a function mapping left points to their true right positions.
    """
    rng = np.random.default_rng(seed)
    tex = ndimage.gaussian_filter(rng.standard_normal((SIZE, SIZE)), 1.5)
    tex = 100 + 30 * tex / tex.std()
    yy, xx = np.mgrid[0:SIZE, 0:SIZE].astype(float)
    lx = M[0, 0] * xx + M[0, 1] * yy + t[0]
    ly = M[1, 0] * xx + M[1, 1] * yy + t[1]
    right = offset + gain * ndimage.map_coordinates(tex, [ly, lx], order=3, mode="reflect")
    left = tex + rng.normal(0, noise, tex.shape)
    right = right + rng.normal(0, noise, tex.shape)
    Minv = np.linalg.inv(M)

    def truth(c, r):
        return (Minv[0, 0] * (c - t[0]) + Minv[0, 1] * (r - t[1]),
                Minv[1, 0] * (c - t[0]) + Minv[1, 1] * (r - t[1]))

    return left, right, truth


def _points(n, seed=1):
    rng = np.random.default_rng(seed)
    return rng.uniform(40, SIZE - 40, n), rng.uniform(40, SIZE - 40, n), rng


@pytest.mark.parametrize("jacobian", ["template", "search"])
def test_affine_accuracy_precision_and_pull_in(jacobian):
    M = np.array([[1.04, 0.06], [-0.03, 0.97]])
    left, right, truth = _pair(M, (1.3, -0.7), noise=3.0)  # SNR = 30/3 = 10
    c, r, rng = _points(800)
    tc, tr = truth(c, r)
    ang = rng.uniform(0, 2 * np.pi, c.size)
    res = lsm_match(left, right, c, r, tc + 2 * np.cos(ang), tr + 2 * np.sin(ang), window=21,
                    jacobian=jacobian)
    v = res.valid
    assert v.mean() >= 0.95, {describe_flags(f) for f in res.flags}
    ec, er = res.cols[v] - tc[v], res.rows[v] - tr[v]
    assert np.sqrt(np.mean(ec**2 + er**2)) <= 0.1
    # predicted σ within ×1.5 of the empirical one
    for e, s in ((ec, res.sigma_col[v]), (er, res.sigma_row[v])):
        ratio = np.std(e) / np.sqrt(np.mean(s.astype(float) ** 2))
        assert 1 / 1.5 <= ratio <= 1.5, ratio
    # the affine and the radiometry are recovered
    Minv = np.linalg.inv(M)
    assert np.allclose(np.median(res.params[v][:, [1, 2, 4, 5]], axis=0), Minv.ravel(),
                       atol=0.01)
    assert np.median(res.params[v, 7]) == pytest.approx(1 / 0.9, abs=0.02)
    assert np.median(res.corr[v]) > 0.9


def test_epipolar_model():
    M = np.array([[1.05, 0.04], [0.0, 1.0]])  # scale and shear in x only, rows correspond
    left, right, truth = _pair(M, (-2.2, 0.0), noise=2.0)
    c, r, rng = _points(600, seed=5)
    tc, tr = truth(c, r)
    assert np.allclose(tr, r)
    res = lsm_match(left, right, c, r, tc + rng.uniform(-2, 2, c.size), None, window=15,
                    model="epipolar")
    v = res.valid
    assert v.mean() >= 0.95
    assert np.sqrt(np.mean((res.cols[v] - tc[v]) ** 2)) <= 0.1
    assert np.allclose(res.rows, r) and np.all(res.sigma_row[v] == 0)
    assert res.cov.shape == (c.size, 5, 5)


def test_failures_are_flagged():
    M = np.eye(2)
    left, right, _ = _pair(M, (0.0, 0.0), noise=2.0)
    c, r, rng = _points(300, seed=7)
    # far start values: not silently accepted
    ang = rng.uniform(0, 2 * np.pi, c.size)
    res = lsm_match(left, right, c, r, c + 6 * np.cos(ang), r + 6 * np.sin(ang), window=15)
    wrong = np.hypot(res.cols - c, res.rows - r) > 0.5
    assert not np.any(res.valid & wrong)
    # textureless template and search
    flat = np.full((100, 100), 80.0)
    res = lsm_match(flat, flat, [50.0], [50.0], [50.5], [50.0], window=15)
    assert res.flags[0] & FLAG_TEXTURELESS and not res.valid[0]
    # noise-only patches: low correlation or divergence, never valid
    rng = np.random.default_rng(9)
    a, b = rng.normal(0, 1, (100, 100)), rng.normal(0, 1, (100, 100))
    res = lsm_match(a, b, np.full(50, 50.0), np.full(50, 50.0), np.full(50, 50.0),
                    np.full(50, 50.0), window=15)
    assert not res.valid.any()
    assert np.all(res.flags & (FLAG_LOW_CORRELATION | FLAG_DIVERGED | 4 | 32 | 1))
    # windows at the image border
    res = lsm_match(left, right, [3.0], [200.0], [3.0], [200.0], window=15)
    assert not res.valid[0] and describe_flags(res.flags[0]).startswith("outside")


def test_sampler_matches_bilinear_reference():
    """The batched sampler equals scipy's order-1 interpolation, for every axis fast path."""
    from photodem.algorithms.matching.lsm import _affine_sampler, _grid

    rng = np.random.default_rng(3)
    img = rng.normal(100, 30, (60, 80)).astype(np.float32)
    n = 200
    grid = _grid(4)
    for kind in ("affine", "rows_fixed", "shift"):
        p = np.zeros((n, 6))
        p[:, 0], p[:, 3] = rng.uniform(-2, 82, n), rng.uniform(-2, 62, n)
        p[:, 1] = p[:, 5] = 1.0
        if kind != "shift":
            p[:, 1] += rng.uniform(-0.1, 0.1, n)
            p[:, 2] = rng.uniform(-0.1, 0.1, n)
        if kind == "affine":
            p[:, 4] = rng.uniform(-0.1, 0.1, n)
            p[:, 5] += rng.uniform(-0.1, 0.1, n)
        vals, inside = _affine_sampler(img.ravel(), 80, 60, p, grid, 4)
        x = p[:, :1] + p[:, 1:2] * grid[0] + p[:, 2:3] * grid[1]
        y = p[:, 3:4] + p[:, 4:5] * grid[0] + p[:, 5:6] * grid[1]
        want_inside = (x.min(1) >= 0) & (x.max(1) <= 79) & (y.min(1) >= 0) & (y.max(1) <= 59)
        assert np.array_equal(inside, want_inside), kind
        assert 0 < inside.sum() < n
        ref = ndimage.map_coordinates(img.astype(float), [y[inside], x[inside]], order=1)
        assert np.allclose(vals[inside], ref, atol=1e-3), kind


@pytest.mark.parametrize("model", ["affine", "epipolar", "shift"])
def test_chunking_and_correlation(model):
    """Results do not depend on the chunk size; ρ equals the directly computed coefficient."""
    from photodem.algorithms.matching.lsm import extract_windows

    M = np.array([[1.02, 0.02], [0.0, 1.0]])
    left, right, truth = _pair(M, (0.8, 0.0), noise=2.0)
    c, r, rng = _points(150, seed=11)
    tc, tr = truth(c, r)
    start = tc + rng.uniform(-1, 1, c.size)
    a = lsm_match(left, right, c, r, start, tr, window=15, model=model, chunk=1024)
    b = lsm_match(left, right, c, r, start, tr, window=15, model=model, chunk=17)
    assert np.array_equal(a.flags, b.flags)
    assert np.allclose(a.params, b.params, atol=1e-9)
    assert np.allclose(a.sigma_col, b.sigma_col, rtol=1e-5, equal_nan=True)
    assert a.valid.mean() >= 0.9
    # ρ of the template and the search window at the final parameters (a pure shift check is
    # close enough when the affine is near identity: compare loosely)
    v = a.valid & (np.abs(a.params[:, [1, 2, 4, 5]] - [1, 0, 0, 1]).max(axis=1) < 0.05)
    g1, _ = extract_windows(left.astype(np.float32), c[v], r[v], 7)
    g2, _ = extract_windows(right.astype(np.float32), a.cols[v], a.rows[v], 7)
    rho = [np.corrcoef(x.ravel(), y.ravel())[0, 1] for x, y in zip(g1, g2)]
    assert np.median(np.abs(np.array(rho) - a.corr[v])) < 0.02
