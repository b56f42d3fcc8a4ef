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

from dataclasses import dataclass
from typing import NamedTuple, Optional, Tuple

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


def _affine_sampler(flat: NDArray, width: int, height: int, p: NDArray, grid: NDArray,
                    reach: float):
    r"""Bilinear samples of a flattened float32 image on affinely mapped grids, shape (n, m).

    Sample j of point i is at :math:`x = a_0 + a_1\xi_j + a_2\eta_j`,
    :math:`y = b_0 + b_1\xi_j + b_2\eta_j` with ``p[i] = (a0, a1, a2, b0, b1, b2, …)`` and
    ``grid = (ξ, η)`` (float32, −reach … reach). Bilinear:
    :math:`g = (1-f_y)[(1-f_x)v_{00} + f_x v_{01}] + f_y[(1-f_x)v_{10} + f_x v_{11}]`.

    Positions are split into an integer base per point, :math:`\lfloor a_0\rfloor,
    \lfloor b_0\rfloor`, and float32 local coordinates relative to it, so all per-sample
    arithmetic is 32 bit, and the four neighbours are gathered from shifted views of the image
    (no index arithmetic per neighbour). An axis whose mapping is the identity for all points
    (rows of epipolar images, both axes of the shift model and of template extraction) has
    integer sample offsets and one fraction per point: no per-sample floor for it. The
    ``inside`` test is exact per point: an affine map of the square grid has its extremes at
    the corners, :math:`a_0 \pm reach\,(|a_1| + |a_2|)`. Rows that are not inside are sampled
    at the image origin (their values are meaningless; the caller flags them).

    Returns
    -------
    values : (n, m) float32
    inside : (n,) bool — all samples lie in [0, width−1] × [0, height−1].
    """
    n = p.shape[0]
    ext_x = reach * (np.abs(p[:, 1]) + np.abs(p[:, 2]))
    ext_y = reach * (np.abs(p[:, 4]) + np.abs(p[:, 5]))
    inside = ((p[:, 0] - ext_x >= 0) & (p[:, 0] + ext_x <= width - 1)
              & (p[:, 3] - ext_y >= 0) & (p[:, 3] + ext_y <= height - 1)
              & np.isfinite(p[:, :6]).all(axis=1))
    q = np.where(inside[:, None], p[:, :6], np.array([0.0, 1, 0, 0, 0, 1]))
    bx = np.floor(q[:, 0])
    by = np.floor(q[:, 3])
    base = (by * width + bx).astype(np.int64)[:, None]
    xi, eta = grid

    def axis(f0, c_xi, c_eta, ident):
        # integer offsets (float32, exact) and fractions of one axis
        if ident is not None:  # x = base + f0 + ξ (or η): integer offsets, one fraction/point
            return ident[None, :], f0.astype(np.float32)[:, None]
        # elementwise rather than a K = 3 matrix product: BLAS threading makes that erratic
        loc = np.multiply.outer(c_xi.astype(np.float32), xi)
        loc += np.multiply.outer(c_eta.astype(np.float32), eta)
        loc += f0.astype(np.float32)[:, None]
        whole = np.floor(loc)
        loc -= whole
        return whole, loc

    ident_x = xi if np.all(q[:, 1] == 1) and np.all(q[:, 2] == 0) else None
    ident_y = eta if np.all(q[:, 4] == 0) and np.all(q[:, 5] == 1) else None
    xw, fx = axis(q[:, 0] - bx, q[:, 1], q[:, 2], ident_x)
    yw, fy = axis(q[:, 3] - by, q[:, 4], q[:, 5], ident_y)
    # index offsets are exact in float32 while |off| < 2**24 (always, unless the windows are
    # huge or extremely distorted in a very wide image: then 64 bit)
    big = (np.max(ext_y[inside], initial=0.0) + 2) * width + np.max(ext_x[inside], initial=0.0)
    off = yw * (np.float32(width) if big < 2**23 else np.float64(width))
    if off.shape == np.broadcast(off, xw).shape:
        off += xw
    else:
        off = off + xw
    if off.shape[0] == n:
        idx = off.astype(np.int64)
        idx += base
    else:  # integer offsets on both axes (shift): one index row for all points
        idx = off.astype(np.int64) + base
    if not np.all((p[inside, 0] - ext_x[inside] >= 1) & (p[inside, 0] + ext_x[inside] < width - 2)
                  & (p[inside, 3] - ext_y[inside] >= 1)
                  & (p[inside, 3] + ext_y[inside] < height - 2)):
        # a window within a pixel of the border: float32 rounding must not leave the image
        np.clip(idx, 0, flat.size - width - 2, out=idx)
    # gathers from shifted views of the image: no index arithmetic per neighbour
    v00 = flat[idx]
    v01 = flat[1:][idx]
    v10 = flat[width:][idx]
    v11 = flat[width + 1:][idx]
    v01 -= v00
    v01 *= fx
    v01 += v00  # top row
    v11 -= v10
    v11 *= fx
    v11 += v10  # bottom row
    v11 -= v01
    v11 *= fy
    v11 += v01
    return v11, inside


