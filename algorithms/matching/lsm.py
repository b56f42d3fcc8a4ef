r"""Least-squares matching (LSM, Ackermann 1983) of many points at once.

A template window of the left image, centred on a point :math:`(x_1, y_1)`, is matched into the
right (search) image by a geometric and a radiometric transformation. With template coordinates
:math:`(\xi, \eta)` relative to the point (pixels, −h … h):

.. math::

    x_2 = a_0 + a_1 \xi + a_2 \eta, \qquad y_2 = b_0 + b_1 \xi + b_2 \eta, \qquad
    g_1(\xi, \eta) + v = r_0 + r_1\, g_2(x_2, y_2)

so :math:`(a_0, b_0)` is the matched position of the point in the search image. Gauss–Newton
linearisation at the current parameters gives per template pixel

.. math::

    \Delta g + v = dr_0 + g_2^0\,dr_1 + r_1 g_x (da_0 + \xi\,da_1 + \eta\,da_2)
                 + r_1 g_y (db_0 + \xi\,db_1 + \eta\,db_2), \quad
    \Delta g = g_1 - (r_0 + r_1 g_2^0)

where :math:`g_2^0, g_x, g_y` are the search window resampled bilinearly at the current
:math:`(x_2, y_2)` and its gradients. The gradients are central differences of the resampled
window (taken along ξ, η) transformed to the image axes with the inverse of the affine
Jacobian. Normal equations :math:`(A^T A)\,dx = A^T \Delta g` are solved for all points as one
batch of small systems.

Models
------
``"affine"``: 6 geometric + 2 radiometric = 8 unknowns :math:`(a_0,a_1,a_2,b_0,b_1,b_2,r_0,r_1)`.

``"epipolar"``: for normalised (epipolar) images the rows correspond, :math:`y_2 = y_1` (more
generally :math:`y_2 = b_0 + \eta` with :math:`b_0` fixed at its start value), and the geometric
unknowns are the seed's three (2-22): :math:`x_2 = a_0 + a_1 \xi + a_2 \eta` — the shift
:math:`a_0` (the disparity), the scale in x :math:`a_1` (terrain slope along the base) and the
shear :math:`a_2` (slope across the base) — plus :math:`r_0, r_1`: 5 unknowns.

``"shift"``: 2 shifts + 2 radiometric (a quick variant for flat terrain and tests).

Precision
---------
:math:`\hat\sigma_0^2 = v^Tv / (n - u)` (n template pixels, u unknowns) and
:math:`\Sigma_{xx} = \hat\sigma_0^2 (A^TA)^{-1}`; the shift precisions are
:math:`\sigma_x = \sqrt{\Sigma_{a_0a_0}}`, :math:`\sigma_y = \sqrt{\Sigma_{b_0b_0}}` in pixels of
the search image. The correlation coefficient of the template and the final resampled window is
returned too.

Failure flags (bits of ``LSMResult.flags``; 0 = a good match) — see the ``FLAG_*`` constants.
"""

from __future__ import annotations

from typing import NamedTuple, Optional

import numpy as np
from numpy.typing import ArrayLike, NDArray

# ---- failure flags (bit field) -----------------------------------------------------------------
#: the iteration limit was reached before the shift increments fell below ``tol_shift``
FLAG_NOT_CONVERGED = 1
#: the shift left the pull-in range (``max_shift`` from the start), or scale / contrast became
#: implausible (divergence)
FLAG_DIVERGED = 2
#: the normal matrix is (numerically) singular: no texture in the needed directions
FLAG_SINGULAR = 4
#: the template or the transformed search window leaves its image
FLAG_OUTSIDE = 8
#: the correlation coefficient after matching is below ``min_corr``
FLAG_LOW_CORRELATION = 16
#: the estimated shift precision is worse than ``max_sigma`` px
FLAG_HIGH_SIGMA = 32
#: the template has (almost) no contrast: its grey-value σ is below ``min_contrast``
FLAG_TEXTURELESS = 64

FLAG_NAMES = {
    FLAG_NOT_CONVERGED: "not_converged",
    FLAG_DIVERGED: "diverged",
    FLAG_SINGULAR: "singular",
    FLAG_OUTSIDE: "outside",
    FLAG_LOW_CORRELATION: "low_correlation",
    FLAG_HIGH_SIGMA: "high_sigma",
    FLAG_TEXTURELESS: "textureless",
}

