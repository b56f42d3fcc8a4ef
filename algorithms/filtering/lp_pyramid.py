r"""Grid levels of the robust linear prediction: the data pyramid and the breakline sides.

The pyramid (:func:`reduce_lowest`, :func:`upsample2`, :func:`pyramid_levels`) and the
partition of a grid by breaklines (:func:`breakline_sides`) are the grid bookkeeping of
:func:`.linear_prediction.filter_linear_prediction`; the covariance model and its solver stay
in :mod:`.linear_prediction` (see its module notes for the method).
"""

from __future__ import annotations

import math
from typing import Any, List, Optional, Sequence, Tuple

import numpy as np
from affine import Affine
from numpy.typing import NDArray
from rasterio.features import rasterize
from scipy import ndimage
from shapely.geometry import LineString

from ..surface.gridding import Grid, line_barrier

Array = NDArray[Any]


# -- breakline sides ------------------------------------------------------------------------------
class BreaklineSides:
    """Breakline sides of a grid: labels 0…k−1 (k−1 = the breakline cells themselves)."""

    def __init__(self, labels: Array, k: int) -> None:
        self.labels = labels
        self.k = k
        self.slices = ndimage.find_objects(labels + 1, max_label=k)


def _extended_lines(lines: Sequence[Any], length: float) -> List[Any]:
    """Each line part's two end segments extended by ``length`` (m) in their directions."""
    out = []
    for g in lines:
        for part in getattr(g, "geoms", [g]):
            c = np.asarray(part.coords, float)[:, :2]
            if len(c) < 2:
                continue
            for a, b in ((c[0], c[1]), (c[-1], c[-2])):
                u = a - b
                n = float(np.hypot(*u))
                if n > 0:
                    out.append(LineString([tuple(a), tuple(a + u / n * length)]))
    return out


def breakline_sides(lines: Sequence[Any], grid: Grid
                    ) -> Tuple[Optional[BreaklineSides], Array, Array]:
    """Partition of the grid by breaklines and their extensions to the grid border.

    Returns
    -------
    (sides or None without lines, barrier mask, barrier heights)
        Sides are the 4-connected components of the cells no (extended) line touches; cells
        touched only by an extension join the nearest side; the breakline cells form a class
        of their own (they correlate along the line, not with either side).
    """
    lines = [g for g in (lines or []) if g is not None and not g.is_empty]
    barrier, zline = line_barrier(lines, grid)
    if not lines or not barrier.any():
        return None, barrier, zline
    diag = grid.spacing * math.hypot(grid.width, grid.height)
    ext = _extended_lines(lines, 2.0 * diag)
    cut = barrier.copy()
    if ext:
        cut |= rasterize([(g, 1) for g in ext], out_shape=grid.shape, transform=grid.transform,
                         fill=0, all_touched=True, dtype="uint8").astype(bool)
    labels, n = ndimage.label(~cut)
    labels = labels.astype(np.int32) - 1  # −1 on cut cells
    only_ext = cut & ~barrier
    if only_ext.any() and n > 0:
        # nearest cell of a side (cut cells are the background of the transform)
        _, (ir, ic) = ndimage.distance_transform_edt(cut, return_indices=True)
        labels[only_ext] = labels[ir[only_ext], ic[only_ext]]
    labels[barrier] = n
    return BreaklineSides(labels, n + 1), barrier, zline


# -- pyramid ---------------------------------------------------------------------------------------
def reduce_min(a: Array) -> Array:
    """Lowest finite value of every 2×2 block (NaN if none)."""
    h, w = a.shape
    p = np.full((h + h % 2, w + w % 2), np.nan, np.float32)
    p[:h, :w] = a
    return np.fmin(np.fmin(p[0::2, 0::2], p[1::2, 0::2]), np.fmin(p[0::2, 1::2], p[1::2, 1::2]))


def _limited_slope(z: Array, axis: int) -> Array:
    """Slope per cell along ``axis`` by the monotonised central (MC) limiter.

    The central difference where both one-sided differences agree in sign, but at most twice
    the smaller of them (0 at a sign change): exact on a plane, while a building or a wall
    next to the cell cannot tilt it by more than twice the terrain's own slope.
    """
    d = np.diff(z, axis=axis)
    pad = [(0, 0), (0, 0)]
    pad[axis] = (1, 0)
    back = np.pad(d, pad, mode="edge")
    pad[axis] = (0, 1)
    fwd = np.pad(d, pad, mode="edge")
    mag = np.minimum(np.minimum(2.0 * np.abs(back), 2.0 * np.abs(fwd)), 0.5 * np.abs(back + fwd))
    return np.where(np.sign(back) == np.sign(fwd), np.sign(fwd) * mag, 0.0)


