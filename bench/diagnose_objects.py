"""Where DSMs lose their objects (issue 19): follow buildings and trees through each stage.

On a synthetic block with truth (default: the ``small`` block as ``make demo`` builds it, model
0102_0103) this script

1. matches the model with fbm_lsm (``terrain``, formerly ``flat``; ``urban``) and dense, and
   measures the DSMs on the truth grid inside the model's measuring area
   (:mod:`photodem.algorithms.quality.objects`):
   completeness on object interior, all object and open cells, heights of objects ≥ 5 m,
   building outlines;
2. builds the **true disparity** of every left epipolar pixel by projecting the truth DSM into
   both epipolar images (z-buffer: the largest disparity is the visible surface), with the
   object class, true height and the terrain height under it — so that every matched point is
   judged at the pixel where it was measured, not where its (possibly wrong) height puts it;
3. fbm_lsm: points per pyramid level on object pixels and their heights (roof / ground /
   neither), the groundel reduction's outliers among them, and an *oracle* run of the surface
   step with the same points moved to their true heights (what the reduction and the FE surface
   lose by themselves);
4. dense: the disparity filters switched on one after the other (SGBM alone, + uniqueness,
   + left–right check, + speckle filter, + one-sided edge erosion, + plane fill = production
   with the DSM path's options (``dense_model.dsm_dense_options``); production without the
   coarse range narrowing), valid and correct disparities on object and open pixels, texture of
   the roofs, and the gridding steps (median per cell, outlier test, gap limit).

Usage (from the repository root)::

    .venv/bin/python -m bench.diagnose_objects [BLOCK_DIR] [--seed N] [--size small|aerial]
        [--fbm-only] [--json OUT.json]

Without ``BLOCK_DIR`` a block of ``--size`` (default ``small``; seed ``N``, default 1) is
generated in a temporary folder. An ``aerial`` block (model 0101_0102, one start point, the
truth's height range, as ``bench_dsm_objects``) is recognised by its project name; ``--fbm-only``
skips the dense tables. Not part of
``make bench`` (about 2 minutes); the numbers go to ``docs/decisions.md`` (issue 19).
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Dict, List, Optional, Tuple

import numpy as np
import rasterio
from rasterio.features import geometry_mask, rasterize
from scipy import ndimage

from photodem.algorithms.feedback import Feedback
from photodem.algorithms.geometry.epipolar import SIDES
from photodem.algorithms.matching import dense as dense_mod
from photodem.algorithms.matching import fbm_model
from photodem.algorithms.matching.dense_model import dsm_dense_options
from photodem.algorithms.matching.model_setup import prepare_model
from photodem.algorithms.processing import registry
from photodem.algorithms.quality.objects import (
    completeness,
    object_masks,
    outline_metrics,
)
from photodem.algorithms.surface.gridding import GridAccumulator, finish_grid
from photodem.algorithms.surface.groundel import reduce_groundels

MODEL = "0102_0103"
#: the model of an ``aerial`` block (as ``bench_dsm_objects``)
AERIAL_MODEL = "0101_0102"
TOL = 0.5  # m: a height is "right" within this of the truth


# -- truth ----------------------------------------------------------------------------------------


@dataclass
class Truth:
    """Truth rasters on the truth grid, masks, and the model's measuring area on it."""

    dsm: np.ndarray
    dtm: np.ndarray
    transform: Any
    crs: Any
    cell: float
    objects: np.ndarray
    interior: np.ndarray
    open: np.ndarray
    area: np.ndarray
    labels: np.ndarray
    heights: np.ndarray  # per building (index = label − 1)
    landcover: np.ndarray  # 3 building, 4 tree (synthetic LANDCOVER codes)
    #: cells ≥ 1 m inside the stereo overlap at their own true height (seen by both images)
    stereo: Optional[np.ndarray] = None


def _read(path: Path) -> Tuple[np.ndarray, Any, Any]:
    with rasterio.open(path) as src:
        a = src.read(1, masked=True).astype(np.float64)
        return a.filled(np.nan), src.transform, src.crs


def load_truth(block: Path, setup: Any) -> Truth:
    """Truth DSM/DTM, masks, the measuring area and the building footprints inside it."""
    import fiona  # optional: only this script reads the footprints
    from shapely.geometry import shape  # optional: with fiona, for the footprints only

    dsm, t, crs = _read(block / "truth" / "dsm.tif")
    dtm, _, _ = _read(block / "truth" / "dtm.tif")
    lc, _, _ = _read(block / "truth" / "landcover.tif")
    cell = abs(t.a)
    m = object_masks(dsm, dtm, cell)
    area = geometry_mask([setup.measuring_area()], out_shape=dsm.shape, transform=t,
                         invert=True)
    poly = setup.measuring_area()
    geoms, heights = [], []
    with fiona.open(block / "truth" / "buildings.gpkg") as layer:
        for feat in layer:
            g = shape(feat["geometry"])
            if poly.contains(g):  # whole buildings inside the measuring area only
                geoms.append(g)
                heights.append(float(feat["properties"]["height"]))
    labels = rasterize([(g, i + 1) for i, g in enumerate(geoms)], out_shape=dsm.shape,
                       transform=t, fill=0, dtype="int32") if geoms else \
        np.zeros(dsm.shape, np.int32)
    return Truth(dsm, dtm, t, crs, cell, m.objects, m.interior, m.open, area, labels,
                 np.asarray(heights), lc, stereo_cells(setup, dsm, area, t))


