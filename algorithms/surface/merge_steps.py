r"""Per-cell merge rules of :mod:`.merge` that keep walls (issue 19).

A plain median of two DSMs, or a mean of any number, puts a cell where one input has the roof
and another the ground (a wall placed a cell or two apart, a roof edge one matcher eroded) at
a height between them: neither the roof nor the ground, and the step is smeared over the cells
where the inputs disagree. Here a cell whose candidate heights spread over more than ``step``
is split into populations:

* sort the candidates; a gap of more than ``step`` between neighbours starts a new population;
* keep the population with the most candidates; on a tie, the one whose median is closest to
  a *local reference*, the median of all inputs' heights in the
  :math:`(2r+1)^2` neighbourhood (:data:`REF_RADIUS`), pooled; on a tie there, the upper
  one (a DSM keeps its objects);
* combine that population with the mode (median or mean); a plain median that lies inside
  the kept population is kept as it is (so where one population holds the majority, the
  median does not change).

Between a wall of one input and the same wall shifted by :math:`s` cells in another, the
neighbourhood votes put the merged wall in between (within :math:`\lceil s/2\rceil` cells of
both), as a step, without intermediate heights. Cells whose candidates agree within ``step``
(open terrain) are merged exactly as before.

Resampling an input that is not on the output grid bilinearly also puts heights between roof
and ground on the cells that straddle a wall; :func:`step_aware` takes the nearest input cell
there instead (where bilinear and nearest differ by more than ``step / 2``) and keeps the
bilinear value everywhere else (slopes).
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view
from numpy.typing import NDArray

Array = NDArray[Any]

#: Height spread (m) above which the candidates of a cell are treated as two surfaces.
STEP_M = 1.0
#: Radius (cells) of the neighbourhood whose pooled median breaks ties between populations.
REF_RADIUS = 2


def step_aware(bilinear: Array, nearest: Array, step: float) -> Array:
    """Bilinear heights, but the nearest input cell where the two differ by > ``step / 2``.

    Parameters
    ----------
    bilinear, nearest : ndarray
        The same input resampled both ways onto the same window (NaN = no height).
    step : float
        Height difference (m) that counts as a step; ≤ 0 keeps the bilinear heights.

    Returns
    -------
    ndarray
        float32 heights (NaN where the bilinear resampling has none).
    """
    if not step > 0:
        return bilinear
    jump = np.isfinite(nearest) & ~(np.abs(bilinear - nearest) <= 0.5 * step)
    jump &= np.isfinite(bilinear)
    return np.where(jump, nearest, bilinear).astype(np.float32)


def local_reference(stack: Array, rows: Array, cols: Array, radius: int = REF_RADIUS) -> Array:
    """Median of all inputs' heights in the neighbourhood of the given cells (pooled).

    Parameters
    ----------
    stack : ndarray (k, h, w)
        Heights of the inputs (NaN = none).
    rows, cols : ndarray of int
        Cells to evaluate.
    radius : int
        Neighbourhood radius in cells; the stack is padded with NaN at its border.

    Returns
    -------
    ndarray
        One float64 reference height per cell (NaN where the neighbourhood has none).
    """
    k = stack.shape[0]
    pad = np.pad(stack, ((0, 0), (radius, radius), (radius, radius)), constant_values=np.nan)
    win = sliding_window_view(pad, (2 * radius + 1, 2 * radius + 1), axis=(1, 2))
    vals = win[:, rows, cols].transpose(1, 0, 2, 3).reshape(rows.size, k * (2 * radius + 1) ** 2)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        return np.nanmedian(vals.astype(np.float64), axis=1)


def _populations(vals: Array, step: float) -> Array:
    """Population label per sorted candidate (columns = cells; NaN sorted last, label −1)."""
    ok = np.isfinite(vals)
    gap = np.zeros(vals.shape, bool)
    gap[1:] = ~(np.diff(vals, axis=0) <= step) & ok[1:]
    labels = np.cumsum(gap, axis=0)
    return np.where(ok, labels, -1)


def _choose(vals: Array, labels: Array, ref: Array) -> Array:
    """Label of the population to keep per cell: most candidates, then closest to ``ref``,
    then the upper one."""
    k, n = vals.shape
    best = np.zeros(n, int)
    best_key = np.full((n, 2), -np.inf)  # (count, −distance to the reference)
    for j in range(k):
        member = labels == j
        cnt = member.sum(axis=0).astype(float)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            med = np.nanmedian(np.where(member, vals, np.nan), axis=0)
        dist = np.abs(med - ref)
        dist = np.where(np.isfinite(dist), dist, np.inf)
        key_c, key_d = cnt, -dist
        # later labels are higher populations: ≥ on a full tie prefers the upper one
        better = (cnt > 0) & ((key_c > best_key[:, 0])
                              | ((key_c == best_key[:, 0]) & (key_d >= best_key[:, 1])))
        best = np.where(better, j, best)
        best_key[better, 0] = key_c[better]
        best_key[better, 1] = key_d[better]
    return best


def combine_keeping_steps(stack: Array, mode: str, plain: Array, step: float,
                          halo: int = 0) -> Array:
    """Merged heights of a (k, h, w) stack that do not average across a step.

    Parameters
    ----------
    stack : ndarray (k, h, w)
        Heights of the inputs on the window plus ``halo`` cells on every side.
    mode : {"median", "mean"}
        How a kept population is combined.
    plain : ndarray (h − 2·halo, w − 2·halo)
        The plain merge of the core (used where the candidates agree within ``step``).
    step : float
        Spread (m) above which a cell's candidates are split into populations; ≤ 0 = off.
    halo : int
        Cells of context around the core in ``stack`` (for the local reference).

    Returns
    -------
    ndarray
        float32 merged heights of the core.
    """
    if not step > 0 or stack.shape[0] < 2:
        return plain
    h, w = plain.shape
    core = stack[:, halo:halo + h, halo:halo + w]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        spread = np.nanmax(core, axis=0) - np.nanmin(core, axis=0)
    rr, cc = np.nonzero(spread > step)
    if rr.size == 0:
        return plain
    vals = np.sort(core[:, rr, cc].astype(np.float64), axis=0)  # NaN last
    labels = _populations(vals, step)
    ref = local_reference(stack, rr + halo, cc + halo)
    keep = labels == _choose(vals, labels, ref)[None, :]
    sel = np.where(keep, vals, np.nan)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        z = np.nanmean(sel, axis=0) if mode == "mean" else np.nanmedian(sel, axis=0)
        if mode != "mean":  # a plain median inside the kept population stays (majorities)
            p = plain[rr, cc]
            inside = (p >= np.nanmin(sel, axis=0)) & (p <= np.nanmax(sel, axis=0))
            z = np.where(inside, p, z)
    out = plain.copy()
    out[rr, cc] = z.astype(np.float32)
    return out


__all__ = ["REF_RADIUS", "STEP_M", "combine_keeping_steps", "local_reference", "step_aware"]
