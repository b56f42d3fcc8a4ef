r"""Förstner interest operator with sub-pixel point location.

For every pixel the gradient normal matrix over a window (default 5 × 5)

.. math::

    N = \sum_{window} \begin{bmatrix} g_x^2 & g_x g_y \\ g_x g_y & g_y^2 \end{bmatrix}, \qquad
    w = \frac{\det N}{\operatorname{tr} N} = \frac{1}{\operatorname{tr} N^{-1}}, \qquad
    q = \frac{4 \det N}{(\operatorname{tr} N)^2} = 1 - \left(\frac{\lambda_1-\lambda_2}
    {\lambda_1+\lambda_2}\right)^2

is formed from Gaussian-derivative gradients. w is the size of the point's error ellipse
(large = precise), q its roundness (1 = round, 0 = an edge). Points are pixels with
``q > q_min`` and ``w > w_factor · median(w)`` (median over all pixels with w > 0) that are the
maximum of w in a ``nms_window`` neighbourhood. The sub-pixel location is Förstner's point
estimate, the point closest (in the least-squares sense) to all lines through the window pixels
perpendicular to their gradients:

.. math:: \hat{\mathbf x} = N^{-1} \sum \nabla g \nabla g^T \mathbf x

which is exact for corners and junctions of straight edges. Optionally the image is divided into
square cells and only the strongest point(s) per cell are kept, so that points spread evenly.
"""

from __future__ import annotations

from typing import NamedTuple, Optional

import numpy as np
from numpy.typing import NDArray
from scipy import ndimage


class InterestPoints(NamedTuple):
    """Förstner points; unpacks as ``cols, rows, w, q`` (1-D arrays, sorted by w descending)."""

    cols: NDArray
    rows: NDArray
    w: NDArray
    q: NDArray


def forstner_measures(image: NDArray, window: int = 5, sigma: float = 0.7):
    """Per-pixel Förstner weight w and roundness q (float32 arrays of the image's shape).

    Parameters
    ----------
    image : (rows, cols) array
    window : int
        Side of the square summation window (odd).
    sigma : float
        σ (px) of the Gaussian derivative filters for the gradients.

    Returns
    -------
    w, q, (sxx, sxy, syy) : the weight, the roundness and the window sums of the gradient
    products (the elements of N).
    """
    img = np.asarray(image, dtype=np.float32)
    gx = ndimage.gaussian_filter(img, sigma, order=(0, 1), mode="nearest")
    gy = ndimage.gaussian_filter(img, sigma, order=(1, 0), mode="nearest")
    area = float(window * window)  # uniform_filter returns means; N holds sums
    sxx = ndimage.uniform_filter(gx * gx, window, mode="nearest") * area
    sxy = ndimage.uniform_filter(gx * gy, window, mode="nearest") * area
    syy = ndimage.uniform_filter(gy * gy, window, mode="nearest") * area
    det = sxx * syy - sxy * sxy
    tr = sxx + syy
    with np.errstate(invalid="ignore", divide="ignore"):
        ok = tr > 1e-12 * max(float(tr.max()), 1e-30)
        w = np.where(ok, det / np.where(ok, tr, 1.0), 0.0).astype(np.float32)
        q = np.where(ok, 4.0 * det / np.where(ok, tr * tr, 1.0), 0.0).astype(np.float32)
    return np.maximum(w, 0), np.clip(q, 0, 1), (sxx, sxy, syy)