def stereo_cells(setup: Any, dsm: np.ndarray, area: np.ndarray, transform: Any,
                 inside: float = 1.0) -> np.ndarray:
    """Cells of the measuring area whose true surface point lies in both images, at least
    ``inside`` m (in pixels of the model's GSD) from their borders.

    The measuring area is the overlap at the mid height; where the true surface is higher or
    lower, a strip along the overlap's edge has no partner in the other image, and no stereo
    method can measure it (issue 19: most open and object cells lost at the area's border;
    :mod:`photodem.algorithms.quality.stereo_overlap`).
    """
    from rasterio.transform import xy

    from photodem.algorithms.quality.stereo_overlap import inside_frames

    rows, cols = np.nonzero(area & np.isfinite(dsm))
    xs, ys = xy(transform, rows, cols)
    frames = setup.frames
    ok = inside_frames(frames, np.column_stack([np.asarray(xs), np.asarray(ys),
                                                dsm[rows, cols]]),
                       margin_px=inside / float(setup.gsd))
    out = np.zeros(dsm.shape, bool)
    out[rows[ok], cols[ok]] = True
    return out


def on_truth_grid(path: Path, truth: Truth) -> np.ndarray:
    """A DSM resampled (bilinear) onto the truth grid, NaN where it has no height."""
    from .truth_grid import on_grid

    return on_grid(path, truth.dsm.shape, truth.transform, truth.crs).astype(np.float64)


def dsm_row(name: str, dsm: np.ndarray, truth: Truth, gsd: float) -> Dict[str, Any]:
    """The issue's table row of one DSM, plus heights of tall objects and outlines."""
    a = truth.area
    st = truth.stereo if truth.stereo is not None else a
    c = completeness(dsm, truth.dsm, {"interior": truth.interior & a,
                                      "objects": truth.objects & a, "open": truth.open & a,
                                      "interior_st": truth.interior & st,
                                      "open_st": truth.open & st,
                                      "roof": truth.interior & a & (truth.landcover == 3),
                                      "tree": truth.interior & a & (truth.landcover == 4)})
    ndsm_true = truth.dsm - truth.dtm
    tall = truth.objects & a & (ndsm_true >= 5.0)
    out = outline_metrics(np.where(a, dsm, np.nan), truth.dtm, truth.dsm,
                          np.where(a, truth.labels, 0), truth.cell, gsd=gsd)
    dz = (dsm - truth.dsm)[truth.interior & a]
    dz = dz[np.isfinite(dz)]
    ok = np.abs(dz) <= TOL
    return {
        "method": name,
        "interior_0_5_pct": 100 * c["interior"]["within_0_5"],
        "interior_1_pct": 100 * c["interior"]["within_1"],
        "interior_measured_pct": 100 * c["interior"]["measured"],
        # interior on buildings (land cover 3) and on tree crowns (4)
        "roof_0_5_pct": 100 * c["roof"]["within_0_5"],
        "tree_0_5_pct": 100 * c["tree"]["within_0_5"],
        "tree_share_of_interior_pct": _pct(truth.landcover == 4, truth.interior & a),
        "objects_0_5_pct": 100 * c["objects"]["within_0_5"],
        "objects_measured_pct": 100 * c["objects"]["measured"],
        "open_0_5_pct": 100 * c["open"]["within_0_5"],
        "open_measured_pct": 100 * c["open"]["measured"],
        # the same on cells both images see (:func:`stereo_cells`)
        "interior_stereo_0_5_pct": 100 * c["interior_st"]["within_0_5"],
        "open_stereo_0_5_pct": 100 * c["open_st"]["within_0_5"],
        "stereo_share_of_area_pct": 100 * float(st.sum()) / max(int(a.sum()), 1),
        "tall_true_ndsm_median_m": float(np.median(ndsm_true[tall])),
        "tall_dsm_ndsm_median_m": float(np.nanmedian((dsm - truth.dtm)[tall])),
        "interior_right_median_m": float(np.median(dz[ok])) if ok.any() else None,
        "interior_right_nmad_m": (float(1.4826 * np.median(np.abs(dz[ok] - np.median(dz[ok]))))
                                  if ok.any() else None),
        "buildings": out["count"],
        "iou_pooled": out["iou_pooled"],
        "wall_median_gsd": out["wall_median_gsd"],
    }


# -- the true disparity of the left epipolar image ----------------------------------------------


@dataclass
class EpiTruth:
    """Per left epipolar pixel: true disparity, class (1 interior, 2 edge, 3 open, 4 other,
    0 unknown), true height, terrain height under it, occluded in the right image."""

    d: np.ndarray
    cls: np.ndarray
    z: np.ndarray
    z_ground: np.ndarray
    occluded: np.ndarray
    lc: np.ndarray  # land cover of the visible truth point

    def roof(self) -> np.ndarray:
        """Object-interior pixels on buildings."""
        return (self.cls == 1) & (self.lc == 3)

    def tree(self) -> np.ndarray:
        """Object-interior pixels on trees."""
        return (self.cls == 1) & (self.lc == 4)


