"""Automatic georeferencing of an image against polygons: the whole chain (seed-001 Table 5.2).

segment the image (several thresholds) → reference objects (vector class selection + dissolve,
or a segmented orthophoto) → moments, invariants, standard positions → hypotheses → consistent
interpretation → global affine → verification → per-pair trimmed ICP → control points → final
transform (affine / projective / poly2) → outputs. No approximate values: position, scale,
rotation and mirroring are all unknown.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence, Union

import numpy as np

from ..errors import GeometryError, InputError
from ..feedback import Feedback, StepFeedback
from .area import area_search, boundary_search, grid_control_points
from .correspondence import apply, consistent_interpretation, find_hypotheses, verify
from .fit import fit_transform, inverse_for_resampling
from .invariants import object_features
from .reference_layer import (
    is_raster,
    reference_objects_from_raster,
    reference_objects_from_vector,
)
from .refinement import (
    control_points,
    grow_ring,
    joint_icp,
    outline_offset,
    simplify_ring,
    trimmed_icp,
)
from .regions import DEFAULT_THRESHOLDS, image_objects, load_image

PathLike = Union[str, Path]

#: Fewest verified pairs for a result (fewer: the failure report, not a wrong answer).
MIN_PAIRS = 3
#: Search modes: object-based, area-based, or objects with the area-based fallback.
SEARCH_MODES = ("auto", "objects", "area")
#: Smallest ECC correlation of an area-based result (below: the boundary-orientation search,
#: then the failure report). Correct synthetic results reach 0.6–0.85; wrong ones stayed
#: below 0.17 with PyPI's OpenCV, but one reached 0.28 with Debian's OpenCV 4.6 (a Voronoi
#: tiling whose dissolved outline is a bare square).
MIN_ECC = 0.4
#: Boundary-orientation search (docs/decisions.md): smallest score (weighted mean cos 2Δ
#: after the refinement) and smallest gap between the chosen placement and the best other
#: one after the coarse refinement. Everest, right placements: 0.62–0.77, gaps ≥ 0.10.
#: Wrong ones: Everest against random tilings of the RGI extent ≤ 0.46 (gaps 0.01–0.12);
#: synthetic tilings against unrelated tilings 0.58–0.72, but with gaps ≤ 0.06.
MIN_ORIENTATION = 0.55
MIN_GAP = 0.08


def parse_thresholds(text: Union[str, Sequence[float], None]) -> List[float]:
    """'5,6,7,8' → [5.0, 6.0, 7.0, 8.0]."""
    if text is None or text == "":
        return list(DEFAULT_THRESHOLDS)
    if isinstance(text, str):
        try:
            vals = [float(t) for t in text.replace(";", ",").split(",") if t.strip()]
        except ValueError as exc:
            raise InputError(f"Thresholds '{text}': give numbers separated by commas, "
                             "e.g. 5,6,7,8.") from exc
    else:
        vals = [float(t) for t in text]
    if not vals or any(v <= 0 for v in vals):
        raise InputError("Thresholds must be positive grey-value differences, e.g. 5,6,7,8.")
    return vals


def georeference(image: PathLike, reference: PathLike, class_field: Optional[str] = None,
                 class_value: Optional[str] = None, transform: str = "affine",
                 thresholds: Union[str, Sequence[float], None] = None,
                 pyramid_level: Union[int, str] = "auto", rd: float = 0.03,
                 max_depth: int = 6, min_overlap: float = 0.7, verify_overlap: float = 0.5,
                 alpha_min: float = 30.0, sigma_np_px: float = 2.0, max_gcps: int = 500,
                 smooth: float = 1.0, merge: bool = True, band: Optional[int] = None,
                 gcp_mode: str = "outline", search: str = "auto",
                 feedback: Optional[Feedback] = None) -> Dict[str, Any]:
    """Georeference ``image`` against ``reference``; returns the result (no files written).

    Parameters
    ----------
    search : {"auto", "objects", "area"}
        ``objects``: the object-based chain only; ``area``: the area-based global search only
        (:mod:`.area`, polygon layers only); ``auto``: objects, and the area-based search
        when the objects give no result.

    Raises
    ------
    InputError
        Unreadable inputs, a missing class field, no polygons after the selection.
    GeometryError
        Too few objects match (the message says how many were found at each stage and why).
    """
    fb = feedback or Feedback()
    t0 = time.perf_counter()
    thr = parse_thresholds(thresholds)
    if transform not in ("affine", "projective", "poly2"):
        raise InputError(f"Unknown transform '{transform}'; use affine, projective or poly2.")
    if search not in SEARCH_MODES:
        raise InputError(f"Unknown search '{search}'; use {', '.join(SEARCH_MODES)}.")
    grey, img_info = load_image(image, band)
    ref_kind = "raster" if is_raster(reference) else "vector"
    if ref_kind == "raster" and search == "area":
        raise InputError("The area-based search needs a polygon layer as reference, not a "
                         "raster; use search = objects or auto.")
    if ref_kind == "vector":  # first: a bad layer or class fails before any work
        ref_objs, crs, ref_info = reference_objects_from_vector(
            reference, class_field, class_value, feedback=fb)
    fb.progress(5)
    params = {"thresholds": thr, "rd": rd, "max_depth": max_depth, "min_overlap": min_overlap,
              "verify_overlap": verify_overlap, "alpha_min": alpha_min,
              "sigma_np_px": sigma_np_px, "max_gcps": max_gcps, "transform": transform,
              "smooth": smooth, "merge": merge, "gcp_mode": gcp_mode,
              "class_field": class_field, "class_value": class_value, "search": search}
    if search == "area":
        return _area_stage(grey, img_info, ref_objs, crs, ref_info, params, fb, t0, None)
    try:
        return _object_stage(grey, img_info, reference, ref_kind,
                             (ref_objs, crs, ref_info) if ref_kind == "vector" else None,
                             pyramid_level, params, fb, t0)
    except GeometryError as exc:
        if search == "objects" or ref_kind == "raster":
            raise
        # the reason and counts only: the advice at the end is repeated by the area stage
        why = str(exc).replace("Georeferencing failed: ", "").split(". Check that")[0]
        fb.info(f"Object stage: {why} — trying the area-based search.")
        return _area_stage(grey, img_info, ref_objs, crs, ref_info, params, fb, t0, why)


def _object_stage(grey: np.ndarray, img_info: Dict[str, Any], reference: PathLike,
                  ref_kind: str, ref: Optional[tuple], pyramid_level: Union[int, str],
                  params: Dict[str, Any], fb: Feedback, t0: float) -> Dict[str, Any]:
    """The object-based chain (seed-001): segmentation to the final fit."""
    thr, rd, max_depth = params["thresholds"], params["rd"], params["max_depth"]
    min_overlap, verify_overlap = params["min_overlap"], params["verify_overlap"]
    alpha_min, sigma_np_px = params["alpha_min"], params["sigma_np_px"]
    max_gcps, transform, smooth = params["max_gcps"], params["transform"], params["smooth"]
    merge, gcp_mode = params["merge"], params["gcp_mode"]
    if ref is not None:
        ref_objs, crs, ref_info = ref
    img_objs, seg = image_objects(grey, thr, pyramid_level=pyramid_level, smooth=smooth,
                                  merge=merge, feedback=StepFeedback(fb, 5, 20))
    if ref_kind == "raster":  # segmented like the image
        ref_objs, crs, ref_info = reference_objects_from_raster(
            reference, thr, pyramid_level=pyramid_level, smooth=smooth, merge=merge,
            feedback=StepFeedback(fb, 20, 35))
    fb.check()
    level = int(seg["level"])
    fi = object_features(img_objs)
    fr = object_features(ref_objs)
    fb.progress(40)
    hyps = find_hypotheses(fi, fr, rd)
    fb.info(f"{len(img_objs)} image objects, {len(ref_objs)} reference objects, "
            f"{len(hyps)} hypotheses (invariants within {100 * rd:g} %).")
    interp = consistent_interpretation(hyps, fi, fr, max_depth=max_depth,
                                       min_overlap=min_overlap)
    fb.progress(55)
    counts = {"image_objects": len(img_objs), "reference_objects": len(ref_objs),
              "hypotheses": len(hyps), "consistent_pairs": len(interp.pairs),
              "search_nodes": interp.nodes, "depth_reached": interp.depth_reached}
    if interp.transform is None or len(interp.pairs) < 2:
        _fail(counts, "no two hypotheses are geometrically consistent")
    ver = verify(hyps, fi, fr, interp.transform, min_overlap=verify_overlap)
    counts.update(verified_stage1=ver.stage1, verified_pairs=len(ver.pairs),
                  reestimated=ver.reestimated)
    if len(ver.pairs) < MIN_PAIRS:
        _fail(counts, f"only {len(ver.pairs)} pair(s) verified (at least {MIN_PAIRS} needed)")
    G = ver.transform
    px = float(np.sqrt(abs(np.linalg.det(G[:2, :2]))))  # map units per level-0 pixel
    refined = []
    icp_stats = []
    for k, h in enumerate(ver.pairs):
        fb.check()
        ring_img = simplify_ring(fi[h.i].obj.ring, 0.5 * 2**level)
        res = trimmed_icp(apply(G, ring_img), fr[h.j].obj.ring, spacing=px * 2**level,
                          model="affine")
        refined.append((fi[h.i].obj.ring, fr[h.j].obj.ring, res.transform @ G))
        icp_stats.append({"pair": k, "image_object": fi[h.i].obj.id,
                          "reference_object": fr[h.j].obj.id, "run": fi[h.i].obj.run,
                          "threshold": fi[h.i].obj.threshold, "overlap": ver.overlaps[k],
                          # µm/µpx: ICP that stops at its iteration limit differs below
                          # that between BLAS builds (these numbers only inform)
                          "icp_rms_m": round(res.rms, 6), "icp_rms_px": round(res.rms / px, 6),
                          "iterations": res.iterations, "converged": res.converged,
                          "kept": res.kept})
    fb.progress(70)
    # one transform for all verified outlines (see refinement.joint_icp); the segmentation
    # shrinks or grows objects a little (boundary pixels form their own regions): that
    # offset is estimated and the image outlines moved by it, alternating with the ICP
    rings = [(simplify_ring(fi[h.i].obj.ring, 0.5 * 2**level), fr[h.j].obj.ring)
             for h in ver.pairs]
    model = "projective" if transform == "projective" else "affine"
    offset_px = 0.0
    T = G
    for _ in range(3):
        fb.check()
        moved = [(grow_ring(a, offset_px), b) for a, b in rings]
        joint = joint_icp(moved, T, spacing=float(2**level), model=model)
        T = joint.transform
        step = outline_offset(moved, T, float(2**level)) / px
        offset_px += step
        if abs(step) < 0.02:
            break
    counts["joint_icp_rms_px"] = joint.rms / px
    counts["outline_offset_px"] = offset_px
    refined = [(grow_ring(a, offset_px), b, T) for a, b, _ in refined]
    fb.progress(75)
    gcps = control_points(refined, alpha_min=alpha_min, sigma_np=sigma_np_px * px,
                          max_count=max_gcps, spacing=px, mode=gcp_mode)
    if len(gcps) < {"affine": 3, "projective": 4, "poly2": 6}[transform] + 2:
        _fail(counts, f"only {len(gcps)} control points within σ_NP = {sigma_np_px:g} px")
    img_xy = np.array([g.image for g in gcps])
    map_xy = np.array([g.map for g in gcps])
    fit = fit_transform(img_xy, map_xy, transform)
    inverse_fit = inverse_for_resampling(fit, img_xy[fit.used], map_xy[fit.used])
    fb.progress(85)
    counts["gcps"] = int(fit.used.sum())
    counts["gcps_sharp"] = int(sum(g.sharp for g, u in zip(gcps, fit.used) if u))
    warnings = []
    hull_share = _hull_share(img_xy[fit.used], grey.shape)
    if hull_share < 0.25:
        warnings.append(f"The control points cover only {100 * hull_share:.0f} % of the image "
                        "(convex hull): expect larger errors towards the image corners.")
    if not interp.depth_reached:
        warnings.append(f"The search did not reach depth {max_depth} "
                        f"({len(interp.pairs)} consistent pairs).")
    for w in warnings:
        fb.warning(w)
    fb.info(f"{len(ver.pairs)} verified pairs, {counts['gcps']} control points, "
            f"RMSE {fit.rmse_px:.2f} px ({fit.rmse_map:.2f} m).")
    return {"fit": fit, "inverse_fit": inverse_fit, "gcps": gcps, "global": G,
            "joint": joint.transform, "search": interp.transform,
            "pairs": ver.pairs, "img_features": fi, "ref_features": fr, "crs": crs,
            "counts": counts, "icp": icp_stats, "segmentation": seg, "reference": ref_info,
            "reference_kind": ref_kind, "image_info": img_info, "grey": grey,
            "warnings": warnings, "seconds": time.perf_counter() - t0, "stage": "objects",
            "parameters": {**params, "pyramid_level": level}}


def _area_stage(grey: np.ndarray, img_info: Dict[str, Any], ref_objs: Sequence[Any],
                crs: Any, ref_info: Dict[str, Any], params: Dict[str, Any], fb: Feedback,
                t0: float, object_failure: Optional[str]) -> Dict[str, Any]:
    """The area-based global search (:mod:`.area`) and the same result layout as the object
    chain; its control points are a grid of image points through the refined affine."""
    fb.info("Area-based search: Fourier–Mellin rotation/scale, NCC translation, ECC.")
    fb.progress(40)
    res = area_search(grey, [o.ring for o in ref_objs])
    fb.progress(60)
    counts: Dict[str, Any] = {"reference_objects": len(ref_objs),
                              "area_candidates": len(res.candidates),
                              "area_ncc": round(res.ncc, 4), "area_ecc": round(res.ecc, 4),
                              "verified_pairs": 0}
    area_info: Dict[str, Any] = {"method": "ecc", "ncc": res.ncc, "ecc": res.ecc,
                                 "mirrored": res.mirrored, "candidates": res.candidates}
    T = res.transform
    if res.ecc < MIN_ECC:
        # the individual polygons' outlines against the image's edge directions
        fb.info(f"ECC correlation {res.ecc:.2f} < {MIN_ECC:g}: boundary-orientation search "
                "(individual outlines against edge directions).")
        outlines = [b for o in ref_objs for b in o.attributes.get("outlines", [o.ring])]
        bres = boundary_search(grey, outlines)
        counts.update(boundary_outlines=len(outlines),
                      boundary_score=round(bres.score, 4),
                      boundary_screen=round(bres.screen, 4),
                      boundary_runner_up=round(bres.runner_up, 4))
        if bres.score < MIN_ORIENTATION or bres.gap < MIN_GAP:
            why = (f"the area-based search found no alignment (ECC correlation {res.ecc:.2f} "
                   f"< {MIN_ECC:g}; boundary-orientation score {bres.score:.2f}, needs "
                   f"≥ {MIN_ORIENTATION:g}, ahead of the next placement by {bres.gap:.2f}, "
                   f"needs ≥ {MIN_GAP:g})")
            if object_failure:
                why += f"; before it, the object stage: {object_failure}"
            _fail(counts, why)
        T = bres.transform
        area_info = {"method": "boundary orientation", "score": bres.score,
                     "screen": bres.screen, "search_score": bres.search_score,
                     "runner_up": bres.runner_up,
                     "mirrored": bres.mirrored, "candidates": bres.candidates,
                     "ecc_before": res.ecc}
    fb.progress(75)
    gcps = grid_control_points(T, np.isfinite(grey))
    transform = params["transform"]
    img_xy = np.array([g.image for g in gcps])
    map_xy = np.array([g.map for g in gcps])
    fit = fit_transform(img_xy, map_xy, transform)
    inverse_fit = inverse_for_resampling(fit, img_xy, map_xy)
    counts["gcps"] = int(fit.used.sum())
    counts["gcps_sharp"] = 0
    how = (f"ECC affine, correlation {res.ecc:.2f}" if area_info["method"] == "ecc" else
           f"boundary-orientation affine, score {area_info['score']:.2f}")
    warnings = [f"Control points from the area-based search (grid through the {how}): "
                "their residuals do not measure the accuracy."]
    if object_failure:
        warnings.append(f"The object stage found no result: {object_failure}")
    for w in warnings:
        fb.warning(w)
    fb.progress(85)
    return {"fit": fit, "inverse_fit": inverse_fit, "gcps": gcps, "global": T,
            "joint": T, "search": T, "pairs": [],
            "img_features": [], "ref_features": [], "crs": crs, "counts": counts, "icp": [],
            "segmentation": {}, "reference": ref_info, "reference_kind": "vector",
            "image_info": img_info, "grey": grey, "warnings": warnings,
            "seconds": time.perf_counter() - t0, "stage": "area",
            "area": area_info,
            "reference_rings": [o.ring for o in ref_objs],
            "parameters": {**params, "pyramid_level": None}}


def _fail(counts: Dict[str, Any], why: str) -> None:
    """Raise the failure message; the exception's ``counts`` keep the figures as data."""
    detail = ", ".join(f"{k.replace('_', ' ')} {v}" for k, v in counts.items())
    raise GeometryError(
        f"Georeferencing failed: {why} ({detail}). Check that image and reference show the "
        "same objects completely (class field/value), try other thresholds or a larger "
        "relative difference.", counts)


def _hull_share(xy: np.ndarray, shape: Sequence[int]) -> float:
    from scipy.spatial import ConvexHull

    if len(xy) < 3:
        return 0.0
    try:
        return float(ConvexHull(xy).volume / (shape[0] * shape[1]))
    except Exception:
        return 0.0
