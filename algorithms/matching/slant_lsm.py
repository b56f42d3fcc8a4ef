r"""Least-squares refinement of the slant passes' disparities (issue 22, part X).

A slant pass (:func:`.dense_model.stretched_source`) matches the left epipolar image against
the right one stretched linearly along its rows by ``s``; on a slope whose true scale
``∂x_r/∂x_l`` is not ``1/s`` its disparities are those of a window compared at the wrong
scale. Affine least-squares matching (:func:`.lsm.lsm_match`, ``model="epipolar"``: shift,
x-scale and shear along the row, contrast and brightness) between the *original* left and
right epipolar images estimates that scale itself. Each disparity is started at the slant
pass's value with ``1/s`` as the start of the x-scale, and kept only where LSM converges,
moves at most :data:`SLANT_LSM_SHIFT` px from its start, ends with a correlation of at least
:data:`SLANT_LSM_CORR` and a shift precision within the LSM default, and neither window
touches masked pixels.

The images are read through :data:`.dense.GreySource` readers over the bounding box of the
given points (one matching tile's worth), so memory stays bounded by the tile.
"""

from __future__ import annotations

from typing import Tuple

import numpy as np
from numpy.typing import ArrayLike

from .dense import GreySource
from .fbm import fill_nodata
from .lsm import lsm_match

#: LSM window side (px) of the refinement.
SLANT_LSM_WINDOW = 11
#: Smallest correlation coefficient of a kept refinement.
SLANT_LSM_CORR = 0.8
#: Largest move (px) of a kept refinement from the slant pass's disparity.
SLANT_LSM_SHIFT = 1.0
#: Points refined together (bounds the memory of :func:`.lsm.lsm_match`'s results).
CHUNK_POINTS = 20000
#: Plausible x-scales of the affine (a slope seen at a grazing angle reaches 0.2–1.9).
_SCALE_RANGE = (0.25, 4.0)


def _box_sums(mask: np.ndarray) -> np.ndarray:
    """Summed-area table of a boolean mask with a leading zero row and column."""
    table = np.zeros((mask.shape[0] + 1, mask.shape[1] + 1), np.int64)
    table[1:, 1:] = np.cumsum(np.cumsum(mask, axis=0), axis=1)
    return table


def _any_in_box(table: np.ndarray, c0: np.ndarray, c1: np.ndarray, r0: np.ndarray,
                r1: np.ndarray) -> np.ndarray:
    """Whether the mask behind ``table`` has a set pixel in columns ``[c0, c1)`` and rows
    ``[r0, r1)`` (integer arrays, clipped to the mask)."""
    h, w = table.shape[0] - 1, table.shape[1] - 1
    c0, c1 = np.clip(c0, 0, w), np.clip(c1, 0, w)
    r0, r1 = np.clip(r0, 0, h), np.clip(r1, 0, h)
    total = table[r1, c1] - table[r0, c1] - table[r1, c0] + table[r0, c0]
    return total > 0


def _read(source: GreySource, r0: int, r1: int, c0: int, c1: int
          ) -> Tuple[np.ndarray, np.ndarray]:
    """A window of a grey source with its masked pixels filled from their nearest valid pixel
    (LSM needs finite values) and the summed-area table of the mask."""
    block, valid = fill_nodata(source(r0, r1, c0, c1))
    return block, _box_sums(~valid)