#: parameter order of ``LSMResult.params`` (all models; fixed ones keep their start value)
PARAM_NAMES = ("a0", "a1", "a2", "b0", "b1", "b2", "r0", "r1")

_MODELS = {
    "affine": (0, 1, 2, 3, 4, 5, 6, 7),
    "epipolar": (0, 1, 2, 6, 7),
    "shift": (0, 3, 6, 7),
}


class LSMResult(NamedTuple):
    """Result of :func:`lsm_match` for n points (arrays of length n unless noted).

    Attributes
    ----------
    cols, rows : float64
        Matched position in the search image (a0, b0).
    params : (n, 8) float64
        a0, a1, a2, b0, b1, b2, r0, r1 (see :data:`PARAM_NAMES`).
    sigma0 : float32
        σ̂0 of the grey-value residuals (grey values).
    sigma_col, sigma_row : float32
        Estimated standard deviation of the matched position, pixels (σ_row is 0 for
        ``epipolar``, where the row is fixed).
    cov : (n, u, u) float64
        Covariance of the estimated unknowns (the model's parameter subset, in the order of
        :data:`PARAM_NAMES`).
    corr : float32
        Correlation coefficient of template and final resampled search window.
    iterations : int16
        Gauss–Newton iterations used.
    flags : uint8
        Failure bits (``FLAG_*``); 0 = good.
    valid : bool
        ``flags == 0``.
    """

    cols: NDArray
    rows: NDArray
    params: NDArray
    sigma0: NDArray
    sigma_col: NDArray
    sigma_row: NDArray
    cov: NDArray
    corr: NDArray
    iterations: NDArray
    flags: NDArray
    valid: NDArray


def describe_flags(flags: int) -> str:
    """Comma-separated names of the bits set in one ``flags`` value ('ok' when 0)."""
    names = [name for bit, name in FLAG_NAMES.items() if int(flags) & bit]
    return ", ".join(names) if names else "ok"


def _bilinear(flat: NDArray, width: int, height: int, x: NDArray, y: NDArray):
    """Bilinear samples of an image (flattened float32) at (x, y), shape (n, m).

    Returns the samples (float32) and, per row (point), whether all its samples are inside
    [0, width−1] × [0, height−1]. Positions are split into an integer base per point and
    float32 offsets, which keeps the per-sample arithmetic in 32 bit.
    """
    bx = np.floor(x[:, :1])
    by = np.floor(y[:, :1])
    xl = (x - bx).astype(np.float32)
    yl = (y - by).astype(np.float32)
    inside = ((bx[:, 0] + xl.min(axis=1) >= 0) & (bx[:, 0] + xl.max(axis=1) <= width - 1)
              & (by[:, 0] + yl.min(axis=1) >= 0) & (by[:, 0] + yl.max(axis=1) <= height - 1))
    xf = np.floor(xl)
    yf = np.floor(yl)
    fx = xl - xf
    fy = yl - yf
    base = (by * width + bx).astype(np.int64)
    idx = base + (yf * width + xf).astype(np.int64)
    # outside points are flagged by the caller; keep their indices in range
    np.clip(idx, 0, flat.size - width - 2, out=idx)
    # np.take is much faster than fancy indexing for flat gathers
    v00 = np.take(flat, idx)
    idx += 1
    v01 = np.take(flat, idx)
    idx += width
    v11 = np.take(flat, idx)
    idx -= 1
    v10 = np.take(flat, idx)
    top = v00 + fx * (v01 - v00)
    bot = v10 + fx * (v11 - v10)
    return top + fy * (bot - top), inside


def extract_windows(image: NDArray, cols: ArrayLike, rows: ArrayLike, half: int):
    """Windows of (2·half+1)² pixels centred on sub-pixel positions, by bilinear resampling.

    Returns
    -------
    windows : (n, 2h+1, 2h+1) float32
    inside : (n,) bool — the whole window lies inside the image.
    """
    img = np.ascontiguousarray(image, dtype=np.float32)
    height, width = img.shape
    c = np.asarray(cols, dtype=np.float64).reshape(-1, 1)
    r = np.asarray(rows, dtype=np.float64).reshape(-1, 1)
    off = np.arange(-half, half + 1, dtype=np.float64)
    xi, eta = np.meshgrid(off, off)
    vals, ins = _bilinear(img.ravel(), width, height, c + xi.ravel(), r + eta.ravel())
    size = 2 * half + 1
    return vals.reshape(-1, size, size), ins


