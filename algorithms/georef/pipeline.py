"""Automatic georeferencing of an image against polygons: the whole chain (seed-001 Table 5.2).

segment the image (several thresholds) → reference objects (vector class selection + dissolve,
or a segmented orthophoto) → moments, invariants, standard positions → hypotheses → consistent
interpretation → global affine → verification → per-pair trimmed ICP → control points → final
transform (affine / projective / poly2) → outputs. No approximate values: position, scale,
rotation and mirroring are all unknown.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np

from ..errors import GeometryError, InputError, PhotodemError
from ..feedback import Feedback, StepFeedback
from ..output_policy import PRODUCT_MARKER
from .area import area_search, boundary_search, grid_control_points
from .buildings import is_buildings, match_buildings
from .correspondence import apply, consistent_interpretation, find_hypotheses, verify
from .evidence import assess
from .evidence import hull_share as _hull_share
from .fit import fit_transform, inverse_for_resampling
from .invariants import object_features
from .keypoints import DETECTORS, keypoint_result
from .products import summary, write_outputs
from .reference_layer import (
    is_raster,
    reference_objects_from_raster,
    reference_objects_from_vector,
)
from .refinement import (
    Keep,
    border_pairs,
    control_points,
    frame_mask,
    grow_ring,
    joint_icp,
    outline_offset,
    simplify_ring,
    trimmed_icp,
)
from .regions import DEFAULT_THRESHOLDS, image_objects, load_image
from .relief import correct_relief, scale_about
from .result import GeorefResult

PathLike = Union[str, Path]

#: Fewest verified pairs for a result (fewer: the failure report, not a wrong answer).
MIN_PAIRS = 3
#: Outline points of objects cut by the image border closer to it than this (pixels of the
#: segmentation level) are left out: the region runs along the border there, and the
#: smoothing before the segmentation reaches about two pixels.
BORDER_MARGIN = 3.0
#: Search modes: object-based, area-based, keypoints (raster references), or ``auto``:
#: keypoints then objects for a raster, objects then the area-based search for polygons.
SEARCH_MODES = ("auto", "objects", "area", "keypoints")
#: Largest joint-ICP RMS (px) of the buildings mode's verified roofs (each roof off its
#: footprint by its own relief). Measured on 40 scenes of 900 px: right placements up to
#: 1.48 px (seven of them refused at the former 1.25 px, all 0.27–0.50 px off once let
#: through), the one wrong placement that reached this test 1.91 px (4.9 px off; the gate
#: refused it as well). An early calibration (9 scenes) had wrong ones from 1.37 px: the gate
#: behind this test is what refuses those.
MAX_BUILDINGS_ICP_RMS_PX = 1.6
#: Kinds of reference polygons (:attr:`GeorefOptions.objects`).
OBJECT_KINDS = ("auto", "areas", "buildings")
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
#: Time budget of the area-based search after a failed buildings mode (the
#: boundary-orientation search is not tried on footprints: :func:`_area_stage`), counted from
#: the start of the run: this many seconds per Mpx of the image, at least
#: :data:`FALLBACK_MIN_S` (a run that cannot succeed says so within 30 s on 1 Mpx, issue 23;
#: the step running at the deadline finishes first). On 20 synthetic suburban scenes the
#: fallback found no right result.
FALLBACK_S_PER_MPX = 25.0
FALLBACK_MIN_S = 10.0
#: Default time budget of the search (s): a hopeless run says so by then (issue 23). Not 30 s:
#: right Everest results (boundary-orientation stage, 0.5 Mpx) took 73–110 s on the shared
#: 2-core test machine (docs/decisions.md).
DEFAULT_TIME_LIMIT_S = 180.0


def parse_thresholds(text: Union[str, Sequence[float], None]) -> List[float]:
    """'5,6,7,8' → [5.0, 6.0, 7.0, 8.0]."""
    if text is None or text == "":
        return list(DEFAULT_THRESHOLDS)
    if isinstance(text, str):
        try:
            vals = [float(t) for t in text.replace(";", ",").split(",") if t.strip()]
        except ValueError as exc:
            raise InputError.of("Thresholds '{text}': give numbers separated by commas, "
                                "e.g. 5,6,7,8.", text=text) from exc
    else:
        vals = [float(t) for t in text]
    if not vals or any(v <= 0 for v in vals):
        raise InputError.of("Thresholds must be positive grey-value differences, e.g. "
                            "5,6,7,8.")
    return vals


@dataclass(frozen=True)
class GeorefOptions:
    """Options of :func:`georeference` (defaults: seed-001 Table 5.2 and the synthetic tests).

    Attributes
    ----------
    class_field, class_value : str, optional
        Attribute and value selecting the reference polygons (``None``: all polygons).
    transform : {"affine", "projective", "poly2"}
        The final image → map transform.
    thresholds : str or sequence of float, optional
        Region-growing thresholds in grey values of 8-bit data ("5,6,7,8"; ``None``: the
        defaults of :data:`.regions.DEFAULT_THRESHOLDS`).
    pyramid_level : int or "auto"
        Pyramid level segmented (factor 2 each); ``"auto"``: the first with at most 4 Mpx.
    rd : float
        Relative difference allowed for each invariant (0.03 = 3 %).
    max_depth : int
        Depth of the consistency search (pairs).
    min_overlap, verify_overlap : float
        Smallest overlap share (0–1) of a consistent pair in the search / the verification.
    alpha_min : float
        Smallest angle (°) between the outline directions at a sharp control point.
    sigma_np_px : float
        Control point tolerance σ_NP (level-0 px): points are accepted (best first) while
        the RMS of their outline distances stays below it.
    max_gcps : int
        Most control points.
    smooth : float
        Gaussian σ (px) of the smoothing before segmentation (0: none).
    merge : bool
        Merge similar adjacent regions after region growing.
    band : int, optional
        Image band used (1-based; ``None``: the mean of the bands).
    gcp_mode : str
        Where control points are taken (``"outline"``: along the outlines).
    search : {"auto", "objects", "area", "keypoints"}
        ``objects``: the object-based chain only; ``area``: the area-based global search
        only (:mod:`.area`, polygon layers only); ``keypoints``: the keypoint stage only
        (:mod:`.keypoints`, raster references only); ``auto``: for a raster reference the
        keypoint stage and the object chain when it gives no result, for polygons the
        objects and the area-based search when they give no result.
    detector : {"auto", "sift", "akaze", "orb"}
        Keypoint detector of the keypoint stage (``auto``: SIFT, else AKAZE, else ORB).
    objects : {"auto", "areas", "buildings"}
        Kind of reference polygons: ``buildings`` (many small footprints: the buildings mode
        of :mod:`.buildings` alone), ``areas`` (forests, fields,
        lakes, glaciers: the stages of ``search``), ``auto``: buildings when the layer has
        many small polygons (:func:`.buildings.is_buildings`), and when it fails the stages
        of ``search`` (the area-based ones; with ``search = objects`` the object stage).
    unverified : bool
        Return a result the independent evidence does not support (:mod:`.evidence`),
        marked ``verified=False`` with a warning, instead of failing.
    time_limit_s : float
        Time budget of the search (s; 0: none): the stages stop when it is spent and the
        run fails with the figures found so far.
    """

    class_field: Optional[str] = None
    class_value: Optional[str] = None
    transform: str = "affine"
    thresholds: Union[str, Sequence[float], None] = None
    pyramid_level: Union[int, str] = "auto"
    rd: float = 0.03
    max_depth: int = 6
    min_overlap: float = 0.7
    verify_overlap: float = 0.5
    alpha_min: float = 30.0
    sigma_np_px: float = 2.0
    max_gcps: int = 500
    smooth: float = 1.0
    merge: bool = True
    band: Optional[int] = None
    gcp_mode: str = "outline"
    search: str = "auto"
    detector: str = "auto"
    objects: str = "auto"
    unverified: bool = False
    time_limit_s: float = DEFAULT_TIME_LIMIT_S

    def check(self) -> List[float]:
        """Refuse unknown transform and search names; returns the parsed thresholds."""
        thr = parse_thresholds(self.thresholds)
        if self.transform not in ("affine", "projective", "poly2"):
            raise InputError.of("Unknown transform '{value}'; use affine, projective or poly2.",
                                value=self.transform)
        if self.search not in SEARCH_MODES:
            raise InputError.of("Unknown search '{value}'; use {options}.", value=self.search,
                                options=", ".join(SEARCH_MODES))
        if self.detector not in ("auto", *DETECTORS):
            raise InputError.of("Unknown keypoint detector '{value}'; use auto, {options}.",
                                value=self.detector, options=", ".join(DETECTORS))
        if self.objects not in OBJECT_KINDS:
            raise InputError.of("Unknown objects '{value}'; use {options}.", value=self.objects,
                                options=", ".join(OBJECT_KINDS))
        if not self.time_limit_s >= 0:
            raise InputError.of("The time limit must be ≥ 0 s (0: none), not {value}.",
                                value=self.time_limit_s)
        return thr

    def report(self, thresholds: List[float], pyramid_level: Optional[int]) -> Dict[str, Any]:
        """The ``parameters`` of the report (this key order: report.json stays the same)."""
        return {"thresholds": thresholds, "rd": self.rd, "max_depth": self.max_depth,
                "min_overlap": self.min_overlap, "verify_overlap": self.verify_overlap,
                "alpha_min": self.alpha_min, "sigma_np_px": self.sigma_np_px,
                "max_gcps": self.max_gcps, "transform": self.transform,
                "smooth": self.smooth, "merge": self.merge, "gcp_mode": self.gcp_mode,
                "class_field": self.class_field, "class_value": self.class_value,
                "search": self.search, "pyramid_level": pyramid_level,
                "detector": self.detector, "objects": self.objects,
                "unverified": self.unverified, "time_limit_s": self.time_limit_s}


def georeference(image: PathLike, reference: PathLike, options: Optional[GeorefOptions] = None,
                 feedback: Optional[Feedback] = None, **overrides: Any) -> GeorefResult:
    """Georeference ``image`` against ``reference``; returns the result (no files written).

    Parameters
    ----------
    image, reference : path
        The image; a polygon layer or a georeferenced raster.
    options : GeorefOptions, optional
        Default: ``GeorefOptions()``.
    feedback : Feedback, optional
        Progress, log and cancellation.
    **overrides
        Fields of :class:`GeorefOptions` that replace those of ``options``
        (``georeference(img, ref, search="area")``).

    Raises
    ------
    InputError
        Unreadable inputs, a missing class field, no polygons after the selection.
    GeometryError
        Too few objects match (the message says how many were found at each stage and why).
    """
    opts = replace(options or GeorefOptions(), **overrides)
    fb = feedback or Feedback()
    t0 = time.perf_counter()
    thr = opts.check()
    grey, img_info = load_image(image, opts.band)
    ref_kind = "raster" if is_raster(reference) else "vector"
    if ref_kind == "raster" and opts.search == "area":
        raise InputError.of("The area-based search needs a polygon layer as reference, not a "
                            "raster; use search = objects or auto.")
    if ref_kind == "vector" and opts.search == "keypoints":
        raise InputError.of("The keypoint search needs a georeferenced raster as reference, "
                            "not a polygon layer; use search = objects, area or auto.")
    ref = None
    if ref_kind == "vector":  # first: a bad layer or class fails before any work
        ref = reference_objects_from_vector(reference, opts.class_field, opts.class_value,
                                            feedback=fb)
    fb.progress(5)
    limit = opts.time_limit_s
    run = _Run(opts, thr, grey, img_info, fb, t0, t0 + limit if limit > 0 else float("inf"))
    buildings = ref is not None and (opts.objects == "buildings"
                                     or (opts.objects == "auto" and is_buildings(ref[0])))
    result = _search(run, reference, ref_kind, ref, buildings)
    return _gate(run, result, reference, ref, buildings)


def _search(run: _Run, reference: PathLike, ref_kind: str, ref: Optional[tuple],
            buildings: bool) -> GeorefResult:
    """The stages in their order; the first result wins. ``buildings``: the reference is
    building footprints (the buildings mode first)."""
    opts, fb = run.options, run.fb
    buildings_failure = None
    if buildings:
        try:
            return _buildings_stage(run, ref)
        except GeometryError as exc:
            buildings_failure = str(exc).replace("Georeferencing failed: ", "").split(
                ". Check that")[0]
            if opts.objects == "buildings":  # asked for: no other stage
                raise
            fb.info(f"Buildings mode: {buildings_failure} — trying the other stages.")
            if opts.search != "objects":  # the object stage: no better on many small ones
                return _area_stage(_fallback_run(run), ref,
                                   f"buildings mode: {buildings_failure}", tiling=False)
    if opts.search == "area":
        return _area_stage(run, ref, None)
    if ref_kind == "raster" and opts.search in ("auto", "keypoints"):
        return _keypoint_stage(run, reference)
    try:
        return _object_stage(run, reference, ref_kind, ref)
    except GeometryError as exc:
        if opts.search == "objects" or ref_kind == "raster" or run.expired():
            raise
        # the reason and counts only: the advice at the end is repeated by the area stage
        why = str(exc).replace("Georeferencing failed: ", "").split(". Check that")[0]
        fb.info(f"Object stage: {why} — trying the area-based search.")
        return _area_stage(run, ref, why)


def _gate(run: _Run, result: GeorefResult, reference: PathLike, ref: Optional[tuple],
          buildings: bool = False) -> GeorefResult:
    """The acceptance gate (:mod:`.evidence`): a result the independent evidence does not
    support fails with the figures — or, with ``unverified``, is returned marked.
    ``buildings``: the reference is building footprints (an area-stage result is then not
    verified: :func:`.evidence.assess`)."""
    fb = run.fb
    fb.check()
    if ref is not None:
        source: Any = _roof_level(result, [b for o in ref[0]
                                           for b in o.attributes.get("outlines", [o.ring])])
    else:
        source = reference
    ev = assess(result, source, buildings=buildings)
    result.evidence, result.verified = ev, ev.verified
    result.counts["verified"] = ev.verified
    fb.info(f"Evidence ({ev.seconds:.1f} s): {ev.text()}.")
    if not ev.verified:
        why = "; ".join(ev.reasons)
        if not run.options.unverified:
            raise _with_counts(GeometryError.of(
                "Georeferencing failed: the {stage} stage's result is not verified: {why} "
                "(RMSE {rmse:.2f} px of {points} control points; {evidence}). No result is "
                "better than a wrong one: check that image and reference show the same area, "
                "or write the result marked unverified.", stage=result.stage, why=why,
                rmse=result.fit.rmse_px, points=ev.points, evidence=ev.text()),
                {**result.counts, "evidence": ev.to_json()})
        warning = f"UNVERIFIED result (written on request): {why}."
        result.warnings.append(warning)
        fb.warning(warning)
    result.seconds = time.perf_counter() - run.t0
    return result


@dataclass
class _Run:
    """What the stages share: the options, the parsed thresholds, the image, the feedback,
    the start time and the time budget's end."""

    options: GeorefOptions
    thresholds: List[float]
    grey: np.ndarray
    image_info: Dict[str, Any]
    fb: Feedback
    t0: float
    deadline: float = float("inf")  #: perf_counter time when the budget is spent
    #: what the budget is, for the message when it is spent ("": the option's time limit)
    budget: str = ""

    def expired(self) -> bool:
        """Whether the time budget is spent."""
        return time.perf_counter() >= self.deadline

    def left(self) -> float:
        """Seconds left of the time budget (inf: none)."""
        return self.deadline - time.perf_counter()