def forstner(image: NDArray, window: int = 5, sigma: float = 0.7, q_min: float = 0.6,
             w_factor: float = 1.0, nms_window: int = 5, subpixel: bool = True,
             subpixel_window: Optional[int] = None, grid_cell: Optional[int] = None,
             per_cell: int = 1, border: Optional[int] = None,
             max_points: Optional[int] = None) -> InterestPoints:
    """Förstner interest points of an image.

    Parameters
    ----------
    image : (rows, cols) array
        Grey values (finite).
    window : int
        Side of the window over which N is summed (seed: 5 × 5).
    sigma : float
        σ of the Gaussian derivative gradients (0.7–1 px).
    q_min : float
        Roundness threshold, q > q_min (0.5–0.75 after Förstner & Gülch 1987); rejects edges.
    w_factor : float
        Weight threshold relative to the median: w > w_factor · median(w) (0.5–1.5).
    nms_window : int
        Non-maximum suppression: a point must be the largest w in this square neighbourhood.
    subpixel : bool
        Refine positions with the Förstner point estimate; if False, integer pixel centres.
    subpixel_window : int, optional
        Window of the point estimate (default ``window + 2``). An estimate that moves more than
        half this window from the pixel is discarded (the integer position is kept). The
        estimate is computed twice, the second time centred on the rounded first estimate.
    grid_cell : int, optional
        If given, keep only the ``per_cell`` strongest points per grid_cell × grid_cell cell.
    per_cell : int
        Points per cell with ``grid_cell``.
    border : int, optional
        Pixels along the edges where no point is reported (default: half the larger window + 1).
    max_points : int, optional
        Keep at most this many points (the strongest).

    Returns
    -------
    InterestPoints (cols, rows, w, q), sorted by w descending.
    """
    img = np.asarray(image, dtype=np.float32)
    if img.ndim != 2:
        raise ValueError("forstner expects a 2-D image")
    w, q, _ = forstner_measures(img, window, sigma)
    sp_win = window + 2 if subpixel_window is None else int(subpixel_window)
    if border is None:
        border = max(window, sp_win, nms_window) // 2 + 1
    positive = w[w > 0]
    thr = w_factor * float(np.median(positive)) if positive.size else np.inf
    cand = (q > q_min) & (w > thr)
    # ties (plateaus of equal w, e.g. on symmetric corners) are broken by a tiny ramp over the
    # pixel index so that one pixel per maximum survives
    wt = w.astype(np.float64) * (1.0 + 1e-9 * np.arange(w.size).reshape(w.shape) / w.size)
    cand &= wt == ndimage.maximum_filter(wt, nms_window, mode="constant", cval=0.0)
    if border > 0:
        cand[:border, :] = cand[-border:, :] = False
        cand[:, :border] = cand[:, -border:] = False
    rows, cols = np.nonzero(cand)
    wv, qv = w[rows, cols], q[rows, cols]
    # plateaus of equal w would give several maxima: keep one per nms window via grid below
    order = np.argsort(-wv, kind="stable")
    rows, cols, wv, qv = rows[order], cols[order], wv[order], qv[order]
    if grid_cell:
        keep = _strongest_per_cell(cols, rows, wv, int(grid_cell), int(per_cell))
        rows, cols, wv, qv = rows[keep], cols[keep], wv[keep], qv[keep]
    if max_points is not None:
        rows, cols, wv, qv = rows[:max_points], cols[:max_points], wv[:max_points], qv[:max_points]
    fc, fr = cols.astype(np.float64), rows.astype(np.float64)
    if subpixel and cols.size:
        fc, fr = _point_estimate(img, cols, rows, sp_win, sigma)
        # a second pass centred on the rounded first estimate (the window then covers the
        # corner symmetrically)
        fc2, fr2 = _point_estimate(img, np.rint(fc).astype(np.int64),
                                   np.rint(fr).astype(np.int64), sp_win, sigma)
        moved = np.hypot(fc2 - cols, fr2 - rows) <= sp_win // 2
        fc, fr = np.where(moved, fc2, fc), np.where(moved, fr2, fr)
    return InterestPoints(fc, fr, wv.astype(np.float32), qv.astype(np.float32))


def _strongest_per_cell(cols: NDArray, rows: NDArray, w: NDArray, cell: int, per_cell: int
                        ) -> NDArray:
    """Indices of the ``per_cell`` largest-w points in each cell (input order = w descending)."""
    ncx = int(cols.max()) // cell + 1 if cols.size else 1
    cell_id = (rows // cell) * ncx + cols // cell
    order = np.lexsort((-w, cell_id))
    sid = cell_id[order]
    first = np.r_[0, np.flatnonzero(np.diff(sid)) + 1]
    start = np.repeat(first, np.diff(np.r_[first, sid.size]))
    rank = np.arange(sid.size) - start
    keep = order[rank < per_cell]
    return np.sort(keep)  # back to w-descending order


def _point_estimate(img: NDArray, cols: NDArray, rows: NDArray, win: int, sigma: float):
    """Förstner point estimate x̂ = N⁻¹ Σ ∇g∇gᵀ x over a win × win window per point (batched)."""
    gx = ndimage.gaussian_filter(img, sigma, order=(0, 1), mode="nearest")
    gy = ndimage.gaussian_filter(img, sigma, order=(1, 0), mode="nearest")
    h = win // 2
    off = np.arange(-h, h + 1)
    dr, dc = np.meshgrid(off, off, indexing="ij")
    rr = np.clip(rows[:, None] + dr.ravel(), 0, img.shape[0] - 1)
    cc = np.clip(cols[:, None] + dc.ravel(), 0, img.shape[1] - 1)
    px, py = gx[rr, cc].astype(np.float64), gy[rr, cc].astype(np.float64)
    xx, xy, yy = px * px, px * py, py * py
    # local coordinates relative to the pixel (dc, dr) keep the numbers small
    u = dc.ravel()[None, :].astype(np.float64)
    v = dr.ravel()[None, :].astype(np.float64)
    n11, n12, n22 = xx.sum(1), xy.sum(1), yy.sum(1)
    b1 = (xx * u + xy * v).sum(1)
    b2 = (xy * u + yy * v).sum(1)
    det = n11 * n22 - n12 * n12
    with np.errstate(invalid="ignore", divide="ignore"):
        du = (n22 * b1 - n12 * b2) / det
        dv = (n11 * b2 - n12 * b1) / det
    ok = np.isfinite(du) & np.isfinite(dv) & (np.abs(du) <= h) & (np.abs(dv) <= h)
    fc = cols + np.where(ok, du, 0.0)
    fr = rows + np.where(ok, dv, 0.0)
    return fc.astype(np.float64), fr.astype(np.float64)
