"""Disparity predictions from the planes of window components (:mod:`.hierarchy`).

Every window component of a pyramid level carries a plane d = p0 + p1·u + p2·v
(:class:`.fbm.Grouping`: u, v relative to the component's centre, in windows). The
coarse-to-fine matcher predicts the disparity of a point from such planes: the coarser
level's (:class:`CoarsePlanes`), the caller's approximation grid (:class:`ApproxGrid`), a
seed, the whole range or the matched neighbour components (:class:`Predictor`, one per
wave). The graph of the components has no edges across barriers, so nothing is predicted
across a breakline.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Optional, Tuple

import numpy as np
from numpy.typing import NDArray

from .fbm import Grouping, group_weighted_median, group_wls
from .pyramid import from_level, to_level

#: Prediction modes of a component (int8 per component).
NONE, COARSE, NEIGHBOURS, RANGE, SEED = 0, 1, 2, 3, 4

__all__ = ["COARSE", "NEIGHBOURS", "NONE", "RANGE", "SEED", "ApproxGrid", "CoarsePlanes",
           "Predictor", "eval_planes", "fill_planes", "neighbour_prediction", "plane_range",
           "points_planes", "suspect_components"]


def eval_planes(plane: NDArray, grouping: Grouping, g: NDArray, cols: NDArray, rows: NDArray
                ) -> NDArray:
    """Disparity of the groups' planes d = p0 + p1·u + p2·v at points (NaN for g < 0)."""
    out = np.full(np.shape(cols), np.nan)
    ok = g >= 0
    if ok.any():
        gg = g[ok]
        u, v = grouping.uv(cols[ok], rows[ok], gg)
        p = plane[gg]
        out[ok] = p[:, 0] + p[:, 1] * u + p[:, 2] * v
    return out


def _point_neighbours(edges: NDArray, g: NDArray) -> Tuple[NDArray, NDArray, NDArray]:
    """Every point's neighbour groups along ``edges`` (group → group).

    Returns ``(point, neighbour, count)``: one (point index, neighbour group) pair per edge
    leaving the point's group ``g`` (none for ``g < 0``), and the number of pairs per point.
    """
    order = np.argsort(edges[:, 0], kind="stable")
    src, dst = edges[order, 0], edges[order, 1]
    start = np.searchsorted(src, g, side="left")
    stop = np.searchsorted(src, g, side="right")
    cnt = np.where(g >= 0, stop - start, 0)
    pi = np.repeat(np.arange(g.size), cnt)
    first = np.cumsum(cnt) - cnt
    return pi, dst[start[pi] + (np.arange(pi.size) - first[pi])], cnt


def plane_range(plane: NDArray, grouping: Grouping, g: NDArray, cols: NDArray, rows: NDArray
                ) -> Tuple[NDArray, NDArray]:
    """Lowest and highest disparity of a group's own plane and its neighbours' planes at
    each point (NaN for g < 0): where they disagree (a roof beside the ground) the point's
    disparity is not known better than that."""
    lo = eval_planes(plane, grouping, g, cols, rows)
    hi = lo.copy()
    e = grouping.edges
    if e.size == 0 or g.size == 0:
        return lo, hi
    pi, nb, cnt = _point_neighbours(e, g)
    if cnt.sum() == 0:
        return lo, hi
    val = eval_planes(plane, grouping, nb, cols[pi], rows[pi])
    ok = np.isfinite(val)
    np.fmin.at(lo, pi[ok], val[ok])
    np.fmax.at(hi, pi[ok], val[ok])
    return lo, hi


def neighbour_prediction(plane: NDArray, grouping: Grouping, matched: NDArray, g: NDArray,
                          cols: NDArray, rows: NDArray) -> NDArray:
    """Mean of the matched neighbour components' planes, evaluated at each point."""
    out = np.full(np.shape(cols), np.nan)
    e = grouping.edges
    if e.size == 0 or g.size == 0:
        return out
    e = e[matched[e[:, 1]]]
    if e.size == 0:
        return out
    pi, nb, cnt = _point_neighbours(e, g)
    if cnt.sum() == 0:
        return out
    val = eval_planes(plane, grouping, nb, cols[pi], rows[pi])
    s = np.bincount(pi, val, g.size)
    has = cnt > 0
    out[has] = s[has] / cnt[has]
    return out