def _fallback_run(run: _Run) -> _Run:
    """``run`` with the deadline of the stages after a failed buildings mode
    (:data:`FALLBACK_S_PER_MPX`), when it comes before the option's time limit."""
    seconds = max(FALLBACK_MIN_S, FALLBACK_S_PER_MPX * run.grey.size / 1e6)
    if run.t0 + seconds >= run.deadline:
        return run
    return replace(run, deadline=run.t0 + seconds,
                   budget=f"the time budget of {seconds:.0f} s after a failed buildings mode "
                          f"({FALLBACK_S_PER_MPX:g} s per Mpx of the image)")


def _keypoint_stage(run: _Run, reference: PathLike) -> GeorefResult:
    """A raster reference: the keypoint stage (:mod:`.keypoints`) first; when it finds too
    few inliers (``search = auto``) the object chain, and when that fails too, one message
    with the figures of both."""
    opts, fb = run.options, run.fb
    try:
        return keypoint_result(run.grey, run.image_info, reference, opts.transform,
                               opts.detector, opts.max_gcps, opts.report(run.thresholds, None),
                               run.t0, StepFeedback(fb, 5, 85))
    except GeometryError as exc:
        if opts.search == "keypoints":
            _fail(exc.counts, f"keypoint stage: {exc}")
        kp_why, kp_counts = str(exc), exc.counts
    fb.info(f"Keypoint stage: {kp_why} — trying the object stage.")
    try:
        return _object_stage(run, reference, "raster", None)
    except GeometryError as exc:
        raise _with_counts(GeometryError.of(
            "{error} Before it, the keypoint stage found no result: {why} ({detail}).",
            error=exc, why=kp_why, detail=_detail(kp_counts)),
            {**kp_counts, **exc.counts}) from exc


