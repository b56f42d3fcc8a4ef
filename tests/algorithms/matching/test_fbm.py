"""Feature-based matching: candidates, robust window consistency, one level on synthetic pairs."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage

from photodem.algorithms.matching.fbm import (
    candidate_pairs,
    correlation_candidates,
    detect_features,
    fbm_match,
    group_weighted_median,
    one_to_one,
    robust_plane_fit,
    window_components,
)


def _pair(h=320, w=320, tex=None, d0=6.0, bump=4.0, step=None, noise=2.0, seed=0):
    """Epipolar pair from a smooth disparity field D defined on the right grid.

    right(x, y) = 0.9·T(x + dfield(x, y), y) + 10 + noise, left = T + noise (T: textured image),
    D = d0 + 0.01·x + 0.005·y + a Gaussian bump (+ an optional step at x > step[0]).
    Returns left, right and truth(cols, rows) → true disparity of left points.
    """
    rng = np.random.default_rng(seed)
    if tex is None:
        t = ndimage.gaussian_filter(rng.standard_normal((h, w + 100)), 1.5)
        tex = 100 + 30 * t / t.std()

    def dfield(x, y):
        d = d0 + 0.01 * x + 0.005 * y + bump * np.exp(
            -(((x - 0.55 * w) / (0.15 * w)) ** 2 + ((y - 0.45 * h) / (0.15 * h)) ** 2))
        return d if step is None else d + step[1] * (x > step[0])

    yy, xr = np.mgrid[0:h, 0:w].astype(float)
    right = ndimage.map_coordinates(tex, [yy, xr + dfield(xr, yy) + 50], order=3, mode="reflect")
    right = 0.9 * right + 10 + rng.normal(0, noise, right.shape)
    left = tex[:, 50:50 + w] + rng.normal(0, noise, (h, w))

    def truth(c, r):
        x = c - dfield(c, r)
        for _ in range(30):  # fixed point of x_r = c − dfield(x_r)
            x = c - dfield(x, r)
        return dfield(x, r)

    return left.astype(np.float32), right.astype(np.float32), truth


def test_candidate_pairs_match_brute_force():
    rng = np.random.default_rng(3)
    ca, ra = rng.uniform(0, 200, 300), rng.uniform(0, 50, 300)
    cb, rb = rng.uniform(0, 200, 400), rng.uniform(0, 50, 400)
    lo = rng.uniform(-5, 5, 300)
    hi = lo + rng.uniform(0, 10, 300)
    hi[::17] = np.nan  # no prediction: no pairs
    ia, ib = candidate_pairs(ca, ra, cb, rb, lo, hi, row_tol=1.0)
    d = ca[:, None] - cb[None, :]
    ok = (np.abs(rb[None, :] - ra[:, None]) <= 1.0) & (d >= lo[:, None]) & (d <= hi[:, None])
    want = set(zip(*np.nonzero(ok)))
    assert set(zip(ia.tolist(), ib.tolist())) == want
    assert len(ia) == len(want)


def test_group_weighted_median_and_one_to_one():
    x = np.array([1.0, 5, 3, 10, 20, 30, 7.0])
    g = np.array([0, 0, 0, 1, 1, 1, 2])
    med = group_weighted_median(x, np.ones(7), g, 4)
    assert med[:3].tolist() == [3.0, 20.0, 7.0] and np.isnan(med[3])
    # a heavy weight pulls the median
    assert group_weighted_median(x, np.array([1, 1, 1, 1, 1, 5, 1.0]), g, 3)[1] == 30.0
    ia = np.array([0, 0, 1, 1, 2])
    ib = np.array([0, 1, 0, 2, 2])
    keep = one_to_one(ia, ib, np.array([0.9, 0.5, 0.95, 0.1, 0.3]), np.ones(5, bool))
    # a0→b0 loses b0 to a1 (0.95); a1's best is b0; a2 keeps b2
    assert keep.tolist() == [2, 4]


def test_robust_fit_removes_half_false_candidates():
    """Checklist 6: 50 % random false candidates, parameters within 0.1 px, all flagged."""
    rng = np.random.default_rng(7)
    ng, n_good = 60, 20
    truth = np.column_stack([rng.uniform(-3, 3, ng), rng.uniform(-1, 1, ng),
                             rng.uniform(-1, 1, ng)])
    g = np.repeat(np.arange(ng), 2 * n_good)
    u, v = rng.uniform(-0.5, 0.5, g.size), rng.uniform(-0.5, 0.5, g.size)
    r = truth[g, 0] + truth[g, 1] * u + truth[g, 2] * v + rng.normal(0, 0.1, g.size)
    false = np.tile(np.r_[np.zeros(n_good, bool), np.ones(n_good, bool)], ng)
    r[false] += rng.choice([-1, 1], false.sum()) * rng.uniform(1.5, 8, false.sum())
    w = rng.uniform(0.5, 2.0, g.size)
    fit = robust_plane_fit(u, v, r, w, g, ng)
    assert np.abs(fit.params[:, 0] - truth[:, 0]).max() < 0.1
    # slopes (per window size) from 20 points with σ 0.1 px: statistical error ≈ 0.08
    assert np.abs(fit.params[:, 1:] - truth[:, 1:]).max() < 0.3
    assert not fit.inlier[false].any()
    assert fit.inlier[~false].mean() > 0.98
    assert np.median(fit.sigma) == pytest.approx(0.3, abs=0.05)  # the σ floor


def test_window_components_split_by_barrier():
    bar = np.zeros((64, 96), bool)
    bar[:, 40] = True  # a vertical breakline through the middle window column
    grp = window_components(bar.shape, 32, bar)
    assert grp.n_groups == 2 * 3 + 2  # windows of the middle column split in two
    assert (grp.labels[bar] == 0).all()
    left_side = grp.of(np.array([38.0]), np.array([5.0]))[0]
    right_side = grp.of(np.array([42.0]), np.array([5.0]))[0]
    assert left_side != right_side
    # they are not neighbours (no edge across the barrier), but both touch their own side
    edges = {tuple(e) for e in grp.edges.tolist()}
    assert (left_side, right_side) not in edges
    assert (grp.of(np.array([20.0]), np.array([5.0]))[0], left_side) in edges


@pytest.fixture(scope="module")
def textured():
    return _pair()


def test_fbm_accuracy_single_level(textured):
    left, right, truth = textured
    res = fbm_match(left, right, 0.0, 20.0)
    e = res.disparity - truth(res.col, res.row)
    assert res.col.size > 0.008 * left.size  # ~1 % of the pixels
    assert np.median(np.abs(e)) <= 0.3
    assert np.mean(np.abs(e) <= 1.0) >= 0.95
    # self-diagnosis per window: planes, σ0 and counts
    ok = res.n_accepted >= 3
    assert ok.mean() > 0.8
    assert np.nanmedian(res.sigma0[ok]) < 0.3
    assert (res.n_candidates >= res.n_accepted).all()
    assert res.stats["accepted"] == res.col.size


def test_repetitive_texture_wrong_candidates_rejected():
    """Stripes (period 7 px) in a ±12 px search and a loose ρ ≥ 0.3: the window consistency
    removes the wrong candidates that pass the local similarity test."""
    rng = np.random.default_rng(11)
    h, w = 320, 320
    base = ndimage.gaussian_filter(rng.standard_normal((h, w + 100)), 1.5)
    xx = np.arange(w + 100)[None, :]
    tex = 100 + 20 * base / base.std() + 20 * np.sin(2 * np.pi * xx / 7.0)
    left, right, truth = _pair(h, w, tex=tex, noise=1.0, seed=11)
    res = fbm_match(left, right, 0.0, 24.0, rho_min=0.3)
    e = res.disparity - truth(res.col, res.row)
    assert res.stats["outliers"] >= 0.15 * res.stats["candidates"]
    assert res.stats["accepted"] > 800
    assert np.mean(np.abs(e) <= 1.0) >= 0.995


def test_bidirectional_check_at_occlusion():
    """A 12 px disparity step occludes a band: the left↔right check removes wrong matches."""
    left, right, truth = _pair(step=(160.0, 12.0), bump=0.0, seed=2)
    res = fbm_match(left, right, 0.0, 30.0)
    loose = fbm_match(left, right, 0.0, 30.0, bidir_tol=None)
    bad = np.sum(np.abs(res.disparity - truth(res.col, res.row)) > 1)
    bad_loose = np.sum(np.abs(loose.disparity - truth(loose.col, loose.row)) > 1)
    assert res.stats["bidir_rejected"] > 0 and loose.stats["bidir_rejected"] == 0
    assert bad < bad_loose
    assert bad <= 0.005 * res.col.size


def test_mask_and_nodata_single_level(textured):
    left, right, _ = textured
    left = left.copy()
    left[:, :20] = np.nan  # no data
    mask = np.zeros(left.shape, bool)
    mask[100:180, 100:180] = True
    res = fbm_match(left, right, 0.0, 20.0, mask=mask)
    ci, ri = np.rint(res.col).astype(int), np.rint(res.row).astype(int)
    assert not mask[ri, ci].any()
    assert res.col.min() > 20


def test_correlation_candidates_find_a_known_shift():
    """Constant shift 7.3 px: the best NCC maximum of every point is at 7.3 ± 0.15 px."""
    rng = np.random.default_rng(5)
    t = ndimage.gaussian_filter(rng.standard_normal((120, 300)), 1.5)
    tex = 100 + 30 * t / t.std()
    yy, xx = np.mgrid[0:120, 0:260].astype(float)
    right = ndimage.map_coordinates(tex, [yy, xx + 7.3], order=3)
    left = tex[:, :260]
    ca, ra = rng.uniform(30, 230, 200), rng.integers(10, 110, 200).astype(float)
    lo = np.full(200, 2.0)
    hi = np.full(200, 14.0)
    hi[::10] = np.nan  # no prediction: no candidates
    ia, d, rho = correlation_candidates(left.astype(np.float32), right.astype(np.float32), ca,
                                        ra, lo, hi, window=7, rho_min=0.6, max_peaks=1)
    assert not np.isin(np.arange(0, 200, 10), ia).any()
    assert ia.size >= 175 and np.unique(ia).size == ia.size
    # fractional point positions carry over: d refers to the sub-pixel point itself
    assert np.median(np.abs(d - 7.3)) < 0.1 and np.abs(d - 7.3).max() < 0.5
    assert (rho >= 0.6).all()
    # several maxima per point, the best first; none on the ends of the range
    ia3, d3, _ = correlation_candidates(left.astype(np.float32), right.astype(np.float32), ca,
                                        ra, lo, hi, window=7, rho_min=0.0, max_peaks=3)
    assert np.bincount(ia3).max() <= 3 and ia3.size > ia.size
    assert ((d3 > 2.0) & (d3 < 14.0)).all()


def test_correlation_candidates_match_accurately(textured):
    left, right, truth = textured
    res = fbm_match(left, right, 0.0, 20.0, candidates="correlation")
    e = res.disparity - truth(res.col, res.row)
    feat = fbm_match(left, right, 0.0, 20.0)
    assert res.col.size > 1.2 * feat.col.size  # no need for the same point in both images
    assert np.median(np.abs(e)) <= 0.2
    assert np.mean(np.abs(e) <= 1.0) >= 0.98


def test_local_thresholds_give_points_in_weak_texture():
    """Half the image with 10 × weaker texture: a global median threshold leaves it almost
    empty, sub-image thresholds do not; a uniform (noise-free) area never gets points."""
    rng = np.random.default_rng(2)
    t = ndimage.gaussian_filter(rng.standard_normal((256, 256)), 1.5)
    img = 100 + 30 * t / t.std()
    img[:, 128:] = 100 + 3 * t[:, 128:] / t.std()
    img[96:160, 160:224] = 100.0
    glob = detect_features(img, window=5, margin=5)
    loc = detect_features(img, window=5, margin=5, local_cell=64)
    weak_g = np.sum(glob.cols > 130)
    weak_l = np.sum(loc.cols > 130)
    strong_g, strong_l = np.sum(glob.cols < 126), np.sum(loc.cols < 126)
    assert weak_g < 0.1 * strong_g
    assert weak_l > 0.35 * strong_l  # the uniform square takes 1/8 of the weak half
    flat = (loc.cols > 166) & (loc.cols < 218) & (loc.rows > 102) & (loc.rows < 154)
    assert not flat.any()
