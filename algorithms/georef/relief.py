"""Relief displacement: the image → map transform from the ground, not from the roofs (issue 23).

In a (near-)vertical frame image a roof at height h is displaced from its footprint radially
from the nadir n by d = (p − n)·h / H (H: flying height above ground). A transform fitted to
roofs (consensus, ICP, outline control points) therefore absorbs the mean displacement as a
scale ≈ 1 + mean(h)/H about the nadir; the image corners end off by that share of their
distance from the nadir. No fit to roofs can tell this from the true scale; only ground-level
evidence can.

The ground-level evidence used here is the base of the walls that face the nadir: between a
footprint edge facing the nadir and the displaced roof edge the wall is seen as a strip
(0 px near the nadir, a few px towards the corners); its outer end is the footprint edge on the
ground. (Edges facing away: the roof hides the wall; they carry only the roof position.)

The chain (:func:`correct_relief`):

1. **Edges**: every footprint (map) mapped into the image by the inverse of the roof-fitted
   transform T; its straight edges whose outward normal faces the nadir, at least 6 px long.
2. **Profile** per edge: grey values sampled across the edge (0.1 px steps, bilinear), the
   median along the edge (trees and chimneys over part of it drop out). Along a straight edge
   the wall strip has a constant width (the radial displacement projected on the normal is
   constant along a line), so the median profile loses nothing.
3. **Misfit curve** per profile (:func:`edge_curve`): roof | wall | ground | anything beyond
   as levels with blurred steps at e ≤ g < f (the ground may slope), least squares for every
   (e, g, f) of a grid; for each ground edge position g the best residual sum of squares,
   in σ² per px above the best. The roof edge is anchored at the profile's largest step near
   the mapped edge (so roof structure further in does not count); a wall (g − e ≥ 0.3 px)
   pays for its two unknowns, else every profile would prefer some wall. An edge therefore
   prefers "no wall" (g = e) unless a wall is seen; a wall of 1 px or more is also explained
   as no wall and a ground step beyond — the edges together decide (step 4). The bias is
   towards no correction.
4. **Relief** (:func:`search_relief`): one scale about the nadir explains all edges: the ground
   edge of an edge at distance r from the nadir (along its normal) lies at g = ρ·r/rmax + δ
   (ρ: the relief at the farthest corner, δ: a common offset between the image's and the
   footprints' edges — the step model's bias). ρ minimises the sum of the capped misfit
   curves over all edges (grid search, δ profiled out): a global estimate, no edge has to be
   decided on its own. Twice: with δ free (:data:`FREE_OFFSET_PX`) for the decision, with δ
   held near zero (:data:`MAX_OFFSET_PX`) for the size — a free δ trades against ρ, a held
   one would let a common offset pass for relief. T' = T·S with S the scale by 1 + ρ/rmax
   about the nadir.
5. **Decision**: T changes only when the roofs sit on the mapped footprints (the start fits:
   :data:`MIN_ROOF_SHARE`), enough edges on enough footprints agree with ρ (their
   misfit ≤ 1 there), ρ > 0 with δ free and held, the free one lowers the summed misfit by at
   least :data:`MIN_GAIN` against ρ = 0, and ρ stays below the plausible limit; otherwise T is
   returned with the reason.
   Without relief the ground edges coincide with the roof edges and ρ = 0 wins.

The control points reported are the ground edges that agree (image) with their feet on the
footprint edges (map): the along-edge coordinate comes from the corrected transform.

Sign convention: profile coordinate t grows along the normal towards the nadir (outwards from
the footprint); the ground edge lies at t = g ≥ e (the roof edge).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Dict, List, Optional, Sequence, Tuple

import numpy as np
from numpy.typing import NDArray
from scipy import ndimage
from scipy.special import erf

from .correspondence import apply
from .objects import unclosed_ring

Array = NDArray[np.float64]

#: Largest wall strip (px) of :func:`edge_curve` by default.
MAX_STRIP_PX = 4.5
#: The ground edge lies at most this far inside the mapped footprint edge (px): the start
#: transform's own error.
G_MIN = -1.0
#: Grid step of the step-model search (px).
GRID_STEP = 0.1
#: Blur of a step (σ, px): the pixel's box and the bilinear interpolation.
STEP_SIGMA = 0.6
#: A wall strip narrower than this (px) is a blurred single step (no wall) ...
MIN_STRIP_PX = 0.3
#: ... a wider one costs this much (σ² per px): two more unknowns.
WALL_PENALTY = 6.0
#: The model's resolution as a share of the roof edge's step (σ floor of the misfit).
MODEL_PRECISION = 0.01
#: An edge's misfit counts up to this (σ² per px): one edge cannot outweigh many.
CHI_CAP = 9.0
#: An edge whose misfit over the ground edge positions rises by less is not informative.
MIN_CHI_RANGE = 4.0
#: The summed misfit at the estimate is at least this much lower than without relief, and at
#: least this much per profiled edge (ρ and the common offset δ trade against each other in a
#: shallow valley: 0.1 per edge seen without relief, 0.19–2.5 with relief 3 px).
MIN_GAIN = 10.0
MIN_GAIN_PER_EDGE = 0.15
#: Edges shorter than this (px) are not profiled; the ends (px) are left out (corners).
MIN_EDGE_PX = 6.0
END_MARGIN_PX = 1.5
#: At least this many edges on at least this many footprints.
MIN_EDGES = 12
MIN_BUILDINGS = 6
#: The roof-fitted start must fit: at least this share of the profiled edges has its roof edge
#: within 0.5 px of the mapped footprint edge (measured: 53–75 % with the right footprints,
#: 22–30 % with footprints of another place).
MIN_ROOF_SHARE = 0.4
#: Whether there is relief at all is decided with the common offset δ of the ground edges
#: free within ± this (px): an offset the step model sees on every edge (the ground edge of a
#: profile without a wall lands 0.3–0.4 px beyond the roof edge) then cannot pass for relief.
FREE_OFFSET_PX = 0.6
#: How much relief is then measured with δ held within ± this (px): a free δ trades against ρ
#: (the edges' mean distance from the nadir is a third of the corner's), which left ρ 0.9–1.0 px
#: too high on buildings seeds 6 and 13 (δ −0.3 to −0.45) and 0.6 px too low on seeds 9
#: and 10 (δ +0.2 to +0.35).
MAX_OFFSET_PX = 0.1
#: Largest plausible relief displacement at the image corner (px); a larger estimate is not
#: relief (inconsistent evidence).
MAX_RELIEF_PX = 6.0
#: The roof edge of every footprint edge is searched within this distance (px) of the mapped
#: edge for the roof refit of the start (the start's own error plus the roofs' relief scatter),
#: then again nearer the refitted edge (a wall base or shadow end within 2.5 px can be the
#: larger step: one pass left seeds 10 and 16 of the buildings bench 0.4 px worse).
ROOF_SEARCH_PX = (2.5, 1.2)
#: Edges whose roof edge is this many robust σ off the refit do not count (Tukey biweight).
ROOF_TUKEY = 4.685
#: At least this many roof edges for the roof refit of the start; fewer: the start is kept.
MIN_ROOF_EDGES = 24
#: A roof edge is taken only where no other step within the search reaches this share of it
#: (relief-0 seed 15, truth start: half of the largest steps were 0.3–2.5 px off the roof edge,
#: where the roof–ground step was weak).
ROOF_STEP_UNIQUE = 0.5
#: The roof refit is dropped when it moves no image corner by this much (px) once its scale
#: about the nadir is taken out: from roof-fitted starts it moves 0.06–0.45 px (its own
#: error); the matched starts it must correct are 0.43–0.73 px off.
REFIT_MIN_PX = 0.5


@dataclass
class EdgeMeasurement:
    """One footprint edge facing the nadir: its mapped midpoint and unit normal towards the
    nadir (image px), its distance from the nadir along the normal (px), the ground edge grid
    ``gs`` (px along the normal from the mapped edge) with the misfit ``chi`` of each (σ² per
    px above the best), the footprint number, the map end points of the edge and the roof edge
    of the best fit (px along the normal)."""

    mid: Array
    normal: Array
    r: float
    gs: Array
    chi: Array
    footprint: int
    map_edge: Array
    roof: float = 0.0

    def at(self, g: float) -> float:
        """The misfit of a ground edge at ``g`` (linear between the grid's; capped)."""
        v = np.interp(g, self.gs, np.minimum(self.chi, CHI_CAP), left=CHI_CAP, right=CHI_CAP)
        return float(v)

    @property
    def informative(self) -> bool:
        """Whether the profile pins the ground edge down at all (its misfit rises)."""
        return bool(np.max(np.minimum(self.chi, CHI_CAP)) >= MIN_CHI_RANGE)


@dataclass
class ReliefCorrection:
    """The outcome of :func:`correct_relief`.

    ``transform``: the corrected image → map transform (3 × 3; the input one when not
    ``applied``); ``correction``: C with ``transform = T @ C`` (image → image); ``image_xy`` /
    ``map_xy``: control points on the ground edges used (image px ↔ map, the map point is the
    foot on the footprint edge); ``relief_px_corner``: the estimated displacement of a roof of
    mean height at the farthest image corner (px) and the half-width of its interval;
    ``edges`` that agree (the control points),
    ``edges_measured`` (profiles that pin the ground edge down), ``edges_tried``,
    ``buildings`` (footprints with a used edge); ``gain``: how much better the estimate
    explains the profiles than no relief (summed misfit, σ² per px); ``offset_px``: the common
    offset δ of the ground edges; ``scale``: the relief's scale about the nadir (part of
    ``correction``, which also holds the roof refit of the start); ``reason`` says why nothing
    changed (empty when ``applied``)."""

    transform: Array
    correction: Array
    applied: bool
    reason: str
    relief_px_corner: float = float("nan")
    relief_se_px: float = float("nan")
    gain: float = float("nan")
    offset_px: float = float("nan")
    scale: float = 1.0
    edges: int = 0
    edges_measured: int = 0
    edges_tried: int = 0
    buildings: int = 0
    image_xy: Array = field(default_factory=lambda: np.zeros((0, 2)))
    map_xy: Array = field(default_factory=lambda: np.zeros((0, 2)))

    def counts(self) -> Dict[str, Any]:
        """The figures for a report's counts (numbers only: they also go into messages)."""
        return {"relief_px_corner": _round(self.relief_px_corner),
                "relief_edges": self.edges, "relief_applied": self.applied}


def _round(x: float) -> Optional[float]:
    return None if not np.isfinite(x) else round(float(x), 3)


# -- edges facing the nadir -------------------------------------------------------------------
def ring_edges(ring_img: Array, min_len: float = MIN_EDGE_PX) -> List[Tuple[int, Array, Array]]:
    """Edges of an image-coordinate ring: (index of the first vertex, midpoint, unit outward
    normal) per edge at least ``min_len`` px long. Works for either orientation of the ring
    (mirrored maps); a closing vertex equal to the first is dropped."""
    ring = unclosed_ring(ring_img)
    if len(ring) < 3:
        return []
    nxt = np.roll(ring, -1, axis=0)
    x, y = ring[:, 0], ring[:, 1]
    area2 = float(np.sum(x * nxt[:, 1] - nxt[:, 0] * y))
    out = []
    for k, (a, b) in enumerate(zip(ring, nxt)):
        d = b - a
        length = float(np.hypot(*d))
        if length < min_len:
            continue
        # outward normal: right of the direction for a counter-clockwise ring (x right, y up)
        n = np.array([d[1], -d[0]]) / length * (1.0 if area2 > 0 else -1.0)
        out.append((k, 0.5 * (a + b), n))
    return out


def _footprint_in_image(Tinv: Array, ring: Array) -> Array:
    """A footprint ring (map x, y; further columns ignored) in image coordinates, unclosed."""
    return apply(Tinv, unclosed_ring(np.asarray(ring, float)[:, :2]))


def facing_edges(ring_img: Array, centre: Array, min_len: float = MIN_EDGE_PX
                 ) -> List[Tuple[int, Array, Array]]:
    """The edges of :func:`ring_edges` whose outward normal points towards ``centre``."""
    return [(k, mid, n) for k, mid, n in ring_edges(ring_img, min_len)
            if float(np.dot(centre - mid, n)) > 0]


def edge_profile(grey: Array, a: Array, b: Array, normal: Array, ts: Array,
                 margin: float = END_MARGIN_PX) -> Optional[Array]:
    """The median grey profile across the edge a → b (image px) at offsets ``ts`` along
    ``normal``; None when too little of the edge lies inside the image."""
    d = b - a
    length = float(np.hypot(*d))
    s = np.arange(margin, length - margin + 1e-9, 1.0)
    if len(s) < 3:
        return None
    u = d / length
    pts = a + s[:, None] * u  # (ns, 2)
    xy = pts[:, None, :] + ts[None, :, None] * normal  # (ns, nt, 2)
    h, w = grey.shape
    inside = (xy[..., 0] >= 0) & (xy[..., 0] <= w - 1) & (xy[..., 1] >= 0) \
        & (xy[..., 1] <= h - 1)
    rows = inside.all(axis=1)
    if rows.sum() < 3:
        return None
    xy = xy[rows]
    vals = ndimage.map_coordinates(grey, [xy[..., 1].ravel(), xy[..., 0].ravel()], order=1,
                                   mode="nearest").reshape(xy.shape[:2])
    return np.median(vals, axis=0)


# -- the step model ---------------------------------------------------------------------------
def _steps(t: Array, x: Array) -> Array:
    """Blurred unit steps (0 → 1 as t passes x): (len(x), len(t))."""
    return 0.5 * (1.0 + erf((t[None, :] - x[:, None]) / (STEP_SIGMA * np.sqrt(2.0))))


def _fit_grid(P: Array, ts: Array, E: Array, G: Array, F: Array) -> Array:
    """Residual sum of squares of the levels' least squares for every step triple (E[k],
    G[k], F[k]) (positions in px; F = inf: no third step). The ground beyond g may slope
    (lawns, lit and shaded ground vary slowly): a ramp starting at g is one more unknown."""
    xs, inv = np.unique(np.concatenate([E, G, F]), return_inverse=True)
    x = np.where(np.isfinite(xs), xs, 1e9)
    step = _steps(ts, x)
    B = np.vstack([np.ones(len(ts)), step, (ts[None, :] - x[:, None]) * step])
    gram = B @ B.T
    proj = B @ P
    ie, ig, jf = inv.reshape(3, -1)
    m = len(xs)
    idx = np.column_stack([np.zeros(len(E), int), 1 + ie, 1 + ig, 1 + jf, 1 + m + ig])
    N = gram[idx[:, :, None], idx[:, None, :]] + 1e-9 * np.eye(5)
    rhs = proj[idx]
    coef = np.linalg.solve(N, rhs[..., None])[..., 0]
    return float(P @ P) - np.einsum("ki,ki->k", rhs, coef)


def profile_offsets(max_strip: float) -> Array:
    """The profile samples of an edge (px, 0.1 px steps; t > 0 towards the nadir): 2 px of
    roof inside the innermost roof edge, 3.5 px of ground beyond the outermost ground edge."""
    return np.arange(-max_strip - 2.5, 2 * max_strip + 3.5 + 1e-9, 0.1)


def _step_sizes(P: Array, ts: Array, lo: float, hi: float, half: float = 1.5
                ) -> Tuple[Array, Array]:
    """Positions in [lo, hi] (between samples) and sizes of the profile's steps there: the
    absolute difference of the means ``half`` px on either side."""
    c = np.concatenate([[0.0], np.cumsum(P)])
    n = round(half / float(ts[1] - ts[0]))
    k = np.arange(n, len(P) - n + 1)  # step between samples k − 1 and k
    jump = ((c[k + n] - c[k]) - (c[k] - c[k - n])) / n
    pos = ts[k] - 0.5 * float(ts[1] - ts[0])
    ok = (pos >= lo) & (pos <= hi)
    return pos[ok], np.abs(jump[ok])


def _main_step(P: Array, ts: Array, lo: float, hi: float, half: float = 1.5
               ) -> Tuple[float, float]:
    """Position and size of the largest step of the profile in [lo, hi]: the difference of
    the means ``half`` px on either side (NaN, 0 when the range is empty)."""
    pos, size = _step_sizes(P, ts, lo, hi, half)
    if not len(pos):
        return float("nan"), 0.0
    j = int(np.argmax(size))
    return float(pos[j]), float(size[j])


def _unique_step(P: Array, ts: Array, lo: float, hi: float) -> Tuple[float, float]:
    """The largest step in [lo, hi] when no other step (a local maximum of the step size at
    least 1 px away) reaches :data:`ROOF_STEP_UNIQUE` of it; else (NaN, 0): the roof edge is
    not told from a shadow end, wall base or roof structure."""
    pos, size = _step_sizes(P, ts, lo, hi)
    if not len(pos):
        return float("nan"), 0.0
    j = int(np.argmax(size))
    left = np.concatenate([[-np.inf], size[:-1]])
    right = np.concatenate([size[1:], [-np.inf]])
    other = (size >= left) & (size >= right) & (np.abs(pos - pos[j]) >= 1.0)
    if other.any() and size[other].max() >= ROOF_STEP_UNIQUE * size[j]:
        return float("nan"), 0.0
    return float(pos[j]), float(size[j])


def edge_curve(profile: Array, ts: Array, max_strip: float = MAX_STRIP_PX
               ) -> Optional[Tuple[Array, Array, float]]:
    """How well each ground edge position g explains the profile: roof | wall | ground |
    (anything beyond) as levels with blurred steps at e ≤ g < f, the ground sloping.

    The roof edge is the profile's largest step within ± (``max_strip``/2 + 0.5) px of the
    mapped footprint edge (t = 0; the roof fit centres the roofs, relief scatters them by their
    height's difference from the mean), e within ± 0.4 px of it; the profile is used from 1.5 px
    inside it (roof structure further in does not count). g runs from ``G_MIN`` to
    ``max_strip`` (g = e: no wall seen); the ground segment is at least 1 px (f may lie beyond
    the profile: nothing there). Returns the g grid (px), the rise of the best residual sum of
    squares at each g over the best in units of σ² per px (σ²: the best fit's mean square;
    ``inf`` where g is impossible), and e of the best fit; None for a profile without a step.
    """
    P = np.asarray(profile, float)
    e0, jump = _main_step(P, ts, -0.5 * max_strip - 0.5, 0.5 * max_strip + 0.5)
    if not np.isfinite(e0):
        return None
    keep = ts >= e0 - 1.5
    P, ts = P[keep], ts[keep]
    per_px = 1.0 / float(ts[1] - ts[0])  # samples per px: neighbours are not independent
    es = e0 + np.arange(-0.4, 0.4 + 1e-9, 0.2)
    gs = np.arange(G_MIN, max_strip + 1e-9, GRID_STEP)
    fs = np.concatenate([np.arange(e0 + 1.0, ts[-1] - 0.5, 0.25), [np.inf]])
    E, G, F = (x.ravel() for x in np.meshgrid(es, gs, fs, indexing="ij"))
    ok = (F >= G + 1.0) & (G >= E - 1e-9)
    if not ok.any():
        return None
    E, G, F = E[ok], G[ok], F[ok]
    sse = _fit_grid(P, ts, E, G, F)
    # σ²: the best fit's mean square, at least that of the model's own resolution (a step
    # placed 0.1 px off leaves about 1 % of its size)
    sigma2 = max(float(sse.min()) / len(P), (MODEL_PRECISION * jump) ** 2, 1e-12)
    # a wall is two more unknowns (its level and width): it must pay for them, else every
    # profile prefers some wall (the model without one is a special case of it). A wall of
    # 1 px or more is also explained by no wall and a step beyond: the penalty makes "no
    # wall" the edge's own preference, and the edges together (the scatter of the roof edges
    # against the alignment of the ground edges) decide
    sse = sse + (G - E >= MIN_STRIP_PX - 1e-6) * WALL_PENALTY * per_px * sigma2
    gi = np.round((G - G_MIN) / GRID_STEP).astype(int)
    by_g = np.full(len(gs), np.inf)
    np.minimum.at(by_g, gi, sse)
    return gs, (by_g - float(sse.min())) / (per_px * sigma2), float(E[int(np.argmin(sse))])


# -- the start refitted to the roof edges -----------------------------------------------------
def roof_edges(grey: Array, T: Array, footprints: Sequence[Array],
               search: float = ROOF_SEARCH_PX[0]) -> Tuple[Array, Array, Array]:
    """The roof edge of every footprint edge (all orientations) against the edge mapped by the
    inverse of ``T``: the profile's largest step within ± ``search`` px, where it is the only
    large one (:func:`_unique_step`).

    Returns the mapped midpoints (n, 2), the unit normals (n, 2; outwards) and the roof edge's
    offset along the normal (n; px)."""
    Tinv = np.linalg.inv(T)
    ts = np.arange(-search - 2.0, search + 2.0 + 1e-9, 0.1)
    mids, normals, offs = [], [], []
    for ring in footprints:
        img = _footprint_in_image(Tinv, ring)
        for k, mid, n in ring_edges(img):
            prof = edge_profile(grey, img[k], img[(k + 1) % len(img)], n, ts)
            if prof is None:
                continue
            pos, jump = _unique_step(prof, ts, -search, search)
            if np.isfinite(pos) and jump > 0:
                mids.append(mid)
                normals.append(n)
                offs.append(pos)
    return (np.array(mids).reshape(-1, 2), np.array(normals).reshape(-1, 2),
            np.array(offs, float))


def roof_refit(mids: Array, normals: Array, offs: Array, centre: Array,
               iterations: int = 8) -> Optional[Array]:
    """The affine image → image correction C that moves the mapped footprint edges onto the
    roof edges seen (point to line: n·(C(m) − m) = offset), Tukey-reweighted (the roofs
    scatter by their height's difference from the mean, and some steps are not the roof edge);
    None with fewer than :data:`MIN_ROOF_EDGES` edges.

    This is what a perfect roof matcher gives (the roof-fitted transform of
    :func:`correct_relief`): a matched start is off it by a shift, rotation and shear (and a
    little scale) that no relief model explains."""
    if len(offs) < MIN_ROOF_EDGES:
        return None
    q = mids - centre
    A = np.column_stack([normals[:, 0] * q[:, 0], normals[:, 0] * q[:, 1],
                         normals[:, 1] * q[:, 0], normals[:, 1] * q[:, 1],
                         normals[:, 0], normals[:, 1]])
    w = np.ones(len(offs))
    for _ in range(iterations):
        sw = np.sqrt(w)
        x = np.linalg.lstsq(A * sw[:, None], offs * sw, rcond=None)[0]
        res = offs - A @ x
        sigma = max(1.4826 * float(np.median(np.abs(res))), 0.05)
        u = res / (ROOF_TUKEY * sigma)
        w = np.where(np.abs(u) < 1.0, (1.0 - u * u) ** 2, 0.0)
        if w.sum() < MIN_ROOF_EDGES:
            return None
    C = np.eye(3)
    C[:2, :2] += x[:4].reshape(2, 2)
    C[:2, 2] = x[4:] - x[:4].reshape(2, 2) @ centre
    return C


# -- the correction ---------------------------------------------------------------------------
def measure_edges(grey: Array, T: Array, footprints: Sequence[Array], centre: Array,
                  max_relief_px: float = MAX_RELIEF_PX) -> Tuple[List[EdgeMeasurement], int]:
    """Profile every footprint edge facing ``centre``; returns the profiled ones and the
    number tried. The wall strip of an edge is at most its distance from ``centre`` (along the
    normal) × ``max_relief_px`` / the corner distance, plus 0.5 px."""
    Tinv = np.linalg.inv(T)
    rmax = _corner_distance(centre, grey.shape)
    out: List[EdgeMeasurement] = []
    tried = 0
    for f, ring in enumerate(footprints):
        img = _footprint_in_image(Tinv, ring)
        for k, mid, n in facing_edges(img, centre):
            tried += 1
            r = abs(float(np.dot(mid - centre, n)))
            strip = max_relief_px * r / rmax + 0.5
            ts = profile_offsets(strip)
            prof = edge_profile(grey, img[k], img[(k + 1) % len(img)], n, ts)
            curve = None if prof is None else edge_curve(prof, ts, strip)
            if curve is None:
                continue
            out.append(EdgeMeasurement(mid, n, r, curve[0], curve[1], f,
                                       np.array([ring[k], ring[(k + 1) % len(ring)]]),
                                       curve[2]))
    return out, tried


def _corner_distance(centre: Array, shape: Tuple[int, ...]) -> float:
    """Distance (px) from ``centre`` to the farthest image corner."""
    h, w = shape[:2]
    return float(np.hypot(*np.maximum(centre + 0.5, np.array([w, h]) - 0.5 - centre)))


def search_relief(meas: Sequence[EdgeMeasurement], rmax: float, max_relief_px: float,
                  max_offset_px: float = MAX_OFFSET_PX) -> Tuple[Array, Array, Array]:
    """The summed misfit of all edges for relief ρ (px at the image corner) on a grid from
    −1 px to ``max_relief_px``: every edge's ground edge at g = ρ·r/rmax + δ (r: its distance
    from the nadir along its normal; δ: an offset common to all edges — where the image shows
    a wall base against where the footprint puts it: the step model's sub-pixel bias —
    searched in ± ``max_offset_px``).
    Returns the ρ grid, the least sum over δ for each ρ and the δ that gives it."""
    span = float(max_offset_px)
    rho = np.arange(-1.0, max_relief_px + 1e-9, 0.05)
    delta = np.arange(-span, span + 1e-9, 0.05) if span > 0 else np.zeros(1)
    R, D = np.meshgrid(rho, delta, indexing="ij")
    total = np.zeros(R.shape)
    for m in meas:
        cap = np.minimum(m.chi, CHI_CAP)
        total += np.interp(R * m.r / rmax + D, m.gs, cap, left=CHI_CAP, right=CHI_CAP)
    k = np.argmin(total, axis=1)
    return rho, total[np.arange(len(rho)), k], delta[k]


def _refine_rho(rho: Array, total: Array) -> float:
    """The minimum of the summed misfit, refined by a parabola through its neighbours."""
    k = int(np.argmin(total))
    if 0 < k < len(rho) - 1:
        y0, y1, y2 = total[k - 1], total[k], total[k + 1]
        den = y0 - 2 * y1 + y2
        if den > 0:
            return float(rho[k] + 0.5 * (y0 - y2) / den * (rho[1] - rho[0]))
    return float(rho[k])


def _control_points(meas: Sequence[EdgeMeasurement], rho: float, delta: float, rmax: float,
                    T2: Array) -> Tuple[Array, Array, List[int]]:
    """Ground edges that agree with relief ρ: the misfit's minimum within 0.5 px of the
    predicted g (image point), its foot on the footprint edge under T2 (map point), and the
    footprints."""
    img, mp, fps = [], [], []
    for m in meas:
        g = rho * m.r / rmax + delta
        near = np.abs(m.gs - g) <= 0.5
        if not m.informative or m.at(g) > 1.0 or not near.any():
            continue
        gm = float(m.gs[near][int(np.argmin(m.chi[near]))])
        x = m.mid + gm * m.normal
        q = apply(T2, x[None])[0]
        a, b = m.map_edge
        d = b - a
        s = float(np.clip(np.dot(q - a, d) / max(float(np.dot(d, d)), 1e-12), 0.0, 1.0))
        img.append(x)
        mp.append(a + s * d)
        fps.append(m.footprint)
    return np.array(img).reshape(-1, 2), np.array(mp).reshape(-1, 2), fps


def scale_about(centre: Array, factor: float) -> Array:
    """3 × 3 scale by ``factor`` about ``centre`` (image → image)."""
    C = np.eye(3)
    C[0, 0] = C[1, 1] = factor
    C[:2, 2] = (1.0 - factor) * np.asarray(centre, float)
    return C


def correct_relief(grey: Array, T: Array, footprints: Sequence[Array],
                   centre: Optional[Sequence[float]] = None,
                   max_relief_px: float = MAX_RELIEF_PX, min_edges: int = MIN_EDGES,
                   min_buildings: int = MIN_BUILDINGS, refit_start: bool = True
                   ) -> ReliefCorrection:
    """Correct a roof-fitted image → map transform for relief displacement.

    Parameters
    ----------
    grey : (rows, cols) array
        The image (any grey scale; level 0).
    T : (3, 3) array
        Image → map transform fitted to the roofs (pixel centres at integers).
    footprints : sequence of (n, 2) arrays
        The matched footprint rings (map coordinates), e.g. of the verified pairs.
    centre : (col, row), optional
        The nadir in the image (default: the image centre).
    max_relief_px : float
        The largest relief displacement considered at the farthest image corner (px).
    min_edges, min_buildings : int
        The evidence needed to change anything: ground edges that agree with the estimate, on
        this many footprints.
    refit_start : bool
        First refit T to the roof edges seen in the image (:func:`roof_start_refit`): a
        matched start is off the roof-fitted transform by a shift, rotation and shear that
        spread the ground edges and hide the relief. Kept only together with a relief
        correction; a refit within its own error (a start already on the roofs) is dropped
        (docs/decisions.md, parts T and U).

    Returns
    -------
    ReliefCorrection
        ``transform = T @ R @ scale_about(centre, 1 + ρ / rmax)`` when applied (R: the roof
        refit, the identity without it; ρ: the relief at the corner, rmax: the corner's
        distance from the nadir), else T and the reason.
    """
    grey = np.asarray(grey, dtype=np.float64)
    T = np.asarray(T, float)
    h, w = grey.shape
    c = np.array([(w - 1) / 2.0, (h - 1) / 2.0]) if centre is None else \
        np.asarray(centre, float)
    R = roof_start_refit(grey, T, footprints, c) if refit_start else np.eye(3)
    T0, T = T, T @ R
    meas, tried = measure_edges(grey, T, footprints, c, max_relief_px)
    rmax = _corner_distance(c, grey.shape)
    info = [m for m in meas if m.informative]
    base: Dict[str, Any] = {"transform": T0, "correction": np.eye(3), "applied": False,
                            "edges_measured": len(info), "edges_tried": tried}
    if len(info) < min_edges:
        return ReliefCorrection(**base, reason=(
            f"too few ground edges: {len(info)} profiled (at least {min_edges} needed)"))
    roof_share = float(np.mean([abs(m.roof) < 0.5 for m in info]))
    if roof_share < MIN_ROOF_SHARE:
        return ReliefCorrection(**base, reason=(
            f"the roofs do not sit on the mapped footprints ({100 * roof_share:.0f} % of the "
            f"edges within 0.5 px, at least {100 * MIN_ROOF_SHARE:.0f} % needed): the start "
            "transform or the footprints do not fit"))
    # whether: δ free (:data:`FREE_OFFSET_PX`); how much: δ held near zero
    rho_grid, total, _ = search_relief(info, rmax, max_relief_px, FREE_OFFSET_PX)
    rho_free = _refine_rho(rho_grid, total)
    gain = float(np.interp(0.0, rho_grid, total) - total.min())
    rho_grid, total, deltas = search_relief(info, rmax, max_relief_px)
    rho = _refine_rho(rho_grid, total)
    delta = float(deltas[int(np.argmin(total))])
    C = scale_about(c, 1.0 + rho / rmax)
    img, mp, fps = _control_points(info, rho, delta, rmax, T @ C)
    se = _interval(rho_grid, total)
    out = dict(base, relief_px_corner=rho, relief_se_px=se, gain=gain, offset_px=delta,
               scale=float(C[0, 0]),
               edges=len(img),
               buildings=len(set(fps)), image_xy=img, map_xy=mp)
    why = ""
    if len(img) < min_edges or len(set(fps)) < min_buildings:
        why = (f"too few ground edges agree: {len(img)} on {len(set(fps))} footprint(s) (at "
               f"least {min_edges} on {min_buildings} needed)")
    elif rho >= max_relief_px - 0.1:
        why = f"implausible relief: the estimate reaches the limit ({max_relief_px:g} px)"
    elif min(rho, rho_free) <= 0 or gain < max(MIN_GAIN, MIN_GAIN_PER_EDGE * len(info)):
        why = (f"no significant relief: {rho_free:.2f} px at the corner with a free offset "
               f"(gain {gain:.1f} over none)")
    if why:
        return ReliefCorrection(**out, reason=why)
    out.update(transform=T @ C, correction=R @ C, applied=True)
    return ReliefCorrection(**out, reason="")


def roof_start_refit(grey: Array, T: Array, footprints: Sequence[Array], centre: Array
                     ) -> Array:
    """The roof refit of the start as an image → image correction R (``T @ R`` maps the roof
    edges seen onto the footprints), one pass per search distance of
    :data:`ROOF_SEARCH_PX`; a pass with too few roof edges changes nothing, and a refit that
    moves no image corner by :data:`REFIT_MIN_PX` apart from a scale about ``centre`` is
    dropped (the identity: a roof-fitted start stays as it is)."""
    R = np.eye(3)
    for search in ROOF_SEARCH_PX:
        C = roof_refit(*roof_edges(grey, T @ R, footprints, search), centre)
        if C is not None:
            R = R @ np.linalg.inv(C)
    if _off_scale_px(R, centre, grey.shape) < REFIT_MIN_PX:
        return np.eye(3)  # within the refit's own error
    return R


def _off_scale_px(C: Array, centre: Array, shape: Tuple[int, ...]) -> float:
    """The largest move (px) of an image corner under the image → image transform ``C`` once
    its isotropic scale about ``centre`` (least squares over the corners) is taken out."""
    h, w = shape[:2]
    p = np.array([[0.0, 0.0], [w - 1.0, 0.0], [0.0, h - 1.0], [w - 1.0, h - 1.0]])
    d, v = apply(C, p) - p, p - centre
    s = float(np.sum(d * v) / np.sum(v * v))
    return float(np.max(np.hypot(*(d - s * v).T)))


def _interval(rho: Array, total: Array) -> float:
    """Half the width of the interval of ρ whose summed misfit is within 1 of the least."""
    ok = rho[total <= total.min() + 1.0]
    return 0.5 * float(ok.max() - ok.min()) + 0.025