def fill_planes(plane: NDArray, grouping: Grouping, matched: NDArray, masked: NDArray
                 ) -> NDArray:
    """Planes for unmatched, unmasked components from their neighbours (over the graph).

    Wave by wave, each open component takes the mean of its filled neighbours' planes
    evaluated at its centre (slopes averaged). The graph has no edges across barriers.
    """
    out = plane.copy()
    have = matched.copy()
    e = grouping.edges
    c = grouping.centres
    ws = grouping.window
    while e.size:
        sel = have[e[:, 1]] & ~have[e[:, 0]] & ~masked[e[:, 0]]
        if not sel.any():
            break
        s, d = e[sel, 0], e[sel, 1]
        u = (c[s, 0] - c[d, 0]) / ws
        v = (c[s, 1] - c[d, 1]) / ws
        p0 = out[d, 0] + out[d, 1] * u + out[d, 2] * v
        n = np.bincount(s, minlength=len(out)).astype(float)
        new = n > 0
        acc = np.zeros_like(out)
        acc[:, 0] = np.bincount(s, p0, len(out))
        acc[:, 1] = np.bincount(s, out[d, 1], len(out))
        acc[:, 2] = np.bincount(s, out[d, 2], len(out))
        out[new] = acc[new] / n[new, None]
        have |= new
    out[~have] = np.nan
    return out


def points_planes(grouping: Grouping, col: NDArray, row: NDArray, d: NDArray, g: NDArray
                   ) -> NDArray:
    """Absolute plane d = p0 + p1·u + p2·v per group from accepted points (NaN where none)."""
    ng = grouping.n_groups
    out = np.full((ng, 3), np.nan)
    if col.size:
        u, v = grouping.uv(col, row, g)
        a = group_wls(u, v, d, np.ones(col.size), g, ng, 1e-3)
        has = np.bincount(g, minlength=ng) > 0
        out[has] = a[has]
    return out


def suspect_components(plane: NDArray, grouping: Grouping, test: NDArray, matched: NDArray,
                        tol: float) -> NDArray:
    """Components (of ``test``) whose plane disagrees with their matched neighbours.

    At the component's centre, the planes of its matched neighbours (over the barrier-free
    graph) are evaluated; with at least 3 of them, the component is suspect when its own
    plane differs from their median by more than ``tol`` px. A single wrong window (a
    consistent but false set of correlation peaks, e.g. from a wrong coarse prediction)
    is thus caught by the majority around it; real relief changes smoothly across windows.
    """
    ng = grouping.n_groups
    out = np.zeros(ng, bool)
    e = grouping.edges
    if e.size == 0:
        return out
    e = e[test[e[:, 0]] & matched[e[:, 1]]]
    if e.size == 0:
        return out
    c = grouping.centres
    s, d = e[:, 0], e[:, 1]
    u, v = grouping.uv(c[s, 0], c[s, 1], d)
    val = plane[d, 0] + plane[d, 1] * u + plane[d, 2] * v
    cnt = np.bincount(s, minlength=ng)
    med = group_weighted_median(val, np.ones(val.size), s, ng)
    own = plane[:, 0]  # the plane at its own centre (u = v = 0)
    out = (cnt >= 3) & test & np.isfinite(med) & (np.abs(own - med) > tol)
    return out


class CoarsePlanes:
    """Predictions from the coarser level's (filled) planes, × 2 to this level."""

    has_span = True

    def __init__(self, plane: NDArray, grouping: Grouping) -> None:
        self.plane = plane
        self.grouping = grouping

    def _at(self, cols: NDArray, rows: NDArray) -> Tuple[NDArray, NDArray, NDArray]:
        c1, r1 = to_level(cols, 1) * 1.0, to_level(rows, 1) * 1.0
        return c1, r1, self.grouping.of(c1, r1, nearest=True)

    def predict(self, cols: NDArray, rows: NDArray) -> NDArray:
        """Disparity of the coarser plane under each point (NaN where none)."""
        c1, r1, g1 = self._at(cols, rows)
        return 2.0 * eval_planes(self.plane, self.grouping, g1, c1, r1)

    def span(self, cols: NDArray, rows: NDArray) -> Tuple[NDArray, NDArray]:
        """Lowest and highest of the coarser own and neighbouring planes at each point."""
        c1, r1, g1 = self._at(cols, rows)
        lo, hi = plane_range(self.plane, self.grouping, g1, c1, r1)
        return 2.0 * lo, 2.0 * hi


