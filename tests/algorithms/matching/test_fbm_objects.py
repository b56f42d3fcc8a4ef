"""fbm_lsm keeps objects (issue 19): on a synthetic epipolar pair with a flat, textured roof and
a gabled, weakly textured two-tone roof of known heights, the ``general`` (default) and
``urban`` chains (matching, groundels, object surfaces, automatic breaklines, FE surface) keep
the roofs and place the walls; the ``terrain`` preset (formerly ``flat``) does not; the old
name is still accepted."""

from __future__ import annotations

from typing import Dict, Tuple

import numpy as np
import pytest
from scipy import ndimage

from photodem.algorithms.matching.fbm_model import _options, object_surfaces
from photodem.algorithms.matching.hierarchy import match_epipolar_fbm_lsm
from photodem.algorithms.matching.presets import DEFAULT_PRESET, SPACING_GSD, resolve_preset
from photodem.algorithms.surface.fe_grid import fe_interpolate
from photodem.algorithms.surface.gridding import Grid
from photodem.algorithms.surface.groundel import reduce_groundels
from photodem.algorithms.surface.jumps import jump_breaklines, point_support

GROUND = 8.0  # px


def _texture(rng: np.random.Generator, shape: Tuple[int, int], sigma: float, amp: float
             ) -> np.ndarray:
    return amp * ndimage.gaussian_filter(rng.normal(size=shape), sigma)


def _scene(seed: int = 5) -> Dict[str, np.ndarray]:
    """An epipolar pair with a textured flat roof (+15 px, about 8 m at B/H 0.35 and GSD
    0.2 m) and a gabled roof (+12 px at the eaves to +20 px at the ridge) with two-tone, weakly
    textured faces; true disparity (a height in disparity units) and labels (1 flat, 2 gabled).
    """
    rng = np.random.default_rng(seed)
    h, w, pad = 240, 320, 48
    d = np.full((h, w), GROUND)
    label = np.zeros((h, w), np.int32)
    label[40:110, 50:130] = 1
    d[40:110, 50:130] = GROUND + 15.0
    label[130:210, 160:260] = 2
    cols = np.arange(160, 260)
    d[130:210, 160:260] = GROUND + 12.0 + 8.0 * (1.0 - np.abs(cols - 209.5) / 50.0)[None, :]
    tex = {0: 120 + _texture(rng, (h, w + pad), 1.2, 60.0),
           1: 100 + _texture(rng, (h, w + pad), 1.0, 45.0),
           2: np.where(np.arange(w + pad)[None, :] < 209.5 + pad / 2, 165.0, 135.0)
           + _texture(rng, (h, w + pad), 1.0, 15.0)}
    # texture fixed to the surface: the left pixel x shows surface point x − d/2
    xs = np.clip(np.rint(np.arange(w)[None, :] - d / 2 + pad / 2).astype(int), 0, w + pad - 1)
    rows = np.arange(h)[:, None]
    left = np.zeros((h, w))
    for k, t in tex.items():
        left = np.where(label == k, t[rows, xs], left)
    right = np.full((h, w), np.nan)
    depth = np.full((h, w), -np.inf)
    xr = np.rint(np.arange(w)[None, :] - d).astype(int)
    for r in range(h):
        for c in np.argsort(d[r], kind="stable"):  # far first, near overwrites (z-buffer)
            if 0 <= xr[r, c] < w and d[r, c] >= depth[r, xr[r, c]]:
                right[r, xr[r, c]] = left[r, c]
                depth[r, xr[r, c]] = d[r, c]
        bad = np.isnan(right[r])
        right[r, bad] = np.interp(np.flatnonzero(bad), np.flatnonzero(~bad), right[r, ~bad])
    left += rng.normal(0, 1.0, left.shape)
    right += rng.normal(0, 1.0, right.shape)
    return {"left": left.astype(np.float32), "right": right.astype(np.float32), "d": d,
            "label": label}


