r"""One computation window of the object-space matching: the coarse-to-fine Gauss–Newton
adjustment of heights, object grey values and radiometry (:func:`adjust_window`), visibility,
gross-error screening and the precision by probing.

The model, its equations and the choices behind them are described in the notes of
:mod:`.object_space`, which cuts the DSM into windows and calls :func:`adjust_window`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np
from numpy.typing import NDArray
from scipy import ndimage, sparse
from scipy.sparse.linalg import splu

from ..feedback import Feedback, ensure_feedback
from ..geometry.orientation import ExteriorOrientation
from ..linalg import CG_OBJECT_SPACE, dot_pairwise, jacobi, pcg
from .pyramid import to_level

Array = NDArray[np.float64]

#: Colour distance (nodes) of the probing estimate of diag(N⁻¹).
PROBE_DISTANCE = 5
#: Regularisation modes.
MODES = ("curvature", "correction")
#: Smallest cosine between the surface normal and the ray to an image (grazing rays, walls).
MIN_COS = 0.3
#: Samples (ground pixels of the level) dropped around occluded and grazing samples.
VIS_MARGIN = 2
#: Gross-error screening: samples whose images deviate by more than this many robust σ.
REJECT_K = 4.0
#: Ridge on the grey-value unknowns, relative to the median grey diagonal of AᵀA.
GREY_RIDGE = 1e-3
#: Height jump (m) of the input DSM that counts as a discontinuity (a wall): the curvature
#: regularisation is cut there and heights are interpolated only from nodes on the same side.
BREAK_M = 1.0
#: Slope (m per m) that never counts as a wall between a node and a point.
SLOPE_TOL = 0.5
#: Ridge on height nodes that neither data nor regularisation determine (relative to the
#: median height diagonal): they keep their start correction.
HEIGHT_RIDGE = 1e-6
#: Relative residual and iteration limit of the conjugate gradients per Gauss–Newton step.
CG_TOL = 1e-6
CG_MAX_ITER = 2000


# -- small numerical helpers -------------------------------------------------------------------
def noblas(eo: Any) -> Any:
    """A copy of an orientation whose rotation matrix is a strided view.

    numpy's ``matmul`` then uses its own loop instead of ``cblas_dgemm`` for the projection
    (:func:`..geometry.projection.world_to_camera`). Inside QGIS another CBLAS (GSL's) may be
    loaded first and sum in another order; the last-bit differences would flip convergence
    decisions, and the product must be the same in every face (Python, CLI, QGIS).
    """

    rot = np.repeat(np.asarray(eo.rotation, dtype=float), 2, axis=1)[:, ::2]
    return ExteriorOrientation(np.array(eo.position, dtype=float), rot)


def _bilinear_index(u: Array, n: int) -> Tuple[Array, Array]:
    """Lower node index (clipped to n−2) and fraction of fractional grid coordinates ``u``."""
    i0 = np.clip(np.floor(u).astype(np.intp), 0, max(n - 2, 0))
    return i0, u - i0


def _bilinear_weights(u: Array, v: Array, nx: int, ny: int) -> Tuple[Array, Array]:
    """Node indices (n, 4) and bilinear weights (n, 4) on an ny × nx node grid (row-major)."""
    iu, fu = _bilinear_index(u, nx)
    iv, fv = _bilinear_index(v, ny)
    iu1 = np.minimum(iu + 1, nx - 1)
    iv1 = np.minimum(iv + 1, ny - 1)
    idx = np.stack([iv * nx + iu, iv * nx + iu1, iv1 * nx + iu, iv1 * nx + iu1], axis=1)
    w = np.stack([(1 - fv) * (1 - fu), (1 - fv) * fu, fv * (1 - fu), fv * fu], axis=1)
    return idx, w


def _sample_stack(stack: NDArray, col: Array, row: Array, margin: float = 1.0
                  ) -> Tuple[Array, NDArray[np.bool_]]:
    """Bilinear values of a (bands, h, w) stack at (col, row); valid inside a margin."""
    _, h, w = stack.shape
    ok = (col >= margin) & (col <= w - 1 - margin) & (row >= margin) & (row <= h - 1 - margin)
    c = np.where(ok, col, margin)
    r = np.where(ok, row, margin)
    c0, fc = _bilinear_index(c, w)
    r0, fr = _bilinear_index(r, h)
    flat = stack.reshape(stack.shape[0], -1)
    i00 = r0 * w + c0
    out = ((1 - fr) * ((1 - fc) * flat[:, i00] + fc * flat[:, i00 + 1])
           + fr * ((1 - fc) * flat[:, i00 + w] + fc * flat[:, i00 + w + 1]))
    return out, ok


def _prolong(nodes: Array, r: Array, c: Array) -> Array:
    """Bilinear interpolation of a node grid at fractional (row, col) node coordinates."""
    return ndimage.map_coordinates(nodes, [r, c], order=1, mode="nearest")


def _prolong_same_side(dz_coarse: Array, z_coarse: Array, z_fine: Array, node_m: float
                       ) -> Array:
    """Node corrections of the next finer level (half the spacing): bilinear from the coarse
    nodes on the same side of a wall (:func:`same_side_weights`), 0 where there is none."""
    ny, nx = z_fine.shape
    pr, pc = np.mgrid[0:ny, 0:nx]
    cy, cx = dz_coarse.shape
    idx, w = _bilinear_weights(pc.ravel() / 2.0, pr.ravel() / 2.0, cx, cy)
    w = same_side_weights(idx, w, z_coarse.ravel(), z_fine.ravel(), node_m)
    return (dz_coarse.ravel()[idx] * w).sum(axis=1).reshape(ny, nx)


def _fill_nearest(z: NDArray) -> NDArray:
    """NaNs replaced by the nearest finite value (for internal use only)."""
    bad = ~np.isfinite(z)
    if not bad.any() or bad.all():
        return np.where(bad, 0.0, z)
    idx = ndimage.distance_transform_edt(bad, return_distances=False, return_indices=True)
    return z[tuple(idx)]


def same_side_weights(idx: NDArray, w: Array, z_nodes: Array, z_points: Array,
                      node_m: float, step: Optional[float] = None) -> Array:
    """Bilinear weights (n, 4) restricted to the nodes on the same side of a discontinuity.

    A node whose input height differs from the point's input height by more than
    ``step + SLOPE_TOL · d`` (``d`` the horizontal distance in m, so slopes up to
    :data:`SLOPE_TOL` never count) lies across a wall (a roof node for a ground point or the
    reverse): its weight is set to 0 and the others are renormalised, so a correction never
    leaks from the roof to the ground. Points without any such node (on a wall, between roof
    and ground) get all-zero weights: they keep their input height.

    Parameters
    ----------
    idx, w : ndarray (n, 4)
        Node indices and bilinear weights (:func:`_bilinear_weights` order).
    z_nodes : ndarray
        Input heights of the nodes (flat).
    z_points : ndarray (n,)
        Input heights of the points.
    node_m : float
        Node spacing (m).
    step : float, optional
        Height jump (m) that counts as a wall; default :data:`BREAK_M`.
    """
    step = BREAK_M if step is None else step
    fu = w[:, 1] + w[:, 3]  # fractions within the node cell, recovered from the weights
    fv = w[:, 2] + w[:, 3]
    d = node_m * np.stack([np.hypot(fu, fv), np.hypot(1 - fu, fv), np.hypot(fu, 1 - fv),
                           np.hypot(1 - fu, 1 - fv)], axis=1)
    same = np.abs(z_nodes[idx] - z_points[:, None]) <= step + SLOPE_TOL * d
    ws = np.where(same, w, 0.0)
    tot = ws.sum(axis=1, keepdims=True)
    return np.where(tot > 0, ws / np.where(tot > 0, tot, 1.0), 0.0)


def _second_difference_rows(ny: int, nx: int, z_nodes: Optional[Array] = None,
                            step: Optional[float] = None) -> sparse.csr_matrix:
    """Rows of the discrete curvature (7.2-5/6) on an ny × nx node grid: [1, −2, 1] X and Y.

    With the input heights of the nodes ``z_nodes``, rows whose three nodes straddle a
    discontinuity (input second difference > ``step``: a wall, not a slope) are left out, so
    the regularisation does not tie the roof's correction to the ground's.
    """
    idx = np.arange(ny * nx).reshape(ny, nx)
    blocks = []
    for centre, lo, hi in ((idx[:, 1:-1], idx[:, :-2], idx[:, 2:]),
                           (idx[1:-1, :], idx[:-2, :], idx[2:, :])):
        c = centre.ravel()
        if c.size:
            blocks.append((lo.ravel(), c, hi.ravel()))
    if not blocks:
        return sparse.csr_matrix((0, ny * nx))
    lo = np.concatenate([b[0] for b in blocks])
    c = np.concatenate([b[1] for b in blocks])
    hi = np.concatenate([b[2] for b in blocks])
    if z_nodes is not None:
        zf = np.asarray(z_nodes, dtype=float).ravel()
        keep = np.abs(zf[lo] - 2.0 * zf[c] + zf[hi]) <= (BREAK_M if step is None else step)
        lo, c, hi = lo[keep], c[keep], hi[keep]
    n = c.size
    rows = np.repeat(np.arange(n), 3)
    cols = np.stack([lo, c, hi], axis=1).ravel()
    vals = np.tile([1.0, -2.0, 1.0], n)
    return sparse.csr_matrix((vals, (rows, cols)), shape=(n, ny * nx))


def _hold_rows(ny: int, nx: int, z_nodes: Array, step: Optional[float] = None
               ) -> sparse.csr_matrix:
    """Rows ``2·dZ_c = 0`` for the centre of every curvature row cut at a wall.

    The cut keeps the roof's correction off the ground, but leaves the nodes next to a wall
    (on weakly textured roofs often all nodes of a small roof) without the regularisation
    that held them; this holds them at the input height instead, with the weight a
    curvature row gives its centre. On the correction ΔZ in both modes.
    """
    idx = np.arange(ny * nx).reshape(ny, nx)
    zf = np.asarray(z_nodes, dtype=float).ravel()
    lim = BREAK_M if step is None else step
    cut = []
    for centre, lo, hi in ((idx[:, 1:-1], idx[:, :-2], idx[:, 2:]),
                           (idx[1:-1, :], idx[:-2, :], idx[2:, :])):
        c, a, b = centre.ravel(), lo.ravel(), hi.ravel()
        cut.append(c[~(np.abs(zf[a] - 2.0 * zf[c] + zf[b]) <= lim)])
    c = np.concatenate(cut) if cut else np.zeros(0, int)
    return sparse.csr_matrix((np.full(c.size, 2.0), (np.arange(c.size), c)),
                             shape=(c.size, ny * nx))


# -- image windows -----------------------------------------------------------------------------
@dataclass
class ImageWindow:
    """Pyramid of one image window: level → (3, h, w) stack of grey, ∂/∂col, ∂/∂row."""

    name: str
    camera: Any
    eo: Any
    col0: int
    row0: int
    levels: List[NDArray] = field(default_factory=list)



# -- the adjustment of one window --------------------------------------------------------------
@dataclass
class WindowResult:
    """Result of one computation window (geometry nodes are on the output grid)."""

    dz: Array  # correction per geometry node (ny, nx)
    sigma: Array  # σ_Z per geometry node (m), NaN where undetermined
    observed: NDArray[np.bool_]  # nodes with observations of ≥ 2 images
    sigma0: float  # grey values
    iterations: List[int]
    cg_iterations: List[int]
    images: List[str]
    ok: bool
    message: str = ""
    reg_share: float = float("nan")
    rejected_share: float = float("nan")  # samples of the finest level left out as gross errors


def adjust_window(z_in: NDArray, valid: NDArray[np.bool_], x_first: float, y_first: float,
                  spacing: float, stride: int, windows: Sequence[ImageWindow], gsd: float,
                  parallax_per_m: float, levels: int, *, max_iter: int = 8,
                  regularisation: float = 1.0, weight: Optional[float] = None,
                  mode: str = "correction", grey_px: float = 2.0,
                  feedback: Optional[Feedback] = None) -> WindowResult:
    r"""Object-space least-squares matching of one window (see the module notes).

    Parameters
    ----------
    z_in : (rows, cols) array
        Input heights at the output cell centres of the window (NaN allowed, see ``valid``).
    valid : (rows, cols) bool
        Cells that may be refined (finite input, not excluded).
    x_first, y_first : float
        World position of the centre of cell (0, 0) of the window.
    spacing : float
        Output cell size (m); rows go south (−Y).
    stride : int
        Output cells per geometry node on level 0; ``(rows − 1)`` and ``(cols − 1)`` must be
        multiples of ``stride·2^(levels−1)``.
    windows : sequence of ImageWindow
        Image pyramids (``levels`` levels) with cameras and orientations.
    gsd : float
        Ground sample distance of level 0 (m).
    parallax_per_m : float
        Pixels of parallax per metre of height for the widest base, B/(H·GSD).
    levels : int
    max_iter, regularisation, mode, grey_px
        See :func:`.object_space.refine_object_space`.
    weight : float, optional
        Fixed λ (``regularisation_weight``); default: from the share ``regularisation``.
    """
    feedback = ensure_feedback(feedback)
    rows, cols = z_in.shape
    win = _Window(_fill_nearest(np.asarray(z_in, dtype=float)), valid, x_first, y_first,
                  spacing, windows, parallax_per_m, feedback)
    opts = _AdjustOptions(int(max_iter), float(regularisation), weight, mode, grey_px)
    st = _WindowState(np.zeros(len(windows)), np.ones(len(windows)))
    names = [w.name for w in windows]
    dz_nodes: Optional[Array] = None
    z_coarse: Optional[Array] = None
    for level in range(levels - 1, -1, -1):
        lat = _lattice(win, rows, cols, stride * 2 ** level, level, gsd, grey_px)
        if lat is None:
            continue
        if dz_nodes is None or z_coarse is None:
            dz = np.zeros((lat.ny, lat.nx))
        else:  # prolongation: bilinear from the same side of walls, node spacing halves
            dz = _prolong_same_side(dz_nodes, z_coarse, lat.zin_nodes, 2 * lat.st * spacing)
        z_coarse = lat.zin_nodes
        out = _adjust_level(win, lat, dz, st, opts)
        if isinstance(out, str):
            return _failed(names, st.iters, st.cg_iters, out)
        dz_nodes = out
    if dz_nodes is None or not st.last:
        return _failed(names, st.iters, st.cg_iters,
                       "the window is too small for the geometry facets")
    sigma, sigma0, observed = _precision(st.last)
    return WindowResult(dz_nodes, sigma, observed, sigma0, st.iters, st.cg_iters, names, True,
                        reg_share=st.reg_share, rejected_share=st.rej_share)


@dataclass(frozen=True)
class _AdjustOptions:
    """Options of :func:`adjust_window` (see :func:`.object_space.refine_object_space`)."""

    max_iter: int
    regularisation: float  # share of the curvature on the height diagonal
    weight: Optional[float]  # fixed λ instead
    mode: str
    grey_px: float


@dataclass
class _Window:
    """The data of one window that every level uses."""

    zf: Array  # input heights, NaNs filled by the nearest value
    valid: NDArray[np.bool_]
    x_first: float
    y_first: float
    spacing: float
    images: Sequence[ImageWindow]
    parallax_per_m: float
    feedback: Feedback


@dataclass
class _WindowState:
    """What carries over from level to level: radiometry, datum, counts, the last system."""

    h0: Array
    h1: Array
    ref: int = -1  # radiometric reference image (−1: not chosen yet)
    first: bool = True  # the start radiometry is still to be matched
    iters: List[int] = field(default_factory=list)
    cg_iters: List[int] = field(default_factory=list)
    last: Dict[str, Any] = field(default_factory=dict)
    reg_share: float = float("nan")
    rej_share: float = float("nan")


@dataclass
class _Lattice:
    """Samples, geometry nodes and grey nodes of one pyramid level of a window."""

    level: int
    st: int  # output cells per geometry node
    ny: int
    nx: int
    ns_y: int
    ns_x: int
    Xs: Array
    Ys: Array
    z_s: Array  # input heights at the samples
    v_s: NDArray[np.bool_]  # samples on refinable cells
    gidx: NDArray
    gw: Array
    oidx: NDArray
    ow: Array
    noy: int
    nox: int
    delta: float  # metres of the ∂/∂Z differences
    reg: sparse.csr_matrix
    hold: sparse.csr_matrix  # rows holding the nodes at cut curvature rows (on ΔZ)
    zin_nodes: Array


def _lattice(win: _Window, rows: int, cols: int, st: int, level: int, gsd: float,
             grey_px: float) -> Optional[_Lattice]:
    """The lattices of ``level`` (None when the window has fewer than 3 nodes a side)."""
    ny, nx = (rows - 1) // st + 1, (cols - 1) // st + 1
    if min(ny, nx) < 3:
        return None
    spacing = win.spacing
    gsd_l = gsd * 2 ** level
    # samples: one per ground pixel of the level, over the hull of the cell centres
    ext_x = (cols - 1) * spacing
    ext_y = (rows - 1) * spacing
    ns_x = max(math.floor(ext_x / gsd_l), 1)
    ns_y = max(math.floor(ext_y / gsd_l), 1)
    su = (np.arange(ns_x) + 0.5) * (ext_x / ns_x)  # metres from the first cell centre
    sv = (np.arange(ns_y) + 0.5) * (ext_y / ns_y)
    SU, SV = np.meshgrid(su, sv)
    SU, SV = SU.ravel(), SV.ravel()
    # input heights and validity at the samples (output cells → bilinear)
    zidx, zw = _bilinear_weights(SU / spacing, SV / spacing, cols, rows)
    z_s = (win.zf.ravel()[zidx] * zw).sum(axis=1)
    v_s = (win.valid.ravel()[zidx] | (zw == 0)).all(axis=1)
    gidx, gw = _bilinear_weights(SU / (st * spacing), SV / (st * spacing), nx, ny)
    zin_nodes = win.zf[::st, ::st][:ny, :nx]
    gw = same_side_weights(gidx, gw, zin_nodes.ravel(), z_s, st * spacing)  # not across walls
    # grey grid
    dgo = grey_px * gsd_l
    nox = math.ceil(ext_x / dgo) + 1
    noy = math.ceil(ext_y / dgo) + 1
    oidx, ow = _bilinear_weights(SU / dgo, SV / dgo, nox, noy)
    return _Lattice(level, st, ny, nx, ns_y, ns_x, win.x_first + SU, win.y_first - SV, z_s,
                    v_s, gidx, gw, oidx, ow, noy, nox, max(gsd_l, 0.05),
                    _second_difference_rows(ny, nx, zin_nodes), _hold_rows(ny, nx, zin_nodes),
                    zin_nodes)


def _level_visibility(win: _Window, lat: _Lattice, dz: Array) -> NDArray[np.bool_]:
    """Samples each image sees on the start surface of the level, eroded by a margin.

    Once per level: the corrections of one level are a fraction of a cell, far below what
    changes an occlusion.
    """
    rows, cols = win.zf.shape
    rr_c, cc_c = np.mgrid[0:rows, 0:cols]
    surf = win.zf + _prolong(dz, rr_c / lat.st, cc_c / lat.st)
    zs = lat.z_s + (dz.ravel()[lat.gidx] * lat.gw).sum(axis=1)
    vis = _visibility(win.images, lat.Xs, lat.Ys, zs, surf, win.x_first, win.y_first,
                      win.spacing)
    return _erode_visibility(vis, lat.ns_y, lat.ns_x, VIS_MARGIN) & lat.v_s[None, :]


@dataclass
class _Observation:
    """Grey values and height coefficients of one linearisation, with its sample masks."""

    g_all: Array
    k_all: Array
    seen: NDArray[np.bool_]
    use: NDArray[np.bool_]


def _adjust_level(win: _Window, lat: _Lattice, dz: Array, st: _WindowState,
                  opts: _AdjustOptions) -> Union[Array, str]:
    """Gauss–Newton iterations of one level from the node corrections ``dz``.

    Returns the corrections after the level, or the message of a failure. Updates the
    radiometry, counts and the last system in ``st``.
    """
    vis = _level_visibility(win, lat, dz)
    rejected = np.zeros(lat.z_s.size, bool)
    in_system = np.zeros(lat.nox * lat.noy, bool)
    G: Optional[Array] = None
    lam = -1.0 if opts.weight is None else float(opts.weight)
    prev_s0 = float("inf")
    n_it = 0
    done = False
    for it in range(opts.max_iter + 1):
        win.feedback.check()
        zs = lat.z_s + (dz.ravel()[lat.gidx] * lat.gw).sum(axis=1)
        g_all, k_all = _observe(win.images, lat.level, lat.Xs, lat.Ys, zs, vis, lat.delta)
        seen = np.isfinite(g_all)
        use = (seen.sum(axis=0) >= 2) & ~rejected
        if use.sum() < 16:
            return "no samples seen by two images"
        ob = _Observation(g_all, k_all, seen, use)
        if st.ref < 0:  # radiometric datum: the image that sees most samples
            st.ref = int(np.argmax(seen[:, use].sum(axis=1)))
        G = _grey_values(ob, G, in_system, st, lat)
        A, obs, cols_g, rad_cols = _design(g_all, k_all, seen & use[None, :], lat.gidx, lat.gw,
                                           lat.oidx, lat.ow, G, st.h0, st.h1, st.ref,
                                           lat.nx * lat.ny, lat.nox * lat.noy)
        n_z = lat.nx * lat.ny
        in_system = cols_g >= 0
        s0 = math.sqrt(dot_pairwise(obs, obs) / max(obs.size - A.shape[1], 1))
        st.last = {"A": A, "l": obs, "n_z": n_z, "ny": lat.ny, "nx": lat.nx,
                   "n_rad": 2 * len(rad_cols)}
        if not np.isfinite(s0) or (it > 0 and s0 > 3.0 * prev_s0):
            return "the adjustment diverged"
        if done or it == opts.max_iter or (it > 1 and abs(prev_s0 - s0) < 0.005 * prev_s0):
            break
        prev_s0 = s0
        x, lam, det = _solve_step(A, obs, cols_g, lat, dz, lam, st, opts)
        # increments clipped to 0.2 geometry spacings and 1 px of parallax
        px_per_m = win.parallax_per_m / 2 ** lat.level
        lim = min(0.2 * lat.st * win.spacing, 1.0 / max(px_per_m, 1e-9))
        dZ = np.clip(x[:n_z], -lim, lim)
        dz = dz + dZ.reshape(lat.ny, lat.nx)
        G = G.copy()
        G[cols_g >= 0] += x[cols_g[cols_g >= 0]]
        for i, (j0, j1) in rad_cols.items():
            st.h0[i] += x[j0]
            st.h1[i] += x[j1]
        # gross-error screening on the image-to-image consistency after this step
        dz_s = (dZ[lat.gidx] * lat.gw).sum(axis=1)
        rejected |= _screen(g_all, k_all, seen, st.h0, st.h1, dz_s, REJECT_K)
        n_it += 1
        # converged in height: one more linearisation gives the final residuals
        # (over the nodes with image data; the others only follow the regularisation)
        done = (not det.any()
                or float(np.max(np.abs(dZ[det]))) < 0.01 / max(px_per_m, 1e-9))
    st.iters.append(n_it)
    n_two = int((vis.sum(axis=0) >= 2).sum())
    st.rej_share = float((rejected & (vis.sum(axis=0) >= 2)).sum()) / max(n_two, 1)
    return dz


def _grey_values(ob: _Observation, G: Optional[Array], in_system: NDArray[np.bool_],
                 st: _WindowState, lat: _Lattice) -> Array:
    """The object grey values to linearise at.

    On the first linearisation of a level they start from the images' mean (after matching
    the start radiometry to the reference, once per window); later, grey nodes outside the
    last system (touched by rejected or new samples only) get the current mean of the
    images, not a stale value.
    """
    g_all, seen, use = ob.g_all, ob.seen, ob.use
    if G is None:
        if st.first:  # start radiometry: mean and spread matched to the reference
            g_ref = g_all[st.ref, use & seen[st.ref]]
            for i in range(g_all.shape[0]):
                gi = g_all[i, use & seen[i]]
                if i != st.ref and gi.size >= 16:
                    st.h1[i] = float(np.std(g_ref) / max(float(np.std(gi)), 1e-6))
                    st.h0[i] = float(np.mean(g_ref) - st.h1[i] * np.mean(gi))
            st.first = False
        return _start_grey(g_all, seen, use, st.h0, st.h1, lat.oidx, lat.ow, lat.noy, lat.nox)
    if in_system.all():
        return G
    fresh = _start_grey(g_all, seen, seen.sum(axis=0) >= 2, st.h0, st.h1, lat.oidx, lat.ow,
                        lat.noy, lat.nox)
    return np.where(in_system, G, fresh)


def _solve_step(A: sparse.csr_matrix, obs: Array, cols_g: NDArray, lat: _Lattice, dz: Array,
                lam: float, st: _WindowState, opts: _AdjustOptions
                ) -> Tuple[Array, float, NDArray[np.bool_]]:
    """One Gauss–Newton solution: normal equations with the curvature regularisation
    (7.2-5/6) and the grey ridge, solved by CG.

    Returns the increments, λ (set from the share on the first step of a level, then kept
    within the Gauss–Newton loop) and the height nodes with image data.
    """
    n_z, n_unk = lat.nx * lat.ny, A.shape[1]
    Nd = (A.T @ A).tocsr()
    b = A.T @ obs
    Rz = sparse.vstack([lat.reg, lat.hold]).tocsr()
    R = sparse.hstack([Rz, sparse.csr_matrix((Rz.shape[0], n_unk - n_z))]).tocsr()
    RtR = (R.T @ R).tocsr()
    if lam < 0:  # λ from the share, once per level
        d_data = float(Nd.diagonal()[:n_z].mean())
        d_reg = float(RtR.diagonal()[:n_z].mean())
        lam = opts.regularisation * d_data / max(d_reg, 1e-30) if d_reg > 0 else 0.0
    Nr = lam * RtR
    st.reg_share = float(Nr.diagonal()[:n_z].mean()
                         / max(float(Nd.diagonal()[:n_z].mean()), 1e-30))
    z_node = dz if opts.mode == "correction" else lat.zin_nodes + dz
    b = b - lam * (R.T @ np.concatenate([lat.reg @ z_node.ravel(), lat.hold @ dz.ravel()]))
    # determinability (seed-004 §5.3 f): a grey node at the edge of the used samples may
    # carry only a corner of one sample's bilinear weights; a ridge of 1e-3 of the typical
    # grey diagonal keeps it from running away (negligible elsewhere)
    dg = Nd.diagonal()[n_z:n_z + int((cols_g >= 0).sum())]
    ridge = np.zeros(n_unk)
    if dg.size:
        ridge[n_z:n_z + dg.size] = GREY_RIDGE * float(np.median(dg))
    # a height node cut off by walls from the regularisation and without data (a small roof
    # nobody sees) would be singular: a tiny ridge keeps its start correction
    dzz = (Nd + Nr).diagonal()[:n_z]
    if (dzz <= 0).any() and (dzz > 0).any():
        ridge[:n_z] = np.where(dzz > 0, 0.0, HEIGHT_RIDGE * float(np.median(dzz[dzz > 0])))
    N = (Nd + Nr + sparse.diags(ridge)).tocsr()
    x, k_cg = pcg(N, b, jacobi(N), tol=CG_TOL, max_iter=CG_MAX_ITER, rule=CG_OBJECT_SPACE)
    st.cg_iters.append(k_cg)
    return x, lam, Nd.diagonal()[:n_z] > 0


def _failed(names: List[str], iters: List[int], cg_iters: List[int], message: str
            ) -> WindowResult:
    return WindowResult(np.zeros((1, 1)), np.full((1, 1), np.nan), np.zeros((1, 1), bool),
                        float("nan"), iters, cg_iters, names, False, message)


def _camera_frame(win: ImageWindow, Xs: Array, Ys: Array, zs: Array) -> Array:
    r"""Camera-frame coordinates :math:`p = R^T(X - C)` of the samples, (n, 3).

    Written out element by element: no BLAS (see :func:`noblas`), and several times faster
    than numpy's non-BLAS matmul loop for (n, 3) @ (3, 3).
    """
    R = np.asarray(win.eo.rotation, dtype=float)
    C = np.asarray(win.eo.position, dtype=float)
    dx, dy, dz = Xs - C[0], Ys - C[1], zs - C[2]
    return np.stack([dx * R[0, j] + dy * R[1, j] + dz * R[2, j] for j in range(3)], axis=-1)


def _observe(windows: Sequence[ImageWindow], level: int, Xs: Array, Ys: Array, zs: Array,
             valid: NDArray[np.bool_], delta: float) -> Tuple[Array, Array]:
    r"""Grey values (NaN = not seen) and height coefficients of every sample in every image.

    The coefficient is :math:`\nabla g\cdot\partial(c, r)/\partial Z` in grey values per
    metre, on pyramid level ``level`` (central differences of ±``delta`` m; in the camera
    frame a height change moves the point along :math:`\partial p/\partial Z = R^T e_Z`, the
    third row of R). ``valid`` is (n,) or (images, n): the samples each image may see
    (visibility, see :func:`_visibility`).
    """
    n_img = len(windows)
    g_all = np.full((n_img, zs.size), np.nan)
    k_all = np.zeros((n_img, zs.size))
    scale = 2.0 ** level
    valid = np.broadcast_to(valid, (n_img, zs.size))
    for i, win in enumerate(windows):
        p = _camera_frame(win, Xs, Ys, zs)
        rz = np.asarray(win.eo.rotation, dtype=float)[2]
        c, r = win.camera.camera_to_pixel(p)
        cp, rp = win.camera.camera_to_pixel(p + delta * rz)
        cm, rm = win.camera.camera_to_pixel(p - delta * rz)
        jc = (cp - cm) / (2 * delta) / scale  # level pixels per metre
        jr = (rp - rm) / (2 * delta) / scale
        lc = to_level(c - win.col0, level)
        lr = to_level(r - win.row0, level)
        vals, ok = _sample_stack(win.levels[level], lc, lr)
        ok &= valid[i] & np.isfinite(lc) & np.isfinite(lr)
        g_all[i] = np.where(ok, vals[0], np.nan)
        k_all[i] = np.where(ok, vals[1] * jc + vals[2] * jr, 0.0)
    return g_all, k_all


def _erode_visibility(vis: NDArray[np.bool_], ny: int, nx: int, margin: int
                      ) -> NDArray[np.bool_]:
    """Shrink every image's visible samples (on the ny × nx sample lattice) by ``margin``
    samples: next to an occluding edge or a wall the image pixel mixes both surfaces (pixel
    footprint, pyramid smoothing, the gradient stencil), so those samples are not used."""
    if margin <= 0:
        return vis
    st = ndimage.generate_binary_structure(2, 2)
    out = np.empty_like(vis)
    for i in range(vis.shape[0]):
        bad = ~vis[i].reshape(ny, nx)
        out[i] = ~ndimage.binary_dilation(bad, st, iterations=margin).ravel()
    return out


def _visibility(windows: Sequence[ImageWindow], Xs: Array, Ys: Array, zs: Array,
                surface: Array, x_first: float, y_first: float, spacing: float,
                min_cos: float = MIN_COS) -> NDArray[np.bool_]:
    r"""Samples each image sees on the current surface: not occluded, not grazing, (images, n).

    ``surface`` holds the current heights on the window's cells (a 2.5D DSM: roofs, trees).

    *Occlusion* (seed-004 §5.3 step 4, by ray marching): from the sample :math:`P` towards the
    projection centre :math:`C` the ray rises :math:`1/t` m per metre of horizontal distance,
    :math:`t = |C_{XY} - P_{XY}|/(C_Z - Z_P)`; it is stepped in half cells,
    :math:`s_k = k\,\Delta/2`, while below the highest surface point, and the sample is
    occluded where :math:`Z_{surf}(P_{XY} + s_k u) > Z_P + s_k/t + \Delta/2` (the tolerance of
    half a cell keeps slopes up to 45° below the ray from occluding themselves).

    *Grazing rays and walls*: the surface normal :math:`n \propto (-Z_X, -Z_Y, 1)` from the
    cell gradients; the sample needs :math:`\cos\angle(n, C - P) \ge` ``min_cos``. This drops
    the walls of a 2.5D DSM (its one-cell ramps at buildings have slopes ≫ 1, so cos ≈ 0 for
    every image that does not look at them side-on, and images that look at the façade see
    something the facet model cannot represent either) and steep back-facing slopes.
    """
    ny, nx = surface.shape
    zmax = float(np.max(surface))
    # surface gradient (per metre) at the samples; rows go south
    gr, gc = np.gradient(surface, spacing)
    u0 = (Xs - x_first) / spacing
    v0 = (y_first - Ys) / spacing
    sidx, sw = _bilinear_weights(np.clip(u0, 0, nx - 1), np.clip(v0, 0, ny - 1), nx, ny)
    zx = (gc.ravel()[sidx] * sw).sum(axis=1)
    zy = -(gr.ravel()[sidx] * sw).sum(axis=1)
    norm_n = np.sqrt(1.0 + zx * zx + zy * zy)
    flat = surface.ravel()
    vis = np.zeros((len(windows), zs.size), bool)
    for i, win in enumerate(windows):
        C = np.asarray(win.eo.position, dtype=float)
        dX, dY, dZ = C[0] - Xs, C[1] - Ys, C[2] - zs
        dist = np.sqrt(dX * dX + dY * dY + dZ * dZ)
        cos = (-zx * dX - zy * dY + dZ) / (norm_n * dist)
        ok = cos >= min_cos
        hor = np.sqrt(dX * dX + dY * dY)
        t = hor / np.maximum(dZ, 1e-9)  # horizontal metres per metre of rise
        ux = np.where(hor > 0, dX / np.maximum(hor, 1e-12), 0.0)
        uy = np.where(hor > 0, dY / np.maximum(hor, 1e-12), 0.0)
        # only rays that can meet higher surface points within the window need marching
        act = np.flatnonzero(ok & (t > 1e-6) & (zs + 0.5 * spacing < zmax))
        step = 0.5 * spacing
        k = 1
        while act.size:
            s = k * step
            u = u0[act] + s * ux[act] / spacing
            v = v0[act] - s * uy[act] / spacing
            inside = (u >= 0) & (u <= nx - 1) & (v >= 0) & (v <= ny - 1)
            ray = zs[act] + s / t[act]
            idx, w = _bilinear_weights(np.clip(u, 0, nx - 1), np.clip(v, 0, ny - 1), nx, ny)
            zsurf = (flat[idx] * w).sum(axis=1)
            hit = inside & (zsurf > ray + step)
            ok[act[hit]] = False
            keep = inside & ~hit & (ray < zmax)
            act = act[keep]
            k += 1
        vis[i] = ok
    return vis


def _screen(g_all: Array, k_all: Array, seen: NDArray[np.bool_], h0: Array, h1: Array,
            dz_s: Array, k: float) -> NDArray[np.bool_]:
    r"""Samples whose images disagree grossly after a Gauss–Newton step (gross-error test).

    The radiometrically corrected grey value each image predicts after the step is
    :math:`\hat g_{pi} = h_{1i}(g_{pi} + k_{pi}\,dZ_p) + h_{0i}`; its deviation from the
    sample mean, scaled by :math:`\sqrt{n_p/(n_p-1)}` to the variance of one image, is compared
    with ``k`` times a robust σ (1.4826 · median of all deviations). A sample with any larger
    deviation is left out of the next iteration (and re-tested there): a surface the 2.5D
    facets cannot represent (a wall smeared over several cells of the input DSM, a tree crown),
    a moving object or an image defect. Unlike reweighting (seed-004 §7.4) this only removes
    what no height within the pull-in range can explain, so texture edges stay in.
    """
    n = seen.sum(axis=0)
    test = n >= 2
    ghat = np.where(seen, h1[:, None] * (np.nan_to_num(g_all) + k_all * dz_s[None, :])
                    + h0[:, None], 0.0)
    mean = ghat.sum(axis=0) / np.maximum(n, 1)
    dev = np.where(seen & test[None, :], np.abs(ghat - mean[None, :]), 0.0)
    dev *= np.sqrt(n / np.maximum(n - 1, 1))[None, :]
    vals = dev[seen & test[None, :]]
    if vals.size < 16:
        return np.zeros(n.size, bool)
    scale = 1.4826 * float(np.median(vals))
    return test & (dev.max(axis=0) > k * max(scale, 1e-6))


def _start_grey(g_all: Array, seen: NDArray[np.bool_], use: NDArray[np.bool_], h0: Array,
                h1: Array, oidx: NDArray, ow: Array, noy: int, nox: int) -> Array:
    """Start grey values: the radiometrically adjusted mean of the images, spread to the grey
    nodes by the bilinear weights (nodes without samples take the nearest value)."""
    adj = np.where(seen, h1[:, None] * g_all + h0[:, None], 0.0)
    gmean = adj[:, use].sum(axis=0) / seen[:, use].sum(axis=0)
    wsum = np.bincount(oidx[use].ravel(), ow[use].ravel(), nox * noy)
    gsum = np.bincount(oidx[use].ravel(), (ow[use] * gmean[:, None]).ravel(), nox * noy)
    G = np.where(wsum > 1e-6, gsum / np.maximum(wsum, 1e-12), np.nan)
    return _fill_nearest(G.reshape(noy, nox)).ravel()


def _design(g_all: Array, k_all: Array, mask: NDArray[np.bool_], gidx: NDArray, gw: Array,
            oidx: NDArray, ow: Array, G: Array, h0: Array, h1: Array, ref: int, n_z: int,
            n_grey: int):
    """Sparse design matrix and reduced observations (see the module notes).

    Columns: [dZ (all geometry nodes) | dG (grey nodes with observations) | dh0, dh1 per
    non-reference image]. Returns ``A, obs, cols_g, rad_cols``.
    """
    img_i, samp = np.nonzero(mask)
    n = img_i.size
    g = g_all[img_i, samp]
    k = h1[img_i] * k_all[img_i, samp]
    ob = oidx[samp]
    used_g = np.zeros(n_grey, bool)
    used_g[ob.ravel()] = True
    cols_g = np.full(n_grey, -1, np.intp)
    cols_g[used_g] = n_z + np.arange(int(used_g.sum()))
    n_g = int(used_g.sum())
    rad_cols: Dict[int, Tuple[int, int]] = {}
    nxt = n_z + n_g
    for i in range(g_all.shape[0]):
        if i != ref:
            rad_cols[i] = (nxt, nxt + 1)
            nxt += 2
    rows = np.arange(n)
    r_list = [np.repeat(rows, 4), np.repeat(rows, 4)]
    c_list = [gidx[samp].ravel(), cols_g[ob].ravel()]
    v_list = [(-k[:, None] * gw[samp]).ravel(), ow[samp].ravel()]
    not_ref = img_i != ref
    if not_ref.any():
        rr = rows[not_ref]
        c0 = np.array([rad_cols.get(i, (0, 0))[0] for i in range(g_all.shape[0])])
        r_list += [rr, rr]
        c_list += [c0[img_i[not_ref]], c0[img_i[not_ref]] + 1]
        v_list += [-np.ones(rr.size), -g[not_ref]]
    A = sparse.csr_matrix((np.concatenate(v_list), (np.concatenate(r_list),
                                                     np.concatenate(c_list))),
                          shape=(n, nxt))
    Gp = (G[ob] * ow[samp]).sum(axis=1)
    obs = h1[img_i] * g + h0[img_i] - Gp
    return A, obs, cols_g, rad_cols


def _precision(last: Dict[str, Any]) -> Tuple[Array, float, NDArray[np.bool_]]:
    r"""σ0 and σ_Z per geometry node from the unregularised normal equations (probing).

    The few radiometric unknowns couple with every grey value and height, so they are
    eliminated by a Schur complement instead of entering the sparse LU (they would make its
    factors dense): with :math:`N = [[B, C], [C^T, D]]`, :math:`Y = B^{-1}C`,
    :math:`S = D - C^TY`,

    .. math:: (N^{-1})_{mm} = (B^{-1})_{mm} + (Y S^{-1} Y^T)_{mm}, \qquad
              \hat x_B = B^{-1}(b_B - C\hat x_D),\; \hat x_D = S^{-1}(b_D - Y^Tb_B)
    """
    A, obs, n_z, ny, nx = last["A"], last["l"], last["n_z"], last["ny"], last["nx"]
    n_rad = last["n_rad"]
    N = (A.T @ A).tocsc()
    d = N.diagonal()
    dz_diag = d[:n_z]
    pos = dz_diag[dz_diag > 0]
    observed = dz_diag > (1e-6 * float(np.median(pos)) if pos.size else np.inf)
    n_all = N.shape[0]
    n_b = n_all - n_rad
    # undetermined unknowns (no observation) are removed; a tiny ridge keeps the LU stable
    keep = np.flatnonzero(np.concatenate([observed, d[n_z:n_b] > 0]))
    rad = np.arange(n_b, n_all)
    B = N[keep][:, keep].tocsc()
    B = B + sparse.diags(1e-10 * B.diagonal() + 1e-12, format="csc")
    C = N[keep][:, rad].toarray()
    D = N[rad][:, rad].toarray()
    sigma = np.full(n_z, np.nan)
    try:
        # B is symmetric positive definite: symmetric mode without pivoting and a minimum-
        # degree ordering of B + Bᵀ factorise 4–5× faster than the default (COLAMD, pivoting)
        lu = splu(B, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                  options={"SymmetricMode": True})
    except RuntimeError:  # exactly singular
        return sigma.reshape(ny, nx), float("nan"), observed.reshape(ny, nx)
    rhs = A.T @ obs
    b_b, b_d = rhs[keep], rhs[rad]
    if n_rad:  # dense products by einsum, not BLAS (see :func:`noblas`)
        Y = lu.solve(C)
        S = D - np.einsum("ij,ik->jk", C, Y)
        Sinv = np.linalg.pinv(S)
        x_d = np.einsum("ij,j->i", Sinv, b_d - np.einsum("ij,i->j", Y, b_b))
        x_b = lu.solve(b_b - np.einsum("ij,j->i", C, x_d))
    else:
        x_d = np.zeros(0)
        x_b = lu.solve(b_b)
    vtv = dot_pairwise(obs, obs) - dot_pairwise(b_b, x_b) - dot_pairwise(b_d, x_d)
    n_obs, n_unk = obs.size, keep.size + n_rad
    sigma0 = math.sqrt(max(vtv, 0.0) / max(n_obs - n_unk, 1))
    node = np.flatnonzero(observed)  # the observed nodes come first in ``keep``
    r, c = np.divmod(node, nx)
    colour = (r % PROBE_DISTANCE) * PROBE_DISTANCE + (c % PROBE_DISTANCE)
    E = np.zeros((keep.size, PROBE_DISTANCE ** 2))
    E[np.arange(node.size), colour] = 1.0
    X = lu.solve(E)
    q = X[np.arange(node.size), colour]
    if n_rad:
        Yz = Y[:node.size]
        q = q + np.einsum("ij,jk,ik->i", Yz, Sinv, Yz)
    sigma[node] = sigma0 * np.sqrt(np.maximum(q, 0.0))
    return sigma.reshape(ny, nx), sigma0, observed.reshape(ny, nx)


__all__ = ["MODES", "PROBE_DISTANCE", "ImageWindow", "WindowResult", "adjust_window", "noblas"]