class ApproxGrid:
    """Predictions from the caller's level-0 disparity grid (``approx``) at level ``k``."""

    has_span = False

    def __init__(self, grid: NDArray, step: float, k: int, scale: float) -> None:
        self.grid = grid
        self.step = step
        self.k = k
        self.scale = scale

    def predict(self, cols: NDArray, rows: NDArray) -> NDArray:
        """Grid value of the level-0 cell holding each point, in level-k px (NaN outside)."""
        grid, step = self.grid, self.step
        i = np.floor((from_level(rows, self.k) + 0.5) / step).astype(np.int64)
        j = np.floor((from_level(cols, self.k) + 0.5) / step).astype(np.int64)
        ok = (i >= 0) & (i < grid.shape[0]) & (j >= 0) & (j < grid.shape[1])
        out = np.full(np.shape(cols), np.nan)
        out[ok] = grid[i[ok], j[ok]] / self.scale
        return out


@dataclass
class Predictor:
    """``predict(cols, rows) -> (d_pred, pull_in)`` of one wave (:func:`.fbm.fbm_level`).

    ``mode``, ``plane`` and ``matched`` are the level's arrays (updated in place by the
    waves); ``todo`` is the wave's set of components to match.
    """

    grouping: Grouping
    mode: NDArray
    plane: NDArray
    matched: NDArray
    seed_d: NDArray
    coarse: Any
    mid: float
    half: float
    pull_ref: float
    pull_grow: float
    todo: NDArray

    def __call__(self, cols: NDArray, rows: NDArray, active: Optional[NDArray] = None,
                 context: Optional[NDArray] = None) -> Tuple[NDArray, NDArray]:
        """(d_pred, pull_in) at left positions of this level; NaN = not matched now.

        ``active`` (per component) replaces the wave's to-do set; ``context``
        components predict from their own plane (enlarged windows).
        """
        g = self.grouping.of(cols, rows)
        gg = np.maximum(g, 0)
        d = np.full(np.shape(cols), np.nan)
        p = np.full(np.shape(cols), np.nan)
        act = (g >= 0) & (self.todo if active is None else active)[gg]
        m = np.where(act, self.mode[gg], NONE)
        sel = m == COARSE
        if sel.any() and self.coarse is not None:
            self._from_coarse(cols, rows, sel, d, p)
        sel = m == SEED
        if sel.any():
            d[sel] = self.seed_d[g[sel]]
            p[sel] = self.pull_grow
        sel = m == RANGE
        if sel.any():
            d[sel] = self.mid
            p[sel] = self.half
        sel = m == NEIGHBOURS
        if sel.any():
            d[sel] = neighbour_prediction(self.plane, self.grouping, self.matched, g[sel],
                                           cols[sel], rows[sel])
            p[sel] = self.pull_grow
        if context is not None:
            own = (g >= 0) & context[gg] & ~act
            if own.any():
                d[own] = eval_planes(self.plane, self.grouping, g[own], cols[own], rows[own])
                p[own] = self.pull_ref
        return d, p

    def _from_coarse(self, cols: NDArray, rows: NDArray, sel: NDArray, d: NDArray,
                     p: NDArray) -> None:
        """Fill ``d``, ``p`` at ``sel`` from the coarser level (or the approximation)."""
        if self.coarse.has_span:
            # between disagreeing coarse planes (e.g. a window's roof plane
            # extrapolated over ground) search their whole span, up to 4 pull-ins
            lo, hi = self.coarse.span(cols[sel], rows[sel])
            d[sel] = 0.5 * (lo + hi)
            p[sel] = self.pull_ref + np.minimum(0.5 * (hi - lo), 3.0 * self.pull_ref)
        else:
            d[sel] = self.coarse.predict(cols[sel], rows[sel])
            p[sel] = self.pull_ref
