r"""The DSM-guided pass of dense matching on convergent models (issue 22, part AD).

Why
---
Slopes that run *across* the base of a convergent pair (embankment faces, ditch sides seen at
a grazing angle by one camera) change their disparity by more than a pixel from one epipolar
row to the next. SGM charges its large-step penalty on every row of such a slope, so it
fronto-parallelises it: on the 19° drone pair 0202_0203 (seed 1) a 13 × 19 m embankment face
came out 3–17 px too high and was dropped by the outlier test, and 27–39 % of the visible
cells of the four drone models that no pass measured lie on such continuous slopes
(:math:`|\partial d/\partial y| > 0.5` px per row). The slant passes stretch the right image
along its rows and cannot undo a shear between rows.

What
----
The first DSM of the model knows the terrain around such holes. Its measured cells,
interpolated over the holes by a membrane (:func:`~..surface.gridding.fill_gaps`), are
projected into the left epipolar image (:func:`dsm_guide`: the median disparity of the cells
that fall into a pixel, so that one cell too high at a crest does not hide a slope seen at a
grazing angle). The plain pass is then matched once more as the refinement of
:func:`.dense._refine_frame`: SGM within ± ``refine`` px of that guide against the right image
warped by it, which takes out the slope's scale *and* shear. A hole of the first pass takes a
refined disparity only where independent evidence confirms it (:func:`verified_holes`):

- least-squares matching between the *unwarped* images (:func:`.slant_lsm.refine_slant`,
  x-scale and shear started from the guide's slope) converges within 1 px with a correlation
  of at least 0.8;
- the match is unique along the row: no other shift within ± :data:`UNIQUE_REACH` px of the
  warped right image correlates with the left window to :data:`UNIQUE_RATIO` × the best
  (:func:`unique_along_rows`). Without this test striped roofs, whose stripes repeat along
  the row, were matched a period off where the guide ran under an unmeasured roof: on the
  47° pair 0101_0103, 1026 building cells came out at ground height.
"""

from __future__ import annotations

from typing import Any, Optional, Tuple

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view
from numpy.typing import NDArray
from scipy import ndimage

from ..geometry.epipolar import EpipolarPair
from ..surface.gridding import Grid, fill_gaps
from .dense import array_source
from .ncc import gather_windows, ncc_surface
from .slant_lsm import refine_slant

Array = NDArray[Any]

#: Half range (px) of the shifts along the row over which a verified match must be unique.
UNIQUE_REACH = 40
#: A second shift (≥ 3 px from the match) correlating to this share of the best is ambiguous.
UNIQUE_RATIO = 0.97
#: Window side (px) of the uniqueness correlation.
UNIQUE_WINDOW = 9
#: Points whose correlation profiles are computed together (bounds the memory).
UNIQUE_CHUNK = 4096
#: Median filter (px) of the guide, which removes the specks of single blunder cells.
GUIDE_SMOOTH = 5
#: Largest gap (cells) interpolated into the guide; beyond it the nearest guide value.
GUIDE_GAP_CELLS = 200
#: Distance (cells) within which two border cells of a hole must agree (:func:`terrain_holes`).
RING_REACH = 2


def terrain_holes(z: Array, measured: Array, area: Array, step: float) -> Array:
    """Cells of the holes of a DSM whose border is one surface.

    A hole is a connected (8-neighbour) set of unmeasured cells of ``area``; its border are
    the measured cells next to it. Where two border cells within :data:`RING_REACH` cells of
    each other differ by more than ``step`` (m), or the sorted heights of the border leave a
    gap of more than ``step`` (a measured speck on an unmeasured roof), the border jumps
    between two surfaces — a roof or a crown and the ground beside it — and a membrane over
    the hole says nothing about what fills it. Holes whose border runs over one surface (a
    slope from its crest round to its toe, a field between two measured patches) are
    returned.
    """
    holes = area & ~measured
    labels, _ = ndimage.label(holes, structure=np.ones((3, 3), bool))
    out = np.zeros(holes.shape, bool)
    h, w = holes.shape
    pad = RING_REACH + 1
    size = 2 * RING_REACH + 1
    for i, box in enumerate(ndimage.find_objects(labels), start=1):
        if box is None:
            continue
        r0, r1 = max(box[0].start - pad, 0), min(box[0].stop + pad, h)
        c0, c1 = max(box[1].start - pad, 0), min(box[1].stop + pad, w)
        comp = labels[r0:r1, c0:c1] == i
        ring = ndimage.binary_dilation(comp, np.ones((3, 3), bool)) & measured[r0:r1, c0:c1]
        if not ring.any():
            continue
        zr = z[r0:r1, c0:c1]
        high = ndimage.maximum_filter(np.where(ring, zr, -np.inf), size=size)
        low = ndimage.minimum_filter(np.where(ring, zr, np.inf), size=size)
        heights = np.sort(zr[ring])
        jump = (high - low)[ring].max()
        if heights.size > 1:  # a measured speck on an unmeasured roof: far from the rest
            jump = max(jump, float(np.diff(heights).max()))
        if not jump > step:
            out[r0:r1, c0:c1] |= comp
    return out


