"""Coarse-to-fine FBM + LSM control strategy on synthetic epipolar pairs with known disparity."""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy import ndimage

from photodem.algorithms.errors import Cancelled, InputError
from photodem.algorithms.feedback import Feedback
from photodem.algorithms.matching.fbm import window_components
from photodem.algorithms.matching.hierarchy import (
    FLAG_GRID,
    FLAG_LSM,
    FLAG_LSM_FAILED,
    FbmLsmOptions,
    match_epipolar_fbm_lsm,
)
from photodem.algorithms.matching.prediction import suspect_components

H = W = 480


def _texture(h, w, seed, blur=1.5):
    t = ndimage.gaussian_filter(np.random.default_rng(seed).standard_normal((h, w)), blur)
    return 100 + 30 * t / t.std()


def _pair(tex=None, step=None, noise=2.0, seed=0, h=H, w=W):
    """Pair from D(x, y) on the right grid: d0 + tilt + bump (+ step); gain 0.9, offset 10.

    right(x, y) = 0.9·T(x + D, y) + 10 + n, left = T + n; truth(c, r) inverts x_r = c − D(x_r).
    """
    rng = np.random.default_rng(seed + 50)
    tex = _texture(h, w + 100, seed) if tex is None else tex

    def dfield(x, y):
        d = 10 + 0.012 * x + 0.006 * y + 8 * np.exp(
            -(((x - 0.55 * w) / (0.15 * w)) ** 2 + ((y - 0.45 * h) / (0.15 * h)) ** 2))
        return d if step is None else d + step[1] * (x > step[0])

    yy, xr = np.mgrid[0:h, 0:w].astype(float)
    right = ndimage.map_coordinates(tex, [yy, xr + dfield(xr, yy) + 50], order=3, mode="reflect")
    right = 0.9 * right + 10 + rng.normal(0, noise, right.shape)
    left = tex[:, 50:50 + w] + rng.normal(0, noise, (h, w))

    def truth(c, r):
        x = c - dfield(c, r)
        for _ in range(30):
            x = c - dfield(x, r)
        return dfield(x, r)

    return left.astype(np.float32), right.astype(np.float32), truth