def _object_stage(run: _Run, reference: PathLike, ref_kind: str,
                  ref: Optional[tuple]) -> GeorefResult:
    """The object-based chain (seed-001): segmentation to the final fit."""
    opts, fb = run.options, run.fb
    thr, pyramid_level = run.thresholds, opts.pyramid_level
    img_objs, seg = image_objects(run.grey, thr, pyramid_level=pyramid_level,
                                  smooth=opts.smooth, merge=opts.merge,
                                  feedback=StepFeedback(fb, 5, 20))
    if ref_kind == "raster":  # segmented like the image
        ref = reference_objects_from_raster(
            reference, thr, pyramid_level=pyramid_level, smooth=opts.smooth, merge=opts.merge,
            feedback=StepFeedback(fb, 20, 35))
    ref_objs, crs, ref_info = ref  # type: ignore[misc]  # given for a vector reference
    fb.check()
    level = int(seg["level"])
    fi = object_features(img_objs)
    fr = object_features(ref_objs)
    fb.progress(40)
    hyps = find_hypotheses(fi, fr, opts.rd)
    fb.info(f"{len(img_objs)} image objects, {len(ref_objs)} reference objects, "
            f"{len(hyps)} hypotheses (invariants within {100 * opts.rd:g} %).")
    interp = consistent_interpretation(hyps, fi, fr, max_depth=opts.max_depth,
                                       min_overlap=opts.min_overlap, deadline=run.deadline)
    fb.progress(55)
    counts = {"image_objects": len(img_objs), "reference_objects": len(ref_objs),
              "hypotheses": len(hyps), "consistent_pairs": len(interp.pairs),
              "search_nodes": interp.nodes, "depth_reached": interp.depth_reached}
    _check_time(run, counts, "the consistency search")
    if interp.transform is None or len(interp.pairs) < 2:
        _fail(counts, "no two hypotheses are geometrically consistent")
    ver = verify(hyps, fi, fr, interp.transform, min_overlap=opts.verify_overlap)
    counts.update(verified_stage1=ver.stage1, verified_pairs=len(ver.pairs),
                  reestimated=ver.reestimated)
    if len(ver.pairs) < MIN_PAIRS:
        _fail(counts, f"only {len(ver.pairs)} pair(s) verified (at least {MIN_PAIRS} needed)")
    matched = _with_border_pairs(
        _Matched(fi, fr, ver.pairs, ver.overlaps, ver.transform, level), run.grey.shape,
        counts)
    icp_stats, T, (fit, inverse_fit, gcps, used_xy) = _icp_and_fit(matched, opts, counts, fb)
    warnings = _object_warnings(used_xy, run.grey.shape, interp, opts.max_depth)
    for w in warnings:
        fb.warning(w)
    fb.info(f"{len(ver.pairs)} verified pairs, {counts['gcps']} control points, "
            f"RMSE {fit.rmse_px:.2f} px ({fit.rmse_map:.2f} m).")
    return GeorefResult(
        fit=fit, inverse_fit=inverse_fit, gcps=gcps, crs=crs, global_transform=ver.transform,
        joint=T, search=interp.transform, pairs=matched.pairs, img_features=fi, ref_features=fr,
        counts=counts, icp=icp_stats, segmentation=seg, reference=ref_info,
        reference_kind=ref_kind, image_info=run.image_info, grey=run.grey, warnings=warnings,
        seconds=time.perf_counter() - run.t0, stage="objects",
        parameters=opts.report(thr, level))


