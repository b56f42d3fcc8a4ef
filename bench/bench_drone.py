"""Synthetic drone block (``synthetic_block --size drone``): both matching methods on its models.

Per model (near-vertical, convergent 25–50°) and method (dense, fbm_lsm): the report's
measured / interpolated / failed-windows shares; the share of the *overlap cells* that hold a
measured height (cells whose true surface point lies inside both frames:
``measured_overlap_pct``) and of the *visible* overlap cells (also seen from both projection
centres over the truth DSM: ``measured_visible_pct``; ``visible_overlap_pct`` is their share
of the overlap); DSM − truth NMAD and RMSE on open terrain (land cover 1 open, 2 road,
6 embankment, 7 field) and on objects (3 buildings, 4 trees) in m and ‰ of the object
distance (mean distance of the two projection centres to the overlap centre), the goal
NMAD ≤ 1.5 · GSD · H/B, and the time. The peer is OpenCV's StereoSGBM on the same epipolar
pair (same disparity range): valid share of the overlap pixels and the ratio to PhotoDEM's SGM.

Goals (issue 22): dense ≥ 85 % of the visible overlap cells measured, fbm_lsm ≤ 20 % failed
windows at the finest level, NMAD ≤ 1.5 GSD·H/B.
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path
from typing import Any, Dict, Optional, Tuple

import numpy as np

#: models measured: near-vertical pairs and the most convergent pair of each strip
MODELS = ("0101_0102", "0202_0203", "0201_0203", "0101_0103")
METHODS = ("dense", "fbm_lsm")
OPEN = (1, 2, 6, 7)
OBJECTS = (3, 4)


def _truth_on(grid_path: str, truth: str, nearest: bool = False) -> Tuple[np.ndarray, Any]:
    """A truth raster resampled onto the grid of ``grid_path``, and that grid's transform."""
    import rasterio

    from .truth_grid import on_grid

    with rasterio.open(grid_path) as ds:
        shape, tr, crs = ds.shape, ds.transform, ds.crs
    return on_grid(truth, shape, tr, crs, nearest=nearest), tr


def overlap_cells(project: Any, model: Any, dsm_path: str, truth_dsm: str) -> np.ndarray:
    """Cells of the DSM grid whose true surface point lies inside both frames (no occlusion
    test: an occluded cell counts as not measured)."""
    from rasterio.transform import xy

    from photodem.algorithms.quality.stereo_overlap import inside_frames

    z, tr = _truth_on(dsm_path, truth_dsm)
    rows, cols = np.mgrid[0:z.shape[0], 0:z.shape[1]]
    xs, ys = xy(tr, rows.ravel(), cols.ravel())
    frames = [(project.camera_of(rec), rec.eo)
              for rec in (project.image(model.left), project.image(model.right))]
    return inside_frames(frames, np.column_stack([xs, ys, z.ravel()])).reshape(z.shape)


def visible_cells(project: Any, model: Any, dsm_path: str, truth_dsm: str,
                  inside: np.ndarray) -> np.ndarray:
    """Overlap cells whose true surface point both projection centres see (the truth DSM,
    :func:`~photodem.algorithms.ortho.visibility.occluded`): what a matcher can measure."""
    import rasterio
    from rasterio.transform import xy

    from photodem.algorithms.ortho.visibility import occluded

    z, tr = _truth_on(dsm_path, truth_dsm)
    rows, cols = np.nonzero(inside)
    xs, ys = (np.asarray(v) for v in xy(tr, rows, cols))
    zs = z[rows, cols]
    with rasterio.open(truth_dsm) as ds:
        full, full_tr = ds.read(1).astype(np.float64), ds.transform
    seen = np.ones(rows.size, bool)
    for name in (model.left, model.right):
        seen &= ~occluded(xs, ys, zs, project.image(name).eo.position, full, full_tr)
    out = np.zeros_like(inside)
    out[rows[seen], cols[seen]] = True
    return out


