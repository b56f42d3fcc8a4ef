r"""Feature-based matching (FBM) of Förstner points on one level of an epipolar image pair.

Seed-000 §2.3–2.5 and §2.8, vectorised over all points of the level at once. Rows of the two
images correspond; the disparity of a pair is :math:`d = c_l - c_r` (left col − right col).

1. **Features** — Förstner points in both images (:func:`.interest.forstner`), sub-pixel.
   :math:`\operatorname{tr} Q = 1/w` follows from the interest weight.
2. **Candidates** (local consistency) — for a left point i the right points j with
   :math:`|r_j - r_i| \le` ``row_tol`` and :math:`d_{ij} \in [\hat d_i - p, \hat d_i + p]`
   (prediction :math:`\hat d_i`, pull-in p). Similarity is the correlation coefficient ρ of
   small windows (``ncc_window``, seed ≈ 5 × 5); for :math:`\rho \ge \rho_{min}` the candidate
   weight is (Paderes 1984, seed 2-28)

   .. math:: w_{ij} = \frac12 \frac{\rho_{ij}}{1-\rho_{ij}} \frac{1}{\sigma_{g_i}\sigma_{g_j}}
             \frac{1}{\sqrt{\operatorname{tr} Q_i \operatorname{tr} Q_j}}

3. **Global consistency** per matching window (or window component, see
   :func:`window_components`): the residual disparities :math:`r = d - \hat d` are fitted by
   :math:`r = a_0 + a_1 u + a_2 v` (u, v = offsets from the window centre in window sizes) with
   iteratively reweighted least squares, :func:`robust_plane_fit`: 2 iterations Huber
   (k = 1.5σ), then 4 with :math:`\exp(-(v/2.5\sigma)^2)`, σ = 1.4826·(weighted) MAD at every
   iteration; candidates beyond ``reject_k``·σ are outliers; then one-to-one (best candidate per
   left point, then per right point). All windows are solved together (grouped normal
   equations from ``bincount`` sums).
4. **Bidirectional check** — the same from right to left; a pair is kept when the right point's
   own best match has a disparity within ``bidir_tol`` px.
5. **Sub-pixel** — the disparity of each kept pair is refined by an NCC parabola
   (:func:`.ncc.ncc_epipolar`, ±2 px around the feature disparity); if that fails the Förstner
   sub-pixel feature difference is kept (flag :data:`FLAG_FEATURE_SUBPIXEL`).

Self-diagnosis per window: the absolute plane :math:`d = p_0 + p_1 u + p_2 v` of the accepted
points, σ0 of their residuals, numbers of features, candidates, outliers and accepted points,
and a failure mark (features present but fewer than ``min_points`` accepted).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, Dict, NamedTuple, Optional, Tuple

import numpy as np
from numpy.typing import NDArray
from scipy import ndimage

from .interest import InterestPoints, forstner, forstner_measures
from .ncc import ncc_epipolar, ncc_surface

#: the NCC parabola failed; the disparity is the difference of the Förstner sub-pixel features
FLAG_FEATURE_SUBPIXEL = 4

#: ``predict(cols, rows) -> (d_pred, pull_in)`` in left-image pixels of the working level;
#: NaN d_pred = do not match this point
Predictor = Callable[[NDArray, NDArray], Tuple[NDArray, NDArray]]


# ---- helpers ------------------------------------------------------------------------------------
def fill_nodata(image: NDArray) -> Tuple[NDArray, NDArray]:
    """NaN pixels replaced by their nearest valid pixel (pyramids and filters need finite values).

    Returns
    -------
    filled : float32 array, valid : bool array (True = the pixel had data).
    """
    img = np.asarray(image, dtype=np.float32)
    valid = np.isfinite(img)
    if valid.all():
        return img, valid
    if not valid.any():
        return np.zeros_like(img), valid
    idx = ndimage.distance_transform_edt(~valid, return_distances=False, return_indices=True)
    return img[tuple(idx)], valid


def local_weight_threshold(w: NDArray, usable: Optional[NDArray], cell: int, w_factor: float,
                           floor: float) -> NDArray:
    r"""Förstner weight threshold per sub-image (seed §2.3 item 5), as a per-pixel map.

    The image is split into ``cell`` × ``cell`` sub-images; each gets
    :math:`t = f\cdot\max(\operatorname{median}_{cell}(w), \text{floor}\cdot
    \operatorname{median}_{image}(w))` over its usable pixels with w > 0. A global median
    threshold leaves areas of weak texture (fields, shadowed slopes) without points when the
    image also holds strong texture; the floor keeps pure noise in uniform areas out.
    Sub-images without usable pixels take the global threshold.
    """
    h, wd = w.shape
    ok = w > 0
    if usable is not None:
        ok &= usable
    vals = np.where(ok, w, np.nan).astype(np.float64)
    glob = float(np.median(vals[ok])) if ok.any() else np.inf
    ny, nx = -(-h // cell), -(-wd // cell)
    pad = np.full((ny * cell, nx * cell), np.nan)
    pad[:h, :wd] = vals
    blocks = pad.reshape(ny, cell, nx, cell).transpose(0, 2, 1, 3).reshape(ny, nx, -1)
    have = np.isfinite(blocks).any(axis=2)
    med = np.full((ny, nx), glob)
    if have.any():
        med[have] = _nanmedian_rows(blocks[have])
    thr = w_factor * np.maximum(med, floor * glob)
    return np.repeat(np.repeat(thr, cell, 0), cell, 1)[:h, :wd]


def _nanmedian_rows(a: NDArray) -> NDArray:
    """Median of the finite values of each row (every row has at least one)."""
    s = np.sort(a, axis=1)  # NaN sorts last
    n = np.isfinite(a).sum(axis=1)
    r = np.arange(a.shape[0])
    lo = s[r, (n - 1) // 2]
    hi = s[r, n // 2]
    return 0.5 * (lo + hi)


def detect_features(image: NDArray, valid: Optional[NDArray] = None, exclude: Optional[NDArray]
                    = None, *, window: int = 5, q_min: float = 0.6, w_factor: float = 1.0,
                    nms_window: int = 5, margin: int = 5, local_cell: Optional[int] = None,
                    local_floor: float = 0.0625) -> InterestPoints:
    """Förstner points of a (finite) image, without points near nodata or in excluded pixels.

    Parameters
    ----------
    image : (rows, cols) float array, finite (see :func:`fill_nodata`).
    valid : bool array, optional
        Pixels with data; points whose ``2·margin+1`` neighbourhood touches nodata are dropped.
    exclude : bool array, optional
        Pixels where no point may lie (exclusion areas, outside the boundary, breaklines).
    window, q_min, w_factor, nms_window :
        Förstner parameters (:func:`.interest.forstner`).
    margin : int
        Half size of the largest window that will be cut around a point (NCC, LSM).
    local_cell : int, optional
        Sub-image side (px) for local weight thresholds (:func:`local_weight_threshold`);
        None: one threshold ``w_factor · median(w)`` for the whole image.
    local_floor : float
        With ``local_cell``: a sub-image's median counts at least ``local_floor`` × the
        image's median.
    """
    if local_cell:
        w_map, _, _ = forstner_measures(image, window)
        usable = None
        if valid is not None or exclude is not None:
            usable = np.ones(image.shape, bool)
            if valid is not None:
                usable &= valid
            if exclude is not None:
                usable &= ~exclude
        thr = local_weight_threshold(w_map, usable, int(local_cell), w_factor, local_floor)
        pts = forstner(image, window=window, q_min=q_min, w_factor=0.0, nms_window=nms_window,
                       border=margin + 1)
    else:
        pts = forstner(image, window=window, q_min=q_min, w_factor=w_factor,
                       nms_window=nms_window, border=margin + 1)
    keep = np.ones(pts.cols.size, bool)
    ci = np.rint(pts.cols).astype(np.int64)
    ri = np.rint(pts.rows).astype(np.int64)
    if local_cell:
        keep &= pts.w > thr[ri, ci]
    if valid is not None and not np.all(valid):
        near_bad = ndimage.maximum_filter(~valid, size=2 * margin + 1, mode="constant",
                                          cval=True)
        keep &= ~near_bad[ri, ci]
    if exclude is not None:
        keep &= ~exclude[ri, ci]
    return InterestPoints(*(a[keep] for a in pts))


def window_vectors(image: NDArray, cols: NDArray, rows: NDArray, window: int
                   ) -> Tuple[NDArray, NDArray]:
    r"""Zero-mean, unit-norm grey-value vectors of windows at the rounded point positions.

    With these, :math:`\rho_{ij} = z_i \cdot z_j`. Returns ``z`` (n, window²) float32 (zeros for
    windows without contrast) and the grey-value σ of each window.
    """
    h = window // 2
    off = np.arange(-h, h + 1)
    ri = np.clip(np.rint(rows).astype(np.int64)[:, None] + off, 0, image.shape[0] - 1)
    ci = np.clip(np.rint(cols).astype(np.int64)[:, None] + off, 0, image.shape[1] - 1)
    g = image[ri[:, :, None], ci[:, None, :]].reshape(len(ri), -1).astype(np.float32)
    g -= g.mean(axis=1, keepdims=True)
    norm = np.sqrt(np.einsum("ij,ij->i", g, g))
    sigma_g = norm / np.sqrt(g.shape[1])
    with np.errstate(invalid="ignore", divide="ignore"):
        z = np.where(norm[:, None] > 1e-6, g / norm[:, None], 0.0).astype(np.float32)
    return z, sigma_g.astype(np.float64)


def candidate_pairs(ca: NDArray, ra: NDArray, cb: NDArray, rb: NDArray, d_lo: NDArray,
                    d_hi: NDArray, row_tol: float = 1.0) -> Tuple[NDArray, NDArray]:
    """All pairs (i, j) with |rb_j − ra_i| ≤ row_tol and ca_i − cb_j ∈ [d_lo_i, d_hi_i].

    Vectorised: the b points are sorted by (rounded row, col) and each a point's admissible
    interval is found by two ``searchsorted`` per row offset. NaN bounds give no pairs.

    Returns
    -------
    ia, ib : int64 arrays of the pairs.
    """
    na = ca.size
    if na == 0 or cb.size == 0:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    big = 1e7  # rows × big + col: one sortable key (|col| < 5e6)
    rbi = np.rint(rb)
    key_b = rbi * big + cb
    order = np.argsort(key_b, kind="stable")
    key_sorted = key_b[order]
    ok = np.isfinite(d_lo) & np.isfinite(d_hi)
    lo = np.where(ok, d_lo, 0.0)
    hi = np.where(ok, d_hi, -1.0)  # empty interval
    rai = np.rint(ra)
    reach = int(np.ceil(row_tol)) + 1
    ia_parts, ib_parts = [], []
    for off in range(-reach, reach + 1):
        base = (rai + off) * big
        s = np.searchsorted(key_sorted, base + ca - hi, side="left")
        e = np.searchsorted(key_sorted, base + ca - lo, side="right")
        cnt = np.maximum(e - s, 0)
        cnt[~ok] = 0
        tot = int(cnt.sum())
        if tot == 0:
            continue
        ia = np.repeat(np.arange(na), cnt)
        first = np.cumsum(cnt) - cnt
        ib = order[s[ia] + (np.arange(tot) - first[ia])]
        ia_parts.append(ia)
        ib_parts.append(ib)
    if not ia_parts:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    ia = np.concatenate(ia_parts)
    ib = np.concatenate(ib_parts)
    keep = np.abs(rb[ib] - ra[ia]) <= row_tol
    return ia[keep], ib[keep]


def correlation_candidates(img_a: NDArray, img_b: NDArray, ca: NDArray, ra: NDArray,
                           d_lo: NDArray, d_hi: NDArray, *, window: int = 7,
                           rho_min: float = 0.6, max_peaks: int = 3, chunk: int = 4096
                           ) -> Tuple[NDArray, NDArray, NDArray]:
    r"""Candidates of a points from the NCC profile along the same row of image b.

    For every a point the correlation coefficient ρ(k) of the ``window`` × ``window``
    template at the rounded point with the b window at column ``round(ca) − k`` is evaluated
    for all integer disparities :math:`k \in [\lceil d_{lo} \rceil, \lfloor d_{hi} \rfloor]`
    (:func:`.ncc.ncc_surface`, float32 sums without BLAS). Every *local maximum* of the profile
    with :math:`\rho \ge \rho_{min}` (at most ``max_peaks``, the highest first, none on the
    ends of the range) is a candidate; its disparity is refined by the parabola through the
    maximum and its two neighbours, :math:`\delta = (\rho_- - \rho_+) / (2(\rho_- - 2\rho_0 +
    \rho_+))`. Unlike feature-to-feature candidates these do not need the same interest point
    to be detected in both images (on real images with perspective and radiometric
    differences only about half of them are).

    Returns
    -------
    ia : (m,) int64 index of the a point; d : (m,) float64 sub-pixel disparity ca − cb;
    rho : (m,) float64 peak correlation.
    """
    ca = np.asarray(ca, float)
    ra = np.asarray(ra, float)
    ok = np.isfinite(d_lo) & np.isfinite(d_hi)
    k0 = np.ceil(np.where(ok, d_lo, 0.0)).astype(np.int64)
    k1 = np.floor(np.where(ok, d_hi, -1.0)).astype(np.int64)
    nd = k1 - k0 + 1
    idx = np.flatnonzero(ok & (nd >= 3))
    empty = (np.zeros(0, np.int64), np.zeros(0), np.zeros(0))
    if idx.size == 0:
        return empty
    # sort by range width so that a chunk's profiles have similar lengths (bounded waste)
    idx = idx[np.argsort(nd[idx], kind="stable")]
    h = window // 2
    hb, wb = img_b.shape
    ci = np.rint(ca).astype(np.int64)
    ri = np.rint(ra).astype(np.int64)
    parts = []
    for s0 in range(0, idx.size, chunk):
        sel = idx[s0:s0 + chunk]
        n = sel.size
        m = int(nd[sel].max())
        rr = np.clip(ri[sel, None] + np.arange(-h, h + 1), 0, img_a.shape[0] - 1)
        cc = np.clip(ci[sel, None] + np.arange(-h, h + 1), 0, img_a.shape[1] - 1)
        tpl = img_a[rr[:, :, None], cc[:, None, :]]
        start = ci[sel] - k1[sel]  # b column of offset 0 (disparity k1)
        rb = np.clip(ri[sel, None] + np.arange(-h, h + 1), 0, hb - 1)
        cb = np.clip(start[:, None] - h + np.arange(m + 2 * h), 0, wb - 1)
        srch = img_b[rb[:, :, None], cb[:, None, :]]
        prof = ncc_surface(tpl, srch)[:, 0, :].astype(np.float64)  # (n, m)
        col_b = start[:, None] + np.arange(m)
        bad = ((col_b - h < 0) | (col_b + h > wb - 1) | (np.arange(m)[None, :] >= nd[sel, None])
               | ((ri[sel] - h < 0) | (ri[sel] + h > hb - 1))[:, None])
        prof = np.where(bad | ~np.isfinite(prof), -2.0, prof)
        left_n = np.concatenate([np.full((n, 1), np.inf), prof[:, :-1]], 1)
        right_n = np.concatenate([prof[:, 1:], np.full((n, 1), np.inf)], 1)
        peak = (prof >= left_n) & (prof > right_n) & (prof >= rho_min)
        pi, pj = np.nonzero(peak)
        if pi.size == 0:
            continue
        rho = prof[pi, pj]
        # the highest ``max_peaks`` maxima of each point
        order = np.lexsort((-rho, pi))
        pi, pj, rho = pi[order], pj[order], rho[order]
        first = np.r_[0, np.flatnonzero(np.diff(pi)) + 1]
        rank = np.arange(pi.size) - np.repeat(first, np.diff(np.r_[first, pi.size]))
        keep = rank < max_peaks
        pi, pj, rho = pi[keep], pj[keep], rho[keep]
        cm, cp = prof[pi, pj - 1], prof[pi, pj + 1]
        den = cm - 2.0 * rho + cp
        with np.errstate(invalid="ignore", divide="ignore"):
            delta = np.where(den < 0, 0.5 * (cm - cp) / np.where(den < 0, den, -1.0), 0.0)
        delta = np.clip(delta, -0.5, 0.5)
        # template cut at the rounded point: the fractional part carries over (shift model)
        d = (k1[sel][pi] - pj - delta) + 0.0
        parts.append((sel[pi], d, rho))
    if not parts:
        return empty
    ia, d, rho = (np.concatenate(p) for p in zip(*parts))
    order = np.argsort(ia, kind="stable")
    return ia[order], d[order], rho[order]


def group_weighted_median(x: NDArray, w: NDArray, g: NDArray, n_groups: int) -> NDArray:
    """Weighted median of ``x`` per group (NaN for groups without positive weight).

    The smallest x of a group whose cumulative weight reaches half the group's total.
    """
    out = np.full(n_groups, np.nan)
    sel = w > 0
    if not sel.any():
        return out
    x, w, g = x[sel], w[sel], g[sel]
    order = np.lexsort((x, g))
    xs, ws, gs = x[order], w[order], g[order]
    tot = np.bincount(gs, ws, n_groups)
    start = np.concatenate([[0.0], np.cumsum(tot)[:-1]])
    within = np.cumsum(ws) - start[gs]
    reached = within >= 0.5 * tot[gs] * (1 - 1e-12)
    idx = np.flatnonzero(reached)
    gi, first = np.unique(gs[idx], return_index=True)
    out[gi] = xs[idx[first]]
    return out


def group_wls(u, v, r, w, g, n_groups, ridge):
    """Weighted least squares r = a0 + a1·u + a2·v per group (normal equations by bincount).

    A ridge ``ridge·Σw`` on the slope terms keeps groups with collinear or very few points
    solvable (it pulls their slopes towards 0, i.e. towards the prediction's slope).
    """
    def s(x):
        return np.bincount(g, x, n_groups)

    sw, su, sv = s(w), s(w * u), s(w * v)
    suu, suv, svv = s(w * u * u), s(w * u * v), s(w * v * v)
    N = np.empty((n_groups, 3, 3))
    N[:, 0] = np.stack([sw, su, sv], 1)
    N[:, 1] = np.stack([su, suu, suv], 1)
    N[:, 2] = np.stack([sv, suv, svv], 1)
    N[:, 1, 1] += ridge * sw
    N[:, 2, 2] += ridge * sw
    N += 1e-12 * np.eye(3)
    b = np.stack([s(w * r), s(w * u * r), s(w * v * r)], 1)
    a = np.linalg.solve(N, b[:, :, None])[:, :, 0]
    a[sw <= 0] = 0.0
    return a


def _start_values(r: NDArray, w: NDArray, g: NDArray, n_groups: int, bin_px: float) -> NDArray:
    """Weighted mode (3-bin smoothed histogram peak) of r per group, refined by a median."""
    out = np.zeros(n_groups)
    if r.size == 0:
        return out
    lo = float(np.floor(r.min() / bin_px)) - 1
    b = (np.floor(r / bin_px) - lo).astype(np.int64)
    nb = int(b.max()) + 2
    hist = np.bincount(g * nb + b, w, n_groups * nb).reshape(n_groups, nb)
    smooth = hist.copy()
    smooth[:, 1:] += hist[:, :-1]
    smooth[:, :-1] += hist[:, 1:]
    peak = (np.argmax(smooth, axis=1) + lo + 0.5) * bin_px
    near = np.abs(r - peak[g]) <= 1.5 * bin_px
    med = group_weighted_median(r[near], w[near], g[near], n_groups)
    return np.where(np.isfinite(med), med, 0.0)


class RobustFit(NamedTuple):
    """Result of :func:`robust_plane_fit`.

    params : (n_groups, 3) a0, a1, a2; sigma : (n_groups,) robust σ of the residuals;
    residual, weight : (n,) final residuals and robust weights; inlier : (n,) bool.
    """

    params: NDArray
    sigma: NDArray
    residual: NDArray
    weight: NDArray
    inlier: NDArray


def robust_plane_fit(u: NDArray, v: NDArray, r: NDArray, w: NDArray, g: NDArray,
                     n_groups: int, *, huber_iterations: int = 2,
                     redescending_iterations: int = 4, huber_k: float = 1.5,
                     redescending_c: float = 2.5, reject_k: float = 3.0,
                     sigma_floor: float = 0.3, ridge: float = 1e-3,
                     mode_bin: float = 1.0) -> RobustFit:
    r"""IRLS fit of :math:`r = a_0 + a_1 u + a_2 v` in many groups (windows) at once.

    Start: :math:`a_0` = the weighted mode of r per group (the peak of a weighted histogram
    with ``mode_bin`` px bins, smoothed over 3 bins), refined by the weighted median of the
    candidates within ±1.5 bins of it; slopes 0. A mode, unlike the median, is not broken by
    50 % wrong candidates as long as these scatter over the pull-in range. Then per iteration, with
    residuals :math:`e` and :math:`\sigma = \max(1.4826\,\mathrm{wMAD}(e), \sigma_{floor})`
    (weighted by the candidate weights times the previous robust weights — at the start 1 near
    the mode, 0 elsewhere — so strong, consistent candidates set the scale),
    :math:`t = |e|/\sigma`:

    - Huber: :math:`\omega = \min(1, k/t)` for the first ``huber_iterations``;
    - redescending: :math:`\omega = \exp(-(t/c)^2)` for the next ``redescending_iterations``;

    and a weighted least-squares solve with weights :math:`w\,\omega`. Inliers:
    :math:`|e| \le` ``reject_k``·σ.

    Parameters
    ----------
    u, v : (n,) coordinates (any unit; O(1) values keep the ridge meaningful)
    r : (n,) observations (residual disparities, px)
    w : (n,) a-priori weights (candidate weights)
    g : (n,) int group index in ``[0, n_groups)``
    sigma_floor : float
        Lower bound of σ (px): very good fits must not reject good points.
    ridge : float
        Relative ridge on the slopes (see :func:`group_wls`).
    """
    u = np.asarray(u, float)
    v = np.asarray(v, float)
    r = np.asarray(r, float)
    w = np.asarray(w, float)
    g = np.asarray(g, np.int64)
    a = np.zeros((n_groups, 3))
    a[:, 0] = _start_values(r, w, g, n_groups, mode_bin)
    sigma = np.full(n_groups, sigma_floor)
    e = r - a[g, 0]
    # the first scale comes from the candidates near the mode only (a MAD over 50 % wrong
    # candidates would be as large as their spread); later scales use the robust weights
    omega = (np.abs(e) <= 1.5 * mode_bin).astype(float)
    for it in range(huber_iterations + redescending_iterations):
        mad = group_weighted_median(np.abs(e), w * omega, g, n_groups)
        sigma = np.maximum(np.where(np.isfinite(mad), 1.4826 * mad, sigma_floor), sigma_floor)
        t = np.abs(e) / sigma[g]
        if it < huber_iterations:
            omega = np.minimum(1.0, huber_k / np.maximum(t, 1e-12))
        else:
            omega = np.exp(-((t / redescending_c) ** 2))
        a = group_wls(u, v, r, w * omega, g, n_groups, ridge)
        e = r - (a[g, 0] + a[g, 1] * u + a[g, 2] * v)
    # final scale from the final residuals, with the final robust weights
    mad = group_weighted_median(np.abs(e), w * omega, g, n_groups)
    sigma = np.maximum(np.where(np.isfinite(mad), 1.4826 * mad, sigma_floor), sigma_floor)
    inlier = np.abs(e) <= reject_k * sigma[g]
    return RobustFit(a, sigma, e, omega, inlier)


def one_to_one(ia: NDArray, ib: NDArray, score: NDArray, valid: NDArray) -> NDArray:
    """Indices of pairs kept when each a and each b point may be used once (best score first).

    First the best valid pair per a point, then among those the best per b point.
    """
    idx = np.flatnonzero(valid)
    if idx.size == 0:
        return idx
    order = idx[np.lexsort((-score[idx], ia[idx]))]
    first = np.r_[True, ia[order][1:] != ia[order][:-1]]
    best_a = order[first]
    order = best_a[np.lexsort((-score[best_a], ib[best_a]))]
    first = np.r_[True, ib[order][1:] != ib[order][:-1]]
    return np.sort(order[first])


# ---- window groups ------------------------------------------------------------------------------
@dataclass
class Grouping:
    """Matching windows, optionally split into components by barrier pixels.

    Attributes
    ----------
    labels : (rows, cols) int32
        Group index + 1 of every pixel; 0 = no group (barrier pixel).
    n_groups : int
    centres : (n_groups, 2) float64
        Centroid (col, row) of each group's pixels.
    area : (n_groups,) int
        Pixels per group.
    window : int
        Side of the matching windows (the unit of the plane coordinates u, v).
    window_index : (n_groups,) int
        Index ``wy·n_wx + wx`` of the window a group lies in.
    edges : (k, 2) int
        Pairs of neighbouring groups (both directions): 4-adjacent windows whose pixels touch
        across the window border without a barrier pixel between them.
    """

    labels: NDArray
    n_groups: int
    centres: NDArray
    area: NDArray
    window: int
    window_index: NDArray
    edges: NDArray
    _filled: Optional[NDArray] = field(default=None, repr=False)

    def of(self, cols: NDArray, rows: NDArray, nearest: bool = False) -> NDArray:
        """Group index of points (−1 outside the image or on a barrier pixel).

        With ``nearest``, a point on a barrier pixel takes the group of the nearest labelled
        pixel.
        """
        labels = self.labels
        if nearest and not labels.all():
            if self._filled is None:
                idx = ndimage.distance_transform_edt(labels == 0, return_distances=False,
                                                     return_indices=True)
                self._filled = labels[tuple(idx)]
            labels = self._filled
        h, w = labels.shape
        ci = np.rint(np.asarray(cols, float))
        ri = np.rint(np.asarray(rows, float))
        inside = np.isfinite(ci) & np.isfinite(ri) & (ci >= 0) & (ci < w) & (ri >= 0) & (ri < h)
        out = np.full(ci.shape, -1, np.int64)
        out[inside] = labels[ri[inside].astype(np.int64), ci[inside].astype(np.int64)] - 1
        return out

    def uv(self, cols: NDArray, rows: NDArray, group: NDArray) -> Tuple[NDArray, NDArray]:
        """Plane coordinates of points relative to their group centre, in window sizes."""
        return ((cols - self.centres[group, 0]) / self.window,
                (rows - self.centres[group, 1]) / self.window)


def window_components(shape: Tuple[int, int], window: int,
                      barriers: Optional[NDArray] = None) -> Grouping:
    """Split an image into square matching windows and each window into barrier-free parts.

    The connected components (4-connectivity) of the non-barrier pixels are labelled for all
    windows in one call: the image is reshaped to a stack of windows and labelled with a 3-D
    structure that connects pixels only within a window. A breakline crossing a window thus
    gives two groups, and the robust plane of one side never sees the points of the other.
    """
    h, w = int(shape[0]), int(shape[1])
    ws = int(window)
    nwy, nwx = -(-h // ws), -(-w // ws)
    free = np.zeros((nwy * ws, nwx * ws), bool)
    free[:h, :w] = True if barriers is None else ~np.asarray(barriers, bool)
    stack = free.reshape(nwy, ws, nwx, ws).transpose(0, 2, 1, 3).reshape(nwy * nwx, ws, ws)
    if barriers is None or not np.any(barriers):
        # one group per window (pixels outside the image belong to no group)
        lab = np.broadcast_to(np.arange(1, nwy * nwx + 1, dtype=np.int32)[:, None, None],
                              stack.shape).copy()
        lab[~stack] = 0
        n = nwy * nwx
    else:
        structure = np.zeros((3, 3, 3), bool)
        structure[1] = ndimage.generate_binary_structure(2, 1)
        lab, n = ndimage.label(stack, structure=structure)
    labels = lab.reshape(nwy, nwx, ws, ws).transpose(0, 2, 1, 3).reshape(nwy * ws, nwx * ws)
    labels = np.ascontiguousarray(labels[:h, :w]).astype(np.int32)
    rr, cc = np.indices((h, w))
    flat = labels.ravel()
    area = np.bincount(flat, minlength=n + 1)[1:]
    with np.errstate(invalid="ignore", divide="ignore"):
        centres = np.stack([np.bincount(flat, cc.ravel(), n + 1)[1:] / area,
                            np.bincount(flat, rr.ravel(), n + 1)[1:] / area], 1)
    win = (rr // ws) * nwx + cc // ws
    window_index = np.zeros(n + 1, np.int64)
    window_index[flat] = win.ravel()
    # neighbours across the vertical and horizontal window borders
    pairs = []
    xb = np.arange(ws, w, ws)
    if xb.size:
        pairs.append(np.stack([labels[:, xb - 1].ravel(), labels[:, xb].ravel()], 1))
    yb = np.arange(ws, h, ws)
    if yb.size:
        pairs.append(np.stack([labels[yb - 1, :].ravel(), labels[yb, :].ravel()], 1))
    if pairs:
        p = np.concatenate(pairs)
        p = p[(p[:, 0] > 0) & (p[:, 1] > 0)] - 1
        p = np.unique(np.concatenate([p, p[:, ::-1]]), axis=0)
    else:
        p = np.zeros((0, 2), np.int64)
    return Grouping(labels, int(n), centres, area, ws, window_index[1:], p.astype(np.int64))


# ---- one direction ------------------------------------------------------------------------------
class OneWay(NamedTuple):
    """Best match of each a point (−1 / NaN when none) and per-group diagnostics."""

    match: NDArray  # (na,) index of the b point or −1
    disparity: NDArray  # (na,) col_a − col_b of the match (NaN when none)
    rho: NDArray  # (na,) ρ of the match
    group: NDArray  # (na,) group of the a point (−1 = not matched/no group)
    fit: Optional[RobustFit]
    n_candidates: NDArray  # per group
    n_outliers: NDArray  # per group


def match_oneway(img_a: NDArray, img_b: NDArray, fa: InterestPoints,
                 fb: Optional[InterestPoints], d_pred: NDArray, pull_in: NDArray, group: NDArray,
                 u: NDArray, v: NDArray, n_groups: int, *, ncc_window: int = 7,
                 rho_min: float = 0.6, row_tol: float = 1.0, rho_cap: float = 0.99,
                 candidates: str = "features", max_peaks: int = 3, **robust) -> OneWay:
    """Candidates, weights, robust consistency and one-to-one for the a points of one level.

    ``d_pred`` / ``pull_in`` / ``group`` / ``u`` / ``v`` are per a point (NaN or −1: skip);
    the disparity is ``col_a − col_b`` in the a image's convention. ``robust`` goes to
    :func:`robust_plane_fit`.

    ``candidates="features"``: the b interest points ``fb`` within the row tolerance and the
    disparity interval (the seed's FBM); ``match`` holds b point indices.
    ``candidates="correlation"``: the local maxima of the NCC profile along the row of b
    (:func:`correlation_candidates`, ``fb`` unused); ``match`` holds the b pixel
    ``row · width + col`` (used for the one-to-one rule).
    """
    na = fa.cols.size
    match = np.full(na, -1, np.int64)
    disp = np.full(na, np.nan)
    rho_out = np.full(na, np.nan)
    n_cand = np.zeros(n_groups, np.int64)
    n_out = np.zeros(n_groups, np.int64)
    active = np.isfinite(d_pred) & (group >= 0)
    d_lo = np.where(active, d_pred - pull_in, np.nan)
    d_hi = np.where(active, d_pred + pull_in, np.nan)
    if candidates == "correlation":
        ia, d, rho = correlation_candidates(img_a, img_b, fa.cols, fa.rows, d_lo, d_hi,
                                            window=ncc_window, rho_min=rho_min,
                                            max_peaks=max_peaks)
        if ia.size == 0:
            return OneWay(match, disp, rho_out, np.where(active, group, -1), None, n_cand,
                          n_out)
        cb = fa.cols[ia] - d
        ib = np.rint(fa.rows[ia]).astype(np.int64) * img_b.shape[1] + np.rint(cb).astype(
            np.int64)
        _, sa = window_vectors(img_a, fa.cols[ia], fa.rows[ia], ncc_window)
        _, sb = window_vectors(img_b, cb, fa.rows[ia], ncc_window)
        # the b position is no interest point: its tr Q is taken equal to the a point's
        tq = (1.0 / np.maximum(fa.w[ia].astype(float), 1e-30)) ** 2
    elif candidates == "features":
        ia, ib = candidate_pairs(fa.cols, fa.rows, fb.cols, fb.rows, d_lo, d_hi, row_tol)
        if ia.size == 0:
            return OneWay(match, disp, rho_out, np.where(active, group, -1), None, n_cand,
                          n_out)
        # window vectors only for the points that take part
        ua, inv_a = np.unique(ia, return_inverse=True)
        ub, inv_b = np.unique(ib, return_inverse=True)
        za, sa = window_vectors(img_a, fa.cols[ua], fa.rows[ua], ncc_window)
        zb, sb = window_vectors(img_b, fb.cols[ub], fb.rows[ub], ncc_window)
        rho = np.empty(ia.size, np.float32)
        step = 1 << 17
        for s0 in range(0, ia.size, step):  # bounded memory for the pair gathers
            sl = slice(s0, s0 + step)
            rho[sl] = np.einsum("ij,ij->i", za[inv_a[sl]], zb[inv_b[sl]])
        keep = rho >= rho_min
        ia, ib, rho = ia[keep], ib[keep], rho[keep].astype(np.float64)
        sa, sb = sa[inv_a[keep]], sb[inv_b[keep]]
        if ia.size == 0:
            return OneWay(match, disp, rho_out, np.where(active, group, -1), None, n_cand,
                          n_out)
        tq = 1.0 / np.maximum(fa.w[ia].astype(float), 1e-30) * (
            1.0 / np.maximum(fb.w[ib].astype(float), 1e-30))
        d = fa.cols[ia] - fb.cols[ib]
    else:
        raise ValueError(f"candidates must be 'features' or 'correlation', not {candidates!r}")
    rc = np.minimum(rho, rho_cap)  # ρ → 1 would give an infinite weight
    wij = 0.5 * rc / (1 - rc) / np.maximum(sa * sb, 1e-12) / np.sqrt(tq)
    wij /= np.median(wij)  # scale-free weights (grey values and w cancel out)
    g = group[ia]
    fit = robust_plane_fit(u[ia], v[ia], d - d_pred[ia], wij, g, n_groups, **robust)
    n_cand = np.bincount(g, minlength=n_groups)
    n_out = np.bincount(g[~fit.inlier], minlength=n_groups)
    kept = one_to_one(ia, ib, wij * fit.weight, fit.inlier)
    match[ia[kept]] = ib[kept]
    disp[ia[kept]] = d[kept]
    rho_out[ia[kept]] = rho[kept]
    return OneWay(match, disp, rho_out, np.where(active, group, -1), fit, n_cand, n_out)


# ---- both directions + sub-pixel ----------------------------------------------------------------
@dataclass
class FBMResult:
    """Accepted matches of one level (left points) and per-group self-diagnosis.

    Point arrays (accepted left points): ``col, row`` (left, sub-pixel), ``disparity``
    (col_l − col_r, px of this level), ``rho`` (NCC), ``sigma_px`` (σ0 of the point's window,
    px), ``group``, ``index`` (into the left features), ``flags`` (:data:`FLAG_FEATURE_SUBPIXEL`).

    Group arrays: ``plane`` (n_groups, 3) absolute plane d = p0 + p1·u + p2·v of the accepted
    points (NaN where none), ``sigma0``, ``n_features``, ``n_candidates``, ``n_outliers``,
    ``n_accepted``, ``failed`` (features present, < min_points accepted).
    """

    col: NDArray
    row: NDArray
    disparity: NDArray
    rho: NDArray
    sigma_px: NDArray
    group: NDArray
    index: NDArray
    flags: NDArray
    plane: NDArray
    sigma0: NDArray
    n_features: NDArray
    n_candidates: NDArray
    n_outliers: NDArray
    n_accepted: NDArray
    failed: NDArray
    stats: Dict[str, int] = field(default_factory=dict)


def fbm_level(left: NDArray, right: NDArray, fl: InterestPoints, fr: InterestPoints,
              grouping: Grouping, predict: Predictor, *, ncc_window: int = 7,
              refine_window: int = 9, rho_min: float = 0.6, row_tol: float = 1.0,
              bidir_tol: Optional[float] = 1.0, min_points: int = 3,
              robust: Optional[dict] = None, candidates: str = "features",
              max_peaks: int = 3) -> FBMResult:
    """Bidirectional FBM of given features on one level (see the module docstring).

    Parameters
    ----------
    left, right : finite float32 images of the level
    fl, fr : Förstner points of both images (:func:`detect_features`)
    grouping : matching windows of the left image (:func:`window_components`)
    predict : ``predict(cols, rows) -> (d_pred, pull_in)`` for left positions; NaN = skip. The
        right→left pass evaluates it at the predicted left position of each right point.
    ncc_window : candidate-similarity window (seed ≈ 5 × 5)
    refine_window : window of the sub-pixel NCC refinement
    rho_min, row_tol, bidir_tol, min_points : thresholds (ρ, rows px, px, points per window);
        ``bidir_tol=None`` (or inf) switches the bidirectional check off
    robust : keyword arguments of :func:`robust_plane_fit`
    candidates : ``"features"`` (right interest points, the seed's FBM) or ``"correlation"``
        (local maxima of the NCC profile along the right row, :func:`correlation_candidates`;
        interest points in the left image only, as the best ISPRS approach, seed §3.4). With
        correlation candidates the right→left pass starts from the matched right positions
        and searches the left row over the same interval (``fr`` is then unused).
    max_peaks : correlation candidates per point (the highest local maxima)
    """
    robust = robust or {}
    ng = grouping.n_groups
    # left → right
    gl = grouping.of(fl.cols, fl.rows)
    dl, pl = predict(fl.cols, fl.rows)
    dl = np.where(gl >= 0, dl, np.nan)
    ul, vl = grouping.uv(fl.cols, fl.rows, np.maximum(gl, 0))
    mkw = dict(ncc_window=ncc_window, rho_min=rho_min, row_tol=row_tol,
               candidates=candidates, max_peaks=max_peaks, **robust)
    lr = match_oneway(left, right, fl, fr, dl, pl, gl, ul, vl, ng, **mkw)
    j = lr.match
    have = j >= 0
    back = np.full(j.size, np.nan)
    if candidates == "correlation":
        # right → left from the matched right positions, same interval and window as the
        # left point (in the right image's convention the disparity is col_r − col_l = −d)
        hv = np.flatnonzero(have)
        fr_m = InterestPoints(fl.cols[hv] - lr.disparity[hv], fl.rows[hv], fl.w[hv],
                              fl.q[hv])
        rl = match_oneway(right, left, fr_m, None, -dl[hv], pl[hv], gl[hv], ul[hv], vl[hv],
                          ng, **mkw)
        back[hv] = -rl.disparity
        d2 = np.where(have, dl, np.nan)
    else:
        # right → left: prediction and group at the predicted left position (two passes)
        d0, _ = predict(fr.cols, fr.rows)
        d0 = np.where(np.isfinite(d0), d0,
                      np.nanmedian(dl) if np.isfinite(dl).any() else 0.0)
        d1, _ = predict(fr.cols + d0, fr.rows)
        d1 = np.where(np.isfinite(d1), d1, d0)
        d2, p2 = predict(fr.cols + d1, fr.rows)
        gr = grouping.of(fr.cols + d1, fr.rows)
        d2 = np.where(gr >= 0, d2, np.nan)
        ur, vr = grouping.uv(fr.cols + d1, fr.rows, np.maximum(gr, 0))
        rl = match_oneway(right, left, fr, fl, -d2, p2, gr, ur, vr, ng, **mkw)
        back[have] = -rl.disparity[j[have]]
    if bidir_tol is None or not np.isfinite(bidir_tol):  # check switched off
        agree = have
    else:
        agree = have & (np.abs(lr.disparity - back) <= bidir_tol)
    n_bidir_rejected = int(have.sum() - agree.sum())
    # windows with too few consistent points fail
    cnt = np.bincount(gl[agree], minlength=ng)
    agree &= cnt[np.maximum(gl, 0)] >= min_points
    idx = np.flatnonzero(agree)
    col, row = fl.cols[idx], fl.rows[idx]
    d_feat = lr.disparity[idx]
    rho = lr.rho[idx]
    flags = np.zeros(idx.size, np.uint8)
    disp = d_feat.copy()
    if idx.size:
        d0r = np.rint(d_feat)
        res = ncc_epipolar(left, right, col, row, d0r - 2, d0r + 2, window=refine_window,
                           min_ncc=rho_min, max_ratio=1.0)
        good = res.valid & (np.abs(res.disparity - d_feat) <= 1.0)
        disp = np.where(good, res.disparity, d_feat)
        rho = np.where(good, res.ncc, rho)
        flags[~good] |= FLAG_FEATURE_SUBPIXEL
    g = gl[idx]
    # self-diagnosis: the absolute plane of the accepted points and its σ0
    plane = np.full((ng, 3), np.nan)
    sigma0 = np.full(ng, np.nan)
    n_acc = np.bincount(g, minlength=ng)
    if idx.size:
        u, v = grouping.uv(col, row, g)
        a = group_wls(u, v, disp, np.ones(idx.size), g, ng, 1e-3)
        e = disp - (a[g, 0] + a[g, 1] * u + a[g, 2] * v)
        dof = np.maximum(n_acc - 3, 1)
        s0 = np.sqrt(np.bincount(g, e * e, ng) / dof)
        has = n_acc > 0
        plane[has] = a[has]
        sigma0[has] = s0[has]
    n_feat = np.bincount(gl[gl >= 0], minlength=ng)
    tried = np.bincount(gl[np.isfinite(dl)], minlength=ng) > 0
    failed = tried & (n_acc == 0)
    sig = np.maximum(np.nan_to_num(sigma0[g], nan=0.5), 0.05)
    stats = {
        "features_left": int(np.isfinite(dl).sum()),
        "features_right": int(np.isfinite(d2).sum()),
        "candidates": int(lr.n_candidates.sum()),
        "outliers": int(lr.n_outliers.sum()),
        "bidir_rejected": n_bidir_rejected,
        "accepted": int(idx.size),
        "subpixel_failed": int((flags & FLAG_FEATURE_SUBPIXEL > 0).sum()),
    }
    return FBMResult(col, row, disp, rho.astype(np.float32), sig.astype(np.float32), g, idx,
                     flags, plane, sigma0, n_feat, lr.n_candidates, lr.n_outliers, n_acc,
                     failed, stats)


def fbm_match(left: NDArray, right: NDArray, min_d: float, max_d: float, *,
              predict: Optional[Predictor] = None, window: int = 32,
              barriers: Optional[NDArray] = None, mask: Optional[NDArray] = None,
              interest_window: int = 5, q_min: float = 0.6, w_factor: float = 1.0,
              nms_window: int = 5, **kwargs) -> FBMResult:
    """Single-level FBM of an epipolar pair (convenience wrapper of :func:`fbm_level`).

    Without ``predict`` every left point searches the whole range ``[min_d, max_d]``. ``mask``
    (left shape, True = no points) and ``barriers`` (True = breakline pixel) are optional; NaN
    pixels are nodata. ``kwargs`` go to :func:`fbm_level`.
    """
    L, vl = fill_nodata(left)
    R, vr = fill_nodata(right)
    margin = max(kwargs.get("ncc_window", 7), kwargs.get("refine_window", 9)) // 2 + 2
    excl = None
    if mask is not None or barriers is not None:
        excl = np.zeros(L.shape, bool)
        for m in (mask, barriers):
            if m is not None:
                excl |= np.asarray(m, bool)
    kw = {"window": interest_window, "q_min": q_min, "w_factor": w_factor,
          "nms_window": nms_window, "margin": margin}
    fl = detect_features(L, vl, excl, **kw)
    fr = detect_features(R, vr, None, **kw)
    grouping = window_components(L.shape, window, barriers)
    if predict is None:
        mid, half = 0.5 * (min_d + max_d), 0.5 * (max_d - min_d)

        def predict(cols, rows):
            return np.full(np.shape(cols), mid), np.full(np.shape(cols), half)

    return fbm_level(L, R, fl, fr, grouping, predict, **kwargs)
