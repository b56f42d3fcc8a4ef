r"""Object-space multi-image least-squares matching on a DSM grid (2.5D "facets stereo vision").

Refines a DSM with every image that sees it (2 … N), after Wrobel's FAST Vision as described by
Schlüter (1999) — see ``methods/seed-004.md`` §5 (the minimal 2.5D algorithm, variant I).

Model (per computation window)
    Sample points :math:`p` on a grid of one ground pixel :math:`\Delta s_\ell = GSD\cdot2^\ell`;
    object grey values :math:`G` on a grid of ``grey_px`` pixels, bilinear; heights as the input
    DSM plus a bilinear correction on geometry nodes of ``facet_px`` pixels (aligned with the
    output cells):

    .. math::

       Z_p = Z^{in}_p + \sum_m a_{pm}\,\Delta Z_m, \qquad G_p = \sum_k b_{pk}\,G_k

    With :math:`(c, r)_{pi} = \mathrm{world\_to\_pixel}_i(X_p, Y_p, Z_p)` and the grey value
    :math:`g_{pi}` of image *i* there (bilinear), the radiometric correspondence
    :math:`h_{1i}\,g_{pi} + h_{0i} = G_p` is linearised (Gauss–Newton, unit weights):

    .. math::

       \sum_k b_{pk}\,dG_k - k_{pi}\sum_m a_{pm}\,dZ_m - g_{pi}\,dh_{1i} - dh_{0i}
       = h_{1i}g_{pi} + h_{0i} - G_p + v_{pi},
       \qquad k_{pi} = h_{1i}\,\nabla g_{pi}\cdot\frac{\partial(c, r)_{pi}}{\partial Z}

    (gradients from central differences of the pyramid level, ∂(c, r)/∂Z by central differences
    of the collinearity, in the camera frame; a window of a larger frame is just a camera
    with its principal point far from the window centre). The radiometric datum is fixed on a
    reference image (:math:`h_0 = 0, h_1 = 1`); only samples seen by at least two images give
    equations.

Visibility and gross errors (seed §5.3 step 4, §7.3/7.12)
    A DSM to be refined has buildings and trees, and a DSM from matching has walls smeared
    over several cells. Once per level, on the level's start surface, every image drops the
    samples it cannot see (ray marching against the window's cells) or sees at a grazing
    angle (cos ∠(normal, ray) < :data:`MIN_COS`: walls, steep back slopes), plus a margin of
    :data:`VIS_MARGIN` samples around them (mixed pixels at occluding edges). After every
    Gauss–Newton step a sample whose images still disagree by more than :data:`REJECT_K`
    robust σ is left out for the rest of the level (:func:`_screen`): a surface the 2.5D
    facets cannot represent or a single-image disturbance. Without both, such samples pull
    the heights of the open ground around them and the per-window radiometry (measured on the
    synthetic aerial block: refined RMS 0.30 → 0.63 m instead of → 0.18 m).

Regularisation (curvature minimisation, seed (7.2-5/6))
    For every interior geometry node, with node spacing normalised to 1 and heights in metres,
    pseudo-observations of weight λ:
    :math:`dZ_{i-1} - 2dZ_i + dZ_{i+1} = -(Z^\circ_{i-1} - 2Z^\circ_i + Z^\circ_{i+1})` along
    both axes. ``regularisation_mode="correction"`` (default) uses only :math:`\Delta Z`: it
    keeps the shape of the input DSM (buildings, embankments, ditches), which a refinement
    must not flatten; ``"curvature"`` uses the surface :math:`Z^\circ = Z^{in} + \Delta Z`
    (the thesis's curvature minimisation, λ = 1e4 for 8-bit grey values, for a start from a
    plane) and bends open ground next to every building and breakline.

Solution
    Normal equations :math:`N = A^TA + \lambda R^TR` (+ a ridge of :data:`GREY_RIDGE` of the
    typical grey diagonal on the grey values: a grey node that only the corner of one
    sample's bilinear weights touches is not determinable), solved by conjugate gradients
    with the Jacobi (diagonal) preconditioner (seed Tab. 7-3: as fast as SSOR, no fill-in).
    Increments are clipped to 0.2 geometry spacings and 1 px of parallax. Stop when
    :math:`\max|dZ| < 0.01\,GSD_\ell H/B` over the nodes with image data or σ0 changes by
    less than 0.5 %, at most ``max_iter`` iterations per level (0: the input with its σ).
    Coarse → fine over ``levels`` image-pyramid levels (:func:`.pyramid.build_pyramid` of the
    image windows, their origins on the lattice of the top level), the correction of level
    ℓ+1 prolongated bilinearly as the start of level ℓ.

Precision (seed §2.13, 7.3-11)
    After the finest level the system is rebuilt **without** regularisation (radiometry kept),
    factorised once (sparse LU in symmetric mode, :func:`scipy.sparse.linalg.splu`);
    :math:`\sigma_0^2 =
    (l^Tl - l^TA\hat x)/(n - u)` in grey values and :math:`\sigma_{Z,m} = \sigma_0\sqrt{Q_{mm}}`.
    :math:`Q_{mm}` is estimated by **probing** (Tang & Saad 2012): the geometry nodes are split
    into :math:`d \times d` colour classes (nodes ``d`` apart, d = 5); one solve with the sum of
    the unit vectors of a class gives :math:`Q_{mm} + \sum_j Q_{mj}` over the other class
    members, which are ≥ 5 nodes away, where the correlations have decayed (seed: 0.2–0.35 for
    direct neighbours). So 25 solves instead of one per node; the bias is a small
    overestimate. Output cells get σ interpolated bilinearly from the nodes (the thesis's
    pragmatic, slightly pessimistic choice).

Windows
    The output grid is processed in tiles of ``tile`` cells plus ``overlap`` cells on every side
    (only the tile's core is written). Each window reads only the image windows it needs
    (:func:`..raster.io.open_image` windows) and uses the images whose footprint covers at least
    ``min_cover`` of it. Exclusion areas and cells outside the boundaries of ``edits.gpkg`` are
    NaN. A window whose adjustment diverges is written as NaN and counted as a failure; the run
    goes on.

Not modelled: breaklines in the regularisation, robust reweighting (off in the thesis as well;
the screening above only removes gross errors), walls (the 2.5D limit: their samples are
dropped, the input heights there are kept up to the smooth correction).
"""

