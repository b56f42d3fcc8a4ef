r"""DSM → DTM by hierarchical robust linear prediction (Kraus & Pfeifer 1998 style).

Linear prediction (least-squares interpolation with filtering, seed-002-003 A3.9)
    Heights are split into a deterministic trend and a zero-mean remainder
    :math:`l = z - t(x, y)`; the remainder is a correlated signal plus white noise,
    :math:`l = s + n`, with the Gaussian covariance

    .. math:: C(d) = C_0 \exp\bigl(-(d / c)^2\bigr), \qquad
              \operatorname{Var}(n_i) = \sigma_n^2 / p_i .

    The signal at any point P (observation or not) is predicted as

    .. math:: \hat s(P) = \mathbf c_P^\top (\mathbf C + \mathbf D)^{-1} \mathbf l, \qquad
              (\mathbf C)_{jk} = C(|P_j P_k|), \ \mathbf D = \operatorname{diag}(\sigma_n^2/p_j),

    and the surface is :math:`t + \hat s`. With :math:`\sigma_n^2 > 0` the support heights are
    filtered (the surface does not pass through them); with :math:`\sigma_n^2 = 0` it is pure
    interpolation (exact at the support points). Different weights ``p`` vary the diagonal.

How it is computed on a grid
    The observations are the DSM cells. Because the Gaussian is separable,
    :math:`\exp(-(\Delta x^2 + \Delta y^2)/c^2) = \exp(-\Delta x^2/c^2)\exp(-\Delta y^2/c^2)`,
    the product :math:`\mathbf C \mathbf x` over all cells is two 1-D correlations with the
    kernel :math:`k(d) = e^{-(d/c)^2}` truncated at :math:`|d| \le 2.5c` (< 0.2 % of C₀). The
    system :math:`(\mathbf C + \mathbf D)\mathbf x = \mathbf l` over the active cells is solved
    by Jacobi-preconditioned conjugate gradients (the matrix is never formed), and
    :math:`\hat{\mathbf s} = \mathbf C \mathbf x` gives the prediction at *every* cell at once:
    the observations' filtered heights and the heights of eliminated cells and holes.
    This is exactly :math:`\mathbf c^\top \mathbf C^{-1}\mathbf l` with a compactly supported
    (truncated) covariance, i.e. every cell's neighbourhood is the disc of radius 2.5 c.
    :func:`predict_dense` is the textbook dense formula (used by the tests to check this).

Covariance from the data
    The empirical covariance of ``l`` over the current ground candidates is formed along rows
    and columns for lags 0…m cells: :math:`V_{zz} = \overline{l^2}`,
    :math:`\hat C(d) = \overline{l_i l_{i+d}}`. A weighted log-linear fit
    :math:`\ln \hat C(d) = \ln C_0 - d^2/c^2` over the positive lags ≥ 1 gives ``c`` (clamped to
    the level's range), then :math:`C_0` by least squares for that ``c``;
    :math:`\sigma_n^2 = V_{zz} - C_0` (the covariance extrapolated to d → 0 is the signal, the
    rest of the variance at lag 0 is noise), at least ``min_noise_share``·V_zz. A fixed
    ``noise_share`` ν overrides it: :math:`C_0 = (1-ν)V_{zz}`, :math:`\sigma_n^2 = ν V_{zz}`.

Robust iterations with an asymmetric weight function
    With the residual :math:`r = l - \hat s` and the shift ``g``

    .. math:: p(r) = \begin{cases} 1 & r \le g \\
                     \dfrac{1}{1 + \bigl((r - g)/h\bigr)^{b}} & g < r \le g + w \\
                     0 & r > g + w \ \text{ or } \ r < g - w_\downarrow \end{cases}

    points below the surface keep their full weight, points above lose it (``h`` = residual
    above ``g`` at which the weight is ½, ``b`` the steepness, ``w`` the cut-off; the lower
    cut-off :math:`w_\downarrow` removes deep blunders). The shift is re-estimated from the
    residual histogram every iteration: :math:`g = -\min(k_g \sigma_-, g_{max})` with
    :math:`\sigma_- = \sqrt{\overline{r^2}}` over the negative residuals (the ground's
    spread below a surface that objects still pull up). Cells with ``p = 0`` are eliminated.
    Below the coarsest level, candidates within ``h`` of the grey opening with a
    ``coarse_spacing`` window keep :math:`p = 1`: the opening removes the objects the pyramid
    removes but keeps slopes, terraces and the upper edges of banks, where the smooth
    prediction passes far below the terrain and the weight function alone would reject it.
    At level 0, after the first prediction, candidates more than the ground tolerance above
    the opening of the candidates with a 5 m window (plus what that opening cuts from the
    prediction) get :math:`p = 0` and are not ground (:func:`~.surface_input.ground_bumps`:
    low objects narrower than that, which the weight function only half rejects).

Hierarchy (data pyramid)
    Level 0 is the DSM; level ℓ+1 takes the mean of the **two lowest** cells of every 2×2
    block of level ℓ (moved to the block centre along the local slope, so steep terrain is
    not biased low; the single lowest cell is the lowest noise value and, on terraced slopes,
    the lower terrace — a bias that piles up over the levels), up
    to the first level whose cell size reaches ``coarse_spacing`` (buildings and small woods
    shrink away; larger ones are bridged by the robust prediction whose correlation length
    grows with the cell size). The coarsest level's trend is a robust plane; every finer
    level's trend is the coarser DTM (bilinear), its ground candidates are the cells within
    the band :math:`[-b_\downarrow, b_\uparrow + \text{slope}\cdot s_{coarse}/2]` of it, and
    their starting weights are the weight function of their residuals to it. ``slope`` is the
    larger of the preset's and the median slope of the coarsest level, and at finer levels
    the local slope of the coarser DTM where it is larger; at every level the cut-off grows
    by slope·s/2 and the half-weight residual by slope·s/4 (a cell's height stands for
    terrain up to half a cell away: on a slope its residual to a smooth surface spreads by
    about slope·s/2, at the finest level too).

Steep vegetated slopes (preset ``steep``)
    At the end, the ground cells more than 1.5, 0.8, 0.5, 0.4 m in turn above the
    least-squares plane through the ground cells within ± ``refine_radius`` are dropped, and
    the DTM is the remaining ground cells filled by a local plane trend plus the membrane fill
    of the residuals (:mod:`.steep_ground`): under a closed canopy the few ground cells are
    too sparse for the prediction, which reverts to the coarser levels' trend between them,
    and shrubs among them lift it by metres.

Operator edits (:class:`~.surface_input.FilterConstraints`)
    ``remove`` cells are never observations (bridged); ``keep`` cells are no observations
    either (the terrain around them is predicted without them) and the DTM equals the DSM
    there; manual ground points (and 3-D
    breakline heights) are observations with a negligible noise variance (weight → ∞) and the
    DTM passes exactly through every ground point (set in its cell); **breaklines** split the
    grid into sides (each line extended to the grid border by its end directions): the
    covariance between cells of different sides is zero, so no prediction and no trend
    reaches across a breakline. Ground points are checked against the surface predicted
    without them (the check the report lists).
"""

from __future__ import annotations

import functools
import math
import time
from dataclasses import asdict, dataclass, fields, replace
from pathlib import Path
from typing import Any, Callable, Dict, List, Optional, Tuple, Union

