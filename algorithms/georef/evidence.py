"""Independent evidence for a georeferencing result: the acceptance gate (issue 23).

A small RMSE says only that the control points agree with the transform fitted to them; it says
nothing about the image corners when the points are bunched together, nor about a consistent
but wrong match. :func:`assess` judges any stage's :class:`~.result.GeorefResult` from three
independent sides:

1. **Spread** of the control points used: the share of the image inside their convex hull and
   the number of image quadrants that hold at least :data:`QUADRANT_POINTS` of them.
2. **Held-out check**: the points are split at their median column (left/right halves) and at
   their median row (top/bottom); each half gets its own transform (the result's kind; a
   poly2 result's halves a projective one: a quadratic fitted to half the points extrapolates
   2 px apart at the far corners even for a right result), and the two halves' transforms are
   compared at the image corners (px). Points bunched in one part of the image extrapolate
   differently from each half: the corners disagree. Each quadrant's points are also
   predicted by the transform of the other quadrants' points (held-out RMSE, px; the result's
   own kind, a poly2 one where the other quadrants hold ≥ :data:`POLY2_SUBSET_POINTS`).
3. **Image–reference agreement** after resampling with the final fit, compared with the same
   at wrong shifts of up to :data:`SHIFT_PX` px (a peak test), for the whole image and each
   quadrant (a local misfit in one corner shows as that quadrant's peak away from zero):

   - polygon reference: the image gradient across the mapped outlines (mean |g · n|);
     peak ratio = the best score / the mean score at shifts ≥ 3 px;
   - raster reference: normalised cross-correlation of gradient magnitudes (robust to
     seasonal and sensor contrast changes) of the image and the reference resampled into it;
     peak margin = the best correlation − the mean at shifts ≥ 3 px.

The thresholds are calibrated on right and wrong results (docs/decisions.md, issue 23): right
results of the bench cases reach corner misfits ≤ 0.65 px, quadrant offsets ≤ 0.44 px, corner
disagreements ≤ 0.69 px and hulls ≥ 34 %; results perturbed by 2–8 px at a corner show corner
misfits of 1.8–8.9 px, control points bunched in a corner hulls ≤ 18 %.
Stages whose control points come from a grid through a search transform (the area stage) give
no independent spread or held-out figures: there, the agreement alone decides.

The reasons of a refusal are (key, figures) pairs (:attr:`Evidence.reason_items`, keys of
:data:`REASON_TEXTS`) and English sentences made from them (:attr:`Evidence.reasons`): the
faces translate the keys with the same figures.
"""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np
import rasterio
from numpy.typing import NDArray
from scipy import ndimage
from scipy.spatial import ConvexHull

from .area import boundary_samples
from .correspondence import apply
from .fit import MIN_POINTS, centre_matrix, fit_matrix, fit_transform
from .result import GeorefResult

Array = NDArray[np.float64]
PathLike = Union[str, Path]

#: Fewest control points for a quadrant to count as covered.
QUADRANT_POINTS = 3
#: Smallest convex-hull share of the image (0–1) and fewest covered quadrants. 20 %: right
#: results of the calibration 34–78 %, but a right synthetic bench result (0.14 px at the
#: corners, 4 of 4 quadrants) had 24.96 %; points clustered in a corner 1–18 %, and a result
#: 1.7 px off 19 % (both still refused).
MIN_HULL = 0.20
MIN_QUADRANTS = 2
#: Largest disagreement (px) at the image corners between the transforms of two halves.
MAX_CORNER_PX = 1.5
#: Against building footprints the control points sit on a few roofs per half, each roof
#: displaced by its own height's relief: the halves may disagree by up to this many of their
#: standard deviations (the scatter of the roofs, :func:`_halves_sd`), but never more than
#: :data:`MAX_BUILDINGS_CORNER_PX`. Right results of 900 px scenes: 1.3–2.6 σ (bench seed 19:
#: 1.8 px at 2.2 σ, 0.31 px off); a placement 3.3 px off at 500 px: 6.9 σ.
HALVES_SIGMAS = 3.0
MAX_BUILDINGS_CORNER_PX = 2.5
#: Largest held-out RMSE (px): each quadrant's points predicted from the others.
MAX_HOLDOUT_PX = 2.0
#: Fewest control points for fitting a poly2 result's own kind to the points that predict a
#: held-out quadrant (5 × its 6 unknowns per coordinate; fewer: a projective transform).
POLY2_SUBSET_POINTS = 30
#: Shifts tried around the result in the agreement test (± px, a square grid).
SHIFT_PX = 5
#: "Far" shifts (px) the peak is compared with.
FAR_PX = 3.0
#: Smallest edge peak ratio (polygons) / correlation peak margin (raster) of the whole image.
MIN_EDGE_PEAK = 1.3
MIN_NCC_MARGIN = 0.08
#: Largest offset (px) of the agreement peak: whole image, and each quadrant with a clear peak.
MAX_OFFSET_PX = 1.0
MAX_LOCAL_OFFSET_PX = 1.5
#: Largest misfit (px) at the image corners extrapolated from the quadrants' agreement peaks.
MAX_CORNER_MISFIT_PX = 1.5
#: Outline samples (1 px apart) a quadrant needs for its own peak; most samples used.
MIN_SAMPLES = 150
MAX_SAMPLES = 20000
#: Longest side (px) of the image in the raster agreement test (larger images are reduced).
RASTER_SIDE = 700