def dsm_guide(pair: EpipolarPair, z: Array, measured: Array, grid: Grid,
              trusted: Optional[Array] = None) -> Array:
    """Disparities of the left epipolar image from a DSM: the guide of the guided pass.

    Parameters
    ----------
    pair : EpipolarPair
        The model's epipolar pair.
    z : ndarray (h, w)
        DSM heights on ``grid`` (NaN = empty).
    measured : ndarray of bool
        Cells whose height was measured (interpolated cells are not trusted).
    grid : Grid
        The DSM's grid.
    trusted : ndarray of bool, optional
        Cells whose guide may give a hole a new disparity (e.g. the measured cells and the
        :func:`terrain_holes`); default all.

    Returns
    -------
    ndarray (height, width of the left epipolar image), float32
        The median disparity of the cells (membrane-filled over holes up to
        :data:`GUIDE_GAP_CELLS` cells) that fall into each pixel; pixels no cell reaches take
        the nearest pixel's value; then a median over :data:`GUIDE_SMOOTH` px. NaN where the
        median cell is not ``trusted`` (and everywhere without a measured cell).
    """
    h, w = pair.height, pair.sizes[0][0]
    zm = np.where(measured, z, np.nan).astype(np.float32)
    if not np.isfinite(zm).any():
        return np.full((h, w), np.nan, np.float32)
    filled, _ = fill_gaps(zm, grid.spacing, GUIDE_GAP_CELLS * grid.spacing)
    trust_cells = np.ones(filled.shape, bool) if trusted is None else trusted
    rows, cols = np.nonzero(np.isfinite(filled))
    xs, ys = grid.transform * (cols + 0.5, rows + 0.5)
    pts = np.column_stack([xs, ys, filled[rows, cols]])
    c_l, r_l = pair.world_to_epipolar(pts, "left")
    c_r, _ = pair.world_to_epipolar(pts, "right")
    ci, ri = np.rint(c_l).astype(np.int64), np.rint(r_l).astype(np.int64)
    inside = (ci >= 0) & (ci < w) & (ri >= 0) & (ri < h) & np.isfinite(c_r)
    key, d = ri[inside] * w + ci[inside], (c_l - c_r)[inside]
    ok = trust_cells[rows, cols][inside]
    guide = np.full(h * w, np.nan, np.float32)
    trust = np.zeros(h * w, bool)
    if key.size:
        order = np.lexsort((d, key))
        key, d, ok = key[order], d[order], ok[order]
        first = np.flatnonzero(np.r_[True, key[1:] != key[:-1]])
        mid = (first + np.r_[first[1:], key.size] - 1) // 2
        guide[key[first]] = d[mid]
        trust[key[first]] = ok[mid]
    guide, trust = guide.reshape(h, w), trust.reshape(h, w)
    have = np.isfinite(guide)
    if not have.any():
        return guide
    _, (nr, nc) = ndimage.distance_transform_edt(~have, return_indices=True)
    out = ndimage.median_filter(guide[nr, nc], size=GUIDE_SMOOTH, mode="nearest")
    out[~trust[nr, nc]] = np.nan
    return out