def _buildings_stage(run: _Run, ref: tuple) -> GeorefResult:
    """The buildings mode (:mod:`.buildings`): consensus of many footprints, then the
    verified pairs through the object stage's ICP and control points."""
    ref_objs, crs, ref_info = ref
    opts, fb = run.options, run.fb
    fb.info(f"Buildings mode: {len(ref_objs)} footprints.")
    m = match_buildings(run.grey, ref_objs, feedback=StepFeedback(fb, 5, 55))
    counts = dict(m.counts)
    if m.transform is None:
        _fail(counts, m.reason)
    if len(m.pairs) < MIN_PAIRS:
        _fail(counts, f"only {len(m.pairs)} roof(s) verified (at least {MIN_PAIRS} needed)")
    matched = _Matched(m.img_features, m.ref_features, m.pairs, m.overlaps, m.transform, 0)
    icp_stats, T, fitted = _icp_and_fit(matched, opts, counts, fb,
                                        max_rms_px=MAX_BUILDINGS_ICP_RMS_PX)
    # every footprint, not only the verified ones: the transform is known to a few px by now,
    # and footprints without a visible wall base do not sway the estimate
    (fit, inverse_fit, gcps, used_xy), relief = _relief_fit(
        run, [o.ring for o in ref_objs], T, fitted, counts)
    warnings = _spread_warnings(used_xy, run.grey.shape)
    for w in warnings:
        fb.warning(w)
    fb.info(f"{len(m.pairs)} verified roofs, {counts['gcps']} control points, "
            f"RMSE {fit.rmse_px:.2f} px ({fit.rmse_map:.2f} m).")
    return GeorefResult(
        fit=fit, inverse_fit=inverse_fit, gcps=gcps, crs=crs, global_transform=m.transform,
        joint=T, search=m.transform, pairs=m.pairs, img_features=m.img_features,
        ref_features=m.ref_features, counts=counts, icp=icp_stats,
        segmentation={"level": 0, "buildings": True, **relief}, reference=ref_info,
        reference_kind="vector", image_info=run.image_info, grey=run.grey, warnings=warnings,
        seconds=time.perf_counter() - run.t0, stage="buildings",
        parameters=opts.report(run.thresholds, 0))