import numpy as np
from numpy.typing import NDArray
from scipy import ndimage

from ..errors import InputError
from ..feedback import Feedback, ensure_feedback
from ..linalg import CG_LP, pcg
from ..surface.gridding import Grid
from .auto_preset import check_dtm, is_auto, resolve_preset
from .lp_pyramid import (
    BreaklineSides,
    breakline_sides,
    hard_grid,
    level_grid,
    local_slope,
    pyramid_levels,
    reduce_lowest,
    reduce_scale,
    terrain_slope,
    tile_offset,
    touches_border,
    upsample_sides,
)
from .presets import linear_prediction_preset
from .steep_ground import refine_ground, trend_fill
from .surface_input import (
    check_ground_points,
    dtm_slope,
    grey_opening,
    ground_bumps,
    low_outliers,
    lowest_points,
    read_filter_constraints,
    read_filter_input,
    write_filter_outputs,
)
from .tiles import filter_in_tiles, tile_limit

Array = NDArray[Any]
PathLike = Union[str, Path]

#: Relative noise variance given to hard constraints (manual ground points).
HARD_NOISE = 1e-6

#: Overlap of tiles (large grids, :mod:`.tiles`) in coarsest-level cells (``coarse_spacing``):
#: the finer levels' predictions reach a few correlation lengths, the coarse levels further.
TILE_OVERLAP_COARSE = 8.0


@dataclass
class LPParameters:
    """Parameters of the robust linear prediction, in operator units (metres).

    Attributes
    ----------
    coarse_spacing : float
        Cell size (m) the pyramid reaches at its coarsest level; about the width of the
        largest building/wood that should disappear by the lowest-cell reduction (larger
        ones are bridged by the prediction).
    iterations : int
        Robust iterations per level (the finest level uses ``fine_iterations``).
    fine_iterations : int
        Robust iterations at levels 0 and 1 (their candidates are already close to ground).
    half_weight : float
        ``h`` (m): residual above the shift at which the weight is ½ (``a = 1/h``).
    exponent : float
        ``b``: steepness of the weight function.
    cutoff : float
        ``w`` (m): residuals more than this above the shift get weight 0 on flat terrain;
        every level adds ``slope``·cell size / 2 (``half_weight`` half of that).
    low_cutoff : float
        ``w↓`` (m): residuals more than this below the shift are blunders (weight 0).
    shift_factor : float
        ``k_g``: the shift is ``g = −min(k_g·σ₋, max_shift)``.
    max_shift : float
        Largest |g| (m).
    band_above, band_below : float
        Candidates at a finer level lie within [−band_below, band_above] (m) of the coarser
        DTM (band_above grows by ``slope``·coarse cell size / 2).
    slope : float
        Least terrain slope allowance (m/m) that widens the cut-off and the band at every
        level; the median slope of the coarsest level (at finer levels the local slope of
        the coarser DTM) is used where it is larger.
    noise_share : float or None
        Fixed noise share ν = σ_n²/V_zz (0 = pure interpolation); None = estimated.
    min_noise_share : float
        Smallest estimated noise share (keeps the system well conditioned).
    max_noise : float
        Largest estimated noise σ (m); where relief or objects inflate the variance, the
        share above ``max_noise²`` is signal (else the prediction would smooth metres away).
    corr_min, corr_max : float
        Range of the correlation length ``c`` in cells of each level.
    corr_length : float or None
        Fixed correlation length (m) at level 0 (coarser levels scale with the cell size);
        None = estimated.
    ground_tolerance : float
        |DSM − DTM| (m) up to which a cell/point is labelled ground on flat terrain.
    ground_slope_factor : float
        ``k``: the ground tolerance grows by ``k``·|∇DTM|·cell size on slopes (see
        :func:`~.surface_input.point_labels`).
    low_outlier : float
        Depth (m) below the second lowest neighbour (5 × 5 cells) beyond which a cell is a low
        blunder before the pyramid is built (:func:`~.surface_input.low_outliers`); 0 = off.
    max_gap : float
        DSM holes wider than this (m) stay NaN in the DTM at the data border; interior holes
        are always filled. 0 = fill everything.
    cg_tol : float
        Relative residual at which the conjugate gradients stop.
    refine_radius : float
        Half side (m) of the window of the ground cells' plane test at the end
        (:func:`.steep_ground.refine_ground`); 0 = off (all presets but ``steep``).
    refine_tolerances : tuple of float
        Heights (m) above that plane beyond which a ground cell is dropped, one pass each.
    trend_window : float
        With the plane test: the DTM is the remaining ground cells filled by a local plane
        trend of this window (m) plus the membrane fill of the residuals
        (:func:`.steep_ground.trend_fill`) instead of the prediction.
    """

    coarse_spacing: float = 32.0
    iterations: int = 4
    fine_iterations: int = 2
    half_weight: float = 0.5
    exponent: float = 4.0
    cutoff: float = 1.5
    low_cutoff: float = 5.0
    shift_factor: float = 1.0
    max_shift: float = 0.5
    band_above: float = 2.0
    band_below: float = 5.0
    slope: float = 0.15
    noise_share: Optional[float] = None
    min_noise_share: float = 0.1
    max_noise: float = 0.3
    corr_min: float = 1.0
    corr_max: float = 3.0
    corr_length: Optional[float] = None
    ground_tolerance: float = 0.5
    ground_slope_factor: float = 1.25
    low_outlier: float = 1.5
    max_gap: float = 0.0
    cg_tol: float = 5e-3
    refine_radius: float = 0.0
    refine_tolerances: Tuple[float, ...] = ()
    trend_window: float = 0.0

    @classmethod
    def from_dict(cls, values: Dict[str, Any]) -> LPParameters:
        """Parameters from a dict; None values and unknown keys are ignored."""
        names = {f.name for f in fields(cls)}
        return replace(cls(), **{k: v for k, v in values.items() if k in names and v is not None})


@dataclass
class Covariance:
    """Gaussian covariance model of the trend-removed heights (C(d) = c0·exp(−(d/corr)²))."""

    c0: float
    noise: float
    corr: float  # in cells
    vzz: float

    @property
    def noise_share(self) -> float:
        return self.noise / max(self.c0 + self.noise, 1e-30)


@dataclass
class LPResult:
    """Result of :func:`filter_linear_prediction`.

    Attributes
    ----------
    dtm : ndarray float32
        The DTM (NaN only at wide holes of the data border, see ``max_gap``).
    ground : ndarray bool
        Ground cells: |DSM − DTM| ≤ ground_tolerance + ground_slope_factor·|∇DTM|·cell (keep
        areas ground, remove areas not).
    weights : ndarray float32
        Final weights of level 0 (0 = eliminated, NaN = no observation).
    iterations : list of dict
        One row per robust iteration (level, spacing, covariance, shift, eliminated share).
    disagreeing : list of dict
        Manual ground points the filter disagrees with (see ``check_ground_points``).
    levels : list of ndarray
        DTM of every level (coarse → fine) when ``keep_levels`` was asked for.
    """

    dtm: Array
    ground: Array
    weights: Array
    iterations: List[Dict[str, Any]]
    disagreeing: List[Dict[str, Any]]
    levels: List[Array]