@dataclass
class Evidence:
    """The figures of :func:`assess` and its verdict.

    Figures that could not be computed are ``None``. ``local_offsets_px`` and ``local_peaks``
    are per image quadrant (top left, top right, bottom left, bottom right).
    """

    verified: bool
    reasons: List[str]  #: why not verified, in English (empty when verified)
    points: int = 0  #: control points used by the fit
    independent_points: bool = True  #: False: points from a grid through a search transform
    #: The reference is building footprints (the edge agreement cannot verify grid points)
    buildings: bool = False
    hull_share: Optional[float] = None  #: convex-hull share of the image (0–1)
    quadrants: Optional[int] = None  #: quadrants with ≥ QUADRANT_POINTS points
    corner_disagreement_px: Optional[float] = None  #: halves' transforms at the corners
    #: the largest disagreement allowed (px): :data:`MAX_CORNER_PX`, or for building
    #: footprints up to :data:`HALVES_SIGMAS` of its standard deviation
    corner_limit_px: float = MAX_CORNER_PX
    #: the transform fitted to predict the held-out quadrants (:func:`holdout_kind`)
    holdout_kind: Optional[str] = None
    holdout_rmse_px: Optional[float] = None  #: leave-one-quadrant-out RMSE
    agreement: Optional[str] = None  #: "edges" (polygons) or "correlation" (raster)
    agreement_score: Optional[float] = None  #: at the result (no shift)
    peak: Optional[float] = None  #: edge peak ratio or correlation peak margin
    offset_px: Optional[float] = None  #: where the agreement peaks (whole image)
    local_offsets_px: List[Optional[float]] = field(default_factory=list)
    local_peaks: List[Optional[float]] = field(default_factory=list)
    #: misfit at the image corners (px) extrapolated from the quadrants' agreement peaks
    corner_misfit_px: Optional[float] = None
    #: per quadrant: how much the best shift beats no shift (edges: ratio − 1; raster: NCC
    #: difference)
    local_gains: List[Optional[float]] = field(default_factory=list)
    #: a quadrant left out of the corner misfit: it departs from the other three (0–3)
    ambiguous_quadrant: Optional[int] = None
    #: the reasons as (key of :data:`REASON_TEXTS`, figures): what the faces translate
    reason_items: List[Tuple[str, Dict[str, Any]]] = field(default_factory=list)
    seconds: float = 0.0

    def to_json(self) -> Dict[str, Any]:
        """JSON-ready (rounded) figures for report.json (not the seconds: reports of the same
        inputs stay byte-identical)."""
        def r(v: Any) -> Any:
            return round(float(v), 4) if isinstance(v, (float, np.floating)) else v
        d = asdict(self)
        d.pop("seconds")
        items = d.pop("reason_items")
        out = {k: ([r(x) for x in v] if isinstance(v, list) and k != "reasons" else r(v))
               for k, v in d.items()}
        out["reason_items"] = [[k, v] for k, v in items]  # JSON: lists, not tuples
        return out

    def text(self) -> str:
        """One line with the figures (the report, the log, the failure message)."""
        return evidence_text(self.to_json())


