r"""Occlusion test for true orthophotos: object-space ray marching with empty-space skipping.

A surface point :math:`P = (X, Y, Z)` of an ortho cell is **occluded** in an image with
projection centre :math:`C` when the straight segment from :math:`P` to :math:`C` passes below
the DSM :math:`h(x, y)` somewhere. With the horizontal distance :math:`r = |C_{xy} - P_{xy}|`,
the unit horizontal direction :math:`u = (C_{xy} - P_{xy}) / r` and the rise per horizontal
metre :math:`g = (C_z - Z) / r`, the ray at horizontal distance :math:`s` is

.. math:: p(s) = P_{xy} + s\,u, \qquad z(s) = Z + g\,s ,

and the cell is occluded when :math:`h(p(s)) - z(s) > \tau` for some :math:`0 < s < r`
(:math:`\tau` a small tolerance against DSM noise). Nothing can block the ray once
:math:`z(s)` exceeds the highest DSM value :math:`h_{max}`, so the march ends at

.. math:: s_{max} = \min\!\Big(r,\; \frac{(h_{max} - Z)\,r}{C_z - Z}\Big)

— the familiar relief displacement :math:`\Delta R = h\,R/H` of the highest object; this is the
margin the DSM window around a tile needs (:func:`march_margin`).

**Why ray marching in object space and not a z-buffer.** A z-buffer (project every DSM cell
into the image, keep the nearest per pixel) is global in image space, leaves holes and false
occlusions where the DSM is sampled more coarsely or finely than the image (steep walls, the
classical "M-portion" artefacts), and needs the whole DSM of the footprint at once. Marching is
local to a tile plus the margin above, exact up to the marching step, and vectorises over all
cells of a tile.

**Empty-space skipping.** Marching every ray in steps of half a DSM cell would cost
:math:`s_{max}/\delta` samples per cell. Instead the DSM window is summarised by max filters
:math:`M_k` (the maximum over :math:`(2k+1)^2` cells). If at the current sample point (nearest
cell :math:`(i, j)`) :math:`M_k[i, j] \le z(s) + \tau`, every DSM value the bilinear surface uses
within a horizontal distance :math:`(k - 1.5)` cells is below the ray there — and the ray only
rises — so the march jumps that far at once. Only near obstacles does it take fine steps and
sample the DSM bilinearly. Open ground costs a handful of iterations per cell.

NaN (nodata) in the DSM never occludes.
"""

from __future__ import annotations

from typing import Optional, Sequence, Tuple

import numpy as np
from affine import Affine
from numpy.typing import ArrayLike, NDArray
from scipy.ndimage import maximum_filter

from ..raster.sample import bilinear_grid

Array = NDArray[np.float64]


def march_margin(z: ArrayLike, r: ArrayLike, centre_z: float, zmax: float) -> float:
    r"""Largest horizontal march :math:`s_{max} = \min(r, (h_{max} - Z)\,r / (C_z - Z))` (m).

    Parameters
    ----------
    z : array_like
        Heights of the cells' surface points (m); NaN ignored.
    r : array_like
        Their horizontal distances from the projection centre (m).
    centre_z : float
        Height of the projection centre (m).
    zmax : float
        Highest DSM value that could block a ray (m).
    """
    z = np.asarray(z, dtype=float)
    r = np.asarray(r, dtype=float)
    with np.errstate(invalid="ignore", divide="ignore"):
        s = np.minimum(r, np.clip(zmax - z, 0.0, None) * r / np.clip(centre_z - z, 1e-9, None))
    s = s[np.isfinite(s)]
    return float(s.max()) if s.size else 0.0


def _max_filters(dsm: Array, levels: Sequence[int]) -> Tuple[Tuple[int, Array], ...]:
    """Max filters of the DSM (NaN counts as −∞) for the skipping levels, largest first."""
    filled = np.where(np.isfinite(dsm), dsm, -np.inf)
    out = []
    for k in sorted({int(k) for k in levels if int(k) >= 2}, reverse=True):
        out.append((k, maximum_filter(filled, size=2 * k + 1, mode="nearest")))
    return tuple(out)