def _corrcoef_rows(a: NDArray, b: NDArray) -> NDArray:
    """Correlation coefficient of corresponding rows of a and b, shape (n, m)."""
    az = a - a.mean(axis=1, keepdims=True)
    bz = b - b.mean(axis=1, keepdims=True)
    num = np.einsum("ij,ij->i", az, bz)
    den = np.sqrt(np.einsum("ij,ij->i", az, az) * np.einsum("ij,ij->i", bz, bz))
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(den > 0, num / np.where(den > 0, den, 1.0), 0.0)


def lsm_match(template_image: NDArray, search_image: NDArray,
              cols: ArrayLike, rows: ArrayLike,
              init_cols: ArrayLike, init_rows: Optional[ArrayLike] = None,
              window: int = 15, model: str = "affine",
              init_params: Optional[NDArray] = None,
              max_iter: int = 20, tol_shift: float = 0.01, max_shift: float = 3.0,
              min_corr: float = 0.7, max_sigma: float = 0.2, min_contrast: float = 1e-3,
              scale_range: tuple = (0.5, 2.0), contrast_range: tuple = (0.3, 3.0),
              jacobian: str = "template", chunk: int = 4096) -> LSMResult:
    r"""Least-squares matching of many points as one batch (Gauss–Newton, bilinear resampling).

    Parameters
    ----------
    template_image, search_image : (rows, cols) arrays
        Left (template) and right (search) image, finite grey values. Both are used as float32.
    cols, rows : (n,) array_like
        Template centres in the template image (sub-pixel allowed; resampled bilinearly).
    init_cols, init_rows : (n,) array_like
        Approximate matched positions in the search image (a0, b0 start values). For
        ``model="epipolar"`` ``init_rows`` defaults to ``rows`` and stays fixed.
    window : int
        Template size in pixels (odd; 15–21 typical, the seed uses 16 and 10–29).
    model : {"affine", "epipolar", "shift"}
        Unknowns, see the module docstring.
    init_params : (n, 8) array, optional
        Full start parameters (a0…r1), e.g. the affine from feature-based matching; overrides
        ``init_cols/init_rows``. Default: identity geometry, r0 = 0, r1 = 1.
    max_iter : int
        Iteration limit (the seed: 10–20).
    tol_shift : float
        Convergence when |da0| and |db0| < tol_shift px (and scale/shear increments
        < tol_shift / half-window, i.e. < tol_shift px at the window border).
    max_shift : float
        Pull-in limit: a shift further than this (px) from the start is a divergence.
    min_corr : float
        Matches whose final correlation coefficient is below this are flagged (seed: ρ > 0.7).
    max_sigma : float
        Matches with σ of the shift above this (px) are flagged (seed: σ_px < 0.2 px).
    min_contrast : float
        Template grey-value σ below this marks the point as textureless (not even tried).
    scale_range, contrast_range : (float, float)
        Plausible range of the affine singular values and of r1; outside = divergence.
    jacobian : {"template", "search"}
        Where the grey-value gradients of the design matrix come from. ``"search"`` is the
        classic form: gradients of the resampled search window, a new normal matrix every
        iteration. ``"template"`` (default, about 3× faster) takes them from the template,
        mapped by the current affine and contrast (A = A0·T(p), so AᵀA = Tᵀ(A0ᵀA0)T and only
        A0ᵀΔg is formed per iteration); both converge to the same solution for
        noise-free data, and their precision agrees within a few per cent.
    chunk : int
        Points processed together (bounds the memory: about 60 · chunk · window² bytes).

    Returns
    -------
    LSMResult
    """
    if model not in _MODELS:
        raise ValueError(f"unknown LSM model {model!r}; use one of {sorted(_MODELS)}")
    if jacobian not in ("template", "search"):
        raise ValueError("jacobian must be 'template' or 'search'")
    if window < 3 or window % 2 == 0:
        raise ValueError("window must be an odd number ≥ 3")
    tpl = np.ascontiguousarray(template_image, dtype=np.float32)
    srch = np.ascontiguousarray(search_image, dtype=np.float32)
    cols = np.atleast_1d(np.asarray(cols, dtype=np.float64))
    rows = np.atleast_1d(np.asarray(rows, dtype=np.float64))
    n = cols.size
    if init_params is not None:
        p0 = np.array(init_params, dtype=np.float64).reshape(n, 8)
    else:
        p0 = np.zeros((n, 8))
        p0[:, 0] = np.broadcast_to(np.asarray(init_cols, dtype=np.float64), (n,))
        p0[:, 3] = rows if init_rows is None else np.broadcast_to(
            np.asarray(init_rows, dtype=np.float64), (n,))
        p0[:, 1] = p0[:, 5] = p0[:, 7] = 1.0
    idx = _MODELS[model]
    u = len(idx)
    half = window // 2
    out = {
        "params": p0.copy(),
        "sigma0": np.full(n, np.nan, np.float32),
        "sig_c": np.full(n, np.nan, np.float32),
        "sig_r": np.full(n, np.nan, np.float32),
        "cov": np.full((n, u, u), np.nan),
        "corr": np.zeros(n, np.float32),
        "iters": np.zeros(n, np.int16),
        "flags": np.zeros(n, np.uint8),
    }
    for start in range(0, n, chunk):
        sl = slice(start, min(n, start + chunk))
        _lsm_chunk(tpl, srch, cols[sl], rows[sl], p0[sl], idx, half, max_iter, tol_shift,
                   max_shift, min_corr, max_sigma, min_contrast, scale_range, contrast_range,
                   jacobian, out, sl)
    p = out["params"]
    if model == "epipolar":
        out["sig_r"] = np.where(np.isfinite(out["sig_c"]), 0.0, np.nan).astype(np.float32)
    flags = out["flags"]
    return LSMResult(p[:, 0].copy(), p[:, 3].copy(), p, out["sigma0"], out["sig_c"],
                     out["sig_r"], out["cov"], out["corr"], out["iters"], flags, flags == 0)