def evidence_text(ev: Dict[str, Any]) -> str:
    """The figures of an evidence dict (:meth:`Evidence.to_json`) in one line."""
    parts = []
    if ev.get("independent_points", True):
        if ev.get("hull_share") is not None:
            parts.append(f"control points cover {100 * ev['hull_share']:.0f} % of the image "
                         f"and {ev.get('quadrants')} of 4 quadrants")
        if ev.get("corner_disagreement_px") is not None:
            parts.append(f"corners disagree by {ev['corner_disagreement_px']:.1f} px between "
                         "halves")
        if ev.get("holdout_rmse_px") is not None:
            parts.append(f"held-out RMSE {ev['holdout_rmse_px']:.2f} px")
    else:
        parts.append("control points from a grid through the search transform (not "
                     "independent)")
    if ev.get("agreement") == "edges" and ev.get("peak") is not None:
        parts.append(f"edge peak ratio {ev['peak']:.2f} at {ev['offset_px']:.1f} px")
    elif ev.get("agreement") == "correlation" and ev.get("peak") is not None:
        parts.append(f"correlation {ev['agreement_score']:.2f}, peak margin "
                     f"{ev['peak']:.2f} at {ev['offset_px']:.1f} px")
    local = [v for v in ev.get("local_offsets_px") or [] if v is not None]
    if local:
        parts.append("quadrant offsets " + ", ".join(f"{v:.1f}" for v in local) + " px")
    if ev.get("corner_misfit_px") is not None:
        parts.append(f"corner misfit {ev['corner_misfit_px']:.1f} px")
    return "; ".join(parts)


def hull_share(xy: Array, shape: Sequence[int]) -> float:
    """Share of the image area inside the convex hull of ``xy`` (0 for fewer than 3)."""
    if len(xy) < 3:
        return 0.0
    try:
        return float(ConvexHull(xy).volume / (shape[0] * shape[1]))
    except Exception:  # collinear or repeated points: no area
        return 0.0


def assess(result: GeorefResult, reference: Union[PathLike, Sequence[Array], None] = None,
           buildings: bool = False) -> Evidence:
    """Independent evidence for ``result`` (see the module notes).

    Parameters
    ----------
    result : GeorefResult
        Any stage's result (its ``fit``, ``gcps``, ``grey`` and ``stage`` are read).
    reference : path or sequence of (n, 2) arrays, optional
        A georeferenced raster (path), or polygon outlines in map coordinates (the reference
        polygons' rings). ``None``: no agreement test (not verified: the agreement is needed).
    buildings : bool
        The polygons are building footprints. Their edge agreement has several peaks a few
        pixels apart (roof outlines displaced by relief, walls, cast shadows), so it cannot
        verify a result whose control points are not independent (the area stage's grid):
        such a result is not verified (reason ``buildings_area``).

    Returns
    -------
    Evidence
    """
    t0 = time.perf_counter()
    fit, grey = result.fit, result.grey
    shape = grey.shape
    used = np.asarray(fit.used, bool)
    img = np.array([g.image for g in result.gcps], float).reshape(-1, 2)[used]
    mp = np.array([g.map for g in result.gcps], float).reshape(-1, 2)[used]
    ev = Evidence(verified=False, reasons=[], points=int(used.sum()),
                  independent_points=result.stage != "area", buildings=buildings)
    if ev.independent_points:
        ev.hull_share = hull_share(img, shape)
        ev.quadrants = int((np.bincount(_quadrant(img, shape), minlength=4)
                            >= QUADRANT_POINTS).sum())
        ev.holdout_kind = holdout_kind(fit.kind, len(img))
        ev.corner_disagreement_px = _corner_disagreement(img, mp, fit, shape)
        if buildings and fit.kind == "affine":
            roofs = np.array([g.pair for g in result.gcps], int).reshape(-1)[used]
            ev.corner_limit_px = _buildings_corner_limit(img, mp, roofs, fit, shape)
        ev.holdout_rmse_px = _holdout_rmse(img, mp, fit, shape)
    if reference is not None:
        if isinstance(reference, (str, Path)):
            _raster_agreement(ev, result, Path(reference))
        else:
            _edge_agreement(ev, result, reference)
    ev.reason_items = _reasons(ev)
    ev.reasons = [reason_text(k, v) for k, v in ev.reason_items]
    ev.verified = not ev.reason_items
    ev.seconds = time.perf_counter() - t0
    return ev