def _splat(idx: np.ndarray, d: np.ndarray, n: int, values: List[np.ndarray]
           ) -> Tuple[np.ndarray, List[np.ndarray]]:
    """Per pixel the largest disparity (the visible surface) and the values of that point."""
    order = np.argsort(d, kind="stable")  # the last write wins: the largest d
    best = np.full(n, np.nan)
    best[idx[order]] = d[order]
    outs = []
    for v in values:
        o = np.full(n, np.nan)
        o[idx[order]] = v[order]
        outs.append(o)
    return best, outs


def epipolar_truth(setup: Any, truth: Truth) -> EpiTruth:
    """Project the truth DSM (inside the measuring area, grown) into both epipolar images."""
    pair = setup.pair
    grow = ndimage.binary_dilation(truth.area, iterations=50)
    rr, cc = np.nonzero(grow & np.isfinite(truth.dsm))
    x, y = truth.transform * (cc + 0.5, rr + 0.5)
    pts = np.column_stack([x, y, truth.dsm[rr, cc]])
    cls = np.full(rr.size, 4.0)
    cls[truth.objects[rr, cc]] = 2
    cls[truth.interior[rr, cc]] = 1
    cls[truth.open[rr, cc]] = 3
    cls[~truth.area[rr, cc]] = 0  # seen, but outside the measuring area: not counted
    out = {}
    for side in SIDES:
        col, row = pair.world_to_epipolar(pts, side)
        out[side] = (col, row)
    (cl, rl), (cr, _) = out["left"], out["right"]
    d = cl - cr
    shape = {s: (pair.sizes[i][1], pair.sizes[i][0]) for i, s in enumerate(SIDES)}
    res = {}
    for side, col in (("left", cl), ("right", cr)):
        h, w = shape[side]
        # pixel centres at integer coordinates (as the matchers' columns and rows)
        ic, ir = np.rint(col).astype(np.int64), np.rint(rl).astype(np.int64)
        ok = (ic >= 0) & (ic < w) & (ir >= 0) & (ir < h) & np.isfinite(d)
        vals = ([cls[ok], pts[ok, 2], truth.dtm[rr[ok], cc[ok]],
                 truth.landcover[rr[ok], cc[ok]]] if side == "left" else [])
        best, outs = _splat(ir[ok] * w + ic[ok], d[ok], h * w, vals)
        res[side] = (best.reshape(h, w), [o.reshape(h, w) for o in outs])
    dl, (c_img, z_img, g_img, lc_img) = res["left"]
    dr = res["right"][0]
    h, w = dl.shape
    rows, cols = np.mgrid[0:h, 0:w]
    xr = np.clip(np.rint(cols - np.nan_to_num(dl)).astype(np.int64), 0, dr.shape[1] - 1)
    with np.errstate(invalid="ignore"):
        occluded = dr[rows, xr] > dl + 1.0
    return EpiTruth(dl, np.nan_to_num(c_img, nan=0).astype(np.int8), z_img, g_img, occluded,
                    np.nan_to_num(lc_img, nan=0).astype(np.int8))


def judge(setup: Any, et: EpiTruth, col: np.ndarray, row: np.ndarray, d: np.ndarray
          ) -> Dict[str, np.ndarray]:
    """Per measurement at left pixel (col, row) with disparity d: class, right, at ground."""
    h, w = et.d.shape
    ic = np.clip(np.rint(col).astype(np.int64), 0, w - 1)
    ir = np.clip(np.rint(row).astype(np.int64), 0, h - 1)
    z = setup.pair.disparity_to_world(d, col, row)[:, 2]
    z_true, z_ground = et.z[ir, ic], et.z_ground[ir, ic]
    with np.errstate(invalid="ignore"):
        return {"cls": et.cls[ir, ic], "lc": et.lc[ir, ic], "right": np.abs(z - z_true) <= TOL,
                "ground": np.abs(z - z_ground) <= TOL, "z": z, "z_true": z_true}


# -- fbm_lsm -------------------------------------------------------------------------------------


def _pct(a: np.ndarray, b: Optional[np.ndarray] = None) -> float:
    if b is None:
        return 100.0 * float(np.mean(a)) if a.size else float("nan")
    return 100.0 * float(np.sum(a & b)) / max(int(np.sum(b)), 1)


