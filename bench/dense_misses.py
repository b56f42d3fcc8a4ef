"""Where a dense DSM loses its object-interior and open cells (issue 19).

For one block of ``dense_objects_seeds`` (built there and kept) this script matches the
block's model with dense (or reads a DSM matched before into ``WORK``) and splits the cells
that ``bench_dsm_objects`` judges (the model's stereo overlap; the shares of the measuring
area outside a frame at their true height are given first) into

* by land cover: object-interior cells on buildings and on trees;
* by what the DSM has there: a *measured* cell (``count.tif`` > 0), an *interpolated* one
  (a height, count 0) or an *empty* one (NaN) — each right (within 0.5 m of the true DSM),
  too low or too high;
* crown cells of the interior by the true surface's slope (right and empty shares);
* open cells that miss, by their distance from the nearest object (occlusion rings lie
  1–4 m from a wall).

With ``--fill`` it also judges the same DSM with its holes filled from their low side
(:func:`photodem.algorithms.ortho.visibility.fill_from_below`'s neighbours, the ones within
1 m of the lowest averaged by inverse distance, at least two of the four directions), the
trial recorded in ``docs/decisions.md`` (2026-11-28, occlusion rings).

Usage (from the repository root)::

    .venv/bin/python -m bench.dense_misses BLOCKS_DIR aerial:11 WORK [--options JSON] [--fill]

Not part of ``make bench``; the numbers go to ``docs/decisions.md``.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any, Dict, List

import numpy as np
import rasterio
from rasterio.features import geometry_mask
from scipy import ndimage

#: land-cover codes of the truth (``algorithms.synthetic.objects.LANDCOVER``)
BUILDING, TREE = 3, 4
#: distance bands (m) of the open cells from the nearest object
OPEN_BANDS = ((1.0, 2.0), (2.0, 4.0), (4.0, 8.0), (8.0, np.inf))
#: slope bands (degrees) of the crowns, and the smoothing (m) of the true DSM for the slope
#: (the leaf clumps' relief, λ ≈ 0.6 m, is not the crown's slope)
SLOPE_BANDS = ((0.0, 30.0), (30.0, 45.0), (45.0, 60.0), (60.0, 90.1))
SLOPE_SMOOTHING_M = 0.2


def _shares(sel: np.ndarray, err: np.ndarray, measured: np.ndarray) -> Dict[str, float]:
    """Shares (% of ``sel``) of the cells by state (measured / interpolated / empty) and
    error (right within 0.5 m, too low, too high)."""
    e, m = err[sel], measured[sel]
    n = max(e.size, 1)
    row: Dict[str, float] = {}
    for state, k in (("measured", m), ("interpolated", ~m & np.isfinite(e))):
        row[f"{state}_right"] = 100.0 * np.count_nonzero(k & (np.abs(e) <= 0.5)) / n
        row[f"{state}_low"] = 100.0 * np.count_nonzero(k & (e < -0.5)) / n
        row[f"{state}_high"] = 100.0 * np.count_nonzero(k & (e > 0.5)) / n
    row["empty"] = 100.0 * np.count_nonzero(np.isnan(e)) / n
    return {k: round(v, 2) for k, v in row.items()}


def _by_slope(true_dsm: np.ndarray, cell: float, sel: np.ndarray, err: np.ndarray
              ) -> List[Dict[str, float]]:
    """Shares of ``sel`` per slope band of the (smoothed) true surface, and right / empty
    within each band."""
    gy, gx = np.gradient(ndimage.gaussian_filter(true_dsm, SLOPE_SMOOTHING_M / cell), cell)
    slope = np.degrees(np.arctan(np.hypot(gx, gy)))
    n = max(int(sel.sum()), 1)
    rows = []
    for lo, hi in SLOPE_BANDS:
        k = sel & (slope >= lo) & (slope < hi)
        m = max(int(k.sum()), 1)
        rows.append({"from_deg": lo, "to_deg": hi, "cells_pct": round(100.0 * k.sum() / n, 1),
                     "right_pct": round(100.0 * np.count_nonzero(k & (np.abs(err) <= 0.5)) / m, 1),
                     "empty_pct": round(100.0 * np.count_nonzero(k & np.isnan(err)) / m, 1)})
    return rows


def breakdown(info: Dict[str, Any], model: str, dsm: Path, count: Path) -> Dict[str, Any]:
    """The split of the interior and open cells of ``dsm`` on the truth grid, in the model's
    stereo overlap."""
    from photodem.algorithms.matching.model_setup import prepare_model
    from photodem.algorithms.quality.objects import object_masks
    from photodem.algorithms.quality.stereo_overlap import stereo_overlap

    from .truth_grid import on_grid

    t = info["truth"]
    with rasterio.open(t["dsm"]) as ref:
        true_dsm = ref.read(1).astype(np.float64)
        cell = abs(ref.transform.a)
        setup = prepare_model(info["project"], model, **info["heights"])
        area = geometry_mask([setup.measuring_area()], out_shape=true_dsm.shape,
                             transform=ref.transform, invert=True)
        grid = (true_dsm.shape, ref.transform, ref.crs)
        z = on_grid(dsm, *grid)
        measured = np.nan_to_num(on_grid(count, *grid, nearest=True)) > 0
        frames = setup.frames
        in_frames = geometry_mask([stereo_overlap(frames, t["dsm"])], out_shape=true_dsm.shape,
                                  transform=ref.transform, invert=True)
    with rasterio.open(t["dtm"]) as src:
        true_dtm = src.read(1).astype(np.float64)
    with rasterio.open(t["landcover"]) as src:
        cover = src.read(1)
    masks = object_masks(true_dsm, true_dtm, cell)
    err = z - true_dsm
    # cells outside a frame at their true height: no stereo method measures them
    out: Dict[str, Any] = {
        f"{name}_outside_frames_pct": round(
            100.0 * (cls & area & ~in_frames).sum() / max((cls & area).sum(), 1), 2)
        for name, cls in (("interior", masks.interior), ("open", masks.open))}
    area &= in_frames
    interior = masks.interior & area
    out["interior_cells"] = int(interior.sum())
    for name, code in (("buildings", BUILDING), ("trees", TREE)):
        sel = interior & (cover == code)
        out[name] = {"share_of_interior": round(100.0 * sel.sum() / max(interior.sum(), 1), 1),
                     **_shares(sel, err, measured)}
    out["trees_by_slope"] = _by_slope(true_dsm, cell, interior & (cover == TREE), err)
    open_ = masks.open & area
    out["open"] = _shares(open_, err, measured)
    dist = ndimage.distance_transform_edt(~masks.objects) * cell
    miss = open_ & ~(np.abs(err) <= 0.5)
    n_open = max(open_.sum(), 1)
    out["open_misses_by_distance"] = [
        {"from_m": lo, "to_m": hi, "cells_pct": round(100.0 * (open_ & band).sum() / n_open, 2),
         "missed_pct": round(100.0 * (miss & band).sum() / n_open, 2),
         "missed_empty_pct": round(100.0 * (miss & band & np.isnan(err)).sum() / n_open, 2)}
        for lo, hi in OPEN_BANDS for band in [(dist >= lo) & (dist < hi)]]
    return out


def fill_low_side(z: np.ndarray, max_cells: int, tolerance: float = 1.0,
                  min_directions: int = 2) -> np.ndarray:
    """The trial fill: each hole cell takes the inverse-distance mean of its nearest valid
    cells in the four axis directions (up to ``max_cells``) that lie within ``tolerance`` m of
    the lowest of them, where at least ``min_directions`` qualify."""
    from photodem.algorithms.ortho.visibility import nearest_valid_along

    valid = np.isfinite(z)
    found = [nearest_valid_along(z, valid, axis, rev, max_cells)
             for axis in (0, 1) for rev in (False, True)]
    h = np.stack([f[0] for f in found])
    d = np.maximum(np.stack([f[1] for f in found]), 1.0)
    use = np.isfinite(h) & (h <= np.fmin.reduce(h, axis=0) + tolerance)
    w = np.where(use, 1.0 / d, 0.0)
    est = (w * np.where(use, h, 0.0)).sum(axis=0) / np.maximum(w.sum(axis=0), 1e-12)
    take = ~valid & (use.sum(axis=0) >= min_directions)
    out = z.copy()
    out[take] = est[take]
    return out


def judged_with_fill(info: Dict[str, Any], model: str, dsm: Path, reach_m: float = 8.0
                     ) -> Dict[str, Any]:
    """``bench_dsm_objects``'s figures of ``dsm`` with its holes filled by
    :func:`fill_low_side` (written beside it as ``dsm_filled.tif``)."""
    from .bench_dsm_objects import _judge

    with rasterio.open(dsm) as src:
        z = src.read(1).astype(np.float64)
        if src.nodata is not None and not np.isnan(src.nodata):
            z[z == src.nodata] = np.nan
        profile = src.profile
        cell = abs(src.transform.a)
    filled = fill_low_side(z, round(reach_m / cell))
    profile.update(dtype="float32", nodata=np.nan)
    target = dsm.with_name("dsm_filled.tif")
    with rasterio.open(target, "w", **profile) as dst:
        dst.write(filled.astype(np.float32), 1)
    return {k: v for k, v in _judge(info, model, str(target)).items() if not k.startswith("_")}


def main(argv: List[str]) -> int:
    from photodem.algorithms.matching.dense_model import match_model_dense

    from .bench_dsm_objects import _judge
    from .dense_objects_seeds import MODELS, block

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("blocks", help="folder of the built blocks (kept between runs)")
    ap.add_argument("spec", help="SIZE:SEED, e.g. aerial:11")
    ap.add_argument("work", help="folder of the dense DSM (matched unless dsm.tif is there)")
    ap.add_argument("--options", default="{}", help="dense options as JSON (a new WORK)")
    ap.add_argument("--fill", action="store_true", help="also judge the low-side fill")
    args = ap.parse_args(argv)
    size, seed = args.spec.split(":")
    info = block(Path(args.blocks), size, int(seed))
    model, work = MODELS[size], Path(args.work)
    if not (work / "dsm.tif").exists():
        match_model_dense(info["project"], model, str(work), **info["heights"],
                          **json.loads(args.options))
    dsm = work / "dsm.tif"
    print(json.dumps(breakdown(info, model, dsm, work / "count.tif"), indent=1))
    print(json.dumps({k: v for k, v in _judge(info, model, str(dsm)).items()
                      if not k.startswith("_")}))
    if args.fill:
        print(json.dumps(judged_with_fill(info, model, dsm)))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
