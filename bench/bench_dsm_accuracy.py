"""DSM accuracy of the matchers in ‰ of the flying height (issue 4 acceptance).

(a) Synthetic ``aerial`` block (wide-angle film geometry rendered as 1024 px windows: base
    ≈ 4600 px, so σ_Z/H = σ_px / base_px is the same as for a full aerial model), model
    0101_0102 with one start point:
    - ``fbm_lsm`` (hierarchical FBM + LSM, groundels, FE surface),
    - ``dense`` (our SGM) and the peer ``dense`` with OpenCV's plain StereoSGBM in the same run,
    - ``refine_object_space`` (3 images) started from the dense DSM,
    each against the true DSM on open textured land cover (classes 1 open, 7 field): RMS, NMAD
    in m and ‰ H, over all cells and over the measured cells (within half a groundel of a
    matched point for fbm_lsm). Targets: fbm_lsm ≤ 0.1 ‰, dense ≤ 0.15 ‰, refined ≤ 0.07 ‰.
(b) Texture direction (seed-000 §6): field furrows parallel vs perpendicular to the epipolar
    lines (flight direction) → fbm_lsm RMS and point count on the field class.
(c) NGI pair 0182/0184: fbm_lsm and dense DSMs against the 24 m reference ``dem.tif``: RMS,
    NMAD, coverage, and RMS / NMAD on the cells every method has (dense leaves unmatched cells
    empty, fbm_lsm interpolates them, so the all-cells figures are over different cells).
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path
from typing import Any, Dict, Optional

import numpy as np

from photodem.algorithms.matching.presets import DEFAULT_PRESET

DATA = Path(__file__).resolve().parents[2] / "shared" / "data" / "ngi_aerial_block"
MODEL = "0101_0102"
OPEN = (1, 7)
#: Terrain cells closer than this to a building or tree (truth DSM above the DTM) are left out
#: of the terrain figures: about one matching window (13–15 px at 0.15 m), where DSMs show the
#: edge of the object (fattening, the grid cell straddling a wall) rather than the terrain.
TERRAIN_MARGIN_M = 2.0


def _errors(dsm: str, truth: Dict[str, Any], count: Optional[str] = None,
            radius: float = 0.0, classes=OPEN) -> Dict[str, float]:
    """DSM − true DSM on the given classes (all cells, and near matched points)."""
    import rasterio
    from rasterio.warp import Resampling, reproject
    from scipy import ndimage

    with rasterio.open(dsm) as src:
        z, transform, crs = src.read(1), src.transform, src.crs
    ref = np.full(z.shape, np.nan, np.float32)
    lc = np.zeros(z.shape, np.float32)
    for path, arr, how in ((truth["dsm"], ref, Resampling.average),
                           (truth["landcover"], lc, Resampling.nearest)):
        with rasterio.open(path) as src:
            reproject(rasterio.band(src, 1), arr, dst_transform=transform, dst_crs=crs,
                      resampling=how)
    sel = np.isin(lc, classes) & np.isfinite(z) & np.isfinite(ref)
    out = {}
    masks = {"all": sel}
    if count:
        with rasterio.open(count) as src:
            n = src.read(1)
        near = ndimage.distance_transform_edt(n == 0) * transform.a <= radius
        masks["measured"] = sel & near
    for key, m in masks.items():
        d = (z - ref)[m].astype(float)
        out[f"rms_{key}_m"] = float(np.sqrt(np.mean(d**2))) if d.size else float("nan")
        out[f"nmad_{key}_m"] = (float(1.4826 * np.median(np.abs(d - np.median(d))))
                                if d.size else float("nan"))
        out[f"cells_{key}"] = int(d.size)
    return out


def _terrain_errors(dsm: str, truth: Dict[str, Any], margin: float = TERRAIN_MARGIN_M
                    ) -> Dict[str, float]:
    """DSM − true DTM on open textured terrain: classes OPEN, no object on the cell, and at
    least ``margin`` m from every object (the issue's "DSM vs truth DTM on open textured
    terrain")."""
    import rasterio
    from rasterio.warp import Resampling, reproject
    from scipy import ndimage

    with rasterio.open(dsm) as src:
        z, transform, crs = src.read(1), src.transform, src.crs
    arrs = {}
    for key, how in (("dtm", Resampling.average), ("dsm", Resampling.average),
                     ("landcover", Resampling.nearest)):
        arrs[key] = np.full(z.shape, np.nan, np.float32)
        with rasterio.open(truth[key]) as src:
            reproject(rasterio.band(src, 1), arrs[key], dst_transform=transform, dst_crs=crs,
                      resampling=how)
    obj = ~(arrs["dsm"] - arrs["dtm"] <= 0.05)  # objects, and NaN, count as not terrain
    far = ndimage.distance_transform_edt(~obj) * transform.a > margin
    sel = np.isin(arrs["landcover"], OPEN) & far & np.isfinite(z)
    d = (z - arrs["dtm"])[sel].astype(float)
    return {"rms_m": float(np.sqrt(np.mean(d**2))) if d.size else float("nan"),
            "nmad_m": float(1.4826 * np.median(np.abs(d - np.median(d)))) if d.size
            else float("nan"), "cells": int(d.size)}


def _start_point(project: Path, truth: Dict[str, Any], lo: float, hi: float) -> None:
    import rasterio
    from shapely.geometry import Point

    from photodem.algorithms.matching.model_setup import prepare_model
    from photodem.algorithms.project.edits import add_features

    setup = prepare_model(project, MODEL, min_height=lo, max_height=hi)
    c = setup.measuring_area().centroid
    with rasterio.open(truth["dtm"]) as src:
        h = float(next(src.sample([(c.x, c.y)]))[0])
    add_features(project / "edits.gpkg", "start_points", [(Point(c.x, c.y), {"height": h})])


def _block(tmp: Path, name: str, texture_direction: float = 0.0):
    import rasterio

    from photodem.algorithms.synthetic.block import generate_block

    block = generate_block(tmp / name, size="aerial", terrain="gentle", seed=1,
                           texture_direction=texture_direction)
    truth = {k: str(v) for k, v in block.truth.items()}
    with rasterio.open(truth["dsm"]) as src:
        z = src.read(1)
    lo, hi = float(np.nanmin(z)) - 5.0, float(np.nanmax(z)) + 5.0
    _start_point(block.project, truth, lo, hi)
    return block, truth, lo, hi


def _row(case: str, res: Dict[str, Any], errs: Dict[str, float], H: float,
         seconds: float, target: Optional[float], terrain: Dict[str, float]) -> Dict[str, Any]:
    row = {"case": case, "terrain_rms_m": terrain["rms_m"],
           "terrain_rms_permille_h": 1000.0 * terrain["rms_m"] / H,
           "rms_m": errs["rms_all_m"], "nmad_m": errs["nmad_all_m"],
           "rms_permille_h": 1000.0 * errs["rms_all_m"] / H}
    if "rms_measured_m" in errs:
        row["rms_measured_m"] = errs["rms_measured_m"]
        row["rms_measured_permille_h"] = 1000.0 * errs["rms_measured_m"] / H
    row.update(coverage_pct=res["metrics"].get("coverage_pct"),
               measured_pct=res["metrics"].get("measured_pct"), seconds=seconds,
               target_permille_h=target)
    return row


def _synthetic(tmp: Path) -> Dict[str, Any]:
    from photodem.algorithms.matching.dense_model import match_model_dense
    from photodem.algorithms.matching.fbm_model import match_model_fbm_lsm
    from photodem.algorithms.matching.object_space import refine_object_space

    block, truth, lo, hi = _block(tmp, "aerial")
    H = float(block.flying_height)
    rows = []
    t0 = time.perf_counter()
    # the terrain preset explicitly (the default of earlier runs, then called "flat"): the
    # terrain target refers to it; the default 'general' keeps objects (issue 19) and is
    # measured beside it, as is 'urban' (built-up areas: on this open terrain its small
    # windows cost accuracy, docs/decisions.md)
    fbm = match_model_fbm_lsm(block.project, MODEL, tmp / "fbm", preset="terrain")
    dt = time.perf_counter() - t0
    half = 0.5 * fbm["metrics"]["groundel_m"]
    rows.append(_row("fbm_lsm terrain preset (1 start point)", fbm,
                     _errors(fbm["dsm"], truth, fbm["count"], half), H, dt, 0.1,
                     _terrain_errors(fbm["dsm"], truth)))
    t0 = time.perf_counter()
    gen = match_model_fbm_lsm(block.project, MODEL, tmp / "fbm_general")
    dt = time.perf_counter() - t0
    rows.append(_row(f"fbm_lsm default preset {DEFAULT_PRESET} (1 start point)", gen,
                     _errors(gen["dsm"], truth, gen["count"],
                             0.5 * gen["metrics"]["groundel_m"]), H, dt, 0.1,
                     _terrain_errors(gen["dsm"], truth)))
    t0 = time.perf_counter()
    urb = match_model_fbm_lsm(block.project, MODEL, tmp / "fbm_urban", preset="urban")
    dt = time.perf_counter() - t0
    rows.append(_row("fbm_lsm urban preset (1 start point)", urb,
                     _errors(urb["dsm"], truth, urb["count"],
                             0.5 * urb["metrics"]["groundel_m"]), H, dt, None,
                     _terrain_errors(urb["dsm"], truth)))
    dense = {}
    for method in ("sgm", "opencv_sgbm"):
        t0 = time.perf_counter()
        dense[method] = match_model_dense(block.project, MODEL, tmp / f"dense_{method}",
                                          min_height=lo, max_height=hi, method=method)
        dt = time.perf_counter() - t0
        rows.append(_row(f"dense {method}", dense[method],
                         _errors(dense[method]["dsm"], truth), H, dt,
                         0.15 if method == "sgm" else None,
                         _terrain_errors(dense[method]["dsm"], truth)))
    t0 = time.perf_counter()
    ref = refine_object_space(block.project, dense["sgm"]["dsm"], tmp / "refined")
    dt = time.perf_counter() - t0
    ref.setdefault("metrics", {})
    rows.append(_row("refine_object_space (3 images) from dense sgm", ref,
                     _errors(ref["dsm"], truth), H, dt, 0.07, _terrain_errors(ref["dsm"], truth)))
    ratio = rows[3]["rms_m"] / rows[4]["rms_m"] if rows[4]["rms_m"] else None
    return {"flying_height_m": H, "gsd_m": block.gsd, "base_px": block.base_px,
            "rows": rows, "dense_rms_ratio_ours_over_sgbm": ratio}


def _texture(tmp: Path) -> Dict[str, Any]:
    from photodem.algorithms.matching.fbm_model import match_model_fbm_lsm

    rows = []
    for direction, label in ((0.0, "parallel"), (90.0, "perpendicular")):
        block, truth, _, _ = _block(tmp, f"tex{int(direction)}", direction)
        r = match_model_fbm_lsm(block.project, MODEL, tmp / f"tex_fbm{int(direction)}",
                                preset="terrain")
        half = 0.5 * r["metrics"]["groundel_m"]
        e = _errors(r["dsm"], truth, r["count"], half, classes=(7,))
        t = _terrain_errors(r["dsm"], truth)
        rows.append({"case": f"furrows {label} to the epipolar lines (field class)",
                     "points": r["metrics"]["points_raw"],
                     "measured_pct": r["metrics"]["measured_pct"],
                     "terrain_nmad_m": t["nmad_m"], "terrain_rms_m": t["rms_m"],
                     "rms_m": e["rms_all_m"], "rms_measured_m": e["rms_measured_m"],
                     "nmad_measured_m": e["nmad_measured_m"]})
    return {"rows": rows}


def _ngi(tmp: Path) -> Dict[str, Any]:
    from photodem.algorithms.processing import registry
    from photodem.algorithms.quality.compare import compare_dems

    proj = tmp / "ngi"
    registry.run("project_create", {
        "images": str(DATA / "ngi"), "exterior": str(DATA / "io" / "ngi_xyz_opk.csv"),
        "interior": str(DATA / "io" / "ngi_int_param.yaml"), "angle_unit": "degrees",
        "dem": str(DATA / "ngi" / "dem.tif"), "output": str(proj)})
    info = registry.run("project_info", {"project": str(proj)})
    model = next((m for m in info["models"]
                  if {m["left"][-8:-4], m["right"][-8:-4]} & {"0182", "0184"} == {"0182", "0184"}
                  or ("0182" in m["name"] and "0184" in m["name"])), None)
    if model is None:
        return {"skipped": "no model 0182/0184 in the created project"}
    out: Dict[str, Any] = {}
    diffs: Dict[str, Path] = {}
    # the terrain preset (the default of earlier runs, then 'flat'), the default 'general',
    # 'urban' and the one an operator picks for these mountains
    for key, method, preset in (("fbm_lsm", "fbm_lsm", "terrain"),
                                (f"fbm_lsm {DEFAULT_PRESET}", "fbm_lsm", None),
                                ("fbm_lsm urban", "fbm_lsm", "urban"),
                                ("fbm_lsm hilly", "fbm_lsm", "hilly"),
                                ("dense", "dense", None)):
        t0 = time.perf_counter()
        params = {"project": str(proj), "model": model["name"], "method": method,
                  "min_height": 100.0, "max_height": 850.0, "spacing": 24.0,
                  "output": str(tmp / f"ngi_{key.replace(' ', '_')}")}
        if preset:
            params["preset"] = preset
        r = registry.run("match_model", params)
        dt = time.perf_counter() - t0
        diffs[key] = tmp / f"ngi_{key.replace(' ', '_')}_dh.tif"
        s = compare_dems(r["dsm"], DATA / "ngi" / "dem.tif", difference_path=diffs[key])["stats"]
        h = model["height_above_ground_m"]
        out[key] = {"rms_m": s["rms"], "nmad_m": s["nmad"], "mean_m": s["mean"],
                    "rms_permille_h": 1000 * s["rms"] / h,
                    "coverage_pct": r["metrics"]["coverage_pct"],
                    "measured_pct": r["metrics"].get("measured_pct"), "seconds": dt}
    for key, s in _on_common_cells(diffs).items():
        out[key].update(rms_common_m=s["rms"], nmad_common_m=s["nmad"], cells_common=s["count"])
    out["model"] = model["name"]
    return out


def _on_common_cells(diffs: Dict[str, Path]) -> Dict[str, Dict[str, Any]]:
    """Statistics of each Δh raster (same reference grid) on the cells all of them have:
    dense leaves the cells it cannot match empty, fbm_lsm interpolates them."""
    import rasterio

    from photodem.algorithms.quality.stats import difference_stats

    dh = {}
    for key, path in diffs.items():
        with rasterio.open(path) as src:
            dh[key] = src.read(1)
    common = np.logical_and.reduce([np.isfinite(d) for d in dh.values()])
    return {key: difference_stats(d[common]) for key, d in dh.items()}


def run() -> dict:
    with tempfile.TemporaryDirectory(prefix="bench-dsm-") as tmp:
        tmp = Path(tmp)
        result: Dict[str, Any] = {"synthetic_aerial": _synthetic(tmp),
                                  "texture": _texture(tmp)}
        result["ngi_0182_0184"] = (_ngi(tmp) if DATA.is_dir()
                                   else {"skipped": f"real data not found at {DATA}"})
    rows = list(result["synthetic_aerial"]["rows"]) + list(result["texture"]["rows"])
    ngi = result["ngi_0182_0184"]
    for method in ("fbm_lsm", f"fbm_lsm {DEFAULT_PRESET}", "fbm_lsm urban", "fbm_lsm hilly",
                   "dense"):
        if method in ngi:
            rows.append({"case": f"NGI {ngi['model']} {method} vs dem.tif (24 m grid)",
                         **ngi[method]})
    result.update(
        title="DSM accuracy of fbm_lsm, dense and object-space refinement (‰ of H)",
        rows=rows,
        notes=["terrain_rms = DSM − truth DTM on open textured terrain: land-cover classes 1 "
               "(open) and 7 (field) of the synthetic truth, no object on the cell and at least "
               f"{TERRAIN_MARGIN_M:g} m (about one matching window) from every building and tree; "
               "the targets refer to this figure",
               "texture direction (seed: furrows parallel to the epipolar lines up to ×2 worse): "
               "compare points, measured share and terrain NMAD; the terrain RMS of both is "
               "dominated by a few gross areas (furrow-period mismatches across the furrows, "
               "gaps along them)",
               "rms/nmad (all) = DSM − truth DSM on every cell of classes 1 and 7, object edges "
               "included (fattening at walls, tree crowns over fields); 'measured' = cells "
               "within half a groundel of a matched point (fbm_lsm interpolates the rest)",
               f"aerial block: H = {result['synthetic_aerial']['flying_height_m']:.0f} m, "
               f"base = {result['synthetic_aerial']['base_px']:.0f} px, so 0.1 ‰ H = "
               f"{1e-4 * result['synthetic_aerial']['base_px']:.2f} px of parallax",
               "NGI: rms/nmad over each DSM's own cells (dense leaves what it cannot match "
               "empty, fbm_lsm fills the measuring area); rms/nmad_common over the cells all "
               "DSMs have, the fair comparison",
               "dense RMS ratio ours / OpenCV StereoSGBM (same pipeline): "
               f"{result['synthetic_aerial']['dense_rms_ratio_ours_over_sgbm']}"])
    return result
