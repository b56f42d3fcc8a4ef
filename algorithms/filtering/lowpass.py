r"""Iterative robust low-pass filtering of a DSM to a DTM (the "Phoenics" method).

After Raguse (2000) §3.3.1 (methods/seed-002-003.md A3.8): a sequence of low-pass filters with a
shrinking window gives approximate DTMs; each is differenced with the current surface, cells too
high above it (buildings, vegetation) or too far below it (blunders) are eliminated, and the
holes are finally filled from the surrounding ground.

Smoothing (normalised convolution of first order)
    In iteration ``k`` every cell gets the height :math:`T_k` of the least-squares plane through
    the remaining cells of a square window of side :math:`w_k` centred on it that are not more
    than the iteration's threshold above the grey opening :math:`O_k` of the remaining cells
    with the same window (:func:`height_above_opening`): objects narrower than the window no
    longer pull the plane up — a building on a hillside, whose roof is flush with the slope
    above it, was otherwise a terrace to the plane and survived. With weights
    :math:`p_j \in \{0, 1\}` (1 = remaining cell), local coordinates ``u, v`` and the window
    means :math:`\bar{\cdot} = \sum p_j \cdot / \sum p_j` (all computed with box filters, so the
    cost per cell does not depend on the window):

    .. math::
        C = \begin{pmatrix} \overline{u^2} - \bar u^2 & \overline{uv} - \bar u \bar v \\
                            \overline{uv} - \bar u \bar v & \overline{v^2} - \bar v^2
            \end{pmatrix},\quad
        (b, c)^T = C^{-1} \begin{pmatrix} \overline{uz} - \bar u \bar z \\
                                          \overline{vz} - \bar v \bar z \end{pmatrix},\quad
        T = \bar z + b (u_0 - \bar u) + c (v_0 - \bar v)

    A tilted plane is reproduced exactly, also next to holes and at the raster border (a plain
    mean would be biased there by slope × centroid offset). Where the support is degenerate
    (:math:`\det C` tiny) the mean :math:`\bar z` is used.

Elimination
    :math:`D_k = M_{k-1} - T_k` (the *difference model*, written per iteration on request);
    a cell is eliminated if :math:`D_k > t_k + s \cdot w_k / 4` (object) or
    :math:`D_k < -(d + s \cdot w_k / 4)` (blunder), with :math:`t_k` the iteration's threshold,
    ``s`` the slope allowance (a plane over a window of side ``w`` lies :math:`s\,w/4` below a
    ridge whose two slopes differ by ``s``, and as far above a valley or the terrace below a
    wall) and ``d`` the blunder depth. Cells within :math:`t_k` of the opening
    (:math:`M_{k-1} - O_k \le t_k`) are not objects: the opening keeps slopes, terraces and the
    upper edges of banks exactly, where the plane misses a break of slope by far more than
    ``s·w/4``. Eliminated cells stay eliminated. After the last iteration, cells more than the
    label tolerance above the opening of the remaining cells with a 5 m window (plus what that
    opening cuts from the last iteration's planes) are eliminated
    (:func:`.surface_input.ground_bumps`: low objects narrower than that, which the planes
    hardly notice). Before the first
    iteration, isolated pits (``low_outlier_m`` below their second lowest neighbour,
    :func:`.surface_input.low_outliers`) are eliminated by a local, slope-invariant test.

Steep vegetated slopes (preset ``steep``)
    After the bumps, remaining cells more than 1.5, 0.8, 0.5, 0.4 m in turn above the
    least-squares plane through the remaining cells within ± ``refine_radius_m`` are
    eliminated (shrubs and low crowns among a few per cent of ground cells), and the holes are
    filled as a local plane trend plus the membrane fill of the residuals, which follows the
    slope across gaps and at the border (:mod:`.steep_ground`).

Hole filling
    Membrane (Laplace) interpolation :math:`\nabla^2 z = 0` of the eliminated and empty cells
    with the ground cells as fixed values, solved coarse to fine on a pyramid (block means of
    the known cells, Jacobi relaxation on every level starting from the coarser solution).

Operator edits
    ``keep`` areas: never eliminated, not used as support for their neighbours, the DSM is the
    DTM there (bit for bit). ``remove`` areas: eliminated before the first iteration, bridged by
    the hole filling. Manual ground points: their cells get the point height, are never
    eliminated and are fixed values of the hole filling (the DTM passes through them); the
    report lists the points the filter's own surface (filled without them) disagrees with.
    Breaklines: the cells on either side of a line are smoothed only with cells of their own
    side (within the window's reach), and the hole filling does not connect cells across a
    line, so a step along a breakline keeps its height.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, fields, replace
from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np
from affine import Affine
from numpy.typing import NDArray
from scipy import ndimage, sparse
from scipy.ndimage import uniform_filter
from scipy.sparse.linalg import cg

from ..errors import InputError
from ..feedback import Feedback, ensure_feedback
from ..project.model import Project
from ..surface.gridding import Grid, polygon_mask
from .auto_preset import check_dtm, is_auto, resolve_preset
from .presets import lowpass_preset
from .steep_ground import refine_ground, trend_fill
from .surface_input import (
    FilterConstraints,
    FilterInput,
    check_ground_points,
    grey_opening,
    ground_bumps,
    low_outliers,
    read_filter_constraints,
    read_filter_input,
    to_crs,
    write_filter_outputs,
)
from .tiles import filter_in_tiles, tile_limit

PathLike = Union[str, Path]
Array = NDArray[Any]

#: Rows per strip of the box-filter smoothing (bounds the float64 temporaries).
STRIP_ROWS = 768

#: Side (cells) below which the hole-filling pyramid stops.
COARSEST = 48

#: Overlap of tiles (large grids, :mod:`.tiles`) in units of the largest window: the
#: iterations compound (a cell eliminated in iteration 1 changes iteration 2's planes) and the
#: hole filling reaches across eliminated buildings.
TILE_OVERLAP_WINDOWS = 2.0


# -- smoothing ------------------------------------------------------------------------------------
def plane_smooth(z: Array, weight: Array, radius: int, min_count: int = 3,
                 strip_rows: int = STRIP_ROWS) -> Array:
    """Height of the local least-squares plane over a square window (see the module notes).

    Parameters
    ----------
    z : ndarray (h, w)
        Heights; cells with weight 0 (or NaN height) are ignored.
    weight : ndarray of bool (h, w)
        Support cells.
    radius : int
        Half side of the window in cells (side ``2·radius + 1``).
    min_count : int
        Fewest support cells a window needs; fewer gives NaN.
    strip_rows : int
        Rows processed at once (memory bound: ~12 float64 arrays of ``strip_rows + 2·radius``
        rows).

    Returns
    -------
    ndarray float32 (h, w)
        The plane heights; the window mean where the plane is undetermined; NaN without support.
    """
    z = np.asarray(z)
    h, w = z.shape
    size = 2 * int(radius) + 1
    out = np.full((h, w), np.nan, np.float32)
    ok_all = np.asarray(weight, bool) & np.isfinite(z)
    if not ok_all.any():
        return out
    # determinant floor relative to a full window's (u and v variances ≈ r(r+1)/3 each)
    full_var = max(radius * (radius + 1) / 3.0, 0.25)
    det_floor = 1e-3 * full_var * full_var
    ucol = np.arange(w, dtype=np.float64) - w / 2.0
    for r0 in range(0, h, strip_rows):
        r1 = min(h, r0 + strip_rows)
        a0, a1 = max(0, r0 - radius), min(h, r1 + radius)
        ok = ok_all[a0:a1]
        p = ok.astype(np.float64)
        if not p.any():
            continue
        zmean = float(np.asarray(z[a0:a1][ok], np.float64).mean())
        # centred heights: better conditioned sums
        zz = np.where(ok, np.asarray(z[a0:a1], np.float64) - zmean, 0.0)
        u = np.broadcast_to(ucol, p.shape)
        v = (np.arange(a1 - a0, dtype=np.float64) - (a1 - a0) / 2.0)[:, None]
        v = np.broadcast_to(v, p.shape)

        def box(a: Array) -> Array:
            return uniform_filter(a, size=size, mode="constant", cval=0.0)

        m0 = box(p)
        with np.errstate(invalid="ignore", divide="ignore"):
            inv = np.where(m0 > 0, 1.0 / np.where(m0 > 0, m0, 1.0), 0.0)
            pu, pv = p * u, p * v
            mu = box(pu) * inv
            mv = box(pv) * inv
            mz = box(zz) * inv
            cuu = box(pu * u) * inv - mu * mu
            cvv = box(pv * v) * inv - mv * mv
            cuv = box(pu * v) * inv - mu * mv
            cuz = box(u * zz) * inv - mu * mz
            cvz = box(v * zz) * inv - mv * mz
            det = cuu * cvv - cuv * cuv
            good = det > det_floor
            sd = np.where(good, det, 1.0)
            b = np.where(good, (cvv * cuz - cuv * cvz) / sd, 0.0)
            c = np.where(good, (cuu * cvz - cuv * cuz) / sd, 0.0)
            t = mz + b * (u - mu) + c * (v - mv)
        count = m0 * size * size
        t = np.where(count >= min_count - 0.5, t, np.nan)
        out[r0:r1] = (t[r0 - a0:r1 - a0] + zmean).astype(np.float32)
    return out


def height_above_opening(z: Array, support: Array, radius: int) -> Array:
    """Height of every support cell above the grey opening of the support cells.

    The opening with the window of the planes (side ``2·radius + 1``,
    :func:`~.surface_input.grey_opening`) is the lower envelope of the support without the
    objects narrower than the window; it keeps slopes, terraces and the upper edges of banks
    exactly. NaN outside the support.
    """
    zs = np.where(support, z, np.nan)
    return (zs - grey_opening(zs, 2 * int(radius) + 1)).astype(np.float32)


def _sub_grid(grid: Grid, r0: int, c0: int, h: int, w: int) -> Grid:
    t = grid.transform
    return Grid(t * Affine.translation(c0, r0), w, h, grid.spacing)


def breakline_sides(lines: Sequence[Any], grid: Grid, reach: float
                    ) -> List[Tuple[Tuple[int, int, int, int], Array, Array]]:
    """Per breakline: its window ``(r0, r1, c0, c1)`` and the left/right side masks within it.

    The sides are the single-sided buffers of width ``reach`` (m) — the cells a smoothing
    window centred on one side could reach on the other.
    """
    out = []
    for line in lines:
        for part in getattr(line, "geoms", [line]):
            if part.is_empty or part.length <= 0:
                continue
            left = part.buffer(reach, single_sided=True)
            right = part.buffer(-reach, single_sided=True)
            xmin, ymin, xmax, ymax = part.buffer(reach).bounds
            inv = ~grid.transform
            cs, rs = zip(*(inv * (x, y) for x in (xmin, xmax) for y in (ymin, ymax)))
            c0, c1 = max(0, math.floor(min(cs))), min(grid.width, math.ceil(max(cs)))
            r0, r1 = max(0, math.floor(min(rs))), min(grid.height, math.ceil(max(rs)))
            if c1 <= c0 or r1 <= r0:
                continue
            sub = _sub_grid(grid, r0, c0, r1 - r0, c1 - c0)
            out.append(((r0, r1, c0, c1), polygon_mask([left], sub), polygon_mask([right], sub)))
    return out


def smooth(z: Array, support: Array, radius: int, sides: Sequence[Any] = (),
           barrier: Optional[Array] = None) -> Array:
    """:func:`plane_smooth` that does not smooth across breaklines.

    ``sides`` comes from :func:`breakline_sides` (with a reach ≥ the window's half diagonal):
    a cell on one side of a line gets its plane from support cells on that side only. Barrier
    cells (on the lines) are never support.
    """
    support = np.asarray(support, bool)
    if barrier is not None:
        support = support & ~barrier
    t = plane_smooth(z, support, radius)
    h, w = z.shape
    for (r0, r1, c0, c1), left, right in sides:
        a0, a1 = max(0, r0 - radius), min(h, r1 + radius)
        b0, b1 = max(0, c0 - radius), min(w, c1 + radius)
        zs, ss = z[a0:a1, b0:b1], support[a0:a1, b0:b1]
        for mine, other in ((left & ~right, right), (right & ~left, left)):
            if not mine.any():
                continue
            other_full = np.zeros(zs.shape, bool)
            other_full[r0 - a0:r1 - a0, c0 - b0:c1 - b0] = other
            ts = plane_smooth(zs, ss & ~other_full, radius)
            block = t[r0:r1, c0:c1]
            block[mine] = ts[r0 - a0:r1 - a0, c0 - b0:c1 - b0][mine]
    return t


# -- hole filling ---------------------------------------------------------------------------------
def _downsample(values: Array, known: Array, barrier: Array) -> Tuple[Array, Array, Array]:
    h, w = values.shape
    hh, ww = (h + 1) // 2, (w + 1) // 2
    vk = np.zeros((2 * hh, 2 * ww))
    kk = np.zeros((2 * hh, 2 * ww))
    bb = np.zeros((2 * hh, 2 * ww), bool)
    use = known & ~barrier
    vk[:h, :w] = np.where(use, values, 0.0)
    kk[:h, :w] = use
    bb[:h, :w] = barrier
    s = vk.reshape(hh, 2, ww, 2).sum(axis=(1, 3))
    n = kk.reshape(hh, 2, ww, 2).sum(axis=(1, 3))
    b = bb.reshape(hh, 2, ww, 2).any(axis=(1, 3))
    inside = np.zeros((2 * hh, 2 * ww))
    inside[:h, :w] = 1.0
    # only blocks known entirely: a partial block's mean sits off its centre (bias on slopes)
    kc = (n > 0) & (n >= inside.reshape(hh, 2, ww, 2).sum(axis=(1, 3)))
    vc = np.where(kc, s / np.maximum(n, 1), np.nan)
    return vc, kc & ~b, b


def _upsample(coarse: Array, shape: Tuple[int, int]) -> Array:
    """Bilinear 2× upsampling (coarse cell centres at fine 2i + ½), cropped to ``shape``."""
    out = coarse.astype(np.float32)
    for axis, n in ((0, shape[0]), (1, shape[1])):
        m = out.shape[axis]
        pos = np.clip((np.arange(n) - 0.5) / 2.0, 0.0, m - 1.0)
        i0 = np.minimum(np.floor(pos).astype(np.int64), max(m - 2, 0))
        i1 = np.minimum(i0 + 1, m - 1)
        f = (pos - i0).astype(np.float32)
        a, b = np.take(out, i0, axis=axis), np.take(out, i1, axis=axis)
        f = f[:, None] if axis == 0 else f[None, :]
        out = a * (1.0 - f) + b * f
    return out


def _relax(values: Array, known: Array, barrier: Array, iterations: int) -> Array:
    r"""Improve the unknown non-barrier cells towards ∇²z = 0 (in place, returned).

    The discrete equations :math:`\sum_{j \in N_4(i)} (z_i - z_j) = 0` over the open
    4-neighbours form a symmetric positive definite system in the unknown cells; it is solved
    by conjugate gradients from the current values (at most ``iterations`` steps).
    """
    h, w = values.shape
    free = ~known & ~barrier
    idx = np.flatnonzero(free)
    if idx.size == 0 or iterations <= 0:
        return values
    flat = values.reshape(-1)
    pos = np.full(h * w, -1, np.int64)
    pos[idx] = np.arange(idx.size)
    rows, cols = np.divmod(idx, w)
    open_ = ~barrier.reshape(-1)
    known_f = known.reshape(-1)
    diag = np.zeros(idx.size)
    rhs = np.zeros(idx.size)
    ai, aj = [], []
    for dr, dc in ((-1, 0), (1, 0), (0, -1), (0, 1)):
        nr, nc = rows + dr, cols + dc
        ok = (nr >= 0) & (nr < h) & (nc >= 0) & (nc < w)
        nb = np.where(ok, np.clip(nr, 0, h - 1) * w + np.clip(nc, 0, w - 1), 0)
        ok &= open_[nb]
        diag += ok
        kn = ok & known_f[nb]
        rhs += np.where(kn, flat[nb], 0.0)
        un = ok & (pos[nb] >= 0)
        ai.append(np.flatnonzero(un))
        aj.append(pos[nb][un])
    has = diag > 0
    diag[~has] = 1.0  # isolated cells keep their start value
    rhs[~has] = flat[idx][~has]
    ai_c, aj_c = np.concatenate(ai), np.concatenate(aj)
    a = sparse.csr_matrix((np.concatenate([diag, -np.ones(ai_c.size)]),
                           (np.concatenate([np.arange(idx.size), ai_c]),
                            np.concatenate([np.arange(idx.size), aj_c]))),
                          shape=(idx.size, idx.size))
    x0 = flat[idx].astype(np.float64)
    # solve for the correction: better conditioned right-hand side, same system
    r0 = rhs - a @ x0
    sol, _ = cg(a, r0, x0=np.zeros_like(x0), maxiter=int(iterations), atol=1e-7)
    flat[idx] = (x0 + sol).astype(values.dtype)
    return values


def membrane_fill(values: Array, known: Array, barrier: Optional[Array] = None,
                  barrier_z: Optional[Array] = None, iterations: int = 40) -> Array:
    r"""Fill the unknown cells by membrane interpolation :math:`\nabla^2 z = 0`.

    Coarse to fine: the known cells are averaged 2 × 2 down to ~:data:`COARSEST` cells, the
    coarsest level is filled from the nearest known cell and relaxed, every finer level starts
    from the coarser solution and is relaxed ``iterations`` times (Jacobi) with the known cells
    fixed. No neighbour relation crosses a barrier cell; unknown barrier cells get
    ``barrier_z`` (3-D breaklines) or the nearest filled height.

    Returns
    -------
    ndarray float32
        ``values`` at known cells, the interpolation elsewhere (NaN only without any known cell).
    """
    values = np.asarray(values, np.float32)
    known = np.asarray(known, bool) & np.isfinite(values)
    barrier = np.zeros(values.shape, bool) if barrier is None else np.asarray(barrier, bool)
    if known.all():
        return values.copy()
    if not (known & ~barrier).any():
        return np.full(values.shape, np.nan, np.float32)
    levels = [(values, known, barrier)]
    while max(levels[-1][0].shape) > COARSEST:
        v, k, b = levels[-1]
        nxt = _downsample(v, k, b)
        if not nxt[1].any():  # nothing known at the coarser level: start here
            break
        levels.append(nxt)
    sol: Optional[Array] = None
    for depth in range(len(levels) - 1, -1, -1):
        v, k, b = levels[depth]
        cur = np.where(k, v, np.nan).astype(np.float32)
        if sol is None:
            src = k & ~b
            if not src.any():
                src = np.isfinite(cur)
            _, (nr, nc) = ndimage.distance_transform_edt(~src, return_indices=True)
            cur = np.where(k, cur, cur[nr, nc]).astype(np.float32)
            n_it = min(4 * max(cur.shape), 200)
        else:
            up = _upsample(sol, cur.shape)
            cur = np.where(k, cur, up).astype(np.float32)
            # coarser levels are cheap (¼ the cells each): relax them longer
            n_it = iterations * 2 ** min(depth, 4)
        cur[~np.isfinite(cur)] = np.nanmean(cur) if np.isfinite(cur).any() else 0.0
        sol = _relax(cur, k, b, n_it)
    assert sol is not None
    out = sol
    bfree = barrier & ~known
    if bfree.any():
        if barrier_z is not None:
            bz = np.asarray(barrier_z, np.float32)
            use = bfree & np.isfinite(bz)
            out[use] = bz[use]
            bfree &= ~use
        if bfree.any():
            src = ~bfree & ~barrier | known
            _, (nr, nc) = ndimage.distance_transform_edt(~src, return_indices=True)
            out[bfree] = out[nr[bfree], nc[bfree]]
    out[known] = values[known]
    return out.astype(np.float32)


# -- the filter -----------------------------------------------------------------------------------
@dataclass
class LowpassParameters:
    """Parameters of the iterative low-pass filter, in operator units (see :mod:`.presets`).

    Attributes
    ----------
    windows_m : list of float
        Side of the smoothing window of every iteration (m), largest first.
    thresholds_m : list of float
        Height above the smoothed surface (m) beyond which a cell is an object, per iteration.
    down_threshold_m : float
        Depth below the smoothed surface (m) beyond which a cell is a blunder.
    slope_pct : float
        Slope allowance (%): the thresholds grow by ``slope_pct/100 · window/4``.
    final_smoothing_m : float
        Window (m) of a last light smoothing of the ground cells; 0 = off.
    height_margin_m : float
        Margin (m) beyond the 0.5 % / 99.5 % height quantiles of gross blunders.
    ground_tolerance_m : float
        Label tolerance (m) on flat terrain.
    low_outlier_m : float or None
        Depth (m) of isolated pits below their second lowest neighbour; 0 or None = off.
    ground_slope_factor : float
        Growth of the label tolerance with the slope (× slope × spacing).
    preset : str
        Name of the preset the values come from.
    height_range : (float, float) or None
        Height quantiles of the blunder test; None = those of the grid (tiles get the whole
        DSM's, so that every tile makes the same test).
    refine_radius_m : float
        Half side (m) of the window of the ground candidates' plane test
        (:func:`.steep_ground.refine_ground`); 0 = off (all presets but ``steep``).
    refine_tolerances_m : list of float
        Heights (m) above that plane beyond which a candidate is dropped, one pass each.
    trend_window_m : float
        Window (m) of the plane trend of the hole filling (:func:`.steep_ground.trend_fill`);
        0 = the plain membrane fill.
    """

    windows_m: List[float]
    thresholds_m: List[float]
    down_threshold_m: float = 5.0
    slope_pct: float = 0.0
    final_smoothing_m: float = 0.0
    height_margin_m: float = 10.0
    ground_tolerance_m: float = 0.5
    low_outlier_m: Optional[float] = 0.0
    ground_slope_factor: float = 0.0
    preset: str = "default"
    height_range: Optional[Tuple[float, float]] = None
    refine_radius_m: float = 0.0
    refine_tolerances_m: Sequence[float] = ()
    trend_window_m: float = 0.0

    @classmethod
    def from_dict(cls, values: Dict[str, Any]) -> LowpassParameters:
        """Parameters from a preset table (unknown keys raise)."""
        names = {f.name for f in fields(cls)}
        for k in values:
            if k not in names:
                raise InputError(f"Unknown low-pass parameter '{k}'.")
        return cls(**values)

    def report(self) -> Dict[str, Any]:
        """The parameters the report lists (without the preset name, the tiles' range and
        the ``steep`` presets' steps where they are off)."""
        off = set() if self.refine_radius_m > 0 else {"refine_radius_m", "refine_tolerances_m"}
        if not self.trend_window_m > 0:
            off.add("trend_window_m")
        return {f.name: getattr(self, f.name) for f in fields(self)
                if f.name not in {"preset", "height_range"} | off}


def _schedule(par: Dict[str, Any], ov: Dict[str, Any]) -> Tuple[List[float], List[float]]:
    """Windows and thresholds of the preset ``par`` with the overrides ``iterations``,
    ``max_window`` and ``threshold`` (popped from ``ov``)."""
    windows = [float(x) for x in ov.pop("windows_m", par["windows_m"])]
    thresholds = [float(x) for x in ov.pop("thresholds_m", par["thresholds_m"])]
    if len(windows) != len(thresholds) or not windows:
        raise InputError("The low-pass schedule needs as many thresholds as windows (≥ 1).")
    n = ov.pop("iterations", None)
    if n is not None and int(n) != len(windows):
        n = int(n)
        if n < 1:
            raise InputError("The low-pass filter needs at least one iteration.")
        f = np.linspace(0.0, 1.0, n) if n > 1 else np.zeros(1)
        windows = list(windows[0] * (windows[-1] / windows[0]) ** f)
        thresholds = list(thresholds[0] * (thresholds[-1] / thresholds[0]) ** f)
    mw = ov.pop("max_window", None)
    if mw is not None:
        if not mw > 0:
            raise InputError("The largest window must be positive.")
        scale = float(mw) / windows[0]
        windows = [x * scale for x in windows]
    thr = ov.pop("threshold", None)
    if thr is not None:
        if not thr > 0:
            raise InputError("The height threshold must be positive.")
        scale = float(thr) / thresholds[-1]
        thresholds = [x * scale for x in thresholds]
    return windows, thresholds


def lowpass_parameters(preset: str = "default",
                       overrides: Optional[Dict[str, Any]] = None) -> LowpassParameters:
    """The preset's parameters with the operator's overrides applied.

    Overrides: ``max_window`` (m; all windows scaled in the preset's proportions),
    ``iterations`` (windows and thresholds resampled geometrically between the first and the
    last), ``threshold`` (m, last iteration; earlier ones scaled in proportion), ``slope``
    (%), or any field of :class:`LowpassParameters`. ``None`` values are ignored.
    """
    par = lowpass_preset(preset)
    par["preset"] = (preset or "default").strip().lower()
    ov = {k: v for k, v in (overrides or {}).items() if v is not None}
    windows, thresholds = _schedule(par, ov)
    slope = ov.pop("slope", None)
    if slope is not None:
        par["slope_pct"] = float(slope)
    for k, v in ov.items():
        if k not in par:
            raise InputError(f"Unknown low-pass parameter '{k}'.")
        par[k] = v
    par["windows_m"] = [round(float(x), 3) for x in windows]
    par["thresholds_m"] = [round(float(x), 3) for x in thresholds]
    return LowpassParameters.from_dict(par)


def _reported_parameters(params: LowpassParameters, rows: List[Dict[str, Any]]
                         ) -> Dict[str, Any]:
    """The report's parameters, with the thresholds the iterations applied (the preset's
    thresholds plus the slope allowance) right after the preset's."""
    out: Dict[str, Any] = {}
    for key, value in params.report().items():
        out[key] = value
        if key == "thresholds_m":
            out["thresholds_applied_m"] = [r["threshold_m"] for r in rows if r["iteration"] >= 1]
    return out


def _filter_tiled(z: Array, spacing: float, params: LowpassParameters,
                  constraints: Optional[FilterConstraints], grid: Grid, limit: int,
                  feedback: Feedback, start: float) -> Dict[str, Any]:
    """:func:`lowpass_filter` of a grid larger than ``limit`` cells, tile by tile."""
    shape = tuple(np.shape(z))
    overlap = math.ceil(TILE_OVERLAP_WINDOWS * max(params.windows_m) / spacing)
    zall = np.asarray(z)
    if not np.isfinite(zall).any():
        raise InputError.of("The DSM holds no height (every cell is nodata).")
    # the blunder range of the whole DSM, not of each tile (same test everywhere)
    tile_params = replace(params, height_range=_height_range(zall[np.isfinite(zall)]))
    tiled = filter_in_tiles(_TileRun(spacing, tile_params), z, grid, constraints, overlap,
                            limit, feedback)
    first = tiled["first"]
    valid = np.isfinite(z)
    n_valid = int(valid.sum())
    keep = (np.zeros(shape, bool) if constraints is None
            else np.asarray(constraints.keep, bool))
    n_filterable = max(int((valid & ~keep).sum()), 1)
    elim = int((valid & ~keep & ~tiled["ground"]).sum())
    feedback.info(f"Filtered in {tiled['tiles']} tiles (overlap {overlap} cells).")
    return {"dtm": tiled["dtm"], "ground": tiled["ground"],
            "iterations": first.get("iterations", []), "differences": [],
            "ground_points_disagreeing": tiled["ground_points_disagreeing"],
            "eliminated_share": elim / n_filterable, "cells_valid": n_valid,
            "cells_ground": int(tiled["ground"].sum()), "tiles": tiled["tiles"],
            "tile_overlap_cells": overlap, "seconds": time.perf_counter() - start}


@dataclass
class _TileRun:
    """Filters one tile of a large grid (the callback of :func:`.tiles.filter_in_tiles`)."""

    spacing: float
    params: LowpassParameters

    def __call__(self, zt: Array, gt: Grid, ct: Optional[FilterConstraints],
                 fb: Feedback) -> Dict[str, Any]:
        return lowpass_filter(zt, self.spacing, self.params, ct, gt, False, fb,
                              max_cells=zt.size)


@dataclass
class _State:
    """The filter's grids: the DSM, the edits, and the surface being thinned out.

    Attributes
    ----------
    dsm : ndarray float32
    valid : ndarray bool
        Cells with a DSM height.
    keep, barrier : ndarray bool
        Keep areas and breakline cells.
    gp : ndarray (n, 3)
        Manual ground points; ``gp_cells`` / ``gp_z`` their cells and heights.
    support : ndarray bool
        Remaining cells (updated by every elimination).
    m : ndarray float32
        The remaining surface (NaN where eliminated).
    n_filterable : int
        Valid cells outside keep areas (denominator of the shares).
    """

    dsm: Array
    valid: Array
    keep: Array
    barrier: Array
    gp: Array
    gp_cells: Array
    gp_z: Array
    support: Array
    m: Array
    n_filterable: int


def _prepare(z: Array, params: LowpassParameters, cons: FilterConstraints,
             grid: Grid) -> Tuple[_State, Dict[str, Any]]:
    """The filter's state before the first iteration and the report row of that step
    (height range, low outliers and remove areas eliminated)."""
    dsm = np.asarray(z, np.float32)
    shape = dsm.shape
    keep = np.asarray(cons.keep, bool)
    remove = np.asarray(cons.remove, bool)
    barrier = (np.asarray(cons.barrier, bool) if cons.barrier is not None
               else np.zeros(shape, bool))
    valid = np.isfinite(dsm)
    if int(valid.sum()) == 0:
        raise InputError.of("The DSM holds no height (every cell is nodata).")
    # manual ground points: their cells take the point height and are protected
    gp = np.asarray(cons.ground_points, float).reshape(-1, 3)
    gp_cells = np.zeros(shape, bool)
    gp_z = np.full(shape, np.nan, np.float32)
    if gp.size:
        r, c = grid.cell_of(gp[:, 0], gp[:, 1])
        ins = r >= 0
        gp_cells[r[ins], c[ins]] = True
        gp_z[r[ins], c[ins]] = gp[ins, 2]
    # height range: robust quantiles ± margin (gross blunders)
    margin = float(params.height_margin_m)
    lo, hi = params.height_range or _height_range(dsm[valid])
    out_of_range = valid & ((dsm < lo - margin) | (dsm > hi + margin)) & ~keep
    # isolated low blunders (a local, slope-invariant test: the iterations' planes cannot tell
    # a pit from the foot of a slope)
    low_depth = float(params.low_outlier_m or 0.0)
    if low_depth > 0:
        out_of_range |= low_outliers(np.where(keep | remove, np.nan, dsm), low_depth) & valid
    support = valid & ~keep & ~remove & ~out_of_range
    m = dsm.copy()
    m[gp_cells] = gp_z[gp_cells]
    support |= gp_cells
    n_filterable = max(int((valid & ~keep).sum()), 1)
    pre = int((valid & ~keep & (remove | out_of_range)).sum())
    row = {"iteration": 0, "window_m": 0.0, "threshold_m": float("nan"),
           "eliminated": pre, "eliminated_share": pre / n_filterable,
           "eliminated_total_share": pre / n_filterable,
           "step": "height range, low outliers and remove areas"}
    return _State(dsm, valid, keep, barrier, gp, gp_cells, gp_z, support, m, n_filterable), row


def _sides(cons: FilterConstraints, grid: Grid, radius: int, spacing: float) -> List[Any]:
    """Breakline sides for windows of ``radius`` cells (none without breaklines)."""
    return breakline_sides(cons.breaklines, grid, (radius + 1) * spacing * 1.5) \
        if cons.breaklines else []


def _eliminate(st: _State, wm: float, tk: float, params: LowpassParameters,
               cons: FilterConstraints, grid: Grid, spacing: float) -> Tuple[Array, int, float]:
    """One iteration: smooth with a window of ``wm`` m, eliminate objects and blunders.

    Returns
    -------
    (the smoothed surface, cells eliminated, the threshold used)
    """
    radius = max(1, round(wm / spacing / 2.0))
    sides = _sides(cons, grid, radius, spacing)
    slope = float(params.slope_pct) / 100.0
    thr = tk + slope * wm / 4.0
    above = height_above_opening(st.m, st.support, radius)
    with np.errstate(invalid="ignore"):
        # objects (cells far above the opening) do not support the planes that judge
        # them; manual ground points always do
        fit = st.support & ~(above > thr) | (st.support & st.gp_cells)
        # cells on the opening lie on terrain it keeps: the plane's error at a break of
        # slope (the upper edge of a bank) is no reason to eliminate them
        on_terrain = above <= tk
    t = smooth(st.m, fit, radius, sides, st.barrier)
    d = st.m - t
    # a plane lies s·w/4 above a valley (foot of a slope, a terrace below a wall) just as
    # it lies s·w/4 below a ridge: the blunder depth grows alike
    thr_down = float(params.down_threshold_m) + slope * wm / 4.0
    with np.errstate(invalid="ignore"):
        elim = st.support & ~st.gp_cells & (((d > thr) & ~on_terrain) | (d < -thr_down))
    # cells without any support in the window keep their height (nothing to compare)
    elim &= np.isfinite(t)
    st.support &= ~elim
    st.m[elim] = np.nan
    return t, int(elim.sum()), thr


def _fill(st: _State, params: LowpassParameters, cons: FilterConstraints, grid: Grid,
          spacing: float, feedback: Feedback, done: float) -> Tuple[Array, List[Dict[str, Any]]]:
    """Optional final smoothing and the hole filling: the DTM and the ground-point check."""
    # optional light smoothing of the ground cells ("interpolation with filtering")
    ground_vals = st.m.copy()
    fs = float(params.final_smoothing_m)
    if fs > spacing:
        radius = max(1, round(fs / spacing / 2.0))
        t = smooth(st.m, st.support, radius, _sides(cons, grid, radius, spacing), st.barrier)
        upd = st.support & ~st.gp_cells & np.isfinite(t)
        ground_vals[upd] = t[upd]
    # known values of the hole filling: ground survivors, keep areas (DSM), ground points
    known = st.support.copy()
    keep_known = st.keep & st.valid
    ground_vals[keep_known] = st.dsm[keep_known]
    known |= keep_known
    # DSM nodata reaching the raster border stays nodata (no extrapolation into nothing)
    outside = _border_nodata(st.valid)  # also where an exclusion area reaches beyond the data
    disagree: List[Dict[str, Any]] = []
    if st.gp.size:
        free = membrane_fill(ground_vals, known & ~st.gp_cells, st.barrier, cons.barrier_z)
        disagree = check_ground_points(free, grid, st.gp, float(params.ground_tolerance_m))
        del free
    feedback.progress(done)
    if params.trend_window_m > 0:
        dtm = trend_fill(ground_vals, known, spacing, float(params.trend_window_m), st.barrier,
                         cons.barrier_z)
    else:
        dtm = membrane_fill(ground_vals, known, st.barrier, cons.barrier_z)
    dtm[keep_known] = st.dsm[keep_known]
    dtm[st.gp_cells] = st.gp_z[st.gp_cells]
    dtm[outside] = np.nan
    return dtm, disagree


def lowpass_filter(z: Array, spacing: float, params: LowpassParameters,
                   constraints: Optional[FilterConstraints] = None, grid: Optional[Grid] = None,
                   keep_differences: bool = False,
                   feedback: Optional[Feedback] = None,
                   max_cells: Optional[int] = None) -> Dict[str, Any]:
    """Filter a DSM grid to a DTM with the iterative robust low-pass (see the module notes).

    Parameters
    ----------
    z : ndarray (h, w)
        DSM, NaN = no data.
    spacing : float
        Cell size (m).
    params : LowpassParameters
        :func:`lowpass_parameters`.
    constraints : FilterConstraints, optional
        The operator's edits on this grid (``grid`` is then needed for the ground points and
        breaklines).
    keep_differences : bool
        Return the difference model of every iteration (not for tiled grids).
    max_cells : int, optional
        Grids with more cells are filtered in overlapping tiles (:mod:`.tiles`; default
        :data:`.tiles.MAX_CELLS`); the overlap is :data:`TILE_OVERLAP_WINDOWS` × the largest
        window.

    Returns
    -------
    dict
        ``dtm`` (float32), ``ground`` (bool: remaining DSM cells, keep areas, ground points),
        ``iterations`` (per iteration: window, threshold, eliminated counts and shares),
        ``differences`` (list of float32 grids or empty), ``ground_points_disagreeing``,
        ``eliminated_share``, ``cells_valid``, ``cells_ground``, ``cells_bumps`` (cells
        eliminated by :func:`.surface_input.ground_bumps`; untiled grids), ``seconds``.
    """
    feedback = ensure_feedback(feedback)
    start = time.perf_counter()
    shape = tuple(np.shape(z))
    if grid is None:
        grid = Grid(Affine(spacing, 0, 0, 0, -spacing, shape[0] * spacing), shape[1], shape[0],
                    spacing)
    limit = tile_limit(max_cells)
    if shape[0] * shape[1] > limit:
        return _filter_tiled(z, spacing, params, constraints, grid, limit, feedback, start)
    cons = constraints if constraints is not None else FilterConstraints.empty(grid)
    st, row0 = _prepare(z, params, cons, grid)
    rows: List[Dict[str, Any]] = [row0]
    diffs: List[Array] = []
    eliminated_total = row0["eliminated"]
    windows = [float(x) for x in params.windows_m]
    n_steps = len(windows) + 2
    last_plane = st.m  # the smooth surface of the last iteration (judges the bumps)
    for k, (wm, tk) in enumerate(zip(windows, [float(x) for x in params.thresholds_m]),
                                 start=1):
        feedback.progress(100.0 * (k - 1) / n_steps)
        last_plane, n_el, thr = _eliminate(st, wm, tk, params, cons, grid, spacing)
        eliminated_total += n_el
        rows.append({"iteration": k, "window_m": wm, "threshold_m": round(thr, 3),
                     "eliminated": n_el, "eliminated_share": n_el / st.n_filterable,
                     "eliminated_total_share": eliminated_total / st.n_filterable,
                     "step": "smoothing and elimination"})
        feedback.info(f"Iteration {k}: window {wm:g} m, threshold {thr:.2f} m, "
                      f"{n_el} cells eliminated ({100.0 * n_el / st.n_filterable:.1f} %).")
        if keep_differences:
            diffs.append(np.where(st.valid, st.dsm - last_plane, np.nan).astype(np.float32))
    # low objects narrower than a few metres pass the windows' planes (they lift them little):
    # at the label resolution a ground cell is within the label tolerance of its neighbourhood
    bumps = ground_bumps(st.m, st.support & ~st.gp_cells, last_plane, spacing,
                         float(params.ground_tolerance_m), float(params.ground_slope_factor))
    n_bumps = int(bumps.sum())
    st.support &= ~bumps
    st.m[bumps] = np.nan
    eliminated_total += n_bumps
    feedback.info(f"{n_bumps} cells stand above their neighbourhood by more than the ground "
                  "tolerance (low objects): eliminated.")
    n_refined = _refine(st, params, spacing)
    eliminated_total += n_refined
    if n_refined:
        feedback.info(f"{n_refined} cells stand above the plane through the ground around them "
                      f"(window {2 * params.refine_radius_m:g} m): eliminated.")
    feedback.progress(100.0 * len(windows) / n_steps)
    dtm, disagree = _fill(st, params, cons, grid, spacing, feedback,
                          100.0 * (len(windows) + 1) / n_steps)
    ground = (st.support | (st.keep & st.valid) | st.gp_cells) & st.valid
    return {"dtm": dtm, "ground": ground, "iterations": rows, "differences": diffs,
            "ground_points_disagreeing": disagree,
            "eliminated_share": eliminated_total / st.n_filterable,
            "cells_valid": int(st.valid.sum()), "cells_ground": int(ground.sum()),
            "cells_bumps": n_bumps, "cells_refined": n_refined,
            "seconds": time.perf_counter() - start}


def _refine(st: _State, params: LowpassParameters, spacing: float) -> int:
    """The ``steep`` presets' plane test of the remaining cells (:mod:`.steep_ground`);
    returns the number of cells it eliminated."""
    if not params.refine_radius_m > 0:
        return 0
    kept = refine_ground(st.m, st.support, spacing, float(params.refine_radius_m),
                         [float(t) for t in params.refine_tolerances_m],
                         protected=st.gp_cells | st.keep, valid=st.valid)
    dropped = st.support & ~kept & ~st.gp_cells
    st.support &= ~dropped
    st.m[dropped] = np.nan
    return int(dropped.sum())


def _height_range(zv: Array) -> Tuple[float, float]:
    """0.5 % and 99.5 % height quantiles of the valid DSM heights (min/max for ≤ 20)."""
    if zv.size > 20:
        lo, hi = np.quantile(zv, [0.005, 0.995])
    else:
        lo, hi = zv.min(), zv.max()
    return float(lo), float(hi)


def _border_nodata(has: Array, reach: int = 3) -> Array:
    """Empty cells connected to the raster border and more than ``reach`` cells from data.

    They stay NaN in the DTM (no extrapolation into areas without data); the first few cells
    are filled so that points at the edge of a gridded point cloud still have a DTM height.
    """
    empty = ~has
    if not empty.any() or not has.any():
        return empty
    lab, n = ndimage.label(empty)
    if n == 0:
        return empty
    edge = np.unique(np.concatenate([lab[0], lab[-1], lab[:, 0], lab[:, -1]]))
    edge = edge[edge > 0]
    far = ndimage.distance_transform_edt(empty) > reach
    return np.isin(lab, edge) & far


def run_filter_lowpass(input: PathLike, output: PathLike, preset: str = "auto",
                       project: Optional[PathLike] = None, spacing: Optional[float] = None,
                       crs: Any = None, overrides: Optional[Dict[str, Any]] = None,
                       write_iterations: bool = False,
                       feedback: Optional[Feedback] = None) -> Dict[str, Any]:
    """``filter_lowpass``: read, filter, write (nothing is written when anything fails).

    Parameters
    ----------
    input : path
        DSM raster or points (see :func:`.surface_input.read_filter_input`).
    output : path
        Output folder (new or empty).
    preset : str
        Name in :data:`.presets.LOWPASS_PRESETS`, or ``auto`` (chosen from the input's slope
        and vegetation share, :mod:`.auto_preset`; the choice and its reason are reported).
    project : path, optional
        Project whose edits.gpkg is honoured.
    spacing : float, optional
        Grid spacing of point input (m).
    crs : optional
        CRS of input without one.
    overrides : dict, optional
        ``max_window``, ``iterations``, ``threshold``, ``slope`` (see
        :func:`lowpass_parameters`).
    write_iterations : bool
        Also write ``diff_01.tif`` … (the difference model of every iteration).

    Returns
    -------
    dict
        ``dtm``, ``ndsm``, ``mask`` or ``labels``, ``report`` (paths) and ``metrics``.
    """
    feedback = ensure_feedback(feedback)
    auto = is_auto(preset)
    params = lowpass_parameters("default" if auto else preset, overrides)  # checks early
    inp: FilterInput = read_filter_input(input, spacing=spacing, crs=crs, feedback=feedback)
    name, choice = resolve_preset(preset, inp, feedback)
    if auto:
        params = lowpass_parameters(name, overrides)
    if project is not None and str(project) != "" and inp.crs is None:
        prj_crs = Project.load(project).crs
        if prj_crs:
            inp.crs = to_crs(prj_crs)
    cons = read_filter_constraints(project, inp.grid, inp.crs)
    feedback.progress(5.0)
    res = lowpass_filter(inp.z, inp.grid.spacing, params, cons, inp.grid,
                         keep_differences=write_iterations, feedback=feedback.step(5.0, 85.0))
    for b in res["ground_points_disagreeing"]:
        feedback.warning(f"Manual ground point {b['index']} ({b['x']:.2f}, {b['y']:.2f}, "
                         f"{b['z']:.2f}): the filter's surface differs by "
                         f"{'?' if b['dh'] is None else format(b['dh'], '+.2f')} m "
                         f"({b['status']}); the DTM passes through the point.")
    report = {
        "algorithm": "filter_lowpass",
        "preset": params.preset,
        "parameters": _reported_parameters(params, res["iterations"]),
        "iterations": res["iterations"],
        "eliminated_share": res["eliminated_share"],
        "cells_valid": res["cells_valid"],
        "cells_ground": res["cells_ground"],
        "ground_tolerance_m": params.ground_tolerance_m,
        "ground_slope_factor": params.ground_slope_factor,
        "grid": {"width": inp.grid.width, "height": inp.grid.height,
                 "spacing": inp.grid.spacing},
        "constraints": {"keep_cells": int(cons.keep.sum()),
                        "remove_cells": int(cons.remove.sum()),
                        "ground_points": len(cons.ground_points),
                        "breaklines": len(cons.breaklines)},
        "ground_points_disagreeing": res["ground_points_disagreeing"],
        "warnings": [],
    }
    if choice is not None:
        report["preset_choice"] = choice
    check_dtm(inp, res["dtm"], report, feedback)
    extra = {f"diff_{i:02d}": d for i, d in enumerate(res["differences"], start=1)}
    out = write_filter_outputs(output, inp, res["dtm"], res["ground"], report,
                               extra_rasters=extra, feedback=feedback.step(85.0, 100.0),
                               title="DSM → DTM: iterative low-pass filter",
                               product="filter_lowpass")
    feedback.info(f"Eliminated {100.0 * res['eliminated_share']:.1f} % of the DSM cells in "
                  f"{res['seconds']:.1f} s; DTM in {out['dtm']}.")
    return out


__all__ = ["LowpassParameters", "breakline_sides", "height_above_opening", "lowpass_filter",
           "lowpass_parameters", "membrane_fill", "plane_smooth", "run_filter_lowpass", "smooth"]