def fbm_levels(setup: Any, et: EpiTruth, grey: Dict[str, np.ndarray], mask: Any,
               barriers: Any, preset: str, seeds: Optional[np.ndarray] = None
               ) -> List[Dict[str, Any]]:
    """Points of every pyramid level (keep_coarse) on object pixels and their heights."""
    opts, surface = fbm_model._options(preset, {"keep_coarse": True})
    opts = fbm_model._object_search(opts, surface, setup)  # as match_model: per model
    m = fbm_model.match_epipolar_fbm_lsm(grey["left"], grey["right"], setup.min_d,
                                         setup.max_d, seeds=seeds, mask=mask,
                                         barriers=barriers, options=opts)
    j = judge(setup, et, m.col, m.row, m.disparity)
    area_int = _pct(et.cls == 1, et.cls > 0)
    rows = []
    for k in sorted({int(v) for v in m.level}, reverse=True):
        sel = m.level == k
        on = sel & (j["cls"] == 1)
        rows.append({"preset": preset, "level": k, "points": int(sel.sum()),
                     "on_interior": int(on.sum()),
                     "on_roof": int(np.sum(on & (j["lc"] == 3))),
                     "on_tree": int(np.sum(on & (j["lc"] == 4))),
                     "on_interior_pct": _pct(j["cls"][sel] == 1),
                     "interior_area_pct": area_int,
                     "interior_right_pct": _pct(j["right"], on),
                     "interior_ground_pct": _pct(j["ground"], on),
                     "open_right_pct": _pct(j["right"], sel & (j["cls"] == 3))})
    return rows


def _surface_completeness(setup: Any, xyz: np.ndarray, sigma_z: np.ndarray, surface: Dict,
                          truth: Truth, cells_interior: Tuple[np.ndarray, np.ndarray],
                          cell: float) -> Tuple[float, Any]:
    """Reduction + FE surface of points; share of the interior DSM cells within TOL."""
    grid = setup.grid
    red = reduce_groundels(xyz[:, 0], xyz[:, 1], xyz[:, 2], cell,
                           origin=(grid.transform.c, grid.transform.f),
                           mode=surface.get("reduction", "l1"))
    mp = fbm_model._ModelPoints(xyz, sigma_z, np.zeros(len(xyz), np.int64),
                                np.arange(len(xyz)), np.ones(grid.shape, bool), len(xyz))
    z = fbm_model._surface(setup, mp, red, surface, "fe", None, Feedback())
    r, c = cells_interior
    return 100.0 * float(np.mean(np.abs(z[r, c] - _truth_at_cells(setup, truth, r, c))
                                 <= TOL)), red


def _truth_at_cells(setup: Any, truth: Truth, r: np.ndarray, c: np.ndarray) -> np.ndarray:
    """True DSM at the centres of DSM cells (nearest truth cell)."""
    x, y = setup.grid.transform * (c + 0.5, r + 0.5)
    tc, tr = ~truth.transform * (x, y)
    return truth.dsm[np.clip(tr.astype(np.int64), 0, truth.dsm.shape[0] - 1),
                     np.clip(tc.astype(np.int64), 0, truth.dsm.shape[1] - 1)]


def interior_cells(setup: Any, truth: Truth) -> Tuple[np.ndarray, np.ndarray]:
    """DSM cells whose centre lies on an object-interior truth cell inside the area."""
    g = setup.grid
    rows, cols = np.mgrid[0:g.height, 0:g.width]
    x, y = g.transform * (cols + 0.5, rows + 0.5)
    tc, tr = ~truth.transform * (x, y)
    tr, tc = np.floor(tr).astype(np.int64), np.floor(tc).astype(np.int64)
    ok = (tr >= 0) & (tr < truth.dsm.shape[0]) & (tc >= 0) & (tc < truth.dsm.shape[1])
    sel = np.zeros(ok.shape, bool)
    sel[ok] = truth.interior[tr[ok], tc[ok]] & truth.area[tr[ok], tc[ok]]
    return np.nonzero(sel)


def _features(grey: Dict[str, np.ndarray], et: EpiTruth, preset: str) -> Dict[str, float]:
    """Level-0 Förstner points of the left image per 1000 px on interior and open pixels."""
    from photodem.algorithms.matching.fbm import detect_features, fill_nodata  # lazy: one use

    opts, _ = fbm_model._options(preset, {})
    filled, valid = fill_nodata(np.asarray(grey["left"], np.float32))
    f = detect_features(filled, valid, None, window=opts.interest_window, q_min=opts.q_min,
                        w_factor=opts.w_factor, nms_window=opts.nms_window, margin=6,
                        local_cell=2 * int(opts.fbm_window) if opts.local_cell is None
                        else int(opts.local_cell), local_floor=opts.local_floor)
    cls = et.cls[np.rint(f.rows).astype(int), np.rint(f.cols).astype(int)]
    return {f"features_per_1000px_{name}": 1000.0 * float(np.sum(cls == k))
            / max(int(np.sum(et.cls == k)), 1) for k, name in ((1, "interior"), (3, "open"))}