# -- closed-form reference ------------------------------------------------------------------------
def gaussian_covariance(d: Array, c0: float, corr: float) -> Array:
    """C(d) = c0 · exp(−(d/corr)²)."""
    return c0 * np.exp(-(np.asarray(d, float) / corr) ** 2)


def predict_dense(xy: Array, values: Array, xy_new: Array, c0: float, corr: float,
                  noise: Union[float, Array] = 0.0) -> Array:
    r"""Textbook linear prediction :math:`\hat s(P) = \mathbf c_P^\top(\mathbf C+\mathbf D)^{-1} l`.

    Parameters
    ----------
    xy : ndarray (n, 2)
        Support points.
    values : ndarray (n,)
        Trend-removed heights ``l``.
    xy_new : ndarray (m, 2)
        Prediction points.
    c0, corr : float
        Gaussian covariance ``C(d) = c0·exp(−(d/corr)²)``.
    noise : float or ndarray (n,)
        Noise variance on the diagonal (0 = pure interpolation).

    Returns
    -------
    ndarray (m,)
    """
    xy = np.asarray(xy, float)
    xy_new = np.asarray(xy_new, float)
    d = np.linalg.norm(xy[:, None, :] - xy[None, :, :], axis=2)
    cmat = gaussian_covariance(d, c0, corr) + np.diag(np.broadcast_to(noise, len(xy)))
    cvec = gaussian_covariance(np.linalg.norm(xy_new[:, None, :] - xy[None, :, :], axis=2),
                               c0, corr)
    return cvec @ np.linalg.solve(cmat, np.asarray(values, float))


# -- covariance operator on a grid ----------------------------------------------------------------

#: Largest negative eigenvalue (relative to C₀) the truncated covariance may have: a fifth of
#: the smallest noise variance :func:`fit_covariance` gives (10⁻²·C₀).
MAX_NEGATIVITY = 2e-3


@functools.lru_cache(maxsize=64)
def _kernel_radius(corr: float) -> int:
    r"""Truncation radius (cells) of the 1-D kernel: ⌈2.5·corr⌉, longer where needed.

    A truncated Gaussian is not positive definite: its spectrum
    :math:`K(f) = \sum_{|d| \le r} e^{-(d/c)^2} \cos 2\pi f d` has negative side lobes of
    about :math:`e^{-(r/c)^2}`, and the separable 2-D operator has the eigenvalues
    :math:`C_0 K(f_x) K(f_y)`, as low as :math:`C_0 K_{min} K(0)`. With c = 6 cells and
    r = 2.5c that is −1.8 % of C₀ — more than a small noise variance, so C + D is indefinite
    and the conjugate gradients diverge (the float overflow at the coarsest level of large
    DSMs). The radius grows until :math:`-K_{min} K(0) \le` :data:`MAX_NEGATIVITY`.
    """
    r = max(1, math.ceil(2.5 * corr))
    f = np.linspace(0.0, 0.5, 1025)
    while True:
        d = np.arange(-r, r + 1, dtype=np.float64)
        k = np.exp(-(d / corr) ** 2)
        spec = (np.cos(2.0 * np.pi * f[:, None] * d[None, :]) * k).sum(axis=1)  # no BLAS
        if -float(spec.min()) * float(k.sum()) <= MAX_NEGATIVITY or r > 6 * corr:
            return r
        r += 1


def _kernel(corr: float) -> Array:
    """1-D Gaussian correlation kernel exp(−(d/corr)²), |d| ≤ :func:`_kernel_radius` cells."""
    r = _kernel_radius(float(corr))
    d = np.arange(-r, r + 1, dtype=np.float64)
    return np.exp(-(d / corr) ** 2).astype(np.float32)


#: Cells per strip of the column pass of :func:`_smooth` (≈ 4 MB of float32: cache-sized).
STRIP_CELLS = 2 ** 20