def _relief_fit(run: _Run, rings: List[np.ndarray], T: np.ndarray, fitted: tuple,
                counts: Dict[str, Any]) -> Tuple[tuple, Dict[str, Any]]:
    """The fit from the ground, not the roofs (:mod:`.relief`): when the walls facing the
    nadir show a relief displacement, the control points (on the roof outlines) are moved by
    it — the scale about the nadir that the roof fit absorbed, and the roof refit of a start
    that was off the roofs — and refitted. ``counts`` gets
    the relief at the image corner and the ground edges that agree. Returns the tuple of
    :func:`_outline_fit` and, when corrected, the scale and its centre (image px) for the
    agreement test of the gate (:func:`_roof_level`)."""
    fit, gcps = fitted[0], fitted[2]
    start = fit.matrix if fit.matrix is not None else T
    rc = correct_relief(run.grey, start, rings)
    counts.update(rc.counts())
    if not rc.applied:
        run.fb.info(f"Relief displacement: none corrected ({rc.reason}).")
        return fitted, {}
    run.fb.info(f"Relief displacement: {rc.relief_px_corner:.2f} px at the image corner "
                f"from {rc.edges} wall bases; control points moved to the ground.")
    back = np.linalg.inv(rc.correction)
    gcps = [replace(g, image=tuple(float(v) for v in apply(back, np.array([g.image]))[0]))
            for g in gcps]
    h, w = run.grey.shape
    return _fit_gcps(gcps, run.options.transform, counts), {
        "relief_scale": rc.scale,
        "relief_centre": [(w - 1) / 2.0, (h - 1) / 2.0]}


def _roof_level(result: GeorefResult, rings: List[Any]) -> List[Any]:
    """The footprints where the roofs are seen, for the gate's image–reference agreement:
    after a relief correction the result maps the ground, while the image's edges are mostly
    roof edges, displaced by the relief (the scale about the nadir) — unchanged without one."""
    scale = result.segmentation.get("relief_scale")
    if not scale:
        return rings
    C = scale_about(np.asarray(result.segmentation["relief_centre"], float), float(scale))
    fit = result.fit
    if fit.matrix is not None:
        F = fit.matrix @ C @ np.linalg.inv(fit.matrix)
        return [apply(F, np.asarray(r, float)[:, :2]) for r in rings]
    return [fit.forward(apply(C, result.inverse_fit.forward(np.asarray(r, float)[:, :2])))
            for r in rings]