def fbm_chain(setup: Any, truth: Truth, et: EpiTruth, grey: Dict[str, np.ndarray], mask: Any,
              barriers: Any, preset: str, seeds: Optional[np.ndarray] = None
              ) -> Dict[str, Any]:
    """The production chain of fbm_lsm, stage by stage, with the object points followed."""
    opts, surface = fbm_model._options(preset, {})
    opts = fbm_model._object_search(opts, surface, setup)
    matches = fbm_model.match_epipolar_fbm_lsm(grey["left"], grey["right"], setup.min_d,
                                               setup.max_d, seeds=seeds, mask=mask,
                                               barriers=barriers, options=opts)
    mp = fbm_model._intersect(setup, matches)
    k = mp.keep
    j = judge(setup, et, matches.col[k], matches.row[k], matches.disparity[k])
    cell = fbm_model._groundel_size(None, surface, setup)
    cells = interior_cells(setup, truth)
    prod, red = _surface_completeness(setup, mp.xyz, mp.sigma_z, surface, truth, cells, cell)
    on = j["cls"] == 1
    inl = ~red.outlier.astype(bool)
    # oracle: the same points (image positions) with their true heights
    d_true = et.d[np.clip(np.rint(matches.row[k]).astype(int), 0, et.d.shape[0] - 1),
                  np.clip(np.rint(matches.col[k]).astype(int), 0, et.d.shape[1] - 1)]
    xyz_t = setup.pair.disparity_to_world(d_true, matches.col[k], matches.row[k])
    good = np.isfinite(xyz_t).all(axis=1)
    xyz_o = np.where(good[:, None], xyz_t, mp.xyz)
    oracle, red_o = _surface_completeness(setup, xyz_o, mp.sigma_z, surface, truth, cells,
                                          cell)
    on_o = on & good
    tot = matches.stats["total"]
    lv = matches.stats["levels"]
    return {
        "preset": preset, "groundel_m": cell, "points": len(k),
        "interior_area_pct": _pct(et.cls == 1, et.cls > 0),
        "points_on_interior": int(on.sum()), "points_on_interior_pct": _pct(on),
        "points_on_roof_interior": int(np.sum(on & (j["lc"] == 3))),
        "points_on_tree_interior": int(np.sum(on & (j["lc"] == 4))),
        "points_per_1000px_roof": 1000.0 * float(np.sum(on & (j["lc"] == 3)))
        / max(int(et.roof().sum()), 1),
        "points_per_1000px_tree": 1000.0 * float(np.sum(on & (j["lc"] == 4)))
        / max(int(et.tree().sum()), 1),
        "points_per_1000px_open": 1000.0 * float(np.sum(j["cls"] == 3))
        / max(int(np.sum(et.cls == 3)), 1),
        "roof_area_pct": _pct(et.roof(), et.cls > 0),
        "interior_points_right_pct": _pct(j["right"], on),
        "roof_points_right_pct": _pct(j["right"], on & (j["lc"] == 3)),
        "tree_points_right_pct": _pct(j["right"], on & (j["lc"] == 4)),
        "interior_points_ground_pct": _pct(j["ground"], on),
        "interior_points_outlier_pct": _pct(~inl, on),
        "interior_right_points_outlier_pct": _pct(~inl, on & j["right"]),
        "interior_right_inliers": int(np.sum(on & j["right"] & inl)),
        "open_points_right_pct": _pct(j["right"], j["cls"] == 3),
        "dsm_interior_0_5_pct": prod,
        "oracle_points_outlier_pct": _pct(red_o.outlier.astype(bool), on_o),
        "oracle_dsm_interior_0_5_pct": oracle,
        "outliers_fbm": int(sum(v.get("outliers", 0) for v in lv.values())),
        "bidirectional_rejections": int(sum(v.get("bidirectional", v.get("bidir_rejected", 0))
                                            for v in lv.values())),
        "failed_windows": int(tot.get("failed_windows", 0)),
        "lsm_rejected": int(tot.get("lsm_rejected", 0)), "lsm_failed": int(tot.get(
            "lsm_failed", 0)),
        **_features(grey, et, preset),
    }


# -- dense -----------------------------------------------------------------------------------------


#: Cumulative filter settings: SGBM alone, then each filter of production switched on.
DENSE_STEPS: Tuple[Tuple[str, Dict[str, Any]], ...] = (
    ("SGBM alone", {"uniqueness": 0, "lr_max_diff": -1.0, "speckle_window": 0,
                    "edge_erosion": 0, "plane_fill": 0}),
    ("+ uniqueness 10 %", {"lr_max_diff": -1.0, "speckle_window": 0, "edge_erosion": 0,
                           "plane_fill": 0}),
    ("+ left–right check", {"speckle_window": 0, "edge_erosion": 0, "plane_fill": 0}),
    ("+ speckle filter", {"edge_erosion": 0, "plane_fill": 0}),
    ("+ one-sided edge erosion", {"plane_fill": 0}),
    ("+ plane fill (production)", {}),
    ("production, full range (no coarse narrowing)", {"coarse_above": 0}),
)


def _texture(grey: np.ndarray, window: int = 9) -> np.ndarray:
    """Local standard deviation of the grey values (px window)."""
    g = np.nan_to_num(np.asarray(grey, np.float64))
    m = ndimage.uniform_filter(g, window)
    return np.sqrt(np.maximum(ndimage.uniform_filter(g * g, window) - m * m, 0.0))