#: Names of the image quadrants (the order of ``local_offsets_px``).
QUADRANT_NAMES = ("top left", "top right", "bottom left", "bottom right")
#: The English sentence of each reason key (:attr:`Evidence.reason_items`), formatted with its
#: figures; the faces translate the same keys and figures into their language.
REASON_TEXTS = {
    "spread": "the control points cover {hull_pct:.0f} % of the image (needs "
              "≥ {min_hull_pct:.0f} %) and {quadrants} of 4 quadrants (needs ≥ {min_quadrants})",
    "no_holdout": "too few control points for a held-out check",
    "halves": "the corners disagree by {corner_px:.1f} px between transforms of halves of the "
              "control points (at most {max_px:g} px)",
    "holdout": "control points held out quadrant by quadrant are predicted with an RMSE of "
               "{rmse_px:.1f} px (at most {max_px:g} px)",
    "no_agreement": "no image–reference agreement could be measured (the reference does not "
                    "reach into the image)",
    "edge_peak": "image and reference do not agree: edge peak ratio {peak:.2f} (needs "
                 "≥ {need:g})",
    "correlation_peak": "image and reference do not agree: correlation peak margin {peak:.2f} "
                        "(needs ≥ {need:g})",
    "offset": "image and reference agree best {offset_px:.1f} px away from the result (at "
              "most {max_px:g} px)",
    "corner_misfit": "image and reference agree best {misfit_px:.1f} px away from the result at "
                     "an image corner (extrapolated from the quadrants; at most {max_px:g} px)",
    "local_offsets": "image and reference agree best away from the result in the {quadrants} "
                     "(at most {max_px:g} px)",
    "buildings_area": "building footprints cannot confirm a result of the area-based search "
                      "(roof edges displaced by relief, walls and cast shadows agree with "
                      "the footprints a few pixels apart)",
}


def reason_text(key: str, values: Dict[str, Any]) -> str:
    """The English sentence of one reason (:data:`REASON_TEXTS`); ``local_offsets`` lists its
    quadrants as "top left quadrant (2.1 px), …"."""
    if key == "local_offsets":
        values = {**values, "quadrants": ", ".join(
            f"{QUADRANT_NAMES[k]} quadrant ({o:.1f} px)" for k, o in values["quadrants"])}
    return REASON_TEXTS[key].format(**values)


def _reasons(ev: Evidence) -> List[Tuple[str, Dict[str, Any]]]:
    """Why ``ev`` does not verify its result (empty: verified): (key, figures) pairs, the
    figures rounded as they are shown."""
    why: List[Tuple[str, Dict[str, Any]]] = []
    if ev.buildings and not ev.independent_points:
        why.append(("buildings_area", {}))
    if ev.independent_points:
        if ev.hull_share < MIN_HULL or ev.quadrants < MIN_QUADRANTS:
            why.append(("spread", {"hull_pct": round(100 * ev.hull_share, 1),
                                   "min_hull_pct": 100 * MIN_HULL, "quadrants": ev.quadrants,
                                   "min_quadrants": MIN_QUADRANTS}))
        if ev.corner_disagreement_px is None:
            why.append(("no_holdout", {}))
        elif ev.corner_disagreement_px > ev.corner_limit_px:
            why.append(("halves", {"corner_px": round(ev.corner_disagreement_px, 2),
                                   "max_px": round(ev.corner_limit_px, 2)}))
        if ev.holdout_rmse_px is not None and ev.holdout_rmse_px > MAX_HOLDOUT_PX:
            why.append(("holdout", {"rmse_px": round(ev.holdout_rmse_px, 2),
                                    "max_px": MAX_HOLDOUT_PX}))
    if ev.agreement is None:
        why.append(("no_agreement", {}))
        return why
    edges = ev.agreement == "edges"
    need = MIN_EDGE_PEAK if edges else MIN_NCC_MARGIN
    if ev.peak < need:
        why.append(("edge_peak" if edges else "correlation_peak",
                    {"peak": round(ev.peak, 3), "need": need}))
    elif ev.offset_px > MAX_OFFSET_PX:
        why.append(("offset", {"offset_px": round(ev.offset_px, 2), "max_px": MAX_OFFSET_PX}))
    if ev.corner_misfit_px is not None and ev.corner_misfit_px > MAX_CORNER_MISFIT_PX:
        why.append(("corner_misfit", {"misfit_px": round(ev.corner_misfit_px, 2),
                                      "max_px": MAX_CORNER_MISFIT_PX}))
    bad = [[k, round(o, 2)] for k, (o, p) in enumerate(zip(ev.local_offsets_px, ev.local_peaks))
           if o is not None and p is not None and p >= need and o > MAX_LOCAL_OFFSET_PX
           and k != ev.ambiguous_quadrant]
    if bad:
        why.append(("local_offsets", {"quadrants": bad, "max_px": MAX_LOCAL_OFFSET_PX}))
    return why


# -- spread and held-out check --------------------------------------------------------------
def _quadrant(xy: Array, shape: Sequence[int]) -> NDArray[np.int64]:
    """Image quadrant of each point: 0 top left, 1 top right, 2 bottom left, 3 bottom right."""
    rows, cols = shape[0], shape[1]
    return ((xy[:, 0] >= (cols - 1) / 2).astype(int)
            + 2 * (xy[:, 1] >= (rows - 1) / 2).astype(int))