def _surface(scene: Dict[str, np.ndarray], preset: str) -> np.ndarray:
    """The fbm_lsm chain of a preset in disparity space: matching, groundels (10 px), object
    surfaces and automatic breaklines (general, urban), FE surface on a 2 px grid → disparity per
    pixel (x = column, y = −row)."""
    opts, surface = _options(preset, {})
    m = match_epipolar_fbm_lsm(scene["left"], scene["right"], 0.0, 47.0, options=opts)
    h, w = scene["d"].shape
    pts = np.column_stack([m.col, -m.row, m.disparity])
    cell = float(surface["groundel_gsd"])  # 1 px = 1 GSD
    red = reduce_groundels(pts[:, 0], pts[:, 1], pts[:, 2], cell, origin=(0.0, 0.0),
                           mode=surface["reduction"])
    inlier, lines = ~red.outlier, []
    if surface.get("objects"):
        inlier, lines = object_surfaces(pts, red)
    grid = Grid.from_bounds(0.0, -float(h), float(w), 0.0, SPACING_GSD)
    z, _ = fe_interpolate(pts[inlier, 0], pts[inlier, 1], pts[inlier, 2], grid,
                          smoothing=float(surface["smoothing"]), breaklines=lines)
    rr = np.minimum(np.arange(h) // 2, grid.height - 1)
    cc = np.minimum(np.arange(w) // 2, grid.width - 1)
    return z[np.ix_(rr, cc)]


def _building(disp: np.ndarray, scene: Dict[str, np.ndarray], k: int) -> Tuple[float, float]:
    """Share of the interior (≥ 5 px inside building ``k``) within 1 px (≈ 0.5 m) of the
    truth, and the median wall position error (px) of its left and right walls per row (wall:
    where the surface passes the middle between ground and eaves)."""
    b = scene["label"] == k
    inner = ndimage.binary_erosion(b, iterations=5)
    complete = float((np.abs(disp - scene["d"]) <= 1.0)[inner].mean())
    errs = []
    for r in np.flatnonzero(b.any(axis=1))[5:-5]:
        tc = np.flatnonzero(b[r])
        mid = (GROUND + scene["d"][r, tc].min()) / 2
        hi = np.flatnonzero(disp[r] > mid)
        hi = hi[(hi > tc[0] - 20) & (hi < tc[-1] + 20)]
        errs += [abs(hi[0] - tc[0]), abs(hi[-1] - tc[-1])] if hi.size else [99, 99]
    return complete, float(np.median(errs))


@pytest.fixture(scope="module")
def scene() -> Dict[str, np.ndarray]:
    return _scene()


@pytest.mark.parametrize("preset", ["general", "urban"])
def test_object_presets_keep_roofs_and_walls(scene, preset) -> None:
    dsm = _surface(scene, preset)
    # measured: urban flat 96.2 % / 4 px, gabled 97.6 % / 7 px, open 97.9 %; general (the
    # default) 95.9 % / 4 px, 97.6 % / 6 px, open 98.0 %. The walls miss the goal of 1 GSD: the
    # automatic breakline lies halfway between the last roof and the first ground point, and
    # the ground beside a wall is partly occluded (few points)
    for k, wall_max in ((1, 6.0), (2, 9.0)):
        c, wall = _building(dsm, scene, k)
        assert c >= 0.9 and wall <= wall_max, (k, c, wall)
    open_ = ndimage.distance_transform_edt(scene["label"] == 0) > 10
    assert (np.abs(dsm - scene["d"]) <= 1.0)[open_].mean() >= 0.95


def test_terrain_removes_roofs(scene) -> None:
    terrain = _surface(scene, "terrain")
    # measured: 0 % on both roofs (the DSM default before issue 19), open 100 %
    for k in (1, 2):
        c, _ = _building(terrain, scene, k)
        assert c <= 0.1  # the terrain preset removes objects, as its name says


def test_point_support_and_jump_breaklines() -> None:
    rng = np.random.default_rng(0)
    x, y = rng.uniform(0, 20, (2, 400))
    roof = (np.abs(x - 10) < 4) & (np.abs(y - 10) < 4)
    z = np.where(roof, 8.0, 0.0) + rng.normal(0, 0.05, x.size)
    z[0] = 5.0  # an isolated blunder
    support = point_support(x, y, z, radius=2.0)
    assert support[0] == 0 and np.median(support[roof]) >= 3
    lines = jump_breaklines(x, y, z, min_step=1.5, supported=support >= 2)
    assert len(lines) == 1
    # the breakline pieces lie between roof and ground: within a point spacing of the wall
    seg = np.array([np.asarray(g.coords) for g in lines[0].geoms]).reshape(-1, 2)
    wall = np.maximum(np.abs(seg[:, 0] - 10), np.abs(seg[:, 1] - 10))
    assert np.median(np.abs(wall - 4.0)) < 1.0


def test_flat_is_an_alias_of_terrain() -> None:
    assert DEFAULT_PRESET == "general"
    assert resolve_preset("flat")[0] == "terrain" and resolve_preset("flat")[1]
    assert resolve_preset("urban") == ("urban", None)