@dataclass
class _Matched:
    """The verified object pairs of the object stage and their common transform."""

    fi: List[Any]  #: image object features
    fr: List[Any]  #: reference object features
    pairs: List[Any]  #: verified hypotheses (``h.i`` image, ``h.j`` reference object)
    overlaps: List[float]  #: overlap share of each pair after the verification
    G: np.ndarray  #: 3 × 3 image → map transform of the verification
    level: int  #: pyramid level of the segmentation
    #: the image points that are outline (None: all; objects cut by the image border: the
    #: points off the border)
    keep: Optional[Keep] = None

    @property
    def px(self) -> float:
        """Map units per level-0 pixel of ``G``."""
        return float(np.sqrt(abs(np.linalg.det(self.G[:2, :2]))))


def _with_border_pairs(m: _Matched, shape: Sequence[int], counts: Dict[str, Any]
                       ) -> _Matched:
    """``m`` with the objects cut by the image border paired under the verified transform
    (:func:`.refinement.border_pairs`; ``counts`` gets ``border_pairs``): a few whole objects
    bunched in one part of the image leave the corners to extrapolation, the cut ones reach
    out to the border."""
    keep = frame_mask(shape, BORDER_MARGIN * 2**m.level)
    extra = border_pairs(m.fi, m.fr, m.G, shape, m.pairs, keep)
    counts["border_pairs"] = len(extra)
    return replace(m, pairs=list(m.pairs) + [h for h, _ in extra],
                   overlaps=list(m.overlaps) + [ov for _, ov in extra], keep=keep)


def _icp_and_fit(m: _Matched, opts: GeorefOptions, counts: Dict[str, Any], fb: Feedback,
                 max_rms_px: Optional[float] = None) -> tuple:
    """The verified pairs to the final fit, shared by the object stage and the buildings
    mode: per-pair ICP, joint ICP (``counts`` gets its RMS and the outline offset), control
    points on the refined outlines. ``max_rms_px``: fail when the joint ICP RMS is larger
    (the outlines do not fit). Returns the per-pair ICP figures, the joint transform and
    :func:`_outline_fit`'s tuple."""
    refined, icp_stats = _pair_icp(m, fb)
    fb.progress(70)
    T, joint_rms, offset_px = _joint_icp(m, opts.transform, fb)
    rms_px = joint_rms / m.px
    counts.update(joint_icp_rms_px=rms_px, outline_offset_px=offset_px)
    if max_rms_px is not None and rms_px > max_rms_px:
        _fail(counts, f"the verified roofs do not fit their footprints (joint ICP RMS "
                      f"{rms_px:.2f} px, at most {max_rms_px:g} px)")
    refined = [(grow_ring(a, offset_px), b, T) for a, b, _ in refined]
    fb.progress(75)
    fitted = _outline_fit(refined, m.px, opts, counts, m.keep)
    fb.progress(85)
    return icp_stats, T, fitted


def _pair_icp(m: _Matched, fb: Feedback) -> Tuple[List[tuple], List[Dict[str, Any]]]:
    """Trimmed ICP of every verified pair on its own: the outlines with each pair's own
    transform, and the per-pair figures of the report."""
    px, level, fi, fr = m.px, m.level, m.fi, m.fr
    refined = []
    icp_stats = []
    for k, h in enumerate(m.pairs):
        fb.check()
        ring_img = simplify_ring(fi[h.i].obj.ring, 0.5 * 2**level)
        res = trimmed_icp(apply(m.G, ring_img), fr[h.j].obj.ring, spacing=px * 2**level,
                          model="affine", keep=_map_keep(m))
        refined.append((fi[h.i].obj.ring, fr[h.j].obj.ring, res.transform @ m.G))
        icp_stats.append({"pair": k, "image_object": fi[h.i].obj.id,
                          "reference_object": fr[h.j].obj.id, "run": fi[h.i].obj.run,
                          "threshold": fi[h.i].obj.threshold, "overlap": m.overlaps[k],
                          # µm/µpx: ICP that stops at its iteration limit differs below
                          # that between BLAS builds (these numbers only inform)
                          "icp_rms_m": round(res.rms, 6), "icp_rms_px": round(res.rms / px, 6),
                          "iterations": res.iterations, "converged": res.converged,
                          "kept": res.kept})
    return refined, icp_stats


def _map_keep(m: _Matched) -> Optional[Keep]:
    """``m.keep`` for points in map coordinates (mapped back by the verified transform)."""
    if m.keep is None:
        return None
    keep, inv = m.keep, np.linalg.inv(m.G)
    return lambda xy: keep(apply(inv, xy))


def _joint_icp(m: _Matched, transform: str, fb: Feedback) -> Tuple[np.ndarray, float, float]:
    """One transform for all verified outlines (see :func:`.refinement.joint_icp`).

    The segmentation shrinks or grows objects a little (boundary pixels form their own
    regions): that offset is estimated and the image outlines moved by it, alternating with
    the ICP. Returns the transform, the joint RMS (map units) and the offset (px).
    """
    level, px = m.level, m.px
    rings = [(simplify_ring(m.fi[h.i].obj.ring, 0.5 * 2**level), m.fr[h.j].obj.ring)
             for h in m.pairs]
    model = "projective" if transform == "projective" else "affine"
    offset_px = 0.0
    T = m.G
    for _ in range(3):
        fb.check()
        moved = [(grow_ring(a, offset_px), b) for a, b in rings]
        joint = joint_icp(moved, T, spacing=float(2**level), model=model, keep=m.keep)
        T = joint.transform
        step = outline_offset(moved, T, float(2**level), keep=m.keep) / px
        offset_px += step
        if abs(step) < 0.02:
            break
    return joint.transform, joint.rms, offset_px