def nearest_valid_along(z: Array, valid: NDArray[np.bool_], axis: int, reverse: bool,
                        max_size: int) -> Tuple[Array, Array]:
    """Height of the nearest valid cell in one direction along ``axis`` (towards higher
    indices with ``reverse``, else towards lower ones) at most ``max_size`` cells away, and
    its distance in cells (0 on a valid cell; ``inf`` and a height of NaN where there is
    none).

    A running maximum of the valid cells' indices finds them for all cells in one pass.
    """
    n = valid.shape[axis]
    shape = [1, 1]
    shape[axis] = n
    idx = np.arange(n).reshape(shape)
    if reverse:  # scan the flipped array and map its indices back
        last = np.flip(np.maximum.accumulate(np.flip(np.where(valid, n - 1 - idx, -1), axis),
                                             axis=axis), axis)
        near = np.where(last >= 0, n - 1 - last, -1)
    else:
        near = np.maximum.accumulate(np.where(valid, idx, -1), axis=axis)
    found = (near >= 0) & (np.abs(idx - near) <= max_size)
    heights = np.take_along_axis(z, np.where(found, near, 0), axis=axis)
    return (np.where(found, heights, np.nan),
            np.where(found, np.abs(idx - near), np.inf).astype(np.float64))


def fill_from_below(dsm: ArrayLike, max_size: int) -> Array:
    """Fill the holes of a matched DSM from their low side.

    A matcher leaves the ground behind a wall empty: one camera cannot see it. For a true
    ortho that ground still needs a height, so that the occlusion test can find it hidden.
    Such holes often run round a building as a ring (the occlusions of both images and the
    eroded wall edges), so they are judged locally, not as a whole: every hole cell looks for
    the nearest valid cell in the four axis directions (up to ``max_size`` cells away) and
    takes the lowest of those it finds — the ground beyond the hole, not the roof on its
    other side; a hole inside a roof finds the roof all round and keeps its height. A cell is
    filled only when it is enclosed (a valid cell found on both sides along one axis), so the
    DSM is never extended beyond its outer border.

    Parameters
    ----------
    dsm : array_like, shape (rows, cols)
        Heights, NaN = hole.
    max_size : int
        Farthest a hole cell looks for valid cells (cells). The result at a cell depends only
        on the cells within ``max_size`` along its row and column, so a window that reaches
        ``max_size`` cells beyond the cells of interest fills them the same whatever the
        window.

    Returns
    -------
    ndarray
        A filled copy (float64).
    """
    z = np.array(dsm, dtype=float)
    hole = ~np.isfinite(z)
    if not hole.any() or hole.all() or max_size < 1:
        return z
    valid = ~hole
    low = np.full(z.shape, np.inf)
    found = []
    for axis in (0, 1):
        for reverse in (False, True):
            heights, dist = nearest_valid_along(z, valid, axis, reverse, max_size)
            ok = np.isfinite(dist)
            low = np.where(ok, np.minimum(low, heights), low)
            found.append(ok)
    # enclosed: valid cells on both sides along a column or a row
    fill = hole & ((found[0] & found[1]) | (found[2] & found[3]))
    z[fill] = low[fill]
    return z