def _stats(err: np.ndarray) -> Dict[str, float]:
    v = err[np.isfinite(err)]
    if v.size == 0:
        return {"nmad_m": float("nan"), "rmse_m": float("nan"), "n": 0}
    med = float(np.median(v))
    return {"nmad_m": float(1.4826 * np.median(np.abs(v - med))),
            "rmse_m": float(np.sqrt(np.mean(v ** 2))), "n": int(v.size)}


def evaluate(project: Any, model_name: str, result: Dict[str, Any], block: Dict[str, Any]
             ) -> Dict[str, Any]:
    """Coverage and accuracy figures of one ``match_model`` result (module notes)."""
    import rasterio

    m = project.model(model_name)
    with rasterio.open(result["dsm"]) as ds:
        dsm = ds.read(1)
    with rasterio.open(result["count"]) as ds:
        measured = ds.read(1) > 0
    inside = overlap_cells(project, m, result["dsm"], block["truth_dsm"])
    seen = visible_cells(project, m, result["dsm"], block["truth_dsm"], inside)
    truth, _ = _truth_on(result["dsm"], block["truth_dsm"])
    lc, _ = _truth_on(result["dsm"], block["truth_landcover"], nearest=True)
    err = np.where(measured & inside, dsm - truth, np.nan)
    recs = [project.image(m.left), project.image(m.right)]
    centre = np.array([*np.mean(np.argwhere(inside), axis=0)])  # row, col
    xy = rasterio.transform.xy(rasterio.open(result["dsm"]).transform, *centre)
    ground = np.array([xy[0], xy[1], float(np.nanmedian(truth[inside]))])
    distance = float(np.mean([np.linalg.norm(r.eo.position - ground) for r in recs]))
    metrics = result["metrics"]
    out = {"model": model_name, "b_h": round(m.b_h, 3),
           "convergence_deg": round(m.convergence, 1),
           "measured_overlap_pct": 100.0 * float(measured[inside].mean()),
           "visible_overlap_pct": 100.0 * float(seen.sum()) / max(int(inside.sum()), 1),
           "measured_visible_pct": 100.0 * float(measured[seen].mean()),
           "measured_pct": metrics.get("measured_pct"),
           "interpolated_pct": metrics.get("interpolated_pct"),
           "failed_windows_finest_pct": metrics.get("failed_windows_finest_pct"),
           "object_distance_m": distance,
           "goal_nmad_m": 1.5 * m.gsd / m.b_h}
    for label, codes in (("open", OPEN), ("objects", OBJECTS)):
        cls = np.isin(lc, codes)
        out[f"{label}_measured_pct"] = 100.0 * float(measured[inside & cls].mean())
        out[f"{label}_measured_visible_pct"] = 100.0 * float(measured[seen & cls].mean())
        s = _stats(np.where(cls, err, np.nan))
        out[f"{label}_nmad_m"] = s["nmad_m"]
        out[f"{label}_rmse_m"] = s["rmse_m"]
        out[f"{label}_nmad_permille"] = 1000.0 * s["nmad_m"] / distance
        out[f"{label}_rmse_permille"] = 1000.0 * s["rmse_m"] / distance
    return out