def _smooth(x: Array, k: Array) -> Array:
    """Separable correlation with ``k`` along columns, then rows (zero outside the grid).

    The column pass runs on strips of rows (with ``len(k)//2`` halo rows): a whole-grid pass
    along axis 0 strides through memory and is ~2.5 × slower; every output cell is the same
    sum of the same products in the same order, so the strips give bit-identical values.
    """
    h, w = x.shape
    r = len(k) // 2
    rows = max(32, STRIP_CELLS // max(w, 1))
    if h <= rows + 2 * r:
        y = ndimage.correlate1d(x, k, axis=0, mode="constant", output=np.float32)
    else:
        y = np.empty((h, w), np.float32)
        for r0 in range(0, h, rows):
            r1 = min(h, r0 + rows)
            a0, a1 = max(0, r0 - r), min(h, r1 + r)
            part = ndimage.correlate1d(x[a0:a1], k, axis=0, mode="constant", output=np.float32)
            y[r0:r1] = part[r0 - a0:r1 - a0]
    return ndimage.correlate1d(y, k, axis=1, mode="constant", output=np.float32)


def covariance_apply(x: Array, c0: float, corr: float,
                     sides: Optional[BreaklineSides] = None) -> Array:
    r"""Covariance times a grid vector: :math:`(\mathbf C\mathbf x)_i = \sum_j C(d_{ij}) x_j`.

    Cells of different breakline sides do not correlate:
    :math:`\mathbf C = \sum_k \mathbf M_k \mathbf C_{full} \mathbf M_k`.
    """
    k = _kernel(corr)
    x = np.asarray(x, np.float32)
    if sides is None:
        y = _smooth(x, k)
        y *= np.float32(c0)
        return y
    out = np.zeros_like(x)
    r = len(k) // 2
    h, w = x.shape
    for lab, sl in enumerate(sides.slices):
        if sl is None:
            continue
        r0, r1 = max(sl[0].start - r, 0), min(sl[0].stop + r, h)
        q0, q1 = max(sl[1].start - r, 0), min(sl[1].stop + r, w)
        m = sides.labels[r0:r1, q0:q1] == lab
        y = _smooth(np.where(m, x[r0:r1, q0:q1], 0.0).astype(np.float32), k)
        out[r0:r1, q0:q1] += np.where(m, c0 * y, 0.0).astype(np.float32)
    return out


def _pcg(matvec: Callable[[Array], Array], b: Array, x: Array, minv: Array, tol: float,
         maxiter: int, feedback: Feedback) -> Tuple[Array, int]:
    """Jacobi-preconditioned conjugate gradients on grid vectors (float32, float64 dots):
    :func:`..linalg.pcg` with the rule :data:`..linalg.CG_LP`."""
    return pcg(matvec, b, minv, x, tol=tol, max_iter=maxiter, rule=CG_LP, feedback=feedback)


def lp_solve(lz: Array, active: Array, cov: Covariance, noise_scale: Optional[Array] = None,
             sides: Optional[BreaklineSides] = None, x0: Optional[Array] = None, tol: float = 1e-3,
             maxiter: int = 300, feedback: Optional[Feedback] = None
             ) -> Tuple[Array, Array, int]:
    r"""Grid prediction :math:`\hat{\mathbf s} = \mathbf C(\mathbf C+\mathbf D)^{-1}\mathbf l`.

    Parameters
    ----------
    l : ndarray (h, w)
        Trend-removed heights (any value where not active).
    active : ndarray of bool
        Observations.
    cov : Covariance
        ``c0``, ``noise`` (σ_n²), ``corr`` (cells).
    noise_scale : ndarray, optional
        Per-cell factor of σ_n² on the diagonal (1/p, σ_i²/σ²); default 1.
    sides : optional
        Breakline partition (no correlation across).
    x0 : ndarray, optional
        Start vector (warm start from the previous robust iteration).

    Returns
    -------
    (ŝ at every cell, the solution x = (C+D)⁻¹ l, CG iterations)
    """
    feedback = ensure_feedback(feedback)
    act = np.asarray(active, bool)
    noise = cov.noise if cov.noise > 0 else HARD_NOISE * cov.c0  # pure interpolation: nugget
    d = np.zeros(act.shape, np.float32)
    scale = 1.0 if noise_scale is None else noise_scale
    d[act] = (noise * np.broadcast_to(scale, act.shape))[act]
    b = np.where(act, lz, 0.0).astype(np.float32)
    actf = act.astype(np.float32)

    def matvec(v: Array) -> Array:
        out = covariance_apply(v, cov.c0, cov.corr, sides)
        out *= actf
        out += d * v
        return out

    # Jacobi: the diagonal is C(0) + D (the kernel's centre is 1)
    minv = np.where(act, 1.0 / (cov.c0 + d), 0.0).astype(np.float32)
    x = np.zeros_like(b) if x0 is None else np.where(act, x0, 0.0).astype(np.float32)
    x, its = _pcg(matvec, b, x, minv, tol, maxiter, feedback)
    s = covariance_apply(x, cov.c0, cov.corr, sides)
    if cov.noise <= 0:
        s = np.where(act, b, s)  # pure interpolation is exact at the support points
    return s, x, its


# -- covariance estimation ------------------------------------------------------------------------
def empirical_covariance(lz: Array, mask: Array, max_lag: int) -> Tuple[Array, Array]:
    """Mean products of heights ``d`` cells apart along rows and columns, d = 0…max_lag.

    Returns
    -------
    (covariance per lag, number of pairs per lag)
    """
    v = np.where(mask, lz, 0.0).astype(np.float64)
    m = np.asarray(mask, bool)
    cov = np.zeros(max_lag + 1)
    cnt = np.zeros(max_lag + 1)
    cov[0] = float(np.sum(v * v))
    cnt[0] = float(m.sum())
    for d in range(1, max_lag + 1):
        s, n = 0.0, 0.0
        if v.shape[1] > d:
            s += float(np.sum(v[:, d:] * v[:, :-d]))
            n += float(np.count_nonzero(m[:, d:] & m[:, :-d]))
        if v.shape[0] > d:
            s += float(np.sum(v[d:] * v[:-d]))
            n += float(np.count_nonzero(m[d:] & m[:-d]))
        cov[d], cnt[d] = s, n
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(cnt > 0, cov / np.maximum(cnt, 1), np.nan), cnt


def fit_covariance(emp: Array, corr_min: float, corr_max: float,
                   noise_share: Optional[float] = None, min_noise_share: float = 0.05,
                   corr: Optional[float] = None, max_noise: Optional[float] = None
                   ) -> Covariance:
    r"""Gaussian model from the empirical covariance (see the module notes).

    Parameters
    ----------
    emp : ndarray
        Empirical covariance at lags 0…m (cells); ``emp[0] = V_zz``.
    corr_min, corr_max : float
        Range of the correlation length (cells).
    noise_share : float, optional
        Fixed ν: C₀ = (1 − ν)·V_zz, σ² = ν·V_zz.
    corr : float, optional
        Fixed correlation length (cells).
    max_noise : float, optional
        Largest noise σ (m): the estimated noise variance is capped at ``max_noise²`` (where
        relief or objects inflate V_zz the signal takes the rest), but kept ≥ 10⁻²·C₀.
    """
    vzz = float(emp[0]) if np.isfinite(emp[0]) and emp[0] > 0 else 1e-4
    vzz = max(vzz, 1e-6)
    d = np.arange(len(emp), dtype=float)
    use = (d >= 1) & np.isfinite(emp) & (emp > 0.02 * vzz)
    if corr is None:
        if use.sum() >= 2:
            w = emp[use]
            A = np.column_stack([np.ones(use.sum()), -d[use] ** 2])
            coef, *_ = np.linalg.lstsq(A * w[:, None], np.log(emp[use]) * w, rcond=None)
            corr = 1.0 / math.sqrt(coef[1]) if coef[1] > 0 else corr_max
        elif use.sum() == 1:
            k = int(d[use][0])
            ratio = min(float(emp[k]) / vzz, 0.999)
            corr = k / math.sqrt(-math.log(ratio)) if ratio > 0 else corr_min
        else:
            corr = corr_min
    corr = float(min(max(corr, corr_min), corr_max))
    if noise_share is not None:
        nu = float(min(max(noise_share, 0.0), 0.99))
        return Covariance((1.0 - nu) * vzz, nu * vzz, corr, vzz)
    kd = np.exp(-(d / corr) ** 2)
    ok = (d >= 1) & np.isfinite(emp)
    c0 = float(np.sum(emp[ok] * kd[ok]) / np.sum(kd[ok] ** 2)) if ok.any() else vzz
    c0 = min(max(c0, 0.05 * vzz), (1.0 - min_noise_share) * vzz)
    noise = vzz - c0
    if max_noise is not None and noise > max_noise ** 2:
        noise = max(max_noise ** 2, 1e-2 * c0)
        c0 = vzz - noise
    return Covariance(c0, noise, corr, vzz)


# -- robust weights -------------------------------------------------------------------------------
def asymmetric_weights(r: Array, g: float, half_weight: float, exponent: float, cutoff: float,
                       low_cutoff: float = np.inf) -> Array:
    r"""Kraus–Pfeifer weights: 1 below ``g``, :math:`1/(1+((r-g)/h)^b)` above, 0 beyond ``g+w``.

    Residuals more than ``low_cutoff`` below ``g`` get 0 too (blunders).
    """
    r = np.asarray(r, np.float64)
    u = np.maximum(r - g, 0.0) / np.maximum(half_weight, 1e-9)
    with np.errstate(over="ignore", invalid="ignore"):
        p = 1.0 / (1.0 + u ** exponent)
    p = np.where(r > g + cutoff, 0.0, p)
    p = np.where(r < g - low_cutoff, 0.0, p)
    return np.where(np.isfinite(r), p, 0.0)


def residual_shift(r: Array, factor: float, max_shift: float) -> float:
    r"""Shift ``g = −min(k·σ₋, g_max)`` with σ₋ the RMS of the negative residuals."""
    neg = r[r < 0]
    if neg.size == 0:
        return 0.0
    return -min(factor * math.sqrt(float(np.mean(neg.astype(np.float64) ** 2))), max_shift)


# -- pyramid ---------------------------------------------------------------------------------------
def _robust_plane(z: Array, valid: Array, prm: LPParameters, cutoff: float) -> Array:
    """Plane trend of the coarsest level, fitted with the asymmetric weights (5 iterations)."""
    rows, cols = np.nonzero(valid)
    zz = z[valid].astype(np.float64)
    if zz.size < 3:
        return np.full(z.shape, float(np.nanmin(z)) if zz.size else 0.0, np.float32)
    A = np.column_stack([np.ones(zz.size), cols - cols.mean(), rows - rows.mean()])
    p = np.ones(zz.size)
    coef = np.zeros(3)
    for _ in range(5):
        sw = np.sqrt(p)
        coef, *_ = np.linalg.lstsq(A * sw[:, None], zz * sw, rcond=None)
        r = zz - A @ coef
        g = residual_shift(r, prm.shift_factor, max(prm.max_shift, cutoff / 2))
        p = asymmetric_weights(r, g, max(prm.half_weight, cutoff / 4), prm.exponent, cutoff,
                               prm.low_cutoff)
        if p.sum() < 3:
            p = np.ones(zz.size)
            break
    rr, cc = np.mgrid[0:z.shape[0], 0:z.shape[1]]
    return (coef[0] + coef[1] * (cc - cols.mean()) + coef[2] * (rr - rows.mean())
            ).astype(np.float32)



# -- the filter -----------------------------------------------------------------------------------
@dataclass
class _TileRun:
    """Filters one tile of a large grid (the callback of :func:`.tiles.filter_in_tiles`)."""

    grid: Grid  # the whole grid (places the tile's σ window)
    prm: LPParameters
    sigma: Optional[Array]  # σ_z of the whole grid

    def __call__(self, zt: Array, gt: Grid, ct: Any, fb: Feedback) -> Dict[str, Any]:
        r0, c0 = tile_offset(self.grid, gt)
        st = None if self.sigma is None else self.sigma[r0:r0 + gt.height, c0:c0 + gt.width]
        res = filter_linear_prediction(zt, gt, self.prm, ct, st, fb, False, max_cells=zt.size)
        return {"dtm": res.dtm, "ground": res.ground, "iterations": res.iterations,
                "ground_points_disagreeing": res.disagreeing}


def _filter_tiled(z: Array, grid: Grid, prm: LPParameters, constraints: Any,
                  sigma: Optional[Array], limit: int, feedback: Feedback) -> LPResult:
    """:func:`filter_linear_prediction` of a grid larger than ``limit`` cells, tile by tile."""
    overlap = math.ceil(TILE_OVERLAP_COARSE * prm.coarse_spacing / grid.spacing)
    tile_sigma = None if sigma is None else np.asarray(sigma)
    tiled = filter_in_tiles(_TileRun(grid, prm, tile_sigma), z, grid, constraints, overlap,
                            limit, feedback)
    feedback.info(f"Filtered in {tiled['tiles']} tiles (overlap {overlap} cells).")
    return LPResult(tiled["dtm"], tiled["ground"], np.full(z.shape, np.nan, np.float32),
                    tiled["first"].get("iterations", []),
                    tiled["ground_points_disagreeing"], [])


@dataclass
class _Observations:
    """The DSM and the operator's edits on the level-0 grid.

    Attributes
    ----------
    z0 : ndarray float32
        DSM, NaN = no data.
    keep, remove : ndarray bool
        Keep / remove areas (remove without the keep cells).
    gpts : ndarray (n, 3)
        Manual ground points.
    lines : list
        Breaklines.
    obs0 : ndarray float32
        Observations: the DSM without keep/remove cells and low blunders.
    noise_scale0 : ndarray float32 or None
        (σ_i / median σ)² per cell.
    """

    z0: Array
    keep: Array
    remove: Array
    gpts: Array
    lines: List[Any]
    obs0: Array
    noise_scale0: Optional[Array]

    @property
    def valid0(self) -> Array:
        """Cells with a DSM height."""
        return np.isfinite(self.z0)


def _noise_scale(sigma: Optional[Array]) -> Optional[Array]:
    """(σ_i / median σ)² per cell (1 where σ is unknown); None without usable σ."""
    if sigma is None:
        return None
    sg = np.asarray(sigma, float)
    med = np.nanmedian(sg[np.isfinite(sg) & (sg > 0)]) if np.any(sg > 0) else np.nan
    if not np.isfinite(med):
        return None
    return np.where(np.isfinite(sg) & (sg > 0), (sg / med) ** 2, 1.0).astype(np.float32)


def _observations(z: Array, prm: LPParameters, constraints: Any,
                  sigma: Optional[Array]) -> _Observations:
    """The level-0 observations and edits (see :class:`_Observations`).

    Raises
    ------
    InputError
        Fewer than 10 usable cells.
    """
    z0 = np.array(z, dtype=np.float32)
    z0[~np.isfinite(z0)] = np.nan
    keep = np.zeros(z0.shape, bool)
    remove = np.zeros(z0.shape, bool)
    gpts = np.zeros((0, 3))
    lines: List[Any] = []
    if constraints is not None:
        keep = np.asarray(constraints.keep, bool)
        remove = np.asarray(constraints.remove, bool) & ~keep
        gpts = np.asarray(constraints.ground_points, float).reshape(-1, 3)
        lines = list(constraints.breaklines or [])
    # keep cells are no observations either: the terrain around an embankment is predicted
    # without it (a 6 m dam would make the Gaussian prediction ring), then the DSM is put back
    obs0 = np.where(remove | keep, np.nan, z0).astype(np.float32)
    if prm.low_outlier > 0:
        # isolated low blunders would pull the lowest-cell pyramid (and with it every level's
        # candidate band) down by metres: cut them before the reduction
        obs0[low_outliers(obs0, prm.low_outlier)] = np.nan
    if np.count_nonzero(np.isfinite(obs0)) + len(gpts) < 10:
        raise InputError.of("Fewer than 10 DSM cells are left for the linear prediction (all "
                            "no data or inside 'remove' exclusion areas); check the input and "
                            "the exclusion areas.")
    return _Observations(z0, keep, remove, gpts, lines, obs0, _noise_scale(sigma))


@dataclass
class _Level:
    """One pyramid level: its observations, trend, candidates and weight-function settings."""

    lv: int
    grid: Grid
    zl: Array  # heights with the ground points and 3-D breakline heights set
    hard: Array  # mean ground-point height per cell (NaN elsewhere)
    is_hard: Array
    sides: Optional[BreaklineSides]
    valid: Array
    forced: Array  # cells of hard constraints and breaklines (always candidates)
    trend: Array
    cand: Array  # ground candidates
    lz: Array  # trend-removed heights
    cutoff: Any  # weight cut-off per cell (grows with the slope)
    half_w: Any  # half-weight residual per cell
    corr_rng: Tuple[float, float]  # range of the correlation length (cells)

    @property
    def max_lag(self) -> int:
        """Longest lag (cells) of the empirical covariance."""
        return math.ceil(2 * self.corr_rng[1]) + 1


@dataclass
class _Coarser:
    """What a level takes from the coarser one: its DTM, its sides and the terrain slope."""

    dtm: Optional[Array] = None
    sides: Optional[BreaklineSides] = None
    slope: float = 0.0  # least slope allowance (m/m), set at the coarsest level


def _level_heights(zl: Array, g_lv: Grid, obs: _Observations
                   ) -> Tuple[Array, Array, Array, Optional[BreaklineSides], Array]:
    """A level's heights with the ground points and 3-D breakline heights set.

    Returns
    -------
    (heights, ground-point heights, ground-point cells, sides, forced cells)
    """
    hard = hard_grid(obs.gpts, g_lv)
    is_hard = np.isfinite(hard)
    sides, _, bz = breakline_sides(obs.lines, g_lv) if obs.lines else (None, None, None)
    zl = np.where(is_hard, hard, zl).astype(np.float32)
    soft_line = np.zeros(zl.shape, bool)
    if bz is not None:
        soft_line = np.isfinite(bz) & ~is_hard
        zl = np.where(soft_line, bz, zl).astype(np.float32)
    forced = (soft_line | is_hard) & np.isfinite(zl)
    return zl, hard, is_hard, sides, forced


def _setup_level(lv: int, grid: Grid, zl: Array, obs: _Observations, prm: LPParameters,
                 coarser: _Coarser) -> _Level:
    """Trend, candidates and weight settings of level ``lv`` (sets ``coarser.slope`` at the
    coarsest level)."""
    g_lv = level_grid(grid, lv)
    zl, hard, is_hard, sides, forced = _level_heights(zl, g_lv, obs)
    valid = np.isfinite(zl)
    up = None
    if coarser.dtm is None:
        coarser.slope = max(prm.slope, terrain_slope(zl, g_lv.spacing))
        slope_f: Any = coarser.slope
    else:
        up = upsample_sides(coarser.dtm, zl.shape, coarser.sides, sides)
        slope_f = np.maximum(coarser.slope, local_slope(up, g_lv.spacing))
    slope_allow = slope_f * g_lv.spacing / 2.0
    if up is None:
        trend = _robust_plane(zl, valid, prm, prm.cutoff + coarser.slope * g_lv.spacing)
        cand = valid.copy()
        corr_rng = (prm.corr_min, max(prm.corr_max, 2.0 * prm.corr_max))
    else:
        trend = up
        dz = zl - trend
        band_up = prm.band_above + slope_f * g_lv.spacing  # = slope · coarse cell / 2
        cand = valid & (((dz <= band_up) & (dz >= -prm.band_below)) | forced)
        corr_rng = (prm.corr_min, prm.corr_max)
    lz = np.where(valid, zl - trend, 0.0).astype(np.float32)
    return _Level(lv, g_lv, zl, hard, is_hard, sides, valid, forced, trend, cand, lz,
                  prm.cutoff + slope_allow, prm.half_weight + slope_allow / 2.0, corr_rng)


def _start_weights(lvl: _Level, prm: LPParameters, coarsest: bool
                   ) -> Tuple[Covariance, Array, Array]:
    """The level's first covariance model, starting weights and cells of full weight."""
    corr_fixed = None if prm.corr_length is None else prm.corr_length / lvl.grid.spacing
    cov = fit_covariance(empirical_covariance(lvl.lz, lvl.cand, lvl.max_lag)[0], *lvl.corr_rng,
                         noise_share=prm.noise_share, min_noise_share=prm.min_noise_share,
                         corr=corr_fixed, max_noise=prm.max_noise)
    p = np.where(lvl.cand, 1.0, 0.0).astype(np.float32)
    # full weight where terrain is certain: hard constraints, and (below the coarsest
    # level) the candidates on the opening (:func:`_on_terrain`)
    sure = lvl.forced | (_on_terrain(lvl.zl, lvl.cand, prm, lvl.grid.spacing) if not coarsest
                         else np.zeros(lvl.zl.shape, bool))
    if not coarsest:
        # the coarser DTM is the first surface: its residuals give the starting weights
        # (one robust iteration for free)
        g0 = residual_shift(lvl.lz[lvl.cand & ~lvl.forced], prm.shift_factor, prm.max_shift)
        p = asymmetric_weights(np.where(lvl.cand, lvl.lz, np.nan), g0, lvl.half_w,
                               prm.exponent, lvl.cutoff, prm.low_cutoff).astype(np.float32)
        p[sure] = 1.0
    return cov, p, sure


@dataclass
class _LevelFit:
    """Outcome of a level's robust iterations."""

    cov: Covariance
    p: Array  # the weights of the last prediction
    s: Array  # the last prediction of the trend-removed heights
    x: Array  # its CG solution (warm start of the ground-point check)
    shift: float
    bumps: Array  # level 0: low objects (no ground)


def _iteration_row(lvl: _Level, cov: Covariance, p: Array, p_new: Array, g: float, its: int,
                   number: int) -> Dict[str, Any]:
    """Report row of one robust iteration."""
    n_valid = max(int(lvl.valid.sum()), 1)
    elim = int(np.count_nonzero(lvl.valid & (p_new == 0)))
    return {"iteration": number, "level": lvl.lv, "spacing_m": float(lvl.grid.spacing),
            "candidates": int(lvl.cand.sum()),
            "eliminated_share": float(np.count_nonzero(lvl.valid & (p_new == 0)
                                                       & (p > 0))) / n_valid,
            "eliminated_total_share": elim / n_valid,
            "shift_m": round(float(g), 4), "c0_m2": round(cov.c0, 5),
            "noise_share": round(cov.noise_share, 4),
            "corr_length_m": round(cov.corr * lvl.grid.spacing, 3),
            "cg_iterations": its}


def _robust_iterations(lvl: _Level, prm: LPParameters, scale_lv: Optional[Array],
                       coarsest: bool, rows: List[Dict[str, Any]], fb: Feedback) -> _LevelFit:
    """Predict, re-weight, repeat: the robust iterations of one level (rows appended)."""
    cov, p, sure = _start_weights(lvl, prm, coarsest)
    bumps = np.zeros(lvl.zl.shape, bool)
    n_iter = prm.fine_iterations if lvl.lv <= 1 else prm.iterations
    x = None
    for k in range(max(n_iter, 1)):
        active = p > 0
        scale = np.where(active, 1.0 / np.maximum(p, 1e-6), 1.0).astype(np.float32)
        if scale_lv is not None:
            scale *= scale_lv
        scale[lvl.is_hard] = HARD_NOISE * cov.c0 / max(cov.noise, 1e-12)
        s, x, its = lp_solve(lvl.lz, active, cov, scale, lvl.sides, x0=x, tol=prm.cg_tol,
                             maxiter=300 if lvl.lz.size > 10 ** 6 else 2000, feedback=fb)
        r = np.where(lvl.valid, lvl.lz - s, np.nan)
        g = residual_shift(r[lvl.cand & ~lvl.forced], prm.shift_factor, prm.max_shift)
        p_new = asymmetric_weights(np.where(lvl.cand, r, np.nan), g, lvl.half_w, prm.exponent,
                                   lvl.cutoff, prm.low_cutoff).astype(np.float32)
        p_new[sure] = 1.0
        if lvl.lv == 0 and k == 0:
            # low objects narrower than a few metres get no weight: the weight function
            # only halves it below h + slope allowance, and they lift the surface
            bumps = _bumps(lvl.zl, lvl.cand & ~lvl.forced & (p_new > 0), lvl.trend + s, prm,
                           lvl.grid.spacing)
        p_new[bumps] = 0.0
        if k == 0 and coarsest and prm.noise_share is None and prm.corr_length is None:
            # coarsest level (objects among the candidates): re-estimate the covariance
            # from the cells that now look like ground
            cov = fit_covariance(empirical_covariance(lvl.lz, p_new > 0.5, lvl.max_lag)[0],
                                 *lvl.corr_rng, min_noise_share=prm.min_noise_share,
                                 max_noise=prm.max_noise)
        rows.append(_iteration_row(lvl, cov, p, p_new, g, its, len(rows) + 1))
        if k < n_iter - 1:
            p = p_new
        fb.progress(100.0 * (k + 1) / max(n_iter, 1))
    return _LevelFit(cov, p, s, x, g, bumps)


def _final_ground(dtm_c: Array, obs: _Observations, bumps: Array, grid: Grid,
                  prm: LPParameters) -> Tuple[Array, Array]:
    """The DTM without wide border holes (``max_gap``) and the ground cells."""
    valid0, remove, keep = obs.valid0, obs.remove, obs.keep
    dtm = np.asarray(dtm_c, np.float32)
    if prm.max_gap > 0 and not valid0.all():
        far = ndimage.distance_transform_edt(~(valid0 | remove)) * grid.spacing > prm.max_gap / 2
        outer = far & touches_border(~(valid0 | remove))
        dtm = np.where(outer, np.nan, dtm).astype(np.float32)
    tol = prm.ground_tolerance + prm.ground_slope_factor * grid.spacing * np.nan_to_num(
        dtm_slope(dtm, grid.spacing))
    with np.errstate(invalid="ignore"):
        ground = valid0 & (np.abs(obs.z0 - dtm) <= tol) & ~remove & ~bumps
    ground |= keep & valid0
    return dtm, ground


def filter_linear_prediction(z: Array, grid: Grid, params: Optional[LPParameters] = None,
                             constraints: Any = None, sigma: Optional[Array] = None,
                             feedback: Optional[Feedback] = None,
                             keep_levels: bool = False,
                             max_cells: Optional[int] = None) -> LPResult:
    """Hierarchical robust linear prediction of a DSM grid (see the module notes).

    Parameters
    ----------
    z : ndarray (h, w)
        DSM, NaN = no data.
    grid : Grid
        Its grid (spacing in metres; the transform places edits).
    params : LPParameters, optional
    constraints : FilterConstraints, optional
        keep / remove masks, ground points, breaklines.
    sigma : ndarray (h, w), optional
        σ_z per cell: the noise variance of a cell is scaled by (σ_i/median σ)².
    feedback : Feedback, optional
    keep_levels : bool
        Keep every level's DTM in ``LPResult.levels`` (not for tiled grids).
    max_cells : int, optional
        Grids with more cells are filtered in overlapping tiles (:mod:`.tiles`, default
        :data:`.tiles.MAX_CELLS`) with an overlap of :data:`TILE_OVERLAP_COARSE` coarse cells;
        ``weights`` is then NaN and ``iterations`` are the first tile's.

    Raises
    ------
    InputError
        Fewer than 10 usable cells (all NaN or all removed).
    """
    feedback = ensure_feedback(feedback)
    prm = params or LPParameters()
    limit = tile_limit(max_cells)
    if z.shape[0] * z.shape[1] > limit:
        return _filter_tiled(z, grid, prm, constraints, sigma, limit, feedback)
    obs = _observations(z, prm, constraints, sigma)
    # pyramid: lowest cells per 2×2 block
    n_red = pyramid_levels(obs.z0.shape, grid.spacing, prm.coarse_spacing)
    zs, scales = [obs.obs0], [obs.noise_scale0]
    for _ in range(n_red):
        zs.append(reduce_lowest(zs[-1]))
        scales.append(reduce_scale(scales[-1]))
    rows: List[Dict[str, Any]] = []
    levels_out: List[Array] = []
    coarser = _Coarser()
    weights0 = np.full(obs.z0.shape, np.nan, np.float32)
    disagreeing: List[Dict[str, Any]] = []
    total_work = sum(4.0 ** -lv for lv in range(n_red + 1))
    done = 0.0
    t_start = time.perf_counter()
    for lv in range(n_red, -1, -1):
        fb = feedback.step(100.0 * done / total_work, 100.0 * (done + 4.0 ** -lv) / total_work)
        done += 4.0 ** -lv
        lvl = _setup_level(lv, grid, zs[lv], obs, prm, coarser)
        fit = _robust_iterations(lvl, prm, scales[lv], lv == n_red, rows, fb)
        # final surface of the level: prediction with the last weights
        dtm_l = (lvl.trend + fit.s).astype(np.float32)
        if lv == 0:
            weights0 = np.where(lvl.valid, fit.p, np.nan).astype(np.float32)
            if lvl.is_hard.any():
                disagreeing = _ground_point_check(lvl, fit, scales[0], obs.gpts, grid, prm, fb)
            dtm_l = np.where(lvl.is_hard, lvl.hard, dtm_l)
            dtm_l = np.where(obs.keep & obs.valid0, obs.z0, dtm_l)
        if keep_levels:
            levels_out.append(dtm_l)
        coarser.dtm, coarser.sides = dtm_l, lvl.sides
        feedback.info(f"Level {lv} ({lvl.grid.spacing:g} m, {lvl.grid.width} × "
                      f"{lvl.grid.height} cells): c = {fit.cov.corr * lvl.grid.spacing:.1f} m, "
                      f"noise share {fit.cov.noise_share:.2f}, shift {fit.shift:+.2f} m, "
                      f"{100.0 * rows[-1]['eliminated_total_share']:.1f} % eliminated "
                      f"({time.perf_counter() - t_start:.1f} s).")
    dtm, ground = _final_ground(coarser.dtm, obs, fit.bumps, grid, prm)
    if prm.refine_radius > 0:
        dtm, ground = _steep_finish(dtm, ground, obs, fit.bumps, grid, prm, constraints,
                                    feedback)
    return LPResult(dtm, ground, weights0, rows, disagreeing, levels_out)


def _steep_finish(dtm: Array, ground: Array, obs: _Observations, bumps: Array, grid: Grid,
                  prm: LPParameters, constraints: Any,
                  feedback: Feedback) -> Tuple[Array, Array]:
    """The ``steep`` presets' end (:mod:`.steep_ground`): the plane test of the ground cells,
    the trend fill of the DTM from the remaining ones, and the ground cells against it.

    Shrubs and low crowns among sparse ground returns lift the prediction by metres on a
    steep forested slope; the prediction also reverts to the coarser levels' trend far from
    the ground cells, where that trend misses the slope.
    """
    valid0, keep = obs.valid0, obs.keep & obs.valid0
    hard = np.zeros(dtm.shape, bool)
    if len(obs.gpts):
        r, c = grid.cell_of(obs.gpts[:, 0], obs.gpts[:, 1])
        hard[r[r >= 0], c[r >= 0]] = True
    cand = ground & ~keep & np.isfinite(obs.obs0)
    kept = refine_ground(obs.obs0, cand, grid.spacing, prm.refine_radius,
                         [float(t) for t in prm.refine_tolerances])
    feedback.info(f"{int((cand & ~kept).sum())} ground cells stand above the plane through the "
                  f"ground around them (window {2 * prm.refine_radius:g} m): eliminated.")
    values = np.where(kept, obs.obs0, np.nan).astype(np.float32)
    values[hard] = dtm[hard]  # the DTM passes through the manual ground points
    values[keep] = obs.z0[keep]
    known = kept | hard | keep
    barrier = getattr(constraints, "barrier", None)
    filled = trend_fill(values, known, grid.spacing, prm.trend_window, barrier)
    filled = np.where(np.isfinite(dtm) | ~valid0, filled, np.nan)  # max_gap holes stay empty
    filled[keep] = obs.z0[keep]
    return _final_ground(filled, obs, bumps | (cand & ~kept), grid, prm)


def _on_terrain(z: Array, cand: Array, prm: LPParameters, spacing: float) -> Array:
    """Candidates within ``half_weight`` of the grey opening with a ``coarse_spacing`` window.

    The opening removes the objects the pyramid is meant to remove (narrower than
    ``coarse_spacing``) and keeps slopes, terraces and the upper edges of banks exactly
    (:func:`~.surface_input.grey_opening`); a cell on it is terrain, however far the smooth
    prediction passes below it at a break of slope — the weight function alone would reject
    it there.
    """
    size = max(3, round(prm.coarse_spacing / spacing) | 1)
    with np.errstate(invalid="ignore"):
        return cand & (z - grey_opening(z, size) <= prm.half_weight)


def _bumps(z: Array, cand: Array, surface: Array, prm: LPParameters, spacing: float) -> Array:
    """Candidates more than the ground tolerance above their neighbourhood's lower envelope
    (:func:`~.surface_input.ground_bumps` with ``ground_tolerance`` and
    ``ground_slope_factor``)."""
    return ground_bumps(z, cand, surface, spacing, prm.ground_tolerance,
                        prm.ground_slope_factor)



def _ground_point_check(lvl: _Level, fit: _LevelFit, scale0: Optional[Array], gpts: Array,
                        grid: Grid, prm: LPParameters,
                        feedback: Feedback) -> List[Dict[str, Any]]:
    """Ground points against the level-0 surface predicted *without* them."""
    active = (fit.p > 0) & ~lvl.is_hard
    scale = np.where(active, 1.0 / np.maximum(fit.p, 1e-6), 1.0).astype(np.float32)
    if scale0 is not None:
        scale *= scale0
    s, _, _ = lp_solve(lvl.lz, active, fit.cov, scale, lvl.sides,
                       x0=np.where(lvl.is_hard, 0.0, fit.x), tol=prm.cg_tol, feedback=feedback)
    return check_ground_points(lvl.trend + s, grid, gpts, prm.ground_tolerance)


# -- the algorithm ------------------------------------------------------------------------------
def _sigma_grid(inp: Any) -> Optional[Array]:
    """σ_z of the lowest point of every cell (the point the cell's height comes from)."""
    if inp.sigma is None or inp.points is None or inp.point_cells is None:
        return None
    low = lowest_points(inp)
    low = low[np.isfinite(inp.sigma[low])]
    if low.size == 0:
        return None
    out = np.full(inp.grid.width * inp.grid.height, np.nan, np.float32)
    out[inp.point_cells[low]] = inp.sigma[low]
    return out.reshape(inp.grid.shape)


def run_filter_linear_prediction(input: PathLike, output: PathLike, preset: str = "auto",
                                 project: Optional[PathLike] = None,
                                 spacing: Optional[float] = None, crs: Any = None,
                                 overrides: Optional[Dict[str, Any]] = None,
                                 write_levels: bool = False,
                                 feedback: Optional[Feedback] = None) -> Dict[str, Any]:
    """Read, filter by robust linear prediction, and write the products (the algorithm's run).

    Parameters
    ----------
    input : path
        DSM raster or points (see :func:`~.surface_input.read_filter_input`).
    output : path
        Output folder (new or empty), written completely or not at all.
    preset : str
        Name in :data:`~.presets.LINEAR_PREDICTION_PRESETS`, or ``auto`` (chosen from the
        input, :mod:`.auto_preset`; the choice and its reason are reported).
    project : path, optional
        Project whose edits are honoured.
    spacing : float, optional
        Grid spacing (m) for point input.
    crs : optional
        CRS of inputs that carry none.
    overrides : dict, optional
        :class:`LPParameters` fields (None = the preset's value).
    write_levels : bool
        Also write the DTM of every pyramid level (``level_<k>.tif``, on the input grid).

    Returns
    -------
    dict
        ``dtm``, ``ndsm``, ``mask`` or ``labels``, ``report``, ``metrics``.
    """
    feedback = ensure_feedback(feedback)
    ov = {k: v for k, v in (overrides or {}).items() if v is not None}
    values = linear_prediction_preset("default" if is_auto(preset) else preset)
    LPParameters.from_dict({**values, **ov})  # bad presets and options fail before reading
    inp = read_filter_input(input, spacing=spacing, crs=crs, feedback=feedback)
    name, choice = resolve_preset(preset, inp, feedback)
    prm = LPParameters.from_dict({**linear_prediction_preset(name), **ov})
    cons = read_filter_constraints(project, inp.grid, inp.crs)
    feedback.progress(5.0)
    t0 = time.perf_counter()
    res = filter_linear_prediction(inp.z, inp.grid, prm, cons, sigma=_sigma_grid(inp),
                                   feedback=feedback.step(5.0, 85.0), keep_levels=write_levels)
    feedback.info(f"Linear prediction took {time.perf_counter() - t0:.1f} s.")
    valid = np.isfinite(inp.z)
    n_valid = int(valid.sum())
    n_ground = int(np.count_nonzero(res.ground))
    extra: Dict[str, Array] = {}
    if write_levels:
        for k, lvl in enumerate(res.levels):
            f = 2 ** (len(res.levels) - 1 - k)
            extra[f"level_{len(res.levels) - 1 - k}"] = np.repeat(
                np.repeat(lvl, f, axis=0), f, axis=1)[:inp.grid.height, :inp.grid.width]
    report: Dict[str, Any] = {
        "algorithm": "filter_linear_prediction",
        "preset": name,
        "parameters": asdict(prm),
        "cells_valid": n_valid,
        "cells_ground": n_ground,
        "eliminated_share": 1.0 - n_ground / max(n_valid, 1),
        "ground_tolerance_m": prm.ground_tolerance,
        "ground_slope_factor": prm.ground_slope_factor,
        "iterations": res.iterations,
        "constraints": {"keep_cells": int(cons.keep.sum()), "remove_cells": int(cons.remove.sum()),
                        "ground_points": len(cons.ground_points),
                        "breaklines": len(cons.breaklines)},
        "ground_points_disagreeing": res.disagreeing,
        "warnings": [],
    }
    if choice is not None:
        report["preset_choice"] = choice
    check_dtm(inp, res.dtm, report, feedback)
    if res.disagreeing:
        msg = (f"{len(res.disagreeing)} manual ground point(s) differ from the filtered surface "
               f"by more than {prm.ground_tolerance:g} m (listed in the report).")
        report["warnings"].append(msg)
        feedback.warning(msg)
    return write_filter_outputs(output, inp, res.dtm, res.ground, report, extra_rasters=extra,
                                feedback=feedback.step(85.0, 100.0),
                                title="DSM → DTM filtering: robust linear prediction",
                                product="filter_linear_prediction")


__all__ = ["Covariance", "LPParameters", "LPResult", "asymmetric_weights", "covariance_apply",
           "empirical_covariance", "filter_linear_prediction", "fit_covariance",
           "gaussian_covariance", "lp_solve", "predict_dense", "residual_shift",
           "run_filter_linear_prediction"]