def occluded(
    x: ArrayLike,
    y: ArrayLike,
    z: ArrayLike,
    centre: ArrayLike,
    dsm: ArrayLike,
    transform: Affine,
    *,
    step: Optional[float] = None,
    tolerance: Optional[float] = None,
    levels: Sequence[int] = (32, 8, 3),
) -> NDArray[np.bool_]:
    """Which surface points are hidden from the projection centre by the DSM.

    Parameters
    ----------
    x, y, z : array_like
        Surface points (same shape), e.g. the cell centres of an ortho tile with their DEM
        heights. NaN heights give ``False``.
    centre : array_like, shape (3,)
        Projection centre (m).
    dsm : array_like, shape (rows, cols)
        DSM window (NaN = nodata) that covers the points plus :func:`march_margin` towards the
        nadir; rays that leave it count as unobstructed.
    transform : affine.Affine
        Geotransform of ``dsm`` (north-up, no rotation).
    step : float, optional
        Fine marching step (m, horizontal); default half a DSM cell.
    tolerance : float, optional
        The DSM must rise more than this above the ray to occlude (m); default one DSM cell
        (keeps noise in matched DSMs from punching holes, far below building heights).
    levels : sequence of int
        Half-widths (cells) of the max filters used to skip empty space.

    Returns
    -------
    ndarray of bool
        ``True`` where the point is occluded.
    """
    X = np.asarray(x, dtype=float)
    Y = np.asarray(y, dtype=float)
    Z = np.asarray(z, dtype=float)
    shape = np.broadcast_shapes(X.shape, Y.shape, Z.shape)
    X, Y, Z = (np.broadcast_to(a, shape).ravel() for a in (X, Y, Z))
    C = np.asarray(centre, dtype=float).reshape(3)
    a = np.asarray(dsm, dtype=float)
    if transform.b != 0.0 or transform.d != 0.0:
        raise ValueError("the occlusion test needs a north-up DSM window (no rotation)")
    cell_x, cell_y = abs(transform.a), abs(transform.e)
    cell = min(cell_x, cell_y)
    step = 0.5 * cell if step is None else float(step)
    tol = cell if tolerance is None else float(tolerance)
    result = np.zeros(X.size, dtype=bool)
    if X.size == 0 or not np.isfinite(a).any():
        return result.reshape(shape)
    zmax = float(np.nanmax(a))
    filters = _max_filters(a, levels)
    inv = ~transform
    nrows, ncols = a.shape

    dx, dy = C[0] - X, C[1] - Y
    r = np.hypot(dx, dy)
    with np.errstate(invalid="ignore", divide="ignore"):
        ux, uy = dx / r, dy / r
        g = (C[2] - Z) / r
        # end of the march: the ray is above every DSM value, or at the nadir
        s_end = np.minimum(r, (zmax + tol - Z) / g)
    active = np.flatnonzero(np.isfinite(Z) & (r > 1e-6) & (g > 0) & (s_end > step))
    s = np.full(active.size, step)
    ux, uy, g, s_end = ux[active], uy[active], g[active], s_end[active]
    X0, Y0, Z0 = X[active], Y[active], Z[active]
    while active.size:
        px = X0 + s * ux
        py = Y0 + s * uy
        zr = Z0 + s * g
        colf = inv.a * px + inv.b * py + inv.c - 0.5  # cell centres at integers
        rowf = inv.d * px + inv.e * py + inv.f - 0.5
        ci = np.rint(colf).astype(np.intp)
        ri = np.rint(rowf).astype(np.intp)
        inside = (ci >= 0) & (ci < ncols) & (ri >= 0) & (ri < nrows)
        ci = np.where(inside, ci, 0)
        ri = np.where(inside, ri, 0)
        jump = np.zeros(active.size)
        for k, mk in filters:  # largest safe jump first
            safe = (jump == 0.0) & (mk[ri, ci] <= zr + tol)
            jump = np.where(safe, (k - 1.5) * cell, jump)
        fine = inside & (jump == 0.0)
        blocked = np.zeros(active.size, dtype=bool)
        if fine.any():
            h = bilinear_grid(a, colf[fine], rowf[fine])
            blocked[fine] = h - zr[fine] > tol  # NaN compares False: nodata never occludes
        result[active[blocked]] = True
        s = s + np.where(jump > 0.0, np.maximum(jump, step), step)
        keep = inside & ~blocked & (s < s_end)
        active, s = active[keep], s[keep]
        ux, uy, g, s_end = ux[keep], uy[keep], g[keep], s_end[keep]
        X0, Y0, Z0 = X0[keep], Y0[keep], Z0[keep]
    return result.reshape(shape)


__all__ = ["fill_from_below", "march_margin", "nearest_valid_along", "occluded"]