def _outline_fit(refined: List[tuple], px: float, opts: GeorefOptions,
                 counts: Dict[str, Any], keep: Optional[Keep] = None) -> tuple:
    """Control points on the refined outlines (``keep``: the image points that are outline)
    and the final fit (``counts`` gets ``gcps`` and ``gcps_sharp``). Returns the fit, its
    inverse, the control points and the image coordinates of the ones used."""
    gcps = control_points(refined, alpha_min=opts.alpha_min, sigma_np=opts.sigma_np_px * px,
                          max_count=opts.max_gcps, spacing=px, mode=opts.gcp_mode, keep=keep)
    if len(gcps) < {"affine": 3, "projective": 4, "poly2": 6}[opts.transform] + 2:
        _fail(counts, f"only {len(gcps)} control points within σ_NP = "
                      f"{opts.sigma_np_px:g} px")
    return _fit_gcps(gcps, opts.transform, counts)


def _fit_gcps(gcps: List[Any], transform: str, counts: Dict[str, Any]) -> tuple:
    """The final fit of the control points (``counts`` gets ``gcps`` and ``gcps_sharp``).
    Returns the fit, its inverse, the control points and the image coordinates of the ones
    used."""
    img_xy = np.array([g.image for g in gcps])
    map_xy = np.array([g.map for g in gcps])
    fit = fit_transform(img_xy, map_xy, transform)
    inverse_fit = inverse_for_resampling(fit, img_xy[fit.used], map_xy[fit.used])
    counts["gcps"] = int(fit.used.sum())
    counts["gcps_sharp"] = int(sum(g.sharp for g, u in zip(gcps, fit.used) if u))
    return fit, inverse_fit, gcps, img_xy[fit.used]


def _spread_warnings(used_xy: np.ndarray, shape: Sequence[int]) -> List[str]:
    """The warning of control points bunched together (convex hull < 25 % of the image)."""
    hull_share = _hull_share(used_xy, shape)
    if hull_share >= 0.25:
        return []
    return [f"The control points cover only {100 * hull_share:.0f} % of the image (convex "
            "hull): expect larger errors towards the image corners."]


def _object_warnings(used_xy: np.ndarray, shape: Sequence[int], interp: Any,
                     max_depth: int) -> List[str]:
    """Warnings of the object stage: control points bunched together, a shallow search."""
    warnings = _spread_warnings(used_xy, shape)
    if not interp.depth_reached:
        warnings.append(f"The search did not reach depth {max_depth} "
                        f"({len(interp.pairs)} consistent pairs).")
    return warnings


def _area_stage(run: _Run, ref: tuple, object_failure: Optional[str],
                tiling: bool = True) -> GeorefResult:
    """The area-based global search (:mod:`.area`) and the same result layout as the object
    chain; its control points are a grid of image points through the refined affine.
    ``tiling``: whether the polygons may tile the terrain (the boundary-orientation search
    when ECC does not confirm the area search); ``False`` after a failed buildings mode:
    building footprints are no tiling — on a synthetic town the search at half its resolution
    placed an image 1943 px off with a score of 0.557 and the gate passed it."""
    ref_objs, crs, ref_info = ref
    grey, fb = run.grey, run.fb
    fb.info("Area-based search: Fourier–Mellin rotation/scale, NCC translation, ECC.")
    fb.progress(40)
    res = area_search(grey, [o.ring for o in ref_objs], deadline=run.deadline)
    fb.progress(60)
    counts: Dict[str, Any] = {"reference_objects": len(ref_objs),
                              "area_candidates": len(res.candidates),
                              "area_ncc": round(res.ncc, 4), "area_ecc": round(res.ecc, 4),
                              "verified_pairs": 0}
    _check_time(run, counts, "the area-based search", object_failure)
    area_info: Dict[str, Any] = {"method": "ecc", "ncc": res.ncc, "ecc": res.ecc,
                                 "mirrored": res.mirrored, "candidates": res.candidates}
    T = res.transform
    if res.ecc < MIN_ECC and not tiling:
        _fail(counts, f"the area-based search found no alignment (ECC correlation "
                      f"{res.ecc:.2f} < {MIN_ECC:g}; the boundary-orientation search needs "
                      f"polygons that tile the terrain, not building footprints); before it, "
                      f"the object stage: {object_failure}")
    if res.ecc < MIN_ECC:
        T, area_info = _boundary_stage(run, ref_objs, res.ecc, counts, object_failure)
    fb.progress(75)
    gcps = grid_control_points(T, np.isfinite(grey))
    img_xy = np.array([g.image for g in gcps])
    map_xy = np.array([g.map for g in gcps])
    fit = fit_transform(img_xy, map_xy, run.options.transform)
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
    return GeorefResult(
        fit=fit, inverse_fit=inverse_fit, gcps=gcps, crs=crs, global_transform=T, joint=T,
        search=T, counts=counts, reference=ref_info, reference_kind="vector",
        image_info=run.image_info, grey=grey, warnings=warnings,
        seconds=time.perf_counter() - run.t0, stage="area", area=area_info,
        reference_rings=[o.ring for o in ref_objs],
        parameters=run.options.report(run.thresholds, None))