def _lsm_chunk(tpl, srch, cols, rows, p0, idx, half, max_iter, tol_shift, max_shift, min_corr,
               max_sigma, min_contrast, scale_range, contrast_range, jacobian, out, sl):
    """Gauss–Newton for one chunk of points; writes into ``out[...][sl]``."""
    n = cols.size
    size = 2 * half + 1
    m = size * size
    u = len(idx)
    height, width = srch.shape
    flat = srch.ravel()
    # template (fixed) and the template-frame grids
    ge1, t_inside = extract_windows(tpl, cols, rows, half + 1)
    g1 = np.ascontiguousarray(ge1[:, 1:-1, 1:-1]).reshape(n, m)
    off = np.arange(-half - 1, half + 2, dtype=np.float32)
    xi_e, eta_e = np.meshgrid(off, off)  # extended grid: one extra pixel for the gradients
    xi_e, eta_e = xi_e.ravel(), eta_e.ravel()
    xi = xi_e.reshape(size + 2, size + 2)[1:-1, 1:-1].ravel()
    eta = eta_e.reshape(size + 2, size + 2)[1:-1, 1:-1].ravel()

    p = p0.copy()
    flags = np.zeros(n, np.uint8)
    flags[~t_inside] |= FLAG_OUTSIDE
    flags[g1.std(axis=1) < min_contrast] |= FLAG_TEXTURELESS
    iters = np.zeros(n, np.int16)
    converged = np.zeros(n, bool)
    last_N = np.zeros((n, u, u))
    last_vv = np.full(n, np.nan)
    last_corr = np.zeros(n)
    active = np.flatnonzero(flags == 0)
    tol_lin = tol_shift / max(half, 1)
    smin, smax = scale_range
    cmin, cmax = contrast_range

    if jacobian == "template":
        # A0: the Jacobian columns built from the template itself (fixed over the iterations);
        # the current Jacobian is A0·T(p), so only A0ᵀΔg has to be formed per iteration.
        t_xi = (0.5 * (ge1[:, 1:-1, 2:] - ge1[:, 1:-1, :-2])).reshape(n, m)
        t_eta = (0.5 * (ge1[:, 2:, 1:-1] - ge1[:, :-2, 1:-1])).reshape(n, m)
        A0 = np.stack((t_xi, t_xi * xi, t_xi * eta, t_eta, t_eta * xi, t_eta * eta,
                       np.ones_like(g1), g1), axis=2)  # (n, m, 8) float32
        N0 = np.matmul(A0.transpose(0, 2, 1), A0).astype(np.float64)
        A0t = np.ascontiguousarray(A0.transpose(0, 2, 1))  # (n, 8, m)
        del A0
        loc = np.arange(n)  # point index of each row of A0t / N0

    for it in range(max_iter):
        if active.size == 0:
            break
        pa = p[active]
        a0, a1, a2 = pa[:, 0:1], pa[:, 1:2], pa[:, 2:3]
        b0, b1, b2 = pa[:, 3:4], pa[:, 4:5], pa[:, 5:6]
        r0, r1 = pa[:, 6:7], pa[:, 7:8]
        det = a1 * b2 - a2 * b1
        inv_det = 1.0 / np.where(np.abs(det) > 1e-6, det, 1e-6)
        if jacobian == "template":
            x2 = a0 + a1 * xi + a2 * eta
            y2 = b0 + b1 * xi + b2 * eta
            g2, ins = _bilinear(flat, width, height, x2, y2)
            outside = ~ins
            resid = g1[active] - (r0.astype(np.float32) + r1.astype(np.float32) * g2)
            if len(active) < 0.8 * len(loc):  # compact the per-point arrays to the active set
                keep = np.searchsorted(loc, active)
                A0t, N0, loc = A0t[keep], N0[keep], active
            sel = np.searchsorted(loc, active)
            At_a = A0t if len(sel) == len(loc) else A0t[sel]
            bfull = np.einsum("nkm,nm->nk", At_a, resid).astype(np.float64)
            # r1·(gx, gy) ≈ J⁻ᵀ (∂g1/∂ξ, ∂g1/∂η) and g2 ≈ (g1 − r0)/r1  →  A = A0·T
            c00, c01 = b2[:, 0] * inv_det[:, 0], -b1[:, 0] * inv_det[:, 0]
            c10, c11 = -a2[:, 0] * inv_det[:, 0], a1[:, 0] * inv_det[:, 0]
            T = np.zeros((len(active), 8, 8))
            for j in range(3):  # geometric columns: a_j from (ξ-part j, η-part j+3)
                T[:, j, j], T[:, j + 3, j] = c00, c01
                T[:, j, j + 3], T[:, j + 3, j + 3] = c10, c11
            T[:, 6, 6] = 1.0
            T[:, 7, 7] = 1.0 / r1[:, 0]
            T[:, 6, 7] = -r0[:, 0] / r1[:, 0]
            T = T[:, :, idx]
            N = np.einsum("nki,nkl,nlj->nij", T, N0[sel], T, optimize=True)
            b = np.einsum("nki,nk->ni", T, bfull)
        else:
            # resample the extended search window (one extra pixel for the gradients)
            x2 = a0 + a1 * xi_e + a2 * eta_e
            y2 = b0 + b1 * xi_e + b2 * eta_e
            ge, ins = _bilinear(flat, width, height, x2, y2)
            outside = ~ins
            ge = ge.reshape(-1, size + 2, size + 2)
            g2 = ge[:, 1:-1, 1:-1].reshape(-1, m)
            gxi = (0.5 * (ge[:, 1:-1, 2:] - ge[:, 1:-1, :-2])).reshape(-1, m)
            geta = (0.5 * (ge[:, 2:, 1:-1] - ge[:, :-2, 1:-1])).reshape(-1, m)
            # ∂g/∂ξ = gx·a1 + gy·b1, ∂g/∂η = gx·a2 + gy·b2  →  solve for (gx, gy)
            f = (inv_det * r1).astype(np.float32)
            gx = (gxi * b2.astype(np.float32) - geta * b1.astype(np.float32)) * f
            gy = (geta * a1.astype(np.float32) - gxi * a2.astype(np.float32)) * f
            all_cols = (gx, gx * xi, gx * eta, gy, gy * xi, gy * eta, np.ones_like(g2), g2)
            A = np.stack([all_cols[k] for k in idx], axis=2)  # (na, m, u) float32
            resid = g1[active] - (r0.astype(np.float32) + r1.astype(np.float32) * g2)
            At = A.transpose(0, 2, 1)
            N = np.matmul(At, A).astype(np.float64)
            b = np.matmul(At, resid[:, :, None]).astype(np.float64)[:, :, 0]
        # Jacobi-scaled normal matrix for a scale-free singularity test (first iteration only in
        # the template mode, where N changes only by the small transformation T)
        d = np.sqrt(np.maximum(np.einsum("nii->ni", N), 1e-30))
        Ns = N / (d[:, :, None] * d[:, None, :])
        if it == 0 or jacobian != "template":
            ev_min = np.linalg.eigvalsh(Ns)[:, 0]
            singular = ~(ev_min > 1e-7)
        else:
            singular = np.zeros(len(active), bool)
        Ns_safe = np.where(singular[:, None, None], np.eye(u), Ns)
        dx = np.linalg.solve(Ns_safe, (b / d)[:, :, None])[:, :, 0] / d
        dx[singular] = 0.0

        # bookkeeping of the state *at* the current parameters (used if this is the last step)
        last_N[active] = N
        vv = np.einsum("ij,ij->i", resid, resid, dtype=np.float64)
        last_vv[active] = vv
        last_corr[active] = _corrcoef_rows(g1[active], g2)

        full = np.zeros((len(active), 8))
        full[:, idx] = dx
        pn = pa + full
        iters[active] = it + 1
        # failure tests
        bad = np.zeros(len(active), np.uint8)
        bad[outside] |= FLAG_OUTSIDE
        bad[singular] |= FLAG_SINGULAR
        drift = np.hypot(pn[:, 0] - p0[active, 0], pn[:, 3] - p0[active, 3])
        det_n = pn[:, 1] * pn[:, 5] - pn[:, 2] * pn[:, 4]
        fro = pn[:, 1] ** 2 + pn[:, 2] ** 2 + pn[:, 4] ** 2 + pn[:, 5] ** 2
        # singular values of the 2×2 affine: s² = (fro ± sqrt(fro² − 4 det²)) / 2
        disc = np.sqrt(np.maximum(fro * fro - 4 * det_n * det_n, 0.0))
        s_hi = np.sqrt(0.5 * (fro + disc))
        s_lo = np.sqrt(np.maximum(0.5 * (fro - disc), 0.0))
        implausible = ((drift > max_shift) | (s_hi > smax) | (s_lo < smin) | (det_n <= 0)
                       | (pn[:, 7] < cmin) | (pn[:, 7] > cmax) | ~np.isfinite(pn).all(axis=1))
        bad[implausible & ~singular & ~outside] |= FLAG_DIVERGED
        ok = bad == 0
        p[active[ok]] = pn[ok]
        flags[active] |= bad
        done = ok & (np.abs(dx[:, 0]) < tol_shift)
        done &= np.abs(full[:, 3]) < tol_shift
        done &= (np.abs(full[:, [1, 2, 4, 5]]) < tol_lin).all(axis=1)
        converged[active[done]] = True
        active = active[ok & ~done]

    flags[(flags == 0) & ~converged] |= FLAG_NOT_CONVERGED
    # precision from the last normal matrix: Σ = σ0² N⁻¹
    m_red = m - u
    sigma0 = np.sqrt(last_vv / max(m_red, 1))
    have = np.isfinite(sigma0) & ((flags & (FLAG_SINGULAR | FLAG_OUTSIDE | FLAG_TEXTURELESS)) == 0)
    cov = np.full((n, u, u), np.nan)
    if have.any():
        Nh = last_N[have]
        d = np.sqrt(np.maximum(np.einsum("nii->ni", Nh), 1e-30))
        Qs = np.linalg.inv(Nh / (d[:, :, None] * d[:, None, :]))
        Q = Qs / (d[:, :, None] * d[:, None, :])
        cov[have] = Q * (sigma0[have] ** 2)[:, None, None]
    pos_c = idx.index(0)
    sig_c = np.sqrt(cov[:, pos_c, pos_c])
    sig_r = np.sqrt(cov[:, idx.index(3), idx.index(3)]) if 3 in idx else np.zeros(n)
    flags[(flags == 0) & (last_corr < min_corr)] |= FLAG_LOW_CORRELATION
    flags[(flags == 0) & ~(np.maximum(sig_c, sig_r) <= max_sigma)] |= FLAG_HIGH_SIGMA

    out["params"][sl] = p
    out["sigma0"][sl] = sigma0
    out["sig_c"][sl] = sig_c
    out["sig_r"][sl] = sig_r
    out["cov"][sl] = cov
    out["corr"][sl] = last_corr
    out["iters"][sl] = iters
    out["flags"][sl] = flags