from __future__ import annotations

import json
import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np
from numpy.typing import NDArray
from rasterio.enums import ColorInterp
from rasterio.windows import Window
from scipy import ndimage, sparse
from scipy.sparse.linalg import splu

from ..crs_check import check_surface_crs
from ..errors import GeometryError, InputError
from ..feedback import Feedback, ensure_feedback
from ..geometry.orientation import ExteriorOrientation
from ..geometry.projection import world_to_pixel
from ..linalg import CG_OBJECT_SPACE, dot_pairwise, jacobi, pcg
from ..project.edits import read_constraints
from ..project.model import Project
from ..raster.io import gtiff_profile, open_image, staged_folder
from ..raster.sample import bilinear_grid, world_to_grid
from ..surface.gridding import Grid, polygon_mask
from .pyramid import build_pyramid, to_level

PathLike = Union[str, Path]
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
#: Relative residual and iteration limit of the conjugate gradients per Gauss–Newton step.
CG_TOL = 1e-6
CG_MAX_ITER = 2000


# -- small numerical helpers -------------------------------------------------------------------
def _noblas(eo: Any) -> Any:
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


def _fill_nearest(z: NDArray) -> NDArray:
    """NaNs replaced by the nearest finite value (for internal use only)."""
    bad = ~np.isfinite(z)
    if not bad.any() or bad.all():
        return np.where(bad, 0.0, z)
    idx = ndimage.distance_transform_edt(bad, return_distances=False, return_indices=True)
    return z[tuple(idx)]


def _second_difference_rows(ny: int, nx: int) -> sparse.csr_matrix:
    """Rows of the discrete curvature (7.2-5/6) on an ny × nx node grid: [1, −2, 1] X and Y."""
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
    n = c.size
    rows = np.repeat(np.arange(n), 3)
    cols = np.stack([lo, c, hi], axis=1).ravel()
    vals = np.tile([1.0, -2.0, 1.0], n)
    return sparse.csr_matrix((vals, (rows, cols)), shape=(n, ny * nx))


# -- image windows -----------------------------------------------------------------------------
@dataclass
class _ImageWindow:
    """Pyramid of one image window: level → (3, h, w) stack of grey, ∂/∂col, ∂/∂row."""

    name: str
    camera: Any
    eo: Any
    col0: int
    row0: int
    levels: List[NDArray] = field(default_factory=list)


def _read_grey(path: Path, col0: int, row0: int, width: int, height: int) -> NDArray:
    """Grey (mean of the colour bands) of an image window, float32."""
    with open_image(path) as src:
        bands = [i + 1 for i, c in enumerate(src.colorinterp) if c != ColorInterp.alpha]
        bands = (bands or [1])[:3]
        data = src.read(bands, window=Window(col0, row0, width, height)).astype(np.float32)
    return data.mean(axis=0)