def _refine_chunk(left: GreySource, right: GreySource, d: np.ndarray, cols: np.ndarray,
                  rows: np.ndarray, scale: np.ndarray, shear: np.ndarray, window: int,
                  min_corr: float, max_shift: float) -> Tuple[np.ndarray, np.ndarray]:
    """:func:`refine_slant` for one chunk of points, on the windows of their bounding box."""
    n = d.size
    half = window // 2
    reach = half + 2  # the template takes one pixel more for its gradients
    x_r = cols - d
    # rows as the left; columns: every start's window at the largest plausible x-scale
    r0, r1 = int(rows.min()) - reach, int(rows.max()) + reach + 1
    lc0, lc1 = int(cols.min()) - reach, int(cols.max()) + reach + 1
    span = int(np.ceil(_SCALE_RANGE[1] * reach + max_shift)) + 2
    rc0, rc1 = int(np.floor(x_r.min())) - span, int(np.ceil(x_r.max())) + span + 1
    tpl, tpl_masked = _read(left, r0, r1, lc0, lc1)
    srch, srch_masked = _read(right, r0, r1, rc0, rc1)
    start = np.zeros((n, 8))
    start[:, 0] = x_r - rc0
    start[:, 1] = 1.0 / scale
    start[:, 2] = shear
    start[:, 3] = rows - r0
    start[:, 5] = start[:, 7] = 1.0
    res = lsm_match(tpl, srch, cols - lc0, rows - r0, None, window=window, model="epipolar",
                    init_params=start, max_shift=max_shift, min_corr=min_corr,
                    scale_range=_SCALE_RANGE)
    keep = res.valid.copy()
    # neither window may hold a masked pixel (their grey values were made up)
    tr = rows - r0
    keep &= ~_any_in_box(tpl_masked, cols - lc0 - half, cols - lc0 + half + 1,
                         tr - half, tr + half + 1)
    ext = half * (np.abs(res.params[:, 1]) + np.abs(res.params[:, 2]))
    lo = np.floor(np.nan_to_num(res.cols - ext, nan=0.0)).astype(np.int64)
    hi = np.ceil(np.nan_to_num(res.cols + ext, nan=0.0)).astype(np.int64) + 2
    keep &= ~_any_in_box(srch_masked, lo, hi, tr - half, tr + half + 1)
    return cols - (res.cols + rc0), keep


def refine_slant(left: GreySource, right: GreySource, d: np.ndarray, cols: np.ndarray,
                 rows: np.ndarray, scale: ArrayLike, window: int = SLANT_LSM_WINDOW,
                 min_corr: float = SLANT_LSM_CORR, max_shift: float = SLANT_LSM_SHIFT,
                 shear: ArrayLike = 0.0) -> Tuple[np.ndarray, np.ndarray]:
    """LSM refinement of disparities found against the right image stretched by ``scale``.

    Points are refined in chunks of :data:`CHUNK_POINTS` in the given order (row by row from
    a tile, so a chunk's windows are a band of rows).

    Parameters
    ----------
    left, right : GreySource
        Readers of the original left and right epipolar images (NaN = masked).
    d : ndarray
        Disparities of the pair, ``x_l − x_r`` (px; already unstretched).
    cols, rows : ndarray
        Their left pixels (integers).
    scale : float or ndarray
        The stretch of the pass: the start of the x-scale is ``1 / scale`` (one per point, or
        one for all).
    window : int
        LSM window side (odd).
    min_corr : float
        Smallest correlation coefficient kept.
    max_shift : float
        Largest move (px) from the start that is kept.
    shear : float or ndarray
        Start of the shear along the row, ``∂x_r/∂y`` (px per row; default 0): a slope
        across the base moves the right image's rows against each other.

    Returns
    -------
    d, keep : ndarray
        Refined disparities and the points kept.
    """
    d = np.asarray(d, np.float64)
    cols = np.asarray(cols, np.int64)
    rows = np.asarray(rows, np.int64)
    scale = np.broadcast_to(np.asarray(scale, np.float64), d.shape)
    shear = np.broadcast_to(np.asarray(shear, np.float64), d.shape)
    out = np.full(d.size, np.nan)
    keep = np.zeros(d.size, bool)
    for i in range(0, d.size, CHUNK_POINTS):
        sl = slice(i, i + CHUNK_POINTS)
        out[sl], keep[sl] = _refine_chunk(left, right, d[sl], cols[sl], rows[sl], scale[sl],
                                          shear[sl], window, min_corr, max_shift)
    return out, keep


__all__ = ["SLANT_LSM_CORR", "SLANT_LSM_SHIFT", "SLANT_LSM_WINDOW", "refine_slant"]