def _boundary_stage(run: _Run, ref_objs: Sequence[Any], ecc: float,
                    counts: Dict[str, Any], object_failure: Optional[str]
                    ) -> Tuple[np.ndarray, Dict[str, Any]]:
    """The individual polygons' outlines against the image's edge directions, when the ECC
    correlation stayed below :data:`MIN_ECC`; ``counts`` gets its figures. Returns the
    transform and the description of the search for the report."""
    grey, fb = run.grey, run.fb
    fb.info(f"ECC correlation {ecc:.2f} < {MIN_ECC:g}: boundary-orientation search "
            "(individual outlines against edge directions).")
    outlines = [b for o in ref_objs for b in o.attributes.get("outlines", [o.ring])]
    bres = boundary_search(grey, outlines, deadline=run.deadline)
    counts.update(boundary_outlines=len(outlines),
                  boundary_score=round(bres.score, 4),
                  boundary_screen=round(bres.screen, 4),
                  boundary_runner_up=round(bres.runner_up, 4))
    _check_time(run, counts, "the boundary-orientation search", object_failure)
    if bres.score < MIN_ORIENTATION or bres.gap < MIN_GAP:
        why = (f"the area-based search found no alignment (ECC correlation {ecc:.2f} "
               f"< {MIN_ECC:g}; boundary-orientation score {bres.score:.2f}, needs "
               f"≥ {MIN_ORIENTATION:g}, ahead of the next placement by {bres.gap:.2f}, "
               f"needs ≥ {MIN_GAP:g})")
        if object_failure:
            why += f"; before it, the object stage: {object_failure}"
        _fail(counts, why)
    info = {"method": "boundary orientation", "score": bres.score,
            "screen": bres.screen, "search_score": bres.search_score,
            "runner_up": bres.runner_up,
            "mirrored": bres.mirrored, "candidates": bres.candidates,
            "ecc_before": ecc}
    return bres.transform, info


def _check_time(run: _Run, counts: Dict[str, Any], where: str,
                before: Optional[str] = None) -> None:
    """Fail with the figures found so far when the time budget is spent (``counts`` gets
    the seconds; ``before``: an earlier stage's failure, named in the message)."""
    if not run.expired():
        return
    counts["seconds"] = round(time.perf_counter() - run.t0, 1)
    budget = run.budget or f"the time limit of {run.options.time_limit_s:g} s"
    why = f"{budget} was reached in {where} without a result"
    if before:
        why += f"; before it, the object stage: {before}"
    _fail(counts, why)


def _fail(counts: Dict[str, Any], why: str) -> None:
    """Raise the failure message; the exception's ``counts`` keep the figures as data."""
    raise _with_counts(GeometryError.of(
        "Georeferencing failed: {why} ({detail}). Check that image and reference show the "
        "same objects completely (class field/value), try other thresholds or a larger "
        "relative difference.", why=why, detail=_detail(counts)), counts)


def _with_counts(error: PhotodemError, counts: Dict[str, Any]) -> PhotodemError:
    """``error`` with the figures behind its message as data (the report's counts)."""
    error.counts = dict(counts)
    return error


def _detail(counts: Dict[str, Any]) -> str:
    """The figures of a failure message: "image objects 12, hypotheses 0, …" — scalars as
    they are, lists and dicts by their length ("candidate runs 3"; the exception's
    ``counts`` keep them whole)."""
    def short(v: Any) -> Any:
        if isinstance(v, (list, tuple, dict)):
            return len(v)
        if isinstance(v, (float, np.floating)):
            return f"{float(v):.4g}"
        return v
    return ", ".join(f"{k.replace('_', ' ')} {short(v)}" for k, v in counts.items())


def run_georeference_polygons(image: PathLike, reference: PathLike, output: PathLike,
                              options: Optional[GeorefOptions] = None,
                              feedback: Optional[Feedback] = None) -> Dict[str, Any]:
    """``georeference_polygons``: georeference ``image`` and write the products into the
    folder ``output`` (see :func:`.products.write_outputs`); returns the outputs of the
    algorithm (:func:`.products.summary`).

    An output folder that holds files PhotoDEM did not write is refused before the work.
    """
    fb = feedback or Feedback()
    out = Path(output)
    if out.is_file() or (out.is_dir() and any(out.iterdir())
                         and not (out / PRODUCT_MARKER).is_file()):
        raise InputError.of("The output folder '{path}' holds files PhotoDEM did not write; "
                            "choose an empty or new folder.", path=out)
    result = georeference(image, reference, options, feedback=StepFeedback(fb, 0, 80))
    paths = write_outputs(out, image, result, feedback=StepFeedback(fb, 80, 100),
                          replace=True)
    return summary(result, paths)
