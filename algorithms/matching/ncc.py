r"""Normalised cross-correlation of many templates against search ranges, batched.

For a template g' (window × window pixels of the left image) and every candidate position of the
same-sized window g'' in the right image

.. math:: \rho = \frac{\sum (g' - \bar g')(g'' - \bar g'')}
                    {\sqrt{\sum (g' - \bar g')^2 \sum (g'' - \bar g'')^2}}, \quad -1 \le \rho \le 1

(seed-000 §2.7, seed-002 A3.1). The maximum is refined to sub-pixel by a parabola through the
peak and its two neighbours, per axis: :math:`\delta = (\rho_{-} - \rho_{+}) /
(2(\rho_{-} - 2\rho_0 + \rho_{+}))`. The ambiguity is the ratio of the second-highest local
maximum to the peak (1 = two equally good matches).

Two forms: :func:`ncc_epipolar` searches a disparity range along the same row of epipolar
images (disparity = left col − right col, as everywhere in PhotoDEM); :func:`ncc_search_2d`
searches a square neighbourhood of a predicted position. Templates are cut at the rounded point
positions; the fractional part of a point is carried over to the result (a pure shift model).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view
from numpy.typing import ArrayLike, NDArray
from scipy import ndimage


class NCCResult(NamedTuple):
    """Result of an NCC search for n points.

    Attributes
    ----------
    cols, rows : float64
        Matched sub-pixel position in the right image (NaN when no peak was found).
    disparity : float64
        Left col − right col (epipolar search; for 2-D searches the same difference).
    ncc : float32
        Peak correlation coefficient (integer position).
    ratio : float32
        Second-highest local maximum / peak (ambiguity; small is good).
    valid : bool
        Peak found inside the range (not on its border), ncc ≥ min_ncc, ratio ≤ max_ratio.
    """

    cols: NDArray
    rows: NDArray
    disparity: NDArray
    ncc: NDArray
    ratio: NDArray
    valid: NDArray


def gather_windows(image: NDArray, row0: NDArray, col0: NDArray, h: int, w: int) -> NDArray:
    """Windows image[row0:row0+h, col0:col0+w] for many points (clipped at the edges)."""
    rr = np.clip(row0[:, None, None] + np.arange(h)[None, :, None], 0, image.shape[0] - 1)
    cc = np.clip(col0[:, None, None] + np.arange(w)[None, None, :], 0, image.shape[1] - 1)
    return image[rr, cc]


def ncc_surface(templates: NDArray, searches: NDArray) -> NDArray:
    """NCC of each template at every position inside its search window.

    Parameters
    ----------
    templates : (n, th, tw) array
    searches : (n, sh, sw) array with sh ≥ th, sw ≥ tw

    Returns
    -------
    (n, sh − th + 1, sw − tw + 1) float32; NaN where a window has no contrast.
    """
    t = np.asarray(templates, dtype=np.float32)
    s = np.asarray(searches, dtype=np.float32)
    n, th, tw = t.shape
    m = th * tw
    tz = t - t.mean(axis=(1, 2), keepdims=True)
    t_ss = np.einsum("nij,nij->n", tz, tz, dtype=np.float64)
    # remove the search window's overall mean (keeps the float32 sums well conditioned)
    s = s - s.mean(axis=(1, 2), keepdims=True)
    view = sliding_window_view(s, (th, tw), axis=(1, 2))  # (n, ry, rx, th, tw), no copy
    num = np.einsum("nyxij,nij->nyx", view, tz)
    # window sums of s and s² by integral images (float64)
    s64 = s.astype(np.float64)
    ii = np.zeros((n, s.shape[1] + 1, s.shape[2] + 1))
    ii2 = np.zeros_like(ii)
    ii[:, 1:, 1:] = s64.cumsum(1).cumsum(2)
    ii2[:, 1:, 1:] = (s64 * s64).cumsum(1).cumsum(2)

    def box(a):
        return a[:, th:, tw:] - a[:, :-th, tw:] - a[:, th:, :-tw] + a[:, :-th, :-tw]

    s_sum, s_sq = box(ii), box(ii2)
    s_ss = np.maximum(s_sq - s_sum * s_sum / m, 0.0)
    den = np.sqrt(t_ss[:, None, None] * s_ss)
    with np.errstate(invalid="ignore", divide="ignore"):
        rho = np.where(den > 1e-9 * (1.0 + t_ss[:, None, None]), num / den, np.nan)
    return rho.astype(np.float32)


def _parabola(cm: NDArray, c0: NDArray, cp: NDArray) -> NDArray:
    """Sub-pixel offset of the peak of a parabola through (−1, cm), (0, c0), (1, cp)."""
    den = cm - 2.0 * c0 + cp
    with np.errstate(invalid="ignore", divide="ignore"):
        d = np.where(den < 0, 0.5 * (cm - cp) / np.where(den < 0, den, -1.0), 0.0)
    return np.clip(d, -0.5, 0.5)


def peak_subpixel(surface: NDArray, min_ncc: float = 0.5, max_ratio: float = 0.95):
    """Best integer peak, sub-pixel offsets and ambiguity of NCC surfaces (n, ry, rx).

    Returns
    -------
    iy, ix : int arrays, the integer peak; dy, dx : sub-pixel offsets (parabola, per axis; 0
    along an axis of length 1); peak : float32; ratio : float32 (second local maximum / peak);
    valid : bool (finite, not on the border of an axis longer than 1, peak ≥ min_ncc,
    ratio ≤ max_ratio).
    """
    rho = np.asarray(surface, dtype=np.float32)
    n, ry, rx = rho.shape
    filled = np.where(np.isfinite(rho), rho, -2.0)
    flat = filled.reshape(n, -1)
    best = flat.argmax(axis=1)
    peak = flat[np.arange(n), best]
    iy, ix = np.divmod(best, rx)
    # second-highest local maximum (3×3 neighbourhood), excluding the peak itself
    locmax = filled == ndimage.maximum_filter(filled, size=(1, 3, 3), mode="constant", cval=-2.0)
    second = np.where(locmax, filled, -2.0).reshape(n, -1)
    second[np.arange(n), best] = -2.0
    sec = second.max(axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        ratio = np.where(peak > 0, np.maximum(sec, 0.0) / peak, 1.0).astype(np.float32)
    ar = np.arange(n)
    dx = np.zeros(n)
    dy = np.zeros(n)
    border = np.zeros(n, bool)
    if rx > 1:
        border |= (ix == 0) | (ix == rx - 1)
        xm, xp = np.clip(ix - 1, 0, rx - 1), np.clip(ix + 1, 0, rx - 1)
        dx = np.where(border, 0.0, _parabola(filled[ar, iy, xm], peak, filled[ar, iy, xp]))
    if ry > 1:
        border |= (iy == 0) | (iy == ry - 1)
        ym, yp = np.clip(iy - 1, 0, ry - 1), np.clip(iy + 1, 0, ry - 1)
        dy = np.where(border, 0.0, _parabola(filled[ar, ym, ix], peak, filled[ar, yp, ix]))
    valid = (peak >= min_ncc) & ~border & (ratio <= max_ratio) & (peak > -2.0)
    return iy, ix, dy, dx, peak.astype(np.float32), ratio, valid


def ncc_epipolar(left: NDArray, right: NDArray, cols: ArrayLike, rows: ArrayLike,
                 min_disparity: ArrayLike, max_disparity: ArrayLike, window: int = 11,
                 min_ncc: float = 0.5, max_ratio: float = 0.95, chunk: int = 2048
                 ) -> NCCResult:
    """NCC search along the rows of epipolar images within a disparity range.

    Parameters
    ----------
    left, right : (rows, cols) arrays
        Epipolar (normalised) images: corresponding points share the row.
    cols, rows : (n,) array_like
        Points in the left image (rounded to the nearest pixel for the template).
    min_disparity, max_disparity : scalar or (n,) array_like
        Search range of d = left col − right col per point (inclusive, integers used).
    window : int
        Template size (odd).
    min_ncc, max_ratio : float
        Validity thresholds on the peak and on the ambiguity.
    chunk : int
        Points per batch (bounds the memory).
    """
    return _search(left, right, cols, rows, None, None, min_disparity, max_disparity, 0,
                   window, min_ncc, max_ratio, chunk)


def ncc_search_2d(left: NDArray, right: NDArray, cols: ArrayLike, rows: ArrayLike,
                  pred_cols: ArrayLike, pred_rows: ArrayLike, radius: int = 5,
                  window: int = 11, min_ncc: float = 0.5, max_ratio: float = 0.95,
                  chunk: int = 1024) -> NCCResult:
    """NCC search in a (2·radius+1)² neighbourhood of predicted right-image positions.

    Parameters
    ----------
    left, right : (rows, cols) arrays
    cols, rows : (n,) array_like
        Points in the left image.
    pred_cols, pred_rows : (n,) array_like
        Predicted positions in the right image (centre of the search).
    radius : int
        Search radius in pixels (along both axes).
    window, min_ncc, max_ratio, chunk :
        As in :func:`ncc_epipolar`.
    """
    return _search(left, right, cols, rows, pred_cols, pred_rows, None, None, int(radius),
                   window, min_ncc, max_ratio, chunk)


def _search(left, right, cols, rows, pred_cols, pred_rows, dmin, dmax, radius, window, min_ncc,
            max_ratio, chunk) -> NCCResult:
    if window < 3 or window % 2 == 0:
        raise ValueError("window must be an odd number ≥ 3")
    L = np.asarray(left, dtype=np.float32)
    R = np.asarray(right, dtype=np.float32)
    c = np.atleast_1d(np.asarray(cols, dtype=np.float64))
    r = np.atleast_1d(np.asarray(rows, dtype=np.float64))
    n = c.size
    h = window // 2
    ci, ri = np.rint(c).astype(np.int64), np.rint(r).astype(np.int64)
    epipolar = pred_cols is None
    if epipolar:
        d0 = np.broadcast_to(np.ceil(np.asarray(dmin, dtype=np.float64)), (n,)).astype(np.int64)
        d1 = np.broadcast_to(np.floor(np.asarray(dmax, dtype=np.float64)), (n,)).astype(np.int64)
        if np.any(d1 < d0):
            raise ValueError("max_disparity must not be smaller than min_disparity")
        nd = int((d1 - d0).max()) + 1 if n else 1
        # right col of offset k is ci − d1 + k, k = 0 … nd−1 (so k = nd−1 − (d − d0) …)
        start_c = ci - d1
        start_r = ri
        ry, rx = 1, nd
    else:
        pc = np.rint(np.broadcast_to(np.asarray(pred_cols, dtype=np.float64), (n,))).astype(
            np.int64)
        pr = np.rint(np.broadcast_to(np.asarray(pred_rows, dtype=np.float64), (n,))).astype(
            np.int64)
        start_c, start_r = pc - radius, pr - radius
        ry = rx = 2 * radius + 1
    out_c = np.full(n, np.nan)
    out_r = np.full(n, np.nan)
    peak = np.full(n, np.nan, np.float32)
    ratio = np.ones(n, np.float32)
    valid = np.zeros(n, bool)
    H, W = R.shape
    for s0 in range(0, n, chunk):
        sl = slice(s0, min(n, s0 + chunk))
        tpl = gather_windows(L, ri[sl] - h, ci[sl] - h, window, window)
        srch = gather_windows(R, start_r[sl] - h, start_c[sl] - h, ry + 2 * h, rx + 2 * h)
        rho = ncc_surface(tpl, srch)
        # offsets whose window leaves the right image, or beyond a point's own range: invalid
        oc = start_c[sl, None, None] + np.arange(rx)[None, None, :]
        orr = start_r[sl, None, None] + np.arange(ry)[None, :, None]
        bad = (oc - h < 0) | (oc + h > W - 1) | (orr - h < 0) | (orr + h > H - 1)
        if epipolar:
            dk = ci[sl, None, None] - oc  # disparity of each offset
            bad = bad | (dk < d0[sl, None, None]) | (dk > d1[sl, None, None])
        rho = np.where(bad, np.nan, rho)
        t_out = ((ci[sl] - h < 0) | (ci[sl] + h > L.shape[1] - 1) | (ri[sl] - h < 0)
                 | (ri[sl] + h > L.shape[0] - 1))
        rho[t_out] = np.nan
        iy, ix, dy, dx, pk, rt, ok = peak_subpixel(rho, min_ncc, max_ratio)
        if epipolar:  # the ends of the disparity range are the border, even if rx is larger
            dk_best = ci[sl] - (start_c[sl] + ix)
            ok &= (dk_best > d0[sl]) & (dk_best < d1[sl])
        found = np.isfinite(rho).any(axis=(1, 2))
        # carry the fractional part of the left point over (shift model)
        out_c[sl] = np.where(found, start_c[sl] + ix + dx + (c[sl] - ci[sl]), np.nan)
        out_r[sl] = np.where(found, start_r[sl] + iy + dy + (r[sl] - ri[sl]), np.nan)
        peak[sl] = np.where(found, pk, np.nan)
        ratio[sl] = rt
        valid[sl] = ok & found
    return NCCResult(out_c, out_r, c - out_c, peak, ratio, valid)