def dense_steps(setup: Any, et: EpiTruth, grey: Dict[str, np.ndarray]
                ) -> Tuple[List[Dict[str, Any]], Dict[str, np.ndarray]]:
    """Valid and right disparities on interior and open pixels for each filter step.

    Returns the table and the disparities of "SGBM alone" (``raw``) and production (``prod``).
    """
    rows, disp = [], {}
    h, w = et.d.shape
    rr, cc = np.mgrid[0:h, 0:w]
    inter, open_, roof, tree = et.cls == 1, et.cls == 3, et.roof(), et.tree()
    for name, over in DENSE_STEPS:
        tiling = {k: v for k, v in over.items() if k == "coarse_above"}
        # the DSM path's options
        opt = dsm_dense_options(setup, **{k: v for k, v in over.items() if k not in tiling})
        t0 = time.perf_counter()
        d = dense_mod.sgm_disparity(grey["left"], grey["right"], setup.min_d, setup.max_d,
                                    options=opt, **tiling)
        ok = np.isfinite(d)
        z = setup.pair.disparity_to_world(np.where(ok, d, np.nan))[..., 2]
        with np.errstate(invalid="ignore"):
            right = np.abs(z - et.z) <= TOL
        rows.append({"step": name, "seconds": round(time.perf_counter() - t0, 1),
                     "interior_valid_pct": _pct(ok, inter),
                     "interior_right_pct": _pct(right, inter),
                     "interior_wrong_pct": _pct(ok & ~right, inter),
                     "roof_valid_pct": _pct(ok, roof), "roof_right_pct": _pct(right, roof),
                     "tree_valid_pct": _pct(ok, tree), "tree_right_pct": _pct(right, tree),
                     "open_valid_pct": _pct(ok, open_), "open_right_pct": _pct(right, open_)})
        if name.endswith("(production)"):
            disp["prod"] = d
        elif name == "SGBM alone":
            disp["raw"] = d
    del rr, cc
    return rows, disp


def _partner_missing(et: EpiTruth, right: np.ndarray) -> np.ndarray:
    """Left pixels whose true partner in the right image has no data (or lies outside it)."""
    h, w = et.d.shape
    rr, cc = np.mgrid[0:h, 0:w]
    xr = np.rint(cc - np.nan_to_num(et.d, nan=-1e9)).astype(np.int64)
    inside = (xr >= 0) & (xr < right.shape[1]) & np.isfinite(et.d)
    out = ~inside
    out[inside] = ~np.isfinite(right[rr[inside], xr[inside]])
    return out


def _by_edge_distance(et: EpiTruth, ok: np.ndarray, gsd: float) -> List[Dict[str, Any]]:
    """Valid share of roof pixels by their distance to the roof's edge (left image)."""
    dist = ndimage.distance_transform_edt(np.isin(et.cls, (1, 2))) * gsd  # m, approx.
    roof = et.roof()
    rows = []
    for lo, hi in ((1.0, 2.0), (2.0, 3.0), (3.0, 5.0), (5.0, np.inf)):
        b = roof & (dist >= lo) & (dist < hi)
        rows.append({"edge_distance_m": f"{lo:g}–{hi:g}", "roof_px_pct": _pct(b, roof),
                     "roof_valid_pct": _pct(ok, b)})
    return rows


def dense_causes(et: EpiTruth, grey: Dict[str, np.ndarray], disp: Dict[str, np.ndarray],
                 gsd: float) -> Dict[str, Any]:
    """Why roof pixels have no disparity: partner without data, texture, edge distance."""
    tex = _texture(grey["left"])
    inter, open_ = et.roof(), et.cls == 3
    ok = np.isfinite(disp["prod"])
    missing = _partner_missing(et, grey["right"])
    raw_bad = inter & ~np.isfinite(disp["raw"])
    edges = [0.0, 1.0, 2.0, 4.0, 8.0, np.inf]
    by_tex = []
    for lo, hi in zip(edges[:-1], edges[1:]):
        b = (tex >= lo) & (tex < hi)
        by_tex.append({"texture_std": f"{lo:g}–{hi:g}", "roof_px_pct": _pct(b, inter),
                       "open_px_pct": _pct(b, open_),
                       "roof_valid_pct": _pct(ok, inter & b),
                       "open_valid_pct": _pct(ok, open_ & b)})
    return {"roof_texture_median": float(np.median(tex[inter])),
            "open_texture_median": float(np.median(tex[open_])),
            "tree_texture_median": float(np.median(tex[et.tree()])),
            "roof_occluded_right_pct": _pct(et.occluded, inter),
            "roof_partner_nodata_pct": _pct(missing, inter),
            "roof_sgbm_invalid_pct": _pct(raw_bad, inter),
            "roof_sgbm_invalid_partner_nodata_pct": _pct(raw_bad & missing, inter),
            "roof_valid_pct_partner_ok": _pct(ok, inter & ~missing),
            "by_edge_distance": _by_edge_distance(et, ok, gsd),
            "roof_share_of_interior_pct": _pct(inter, et.cls == 1),
            "by_texture": by_tex}