def reduce_lowest(a: Array, max_slope: float = 1.5) -> Array:
    r"""Mean of the two lowest cells of every 2×2 block, moved to the block centre along the slope.

    The lowest cells keep the ground and drop objects: a building edge or corner covers at
    most two cells of a block, so objects shrink by about a fine cell per side and level.
    Two rather than the single lowest cell, because the minimum of four is the lowest noise
    or roughness value (−1.03 σ for Gaussian noise, −0.66 σ for the mean of the two lowest)
    and, on terraced slopes, the lower terrace; the bias piles up over the levels (metres at
    16 m cells on 50 % slopes: the finer levels' candidate band then cuts the slope). On a
    slope the lowest cells lie on the block's downhill side: with the gradient
    ``(g_x, g_y)`` of the level (:func:`_limited_slope` per cell, averaged over the block,
    clipped to ``max_slope``) and the mean offset ``(δx, δy)`` of the two cells from the
    block centre (±½ fine cell each), the block value is :math:`\bar z_2 - g_x δx - g_y δy`.
    """
    h, w = a.shape
    p = np.full((h + h % 2, w + w % 2), np.nan, np.float32)
    p[:h, :w] = a
    subs = np.stack([p[0::2, 0::2], p[0::2, 1::2], p[1::2, 0::2], p[1::2, 1::2]])
    order = np.argsort(np.where(np.isfinite(subs), subs, np.inf), axis=0, kind="stable")
    v0 = np.take_along_axis(subs, order[:1], axis=0)[0]
    v1 = np.take_along_axis(subs, order[1:2], axis=0)[0]
    two = np.isfinite(v1)  # blocks with a single cell take that cell
    i1 = np.where(two, order[1], order[0])
    out = np.where(two, 0.5 * (v0 + v1), v0)
    ok = np.isfinite(a)
    if ok.sum() < 4 or min(a.shape) < 3:
        return out.astype(np.float32)
    dcol = np.array([-0.5, 0.5, -0.5, 0.5])  # offset in fine cells: +x to the right
    drow = np.array([-0.5, -0.5, 0.5, 0.5])  # rows grow downwards
    _, (ir, ic) = ndimage.distance_transform_edt(~ok, return_indices=True)
    zf = np.asarray(a, np.float64)[ir, ic]  # gaps take the nearest value for the gradient
    hh, ww = p.shape[0] // 2, p.shape[1] // 2
    grads = []
    for axis in (0, 1):
        g = np.pad(_limited_slope(zf, axis), ((0, h % 2), (0, w % 2)), mode="edge")
        grads.append(np.clip(g.reshape(hh, 2, ww, 2).mean(axis=(1, 3)), -max_slope, max_slope))
    gr, gc = grads
    dc = 0.5 * (dcol[order[0]] + dcol[i1])
    dr = 0.5 * (drow[order[0]] + drow[i1])
    return (out - gc * dc - gr * dr).astype(np.float32)


def _up1(a: Array, axis: int, n: int) -> Array:
    a = np.moveaxis(a, axis, 0)
    prev = np.concatenate([a[:1], a[:-1]])
    nxt = np.concatenate([a[1:], a[-1:]])
    out = np.empty((2 * a.shape[0],) + a.shape[1:], np.float32)
    out[0::2] = 0.75 * a + 0.25 * prev
    out[1::2] = 0.75 * a + 0.25 * nxt
    return np.moveaxis(out[:n], 0, axis)


def upsample2(a: Array, shape: Tuple[int, int]) -> Array:
    """Bilinear ×2 upsampling of a level to the next finer level of ``shape``.

    Coarse cell i covers fine cells 2i, 2i+1, so fine cell 2i lies a quarter coarse cell
    before coarse centre i: :math:`f_{2i} = ¾a_i + ¼a_{i-1}`, :math:`f_{2i+1} = ¾a_i + ¼a_{i+1}`
    (edges clamped).
    """
    return _up1(_up1(np.asarray(a, np.float32), 0, shape[0]), 1, shape[1])