def _stack(level_image: NDArray) -> NDArray:
    img = np.asarray(level_image, dtype=np.float32)
    gr, gc = np.gradient(img)
    return np.stack([img, gc, gr]).astype(np.float32)


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
                  spacing: float, stride: int, windows: Sequence[_ImageWindow], gsd: float,
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
    windows : sequence of _ImageWindow
        Image pyramids (``levels`` levels) with cameras and orientations.
    gsd : float
        Ground sample distance of level 0 (m).
    parallax_per_m : float
        Pixels of parallax per metre of height for the widest base, B/(H·GSD).
    levels : int
    max_iter, regularisation, mode, grey_px
        See :func:`refine_object_space`.
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
    for level in range(levels - 1, -1, -1):
        lat = _lattice(win, rows, cols, stride * 2 ** level, level, gsd, grey_px)
        if lat is None:
            continue
        if dz_nodes is None:
            dz = np.zeros((lat.ny, lat.nx))
        else:  # prolongation: bilinear, node spacing halves
            pr, pc = np.mgrid[0:lat.ny, 0:lat.nx]
            dz = _prolong(dz_nodes, pr / 2.0, pc / 2.0)
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
    """Options of :func:`adjust_window` (see :func:`refine_object_space`)."""

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
    images: Sequence[_ImageWindow]
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
    # grey grid
    dgo = grey_px * gsd_l
    nox = math.ceil(ext_x / dgo) + 1
    noy = math.ceil(ext_y / dgo) + 1
    oidx, ow = _bilinear_weights(SU / dgo, SV / dgo, nox, noy)
    return _Lattice(level, st, ny, nx, ns_y, ns_x, win.x_first + SU, win.y_first - SV, z_s,
                    v_s, gidx, gw, oidx, ow, noy, nox, max(gsd_l, 0.05),
                    _second_difference_rows(ny, nx), win.zf[::st, ::st][:ny, :nx])


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
    R = sparse.hstack([lat.reg, sparse.csr_matrix((lat.reg.shape[0], n_unk - n_z))]).tocsr()
    RtR = (R.T @ R).tocsr()
    if lam < 0:  # λ from the share, once per level
        d_data = float(Nd.diagonal()[:n_z].mean())
        d_reg = float(RtR.diagonal()[:n_z].mean())
        lam = opts.regularisation * d_data / max(d_reg, 1e-30) if d_reg > 0 else 0.0
    Nr = lam * RtR
    st.reg_share = float(Nr.diagonal()[:n_z].mean()
                         / max(float(Nd.diagonal()[:n_z].mean()), 1e-30))
    z_node = dz if opts.mode == "correction" else lat.zin_nodes + dz
    b = b - lam * (R.T @ (lat.reg @ z_node.ravel()))
    # determinability (seed-004 §5.3 f): a grey node at the edge of the used samples may
    # carry only a corner of one sample's bilinear weights; a ridge of 1e-3 of the typical
    # grey diagonal keeps it from running away (negligible elsewhere)
    dg = Nd.diagonal()[n_z:n_z + int((cols_g >= 0).sum())]
    ridge = np.zeros(n_unk)
    if dg.size:
        ridge[n_z:n_z + dg.size] = GREY_RIDGE * float(np.median(dg))
    N = (Nd + Nr + sparse.diags(ridge)).tocsr()
    x, k_cg = pcg(N, b, jacobi(N), tol=CG_TOL, max_iter=CG_MAX_ITER, rule=CG_OBJECT_SPACE)
    st.cg_iters.append(k_cg)
    return x, lam, Nd.diagonal()[:n_z] > 0


def _failed(names: List[str], iters: List[int], cg_iters: List[int], message: str
            ) -> WindowResult:
    return WindowResult(np.zeros((1, 1)), np.full((1, 1), np.nan), np.zeros((1, 1), bool),
                        float("nan"), iters, cg_iters, names, False, message)


def _camera_frame(win: _ImageWindow, Xs: Array, Ys: Array, zs: Array) -> Array:
    r"""Camera-frame coordinates :math:`p = R^T(X - C)` of the samples, (n, 3).

    Written out element by element: no BLAS (see :func:`_noblas`), and several times faster
    than numpy's non-BLAS matmul loop for (n, 3) @ (3, 3).
    """
    R = np.asarray(win.eo.rotation, dtype=float)
    C = np.asarray(win.eo.position, dtype=float)
    dx, dy, dz = Xs - C[0], Ys - C[1], zs - C[2]
    return np.stack([dx * R[0, j] + dy * R[1, j] + dz * R[2, j] for j in range(3)], axis=-1)