def dense_range(setup: Any, et: EpiTruth, grey: Dict[str, np.ndarray]) -> Dict[str, Any]:
    """The search range: its width, whether the coarse pass narrows it, and the interior
    pixels whose true disparity lies outside it (or outside its coarse narrowing)."""
    lo, hi = setup.min_d, setup.max_d
    inter = et.cls == 1
    with np.errstate(invalid="ignore"):
        outside = (et.d < lo) | (et.d > hi)
    out = {"search_range_px": [int(lo), int(hi)],
           "coarse_narrowing": bool(dense_mod._num_disparities(lo, hi) > dense_mod.COARSE_ABOVE),
           "interior_true_d_outside_range_pct": _pct(outside, inter)}
    if out["coarse_narrowing"]:
        factor = dense_mod._coarse_factor(dense_mod._num_disparities(lo, hi))
        src_l, shape_l = dense_mod.array_source(grey["left"])
        src_r, shape_r = dense_mod.array_source(grey["right"])
        coarse = dense_mod._coarse_disparity(
            src_l, src_r, shape_l, shape_r, lo, hi, factor, dense_mod.DenseOptions(),
            Feedback(), margin=48)
        # the coarse disparities at the pixel's block, ± the slack of a tile's range
        cz = np.kron(coarse, np.ones((factor, factor)))[:et.d.shape[0], :et.d.shape[1]]
        with np.errstate(invalid="ignore"):
            dz = np.abs(cz - et.d)
        out["coarse_factor"] = factor
        out["interior_coarse_valid_pct"] = _pct(np.isfinite(cz), inter)
        out["interior_coarse_right_2px_pct"] = _pct(dz <= 2.0 * factor, inter)
        out["open_coarse_right_2px_pct"] = _pct(dz <= 2.0 * factor, et.cls == 3)
    return out


def dense_gridding(setup: Any, truth: Truth, disp: np.ndarray) -> List[Dict[str, Any]]:
    """Median per cell, outlier test and gap limit switched on one after the other."""
    grid, pair = setup.grid, setup.pair
    ok = np.isfinite(disp)
    rr, cc = np.nonzero(ok)
    pts = pair.disparity_to_world(disp[ok], cc, rr)
    acc = GridAccumulator(grid)
    acc.add(pts[:, 0], pts[:, 1], pts[:, 2])
    zg, count = acc.reduce()
    r, c = interior_cells(setup, truth)
    zt = _truth_at_cells(setup, truth, r, c)
    spacing = setup.spacing
    radius, thr = 5.0 * spacing, float(setup.gsd) * setup.flying_height / pair.base
    rows = []
    for name, kw in (("median per cell", {"max_gap": 0.0}),
                     ("+ outlier test", {"max_gap": 0.0, "outlier_radius": radius,
                                         "outlier_threshold": thr}),
                     ("+ gap filling ≤ 2 m (production)",
                      {"max_gap": 10.0 * spacing, "outlier_radius": radius,
                       "outlier_threshold": thr}),
                     ("+ gap filling ≤ 20 m", {"max_gap": 100.0 * spacing,
                                              "outlier_radius": radius,
                                              "outlier_threshold": thr})):
        res = finish_grid(zg, count, grid, exclusions=setup.exclusions,
                          boundary=setup.boundaries, breaklines=setup.breaklines, **kw)
        z = res.z[r, c]
        rows.append({"step": name, "interior_cells_with_height_pct": _pct(np.isfinite(z)),
                     "interior_cells_0_5_pct": _pct(np.abs(z - zt) <= TOL)})
    return rows


# -- the run -------------------------------------------------------------------------------------


def _md(rows: List[Dict[str, Any]]) -> str:
    keys = list(rows[0]) if rows else []
    out = ["| " + " | ".join(keys) + " |", "|" + "---|" * len(keys)]
    for r in rows:
        out.append("| " + " | ".join(f"{v:.1f}" if isinstance(v, float) else str(v)
                                     for v in r.values()) + " |")
    return "\n".join(out)


def _products(block: Path, out: Path, truth: Truth, gsd: float, model: str,
              heights: Dict[str, float], fbm_only: bool = False, dense_only: bool = False
              ) -> List[Dict[str, Any]]:
    """match_model for terrain, general, urban (unless ``dense_only``) and dense (unless
    ``fbm_only``); the issue's table rows."""
    rows = []
    runs = [] if dense_only else [("fbm_lsm terrain", {"preset": "terrain"}),
                                  ("fbm_lsm general", {"preset": "general"}),
                                  ("fbm_lsm urban", {"preset": "urban"})]
    if not fbm_only:
        runs.append(("dense", {"method": "dense"}))
    for name, params in runs:
        r = registry.run("match_model", {"project": str(block), "model": model,
                                         "output": str(out / name.replace(" ", "_")),
                                         **heights, **params})
        rows.append(dsm_row(name, on_truth_grid(Path(r["dsm"]), truth), truth, gsd))
    return rows


def model_and_heights(block: Path) -> Tuple[str, Dict[str, float]]:
    """The diagnosed model of a block and its height range: the ``small`` block's model with
    the default range, or an ``aerial`` block's model with the truth's range ± 5 m (as
    ``bench_dsm_objects``; the default ± 0.3 H would be a range of 690 m there)."""
    from photodem.algorithms.project.model import Project  # lazy: one use

    project = Project.load(block)
    names = {m.name for m in project.models}
    if "aerial" not in project.name or AERIAL_MODEL not in names:
        return MODEL, {}
    z, _, _ = _read(block / "truth" / "dsm.tif")
    return AERIAL_MODEL, {"min_height": float(np.nanmin(z)) - 5.0,
                          "max_height": float(np.nanmax(z)) + 5.0}