def holdout_kind(kind: str, points: int) -> str:
    """The transform that predicts held-out quadrants from ``points`` control points: the
    result's own kind; a second-order polynomial only with at least
    :data:`POLY2_SUBSET_POINTS` points (about 3/4 of them predict a quadrant), else a
    projective transform."""
    if kind == "poly2" and 3 * points // 4 < POLY2_SUBSET_POINTS:
        return "projective"
    return kind


def _halves_kind(kind: str) -> str:
    """The transform of the halves: a quadratic fitted to half the points extrapolates wildly
    to the other half's corners (a right poly2 result on 500 points: 2.0 px), so a poly2
    result's halves get a projective transform."""
    return "projective" if kind == "poly2" else kind


def _subset_map(img: Array, mp: Array, kind: str) -> Callable[[Array], Array]:
    """The image → map function of ``kind`` fitted to a subset (least squares, no robust
    step). Raises ValueError / LinAlgError for too few or degenerate points."""
    if kind == "poly2":
        return fit_transform(img, mp, kind, robust=False).forward
    M = fit_matrix(img, mp, kind)
    return lambda xy: apply(M, xy)


def _corners(shape: Sequence[int]) -> Array:
    rows, cols = shape[0], shape[1]
    return np.array([[-0.5, -0.5], [cols - 0.5, -0.5], [-0.5, rows - 0.5],
                     [cols - 0.5, rows - 0.5]])


