r"""Finite-element gridding of scattered points (HIFI-like): bilinear elements, thin-plate
regularisation, breaklines, exclusion areas, tiles and robust IRLS (seed-000 §2.13).

Unknowns
    The heights :math:`z_{rc}` of the grid nodes, which are the cell centres of
    :class:`.gridding.Grid` (node (r, c) at ``x0 + (c+½)·s, y0 − (r+½)·s``). Between the nodes
    the surface is bilinear.

Observation equations (one per point *k*, weight :math:`w_k = 1/σ_k^2`, default 1)
    With the point's node coordinates :math:`u = (x − x_0)/s − ½`, :math:`v = (y_0 − y)/s − ½`,
    :math:`j = \lfloor u \rfloor`, :math:`i = \lfloor v \rfloor`, :math:`a = u − j`,
    :math:`b = v − i`:

    .. math:: (1-a)(1-b)\,z_{ij} + a(1-b)\,z_{i,j+1} + (1-a)b\,z_{i+1,j} + ab\,z_{i+1,j+1}
              = z_k + e_k .

    On the outer half cells of the grid ``i, j`` are clamped so that ``a, b`` leave [0, 1]:
    bilinear extrapolation, still exact for planes.

Curvature equations (thin-plate-like regularisation, weight λ)
    Second differences at every node and cell, :math:`0 = z_{r,c-1} − 2z_{rc} + z_{r,c+1}`
    (X), :math:`0 = z_{r-1,c} − 2z_{rc} + z_{r+1,c}` (Y) and, with weight 2λ,
    :math:`0 = z_{rc} − z_{r,c+1} − z_{r+1,c} + z_{r+1,c+1}` (XY): the discrete
    :math:`\iint z_{xx}^2 + 2z_{xy}^2 + z_{yy}^2\,dA` of a thin plate, so a plane costs nothing.

Smoothing (dimensionless, scale-invariant)
    :math:`λ = \text{smoothing}\cdot\tilde w` with :math:`\tilde w` the median point weight: one
    curvature equation (a second difference across one cell, in height units) counts
    ``smoothing`` times as much as a typical point with a residual of the same size. The result
    does not change when heights, coordinates and σ are scaled together (units, σ level) and is
    the same in every tile. With ρ points per cell the fit acts as a low-pass whose
    half-power wavelength is about :math:`2π\,s\,(\text{smoothing}/ρ)^{1/4}`: the surface
    follows details longer than that and smooths shorter ones (noise). Small values (0.01–0.1)
    interpolate, larger ones (1–10) filter noisy matching points.

    Per cell, the same ``smoothing`` smooths more on a coarser grid: the curvature equations
    approximate :math:`λ s^2 \iint z''^2 dA`, and with the points' density fixed ρ grows as
    :math:`s^2`, so the wavelength grows as :math:`\sqrt{s}`. With ``reference_spacing``
    :math:`s_0` the smoothing refers to cells of that size, :math:`λ = \text{smoothing}
    \cdot\tilde w\cdot(s_0/s)^2` (the same continuum energy, as the cascade's λ/4 per
    coarsening), and the surface does not depend on the output spacing.

Breaklines
    A curvature equation is dropped when its stencil (the grid edges between its nodes,
    closed at the nodes) is crossed or touched by a breakline segment: the slope, and even the
    height, may jump there. 3-D breaklines are densified every ½ cell; their vertices are
    observations with weight ``breakline_weight``·w̃ (their own heights hold the edge).

Exclusion areas, boundaries, gaps
    Cells in exclusion areas or outside the boundary polygons get no observations and are NaN.
    Their nodes next to the domain stay free unknowns (they only extend the bilinear stencils),
    so the surface is not coupled across an exclusion area. Gaps (4-connected cells without
    data): no node farther than ``max_gap/2`` from data gets a height (per node, unlike the
    per-gap rule of :func:`.gridding.fill_gaps`, because scattered points leave one connected
    empty region around all of them). Connected parts of the domain without any
    observation stay NaN.

Solution per tile
    The normal equations :math:`(A^T W A + λ\,D^T Λ D + ε\tilde w I)\,z = A^T W z_{obs} +
    ε\tilde w\,z_0` (ε = 1e-10, :math:`z_0` the nearest measured height: only keeps
    data-less corners regular) are solved tile by tile: each tile of ``tile`` × ``tile`` nodes
    is extended by ``overlap`` nodes on every side and solved; the outer overlap/2 of each
    solution is dropped (the free tile edge bends the plate there) and neighbours are blended
    by linear ramps over the ``overlap`` nodes centred on the tile border (weights add up to
    one), so there is no seam. ``solver="cg"`` (default): conjugate gradients on the tile,
    preconditioned by a geometric multigrid V-cycle (:mod:`.fe_multigrid`: Galerkin coarse
    grids down to ≤ 64² nodes, Chebyshev smoothing), from the nearest measured heights (or the
    last solution in robust mode), to ‖r‖ ≤ 1e-9·‖b‖: a few tens of iterations, and the
    surface is within 0.01 mm of the direct solution (docs/decisions.md, part W).
    ``solver="cg_jacobi"`` (the former default): a cascade — the same problem on grids
    coarsened by 2 (λ/4 per level, the same continuum energy) down to ≤ 64² nodes solved
    directly, each level's solution bilinearly prolongated as the start of Jacobi-preconditioned
    conjugate gradients on the next finer one; at 1e-7 it stopped up to 0.5 m short of its own
    solution in large gaps, because the residual no longer sees the smooth error there.
    ``solver="direct"``: sparse LU (SuperLU, minimum-degree ordering) of the whole tile.
    Measured on 2000 × 2000 nodes (2 busy cores) with the cascade: 4 M points (1 per cell)
    13 s against 125 s direct (256-node tiles); 160 k points (1 per 25 cells) 62 s.

Robust IRLS (``robust=True``)
    After each solution the point residuals :math:`e_k = z_k − \hat z(x_k, y_k)` are normalised
    by :math:`\hat σ = 1.4826\,\mathrm{median}|e_k\sqrt{w_k/\tilde w}|` (per tile, taken from
    the plain and the Huber solution and then kept, not below ``robust_floor``) and the
    weights multiplied by Huber's :math:`\min(1, 1.5/|\bar e|)` in the first iteration, then by
    :math:`\exp(-\bar e^2/(2\cdot 2.5^2))` (redescending, so blunders and 3-D disturbances get
    almost no weight). ``robust_iterations`` re-solutions, each starting from the last.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Any, Dict, List, Optional, Sequence, Tuple

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import ndimage, sparse
from scipy.sparse.linalg import splu

from ..errors import InputError
from ..feedback import Feedback, ensure_feedback
from ..linalg import CG_FE, jacobi, pcg
from .fe_multigrid import VCycle
from .gridding import Grid, polygon_mask

Array = NDArray[Any]

_EPS = 1e-10  # ridge towards the nearest measured height (relative to the median weight)
_COARSEST = 64  # nodes per side below which the cascade / the V-cycle solves directly
_SOLVERS = ("cg", "cg_jacobi", "direct")
_HUBER = 1.5
_WELSCH = 2.5


# -- breakline geometry --------------------------------------------------------------------
def _segments(lines: Sequence[Any]) -> Array:
    """(n, 6) array of breakline segments x1, y1, z1, x2, y2, z2 (z NaN for 2-D lines)."""
    segs: List[Array] = []
    for g in lines:
        if g is None or g.is_empty:
            continue
        for part in getattr(g, "geoms", [g]):
            c = np.asarray(part.coords, float)
            if c.ndim != 2 or len(c) < 2:
                continue
            if c.shape[1] < 3:
                c = np.c_[c[:, :2], np.full(len(c), np.nan)]
            segs.append(np.c_[c[:-1, :3], c[1:, :3]])
    return np.concatenate(segs) if segs else np.empty((0, 6))


def _crossings(seg_uv: Array, shape: Tuple[int, int]) -> Tuple[Array, Array, Array]:
    """Grid edges and cells touched by segments given in node coordinates (u, v).

    Returns ``hx`` (h, w−1): edge (r, c)–(r, c+1) touched; ``vx`` (h−1, w): edge
    (r, c)–(r+1, c) touched; ``cx`` (h−1, w−1): the cell between nodes (r..r+1, c..c+1) holds a
    segment end point. A segment through a node touches both edges that meet there.
    """
    h, w = shape
    hx = np.zeros((h, max(w - 1, 0)), bool)
    vx = np.zeros((max(h - 1, 0), w), bool)
    cx = np.zeros((max(h - 1, 0), max(w - 1, 0)), bool)
    if len(seg_uv) == 0:
        return hx, vx, cx
    u1, v1, u2, v2 = seg_uv.T

    def mark(a1: Array, b1: Array, a2: Array, b2: Array, out: Array) -> None:
        # crossings of the lines a = integer (a: the coordinate across the edges' direction)
        lo, hi = np.ceil(np.minimum(a1, a2)), np.floor(np.maximum(a1, a2))
        ok = (a1 != a2) & (hi >= lo)
        n = np.where(ok, hi - lo + 1, 0).astype(np.int64)
        if n.sum() == 0:
            return
        seg = np.repeat(np.arange(a1.size), n)
        a = lo[seg] + (np.arange(n.sum()) - np.repeat(np.cumsum(n) - n, n))
        t = (a - a1[seg]) / (a2[seg] - a1[seg])
        b = b1[seg] + t * (b2[seg] - b1[seg])
        ai = a.astype(np.int64)
        bi = np.floor(b).astype(np.int64)
        on_node = b == bi  # through a node: both edges that meet there
        for bb, use in ((bi, np.ones(bi.size, bool)), (bi - 1, on_node)):
            keep = use & (ai >= 0) & (ai < out.shape[0]) & (bb >= 0) & (bb < out.shape[1])
            out[ai[keep], bb[keep]] = True

    mark(v1, u1, v2, u2, hx)  # crossings of the rows v = r give horizontal edges
    mark(u1, v1, u2, v2, vx.T)  # crossings of the columns u = c give vertical edges
    for uu, vv in ((u1, v1), (u2, v2)):
        r, c = np.floor(vv).astype(np.int64), np.floor(uu).astype(np.int64)
        keep = (r >= 0) & (r < cx.shape[0]) & (c >= 0) & (c < cx.shape[1])
        cx[r[keep], c[keep]] = True
    return hx, vx, cx


def _densify(segs: Array, step: float) -> Tuple[Array, Array, Array]:
    """x, y, z of 3-D breakline segments sampled every ``step`` (end points included)."""
    segs = segs[np.isfinite(segs[:, 2]) & np.isfinite(segs[:, 5])]
    if len(segs) == 0:
        return np.empty(0), np.empty(0), np.empty(0)
    length = np.hypot(segs[:, 3] - segs[:, 0], segs[:, 4] - segs[:, 1])
    n = np.maximum(1, np.ceil(length / step)).astype(np.int64)
    seg = np.repeat(np.arange(len(segs)), n + 1)
    t = (np.arange(seg.size) - np.repeat(np.cumsum(n + 1) - (n + 1), n + 1)) / n[seg]
    p = segs[seg, :3] + t[:, None] * (segs[seg, 3:] - segs[seg, :3])
    return p[:, 0], p[:, 1], p[:, 2]


# -- one level of one tile -----------------------------------------------------------------
class _Level:
    """The FE system of one grid window (all its nodes; nodes that are not unknowns are
    decoupled and keep their ridge value).

    The normal matrix is a 2-D stencil: every equation couples nodes at most two apart, so it
    is assembled as the diagonals of the flattened node index (offsets 0, 1, 2, W−1, W, W+1,
    2W), each accumulated by vectorised slicing / bincount, and converted to CSR once.
    """

    def __init__(self, shape: Tuple[int, int], u: Array, v: Array, z: Array, w: Array,
                 unknown: Array, crossings: Tuple[Array, Array, Array], lam: float,
                 wref: float, prior: Array) -> None:
        h, wd = shape
        self.shape = shape
        self.n = h * wd
        self.nodes = np.flatnonzero(unknown)
        # observation stencils (clamped base node: bilinear extrapolation at the border)
        j = np.clip(np.floor(u), 0, max(wd - 2, 0)).astype(np.int64)
        i = np.clip(np.floor(v), 0, max(h - 2, 0)).astype(np.int64)
        a = u - j if wd > 1 else np.zeros_like(u)
        b = v - i if h > 1 else np.zeros_like(v)
        j1, i1 = np.minimum(j + 1, wd - 1), np.minimum(i + 1, h - 1)
        cols = np.stack([i * wd + j, i * wd + j1, i1 * wd + j, i1 * wd + j1], 1)
        vals = np.stack([(1 - a) * (1 - b), a * (1 - b), (1 - a) * b, a * b], 1)
        self.used = unknown.ravel()[cols].all(1)
        self.cols, self.vals = cols[self.used], vals[self.used]
        self.z = z[self.used]
        # curvature equations whose nodes are all unknown and whose edges no breakline touches
        hx, vx, cx = crossings
        un = unknown
        diag: Dict[int, Array] = {}

        def acc(off: int, sl: Tuple[slice, slice], val: Array) -> None:
            # M[p, p+off] += val at the nodes p of the window slice sl
            d = diag.setdefault(off, np.zeros((h, wd)))
            d[sl] += val

        if wd >= 3:  # z[r,c−1] − 2 z[r,c] + z[r,c+1], centred at column c = 1..W−2
            q = lam * (un[:, :-2] & un[:, 1:-1] & un[:, 2:] & ~hx[:, :-1] & ~hx[:, 1:])
            left, mid, right = (slice(None), slice(0, -2)), (slice(None), slice(1, -1)), \
                (slice(None), slice(2, None))
            acc(0, left, q)
            acc(0, mid, 4 * q)
            acc(0, right, q)
            acc(1, left, -2 * q)
            acc(1, mid, -2 * q)
            acc(2, left, q)
        if h >= 3:  # the same along the columns
            q = lam * (un[:-2] & un[1:-1] & un[2:] & ~vx[:-1] & ~vx[1:])
            top, mid, bottom = (slice(0, -2), slice(None)), (slice(1, -1), slice(None)), \
                (slice(2, None), slice(None))
            acc(0, top, q)
            acc(0, mid, 4 * q)
            acc(0, bottom, q)
            acc(wd, top, -2 * q)
            acc(wd, mid, -2 * q)
            acc(2 * wd, top, q)
        if h >= 2 and wd >= 2:  # z[r,c] − z[r,c+1] − z[r+1,c] + z[r+1,c+1], weight 2λ
            q = 2 * lam * (un[:-1, :-1] & un[:-1, 1:] & un[1:, :-1] & un[1:, 1:] & ~cx
                           & ~hx[:-1] & ~hx[1:] & ~vx[:, :-1] & ~vx[:, 1:])
            p00, p01 = (slice(0, -1), slice(0, -1)), (slice(0, -1), slice(1, None))
            p10, p11 = (slice(1, None), slice(0, -1)), (slice(1, None), slice(1, None))
            for sl in (p00, p01, p10, p11):
                acc(0, sl, q)
            acc(1, p00, -q)  # (00, 01)
            acc(1, p10, -q)  # (10, 11)
            acc(wd, p00, -q)  # (00, 10)
            acc(wd, p01, -q)  # (01, 11)
            acc(wd + 1, p00, q)  # (00, 11)
            acc(wd - 1, p01, q)  # (01, 10)
        self.ridge = _EPS * wref
        self.R = {k: d.ravel() for k, d in diag.items()}
        self.R.setdefault(0, np.zeros(self.n))
        self.R[0] = self.R[0] + self.ridge
        self.prior = prior.ravel().astype(float)
        # (offset, first, second) of the 10 products of a bilinear stencil's coefficients
        self._pairs = [(0, 0, 0), (0, 1, 1), (0, 2, 2), (0, 3, 3), (1, 0, 1), (1, 2, 3),
                       (wd, 0, 2), (wd, 1, 3), (wd + 1, 0, 3), (wd - 1, 1, 2)]

    def normal(self, w: Array) -> Tuple[Any, Array]:
        """Normal matrix (CSR) and right-hand side for the weights ``w`` of the used points."""
        n = self.n
        diags = {k: d.copy() for k, d in self.R.items()}
        for off, ka, kb in self._pairs:
            add = np.bincount(self.cols[:, ka], weights=w * self.vals[:, ka] * self.vals[:, kb],
                              minlength=n)
            if off in diags:
                diags[off] += add
            else:
                diags[off] = add
        offs = [k for k in diags if 0 < k < n]
        data = [diags[0]] + [diags[k][:n - k] for k in offs] + [diags[k][:n - k] for k in offs]
        N = sparse.diags(data, [0] + offs + [-k for k in offs], shape=(n, n), format="csr")
        rhs = np.bincount(self.cols.ravel(), weights=(self.vals * (w * self.z)[:, None]).ravel(),
                          minlength=n)
        return N, rhs + self.ridge * self.prior

    def apply(self, x: Array) -> Array:
        """Bilinear values of the node heights ``x`` (all window nodes) at the used points."""
        return np.einsum("ij,ij->i", self.vals, x[self.cols])


def _block_any(mask: Array) -> Array:
    h, w = mask.shape
    m = np.pad(mask, ((0, h % 2), (0, w % 2)))
    return m[0::2, 0::2] | m[1::2, 0::2] | m[0::2, 1::2] | m[1::2, 1::2]


def _block_mean(a: Array) -> Array:
    h, w = a.shape
    m = np.pad(a, ((0, h % 2), (0, w % 2)), mode="edge")
    return 0.25 * (m[0::2, 0::2] + m[1::2, 0::2] + m[0::2, 1::2] + m[1::2, 1::2])


def _prolong(coarse: Array, shape: Tuple[int, int]) -> Array:
    """Bilinear interpolation of a coarse node grid (factor 2) at the fine nodes."""
    h, w = shape
    rr = (np.arange(h) + 0.5) / 2.0 - 0.5
    cc = (np.arange(w) + 0.5) / 2.0 - 0.5
    R, C = np.meshgrid(rr, cc, indexing="ij")
    return ndimage.map_coordinates(coarse, [R, C], order=1, mode="nearest")


class _TileProblem:
    """All levels of the cascade of one tile (level 0 = the tile itself)."""

    def __init__(self, shape: Tuple[int, int], u: Array, v: Array, z: Array, w: Array,
                 unknown: Array, seg_uv: Array, lam: float, wref: float, prior: Array,
                 cascade: bool) -> None:
        self.levels: List[_Level] = []
        k = 0
        while True:
            f = 2.0 ** k
            # node coordinates on level k: u_k = (u + ½)/2^k − ½
            uk, vk = (u + 0.5) / f - 0.5, (v + 0.5) / f - 0.5
            seg = (seg_uv + 0.5) / f - 0.5 if len(seg_uv) else seg_uv
            self.levels.append(_Level(shape, uk, vk, z, w, unknown,
                                      _crossings(seg, shape), lam / 4.0 ** k, wref, prior))
            if not cascade or max(shape) <= _COARSEST:
                break
            shape = ((shape[0] + 1) // 2, (shape[1] + 1) // 2)
            unknown, prior = _block_any(unknown), _block_mean(prior)
            k += 1

    def solve(self, w: Array, x0: Optional[Array], solver: str, tol: float, maxiter: int,
              feedback: Feedback) -> Tuple[Array, int]:
        """Node heights of level 0 (NaN where not unknown), CG iterations used."""
        its = 0
        if solver == "direct":
            lv = self.levels[0]
            N, b = lv.normal(w[lv.used])
            x = splu(N.tocsc(), permc_spec="MMD_AT_PLUS_A").solve(b)
            return self._grid(lv, x), 0
        if solver == "cg":
            return self._solve_multigrid(w, x0, tol, maxiter, feedback)
        if x0 is not None:  # a warm start (robust iterations): only the finest level
            lv = self.levels[0]
            N, b = lv.normal(w[lv.used])
            x, its = pcg(N, b, jacobi(N), _nan_nearest(x0).ravel().astype(float), tol=tol,
                          max_iter=maxiter, rule=CG_FE, feedback=feedback)
            return self._grid(lv, x), its
        grid = None
        for lv in reversed(self.levels):
            N, b = lv.normal(w[lv.used])
            if grid is None:
                x = splu(N.tocsc(), permc_spec="MMD_AT_PLUS_A").solve(b)
            else:
                start = _prolong(_nan_nearest(grid), lv.shape).ravel().astype(float)
                x, k = pcg(N, b, jacobi(N), start, tol=tol, max_iter=maxiter, rule=CG_FE,
                           feedback=feedback)
                its += k
            grid = self._grid(lv, x)
        assert grid is not None
        return grid, its

    def _solve_multigrid(self, w: Array, x0: Optional[Array], tol: float, maxiter: int,
                         feedback: Feedback) -> Tuple[Array, int]:
        """CG on level 0 preconditioned by a V-cycle (:mod:`.fe_multigrid`).

        Starts from ``x0`` (a warm start) or the ridge targets; nodes that are not unknowns
        start at their ridge target, their exact solution, so their residual is zero.
        """
        lv = self.levels[0]
        N, b = lv.normal(w[lv.used])
        keep = np.zeros(lv.n, bool)
        keep[lv.nodes] = True
        x = lv.prior.copy()
        if x0 is not None:
            x[keep] = _nan_nearest(x0).ravel()[keep]
        x, its = pcg(N, b, VCycle(N, lv.shape, keep, _COARSEST), x, tol=tol,
                     max_iter=maxiter, rule=CG_FE, feedback=feedback)
        return self._grid(lv, x), its

    @staticmethod
    def _grid(lv: _Level, x: Array) -> Array:
        g = np.full(lv.shape, np.nan)
        g.flat[lv.nodes] = x[lv.nodes]
        return g

    def residuals(self, grid: Array) -> Array:
        lv = self.levels[0]
        return lv.z - lv.apply(_nan_nearest(grid).ravel())


def _nan_nearest(a: Array) -> Array:
    bad = ~np.isfinite(a)
    if not bad.any() or bad.all():
        return np.where(bad, 0.0, a)
    _, (r, c) = ndimage.distance_transform_edt(bad, return_indices=True)
    return a[r, c]


def _ramp(n: int, lo_edge: bool, hi_edge: bool, overlap: int) -> Array:
    """Blend weights along one axis of an extended tile.

    Zero on the outer overlap/2 (the tile's own free edge bends the plate there), then linear
    up to one over the next ``overlap`` nodes; the neighbour's ramp runs the other way over the
    same band, so the weights add up to one. No ramp at the grid's own border.
    """
    x = np.arange(n) + 0.5
    wgt = np.ones(n)
    if overlap > 0:
        if not lo_edge:
            wgt = np.minimum(wgt, (x - 0.5 * overlap) / overlap)
        if not hi_edge:
            wgt = np.minimum(wgt, (n - x - 0.5 * overlap) / overlap)
    return np.clip(wgt, 0.0, 1.0)


# -- public --------------------------------------------------------------------------------
def _spacing_factor(reference: Optional[float], spacing: float) -> float:
    """λ factor (reference / spacing)² that keeps the continuum curvature energy of a
    smoothing stated for cells of ``reference`` m on a grid of ``spacing`` m (1 without one)."""
    if reference is None:
        return 1.0
    if not (reference > 0 and math.isfinite(reference)):
        raise InputError(f"The reference spacing must be a positive number, got {reference}.")
    return (float(reference) / float(spacing)) ** 2


def fe_interpolate(x: ArrayLike, y: ArrayLike, z: ArrayLike, grid: Grid, *,
                   weights: Optional[ArrayLike] = None, smoothing: float = 0.1,
                   breaklines: Sequence[Any] = (), exclusions: Sequence[Any] = (),
                   boundaries: Sequence[Any] = (), max_gap: Optional[float] = None,
                   reference_spacing: Optional[float] = None, robust: bool = False,
                   robust_iterations: int = 5, robust_floor: float = 0.0,
                   breakline_weight: float = 100.0, tile: int = 512, overlap: int = 32,
                   solver: str = "cg", tol: float = 1e-9, maxiter: int = 3000,
                   feedback: Optional[Feedback] = None) -> Tuple[Array, Dict[str, Any]]:
    """Interpolate scattered points to a grid by finite elements (see the module notes).

    Parameters
    ----------
    x, y, z : array_like
        Points (m, grid CRS); non-finite ones are ignored.
    grid : Grid
        The output grid; its cell centres are the FE nodes.
    weights : array_like, optional
        Point weights :math:`1/σ^2` (any common scale; default 1).
    smoothing : float
        Dimensionless weight of a curvature equation relative to the median point weight
        (:math:`λ = \\text{smoothing}\\cdot\\tilde w`); see the module notes.
    breaklines : sequence of shapely (3-D) LineStrings
        Slope (and height) discontinuities; 3-D vertices are high-weight observations.
    exclusions, boundaries : sequences of shapely polygons
        Excluded areas (NaN, no observations); measuring area (NaN outside; none = all).
    max_gap : float, optional
        Largest gap (inscribed diameter, m) that gets heights; default every gap.
    reference_spacing : float, optional
        Cell size (m) that ``smoothing`` refers to: λ is scaled by (reference_spacing /
        spacing)² so that the surface does not depend on the grid spacing (module notes);
        default the grid's own spacing (λ per cell).
    robust : bool
        Iteratively reweighted solution that suppresses blunders (see the module notes).
    robust_iterations : int
        Re-solutions in robust mode.
    robust_floor : float
        Lower bound (m) of the residual scale σ̂ in robust mode: residuals below about
        2·robust_floor are never treated as blunders (use it when the points are nearly
        noise-free, so that σ̂ does not fall below the smoothing's own misfit).
    breakline_weight : float
        Weight of a densified breakline vertex relative to the median point weight.
    tile, overlap : int
        Tile side and overlap on each side (nodes); peak memory grows with (tile+2·overlap)².
    solver : {"cg", "cg_jacobi", "direct"}
        Multigrid-preconditioned CG, the former cascadic Jacobi-preconditioned CG, or sparse
        LU per tile.
    tol, maxiter : float, int
        CG stopping rule ‖r‖ ≤ tol·‖b‖ and iteration limit (per level with ``cg_jacobi``).
    feedback : Feedback, optional

    Returns
    -------
    z : ndarray (h, w) float32
        Heights at the cell centres, NaN where there is none.
    info : dict
        ``points`` (given), ``used`` (observations), ``breakline_vertices``, ``rms``,
        ``sigma_mad`` (1.4826·MAD), ``max_abs`` of the point residuals (m, robust mode: of the
        points kept, weight ≥ 0.5), ``downweighted`` (robust weight < 0.5), ``lambda``,
        ``smoothing``, ``tiles``, ``cg_iterations``, ``solver``, ``seconds``; ``count``
        (uint32 grid, points per cell), ``residuals`` (float32 per given point, NaN if unused),
        ``robust_weight`` (float32 per given point, NaN if unused; None unless robust).
    """
    t_start = time.perf_counter()
    feedback = ensure_feedback(feedback)
    if solver not in _SOLVERS:
        raise InputError(f"Unknown FE solver '{solver}'; use one of {', '.join(_SOLVERS)}.")
    if not (smoothing > 0 and math.isfinite(smoothing)):
        raise InputError(f"The smoothing must be a positive number, got {smoothing}.")
    x = np.ravel(np.asarray(x, float))
    y = np.ravel(np.asarray(y, float))
    z = np.ravel(np.asarray(z, float))
    w = (np.ones(z.size) if weights is None
         else np.ravel(np.broadcast_to(np.asarray(weights, float), z.shape)).copy())
    domain = ~polygon_mask(exclusions, grid)
    if len(boundaries):
        domain &= polygon_mask(boundaries, grid)
    obs = _observations(x, y, z, w, grid, domain, breaklines, breakline_weight)
    lam = float(smoothing) * obs.wref * _spacing_factor(reference_spacing, grid.spacing)
    active, unknown = _active_nodes(domain, obs, max_gap, grid.spacing)
    zref = float(np.median(obs.pz))
    opts = _SolveOptions(solver, tol, maxiter, robust, robust_iterations, robust_floor)
    mosaic = _Mosaic(obs, active, unknown, _prior(obs, zref, grid.shape), lam, zref,
                     max(8, int(tile)), max(0, int(overlap)), opts)
    its_total = 0
    for t in range(mosaic.n_tiles):
        feedback.progress(100.0 * t / mosaic.n_tiles)
        its_total += mosaic.add(t, feedback)
    feedback.progress(100.0)
    out = mosaic.surface()
    run = {"lambda": lam, "smoothing": float(smoothing), "tiles": mosaic.n_tiles,
           "cg_iterations": int(its_total), "solver": solver,
           "seconds": time.perf_counter() - t_start}
    return out.astype(np.float32), _summary(out, obs, z, mosaic, robust, run)


@dataclass
class _Observations:
    """The observations of the grid: the given points in the domain, then the densified
    vertices of 3-D breaklines (node coordinates ``pu, pv``, cells ``pr, pc``)."""

    pid: Array  # indices of the given points that are used
    n_bl: int  # breakline vertices, appended after the points
    pu: Array
    pv: Array
    pz: Array
    pw: Array
    pr: Array
    pc: Array
    seg_uv: Array  # breakline segments u1, v1, u2, v2 in node coordinates
    wref: float  # median weight of the used points
    count: Array  # points per cell


def _observations(x: Array, y: Array, z: Array, w: Array, grid: Grid, domain: Array,
                  breaklines: Sequence[Any], breakline_weight: float) -> _Observations:
    """Points in the domain and 3-D breakline vertices as observations (module notes)."""
    h, wd = grid.shape
    s = grid.spacing
    x0, y0 = grid.transform.c, grid.transform.f
    row, col = grid.cell_of(x, y)
    ok = (row >= 0) & np.isfinite(z) & np.isfinite(w) & (w > 0)
    ok[ok] = domain[row[ok], col[ok]]
    pid = np.flatnonzero(ok)
    if pid.size == 0:
        raise InputError("No point lies in the grid's measuring area (outside the boundary or "
                         "in exclusion areas); check the points, polygons and CRS.")
    wref = float(np.median(w[pid]))
    count = np.bincount(row[pid] * wd + col[pid], minlength=h * wd).reshape(h, wd)
    # breaklines: segments in node coordinates, 3-D vertices as observations
    segs = _segments(breaklines)
    seg_uv = np.empty((0, 4))
    ox = oy = oz = np.empty(0)
    if len(segs):
        seg_uv = np.c_[(segs[:, 0] - x0) / s - 0.5, (y0 - segs[:, 1]) / s - 0.5,
                       (segs[:, 3] - x0) / s - 0.5, (y0 - segs[:, 4]) / s - 0.5]
        bx, by, bz = _densify(segs, 0.5 * s)
        br, bc = grid.cell_of(bx, by)
        keep = br >= 0
        keep[keep] = domain[br[keep], bc[keep]]
        ox, oy, oz = bx[keep], by[keep], bz[keep]
    px = np.concatenate([x[pid], ox])
    py = np.concatenate([y[pid], oy])
    pz = np.concatenate([z[pid], oz])
    pw = np.concatenate([w[pid], np.full(ox.size, breakline_weight * wref)])
    pr, pc = grid.cell_of(px, py)
    return _Observations(pid, ox.size, (px - x0) / s - 0.5, (y0 - py) / s - 0.5, pz, pw, pr,
                         pc, seg_uv, wref, count)


def _active_nodes(domain: Array, obs: _Observations, max_gap: Optional[float],
                  spacing: float) -> Tuple[Array, Array]:
    """Nodes that get a height (``active``) and the unknowns (active nodes and their ring).

    A node is active in the domain unless it lies farther than ``max_gap``/2 from data, or
    in a connected part of the domain without data.
    """
    measured = np.zeros(domain.shape, bool)
    measured[obs.pr, obs.pc] = True
    active = domain.copy()
    hole = domain & ~measured
    if max_gap is not None and math.isfinite(max_gap) and hole.any():
        # per node, not per connected gap: scattered points leave one connected "gap"
        # around all of them, which the per-gap rule of gridding.fill_gaps would drop whole
        dist = ndimage.distance_transform_edt(~measured)
        active &= ~(2.0 * dist * spacing > max_gap + 1e-9)
    labels, n = ndimage.label(active)
    if n:
        has = np.concatenate([[False], np.asarray(ndimage.maximum(
            measured, labels, index=np.arange(1, n + 1))) > 0])
        active &= has[labels]
    return active, ndimage.binary_dilation(active, structure=np.ones((3, 3), bool))


def _prior(obs: _Observations, zref: float, shape: Tuple[int, int]) -> Array:
    """Ridge target of every node: the nearest measured cell's mean height − ``zref``."""
    h, wd = shape
    cell = obs.pr * wd + obs.pc
    cell_sum = np.bincount(cell, weights=obs.pz - zref, minlength=h * wd)
    cell_n = np.bincount(cell, minlength=h * wd)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = (cell_sum / cell_n).reshape(h, wd)
    return _nan_nearest(mean)


@dataclass(frozen=True)
class _SolveOptions:
    """Solver and robust-reweighting options of :func:`fe_interpolate`."""

    solver: str
    tol: float
    maxiter: int
    robust: bool
    robust_iterations: int
    robust_floor: float


class _Mosaic:
    """Tiles of ``tile`` × ``tile`` nodes, each solved with ``overlap`` nodes on every side
    and blended into the grid by linear ramps (module notes)."""

    def __init__(self, obs: _Observations, active: Array, unknown: Array, prior: Array,
                 lam: float, zref: float, tile: int, overlap: int, opts: _SolveOptions) -> None:
        self.obs, self.active, self.unknown, self.prior = obs, active, unknown, prior
        self.lam, self.zref, self.tile, self.overlap, self.opts = lam, zref, tile, overlap, opts
        h, wd = active.shape
        self.acc = np.zeros((h, wd))
        self.acc_w = np.zeros((h, wd))
        self.rw_all = np.full(obs.pz.size, np.nan)
        self.ty, self.tx = math.ceil(h / tile), math.ceil(wd / tile)
        self.n_tiles = self.ty * self.tx
        self.tj = np.clip(np.floor(obs.pu), 0, max(wd - 2, 0)).astype(np.int64)  # stencil base
        self.ti = np.clip(np.floor(obs.pv), 0, max(h - 2, 0)).astype(np.int64)

    def _window(self, t: int) -> Tuple[int, int, int, int, int, int]:
        """Core tile (row, col) and the extended window r0, r1, c0, c1 of tile ``t``."""
        h, wd = self.active.shape
        r_core, c_core = divmod(t, self.tx)
        r0 = max(0, r_core * self.tile - self.overlap)
        c0 = max(0, c_core * self.tile - self.overlap)
        r1 = min(h, (r_core + 1) * self.tile + self.overlap)
        c1 = min(wd, (c_core + 1) * self.tile + self.overlap)
        return r_core, c_core, r0, r1, c0, c1

    def add(self, t: int, feedback: Feedback) -> int:
        """Solve tile ``t`` and blend it into the grid; returns its CG iterations."""
        h, wd = self.active.shape
        r_core, c_core, r0, r1, c0, c1 = self._window(t)
        if not self.active[r0:r1, c0:c1].any():
            return 0
        tj, ti, obs = self.tj, self.ti, self.obs
        # points whose bilinear stencil lies inside the window
        sel = np.flatnonzero((tj >= c0) & (np.minimum(tj + 1, wd - 1) < c1) & (ti >= r0)
                             & (np.minimum(ti + 1, h - 1) < r1))
        if sel.size == 0:
            return 0
        seg = obs.seg_uv
        lseg = seg - np.array([c0, r0, c0, r0]) if len(seg) else seg
        prob = _TileProblem((r1 - r0, c1 - c0), obs.pu[sel] - c0, obs.pv[sel] - r0,
                            obs.pz[sel] - self.zref, obs.pw[sel], self.unknown[r0:r1, c0:c1],
                            lseg, self.lam, obs.wref, self.prior[r0:r1, c0:c1],
                            cascade=self.opts.solver == "cg_jacobi")
        sol, its, rw = self._solve(prob, sel, feedback)
        if self.opts.robust:
            # robust weights of the points whose base node lies in the tile's core
            g = sel[prob.levels[0].used]
            core = ((tj[g] >= c_core * self.tile) & (tj[g] < (c_core + 1) * self.tile)
                    & (ti[g] >= r_core * self.tile) & (ti[g] < (r_core + 1) * self.tile))
            self.rw_all[g[core]] = rw[core]
        ramp = np.outer(_ramp(r1 - r0, r0 == 0, r1 == h, self.overlap),
                        _ramp(c1 - c0, c0 == 0, c1 == wd, self.overlap))
        good = np.isfinite(sol)
        self.acc[r0:r1, c0:c1] += np.where(good, sol, 0.0) * ramp * good
        self.acc_w[r0:r1, c0:c1] += ramp * good
        return its

    def _solve(self, prob: _TileProblem, sel: Array, feedback: Feedback
               ) -> Tuple[Array, int, Array]:
        """Plain solution of a tile, then the robust re-solutions (module notes).

        Returns the node heights, the CG iterations and the robust weights of the tile's
        used observations (ones without ``robust``).
        """
        o, pw, wref = self.opts, self.obs.pw, self.obs.wref
        lv0 = prob.levels[0]
        is_pt = sel[lv0.used] < self.obs.pid.size  # robust weights act on points only
        wt = pw[sel].copy()
        sol, its = prob.solve(wt, None, o.solver, o.tol, o.maxiter, feedback)
        rw = np.ones(int(lv0.used.sum()))
        if not o.robust:
            return sol, its, rw
        wu = wt[lv0.used]
        sig = 0.0
        for it in range(max(1, int(o.robust_iterations))):
            en = np.abs(prob.residuals(sol)) * np.sqrt(wu / wref)
            if it <= 1:  # σ from the plain and the Huber solution, then kept: no collapse
                sig = 1.4826 * float(np.median(en[is_pt])) if is_pt.any() else 0.0
                sig = max(sig, float(o.robust_floor))
            if not sig > 0:
                break
            rw = _robust_weights(en / sig, it, is_pt)
            wt = pw[sel].copy()
            wt[lv0.used] = wu * rw
            sol, k = prob.solve(wt, sol if o.solver != "direct" else None, o.solver, o.tol,
                                o.maxiter, feedback)
            its += k
        return sol, its, rw

    def surface(self) -> Array:
        """The blended heights (float64), NaN where no node is active."""
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(self.active & (self.acc_w > 0), self.acc / self.acc_w + self.zref,
                            np.nan)


def _robust_weights(eb: Array, it: int, is_pt: Array) -> Array:
    """Huber weights (first re-solution), then Welsch's; breakline vertices keep 1."""
    rw = (np.minimum(1.0, _HUBER / np.maximum(eb, 1e-12)) if it == 0
          else np.exp(-0.5 * (eb / _WELSCH) ** 2))
    return np.where(is_pt, np.maximum(rw, 1e-6), 1.0)


def _summary(out: Array, obs: _Observations, z: Array, mosaic: _Mosaic, robust: bool,
             run: Dict[str, Any]) -> Dict[str, Any]:
    """The info dict of :func:`fe_interpolate`: point statistics (residuals against the
    blended grid, robust weights, counts) around the figures of the ``run``."""
    n_in, pid = z.size, obs.pid
    res = np.full(n_in, np.nan)
    res[pid] = z[pid] - _bilinear(out, obs.pu[:pid.size], obs.pv[:pid.size])
    rwp = np.full(n_in, np.nan)
    if robust:
        rwp[pid] = mosaic.rw_all[:pid.size]
    e = res[pid]
    fin = np.isfinite(e)
    kept = fin & ~(rwp[pid] < 0.5) if robust else fin
    nan = float("nan")
    return {
        "points": int(n_in), "used": int(pid.size), "breakline_vertices": int(obs.n_bl),
        "rms": float(np.sqrt(np.mean(e[kept] ** 2))) if kept.any() else nan,
        "sigma_mad": (float(1.4826 * np.median(np.abs(e[kept] - np.median(e[kept]))))
                      if kept.any() else nan),
        "max_abs": float(np.abs(e[kept]).max()) if kept.any() else nan,
        "downweighted": int(np.sum(rwp[pid] < 0.5)) if robust else 0,
        **run,
        "count": obs.count.astype(np.uint32), "residuals": res.astype(np.float32),
        "robust_weight": rwp.astype(np.float32) if robust else None,
    }


def _bilinear(g: Array, u: Array, v: Array) -> Array:
    """Bilinear (border: extrapolated) value of node grid ``g`` at node coordinates (NaN-aware)."""
    h, w = g.shape
    j = np.clip(np.floor(u), 0, max(w - 2, 0)).astype(np.int64)
    i = np.clip(np.floor(v), 0, max(h - 2, 0)).astype(np.int64)
    a = u - j if w > 1 else np.zeros_like(u)
    b = v - i if h > 1 else np.zeros_like(v)
    j1, i1 = np.minimum(j + 1, w - 1), np.minimum(i + 1, h - 1)
    return ((1 - a) * (1 - b) * g[i, j] + a * (1 - b) * g[i, j1] + (1 - a) * b * g[i1, j]
            + a * b * g[i1, j1])


__all__ = ["fe_interpolate"]