def _window_coverage(m, shape, ws=32, exclude=None):
    """Share of the 32 × 32 windows (fully inside, not excluded) that hold a point."""
    ny, nx = shape[0] // ws, shape[1] // ws
    held = np.zeros((ny, nx), bool)
    iy, ix = (m.row // ws).astype(int), (m.col // ws).astype(int)
    ok = (iy < ny) & (ix < nx)
    held[iy[ok], ix[ok]] = True
    want = np.ones((ny, nx), bool)
    if exclude is not None:
        want &= ~exclude[: ny * ws, : nx * ws].reshape(ny, ws, nx, ws).all(axis=(1, 3))
    return held[want].mean()


@pytest.fixture(scope="module")
def pair():
    return _pair()


def test_fbm_accuracy_and_lsm_refinement(pair):
    left, right, truth = pair
    fbm = match_epipolar_fbm_lsm(left, right, 0.0, 40.0, options=FbmLsmOptions(lsm=False))
    e = fbm.disparity - truth(fbm.col, fbm.row)
    assert len(fbm) > 0.008 * left.size
    assert np.median(np.abs(e)) <= 0.3
    assert np.mean(np.abs(e) <= 1.0) >= 0.95
    assert (fbm.level == 0).all() and not (fbm.flags & (FLAG_LSM | FLAG_LSM_FAILED)).any()
    # the FBM points only (no grid densification): LSM refines the same points
    m = match_epipolar_fbm_lsm(left, right, 0.0, 40.0, options=FbmLsmOptions(grid_step=0,
                                                                             lsm_reject=False))
    el = m.disparity - truth(m.col, m.row)
    lsm = (m.flags & FLAG_LSM) > 0
    assert lsm.mean() > 0.95
    assert np.sqrt(np.mean(el[lsm] ** 2)) <= 0.1
    # refinement: not worse than the FBM points (same points, same sub-pixel start)
    assert np.sqrt(np.mean(el**2)) <= np.sqrt(np.mean(e**2)) + 0.005
    # predicted σ is realistic (within ×2 of the empirical error)
    ratio = np.std(el[lsm]) / np.sqrt(np.mean(m.sigma_px[lsm].astype(float) ** 2))
    assert 0.5 <= ratio <= 2.0
    st = m.stats
    json.dumps(st)  # JSON-ready
    assert st["total"]["lsm_tried"] == len(m)
    assert st["levels"]["0"]["failure_pct"] <= 1.0
    assert set(st["levels"]) == {str(k) for k in range(st["total"]["levels"])}


def test_lsm_improves_noisy_fbm():
    """Higher noise: the 17 × 17 LSM beats the 9 × 9 NCC parabola of the FBM points."""
    left, right, truth = _pair(noise=6.0, seed=4)
    fbm = match_epipolar_fbm_lsm(left, right, 0.0, 40.0, options=FbmLsmOptions(lsm=False))
    m = match_epipolar_fbm_lsm(left, right, 0.0, 40.0)
    e_fbm = fbm.disparity - truth(fbm.col, fbm.row)
    e = m.disparity - truth(m.col, m.row)
    lsm = (m.flags & FLAG_LSM) > 0
    assert np.sqrt(np.mean(e[lsm] ** 2)) <= 0.1
    ok = np.abs(e_fbm) < 1
    assert np.sqrt(np.mean(e[lsm] ** 2)) < 0.8 * np.sqrt(np.mean(e_fbm[ok] ** 2))


def test_one_seed_covers_everything(pair):
    left, right, truth = pair
    seed = np.array([[100.0, 380.0, float(truth(np.array([100.0]), np.array([380.0]))[0])]])
    # two levels only: the top level (240 px, 8 × 8 windows) must grow from the seed window
    opt = FbmLsmOptions(levels=2, lsm=False)
    m = match_epipolar_fbm_lsm(left, right, -100.0, 100.0, seeds=seed, options=opt)
    top = m.stats["levels"]["1"]
    assert top["waves"] >= 5 and top["retry_recovered"] >= 30  # region growing
    assert top["range_fallback"] == 0
    assert _window_coverage(m, left.shape) >= 0.98
    e = m.disparity - truth(m.col, m.row)
    assert np.mean(np.abs(e) <= 1.0) >= 0.98
    assert m.stats["total"]["seeds_used"] == 1


def test_mask_honoured_and_nodata(pair):
    left, right, truth = pair
    left = left.copy()
    left[:, -30:] = np.nan  # no data at the right edge
    yy, xx = np.mgrid[0:H, 0:W]
    mask = (xx - 200) ** 2 + (yy - 220) ** 2 < 70**2
    m = match_epipolar_fbm_lsm(left, right, 0.0, 40.0, mask=mask,
                               options=FbmLsmOptions(lsm=False))
    ci, ri = np.rint(m.col).astype(int), np.rint(m.row).astype(int)
    assert not mask[ri, ci].any()
    assert m.col.max() < W - 30
    e = m.disparity - truth(m.col, m.row)
    assert np.mean(np.abs(e) <= 1.0) >= 0.98
    # windows partly covered by the mask still get points outside it
    near = (np.hypot(m.col - 200, m.row - 220) < 85)
    assert near.sum() > 20


def test_barrier_not_smoothed_across():
    """A 10 px disparity step along a breakline: points right next to it are correct."""
    x_step = 250.0
    left, right, truth = _pair(step=(x_step, 10.0), seed=3)
    rows = np.arange(H, dtype=float)
    # the step in left coordinates: x_r = x_step reached from the lower side
    x_l = x_step + truth(np.full(H, x_step - 1.0), rows) + 1.0
    bar = np.zeros((H, W), bool)
    bar[np.arange(H), np.rint(x_l).astype(int)] = True
    opt = FbmLsmOptions(lsm=False)
    m = match_epipolar_fbm_lsm(left, right, 0.0, 50.0, barriers=bar, options=opt)
    e = m.disparity - truth(m.col, m.row)
    dist = m.col - x_l[np.clip(np.rint(m.row).astype(int), 0, H - 1)]
    # left side: next to the line; right side: beyond the 10 px occluded band
    west = (dist < -1) & (dist > -12)
    east = (dist > 11) & (dist < 24)
    assert west.sum() >= 20 and east.sum() >= 20
    assert np.mean(np.abs(e[west]) <= 1.0) >= 0.95
    assert np.mean(np.abs(e[east]) <= 1.0) >= 0.95
    assert not (np.abs(dist) < 0.5).any()  # nothing on the breakline itself


def test_textureless_patch_is_marked_not_fatal():
    tex = _texture(H, W + 100, 5)
    tex[150:330, 200:390] = 100.0  # a uniform field (≈ 5 × 5 windows), 50 px texture shift
    left, right, truth = _pair(tex=tex, seed=5)
    m = match_epipolar_fbm_lsm(left, right, 0.0, 40.0, options=FbmLsmOptions(lsm=False))
    fails = m.failures[m.failures[:, 2] == 0]
    assert len(fails) >= 4
    inside = (fails[:, 0] > 150) & (fails[:, 0] < 340) & (fails[:, 1] > 150) & (fails[:, 1] < 330)
    assert inside.mean() >= 0.8  # the marks are where the texture is missing
    assert m.stats["levels"]["0"]["failure_pct"] > 1.0
    e = m.disparity - truth(m.col, m.row)
    assert np.mean(np.abs(e) <= 1.0) >= 0.98
    # matching went on around it: the textured windows are covered
    patch = np.zeros((H, W), bool)
    patch[140:340, 140:350] = True
    assert _window_coverage(m, (H, W), exclude=patch) >= 0.97


def test_texture_parallel_to_epipolar_lines_is_worse():
    """Seed §6.5.4: furrows ∥ the base (epipolar lines) are worse than ⟂ (Aa2 vs Aa1)."""
    yy, xx = np.mgrid[0:H, 0:W + 100].astype(float)
    base = _texture(H, W + 100, 3, blur=2.0)
    out = {}
    for name, stripes in (("perpendicular", np.sin(2 * np.pi * xx / 6.0)),
                          ("parallel", np.sin(2 * np.pi * yy / 6.0))):
        tex = 100 + 0.5 * (base - 100) + 15 * stripes
        left, right, truth = _pair(tex=tex, seed=3)
        m = match_epipolar_fbm_lsm(left, right, 0.0, 40.0)
        e = m.disparity - truth(m.col, m.row)
        lsm = (m.flags & FLAG_LSM) > 0
        out[name] = (np.sqrt(np.mean(e[lsm] ** 2)), np.median(m.sigma_px[lsm]))
    # measured error and the LSM's own σ both grow by ≥ 25 %
    assert out["parallel"][0] >= 1.25 * out["perpendicular"][0], out
    assert out["parallel"][1] >= 1.25 * out["perpendicular"][1], out


def test_cancel_and_bad_input(pair):
    left, right, _ = pair
    fb = Feedback()
    fb.cancel()
    with pytest.raises(Cancelled):
        match_epipolar_fbm_lsm(left, right, 0.0, 40.0, feedback=fb)
    with pytest.raises(InputError, match="start point"):
        match_epipolar_fbm_lsm(left, right, 0.0, 40.0, seeds=np.array([[-500.0, 10.0, 5.0]]))
    with pytest.raises(InputError, match="disparity range"):
        match_epipolar_fbm_lsm(left, right, 40.0, 0.0)
    with pytest.raises(InputError, match="rows"):
        match_epipolar_fbm_lsm(left, right[:-3], 0.0, 40.0)


def test_progress_and_approx_grid(pair):
    left, right, truth = pair
    seen = []
    fb = Feedback(on_progress=seen.append)
    step = 64.0
    gy, gx = np.mgrid[0:H // 64 + 1, 0:W // 64 + 1] * step + step / 2
    grid = truth(gx.astype(float), gy.astype(float)) + 1.0  # 1 px off
    m = match_epipolar_fbm_lsm(left, right, 0.0, 40.0, approx=(grid, step), feedback=fb,
                               options=FbmLsmOptions(levels=2, lsm=False))
    assert seen and seen[-1] == 100.0 and np.all(np.diff(seen) >= -1e-9)
    e = m.disparity - truth(m.col, m.row)
    assert np.mean(np.abs(e) <= 1.0) >= 0.98
    assert _window_coverage(m, left.shape) >= 0.98


def test_grid_densification_and_lsm_rejection(pair):
    """Default: FBM points + LSM-checked grid nodes every 4 px; failed LSM points dropped."""
    left, right, truth = pair
    m = match_epipolar_fbm_lsm(left, right, 0.0, 40.0)
    e = m.disparity - truth(m.col, m.row)
    grid = (m.flags & FLAG_GRID) > 0
    assert len(m) > 0.04 * left.size and grid.sum() > 0.8 * len(m)
    assert np.sqrt(np.mean(e[grid] ** 2)) <= 0.1
    assert np.mean(np.abs(e) <= 1.0) >= 0.999
    assert not (m.flags & FLAG_LSM_FAILED).any() and (m.flags & FLAG_LSM).all()
    tot = m.stats["total"]
    assert tot["lsm_rejected"] == tot["lsm_failed"]
    assert tot["grid"]["accepted"] == grid.sum() and tot["points"] == len(m)
    json.dumps(m.stats)


def _narrow_overlap(shift=380, w=480, h=320, seed=8):
    """Right image = left shifted by ``shift`` px: only w − shift columns overlap."""
    tex = _texture(h, w + shift + 20, seed)
    rng = np.random.default_rng(seed)
    left = tex[:, :w] + rng.normal(0, 2.0, (h, w))
    right = 0.9 * tex[:, shift:shift + w] + 10 + rng.normal(0, 2.0, (h, w))
    return left.astype(np.float32), right.astype(np.float32)


@pytest.mark.parametrize("window", [16, 24, 32, 48])
def test_narrow_overlap_never_zero_points(window):
    """A 100 px overlap strip: the pyramid keeps a whole window across the overlap at the top,
    windows without overlap are masked (not failures), every window size gives points."""
    shift = 380
    left, right = _narrow_overlap(shift)
    m = match_epipolar_fbm_lsm(left, right, shift - 40.0, shift + 40.0,
                               options=FbmLsmOptions(fbm_window=window))
    assert len(m) > 0.03 * left.shape[0] * (left.shape[1] - shift)
    assert np.mean(np.abs(m.disparity - shift) <= 0.5) >= 0.99
    assert m.col.min() >= shift - 41  # nothing where the range cannot reach the right image
    assert m.stats["levels"]["0"]["failure_pct"] <= 10.0
    top = m.stats["levels"][str(m.stats["total"]["levels"] - 1)]
    assert top["accepted"] > 0


def test_failed_coarse_level_falls_back_to_the_range():
    """Top level without texture (a blurred copy → no features there): the level below
    searches the whole range instead of returning nothing."""
    left, right, _ = _pair()
    opt = FbmLsmOptions(levels=3, lsm=False, grid_step=0, densify=False, enlarge=False,
                        rho_min=0.999)  # nothing passes on the top level ...
    m = match_epipolar_fbm_lsm(left, right, 0.0, 40.0, options=opt)
    assert len(m) == 0 or m.stats["levels"]["2"]["accepted"] == 0
    # ... while with the normal threshold on the lower levels the range fallback matches
    opt = FbmLsmOptions(levels=3, lsm=False, grid_step=0)
    m = match_epipolar_fbm_lsm(left, right, 0.0, 40.0, options=opt)
    assert len(m) > 0.008 * left.size


def test_suspect_components_majority_of_neighbours():
    grp = window_components((160, 160), 32)
    plane = np.zeros((grp.n_groups, 3))
    plane[:, 0] = 10.0 + 0.05 * grp.centres[:, 0]  # a tilted plane (disparity per window)
    plane[:, 1] = 0.05 * 32  # its slope in window units
    plane[12, 0] += 5.0  # the centre window is wrong by 5 px
    matched = np.ones(grp.n_groups, bool)
    sus = suspect_components(plane, grp, matched, matched, 2.0)
    assert sus.tolist() == [k == 12 for k in range(grp.n_groups)]
    # a corner window with only 2 matched neighbours is never judged
    plane[0, 0] += 5.0
    assert not suspect_components(plane, grp, matched, matched, 2.0)[0]