def _halves(img: Array) -> List[Tuple[NDArray[np.int64], NDArray[np.int64]]]:
    """The two splits of the points into halves: at the median column, at the median row."""
    out = []
    for axis in (0, 1):
        order = np.argsort(img[:, axis], kind="stable")
        out.append((order[:len(order) // 2], order[len(order) // 2:]))
    return out


def _corner_disagreement(img: Array, mp: Array, fit: Any, shape: Sequence[int]
                         ) -> Optional[float]:
    """Largest distance (px) at the image corners between the transforms of two halves of
    the points (split at the median column, then at the median row); ``None``: too few."""
    kind = _halves_kind(fit.kind)
    need = MIN_POINTS[kind] + 1
    corners = _corners(shape)
    worst = None
    for a, b in _halves(img):
        if len(a) < need or len(b) < need:
            return None
        try:
            fa, fb = _subset_map(img[a], mp[a], kind), _subset_map(img[b], mp[b], kind)
        except (ValueError, np.linalg.LinAlgError):
            return None
        d = np.hypot(*(fa(corners) - fb(corners)).T).max() / fit.pixel_size
        d = float(d) if np.isfinite(d) else float("inf")
        worst = d if worst is None else max(worst, d)
    return worst


def _halves_sd(img: Array, mp: Array, roofs: NDArray[np.int64], shape: Sequence[int]
               ) -> Optional[float]:
    """Standard deviation (map units) of the halves' disagreement where it is largest (the
    split and corner of :func:`_corner_disagreement`), for affine fits to the halves: each half's
    parameter covariance from its residuals summed per roof (points on one roof share its
    relief error, so the roofs, not the points, are the independent observations); the two
    halves independent. ``None`` with fewer than 4 roofs in a half."""
    corners = np.column_stack([_corners(shape), np.ones(4)])
    worst: Optional[Tuple[float, float]] = None  # (disagreement, its standard deviation)
    for a, b in _halves(img):
        diff, var = np.zeros((4, 2)), np.zeros(4)
        for sign, idx in ((1.0, a), (-1.0, b)):
            if len(np.unique(roofs[idx])) < 4:
                return None
            A = np.column_stack([img[idx], np.ones(len(idx))])
            bread = np.linalg.pinv(A.T @ A)
            beta = bread @ A.T @ mp[idx]
            e = mp[idx] - A @ beta
            for k in range(2):
                meat = np.zeros((3, 3))
                for r in np.unique(roofs[idx]):
                    on = roofs[idx] == r
                    v = A[on].T @ e[on, k]
                    meat += np.outer(v, v)
                var += np.einsum("ij,jk,ik->i", corners, bread @ meat @ bread, corners)
            diff += sign * (corners @ beta)
        d = np.hypot(*diff.T)
        k = int(np.argmax(d))
        if worst is None or d[k] > worst[0]:
            worst = (float(d[k]), float(np.sqrt(var[k])))
    return None if worst is None else worst[1]


def _buildings_corner_limit(img: Array, mp: Array, roofs: NDArray[np.int64], fit: Any,
                            shape: Sequence[int]) -> float:
    """The halves' limit (px) against building footprints (:data:`HALVES_SIGMAS`)."""
    sd = _halves_sd(img, mp, roofs, shape)
    if sd is None:
        return MAX_CORNER_PX
    return float(np.clip(HALVES_SIGMAS * sd / fit.pixel_size, MAX_CORNER_PX,
                         MAX_BUILDINGS_CORNER_PX))


def _holdout_rmse(img: Array, mp: Array, fit: Any, shape: Sequence[int]) -> Optional[float]:
    """RMSE (px) of each quadrant's points predicted by the transform of the other quadrants'
    points (quadrants whose complement has too few points are skipped; ``None``: none)."""
    kind = holdout_kind(fit.kind, len(img))
    q = _quadrant(img, shape)
    res = []
    for k in range(4):
        held = q == k
        if not held.any() or (~held).sum() < MIN_POINTS[kind] + 1:
            continue
        try:
            f = _subset_map(img[~held], mp[~held], kind)
        except (ValueError, np.linalg.LinAlgError):
            continue
        res.append(f(img[held]) - mp[held])
    if not res:
        return None
    r = np.vstack(res)
    return float(np.sqrt(np.mean(np.sum(r**2, axis=1))) / fit.pixel_size)


# -- image–reference agreement ---------------------------------------------------------------
def _shifts() -> Array:
    """The (dx, dy) grid of the peak test."""
    s = np.arange(-SHIFT_PX, SHIFT_PX + 1, dtype=float)
    dx, dy = np.meshgrid(s, s)
    return np.column_stack([dx.ravel(), dy.ravel()])


def _map_to_image(result: GeorefResult, xy: Array) -> Array:
    """Map → image coordinates under the result's fit (poly2: its inverse fit)."""
    if result.fit.matrix is not None:
        return apply(np.linalg.inv(result.fit.matrix), xy)
    return result.inverse_fit.forward(xy)


def _smoothed_gradient(grey: Array, sigma: float = 1.0) -> Tuple[Array, Array, NDArray[np.bool_]]:
    """Gradient (gx along columns, gy along rows) of the Gaussian-smoothed image and where it
    is valid (not within two pixels of no data)."""
    valid = np.isfinite(grey)
    fill = float(np.nanmean(grey)) if valid.any() else 0.0
    g = ndimage.gaussian_filter(np.where(valid, grey, fill).astype(np.float64), sigma)
    gy, gx = np.gradient(g)
    core = valid if valid.all() else ndimage.binary_erosion(valid, iterations=3)
    return gx, gy, core


def _edge_agreement(ev: Evidence, result: GeorefResult, rings: Sequence[Array]) -> None:
    """Polygon reference: mean |gradient · outline normal| along the outlines taken into the
    image, at the result and at shifts (module notes); fills ``ev``."""
    grey = result.grey
    rows, cols = grey.shape
    img_rings = [_map_to_image(result, np.asarray(r, float)[:, :2]) for r in rings]
    pts, ang, _ = boundary_samples(img_rings, 1.0)
    gx, gy, core = _smoothed_gradient(grey)
    m = SHIFT_PX + 1
    inside = ((pts[:, 0] >= m) & (pts[:, 0] <= cols - 1 - m) & (pts[:, 1] >= m)
              & (pts[:, 1] <= rows - 1 - m))
    pts, ang = pts[inside], ang[inside]
    ok = core[np.round(pts[:, 1]).astype(int), np.round(pts[:, 0]).astype(int)]
    pts, ang = pts[ok], ang[ok]
    if len(pts) < MIN_SAMPLES:
        return
    if len(pts) > MAX_SAMPLES:  # evenly thinned: the figures are means
        keep = np.linspace(0, len(pts) - 1, MAX_SAMPLES).astype(int)
        pts, ang = pts[keep], ang[keep]
    nx, ny = -np.sin(ang), np.cos(ang)
    shifts = _shifts()
    q = _quadrant(pts, grey.shape)
    sums = np.zeros((len(shifts), 4))
    for k, (dx, dy) in enumerate(shifts):
        coords = [pts[:, 1] + dy, pts[:, 0] + dx]
        v = np.abs(ndimage.map_coordinates(gx, coords, order=1) * nx
                   + ndimage.map_coordinates(gy, coords, order=1) * ny)
        sums[k] = np.bincount(q, weights=v, minlength=4)
    n = np.bincount(q, minlength=4).astype(float)
    whole = sums.sum(axis=1) / n.sum()
    ev.agreement = "edges"
    ev.agreement_score = float(whole[len(shifts) // 2])
    peak, off = _peak(whole, shifts, ratio=True)
    local = [_peak(sums[:, k] / n[k], shifts, ratio=True) if n[k] >= MIN_SAMPLES else None
             for k in range(4)]
    zero = len(shifts) // 2
    ev.local_gains = [None if n[k] < MIN_SAMPLES else
                      float(sums[:, k].max() / max(sums[zero, k], 1e-12)) - 1.0
                      for k in range(4)]
    centres = [pts[q == k].mean(axis=0) if n[k] else None for k in range(4)]
    _local_figures(ev, peak, off, local, centres, MIN_EDGE_PEAK, grey.shape, 1.0)


def _peak(score: Array, shifts: Array, ratio: bool) -> Tuple[float, Array]:
    """Peak figure and offset (dx, dy px, sub-pixel by parabolas) of a score over the shift
    grid: ``ratio``: best / mean of the far shifts, else best − mean of the far shifts."""
    far = np.hypot(*shifts.T) >= FAR_PX
    k = int(np.argmax(score))
    best, ref = float(score[k]), float(np.mean(score[far]))
    peak = best / ref if ratio else best - ref
    if ratio and ref <= 0:
        peak = 0.0
    n = 2 * SHIFT_PX + 1
    grid = score.reshape(n, n)  # rows: dy, columns: dx
    i, j = divmod(k, n)
    off = [shifts[k, 0], shifts[k, 1]]
    for axis, (lo, hi) in ((0, (grid[i, j - 1] if j > 0 else None,
                               grid[i, j + 1] if j < n - 1 else None)),
                           (1, (grid[i - 1, j] if i > 0 else None,
                                grid[i + 1, j] if i < n - 1 else None))):
        if lo is not None and hi is not None:
            den = lo - 2 * best + hi
            if den < 0:
                off[axis] += float(np.clip(0.5 * (lo - hi) / den, -0.5, 0.5))
    return float(peak), np.array(off, float)


def _raster_agreement(ev: Evidence, result: GeorefResult, path: Path) -> None:
    """Raster reference: NCC of gradient magnitudes of the image and the reference resampled
    into it, at the result and at shifts (module notes); fills ``ev``."""
    grey = result.grey
    rows, cols = grey.shape
    f = max(1.0, max(rows, cols) / RASTER_SIDE)
    r = np.arange(0, rows, f)
    c = np.arange(0, cols, f)
    cc, rr = np.meshgrid(c, r)
    small = ndimage.map_coordinates(np.where(np.isfinite(grey), grey, np.nan), [rr, cc],
                                    order=1, cval=np.nan)
    with rasterio.open(path) as src:
        ref = src.read().astype(np.float64)
        nod = src.nodata
        to_pix = np.linalg.inv(centre_matrix(src.transform))
    if nod is not None:
        ref[ref == nod] = np.nan
    ref = ref.mean(axis=0)
    xy = result.fit.forward(np.column_stack([cc.ravel(), rr.ravel()]))
    ij = apply(to_pix, xy)
    res = ndimage.map_coordinates(ref, [ij[:, 1], ij[:, 0]], order=1, cval=np.nan
                                  ).reshape(small.shape)
    a, b = _gradient_magnitude(small), _gradient_magnitude(res)
    _ncc_peaks(ev, a, b, f)


def _gradient_magnitude(a: Array) -> Array:
    """|∇a| after a Gaussian of 1 px; NaN within two pixels of no data."""
    gx, gy, core = _smoothed_gradient(a)
    return np.where(core, np.hypot(gx, gy), np.nan)


def _ncc_peaks(ev: Evidence, a: Array, b: Array, f: float) -> None:
    """NCC of ``a`` with ``b`` shifted over the grid, whole image and per quadrant (offsets
    × ``f`` into full-resolution px); fills ``ev``."""
    rows, cols = a.shape
    m = SHIFT_PX
    shifts = _shifts()
    h2, w2 = rows // 2, cols // 2
    quads = [(slice(m, h2), slice(m, w2)), (slice(m, h2), slice(w2, cols - m)),
             (slice(h2, rows - m), slice(m, w2)), (slice(h2, rows - m), slice(w2, cols - m))]
    sums = np.zeros((len(shifts), 4, 6))  # n, Σa, Σb, Σab, Σa², Σb²
    for k, (dx, dy) in enumerate(shifts.astype(int)):
        for qi, (rs, cs) in enumerate(quads):
            x = a[rs, cs]
            y = b[rs.start + dy:rs.stop + dy, cs.start + dx:cs.stop + dx]
            ok = np.isfinite(x) & np.isfinite(y)
            x, y = x[ok], y[ok]
            sums[k, qi] = (x.size, x.sum(), y.sum(), (x * y).sum(), (x * x).sum(),
                           (y * y).sum())

    def ncc(s: Array) -> Array:
        n = np.maximum(s[..., 0], 1)
        cov = s[..., 3] - s[..., 1] * s[..., 2] / n
        va = s[..., 4] - s[..., 1] ** 2 / n
        vb = s[..., 5] - s[..., 2] ** 2 / n
        return np.where((va > 0) & (vb > 0), cov / np.sqrt(np.maximum(va * vb, 1e-300)), 0.0)

    whole = ncc(sums.sum(axis=1))
    if sums[:, :, 0].sum(axis=1).min() < MIN_SAMPLES:
        return
    ev.agreement = "correlation"
    ev.agreement_score = float(whole[len(shifts) // 2])
    peak, off = _peak(whole, shifts, ratio=False)
    local = [_peak(ncc(sums[:, qi]), shifts, ratio=False)
             if sums[:, qi, 0].min() >= MIN_SAMPLES else None for qi in range(4)]
    zero = len(shifts) // 2
    ev.local_gains = [None if v is None else float(ncc(sums[:, qi]).max()
                                                   - ncc(sums[zero, qi]))
                      for qi, v in enumerate(local)]
    centres = [np.array([(cs.start + cs.stop) / 2, (rs.start + rs.stop) / 2]) * f
               for rs, cs in quads]
    _local_figures(ev, peak, off * f, [None if v is None else (v[0], v[1] * f) for v in local],
                   centres, MIN_NCC_MARGIN, (rows * f, cols * f), f)


def _local_figures(ev: Evidence, peak: float, off: Array,
                   local: Sequence[Optional[Tuple[float, Array]]],
                   centres: Sequence[Optional[Array]], need: float, shape: Sequence[float],
                   f: float) -> None:
    """Fill ``ev`` with the whole image's and the quadrants' peaks, and the misfit at the
    image corners extrapolated from the quadrants' shifts (offsets in full-resolution px).

    The shifts of the quadrants with a clear peak get a similarity field (shift, scale,
    rotation about the image centre — what a wrong transform shows); with four quadrants,
    one that departs from the other three by more than :data:`MAX_LOCAL_OFFSET_PX` is
    ambiguous (parallel edges a few px apart, e.g. moraines) and left out. Two quadrants:
    the larger of their shifts; fewer: the whole image's offset.
    """
    ev.peak, ev.offset_px = peak, float(np.hypot(*off))
    ev.local_peaks = [None if v is None else v[0] for v in local]
    ev.local_offsets_px = [None if v is None else float(np.hypot(*v[1])) for v in local]
    clear = [k for k, (c, v) in enumerate(zip(centres, local))
             if v is not None and c is not None and v[0] >= need]
    if len(clear) < 2:
        ev.corner_misfit_px = ev.offset_px if peak >= need else None
        return
    if len(clear) == 2:
        ev.corner_misfit_px = max(ev.local_offsets_px[k] for k in clear)
        return
    centre = np.array([(shape[1] - 1) / 2, (shape[0] - 1) / 2])
    xy = {k: np.asarray(centres[k], float) - centre for k in clear}
    d = {k: np.asarray(local[k][1], float) for k in clear}
    model, res = _similarity_field(clear, xy, d)
    if len(clear) == 4 and res.max() > MAX_LOCAL_OFFSET_PX:
        worst = clear[int(np.argmax(res))]
        clear = [k for k in clear if k != worst]
        ev.ambiguous_quadrant = worst
        model, res = _similarity_field(clear, xy, d)
    corners = _corners((shape[0], shape[1])) - centre
    ev.corner_misfit_px = float(np.hypot(*_similarity_apply(model, corners).T).max())


def _similarity_field(keys: Sequence[int], xy: Dict[int, Array], d: Dict[int, Array]
                      ) -> Tuple[Array, Array]:
    """Least-squares shift field d = t + [[a, −b], [b, a]] · xy over the quadrants ``keys``;
    returns the parameters (tx, ty, a, b) and each quadrant's residual length (px)."""
    rows, rhs = [], []
    for k in keys:
        u, v = xy[k]
        rows += [[1.0, 0.0, u, -v], [0.0, 1.0, v, u]]
        rhs += [d[k][0], d[k][1]]
    p = np.linalg.lstsq(np.array(rows), np.array(rhs), rcond=None)[0]
    pts = np.array([xy[k] for k in keys])
    res = np.hypot(*(_similarity_apply(p, pts) - np.array([d[k] for k in keys])).T)
    return p, res


def _similarity_apply(p: Array, xy: Array) -> Array:
    """The shift field of :func:`_similarity_field` at ``xy`` (relative to the centre)."""
    tx, ty, a, b = p
    return np.column_stack([tx + a * xy[:, 0] - b * xy[:, 1], ty + b * xy[:, 0] + a * xy[:, 1]])