def _grid(half: int) -> NDArray:
    """(ξ, η) of a (2·half+1)² window, row-major, shape (2, m) float32."""
    off = np.arange(-half, half + 1, dtype=np.float32)
    xi, eta = np.meshgrid(off, off)
    return np.stack((xi.ravel(), eta.ravel()))


def extract_windows(image: NDArray, cols: ArrayLike, rows: ArrayLike, half: int):
    """Windows of (2·half+1)² pixels centred on sub-pixel positions, by bilinear resampling.

    Returns
    -------
    windows : (n, 2h+1, 2h+1) float32
    inside : (n,) bool — the whole window lies inside the image.
    """
    img = np.ascontiguousarray(image, dtype=np.float32)
    height, width = img.shape
    c = np.atleast_1d(np.asarray(cols, dtype=np.float64))
    r = np.atleast_1d(np.asarray(rows, dtype=np.float64))
    p = np.zeros((c.size, 6))
    p[:, 0], p[:, 3] = c, r
    p[:, 1] = p[:, 5] = 1.0
    vals, ins = _affine_sampler(img.ravel(), width, height, p, _grid(half), half)
    size = 2 * half + 1
    return vals.reshape(-1, size, size), ins


def lsm_match(template_image: NDArray, search_image: NDArray,
              cols: ArrayLike, rows: ArrayLike,
              init_cols: ArrayLike, init_rows: Optional[ArrayLike] = None,
              window: int = 15, model: str = "affine",
              init_params: Optional[NDArray] = None,
              max_iter: int = 20, tol_shift: float = 0.01, max_shift: float = 3.0,
              min_corr: float = 0.7, max_sigma: float = 0.2, min_contrast: float = 1e-3,
              scale_range: tuple = (0.5, 2.0), contrast_range: tuple = (0.3, 3.0),
              jacobian: str = "template", chunk: Optional[int] = None) -> LSMResult:
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
    chunk : int, optional
        Points processed together (bounds the memory: about 60 · chunk · window² bytes). The
        default, 2¹⁸ / (window + 2)² (≈ 900 points for 15 × 15), keeps a chunk's per-sample
        arrays in the CPU cache: larger chunks are markedly slower, not faster.

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
    if chunk is None:
        chunk = max(16, 2**18 // (window + 2) ** 2)
    cfg = _Settings(tuple(idx), half, max_iter, tol_shift, max_shift, min_corr, max_sigma,
                    min_contrast, scale_range, contrast_range, jacobian)
    for start in range(0, n, int(chunk)):
        sl = slice(start, min(n, start + chunk))
        _lsm_chunk(tpl, srch, cols[sl], rows[sl], p0[sl], cfg, out, sl)
    p = out["params"]
    if model == "epipolar":
        out["sig_r"] = np.where(np.isfinite(out["sig_c"]), 0.0, np.nan).astype(np.float32)
    flags = out["flags"]
    return LSMResult(p[:, 0].copy(), p[:, 3].copy(), p, out["sigma0"], out["sig_c"],
                     out["sig_r"], out["cov"], out["corr"], out["iters"], flags, flags == 0)


def _singular(Ns: NDArray, eps: float = 1e-7) -> NDArray:
    """Per matrix: is the smallest eigenvalue of the (unit-diagonal) normal matrix ≤ eps?

    λ_min > eps ⇔ Ns − eps·I is positive definite ⇔ its Cholesky factorisation exists; that
    batch test is several times cheaper than eigenvalues, which are computed only when some
    matrix of the batch fails it.
    """
    u = Ns.shape[-1]
    if np.isfinite(Ns).all():
        try:
            np.linalg.cholesky(Ns - eps * np.eye(u))
            return np.zeros(Ns.shape[0], bool)
        except np.linalg.LinAlgError:
            pass
    with np.errstate(invalid="ignore"):
        safe = np.where(np.isfinite(Ns), Ns, 0.0)
        return ~(np.linalg.eigvalsh(safe)[:, 0] > eps) | ~np.isfinite(Ns).all(axis=(1, 2))


@dataclass(frozen=True)
class _Settings:
    """Model and thresholds of one :func:`lsm_match` call (see its parameters)."""

    idx: Tuple[int, ...]
    half: int
    max_iter: int
    tol_shift: float
    max_shift: float
    min_corr: float
    max_sigma: float
    min_contrast: float
    scale_range: tuple
    contrast_range: tuple
    jacobian: str

    @property
    def u(self) -> int:
        return len(self.idx)

    @property
    def m(self) -> int:
        return (2 * self.half + 1) ** 2


@dataclass
class _Chunk:
    """Per-point state of one chunk; the ``*c`` arrays and ``A0t``, ``N0`` are compacted
    to the points still iterating (row k belongs to point ``loc[k]``)."""

    p0: NDArray
    p: NDArray
    flags: NDArray
    g1_mean: NDArray
    g1_q: NDArray
    iters: NDArray
    converged: NDArray
    last_normal: NDArray
    last_vv: NDArray
    last_corr: NDArray
    active: NDArray
    loc: NDArray
    g1c: NDArray
    A0t: Optional[NDArray] = None
    N0: Optional[NDArray] = None

    def compact(self) -> None:
        """Drop the rows of points that stopped iterating."""
        if len(self.active) < len(self.loc):
            keep = np.searchsorted(self.loc, self.active)
            self.g1c = self.g1c[keep]
            if self.A0t is not None:
                self.A0t, self.N0 = self.A0t[keep], self.N0[keep]
            self.loc = self.active


def _template_jacobian(ge1a: NDArray, g1c: NDArray, grid: NDArray,
                       m: int) -> Tuple[NDArray, NDArray]:
    """A0ᵀ (n, 8, m) from the template's own gradients, and N0 = A0ᵀA0 (float64).

    The Jacobian at parameters p is A0·T(p), so only A0ᵀΔg has to be formed per iteration.
    """
    xi, eta = grid
    t_xi = (0.5 * (ge1a[:, 1:-1, 2:] - ge1a[:, 1:-1, :-2])).reshape(-1, m)
    t_eta = (0.5 * (ge1a[:, 2:, 1:-1] - ge1a[:, :-2, 1:-1])).reshape(-1, m)
    A0t = np.empty((len(g1c), 8, m), np.float32)  # (n, 8, m): Jacobian transposed
    A0t[:, 0], A0t[:, 3] = t_xi, t_eta
    np.multiply(t_xi, xi, out=A0t[:, 1])
    np.multiply(t_xi, eta, out=A0t[:, 2])
    np.multiply(t_eta, xi, out=A0t[:, 4])
    np.multiply(t_eta, eta, out=A0t[:, 5])
    A0t[:, 6] = 1.0
    A0t[:, 7] = g1c
    del t_xi, t_eta
    N0 = np.matmul(A0t, A0t.transpose(0, 2, 1)).astype(np.float64)
    return A0t, N0


def _start_chunk(tpl: NDArray, cols: NDArray, rows: NDArray, p0: NDArray,
                 cfg: _Settings) -> _Chunk:
    """Template windows (flags: outside, textureless), their statistics for ρ and, in the
    template mode, the fixed Jacobian."""
    n, m, half = cols.size, cfg.m, cfg.half
    # template (fixed) with one extra pixel for the gradients
    ge1, t_inside = extract_windows(tpl, cols, rows, half + 1)
    g1 = np.ascontiguousarray(ge1[:, 1:-1, 1:-1]).reshape(n, m)
    flags = np.zeros(n, np.uint8)
    flags[~t_inside] |= FLAG_OUTSIDE
    # template statistics for the correlation coefficient: Σg1, Σ(g1 − ḡ1)²
    g1_mean = g1.mean(axis=1, dtype=np.float64)
    g1_q = np.einsum("ij,ij->i", g1, g1, dtype=np.float64) - m * g1_mean**2
    flags[~(np.sqrt(np.maximum(g1_q, 0.0) / m) >= cfg.min_contrast)] |= FLAG_TEXTURELESS
    active = np.flatnonzero(flags == 0)
    ch = _Chunk(p0, p0.copy(), flags, g1_mean, g1_q, np.zeros(n, np.int16), np.zeros(n, bool),
                np.zeros((n, cfg.u, cfg.u)), np.full(n, np.nan), np.zeros(n), active, active,
                g1[active])
    if cfg.jacobian == "template":
        ch.A0t, ch.N0 = _template_jacobian(ge1[active], ch.g1c, _grid(half), m)
    return ch


def _normals_template(ch: _Chunk, pa: NDArray, inv_det: NDArray, sampler: Tuple,
                      cfg: _Settings) -> Tuple[NDArray, ...]:
    """Normal equations N = TᵀN0T, b = Tᵀ(A0ᵀΔg) with the template's gradients.

    r1·(gx, gy) ≈ J⁻ᵀ (∂g1/∂ξ, ∂g1/∂η) and g2 ≈ (g1 − r0)/r1  →  A = A0·T.
    """
    flat, width, height, grid, _ = sampler
    a1, a2 = pa[:, 1:2], pa[:, 2:3]
    b1, b2 = pa[:, 4:5], pa[:, 5:6]
    r0, r1 = pa[:, 6:7], pa[:, 7:8]
    g2, ins = _affine_sampler(flat, width, height, pa, grid, cfg.half)
    resid = g2
    resid *= -r1.astype(np.float32)
    resid -= r0.astype(np.float32)
    resid += ch.g1c  # Δg = g1 − (r0 + r1·g2), in place of g2
    bfull = np.matmul(ch.A0t, resid[:, :, None])[:, :, 0].astype(np.float64)
    s_res, s_g1res = bfull[:, 6], bfull[:, 7]  # Σ Δg, Σ g1·Δg (columns 1 and g1)
    c00, c01 = b2[:, 0] * inv_det[:, 0], -b1[:, 0] * inv_det[:, 0]
    c10, c11 = -a2[:, 0] * inv_det[:, 0], a1[:, 0] * inv_det[:, 0]
    T = np.zeros((len(pa), 8, 8))
    for j in range(3):  # geometric columns: a_j from (ξ-part j, η-part j+3)
        T[:, j, j], T[:, j + 3, j] = c00, c01
        T[:, j, j + 3], T[:, j + 3, j + 3] = c10, c11
    T[:, 6, 6] = 1.0
    T[:, 7, 7] = 1.0 / r1[:, 0]
    T[:, 6, 7] = -r0[:, 0] / r1[:, 0]
    T = T[:, :, cfg.idx]
    N = np.matmul(T.transpose(0, 2, 1), np.matmul(ch.N0, T))
    b = np.matmul(bfull[:, None, :], T)[:, 0]
    return N, b, resid, ~ins, s_res, s_g1res


def _normals_search(ch: _Chunk, pa: NDArray, inv_det: NDArray, sampler: Tuple,
                    cfg: _Settings) -> Tuple[NDArray, ...]:
    """Normal equations with the gradients of the resampled search window (classic form).

    The extended search window (one extra pixel for the gradients) is resampled;
    ∂g/∂ξ = gx·a1 + gy·b1, ∂g/∂η = gx·a2 + gy·b2 are solved for (gx, gy), times r1.
    """
    flat, width, height, grid, grid_e = sampler
    idx, half, m, u = cfg.idx, cfg.half, cfg.m, cfg.u
    size = 2 * half + 1
    xi, eta = grid
    a1, a2 = pa[:, 1:2], pa[:, 2:3]
    b1, b2 = pa[:, 4:5], pa[:, 5:6]
    r0, r1 = pa[:, 6:7], pa[:, 7:8]
    ge, ins = _affine_sampler(flat, width, height, pa, grid_e, half + 1)
    ge = ge.reshape(-1, size + 2, size + 2)
    na = len(pa)
    At = np.empty((na, u, m), np.float32)  # Jacobian transposed, filled row by row
    g2 = ge[:, 1:-1, 1:-1]
    # window differences along ξ and η (central differences = half of these)
    dxi = (ge[:, 1:-1, 2:] - ge[:, 1:-1, :-2]).reshape(na, m)
    deta = (ge[:, 2:, 1:-1] - ge[:, :-2, 1:-1]).reshape(na, m)
    f = 0.5 * inv_det * r1
    for j0, own, c_own, other, c_other in ((0, dxi, b2 * f, deta, -b1 * f),
                                           (3, deta, a1 * f, dxi, -a2 * f)):
        if j0 not in idx:
            continue
        k = idx.index(j0)
        g = np.multiply(own, c_own.astype(np.float32), out=At[:, k])
        if np.any(c_other != 0):  # zero for the rows of epipolar images
            g += other * c_other.astype(np.float32)
        for j, w in ((j0 + 1, xi), (j0 + 2, eta)):
            if j in idx:
                np.multiply(g, w, out=At[:, idx.index(j)])
    At[:, idx.index(6)] = 1.0
    g2_rows = At[:, idx.index(7)]
    g2_rows.reshape(na, size, size)[...] = g2
    resid = np.multiply(g2_rows, -r1.astype(np.float32))
    resid -= r0.astype(np.float32)
    resid += ch.g1c  # Δg = g1 − (r0 + r1·g2)
    N = np.matmul(At, At.transpose(0, 2, 1)).astype(np.float64)
    b = np.matmul(At, resid[:, :, None])[:, :, 0].astype(np.float64)
    s_res = b[:, idx.index(6)]
    s_g1res = np.einsum("ij,ij->i", ch.g1c, resid).astype(np.float64)
    return N, b, resid, ~ins, s_res, s_g1res


def _solve(N: NDArray, b: NDArray, test_singular: bool) -> Tuple[NDArray, NDArray]:
    """Increments dx of the Jacobi-scaled normal equations and the singular systems.

    The scaling makes the singularity test scale-free; in the template mode it runs in the
    first iteration only, where N changes only by the small transformation T.
    """
    u = N.shape[-1]
    d = np.sqrt(np.maximum(np.einsum("nii->ni", N), 1e-30))
    Ns = N / (d[:, :, None] * d[:, None, :])
    if test_singular:
        singular = _singular(Ns)
    else:
        singular = np.zeros(len(N), bool)
    Ns_safe = np.where(singular[:, None, None], np.eye(u), Ns)
    dx = np.linalg.solve(Ns_safe, (b / d)[:, :, None])[:, :, 0] / d
    dx[singular] = 0.0
    return dx, singular


def _correlation(ch: _Chunk, r1: NDArray, vv: NDArray, s_res: NDArray, s_g1res: NDArray,
                 m: int) -> NDArray:
    """ρ(g1, g2) from sums already at hand.

    g2 = (g1 − r0 − Δg)/r1, so with centred values (z) ρ = sign(r1)·(q − Σg1zΔg) /
    sqrt(q·(q − 2Σg1zΔg + Σ(Δg_z)²)), q = Σ g1z², Σg1zΔg = Σg1Δg − ḡ1ΣΔg,
    Σ(Δg_z)² = vv − (ΣΔg)²/m.
    """
    q = ch.g1_q[ch.active]
    s_zr = s_g1res - ch.g1_mean[ch.active] * s_res
    den2 = q * (q - 2 * s_zr + (vv - s_res**2 / m))
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = np.sign(r1[:, 0]) * (q - s_zr) / np.sqrt(np.where(den2 > 0, den2, np.inf))
    return np.clip(corr, -1.0, 1.0)


def _failures(ch: _Chunk, pn: NDArray, outside: NDArray, singular: NDArray,
              cfg: _Settings) -> NDArray:
    """Failure bits of the step to ``pn``: outside, singular, or diverged (drift beyond the
    pull-in, implausible affine singular values or contrast, non-finite)."""
    smin, smax = cfg.scale_range
    cmin, cmax = cfg.contrast_range
    active, p0 = ch.active, ch.p0
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
    implausible = ((drift > cfg.max_shift) | (s_hi > smax) | (s_lo < smin) | (det_n <= 0)
                   | (pn[:, 7] < cmin) | (pn[:, 7] > cmax) | ~np.isfinite(pn).all(axis=1))
    bad[implausible & ~singular & ~outside] |= FLAG_DIVERGED
    return bad


def _iterate(ch: _Chunk, it: int, sampler: Tuple, cfg: _Settings) -> None:
    """One Gauss–Newton step of the active points; records the state at the current
    parameters (used if this is the last step), moves the good ones, retires the rest."""
    ch.compact()
    active = ch.active
    pa = ch.p[active]
    a1, a2 = pa[:, 1:2], pa[:, 2:3]
    b1, b2 = pa[:, 4:5], pa[:, 5:6]
    det = a1 * b2 - a2 * b1
    inv_det = 1.0 / np.where(np.abs(det) > 1e-6, det, 1e-6)
    template = cfg.jacobian == "template"
    normals = _normals_template if template else _normals_search
    N, b, resid, outside, s_res, s_g1res = normals(ch, pa, inv_det, sampler, cfg)
    dx, singular = _solve(N, b, it == 0 or not template)
    ch.last_normal[active] = N
    vv = np.einsum("ij,ij->i", resid, resid).astype(np.float64)
    ch.last_vv[active] = vv
    ch.last_corr[active] = _correlation(ch, pa[:, 7:8], vv, s_res, s_g1res, cfg.m)
    full = np.zeros((len(active), 8))
    full[:, cfg.idx] = dx
    pn = pa + full
    ch.iters[active] = it + 1
    bad = _failures(ch, pn, outside, singular, cfg)
    ok = bad == 0
    ch.p[active[ok]] = pn[ok]
    ch.flags[active] |= bad
    tol_lin = cfg.tol_shift / max(cfg.half, 1)
    done = ok & (np.abs(dx[:, 0]) < cfg.tol_shift)
    done &= np.abs(full[:, 3]) < cfg.tol_shift
    done &= (np.abs(full[:, [1, 2, 4, 5]]) < tol_lin).all(axis=1)
    ch.converged[active[done]] = True
    ch.active = active[ok & ~done]


def _finish_chunk(ch: _Chunk, cfg: _Settings, out: dict, sl: slice) -> None:
    """Precision Σ = σ0² N⁻¹ from the last normal matrix, final flags; into ``out[sl]``."""
    flags, idx, u = ch.flags, cfg.idx, cfg.u
    n = flags.size
    flags[(flags == 0) & ~ch.converged] |= FLAG_NOT_CONVERGED
    m_red = cfg.m - u
    sigma0 = np.sqrt(ch.last_vv / max(m_red, 1))
    have = np.isfinite(sigma0) & ((flags & (FLAG_SINGULAR | FLAG_OUTSIDE | FLAG_TEXTURELESS)) == 0)
    cov = np.full((n, u, u), np.nan)
    if have.any():
        Nh = ch.last_normal[have]
        d = np.sqrt(np.maximum(np.einsum("nii->ni", Nh), 1e-30))
        Qs = np.linalg.inv(Nh / (d[:, :, None] * d[:, None, :]))
        Q = Qs / (d[:, :, None] * d[:, None, :])
        cov[have] = Q * (sigma0[have] ** 2)[:, None, None]
    pos_c = idx.index(0)
    sig_c = np.sqrt(cov[:, pos_c, pos_c])
    sig_r = np.sqrt(cov[:, idx.index(3), idx.index(3)]) if 3 in idx else np.zeros(n)
    flags[(flags == 0) & (ch.last_corr < cfg.min_corr)] |= FLAG_LOW_CORRELATION
    flags[(flags == 0) & ~(np.maximum(sig_c, sig_r) <= cfg.max_sigma)] |= FLAG_HIGH_SIGMA
    out["params"][sl] = ch.p
    out["sigma0"][sl] = sigma0
    out["sig_c"][sl] = sig_c
    out["sig_r"][sl] = sig_r
    out["cov"][sl] = cov
    out["corr"][sl] = ch.last_corr
    out["iters"][sl] = ch.iters
    out["flags"][sl] = flags


def _lsm_chunk(tpl: NDArray, srch: NDArray, cols: NDArray, rows: NDArray, p0: NDArray,
               cfg: _Settings, out: dict, sl: slice) -> None:
    """Gauss–Newton for one chunk of points; writes into ``out[...][sl]``.

    Per-point arrays (template, Jacobian, normal matrix) are kept compacted to the points still
    iterating, so converged and failed points cost nothing in later iterations.
    """
    height, width = srch.shape
    # the image flattened for the sampler, the window grid and the one-pixel-larger grid
    sampler = (srch.ravel(), width, height, _grid(cfg.half), _grid(cfg.half + 1))
    ch = _start_chunk(tpl, cols, rows, p0, cfg)
    for it in range(cfg.max_iter):
        if ch.active.size == 0:
            break
        _iterate(ch, it, sampler, cfg)
    _finish_chunk(ch, cfg, out, sl)