def _observe(windows: Sequence[_ImageWindow], level: int, Xs: Array, Ys: Array, zs: Array,
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


def _visibility(windows: Sequence[_ImageWindow], Xs: Array, Ys: Array, zs: Array,
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
    if n_rad:  # dense products by einsum, not BLAS (see :func:`_noblas`)
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


# -- the driver ------------------------------------------------------------------------------
def _footprint_cover(cam: Any, eo: Any, X: Array, Y: Array, Z: Array) -> float:
    """Share of the points (X, Y, Z) that project inside the image."""
    c, r = world_to_pixel(np.stack([X, Y, Z], axis=-1), cam, eo)
    ok = (c >= 0) & (c <= cam.width - 1) & (r >= 0) & (r <= cam.height - 1)
    return float(np.mean(ok)) if ok.size else 0.0


def _image_window(cam: Any, eo: Any, X: Array, Y: Array, zlo: float, zhi: float, pad: int,
                  align: int = 1) -> Optional[Tuple[int, int, int, int]]:
    """Level-0 pixel window (col0, row0, width, height) that holds the points, clipped.

    The origin is a multiple of ``align`` (2^(levels−1)), so every pyramid level samples the
    image on the same lattice whichever window a tile reads: neighbouring tiles and windows
    cut from a larger frame at even offsets see identical pyramid pixels.
    """
    cs, rs = [], []
    for z in (zlo, zhi):
        c, r = world_to_pixel(np.stack([X, Y, np.full_like(X, z)], axis=-1), cam, eo)
        cs.append(c)
        rs.append(r)
    c = np.concatenate(cs)
    r = np.concatenate(rs)
    if not (np.isfinite(c).any() and np.isfinite(r).any()):
        return None
    c0 = max((math.floor(np.nanmin(c)) - pad) // align * align, 0)
    c1 = min(math.ceil(np.nanmax(c)) + pad + 1, cam.width)
    r0 = max((math.floor(np.nanmin(r)) - pad) // align * align, 0)
    r1 = min(math.ceil(np.nanmax(r)) + pad + 1, cam.height)
    if c1 - c0 < 8 or r1 - r0 < 8:
        return None
    return c0, r0, c1 - c0, r1 - r0


def refine_object_space(project: Any, dsm: PathLike, output_dir: PathLike, *,
                        spacing: Optional[float] = None, levels: Optional[int] = None,
                        max_iter: int = 8, regularisation: float = 1.0,
                        regularisation_weight: Optional[float] = None,
                        regularisation_mode: str = "correction",
                        images: Optional[Sequence[str]] = None, tile: int = 192,
                        overlap: Optional[int] = None, facet_px: float = 8.0,
                        grey_px: float = 2.0, min_cover: float = 0.1,
                        feedback: Optional[Feedback] = None) -> Dict[str, Any]:
    r"""Refine a DSM by object-space multi-image least-squares matching (module notes).

    Parameters
    ----------
    project : Project or path
        The project (cameras, oriented images, edits.gpkg).
    dsm : path
        The DSM to refine (float, NaN/nodata = no height), in the project CRS.
    output_dir : path
        Output folder (created, or replaced if PhotoDEM wrote it); nothing is left on error.
    spacing : float, optional
        Cell size of the refined DSM (m); default the DSM's. Geometry nodes lie on every
        ``stride``-th cell, ``stride = max(1, round(facet_px·GSD / spacing))``.
    levels : int, optional
        Image-pyramid levels (coarse → fine); default 2 (the input DSM must be within
        ≈ 2 px of parallax on the top level, i.e. ≈ 4 px on level 0). More levels only help
        where the texture survives the reduction.
    max_iter : int
        Gauss–Newton iterations per level at most; 0 returns the input heights (with σ) on
        the refinable cells.
    regularisation : float
        Share of the curvature regularisation on the height diagonal of the normal equations,
        mean diag(λRᵀR) / mean diag(AᵀA) (seed-004 §5.5): λ is set from it on the first
        iteration of every level and window, so it does not depend on the grey-value range,
        texture or image count. 0 = no regularisation.
    regularisation_weight : float, optional
        A fixed λ instead (grey values² per m², node spacing normalised to 1; the thesis used
        1e4 with 8-bit images).
    regularisation_mode : {"correction", "curvature"}
        Penalise only the curvature of the correction to the DSM (default; keeps buildings and
        breaklines of the input) or of the surface itself (thesis, start from a plane).
    images : sequence of str, optional
        Image names to use; default every image whose footprint covers ≥ ``min_cover`` of a
        tile.
    tile : int
        Tile side in output cells (plus ``overlap`` on every side).
    overlap : int, optional
        Overlap in cells on every side; default 3 geometry facets.
    facet_px, grey_px : float
        Geometry and grey facet sizes in image pixels (thesis: 8 and 2).
    min_cover : float
        Share of a tile an image must see to be used there.
    feedback : Feedback, optional
        Progress and cancellation.

    Returns
    -------
    dict
        ``{"dsm", "sigma", "report", "metrics"}``.
    """
    feedback = ensure_feedback(feedback)
    t_start = time.perf_counter()
    _check_options(regularisation_mode, regularisation, regularisation_weight, max_iter)
    if not isinstance(project, Project):
        project = Project.load(project)
    plan = _plan(project, Path(dsm), images, spacing, levels, tile, overlap, facet_px)
    settings = _TileSettings(min_cover, max_iter, regularisation, regularisation_weight,
                             regularisation_mode, grey_px)
    W, H = plan.out_grid.width, plan.out_grid.height
    feedback.info(f"Object-space matching: {len(plan.recs)} images, GSD {plan.gsd:.3f} m, DSM "
                  f"{W}×{H} cells at {plan.spacing:.3f} m, geometry nodes every {plan.stride} "
                  f"cells, {plan.levels} levels, {len(plan.tiles)} tiles.")
    out = Path(output_dir)
    totals = _Totals()
    with staged_folder(out, replace=True, product="refine_object_space") as tmp:
        _write_tiles(plan, settings, tmp, totals, feedback)
        feedback.check()
        seconds = time.perf_counter() - t_start
        metrics = _metrics(plan, totals)
        report = {"dsm": str(plan.dsm), "crs": project.crs, "metrics": metrics,
                  "options": {"max_iter": int(max_iter), "regularisation": regularisation,
                              "regularisation_weight": regularisation_weight,
                              "regularisation_mode": regularisation_mode,
                              "facet_px": facet_px, "grey_px": grey_px, "tile": plan.tile,
                              "overlap": plan.overlap, "min_cover": min_cover,
                              "sigma": "probing of diag(N⁻¹), colour distance "
                                       f"{PROBE_DISTANCE} nodes, without regularisation"},
                  "tiles": totals.tile_reports, "seconds": {"total": seconds}}
        (tmp / "report.json").write_text(json.dumps(report, indent=1), encoding="utf-8")
        feedback.progress(100.0)
    feedback.info(f"Refined {totals.n_refined} cells ({totals.n_nodes} geometry nodes), median "
                  f"σ_Z {metrics['sigma_z_median_m'] or float('nan'):.3f} m, "
                  f"{totals.failures} failed tiles.")
    return {"dsm": str(out / "dsm.tif"), "sigma": str(out / "sigma.tif"),
            "report": str(out / "report.json"), "metrics": metrics}


def _check_options(mode: str, regularisation: float, weight: Optional[float],
                   max_iter: int) -> None:
    """Reject a mode, regularisation or iteration count that cannot be used."""
    if mode not in MODES:
        raise InputError(f"Unknown regularisation mode '{mode}'; use one of "
                         f"{', '.join(MODES)}.")
    if not regularisation >= 0 or (weight is not None and not weight >= 0):
        raise InputError("The regularisation must not be negative.")
    if int(max_iter) < 0:
        raise InputError("max_iter must not be negative (0 = no adjustment, only σ).")


@dataclass(frozen=True)
class _TileSettings:
    """Options of the adjustment of every tile (see :func:`refine_object_space`)."""

    min_cover: float
    max_iter: int
    regularisation: float
    weight: Optional[float]
    mode: str
    grey_px: float


@dataclass
class _Plan:
    """The frame of a refinement: images, grids, lattice and tiles."""

    project: Any
    dsm: Path
    recs: Sequence[Any]
    cams: Dict[str, Any]
    in_grid: Grid
    out_grid: Grid
    nodata: Optional[float]
    spacing: float
    gsd: float
    levels: int
    stride: int  # output cells per geometry node on level 0
    unit: int  # node lattice of the top level, in cells
    tile: int
    overlap: int
    excl: List[Any]
    bounds: List[Any]
    tiles: List[Tuple[int, int]]


@dataclass
class _Totals:
    """What the tiles add up to: their reports, σ of the refined cells, counts."""

    tile_reports: List[Dict[str, Any]] = field(default_factory=list)
    sig_all: List[Array] = field(default_factory=list)
    n_refined: int = 0
    n_nodes: int = 0
    failures: int = 0


def _records(project: Any, dsm: Path, images: Optional[Sequence[str]]) -> List[Any]:
    """The image records to use, after checking that the DSM and the image files exist."""
    if not dsm.is_file():
        raise InputError(f"The DSM '{dsm}' does not exist.")
    recs = project.images if images is None else [project.image(n) for n in images]
    if len(recs) < 2:
        raise InputError("Object-space matching needs at least two images; the project or "
                         "the 'images' list has fewer.")
    for rec in recs:
        p = project.image_path(rec)
        if not p.is_file():
            raise InputError(f"Image file '{p}' of image '{rec.name}' does not exist; fix its "
                             "path in project.toml.")
    return recs


def _dsm_frame(dsm: Path, project: Any) -> Tuple[Grid, Optional[float], Any, Array]:
    """Grid, nodata, bounds and a coarse overview of the heights (≤ 256 cells a side)."""
    with open_image(dsm) as src:
        check_surface_crs(dsm, src.crs, project.crs, "DSM")
        t = src.transform
        if t.b != 0 or t.d != 0 or abs(abs(t.a) - abs(t.e)) > 1e-9 * abs(t.a):
            raise InputError(f"The DSM '{dsm.name}' must be north-up with square cells.")
        in_grid = Grid(t, src.width, src.height, float(abs(t.a)))
        step = max(1, max(src.width, src.height) // 256)
        ov = src.read(1, out_shape=(max(1, src.height // step), max(1, src.width // step)),
                      masked=True).astype(float).filled(np.nan)
        frame = (in_grid, src.nodata, src.bounds, ov)
    if not np.isfinite(ov).any():
        raise InputError(f"The DSM '{dsm.name}' has no heights.")
    return frame


def _plan(project: Any, dsm: Path, images: Optional[Sequence[str]], spacing: Optional[float],
          levels: Optional[int], tile: int, overlap: Optional[int], facet_px: float) -> _Plan:
    """Check the inputs and fix grids, GSD, geometry stride, overlap and tiles."""
    recs = _records(project, dsm, images)
    in_grid, nodata, b, ov = _dsm_frame(dsm, project)
    dsm_spacing = in_grid.spacing
    spacing = dsm_spacing if not spacing else float(spacing)
    if not spacing > 0:
        raise InputError(f"The spacing must be positive, got {spacing}.")
    out_grid = in_grid if spacing == dsm_spacing else Grid.from_bounds(
        b.left, b.bottom, b.right, b.top, spacing)
    z_mean = float(np.nanmean(ov))
    cams = {rec.name: project.camera_of(rec) for rec in recs}
    heights = np.array([rec.eo.position[2] - z_mean for rec in recs])
    if not (heights > 0).all():
        raise GeometryError("Some images are not above the DSM; check the DSM heights and the "
                            "orientations.")
    gsd = float(np.median([cams[r.name].gsd(h) for r, h in zip(recs, heights)]))
    levels = 2 if levels is None else int(levels)
    if levels < 1:
        raise InputError("levels must be at least 1.")
    stride = max(1, round(facet_px * gsd / spacing))
    unit = stride * 2 ** (levels - 1)
    overlap = int(overlap) if overlap is not None else 3 * stride
    tile = max(int(tile), unit)
    excl, bounds = [], []
    if Path(project.edits_path).is_file():
        excl, bounds, _lines = read_constraints(project.edits_path, project.crs or None)
    W, H = out_grid.width, out_grid.height
    tiles = [(r0, c0) for r0 in range(0, H, tile) for c0 in range(0, W, tile)]
    return _Plan(project, dsm, recs, cams, in_grid, out_grid, nodata, spacing, gsd, levels,
                 stride, unit, tile, overlap, excl, bounds, tiles)


def _write_tiles(plan: _Plan, settings: _TileSettings, tmp: Path, totals: _Totals,
                 feedback: Feedback) -> None:
    """Refine tile by tile and write the cores into dsm.tif and sigma.tif of ``tmp``."""
    W, H = plan.out_grid.width, plan.out_grid.height
    profile = gtiff_profile(W, H, 1, "float32", plan.project.crs, nodata=float("nan"),
                            predictor=3, transform=plan.out_grid.transform)
    with open_image(tmp / "dsm.tif", "w", **profile) as dst_z, \
            open_image(tmp / "sigma.tif", "w", **profile) as dst_s, \
            open_image(plan.dsm) as src:
        for t_i, (r0, c0) in enumerate(plan.tiles):
            feedback.progress(100.0 * t_i / len(plan.tiles))
            z_out, s_out, rep = _refine_tile(plan, settings, src, r0, c0, totals, feedback)
            totals.tile_reports.append(rep)
            th, tw = z_out.shape
            dst_z.write(z_out[None], window=Window(c0, r0, tw, th))
            dst_s.write(s_out[None], window=Window(c0, r0, tw, th))


def _window_heights(plan: _Plan, src: Any, wr0: int, wc0: int, nr: int, nc: int,
                    x_first: float, y_first: float) -> Array:
    """Input heights (NaN = none) at the cell centres of a window of the output grid."""
    spacing = plan.spacing
    if plan.out_grid is plan.in_grid:
        z_in = src.read(1, window=Window(wc0, wr0, nc, nr), boundless=True,
                        fill_value=np.nan, masked=True)
        z_in = z_in.astype(float).filled(np.nan)
    else:
        xs = x_first + spacing * np.arange(nc)
        ys = y_first - spacing * np.arange(nr)
        XX, YY = np.meshgrid(xs, ys)
        cc, rr = world_to_grid(src.transform, XX, YY)
        ic0 = max(int(np.floor(cc.min())) - 1, 0)
        ir0 = max(int(np.floor(rr.min())) - 1, 0)
        ic1 = min(int(np.ceil(cc.max())) + 2, src.width)
        ir1 = min(int(np.ceil(rr.max())) + 2, src.height)
        if ic1 > ic0 and ir1 > ir0:
            a = src.read(1, window=Window(ic0, ir0, ic1 - ic0, ir1 - ir0),
                         masked=True).astype(float).filled(np.nan)
            z_in = bilinear_grid(a, cc - ic0, rr - ir0)
        else:
            z_in = np.full((nr, nc), np.nan)
    if plan.nodata is not None and np.isfinite(plan.nodata):
        z_in[z_in == plan.nodata] = np.nan
    return z_in


def _refine_tile(plan: _Plan, settings: _TileSettings, src: Any, r0: int, c0: int,
                 totals: _Totals, feedback: Feedback) -> Tuple[Array, Array, Dict[str, Any]]:
    """Heights and σ of the core of the tile at (r0, c0) (NaN where not refined), and its
    report; adds to ``totals``."""
    W, H = plan.out_grid.width, plan.out_grid.height
    overlap, unit, spacing = plan.overlap, plan.unit, plan.spacing
    th, tw = min(plan.tile, H - r0), min(plan.tile, W - c0)
    # window: core ± overlap, extended so that nodes of every level fit exactly
    wr0, wc0 = r0 - overlap, c0 - overlap
    nr = ((th + 2 * overlap - 1 + unit - 1) // unit) * unit + 1
    nc = ((tw + 2 * overlap - 1 + unit - 1) // unit) * unit + 1
    wgrid = Grid(plan.out_grid.transform * plan.out_grid.transform.translation(wc0, wr0),
                 nc, nr, spacing)
    x_first, y_first = wgrid.transform * (0.5, 0.5)
    z_in = _window_heights(plan, src, wr0, wc0, nr, nc, x_first, y_first)
    valid = np.isfinite(z_in)
    if plan.excl:
        valid &= ~polygon_mask(plan.excl, wgrid)
    if plan.bounds:
        valid &= polygon_mask(plan.bounds, wgrid)
    core = (slice(overlap, overlap + th), slice(overlap, overlap + tw))
    z_out = np.full((th, tw), np.nan, np.float32)
    s_out = np.full((th, tw), np.nan, np.float32)
    rep: Dict[str, Any] = {"tile": [int(r0), int(c0)], "images": [], "iterations": [],
                           "sigma0": None, "failed": False}
    if not valid[core].any():
        return z_out, s_out, rep
    res = _run_tile(plan, z_in, valid, x_first, y_first, settings, feedback)
    rep["images"] = res.images
    rep["iterations"] = res.iterations
    rep["cg_iterations"] = res.cg_iterations
    rep["regularisation_share"] = (round(res.reg_share, 4)
                                   if np.isfinite(res.reg_share) else None)
    rep["rejected_share"] = (round(res.rejected_share, 4)
                             if np.isfinite(res.rejected_share) else None)
    if not res.ok:
        totals.failures += 1
        rep["failed"] = True
        rep["message"] = res.message
        feedback.warning(f"Tile at row {r0}, col {c0}: {res.message}; left empty (NaN).")
        return z_out, s_out, rep
    z_out, s_out = _tile_products(res, z_in, valid, core, plan.stride)
    rep["sigma0"] = round(res.sigma0, 4) if np.isfinite(res.sigma0) else None
    k = np.isfinite(s_out)
    totals.n_refined += int(k.sum())
    totals.sig_all.append(s_out[k].astype(float))
    st = plan.stride
    nodes_core = res.observed[overlap // st:(overlap + th) // st,
                              overlap // st:(overlap + tw) // st]
    totals.n_nodes += int(nodes_core.sum())
    return z_out, s_out, rep


def _tile_products(res: WindowResult, z_in: Array, valid: NDArray[np.bool_],
                   core: Tuple[slice, slice], stride: int) -> Tuple[Array, Array]:
    """Refined heights and σ (float32) of a tile's core from the node results (bilinear)."""
    nr, nc = z_in.shape
    rr_, cc_ = np.mgrid[0:nr, 0:nc]
    coords = [rr_ / stride, cc_ / stride]
    dz = ndimage.map_coordinates(res.dz, coords, order=1, mode="nearest")
    sg = ndimage.map_coordinates(np.nan_to_num(res.sigma, nan=1e9), coords, order=1,
                                 mode="nearest")
    obs = ndimage.map_coordinates(res.observed.astype(float), coords, order=1, mode="nearest")
    good = valid & (obs > 0.5) & (sg < 1e8)
    zr = np.where(good, z_in + dz, np.nan)
    sr = np.where(good, sg, np.nan)
    # σ to 0.1 mm: the sparse LU may differ in the last bits between processes (BLAS
    # builds), which must not show in the product
    return zr[core].astype(np.float32), np.round(sr[core], 4).astype(np.float32)


def _metrics(plan: _Plan, totals: _Totals) -> Dict[str, Any]:
    """The figures of the report (σ0 per tile, σ_Z of the refined cells, counts)."""
    sig = np.concatenate(totals.sig_all) if totals.sig_all else np.zeros(0)
    s0s = [r["sigma0"] for r in totals.tile_reports if r.get("sigma0") is not None]
    return {
        "cells": [plan.out_grid.width, plan.out_grid.height],
        "spacing_m": plan.spacing,
        "gsd_m": plan.gsd,
        "geometry_stride_cells": plan.stride,
        "levels": plan.levels,
        "tiles": len(plan.tiles),
        "refined_cells": totals.n_refined,
        "geometry_nodes": totals.n_nodes,
        "failures": totals.failures,
        "sigma0_grey_mean": float(np.mean(s0s)) if s0s else None,
        "sigma0_grey_median": float(np.median(s0s)) if s0s else None,
        # no mean: nodes on texture-free ground have σ of kilometres (no regularisation
        # in the σ), which would swamp it; the share of such nodes is reported instead
        "sigma_z_median_m": float(np.median(sig)) if sig.size else None,
        "sigma_z_p95_m": float(np.percentile(sig, 95)) if sig.size else None,
        "nodes_sigma_over_1m_pct": (round(100.0 * float(np.mean(sig > 1.0)), 3)
                                    if sig.size else None),
    }


def _run_tile(plan: _Plan, z_in: Array, valid: NDArray[np.bool_], x_first: float,
              y_first: float, settings: _TileSettings, feedback: Feedback) -> WindowResult:
    """Choose the images of a window, read their windows and pyramids, adjust."""
    spacing, gsd, levels = plan.spacing, plan.gsd, plan.levels
    nr, nc = z_in.shape
    zf = z_in[valid]
    zlo, zhi = float(zf.min()), float(zf.max())
    zm = float(np.median(zf))
    # footprint test on a coarse lattice of the window's valid cells
    rr, cc = np.nonzero(valid)
    sel = np.linspace(0, rr.size - 1, min(rr.size, 400)).astype(int)
    X = x_first + cc[sel] * spacing
    Y = y_first - rr[sel] * spacing
    Z = z_in[rr[sel], cc[sel]]
    border = np.array([[0, 0], [0, nc - 1], [nr - 1, 0], [nr - 1, nc - 1]], float)
    BX = x_first + border[:, 1] * spacing
    BY = y_first - border[:, 0] * spacing
    lim = 2.0 ** levels * 8.0
    wins: List[_ImageWindow] = []
    for rec in plan.recs:
        cam = plan.cams[rec.name]
        if _footprint_cover(cam, rec.eo, X, Y, Z) < settings.min_cover:
            continue
        box = _image_window(cam, rec.eo, np.concatenate([BX, X]), np.concatenate([BY, Y]),
                            zlo - 1.0, zhi + 1.0, int(lim), 2 ** (levels - 1))
        if box is None:
            continue
        grey = _read_grey(plan.project.image_path(rec), *box)
        pyr = build_pyramid(grey, levels)
        if len(pyr) < levels:
            continue
        wins.append(_ImageWindow(rec.name, cam, _noblas(rec.eo), box[0], box[1],
                                 [_stack(p) for p in pyr]))
    if len(wins) < 2:
        return WindowResult(np.zeros((1, 1)), np.full((1, 1), np.nan), np.zeros((1, 1), bool),
                            float("nan"), [], [], [w.name for w in wins], False,
                            "fewer than two images see it")
    # widest base over the used images → parallax per metre of height
    P = np.array([w.eo.position for w in wins])
    base = max(float(np.linalg.norm(P[i, :2] - P[j, :2]))
               for i in range(len(wins)) for j in range(i + 1, len(wins)))
    h = float(np.mean(P[:, 2]) - zm)
    parallax_per_m = max(base / h / gsd, 1e-6)
    return adjust_window(z_in, valid, x_first, y_first, spacing, plan.stride, wins, gsd,
                         parallax_per_m, levels, max_iter=settings.max_iter,
                         regularisation=settings.regularisation, weight=settings.weight,
                         mode=settings.mode, grey_px=settings.grey_px, feedback=feedback)


__all__ = ["MODES", "WindowResult", "adjust_window", "refine_object_space"]
