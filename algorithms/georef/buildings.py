"""Buildings mode of the polygon georeferencing: many small footprints (issue 23).

Building footprints (cadastre, OpenStreetMap) are small, many and alike, and a footprint is not
a homogeneous image region: a gabled roof has a sunlit and a shaded half, roofs carry chimneys,
shadows and trees cut them, relief displacement moves them. One pair says little; the
*configuration* of neighbouring buildings carries the information. The chain:

1. **Candidates** (:func:`roof_candidates`): segments of a graph-based segmentation
   (Felzenszwalb & Huttenlocher, two scales — a multiple segmentation) whose outline stands
   out (mean gradient along it); segments below a minimum size (chimneys, dormers, gravel)
   join a neighbour, so a roof half carrying spots stays one segment and narrow halves keep
   their exact outline (no gradient band); pairs of adjacent segments whose union is
   rectangular are added (the two halves of a gabled roof merged across the ridge); size
   window and shape filters (rectangularity, elongation, no holes). A single segment
   elongated like a roof half also gives its rectangle mirrored across either long side
   (:func:`mirrored_wholes`): the shaded half often runs into its cast shadow, so the sunlit
   half alone must stand for the whole roof. Mirrored wholes never seed hypotheses and are
   neighbour sites only when the segments' own sites give no consensus.
2. **One-pair hypotheses**: every (candidate, footprint) pair of plausible size gives the 8
   affine maps of the standard positions (:mod:`.invariants`; a rectangle's standard position is
   a square, so all D4 alternatives). Each is scored by its **neighbourhood**: the k nearest
   other candidate sites mapped by it must land on footprint centroids (tolerance grows with
   the distance) — the affine-invariant constellation of the neighbours, tested directly.
   When these give no consensus (a town whose roofs are seen only as narrow halves, too
   irregular to give the whole affine from one shape), **pair hypotheses**
   (:func:`_pair_hypotheses`): two neighbouring elongated candidates against the shapes of
   two neighbouring footprints, matched by their area ratio and the directions of their long
   sides against the line joining them; each match gives a similarity, scored the same way.
3. **Consensus** (:func:`match_buildings`): the best-supported hypotheses are grown over the
   whole image (map all sites, nearest footprint within a tolerance, one-to-one, affine fit,
   repeated with a shrinking tolerance), in batches of :data:`TRY_BATCH` up to
   :data:`MAX_TRIES`. Every different placement with enough centroid matches is refined
   (step 4) and ranked by its **shape count**: the footprints a candidate covers, or covers
   one roof half of (overlap ≥ 0.5, one partner each). Centroids alone are matched by chance
   in a town of like buildings (a wrong placement gathers 8–15 of them); shapes are not (0–10).
   Accepted when at least :data:`MIN_MATCHES` footprints and :data:`MIN_SHARE` of those
   inside the image are matched by shape, :data:`MIN_LEAD` × any different placement; the
   tries stop early (after :data:`MIN_TRIES`) once one is.
4. **Refinement** (:func:`_refine`): the growth pairs centroids by distance only (a roof
   half taken for the whole roof leaves it a few pixels off); the consensus is refitted on
   candidates that cover a footprint or a roof half under it (best overlap per shape). The
   accepted one is also refitted from the image centre outwards (:func:`_centre_out`: an
   affine a little off in scale pairs far roofs with their neighbours) and the refit that
   covers more footprints at the verification's overlap is kept (:func:`_pull_in`). Then
   the verified whole roofs (overlap, one partner each) refit it again while their number
   grows; they become the pairs for the usual ICP and control points.

Relief displacement (roofs 0–3 px from their footprints, radial from the image centre ∝ height)
is a per-building offset; its radial mean is a scale about the image centre that no transform
fitted to roofs can tell from the true scale (see the bench notes).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Dict, List, Optional, Sequence, Tuple

import numpy as np
from numpy.typing import NDArray
from scipy import ndimage
from scipy.spatial import cKDTree
from skimage.measure import label as label_connected
from skimage.segmentation import felzenszwalb

from ..feedback import Feedback
from .correspondence import Hypothesis, affine_from_points, apply, overlap, verify
from .invariants import _D4, ObjectFeatures, min_bounding_rectangle, object_features
from .objects import IMAGE, PolygonObject, orient_ring
from .regions import label_rings

Array = NDArray[np.float64]

#: Automatic buildings mode: at least this many reference polygons ...
AUTO_MIN_POLYGONS = 15
#: ... whose median area is below this share of the reference extent (bounding box).
#: Building footprints: 0.003–0.07 % (a 450 m town: 150 m² of 200 000 m²); the suburban
#: scenes of 500 and 900 px (seeds 0–59): 0.02–0.25 % (a small image shows a small town
#: whose footprints cover more of it; 0.2 % missed two of them, which then ran the area
#: stages for 83 and 180 s); the synthetic forest/field/lake maps of the polygon bench:
#: 0.75–1.1 %.
AUTO_MAX_MEDIAN_SHARE = 0.004
#: ... at most this large (map units², m²: buildings, not glaciers — the 39 RGI glaciers of the
#: Everest bench have a median of 0.02 % of their extent but of square kilometres) ...
AUTO_MAX_AREA = 5000.0
#: ... and rectangular (median area / minimum bounding rectangle; footprints ≈ 0.9–1).
AUTO_RECTANGULARITY = 0.7
#: Scales of the graph-based segmentation (Felzenszwalb & Huttenlocher; image standardised
#: to mean 0, standard deviation 1): larger → larger segments. Two runs: one that keeps roof
#: halves apart, one that joins weakly separated parts.
SEGMENT_SCALES = (300.0, 1000.0)
#: Smallest segment (px): smaller ones (chimneys, dormers, gravel, noise) join a neighbour.
MIN_SEGMENT_PX = 25
#: A candidate's mean gradient along its outline, × the median gradient magnitude (σ = 1 px):
#: the pieces of an over-segmented lawn or road edge have weak outlines.
MIN_BORDER_CONTRAST = 5.0
#: Zones darker on average than this percentile of the image are shadows, not roofs.
SHADOW_PERCENTILE = 6.0
#: Size window of candidates: px² and share of the image.
MIN_CANDIDATE_PX = 16
MAX_CANDIDATE_SHARE = 0.02
#: Shape filter: area / area of the minimum bounding rectangle, and its longer / shorter side.
MIN_RECTANGULARITY = 0.55
MAX_ELONGATION = 10.0
#: Share of a candidate's outline area its own pixels fill (holes: not a roof).
MIN_FILL = 0.92
#: A single segment at least this rectangular and elongated (long / short side) may be one
#: half of a gabled roof (a whole roof no longer than wide has halves of 2:1): its mirror
#: images across either long side are added as whole-roof candidates (the shaded half often
#: runs into its cast shadow and has no outline of its own).
MIRROR_RECTANGULARITY = MIN_RECTANGULARITY
MIRROR_MIN_ELONGATION = 1.8
#: Candidates at least this rectangular are neighbours (sites) in the hypothesis scoring.
SITE_RECTANGULARITY = 0.7
#: Candidates at least this rectangular seed hypotheses (all are neighbours).
SOURCE_RECTANGULARITY = 0.8
#: Rounds of the consensus, each tried when the ones before give none: (rectangularity of the
#: candidates that are sites, mirrored wholes among the sites, pair hypotheses instead of
#: one-pair ones). The last: pairs of any candidates elongated enough — narrow roof halves
#: whose pixel outlines are too irregular to seed a one-pair hypothesis (seeds 6, 14 of the
#: buildings bench: 0 right one-pair hypotheses, 9 / 7 right pair ones).
CONSENSUS_ROUNDS = ((SITE_RECTANGULARITY, False, False), (SITE_RECTANGULARITY, True, False),
                    (MIN_RECTANGULARITY, False, True))
#: Neighbours scored per hypothesis.
NEIGHBOURS = 8
#: Pair hypotheses (:func:`_pair_hypotheses`): an elongated site (long / short side) with its
#: nearest elongated sites, against the shapes of a footprint and its nearest footprints
#: (those elongated enough to have a long side); descriptors within a log area ratio and a
#: direction of the long sides this far apart match.
PAIR_NEIGHBOURS = 8
PAIR_REF_NEIGHBOURS = 6
PAIR_MIN_ELONGATION = 1.4
PAIR_MIN_SHAPE_ELONGATION = 1.25
PAIR_AREA_LOG = 0.3
PAIR_ANGLE_DEG = 10.0
#: Acceptance by the shape count (footprints covered by a candidate or by one on a roof half
#: after :func:`_refine`): at least this many, this share of the footprints inside the image,
#: and this ratio over the best different placement. Seeds 0–19 at relief 3: right placements
#: 15–58 shapes, 45–78 % of those inside, ≥ 2.7 × the runner-up; the best wrong ones (seeds
#: 6, 14, three different towns) 3–10 shapes, ≤ 21 %, ≤ 1.5 ×.
MIN_MATCHES = 12
MIN_SHARE = 0.35
MIN_LEAD = 2.0
#: Growth tries: at most :data:`MAX_TRIES` hypotheses (best support first) in batches of
#: :data:`TRY_BATCH`, stopping after :data:`MIN_TRIES` once a placement is accepted.
MAX_TRIES = 160
MIN_TRIES = 40
TRY_BATCH = 20
#: Grown placements with at least this many centroid matches get their shape count (it
#: may exceed the centroid count: a site is one per roof, a footprint may have two halves).
MIN_GROWN = 6
#: Centre-out refit of the accepted consensus (:func:`_centre_out`): shares of its shape
#: pairs nearest the image centre fitted in turn, at least this many pairs.
CENTRE_OUT_SHARES = (0.3, 0.45, 0.6, 0.75, 0.9, 1.0)
CENTRE_OUT_MIN_PAIRS = 12
#: Overlap of a verified roof with its footprint (min of both shares): a roof half (≤ 0.5)
#: or a roof with its shadow would pull the ICP's outlines apart. 0.7 since the mirrored
#: wholes (0.6 before: with whole roofs for half the footprints the stricter choice leaves
#: enough roofs and a lower ICP RMS; seeds 0–9 at relief 3: 6 instead of 4 within 1 px).
VERIFY_OVERLAP = 0.7
#: Rounds of verification and refit of the consensus on the verified roofs.
REFINE_ROUNDS = 4


def is_buildings(ref_objs: Sequence[PolygonObject]) -> bool:
    """True when the reference looks like building footprints: many small rectangular
    polygons (:data:`AUTO_MIN_POLYGONS`, :data:`AUTO_MAX_MEDIAN_SHARE`,
    :data:`AUTO_MAX_AREA`, :data:`AUTO_RECTANGULARITY`)."""
    if len(ref_objs) < AUTO_MIN_POLYGONS:
        return False
    pts = np.vstack([o.ring for o in ref_objs])
    extent = float(np.prod(pts.max(axis=0) - pts.min(axis=0)))
    med = float(np.median([o.area for o in ref_objs]))
    if not (extent > 0 and med < AUTO_MAX_MEDIAN_SHARE * extent and med <= AUTO_MAX_AREA):
        return False
    return float(np.median([_shape_ok(o.ring)[1] for o in ref_objs])) >= AUTO_RECTANGULARITY


# -- candidates ---------------------------------------------------------------------------------
def _segments(image: Array, scale: float, valid: NDArray[np.bool_]) -> NDArray[np.int32]:
    """4-connected segments of the graph-based segmentation (Felzenszwalb & Huttenlocher) of
    ``image`` (standardised) at ``scale``; 0 outside ``valid``."""
    seg = felzenszwalb(image, scale=scale, sigma=0.5, min_size=MIN_SEGMENT_PX) + 1
    # its segments are 8-connected: split them so that every label has one outline
    lab = label_connected(seg, connectivity=1).astype(np.int32)
    lab[~valid] = 0
    return lab


def _border_contrast(lab: NDArray[np.int32], gm: Array, n: int) -> Array:
    """Mean gradient magnitude on every label's border pixels (a 4-neighbour of another
    label): a roof stands out along its outline, a piece of an over-segmented lawn does not."""
    border = np.zeros(lab.shape, bool)
    dh = lab[:, :-1] != lab[:, 1:]
    dv = lab[:-1, :] != lab[1:, :]
    border[:, :-1] |= dh
    border[:, 1:] |= dh
    border[:-1, :] |= dv
    border[1:, :] |= dv
    lb = lab[border]
    cnt = np.bincount(lb, minlength=n + 1)
    return np.bincount(lb, weights=gm[border], minlength=n + 1) / np.maximum(cnt, 1)


def _ring_area(ring: Array) -> float:
    x, y = ring[:, 0], ring[:, 1]
    return 0.5 * abs(float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y)))


def _shape_ok(ring: Array) -> Tuple[bool, float]:
    """Rectangularity and elongation filter; returns (passes, rectangularity)."""
    area = _ring_area(ring)
    _, _, half = min_bounding_rectangle(ring)
    mbr = 4.0 * half[0] * half[1]
    if mbr <= 0 or min(half) <= 0:
        return False, 0.0
    rect = area / mbr
    elong = max(half) / min(half)
    return rect >= MIN_RECTANGULARITY and elong <= MAX_ELONGATION, rect


def _adjacent_pairs(lab: NDArray[np.int32], keep: NDArray[np.bool_]
                    ) -> List[Tuple[int, int, int]]:
    """Pairs of kept labels touching (4-neighbours) with the length of the shared border."""
    pairs: Dict[Tuple[int, int], int] = {}
    for a, b in ((lab[:, :-1], lab[:, 1:]), (lab[:-1, :], lab[1:, :])):
        m = (a != b) & (a > 0) & (b > 0)
        m &= keep[a] & keep[b]
        lo, hi = np.minimum(a[m], b[m]), np.maximum(a[m], b[m])
        key = lo.astype(np.int64) * (int(lab.max()) + 1) + hi
        vals, counts = np.unique(key, return_counts=True)
        for v, c in zip(vals, counts):
            k = (int(v // (int(lab.max()) + 1)), int(v % (int(lab.max()) + 1)))
            pairs[k] = pairs.get(k, 0) + int(c)
    return [(a, b, c) for (a, b), c in pairs.items()]


def roof_candidates(grey: Array, scales: Sequence[float] = SEGMENT_SCALES,
                    feedback: Optional[Feedback] = None) -> Tuple[List[PolygonObject],
                                                                  Dict[str, Any]]:
    """Image objects that may be roofs (module notes, step 1), level-0 image coordinates
    (pixel centres at integers). Returns the objects and figures per segmentation scale."""
    fb = feedback or Feedback()
    valid = np.isfinite(grey)
    filled = np.where(valid, grey, np.nanmean(grey))
    g = ndimage.gaussian_filter(filled, 1.0)
    gm = np.hypot(ndimage.sobel(g, 0), ndimage.sobel(g, 1)) / 8.0
    lo, hi = MIN_CANDIDATE_PX, MAX_CANDIDATE_SHARE * grey.size
    # in units of the median gradient (noise and texture of the open ground): the same
    # contrast for 8-bit data and for stretched 11/12-bit data with a different noise level
    unit = max(float(np.median(gm[valid])), 1e-3)
    dark = float(np.percentile(g[valid], SHADOW_PERCENTILE))
    # standardised: the segmentation scale means the same for 8-bit and 11/12-bit data
    std = (filled - float(np.mean(filled))) / max(float(np.std(filled)), 1e-9)
    objs: List[PolygonObject] = []
    runs = []
    for k, t in enumerate(scales):
        fb.check()
        lab = _segments(std, float(t), valid)
        n = int(lab.max())
        size = np.bincount(lab.ravel(), minlength=n + 1)
        keep = (size >= lo) & (size <= hi)
        # shadow: the darkest zones (a shaded roof half joined to its cast shadow would pull
        # the roof's centroid away from the sun)
        mean = np.bincount(lab.ravel(), weights=g.ravel(), minlength=n + 1) / np.maximum(size, 1)
        keep &= mean > dark
        keep &= _border_contrast(lab, gm, n) >= MIN_BORDER_CONTRAST * unit
        keep[0] = False
        n_single = n_mirrored = 0
        for value, ring in label_rings(lab, keep):
            ok, rect = _shape_ok(ring)
            # holes (a lawn block around houses, not a roof) fail the fill share
            if ok and size[value] >= MIN_FILL * _ring_area(ring):
                objs.append(_candidate(ring - 0.5, k, t, int(size[value]), rect, len(objs)))
                n_single += 1
                if rect >= MIRROR_RECTANGULARITY:
                    for whole in mirrored_wholes(ring - 0.5, int(size[value]), max_area=hi):
                        objs.append(_candidate(whole, k, t, 2 * int(size[value]), 1.0,
                                               len(objs), mirrored=True))
                        n_mirrored += 1
        # halves of a gabled roof (or roof and dormer side): merge pairs of adjacent zones
        n_merged = 0
        boxes = ndimage.find_objects(lab)
        for a, b, border in _adjacent_pairs(lab, keep):
            sa, sb = int(size[a]), int(size[b])
            if min(sa, sb) < 0.2 * (sa + sb) or sa + sb > hi:
                continue
            if border < 1.5 * math.sqrt(min(sa, sb)):  # a long shared edge: the ridge
                continue
            ring = _union_ring(lab, a, b, boxes)
            if ring is None:
                continue
            ok, rect = _shape_ok(ring)
            if ok and rect >= 0.7:
                objs.append(_candidate(ring - 0.5, k, t, sa + sb, rect, len(objs),
                                       merged=True))
                n_merged += 1
        runs.append({"scale": float(t), "segments": n, "single": n_single,
                     "merged": n_merged, "mirrored": n_mirrored})
    return objs, {"runs": runs}


def mirrored_wholes(ring: Array, pixels: float, max_area: float = np.inf) -> List[Array]:
    """Whole-roof rectangles of a segment that may be one roof half: its rectangle doubled
    across each of its long sides (the ridge is one of them; which one the footprints decide).
    The rectangle is the minimum bounding rectangle of the pixel outline shrunk by a common
    margin to the segment's ``pixels`` (the staircase outline of a rotated edge lies up to
    half a pixel outside it). Empty when the segment is not elongated enough
    (:data:`MIRROR_MIN_ELONGATION`) or the whole would exceed ``max_area`` (px²)."""
    c, ax, half = min_bounding_rectangle(ring)
    i = int(np.argmax(half))
    a, b = float(half[i]), float(half[1 - i])
    # (2a − 2d)(2b − 2d) = pixels, the smaller root
    d = 0.5 * ((a + b) - math.sqrt(max((a - b) ** 2 + pixels, 0.0)))
    a, b = a - max(d, 0.0), b - max(d, 0.0)
    if b <= 0 or a / b < MIRROR_MIN_ELONGATION or 8.0 * a * b > max_area:
        return []
    u, v = ax[i], ax[1 - i]
    corners = np.array([(-1, -1), (1, -1), (1, 1), (-1, 1)], float)
    out = []
    for side in (-1.0, 1.0):
        cc = c + side * b * v
        out.append(orient_ring(cc + corners[:, :1] * a * u + corners[:, 1:] * 2.0 * b * v))
    return out


def _candidate(ring: Array, run: int, t: float, pixels: int, rect: float, ident: int,
               merged: bool = False, mirrored: bool = False) -> PolygonObject:
    return PolygonObject(id=ident, ring=ring, source=IMAGE, run=run, threshold=float(t),
                         attributes={"pixels": pixels, "rectangularity": round(rect, 3),
                                     "merged": merged, "mirrored": mirrored})


def _union_ring(lab: NDArray[np.int32], a: int, b: int, boxes: Sequence[Any]
                ) -> Optional[Array]:
    """Outer ring of the union of labels ``a`` and ``b`` (full-image corner coordinates);
    ``boxes``: :func:`scipy.ndimage.find_objects` of ``lab`` (only the pair's box is read)."""
    sa, sb = boxes[a - 1], boxes[b - 1]
    r0, r1 = min(sa[0].start, sb[0].start), max(sa[0].stop, sb[0].stop)
    c0, c1 = min(sa[1].start, sb[1].start), max(sa[1].stop, sb[1].stop)
    win = lab[r0:r1, c0:c1]
    sub = ((win == a) | (win == b)).astype(np.int32)
    sub_lab, n = ndimage.label(sub)
    if n != 1:
        return None
    rings = label_rings(sub_lab)
    if not rings:
        return None
    return rings[0][1] + np.array([c0, r0], float)


# -- hypotheses and consensus -------------------------------------------------------------------
@dataclass
class BuildingMatch:
    """The consensus of the buildings mode."""

    transform: Optional[Array]  #: 3 × 3 image → map (None: no consensus)
    pairs: List[Hypothesis]  #: verified (candidate, footprint) pairs
    overlaps: List[float]
    img_features: List[ObjectFeatures]
    ref_features: List[ObjectFeatures]
    counts: Dict[str, Any] = field(default_factory=dict)
    reason: str = ""  #: why there is no result


def _sites(fi: Sequence[ObjectFeatures], radius: float, use: Sequence[bool]
           ) -> Tuple[Array, NDArray[np.int64]]:
    """Centroids of the candidates in ``use`` merged within ``radius`` px (the runs segment
    one roof several times): site centroids and the site of every candidate (-1: none)."""
    c = np.array([f.centroid if u else [np.nan, np.nan] for f, u in zip(fi, use)])
    c = np.where(np.isfinite(c), c, 1e12)
    tree = cKDTree(c)
    site = -np.ones(len(c), np.int64)
    centres = []
    for k in np.argsort([-f.area for f in fi]):
        if site[k] >= 0 or not use[k]:
            continue
        near = [j for j in tree.query_ball_point(c[k], radius) if site[j] < 0]
        site[near] = len(centres)
        centres.append(c[k])
    return np.array(centres), site


def roof_halves(ref_objs: Sequence[PolygonObject]) -> Tuple[List[PolygonObject], List[int]]:
    """The two halves of every footprint's minimum bounding rectangle split along its long
    axis: what one side of a gabled or hipped roof looks like. Returns the half rectangles and
    the footprint (index) each belongs to."""
    out, owner = [], []
    for j, o in enumerate(ref_objs):
        c, ax, half = min_bounding_rectangle(o.ring)
        u, v = (ax[0], ax[1]) if half[0] >= half[1] else (ax[1], ax[0])
        a, b = max(half), min(half)
        for side in (-1.0, 1.0):
            cc = c + side * 0.5 * b * v
            ring = np.array([cc + s * a * u + t * 0.5 * b * v
                             for s, t in ((-1, -1), (1, -1), (1, 1), (-1, 1))])
            out.append(PolygonObject(id=len(out), ring=orient_ring(ring), source=o.source))
            owner.append(j)
    return out, owner


@dataclass
class _Shapes:
    """Reference shapes a candidate may be: footprints and their roof halves, with the
    footprint each belongs to."""

    normaliser_inv: Array  # (m, 2, 2)
    centroid: Array  # (m, 2)
    area: Array  # (m,)
    owner: NDArray[np.int64]  # (m,)
    axis: Array  # (m,) direction of the long side (rad)
    elongation: Array  # (m,) long / short side


def _shapes(fr: Sequence[ObjectFeatures], fh: Sequence[ObjectFeatures],
            owner_h: Sequence[int]) -> _Shapes:
    both = list(fr) + list(fh)
    axis, elongation = _long_axes(both)
    return _Shapes(np.linalg.inv(np.array([f.normaliser for f in both])),
                   np.array([f.centroid for f in both]), np.array([f.area for f in both]),
                   np.array(list(range(len(fr))) + list(owner_h), np.int64), axis, elongation)


def _long_axes(fs: Sequence[ObjectFeatures]) -> Tuple[Array, Array]:
    """Direction (rad) of the long side of every object's minimum bounding rectangle and its
    elongation (long / short side)."""
    axis, elongation = np.zeros(len(fs)), np.ones(len(fs))
    for k, f in enumerate(fs):
        _, ax, half = f.mbr
        i = int(np.argmax(half))
        axis[k] = math.atan2(ax[i][1], ax[i][0])
        elongation[k] = float(half[i]) / max(float(half[1 - i]), 1e-9)
    return axis, elongation


def _hypotheses(fi: Sequence[ObjectFeatures], shapes: _Shapes, sites: Array,
                site_of: NDArray[np.int64], cr: Array, base_tol: float,
                sources: Sequence[int], image_area: float
                ) -> List[Tuple[float, Array, Array]]:
    """(support, transform, map position) of every one-pair hypothesis with support ≥ 2
    (module notes, step 2); ``sources``: the candidates tried.

    The support counts the footprint's k nearest neighbouring footprints that, mapped into
    the image by the hypothesis, land on distinct candidate sites: the footprints are clean
    (no clutter), so their constellation is the one to test; the image has clutter besides
    the roofs, which only adds a few chance hits.
    """
    nb = _Neighbourhood.of(sites, cr, len(sites) / image_area)
    D4 = np.array(_D4)
    out = []
    for i in sources:
        f = fi[i]
        # L = N_shape⁻¹ D N_i for every shape and D4 element: (m, 8, 2, 2)
        L = np.einsum("mab,dbc,ce->mdae", shapes.normaliser_inv, D4, f.base)
        det = np.abs(np.linalg.det(L))
        ratio = det * f.area / shapes.area[:, None]
        mi, di = np.nonzero((ratio > 0.6) & (ratio < 1.6))
        if not len(mi):
            continue
        Ls = L[mi, di]  # (h, 2, 2)
        support = nb.support(Ls, np.broadcast_to(f.centroid, (len(mi), 2)), mi, shapes,
                             base_tol, np.full((len(mi), 1), site_of[i]))
        for h in np.nonzero(support >= 2)[0]:
            out.append((float(support[h]), _affine(Ls[h], f.centroid,
                                                   shapes.centroid[mi[h]]),
                        shapes.centroid[mi[h]]))
    out.sort(key=lambda t: -t[0])
    return out


def _affine(L: Array, src: Array, dst: Array) -> Array:
    """3 × 3 affine with linear part ``L`` that maps the point ``src`` onto ``dst``."""
    T = np.eye(3)
    T[:2, :2] = L
    T[:2, 2] = dst - L @ src
    return T


@dataclass
class _Neighbourhood:
    """The test of a hypothesis by its neighbourhood: the vectors from every footprint to its
    :data:`NEIGHBOURS` nearest footprints, the sites (image) and their density."""

    stree: cKDTree  #: the candidate sites (image)
    W: Array  #: (n_ref, k, 2) vectors from each footprint to its nearest ones (map)
    cr: Array  #: footprint centroids (map)
    density: float  #: sites per px²

    @classmethod
    def of(cls, sites: Array, cr: Array, density: float) -> _Neighbourhood:
        k = min(NEIGHBOURS + 1, len(cr))
        _, rn = cKDTree(cr).query(cr, k)
        return cls(cKDTree(sites), cr[rn[:, 1:]] - cr[:, None, :], cr, density)

    def support(self, L: Array, xy: Array, mi: NDArray[np.int64], shapes: _Shapes,
                base_tol: float, exclude: NDArray[np.int64]) -> Array:
        """Support of the hypotheses ``L`` (h, 2, 2) that put the image point ``xy`` (h, 2)
        on shape ``mi`` (h,): the owning footprint's neighbours mapped into the image that
        land on distinct sites other than ``exclude`` (h, e), minus the hits expected by
        chance (the sites' density over the tolerance discs)."""
        own = shapes.owner[mi]
        # the footprint's neighbours relative to the shape's centroid, into the image
        Wh = self.W[own] + (self.cr[own] - shapes.centroid[mi])[:, None, :]
        img = xy[:, None, :] + np.einsum("hab,hnb->hna", np.linalg.inv(L), Wh)
        det = np.abs(np.linalg.det(L))
        tol = (base_tol + 0.06 * np.linalg.norm(Wh, axis=2)) / np.sqrt(det)[:, None]
        d, j = self.stree.query(img.reshape(-1, 2), distance_upper_bound=float(tol.max()))
        j = j.reshape(tol.shape)
        hit = (d.reshape(tol.shape) <= tol) & ~np.any(j[:, :, None] == exclude[:, None, :],
                                                      axis=2)
        chance = np.minimum(1.0, self.density * np.pi * tol**2).sum(axis=1)
        return _distinct(np.where(hit, j, -1)) - chance


def _pair_hypotheses(fi: Sequence[ObjectFeatures], shapes: _Shapes, sites: Array,
                     site_of: NDArray[np.int64], cr: Array, base_tol: float,
                     image_area: float) -> List[Tuple[float, Array, Array]]:
    """(support, transform, map position) of the *pair* hypotheses with support ≥ 2: two
    neighbouring elongated sites matched to two shapes (footprints or roof halves) of
    neighbouring footprints by a descriptor that a similarity (mirrored or not) leaves
    unchanged — the log ratio of their areas and the direction of each one's long side
    against the line joining them (:func:`_pair_descriptors`). Each match gives the
    similarity of the two centroids; the support is that of :func:`_hypotheses`, the two
    sites themselves not counted.

    A one-pair hypothesis needs one candidate that is a whole roof or a clean half whose
    shape gives the whole affine; this needs only centroids, areas and long sides, which
    narrow roof halves (pixel outlines of low rectangularity) still give.
    """
    rep = _site_representatives(fi, site_of, len(sites))
    ang_i, el_i = _long_axes([fi[r] for r in rep])
    area_i = np.array([fi[r].area for r in rep])
    ends = np.nonzero(el_i >= PAIR_MIN_ELONGATION)[0]
    if len(ends) < 2 or len(cr) < 2:
        return []
    # image: every elongated site with its nearest elongated sites (both orders)
    k = min(PAIR_NEIGHBOURS + 1, len(ends))
    _, nn = cKDTree(sites[ends]).query(sites[ends], k)
    ia, ib = ends[np.repeat(np.arange(len(ends)), k - 1)], ends[nn[:, 1:].ravel()]
    # map: the shapes of every footprint with those of its nearest footprints
    k = min(PAIR_REF_NEIGHBOURS + 1, len(cr))
    _, rn = cKDTree(cr).query(cr, k)
    fa, fb = np.repeat(np.arange(len(cr)), k - 1), rn[:, 1:].ravel()
    of = [np.nonzero(shapes.owner == j)[0] for j in range(len(cr))]
    ma, mb = [], []
    for a, b in zip(fa, fb):
        for sa in of[a]:
            ma += [sa] * len(of[b])
            mb += list(of[b])
    ma, mb = np.array(ma, np.int64), np.array(mb, np.int64)
    keep = (shapes.elongation[ma] >= PAIR_MIN_SHAPE_ELONGATION) & \
        (shapes.elongation[mb] >= PAIR_MIN_SHAPE_ELONGATION)
    ma, mb = ma[keep], mb[keep]
    if not len(ma):
        return []
    di = _pair_descriptors(sites[ia], sites[ib], ang_i[ia], ang_i[ib], area_i[ia] / area_i[ib])
    dm = _pair_descriptors(shapes.centroid[ma], shapes.centroid[mb], shapes.axis[ma],
                           shapes.axis[mb], shapes.area[ma] / shapes.area[mb])
    itree = cKDTree(di)
    out = []
    nb = _Neighbourhood.of(sites, cr, len(sites) / image_area)
    for mirror in (1.0, -1.0):  # a mirrored similarity turns the directions the other way
        hits = cKDTree(dm * np.array([1.0, 1.0, mirror, 1.0, mirror])).query_ball_tree(
            itree, 1.0)
        pm = np.array([m for m, h in enumerate(hits) for _ in h], np.int64)
        pi = np.array([x for h in hits for x in h], np.int64)
        if not len(pm):
            continue
        a, b, sa, sb = ia[pi], ib[pi], ma[pm], mb[pm]
        L = _similarities(sites[b] - sites[a], shapes.centroid[sb] - shapes.centroid[sa],
                          mirror)
        det = np.abs(np.linalg.det(L))
        ok = np.isfinite(det) & (det > 0)  # footprints of one building share a centroid
        for i, m in ((a, sa), (b, sb)):
            ratio = det * area_i[i] / shapes.area[m]
            ok &= (ratio > 0.6) & (ratio < 1.6)
        a, b, sa, L = a[ok], b[ok], sa[ok], L[ok]
        if not len(L):
            continue
        support = nb.support(L, sites[a], sa, shapes, base_tol, np.stack([a, b], axis=1))
        for h in np.nonzero(support >= 2)[0]:
            out.append((float(support[h]), _affine(L[h], sites[a[h]],
                                                   shapes.centroid[sa[h]]),
                        shapes.centroid[sa[h]]))
    out.sort(key=lambda t: -t[0])
    return out


def _site_representatives(fi: Sequence[ObjectFeatures], site_of: NDArray[np.int64],
                          n_sites: int) -> NDArray[np.int64]:
    """The largest candidate of every site (the one :func:`_sites` placed it at)."""
    rep = -np.ones(n_sites, np.int64)
    for k in np.argsort([-f.area for f in fi], kind="stable"):
        if site_of[k] >= 0 and rep[site_of[k]] < 0:
            rep[site_of[k]] = k
    return rep


def _pair_descriptors(p: Array, q: Array, ang_p: Array, ang_q: Array, area_ratio: Array
                      ) -> Array:
    """(n, 5) descriptors of object pairs that a similarity leaves unchanged (a mirrored one
    negates the 3rd and 5th component): the log area ratio and, for each object, the
    direction of its long side against the line from ``p`` to ``q`` as (cos 2θ, sin 2θ)
    (a long side has no sign), scaled so that a distance of 1 is :data:`PAIR_AREA_LOG` or
    :data:`PAIR_ANGLE_DEG` apart."""
    v = q - p
    phi = np.arctan2(v[:, 1], v[:, 0])
    chord = 2.0 * math.sin(math.radians(PAIR_ANGLE_DEG))
    tp, tq = 2.0 * (ang_p - phi), 2.0 * (ang_q - phi)
    return np.column_stack([np.log(area_ratio) / PAIR_AREA_LOG, np.cos(tp) / chord,
                            np.sin(tp) / chord, np.cos(tq) / chord, np.sin(tq) / chord])


def _similarities(v: Array, V: Array, mirror: float) -> Array:
    """(n, 2, 2) linear parts of the similarities that turn the image vectors ``v`` into the
    map vectors ``V``; ``mirror`` −1: mirrored (the image y axis flipped first)."""
    w = v * np.array([1.0, mirror])
    zv, zV = w[:, 0] + 1j * w[:, 1], V[:, 0] + 1j * V[:, 1]
    z = zV / zv
    L = np.empty((len(z), 2, 2))
    L[:, 0, 0], L[:, 0, 1] = z.real, -z.imag * mirror
    L[:, 1, 0], L[:, 1, 1] = z.imag, z.real * mirror
    return L


def _distinct(j: NDArray[np.int64]) -> NDArray[np.int64]:
    """Distinct non-negative values per row (neighbours landing on the same footprint count
    once: a collapsed map sends them all to one place)."""
    js = np.sort(j, axis=1)
    new = np.ones_like(js, bool)
    new[:, 1:] = js[:, 1:] != js[:, :-1]
    return np.sum(new & (js >= 0), axis=1)


def _grow(T: Array, sites: Array, cr: Array, rtree: cKDTree, base_tol: float,
          seed_xy: Array) -> Tuple[Array, NDArray[np.int64], NDArray[np.int64]]:
    """Grow one hypothesis over the whole image: nearest footprint per site, one-to-one,
    robust affine refit; the tolerance is ``base_tol`` plus a share of the distance from
    ``seed_xy`` (map) shrinking from 6 % to 1 %, repeated until the matches stop changing.
    Returns the transform and the matched site and target indices."""
    si = rj = np.zeros(0, np.int64)
    # the tolerance grows with the distance from the seed: an affine slightly off in scale
    # or shear misplaces far buildings most
    schedule = [0.06, 0.04, 0.03, 0.02] + [0.01] * 12
    prev: Optional[set] = None
    for k, f in enumerate(schedule):
        mapped = apply(T, sites)
        tol = base_tol + f * np.linalg.norm(mapped - seed_xy, axis=1)
        d, j = rtree.query(mapped, distance_upper_bound=float(tol.max()))
        ok = d <= tol
        order = np.argsort(d[ok])
        s_ok, j_ok = np.nonzero(ok)[0][order], j[ok][order]
        _, first = np.unique(j_ok, return_index=True)  # one site per footprint (nearest)
        si, rj = s_ok[first], j_ok[first]
        if len(si) < 3:
            break
        T2 = _robust_affine(sites[si], cr[rj])
        if T2 is None:
            break
        T = T2
        now = set(zip(si.tolist(), rj.tolist()))
        if k >= 3 and now == prev:
            break
        prev = now
    return T, si, rj


def _robust_affine(src: Array, dst: Array) -> Optional[Array]:
    """Least-squares affine, refitted without the pairs beyond 2.5 × the median residual."""
    T = affine_from_points(src, dst)
    if T is None or len(src) < 6:
        return T
    r = np.linalg.norm(apply(T, src) - dst, axis=1)
    keep = r <= 2.5 * max(float(np.median(r)), 1e-9)
    return affine_from_points(src[keep], dst[keep]) if keep.sum() >= 3 else T


def _inside_count(T: Array, cr: Array, shape: Tuple[int, int]) -> int:
    """Footprints whose centroid falls inside the image under ``T``."""
    p = apply(np.linalg.inv(T), cr)
    return int(np.sum((p[:, 0] >= 0) & (p[:, 1] >= 0) & (p[:, 0] <= shape[1] - 1)
                      & (p[:, 1] <= shape[0] - 1)))


def _same_placement(si: NDArray[np.int64], rj: NDArray[np.int64], sk: NDArray[np.int64],
                    rk: NDArray[np.int64]) -> bool:
    """Two consensus sets describe the same placement: most sites both matched go to the
    same footprint (growths from different seeds end a few pixels apart, with other sites)."""
    a = dict(zip(si.tolist(), rj.tolist()))
    common = [(a[s], r) for s, r in zip(sk.tolist(), rk.tolist()) if s in a]
    return bool(common) and sum(x == y for x, y in common) >= 0.5 * len(common)


def match_buildings(grey: Array, ref_objs: Sequence[PolygonObject],
                    feedback: Optional[Feedback] = None,
                    max_tries: int = MAX_TRIES) -> BuildingMatch:
    """Candidates, hypotheses and consensus (module notes, steps 1–4)."""
    fb = feedback or Feedback()
    cands, cinfo = roof_candidates(grey, feedback=fb)
    counts_runs = cinfo["runs"]
    counts: Dict[str, Any] = {"image_objects": len(cands), "reference_objects": len(ref_objs),
                              "candidate_runs": counts_runs}
    fr = object_features(ref_objs)
    if len(cands) < MIN_MATCHES:
        return BuildingMatch(None, [], [], [], fr, counts, f"only {len(cands)} roof "
                             "candidates in the image")
    fi = object_features(cands)
    fb.progress(30)
    cr = np.array([f.centroid for f in fr])
    base_tol = 0.25 * math.sqrt(float(np.median([f.area for f in fr])))
    halves, owner = roof_halves(ref_objs)
    shapes = _shapes(fr, object_features(halves), owner)
    rings = [o.ring for o in ref_objs] + [h.ring for h in halves]
    mirrored = [bool(c.attributes.get("mirrored")) for c in cands]
    rect = [c.attributes["rectangularity"] for c in cands]
    # the mirrored wholes never seed a hypothesis (two per half, one of them wrong: they
    # flood the tries with false seeds); as neighbour sites they are tried only when the
    # segments' own sites give no consensus — their wrong halves add chance matches that
    # favour placements at a wrong scale
    sources = [i for i in range(len(cands)) if rect[i] >= SOURCE_RECTANGULARITY
               and not mirrored[i]]
    T, why = None, ""
    for min_rect, with_mirrored, pairs in CONSENSUS_ROUNDS:
        if with_mirrored and not any(mirrored):
            continue
        use = [r >= min_rect and (with_mirrored or not m) for r, m in zip(rect, mirrored)]
        T, why = _consensus(fi, use, _Reference(shapes, rings, cr, base_tol),
                            None if pairs else sources, grey.shape, counts, max_tries, fb)
        counts["consensus_mirrored_sites"] = with_mirrored
        counts["consensus_pair_hypotheses"] = pairs
        if T is not None:
            break
    fb.progress(50)
    if T is None:
        return BuildingMatch(None, [], [], fi, fr, counts, why)
    return _verified(T, fi, fr, counts, base_tol)


@dataclass
class _Reference:
    """What the consensus matches against: the shapes (footprints and roof halves), their
    rings (map), the footprint centroids and the base tolerance (map units)."""

    shapes: _Shapes
    rings: List[Array]
    cr: Array
    base_tol: float


@dataclass
class _Placement:
    """One grown hypothesis: centroid matches, then (refined) its shape count."""

    n: int  #: footprints matched by centroid in the growth
    T: Array  #: the grown transform, refined once the shape count is known
    si: NDArray[np.int64]  #: matched sites
    rj: NDArray[np.int64]  #: their footprints
    shapes: int = -1  #: footprints matched by shape (-1: not evaluated)


def _consensus(fi: Sequence[ObjectFeatures], use: Sequence[bool], ref: _Reference,
               sources: Optional[Sequence[int]], shape: Tuple[int, int], counts: Dict[str, Any],
               max_tries: int, fb: Feedback) -> Tuple[Optional[Array], str]:
    """Hypotheses on the sites of the candidates in ``use`` — one-pair hypotheses of the
    candidates ``sources`` (:func:`_hypotheses`), or pair hypotheses (:func:`_pair_hypotheses`)
    when ``sources`` is None — grown over the image, ranked and
    accepted by their shape count (module notes, steps 2–4). The tries go on in batches until
    one placement has a clear lead (:func:`_decision`) or ``max_tries`` are spent. Returns the
    accepted (refined) transform, or None and why not; ``counts`` gets the figures."""
    sites, site_of = _sites(fi, 3.0, use)
    area = float(shape[0] * shape[1])
    hyps = _pair_hypotheses(fi, ref.shapes, sites, site_of, ref.cr, ref.base_tol, area) \
        if sources is None else _hypotheses(fi, ref.shapes, sites, site_of, ref.cr,
                                            ref.base_tol, sources, area)
    counts.update(sites=len(sites), hypotheses=len(hyps),
                  best_support=round(float(hyps[0][0]), 3) if hyps else 0)
    # targets of the growth: footprint centroids and roof-half centroids (a site is often one
    # half of a gabled roof); a footprint counts once
    ttree = cKDTree(ref.shapes.centroid)
    found: List[_Placement] = []
    n_tries = min(len(hyps), max_tries)
    ok, why = False, "no hypothesis is supported by its neighbours"
    for start in range(0, n_tries, TRY_BATCH):
        for _, T0, xy in hyps[start:start + TRY_BATCH]:
            fb.check()
            T, si, tj = _grow(T0, sites, ref.shapes.centroid, ttree, ref.base_tol, xy)
            _add_placement(found, _Placement(len(np.unique(ref.shapes.owner[tj])), T, si,
                                             ref.shapes.owner[tj]))
        for p in found:
            if p.shapes < 0 and p.n >= MIN_GROWN:
                p.T, p.shapes = _refine(p.T, fi, ref.shapes, ref.rings, ref.base_tol)
        tried = min(start + TRY_BATCH, n_tries)
        counts["tries"] = tried
        if found:
            ok, why = _decision(found, ref.cr, shape, counts)
            if ok and tried >= MIN_TRIES:
                break
    if not ok:
        return None, why
    T, taken = _pull_in(_best(found).T, fi, ref.shapes, ref.rings, ref.base_tol, shape)
    counts["centre_out_refit"] = taken
    return T, ""


def _add_placement(found: List[_Placement], new: _Placement) -> None:
    """Add a grown placement unless a placement it is the same as (:func:`_same_placement`)
    matched at least as many footprints; a better growth replaces it."""
    if new.n < 3:
        return
    for k, p in enumerate(found):
        if _same_placement(p.si, p.rj, new.si, new.rj):
            if new.n > p.n:
                found[k] = new
            return
    found.append(new)


def _best(found: Sequence[_Placement]) -> _Placement:
    """The placement with the most shape matches (then centroid matches)."""
    return max(found, key=lambda p: (p.shapes, p.n))


def _decision(found: Sequence[_Placement], cr: Array, shape: Tuple[int, int],
              counts: Dict[str, Any]) -> Tuple[bool, str]:
    """Acceptance of the best placement by its shape count: at least :data:`MIN_MATCHES`
    footprints and :data:`MIN_SHARE` of those inside the image, :data:`MIN_LEAD` × the best
    different placement. Returns (accepted, why not); ``counts`` gets the figures."""
    best = _best(found)
    others = [p for p in found if p is not best and not _same_placement(best.si, best.rj,
                                                                         p.si, p.rj)]
    runner = max([max(p.shapes, 0) for p in others] or [0])
    n = max(best.shapes, 0)
    inside = _inside_count(best.T, cr, shape)
    counts.update(consensus_pairs=best.n, shape_pairs=n, footprints_inside=inside,
                  runner_up_shapes=runner,
                  runner_up_pairs=max([p.n for p in others] or [0]))
    if n < MIN_MATCHES or n < MIN_SHARE * inside or n < MIN_LEAD * runner:
        return False, (f"the best placement matches {n} footprint(s) of {inside} inside the "
                       f"image by shape (needs ≥ {MIN_MATCHES} and ≥ "
                       f"{100 * MIN_SHARE:.0f} %), the best different one {runner} (needs a "
                       f"lead of ×{MIN_LEAD:g})")
    return True, ""


def _shape_pairs(T: Array, fi: Sequence[ObjectFeatures], shapes: _Shapes,
                 rings: Sequence[Array], base_tol: float) -> List[Tuple[int, int, float]]:
    """(candidate, shape, overlap) under ``T``: the candidate covers a footprint or a roof
    half (overlap ≥ 0.5, centroids within ``base_tol``), the best overlap first, one partner
    each."""
    ci = np.array([f.centroid for f in fi])
    d, j = cKDTree(shapes.centroid).query(apply(T, ci), min(3, len(shapes.centroid)))
    scored = []
    for i, m in zip(*np.nonzero(d <= base_tol)):
        shape = int(j[i, m])
        ov = overlap(apply(T, fi[i].obj.ring), rings[shape])
        if ov >= 0.5:
            scored.append((ov, int(i), shape))
    scored.sort(reverse=True)
    used_i, used_s, out = set(), set(), []
    for ov, i, shape in scored:
        if i not in used_i and shape not in used_s:
            used_i.add(i)
            used_s.add(shape)
            out.append((i, shape, ov))
    return out


def _covered(pairs: Sequence[Tuple[int, int, float]], shapes: _Shapes,
             min_overlap: float = 0.5) -> int:
    """Footprints with a shape pair (:func:`_shape_pairs`) of at least ``min_overlap``."""
    return len({int(shapes.owner[s]) for _, s, ov in pairs if ov >= min_overlap})


def _fit_pairs(ci: Array, shapes: _Shapes, pairs: Sequence[Tuple[int, int, float]]
               ) -> Optional[Array]:
    """Robust affine of candidate centroids onto their shapes' centroids (≥ 6 pairs)."""
    if len(pairs) < 6:
        return None
    return _robust_affine(ci[[i for i, _, _ in pairs]],
                          shapes.centroid[[s for _, s, _ in pairs]])


def _refine(T: Array, fi: Sequence[ObjectFeatures], shapes: _Shapes,
            rings: Sequence[Array], base_tol: float) -> Tuple[Array, int]:
    """Refit the consensus on the candidates that cover a footprint or a roof half under
    ``T`` (:func:`_shape_pairs`): the growth pairs site and shape centroids by distance only,
    so a half taken for a whole roof (or one candidate of a cluster for another) leaves the
    consensus a few pixels off. Returns the transform and its *shape count*: the footprints
    covered by a candidate or by one on a roof half (a wrong placement pairs centroids by
    chance, rarely shapes)."""
    ci = np.array([f.centroid for f in fi])
    pairs = _shape_pairs(T, fi, shapes, rings, base_tol)
    for _ in range(REFINE_ROUNDS):
        T2 = _fit_pairs(ci, shapes, pairs)
        if T2 is None:
            break
        moved = float(np.max(np.abs(apply(T2, ci) - apply(T, ci))))
        T = T2
        pairs = _shape_pairs(T, fi, shapes, rings, base_tol)
        if moved < 0.01 * base_tol:
            break
    return T, _covered(pairs, shapes)


def _centre_out(T: Array, fi: Sequence[ObjectFeatures], shapes: _Shapes,
                rings: Sequence[Array], base_tol: float, centre: Array) -> Array:
    """Refit ``T`` on its shape pairs nearest ``centre`` (image) first, then on ever more
    (:data:`CENTRE_OUT_SHARES`, at least :data:`CENTRE_OUT_MIN_PAIRS`): a consensus a
    little off in scale or shear is right near the middle of its pairs but pairs far roofs
    with the neighbouring unit of a terrace, and a refit on all pairs keeps that; the near
    pairs' fit extrapolates to the next ring."""
    ci = np.array([f.centroid for f in fi])
    for share in CENTRE_OUT_SHARES:
        for _ in range(2):
            pairs = _shape_pairs(T, fi, shapes, rings, base_tol)
            r = np.linalg.norm(ci[[i for i, _, _ in pairs]] - centre, axis=1)
            near = np.argsort(r)[:max(CENTRE_OUT_MIN_PAIRS, math.ceil(share * len(r)))]
            T2 = _fit_pairs(ci, shapes, [pairs[k] for k in near])
            if T2 is None:
                return T
            T = T2
    return T


def _pull_in(T: Array, fi: Sequence[ObjectFeatures], shapes: _Shapes,
             rings: Sequence[Array], base_tol: float, image_shape: Tuple[int, int]
             ) -> Tuple[Array, bool]:
    """The refined consensus or its centre-out refit (:func:`_centre_out`), whichever covers
    more footprints at the verification's overlap (:data:`VERIFY_OVERLAP`; the shape count
    at 0.5 does not tell a placement 2 px off from one 7 px off). Returns the transform and
    whether the centre-out refit was taken."""
    centre = 0.5 * (np.array(image_shape[::-1], float) - 1.0)
    T2 = _centre_out(T, fi, shapes, rings, base_tol, centre)
    score = [_covered(_shape_pairs(X, fi, shapes, rings, base_tol), shapes, VERIFY_OVERLAP)
             for X in (T, T2)]
    return (T2, True) if score[1] > score[0] else (T, False)


def _verified(T: Array, fi: Sequence[ObjectFeatures], fr: Sequence[ObjectFeatures],
              counts: Dict[str, Any], base_tol: float) -> BuildingMatch:
    """Candidates against footprints under the refined ``T``: the existing verification
    (overlap, one partner each) picks the candidate shape of each footprint (for the review's
    overlay and the per-pair figures)."""
    cr = np.array([f.centroid for f in fr])
    ci = np.array([f.centroid for f in fi])
    rtree = cKDTree(cr)
    ver = None
    for _ in range(REFINE_ROUNDS):
        d, j = rtree.query(apply(T, ci))
        hyps = [Hypothesis(i=i, j=int(j[i]), transform=T, q=1.0, w=1.0, d=0.0)
                for i in range(len(fi)) if d[i] <= base_tol]
        v = verify(hyps, fi, fr, T, min_overlap=VERIFY_OVERLAP, reestimate=False)
        if ver is not None and len(v.pairs) <= len(ver.pairs):
            break
        ver = v
        # the consensus is fitted to roof-half and footprint centroids (a few px off); the
        # verified whole roofs give a better affine for the next round
        T2 = _robust_affine(ci[[h.i for h in v.pairs]], cr[[h.j for h in v.pairs]]) \
            if len(v.pairs) >= 6 else None
        if T2 is None:
            break
        T = T2
    assert ver is not None
    counts.update(verified_pairs=len(ver.pairs))
    T = ver.transform
    return BuildingMatch(T, ver.pairs, ver.overlaps, list(fi), list(fr), counts)
