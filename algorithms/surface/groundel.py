r"""Robust data reduction in object space: one representative point per *groundel*.

A groundel (Geländeelement, Gülch 1994 §5.4) is a square ground cell of side ``GE``. Matched
points are of three kinds — correct terrain points, 3-D disturbances (trees, houses) and false
matches — and the reduction keeps one robust value per cell that ignores small or isolated
disturbances (large ones are the operator's exclusion areas).

Cells
    Cell (row, col) of side :math:`s` with origin :math:`(x_0, y_0)` (the upper-left corner, as
    in :class:`.gridding.Grid`) covers :math:`[x_0 + c s,\ x_0 + (c+1) s) \times
    (y_0 - (r+1) s,\ y_0 - r s]`; its centre is :math:`(X_c, Y_c)`.

Robust surface per cell (``mode``)
    ``"l1"``
        The L1 tilted plane :math:`Z = c_0 + c_1 (X - X_c) + c_2 (Y - Y_c)` minimising
        :math:`\sum_k p_k |Z_k - c_0 - c_1 \Delta X_k - c_2 \Delta Y_k|` (breakdown like the
        median, Hahn 1985). Solved for all cells at once by iteratively reweighted least
        squares: each iteration solves the 3×3 normal equations of every cell with weights
        :math:`w_k = p_k / \max(|v_k|, \delta)` (:math:`\delta = 10^{-6} s`, the smoothing that
        keeps the weights finite), starting from the median and zero slope. The plane is used
        only when the cell has at least max(``plane_min_points``, 7) points spread over both
        axes and the slope is significant:

        .. math:: T = \frac{g^T S g}{(\pi/2)\, \sigma_{1,cell}^2} > \chi^2_{2;0.95} = 5.99,

        :math:`g = (c_1, c_2)`, :math:`S` the centred scatter matrix of the cell's
        :math:`(\Delta X, \Delta Y)` (the inverse of the slope block of :math:`(A^T A)^{-1}`),
        :math:`\pi/2` the variance ratio of the L1 to the least-squares estimate for Gaussian
        noise. Otherwise the cell falls back to the median (a flat cell).
    ``"median"``
        The (weighted) median of the heights.
    ``"lower"``
        The lower envelope: the ``lower_percentile`` percentile of the heights (vegetation
        over visible ground, seed-000 §2.11 (5)).

    With weights :math:`p_k` (e.g. :math:`1/\sigma_k^2`) medians and percentiles are weighted:
    the smallest :math:`Z` with :math:`\sum_{Z_i \le Z} p_i \ge q \sum p_i`; unweighted ones
    interpolate linearly between order statistics (numpy's default).

Per cell
    ``n``; the robust value at the cell centre ``z`` (:math:`c_0`, the median or the
    percentile); the representative point ``rep_*`` — the measured point with the smallest
    :math:`|v|`; residuals :math:`v_k = Z_k - \hat Z(X_k, Y_k)`;

    .. math:: \sigma_{1,cell} = 1.4826 \cdot \operatorname{med}_k |v_k - \operatorname{med}(v)|
              \cdot \sqrt{n / (n - 2u)}

    with :math:`u` = 3 for a plane, 1 for a median or percentile. The factor corrects the MAD
    of fitted residuals: simulations with Gaussian noise give
    :math:`E[\mathrm{MAD}\text{-}\sigma]^2 \approx \sigma^2 (1 - 2u/n)` for both the median
    and the L1 plane (n = 6…60; without it σ1 is 5 % low at 36 points per cell and 16 % at 12).
    A plane therefore needs :math:`n \ge 7`. A point is flagged
    as an outlier (blunder or 3-D disturbance) when :math:`|v_k| > \max(k\, \sigma_{1,cell},
    \text{floor})`. Cells with fewer than ``min_points`` points get no σ1 and no flags.

Overall (seed-000 §5.1)
    :math:`\sigma_1 = \operatorname{mean}\,\sigma_{1,cell}` (accuracy of the raw points) and
    :math:`\bar n` the mean number of points over the cells with at least ``min_points``
    points; :math:`\sigma_2 = F\,\sigma_1/\sqrt{\bar n}` the accuracy of the reduced points,
    :math:`F \approx 2` (empirical, seed Tab. 6.4: 1.55–2.20).

Memory and speed
    Points are grouped by one ``argsort`` of the cell key, then processed in chunks of about
    ``chunk_points`` points aligned to cell boundaries; every per-cell quantity is a
    ``bincount``/``reduceat`` over a chunk, so there is no Python loop per cell and the working
    memory is bounded by the chunk (plus the per-point outputs).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Dict, List, Optional, Tuple

import numpy as np
from affine import Affine
from numpy.typing import ArrayLike, NDArray

from ..errors import InputError
from ..feedback import Feedback, ensure_feedback
from .gridding import Grid

Array = NDArray[Any]

#: Reduction modes.
MODES = ("l1", "median", "lower")

#: 1 / Φ⁻¹(0.75): MAD → σ for Gaussian residuals.
MAD_TO_SIGMA = 1.4826

#: χ²(2 degrees of freedom, 95 %): the slope-significance threshold.
CHI2_2_95 = 5.991


@dataclass
class GroundelResult:
    """The reduced points (one per cell) and the per-point residuals and flags.

    Per cell (length ``cells``): ``row``, ``col`` (int64, relative to ``origin``), ``x``, ``y``
    (cell centre), ``z`` (robust value at the centre), ``n`` (points), ``sigma1`` (σ1 of the
    cell, NaN below ``min_points``), ``plane`` (bool: tilted plane used), ``slope`` ((cells, 2)
    c1, c2; 0 for median cells), ``outliers`` (flagged points), ``rep_index`` (index of the
    representative point in the input), ``rep_x``, ``rep_y``, ``rep_z``.

    Per input point (length of the input): ``residual`` (NaN for invalid points),
    ``outlier`` (bool), ``cell_index`` (index into the cell arrays, −1 for invalid points).
    """

    cell_size: float
    origin: Tuple[float, float]
    mode: str
    row: Array
    col: Array
    x: Array
    y: Array
    z: Array
    n: Array
    sigma1: Array
    plane: Array
    slope: Array
    outliers: Array
    rep_index: Array
    rep_x: Array
    rep_y: Array
    rep_z: Array
    residual: Array
    outlier: Array
    cell_index: Array
    sigma1_mean: float
    sigma2: float
    n_mean: float
    points_raw: int
    points_valid: int
    F: float
    k: float
    min_points: int
    options: Dict[str, Any] = field(default_factory=dict)

    @property
    def cells(self) -> int:
        """Number of reduced points (occupied cells)."""
        return int(self.z.size)

    @property
    def n_outliers(self) -> int:
        return int(np.count_nonzero(self.outlier))

    def summary(self) -> Dict[str, Any]:
        """JSON-ready numbers (the ``reduction`` entry of the model report)."""

        def num(v: float) -> Optional[float]:
            return float(v) if math.isfinite(v) else None

        reliable = self.n >= self.min_points
        return {
            "mode": self.mode,
            "cell_m": float(self.cell_size),
            "points_raw": int(self.points_raw),
            "points_valid": int(self.points_valid),
            "points_reduced": self.cells,
            "outliers": self.n_outliers,
            "outlier_pct": (100.0 * self.n_outliers / self.points_valid
                            if self.points_valid else 0.0),
            "sigma1_m": num(self.sigma1_mean),
            "sigma2_m": num(self.sigma2),
            "n_mean": num(self.n_mean),
            "F": float(self.F),
            "k": float(self.k),
            "cells_with_sigma": int(np.count_nonzero(reliable)),
            "cells_below_min_points": int(np.count_nonzero(~reliable)),
            "plane_cells": int(np.count_nonzero(self.plane)),
            "points_per_cell": _quantiles(self.n),
            "sigma1_cells_m": _quantiles(self.sigma1[reliable]),
        }

    def grid(self) -> Tuple[Grid, Dict[str, Array]]:
        """The occupied cells as rasters on the smallest grid holding them.

        Returns
        -------
        grid : Grid
        layers : dict
            ``z`` (float32, NaN = empty), ``n`` (uint32), ``sigma1`` (float32).
        """
        s = self.cell_size
        x0, y0 = self.origin
        if self.cells == 0:
            g = Grid(Affine(s, 0.0, x0, 0.0, -s, y0), 1, 1, s)
            return g, {"z": np.full((1, 1), np.nan, np.float32),
                       "n": np.zeros((1, 1), np.uint32),
                       "sigma1": np.full((1, 1), np.nan, np.float32)}
        r0, c0 = int(self.row.min()), int(self.col.min())
        h, w = int(self.row.max()) - r0 + 1, int(self.col.max()) - c0 + 1
        g = Grid(Affine(s, 0.0, x0 + c0 * s, 0.0, -s, y0 - r0 * s), w, h, s)
        rr, cc = self.row - r0, self.col - c0
        layers = {"z": np.full((h, w), np.nan, np.float32),
                  "n": np.zeros((h, w), np.uint32),
                  "sigma1": np.full((h, w), np.nan, np.float32)}
        layers["z"][rr, cc] = self.z
        layers["n"][rr, cc] = self.n
        layers["sigma1"][rr, cc] = self.sigma1
        return g, layers


def _quantiles(values: Array) -> Dict[str, Optional[float]]:
    v = np.asarray(values, float)
    v = v[np.isfinite(v)]
    if v.size == 0:
        return {"min": None, "q25": None, "median": None, "q75": None, "max": None}
    q = np.percentile(v, [0, 25, 50, 75, 100])
    return dict(zip(("min", "q25", "median", "q75", "max"), (float(a) for a in q)))


# -- per-cell order statistics on points sorted by cell --------------------------------------------
def _group_sort(lid: Array, values: Array, start: Array) -> Array:
    """Permutation sorting ``values`` within cells; ``lid`` is sorted (cells contiguous).

    One float argsort of ``lid + ½ (v − min_cell) / range_cell`` (the value mapped monotonically
    into [lid, lid + ½]) instead of a lexsort: ~7× faster; values closer than ~1e-10 of their
    cell's range may swap, which changes no order statistic by more than that.
    """
    lo = np.minimum.reduceat(values, start)
    span = np.maximum.reduceat(values, start) - lo
    span[~(span > 0)] = 1.0
    return np.argsort(lid + 0.5 * (values - lo[lid]) / span[lid])


def _percentile_sorted(vs: Array, start: Array, cnt: Array, q: float) -> Array:
    """Per-group percentile ``q`` (0…1) of group-sorted values, linear interpolation."""
    pos = start + q * (cnt - 1)
    lo = np.floor(pos).astype(np.int64)
    hi = np.minimum(lo + 1, start + cnt - 1)
    t = pos - lo
    return vs[lo] * (1.0 - t) + vs[hi] * t


def _cell_quantile(lid: Array, values: Array, start: Array, cnt: Array, q: float,
                   w: Optional[Array]) -> Array:
    """Per-cell (weighted) quantile ``q`` (0…1) of ``values``."""
    order = _group_sort(lid, values, start)
    vs = values[order]
    if w is None:
        return _percentile_sorted(vs, start, cnt, q)
    ws = w[order]
    cw = np.cumsum(ws)
    total = np.add.reduceat(ws, start)
    before = cw[start] - ws[start]
    # first sorted point whose cumulative weight reaches q of the cell's total
    idx = np.searchsorted(cw, before + q * total - 1e-12 * total, side="left")
    idx = np.clip(idx, start, start + cnt - 1)
    return vs[idx]


def _mad_sigma(lid: Array, v: Array, start: Array, cnt: Array, u: Array) -> Array:
    r"""σ = 1.4826 · median|v − median v| · √(n/(n−2u)) per cell (NaN where n ≤ 2u)."""
    med = _cell_quantile(lid, v, start, cnt, 0.5, None)
    a = np.abs(v - med[lid])
    mad = _cell_quantile(lid, a, start, cnt, 0.5, None)
    red = cnt - 2.0 * u
    with np.errstate(divide="ignore", invalid="ignore"):
        corr = np.sqrt(np.where(red > 0, cnt / np.maximum(red, 1), np.nan))
    return MAD_TO_SIGMA * mad * corr


def _l1_planes(lid: Array, dx: Array, dy: Array, z: Array, p: Array, start: Array,
               cnt: Array, c0: Array, active: Array, delta: float, half: float,
               max_iter: int, tol: float, rel_tol: float) -> Tuple[Array, Array, Array, int]:
    r"""IRLS for the L1 plane of every active cell; returns c0, c1, c2 and the iterations.

    A cell has converged when its plane moves by less than :math:`t` anywhere within the
    cell (``half`` = half the cell side): :math:`|Δc_0| + half\,(|Δc_1| + |Δc_2|) < t` with
    :math:`t = \max(tol,\ rel\_tol \cdot \hat\sigma)`, :math:`\hat\sigma` the robust σ of the
    plane residuals after a few iterations. IRLS for L1 converges only linearly near the
    optimum; a precision of a small fraction of the noise is all the reduction needs, and exact
    data (σ̂ ≈ 0) still converge to ``tol``. Converged cells leave the iterations.
    """
    m = c0.size
    c0 = c0.copy()
    c1 = np.zeros(m)
    c2 = np.zeros(m)
    full = (lid, dx, dy, z)
    sel = active[lid]
    lid, dx, dy, z, p = lid[sel], dx[sel], dy[sel], z[sel], p[sel]
    done = ~active
    limit = np.full(m, tol)
    it = 0
    for it in range(1, max_iter + 1):
        if it == SCALE_ITERATION:
            fl, fx, fy, fz = full
            scale = _mad_sigma(fl, fz - (c0[fl] + c1[fl] * fx + c2[fl] * fy), start, cnt,
                               np.full(m, 3.0))
            limit = np.maximum(tol, rel_tol * np.nan_to_num(scale, nan=0.0))
        r = z - (c0[lid] + c1[lid] * dx + c2[lid] * dy)
        w = p / np.maximum(np.abs(r), delta)
        wx, wy = w * dx, w * dy
        cells = np.flatnonzero(~done)
        N = np.empty((cells.size, 3, 3))
        b = np.empty((cells.size, 3, 1))
        for (i, j), a in (((0, 0), w), ((0, 1), wx), ((0, 2), wy), ((1, 1), wx * dx),
                          ((1, 2), wx * dy), ((2, 2), wy * dy)):
            N[:, i, j] = N[:, j, i] = np.bincount(lid, weights=a, minlength=m)[cells]
        for i, a in enumerate((w, wx, wy)):
            b[:, i, 0] = np.bincount(lid, weights=a * z, minlength=m)[cells]
        # a tiny ridge on the slopes keeps near-degenerate cells solvable (no effect otherwise)
        ridge = 1e-12 * (N[:, 1, 1] + N[:, 2, 2]) + 1e-300
        N[:, 1, 1] += ridge
        N[:, 2, 2] += ridge
        sol = np.linalg.solve(N, b)[:, :, 0]  # b as (m, 3, 1): numpy 1.x and 2.x agree
        change = np.abs(sol[:, 0] - c0[cells]) + half * (np.abs(sol[:, 1] - c1[cells])
                                                         + np.abs(sol[:, 2] - c2[cells]))
        c0[cells], c1[cells], c2[cells] = sol[:, 0], sol[:, 1], sol[:, 2]
        conv = change < limit[cells]
        if conv.all():
            break
        if conv.any():
            done[cells[conv]] = True
            keep = ~done[lid]
            if np.count_nonzero(keep) < 0.8 * lid.size:  # compress now and then
                lid, dx, dy, z, p = lid[keep], dx[keep], dy[keep], z[keep], p[keep]
    return c0, c1, c2, it


#: IRLS iteration at which the noise scale for the relative convergence test is estimated.
SCALE_ITERATION = 6


def _reduce_chunk(lid: Array, x: Array, y: Array, z: Array, p: Optional[Array], start: Array,
                  cnt: Array, xc: Array, yc: Array, opts: Dict[str, Any]) -> Dict[str, Array]:
    """Reduce the points of a chunk of whole cells (``lid`` = local cell id, sorted)."""
    mode, cell = opts["mode"], opts["cell"]
    m = cnt.size
    loc = _cell_quantile(lid, z, start, cnt, 0.5 if mode != "lower"
                         else opts["lower_percentile"] / 100.0, p)
    c1 = np.zeros(m)
    c2 = np.zeros(m)
    plane = np.zeros(m, bool)
    u = np.ones(m)
    dx = x - xc[lid]
    dy = y - yc[lid]
    iterations = 0
    if mode == "l1":
        # geometry: the smaller eigenvalue of the centred (ΔX, ΔY) scatter per point must show
        # a spread over both axes, else the plane is undetermined
        cntf = cnt.astype(float)
        mx = np.add.reduceat(dx, start) / cntf
        my = np.add.reduceat(dy, start) / cntf
        ex, ey = dx - mx[lid], dy - my[lid]
        sxx = np.add.reduceat(ex * ex, start)
        sxy = np.add.reduceat(ex * ey, start)
        syy = np.add.reduceat(ey * ey, start)
        half_tr = 0.5 * (sxx + syy)
        lam_min = half_tr - np.sqrt(np.maximum(0.25 * (sxx - syy) ** 2 + sxy ** 2, 0.0))
        spread_ok = lam_min / cntf > (0.05 * cell) ** 2
        # σ of L1-plane residuals needs n > 2u = 6 (see _mad_sigma)
        active = (cnt >= max(opts["plane_min_points"], 7)) & spread_ok
        if active.any():
            pw = np.ones_like(z) if p is None else p
            a0, a1, a2, iterations = _l1_planes(
                lid, dx, dy, z, pw, start, cnt, loc, active, 1e-6 * cell, 0.5 * cell,
                opts["max_iter"], opts["tol"], opts["rel_tol"])
            vp = z - (a0[lid] + a1[lid] * dx + a2[lid] * dy)
            s_plane = _mad_sigma(lid, vp, start, cnt, np.full(m, 3.0))
            s_eff = np.maximum(np.nan_to_num(s_plane, nan=0.0), 1e-9 * cell)
            T = (a1 * a1 * sxx + 2.0 * a1 * a2 * sxy + a2 * a2 * syy) / (
                0.5 * math.pi * s_eff * s_eff)
            plane = active & (opts["slope_test"] < T)
            loc = np.where(plane, a0, loc)
            c1 = np.where(plane, a1, 0.0)
            c2 = np.where(plane, a2, 0.0)
            u = np.where(plane, 3.0, 1.0)
    v = z - (loc[lid] + c1[lid] * dx + c2[lid] * dy)
    sigma = _mad_sigma(lid, v, start, cnt, u)
    reliable = cnt >= opts["min_points"]
    sigma = np.where(reliable, sigma, np.nan)
    limit = np.maximum(opts["k"] * np.nan_to_num(sigma, nan=np.inf), opts["floor"])
    absv = np.abs(v)
    outlier = absv > limit[lid]
    # representative: the point with the smallest |v| (the first of equals)
    best = np.minimum.reduceat(absv, start)
    cand = np.flatnonzero(absv == best[lid])
    first = cand[np.unique(lid[cand], return_index=True)[1]]
    return {"z": loc, "c1": c1, "c2": c2, "plane": plane, "sigma": sigma, "v": v,
            "outlier": outlier, "rep": first,
            "outliers": np.bincount(lid, weights=outlier, minlength=m).astype(np.int64),
            "iterations": np.array(iterations)}


def _check_options(mode: str, cell: float, lower_percentile: float, min_points: int,
                   plane_min_points: int) -> None:
    """InputError for an unknown mode or a parameter out of range."""
    if mode not in MODES:
        raise InputError(f"Unknown groundel mode '{mode}'; use one of {', '.join(MODES)}.")
    if not (cell > 0 and math.isfinite(cell)):
        raise InputError(f"The groundel size must be positive, got {cell}.")
    if not 0.0 <= lower_percentile <= 100.0:
        raise InputError(f"The lower-envelope percentile must be within 0…100, got "
                         f"{lower_percentile}.")
    if min_points < 1 or plane_min_points < 3:
        raise InputError("min_points must be ≥ 1 and plane_min_points ≥ 3.")


@dataclass
class _Cells:
    """The valid points sorted by cell, and the occupied cells.

    Attributes
    ----------
    x0, y0 : float
        Upper-left corner of the cell grid.
    pts : ndarray int64
        Input index of every valid point, sorted by cell.
    starts, counts : ndarray
        First sorted point and number of points of every cell.
    row, col : ndarray int64
        Cell indices (relative to the corner).
    cx, cy : ndarray
        Cell centres.
    """

    x0: float
    y0: float
    pts: Array
    starts: Array
    counts: Array
    row: Array
    col: Array
    cx: Array
    cy: Array


def _sort_into_cells(x: Array, y: Array, idx: Array, cell: float,
                     origin: Optional[Tuple[float, float]]) -> _Cells:
    """Sort the valid points (``idx``) by cell (stable: input order within a cell)."""
    if origin is None:
        x0 = math.floor(float(x[idx].min()) / cell) * cell
        y0 = math.ceil(float(y[idx].max()) / cell) * cell
    else:
        x0, y0 = float(origin[0]), float(origin[1])
    col = np.floor((x[idx] - x0) / cell).astype(np.int64)
    row = np.floor((y0 - y[idx]) / cell).astype(np.int64)
    rmin, cmin = int(row.min()), int(col.min())
    ncols = int(col.max()) - cmin + 1
    key = (row - rmin) * ncols + (col - cmin)
    del row, col
    order = np.argsort(key, kind="stable")
    skey = key[order]
    pts = idx[order]  # input index of each sorted point
    del key, order
    starts = np.concatenate([[0], np.flatnonzero(np.diff(skey)) + 1])
    counts = np.diff(np.append(starts, skey.size))
    ckey = skey[starts]
    del skey
    crow = ckey // ncols + rmin
    ccol = ckey % ncols + cmin
    return _Cells(x0, y0, pts, starts, counts, crow, ccol, x0 + (ccol + 0.5) * cell,
                  y0 - (crow + 0.5) * cell)


def _chunk_bounds(cells: _Cells, chunk_points: int) -> Tuple[List[int], Array]:
    """Chunks of whole cells, about ``chunk_points`` points each.

    Returns
    -------
    (first cell of every chunk and the end, first sorted point of every cell and the end)
    """
    m = cells.starts.size
    bounds = [0]
    cum = np.append(cells.starts, cells.pts.size)
    while bounds[-1] < m:
        target = cum[bounds[-1]] + max(int(chunk_points), 1)
        nxt = int(np.searchsorted(cum, target, side="right")) - 1
        bounds.append(min(max(nxt, bounds[-1] + 1), m))
    return bounds, cum


@dataclass
class _Outputs:
    """Per-cell and per-point results, filled chunk by chunk."""

    z: Array
    sigma: Array
    plane: Array
    slope: Array
    outliers: Array
    rep: Array
    residual: Array
    outlier: Array
    cell_index: Array
    max_it: int = 0

    @classmethod
    def empty(cls, m: int, n_raw: int) -> _Outputs:
        """Outputs of ``m`` cells and ``n_raw`` input points."""
        return cls(np.empty(m), np.empty(m), np.zeros(m, bool), np.zeros((m, 2)),
                   np.zeros(m, np.int64), np.empty(m, np.int64), np.full(n_raw, np.nan),
                   np.zeros(n_raw, bool), np.full(n_raw, -1, np.int64))


def _reduce_cells(x: Array, y: Array, z: Array, p_all: Optional[Array], cells: _Cells,
                  opts: Dict[str, Any], chunk_points: int, feedback: Feedback) -> _Outputs:
    """Run :func:`_reduce_chunk` over chunks of whole cells and gather the results."""
    out = _Outputs.empty(cells.starts.size, x.size)
    bounds, cum = _chunk_bounds(cells, chunk_points)
    for ci, (a, b) in enumerate(zip(bounds[:-1], bounds[1:])):
        feedback.progress(100.0 * ci / (len(bounds) - 1))
        s, e = int(cum[a]), int(cum[b])
        sel = cells.pts[s:e]
        cnt = cells.counts[a:b]
        start = cells.starts[a:b] - s
        lid = np.repeat(np.arange(b - a), cnt)
        res = _reduce_chunk(lid, x[sel], y[sel], z[sel], None if p_all is None else p_all[sel],
                            start, cnt, cells.cx[a:b], cells.cy[a:b], opts)
        out.z[a:b] = res["z"]
        out.sigma[a:b] = res["sigma"]
        out.plane[a:b] = res["plane"]
        out.slope[a:b, 0] = res["c1"]
        out.slope[a:b, 1] = res["c2"]
        out.outliers[a:b] = res["outliers"]
        out.rep[a:b] = sel[res["rep"]]
        out.residual[sel] = res["v"]
        out.outlier[sel] = res["outlier"]
        out.cell_index[sel] = np.arange(a, b)[lid]
        out.max_it = max(out.max_it, int(res["iterations"]))
    feedback.progress(100.0)
    return out


def reduce_groundels(x: ArrayLike, y: ArrayLike, z: ArrayLike, cell: float, *,
                     origin: Optional[Tuple[float, float]] = None, mode: str = "l1",
                     lower_percentile: float = 10.0, min_points: int = 3,
                     plane_min_points: int = 6, F: float = 2.0, k: float = 3.0,
                     weights: Optional[ArrayLike] = None, floor: float = 1e-3,
                     slope_test: float = CHI2_2_95, max_iter: int = 100, tol: float = 1e-6,
                     rel_tol: float = 2e-3,
                     chunk_points: int = 2_000_000,
                     feedback: Optional[Feedback] = None) -> GroundelResult:
    r"""Reduce points to one robust point per ground cell (see the module notes).

    Parameters
    ----------
    x, y, z : array_like, shape (n,)
        Point coordinates (m); non-finite points are ignored.
    cell : float
        Groundel side GE (m); rule of thumb √2 × the matching window on the ground.
    origin : (x0, y0), optional
        Upper-left corner of the cell grid; default: the points' extent snapped to multiples
        of ``cell`` (as :meth:`.gridding.Grid.from_bounds`).
    mode : {"l1", "median", "lower"}
        L1 tilted plane (median fallback), median, or lower envelope.
    lower_percentile : float
        Percentile (0–100) of the ``"lower"`` mode.
    min_points : int
        Cells with fewer points get no σ1 and no outlier flags (still one reduced point).
    plane_min_points : int
        Fewer points than this: median instead of the plane.
    F : float
        σ2 = F·σ1/√n̄.
    k : float
        Outlier threshold in σ1 of the cell.
    weights : array_like, optional
        Point weights :math:`p_k > 0` (e.g. 1/σ²); non-positive or non-finite weights drop
        the point.
    floor : float
        Smallest residual (m) that can be an outlier (cells with σ1 ≈ 0).
    slope_test : float
        χ² threshold of the slope significance (2 degrees of freedom).
    max_iter, tol, rel_tol : int, float, float
        IRLS limits: a cell stops when its plane moves by less than
        ``max(tol, rel_tol·σ̂_cell)`` (m) within the cell (see :func:`_l1_planes`).
    chunk_points : int
        Points processed at once (memory bound).

    Returns
    -------
    GroundelResult

    Raises
    ------
    InputError
        Bad parameters, arrays of different lengths, or no finite point.
    """
    feedback = ensure_feedback(feedback)
    _check_options(mode, cell, lower_percentile, min_points, plane_min_points)
    x = np.ravel(np.asarray(x, dtype=np.float64))
    y = np.ravel(np.asarray(y, dtype=np.float64))
    z = np.ravel(np.asarray(z, dtype=np.float64))
    if not (x.size == y.size == z.size):
        raise InputError(f"x, y, z have different lengths ({x.size}, {y.size}, {z.size}).")
    valid = np.isfinite(x) & np.isfinite(y) & np.isfinite(z)
    p_all = None
    if weights is not None:
        p_all = np.ravel(np.broadcast_to(np.asarray(weights, dtype=np.float64), z.shape))
        valid &= np.isfinite(p_all) & (p_all > 0)
    idx = np.flatnonzero(valid)
    if idx.size == 0:
        raise InputError("No finite point to reduce (all coordinates NaN or outside).")
    cells = _sort_into_cells(x, y, idx, cell, origin)
    del idx
    opts = {"mode": mode, "cell": float(cell), "lower_percentile": float(lower_percentile),
            "min_points": int(min_points), "plane_min_points": int(plane_min_points),
            "k": float(k), "floor": float(floor), "slope_test": float(slope_test),
            "max_iter": int(max_iter), "tol": float(tol),
            "rel_tol": float(rel_tol)}
    out = _reduce_cells(x, y, z, p_all, cells, opts, chunk_points, feedback)
    counts = cells.counts
    reliable = counts >= min_points
    if reliable.any():
        sigma1 = float(np.nanmean(out.sigma[reliable]))
        n_mean = float(counts[reliable].mean())
        sigma2 = F * sigma1 / math.sqrt(n_mean)
    else:
        sigma1 = sigma2 = n_mean = float("nan")
    return GroundelResult(
        cell_size=float(cell), origin=(cells.x0, cells.y0), mode=mode, row=cells.row,
        col=cells.col, x=cells.cx, y=cells.cy, z=out.z, n=counts.astype(np.int64),
        sigma1=out.sigma, plane=out.plane, slope=out.slope, outliers=out.outliers,
        rep_index=out.rep, rep_x=x[out.rep], rep_y=y[out.rep], rep_z=z[out.rep],
        residual=out.residual, outlier=out.outlier, cell_index=out.cell_index,
        sigma1_mean=sigma1, sigma2=sigma2, n_mean=n_mean, points_raw=int(x.size),
        points_valid=int(cells.pts.size), F=float(F), k=float(k), min_points=int(min_points),
        options={**opts, "irls_iterations": out.max_it},
    )


__all__ = ["MODES", "GroundelResult", "reduce_groundels"]