def diagnose(block: Path, work: Path, fbm_only: bool = False, dense_only: bool = False
             ) -> Dict[str, Any]:
    """All tables of the diagnosis (see the module text); ``fbm_only`` / ``dense_only`` skip
    the other matcher."""
    t0 = time.perf_counter()
    model, heights = model_and_heights(block)
    setup = prepare_model(block, model, spacing_gsd=fbm_model.SPACING_GSD, **heights)
    truth = load_truth(block, setup)
    products = _products(block, work, truth, float(setup.gsd), model, heights, fbm_only,
                           dense_only)
    et = epipolar_truth(setup, truth)
    grey, mask, barriers = fbm_model._grey_epipolar(setup, Feedback())
    seeds = fbm_model.start_point_seeds(setup)
    levels, chains = [], []
    for preset in () if dense_only else ("terrain", "general", "urban"):
        levels += fbm_levels(setup, et, grey, mask, barriers, preset, seeds)
        chains.append(fbm_chain(setup, truth, et, grey, mask, barriers, preset, seeds))
    steps, causes, gridding = [], {}, []
    if not fbm_only:
        setup_dense = prepare_model(block, model, spacing_gsd=1.0, **heights)
        steps, disp = dense_steps(setup_dense, et, grey)
        causes = dense_causes(et, grey, disp, float(setup.gsd))
        causes.update(dense_range(setup_dense, et, grey))
        gridding = dense_gridding(setup_dense, truth, disp["prod"])
    return {"block": str(block), "model": model, "gsd_m": float(setup.gsd),
            "flying_height_m": float(setup.flying_height),
            "buildings_in_area": int(truth.heights.size),
            "interior_share_of_area_pct": _pct(truth.interior, truth.area),
            "objects_share_of_area_pct": _pct(truth.objects, truth.area),
            "products": products, "fbm_levels": levels, "fbm_chain": chains,
            "dense_steps": steps, "dense_causes": causes, "dense_gridding": gridding,
            "seconds": round(time.perf_counter() - t0, 1)}


def report(res: Dict[str, Any]) -> str:
    """The tables as Markdown."""
    chain = res["fbm_chain"] or [{"preset": "–"}]
    parts = [f"block {res['block']}, model {res['model']}, GSD {res['gsd_m']:.3f} m, "
             f"H {res['flying_height_m']:.0f} m; {res['buildings_in_area']} buildings inside "
             f"the area; objects {res['objects_share_of_area_pct']:.1f} %, interior "
             f"{res['interior_share_of_area_pct']:.1f} % of the area",
             "DSMs:", _md(res["products"]), "fbm_lsm points per level:", _md(res["fbm_levels"]),
             "fbm_lsm chain:", _md([{"key": k, **{c["preset"]: c[k] for c in chain}}
                                   for k in chain[0] if k != "preset"])]
    if res["dense_steps"]:
        causes = dict(res["dense_causes"])
        by_tex = causes.pop("by_texture")
        by_edge = causes.pop("by_edge_distance")
        parts += ["dense filter steps:", _md(res["dense_steps"]),
                  "dense causes: " + json.dumps(causes), _md(by_tex), _md(by_edge),
                  "dense gridding:", _md(res["dense_gridding"])]
    return "\n\n".join(parts)


def _aerial_start_point(block: Path) -> None:
    """One start point at the true terrain height, as ``bench_dsm_objects`` gives it."""
    from .bench_dsm_accuracy import _start_point  # lazy: only generated aerial blocks

    truth = {k: str(block / "truth" / f"{k}.tif") for k in ("dsm", "dtm")}
    _, heights = model_and_heights(block)
    _start_point(block, truth, heights["min_height"], heights["max_height"])


def main(argv: List[str]) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("block", nargs="?", help="block folder (default: a new small block)")
    ap.add_argument("--json", help="write all numbers to this JSON file")
    ap.add_argument("--seed", type=int, default=1, help="seed of a generated block (default 1, "
                                                        "as make demo)")
    ap.add_argument("--size", default="small", choices=("small", "aerial"),
                    help="size of a generated block (default small)")
    only = ap.add_mutually_exclusive_group()
    only.add_argument("--fbm-only", action="store_true", help="fbm_lsm tables only (no dense)")
    only.add_argument("--dense-only", action="store_true", help="dense tables only (no fbm_lsm)")
    args = ap.parse_args(argv)
    with tempfile.TemporaryDirectory(prefix="diagnose-objects-") as tmp:
        block = Path(args.block) if args.block else None
        if block is None:
            block = Path(tmp) / args.size
            params = {"size": args.size, "seed": args.seed, "output": str(block)}
            if args.size == "aerial":
                params["terrain"] = "gentle"  # as bench_dsm_objects
            registry.run("synthetic_block", params)
            if args.size == "aerial":
                _aerial_start_point(block)
        res = diagnose(block, Path(tmp), fbm_only=args.fbm_only, dense_only=args.dense_only)
    if args.json:
        Path(args.json).write_text(json.dumps(res, indent=1, default=float))
    print(report(res))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