def upsample_sides(a: Array, shape: Tuple[int, int], sides_c: Optional[BreaklineSides],
                    sides_f: Optional[BreaklineSides]) -> Array:
    """Upsampling that takes every fine cell's value only from coarse cells of its side."""
    up = upsample2(a, shape)
    if sides_c is None or sides_f is None:
        return up
    hc, wc = a.shape
    # side of a coarse cell = side of the fine cell at its upper-left corner (same geometry)
    rr = np.minimum(np.arange(hc) * 2, shape[0] - 1)
    cc = np.minimum(np.arange(wc) * 2, shape[1] - 1)
    lab_c = sides_f.labels[np.ix_(rr, cc)].copy()
    lab_c[sides_c.labels == sides_c.k - 1] = -1  # coarse breakline cells belong to no side
    out = up.copy()
    for lab, sl in enumerate(sides_f.slices[:-1]):
        if sl is None:
            continue
        c0 = max(sl[0].start // 2 - 2, 0), max(sl[1].start // 2 - 2, 0)
        c1 = min(sl[0].stop // 2 + 2, hc), min(sl[1].stop // 2 + 2, wc)
        sub_lab = lab_c[c0[0]:c1[0], c0[1]:c1[1]]
        have = sub_lab == lab
        if not have.any():
            continue
        sub = a[c0[0]:c1[0], c0[1]:c1[1]]
        if not have.all():  # other sides' cells take the nearest value of this side
            _, (ir, ic) = ndimage.distance_transform_edt(~have, return_indices=True)
            sub = sub[ir, ic]
        f0 = (2 * c0[0], 2 * c0[1])
        fine = upsample2(sub, (min(2 * c1[0], shape[0]) - f0[0],
                               min(2 * c1[1], shape[1]) - f0[1]))
        m = sides_f.labels[f0[0]:f0[0] + fine.shape[0], f0[1]:f0[1] + fine.shape[1]] == lab
        view = out[f0[0]:f0[0] + fine.shape[0], f0[1]:f0[1] + fine.shape[1]]
        view[m] = fine[m]
    return out


def level_grid(grid: Grid, level: int) -> Grid:
    f = 2 ** level
    t = grid.transform
    return Grid(Affine(t.a * f, t.b, t.c, t.d, t.e * f, t.f), -(-grid.width // f),
                -(-grid.height // f), grid.spacing * f)


def pyramid_levels(shape: Tuple[int, int], spacing: float, coarse_spacing: float) -> int:
    """Number of reductions: the first level whose cell reaches ``coarse_spacing``, keeping
    at least 8 cells along the shorter side."""
    n = 0
    while spacing * 2 ** n < coarse_spacing and min(shape) / 2 ** (n + 1) >= 8:
        n += 1
    return n


# -- ground points and tiles ---------------------------------------------------------------------
def cells_of(points: Array, grid: Grid) -> Tuple[Array, Array]:
    """Flat cell index (−1 outside) and heights of 3-D points on a grid."""
    pts = np.asarray(points, float).reshape(-1, 3)
    r, c = grid.cell_of(pts[:, 0], pts[:, 1]) if len(pts) else (np.zeros(0, int),) * 2
    return np.where(r >= 0, r * grid.width + c, -1), pts[:, 2]


def hard_grid(points: Array, grid: Grid) -> Array:
    """Mean height of the ground points per cell (NaN elsewhere)."""
    flat, z = cells_of(points, grid)
    out = np.full(grid.width * grid.height, np.nan, np.float32)
    ok = flat >= 0
    if ok.any():
        n = np.bincount(flat[ok], minlength=out.size)
        s = np.bincount(flat[ok], weights=z[ok], minlength=out.size)
        out = np.where(n > 0, s / np.maximum(n, 1), np.nan).astype(np.float32)
    return out.reshape(grid.shape)


def tile_offset(grid: Grid, sub: Grid) -> Tuple[int, int]:
    """(row, col) of a sub-grid's first cell in ``grid``."""
    t, u = grid.transform, sub.transform
    return round((u.f - t.f) / t.e), round((u.c - t.c) / t.a)


def terrain_slope(z: Array, spacing: float) -> float:
    """Median gradient magnitude (m/m) of the coarsest level: the slope allowance actually
    needed (the preset's ``slope`` is the least one), so one default serves steep terrain."""
    gy, gx = np.gradient(np.asarray(z, np.float64), spacing)
    g = np.hypot(gx, gy)
    g = g[np.isfinite(g)]
    return float(np.median(g)) if g.size else 0.0


def local_slope(z: Array, spacing: float) -> Array:
    """Gradient magnitude (m/m) per cell of a surface (central differences)."""
    gy, gx = np.gradient(np.asarray(z, np.float64), spacing)
    g = np.hypot(gx, gy)
    return np.where(np.isfinite(g), g, 0.0)


def reduce_scale(sc: Optional[Array]) -> Optional[Array]:
    """Noise scale of a coarse cell: the smallest of its block (the lowest cell is one of them)."""
    if sc is None:
        return None
    return np.nan_to_num(reduce_min(sc), nan=1.0).astype(np.float32)


def touches_border(mask: Array) -> Array:
    """Cells of the components of ``mask`` that touch the grid border."""
    lab, n = ndimage.label(mask)
    if n == 0:
        return np.zeros(mask.shape, bool)
    edge = np.unique(np.concatenate([lab[0], lab[-1], lab[:, 0], lab[:, -1]]))
    return np.isin(lab, edge[edge > 0])

__all__ = ["BreaklineSides", "breakline_sides", "cells_of", "hard_grid", "level_grid",
           "local_slope", "pyramid_levels", "reduce_lowest", "reduce_min", "reduce_scale",
           "terrain_slope", "tile_offset", "touches_border", "upsample2", "upsample_sides"]