def unique_along_rows(left: Array, warped: Array, rows: Array, cols: Array, residual: Array,
                      reach: int = UNIQUE_REACH, window: int = UNIQUE_WINDOW,
                      ratio: float = UNIQUE_RATIO) -> Array:
    """Whether the matches at left pixels (``rows``, ``cols``) are unique along their rows.

    ``warped`` is the right frame warped by the guide (:func:`.dense._warp_rows`), so that
    the match of a left pixel lies at the residual shift ``residual``. The normalised
    cross-correlation of the left window with the warped window at every integer shift
    within ± ``reach`` px gives a profile (:func:`.ncc.ncc_surface` of each left window over
    its row of the warped frame); a match is unique where its best correlation within 1 px
    of ``residual`` is positive and no shift 3 px or more away reaches ``ratio`` × that.
    Windows touching masked pixels or the frame's edge count as −1.
    """
    half = window // 2
    pad = reach + half  # NaN beyond the frame: windows reaching out of it are masked
    lp = np.pad(np.asarray(left, np.float32), half, constant_values=np.nan)
    wp = np.pad(np.asarray(warped, np.float32), ((half, half), (pad, pad)),
                constant_values=np.nan)
    shifts = np.arange(-reach, reach + 1)
    profile = np.full((rows.size, shifts.size), -1.0)
    for i in range(0, rows.size, UNIQUE_CHUNK):
        r, c = rows[i:i + UNIQUE_CHUNK], cols[i:i + UNIQUE_CHUNK]
        tpl = gather_windows(lp, r, c, window, window)
        srch = gather_windows(wp, r, c, window, window + 2 * reach)
        masked = ~np.isfinite(srch)
        rho = ncc_surface(np.nan_to_num(tpl), np.where(masked, 0.0, srch))[:, 0]
        touched = sliding_window_view(masked, window, axis=2).any(axis=(1, 3))
        touched |= ~np.isfinite(tpl).all(axis=(1, 2))[:, None] | ~np.isfinite(rho)
        # surface column j is the window centred on the warped column x − reach + j: shift
        # reach − j
        profile[i:i + UNIQUE_CHUNK] = np.where(touched, -1.0, rho)[:, ::-1]
    dist = np.abs(shifts[None, :] - np.asarray(residual, np.float64)[:, None])
    best = np.where(dist <= 1.0, profile, -1.0).max(axis=1)
    other = np.where(dist >= 3.0, profile, -1.0).max(axis=1)
    return (best > 0.0) & (other < ratio * best)


def verified_holes(left: Array, right: Array, guide: Array, residual: Array, refined: Array,
                   holes: Array, warped: Array) -> Tuple[Array, Array]:
    """The refined disparities of the first pass's holes that independent evidence confirms.

    Parameters
    ----------
    left, right : ndarray
        The matching frame's left and right grey values (NaN = masked; common columns:
        left pixel ``x`` ↔ right pixel ``x − d``).
    guide, residual, refined : ndarray
        The guide, the residual disparities against the warped right frame and their sum
        (after the border filters).
    holes : ndarray of bool
        Pixels the first pass left without a disparity.
    warped : ndarray
        The right frame warped by the guide.

    Returns
    -------
    d, take : ndarray
        ``refined`` with the verified holes replaced by their LSM disparities, and the
        verified holes.
    """
    take = holes & np.isfinite(refined) & np.isfinite(residual)
    rows, cols = np.nonzero(take)
    if not rows.size:
        return refined, take
    ok = unique_along_rows(left, warped, rows, cols, residual[rows, cols], UNIQUE_REACH,
                           UNIQUE_WINDOW, UNIQUE_RATIO)
    rows, cols = rows[ok], cols[ok]
    # the slope the guide knows is the start of the affine: x_r = x − g(x, y)
    g_y, g_x = np.gradient(guide.astype(np.float64))
    scale = 1.0 / np.clip(1.0 - g_x[rows, cols], 0.3, 3.0)  # refine_slant starts at 1/scale
    src_l, _ = array_source(left)
    src_r, _ = array_source(right)
    d, keep = refine_slant(src_l, src_r, refined[rows, cols], cols, rows, scale,
                           shear=-g_y[rows, cols])
    out = refined.copy()
    out[rows[keep], cols[keep]] = d[keep]
    verified = np.zeros_like(take)
    verified[rows[keep], cols[keep]] = True
    return out, verified


__all__ = ["dsm_guide", "terrain_holes", "unique_along_rows", "verified_holes"]