def sgbm_peer(project: Any, model_name: str) -> Optional[Dict[str, Any]]:
    """Valid share of OpenCV StereoSGBM and PhotoDEM SGM on the model's epipolar pair over the
    overlap pixels (same disparity range, same grey images); None without cv2."""
    try:
        import cv2  # optional: the peer
    except ImportError:
        return None
    from photodem.algorithms.matching.dense import sgm_disparity
    from photodem.algorithms.matching.model_setup import prepare_model

    st = prepare_model(project, model_name)
    pair = st.pair
    grey = []
    for side, rec in zip(("left", "right"), st.records):
        img, valid = pair.resample(project.read_image(rec).astype(np.float32).mean(axis=0),
                                   side)
        grey.append((img, valid))
    (lg, lv), (rg, rv) = grey
    lo, hi = st.min_d, st.max_d
    t0 = time.perf_counter()
    ours = sgm_disparity(np.where(lv, lg, np.nan), np.where(rv, rg, np.nan), lo, hi)
    t_ours = time.perf_counter() - t0
    num = int(np.ceil((hi - lo + 1) / 16.0)) * 16
    h = max(lg.shape[0], rg.shape[0])
    width = max(lg.shape[1], rg.shape[1])
    lw = np.zeros((h, width), np.uint8)
    rw = np.zeros((h, width), np.uint8)
    lw[:lg.shape[0], :lg.shape[1]] = np.clip(lg, 0, 255)
    rw[:rg.shape[0], :rg.shape[1]] = np.clip(rg, 0, 255)
    sgbm = cv2.StereoSGBM_create(minDisparity=int(lo), numDisparities=num, blockSize=5,
                                 P1=8 * 25, P2=32 * 25, uniquenessRatio=10, disp12MaxDiff=1,
                                 speckleWindowSize=100, speckleRange=2,
                                 mode=cv2.STEREO_SGBM_MODE_SGBM)
    t0 = time.perf_counter()
    disp = sgbm.compute(lw, rw).astype(np.float32) / 16.0
    t_cv = time.perf_counter() - t0
    cv_valid = disp[:lg.shape[0], :lg.shape[1]] >= lo
    # overlap pixels: left pixels whose partner at the mid disparity has right-image data
    both = lv.copy()
    shift = round(0.5 * (lo + hi))
    cc = np.arange(lg.shape[1]) - shift
    ok = (cc >= 0) & (cc < rg.shape[1])
    both[:, ~ok] = False
    both[:, ok] &= rv[:lg.shape[0], cc[ok]]
    ours_pct = 100.0 * float(np.isfinite(ours)[both].mean())
    cv_pct = 100.0 * float(cv_valid[both].mean())
    return {"model": model_name, "method": "sgm vs StereoSGBM",
            "photodem_valid_pct": ours_pct, "opencv_valid_pct": cv_pct,
            "ratio": ours_pct / cv_pct if cv_pct > 0 else float("nan"),
            "photodem_s": t_ours, "opencv_s": t_cv}


def run(models: Tuple[str, ...] = MODELS, methods: Tuple[str, ...] = METHODS,
        folder: Optional[Path] = None) -> dict:
    from photodem.algorithms.processing import registry
    from photodem.algorithms.project.model import Project

    with tempfile.TemporaryDirectory() as tmp:
        base = Path(folder or tmp)
        t0 = time.perf_counter()
        block = registry.run("synthetic_block", {"size": "drone", "seed": 1,
                                                 "output": str(base / "drone")})
        t_block = time.perf_counter() - t0
        project = Project.load(block["project"])
        rows = []
        for name in models:
            for method in methods:
                t0 = time.perf_counter()
                res = registry.run("match_model", {
                    "project": block["project"], "model": name, "method": method,
                    "output": str(base / "dsm" / method / name)})
                row = evaluate(project, name, res, block)
                row["method"] = method
                row["seconds"] = time.perf_counter() - t0
                rows.append(row)
            peer = sgbm_peer(project, name)
            if peer is not None:
                rows.append(peer)
    notes = [f"Block: {block['images']} images, GSD {block['gsd_m']} m, H "
             f"{block['flying_height_m']} m, made in {t_block:.1f} s.",
             "Goals: dense measured_visible_pct ≥ 85 (measured_overlap_pct: all overlap cells, "
             "occluded ones included); fbm_lsm failed_windows_finest_pct ≤ 20; "
             "open_nmad_m ≤ goal_nmad_m (1.5 GSD·H/B)."]
    return {"title": "Synthetic drone block: convergent models, both methods", "rows": rows,
            "notes": notes}
