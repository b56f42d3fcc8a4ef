r"""Co-registration of a DEM to a reference DEM after Nuth & Kääb (2011).

A DEM that is horizontally displaced against the reference shows height differences that depend
on slope :math:`\alpha` and aspect :math:`\psi` of the terrain (Nuth & Kääb 2011, eq. 3):

.. math::

   \frac{\Delta h}{\tan\alpha} = a\cos(b - \psi) + c

with :math:`a` the length and :math:`b` the direction of the displacement and :math:`c` a
bias term. Writing :math:`\mathbf{u} = \nabla h_{ref} / |\nabla h_{ref}|` (unit uphill direction,
:math:`\mathbf{u} = -(\sin\psi, \cos\psi)`), the same model is linear in the shift:

.. math::

   \frac{\Delta h}{\tan\alpha} = u_x\,d_x + u_y\,d_y + c

(first-order Taylor expansion of
:math:`h_{DEM}(\mathbf{p}) = h_{ref}(\mathbf{p} + \mathbf{d}) - d_z`).
Each iteration samples the DEM at the shifted positions (bilinear), removes the median height
difference, fits :math:`(d_x, d_y, c)` by least squares on the cells with slope ≥
``min_slope_deg`` after rejecting outliers beyond 3 NMAD (twice), and adds the increment; it stops
when the increment is below ``tol`` or after ``max_iter``. The vertical shift is the median
height difference after the final horizontal shift, on all stable cells.

Sign convention
---------------
``(dx, dy, dz)`` is the shift to **add** to the DEM's coordinates and heights so that it matches
the reference: the corrected DEM is :math:`h'(x + d_x, y + d_y) = h(x, y) + d_z`
(:func:`apply_shift` moves the geotransform by ``(dx, dy)`` and adds ``dz``). This is the
convention of the translation that xDEM's ``NuthKaab`` applies to the to-be-aligned DEM
(its affine matrix / ``shift_x, shift_y, shift_z``). x is easting, y northing, in the units of
the CRS (metres).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any, Dict, Optional, Tuple

import numpy as np
from affine import Affine
from numpy.typing import ArrayLike, NDArray
from scipy import ndimage

from ..errors import InputError


@dataclass
class CoregResult:
    """Result of :func:`nuth_kaab` (see the module text for the sign convention).

    Attributes
    ----------
    dx, dy, dz : float
        Shift to add to the DEM's easting, northing and heights (CRS units).
    iterations : int
        Iterations run.
    residual_nmad : float or None
        NMAD of the height differences on the stable cells after applying the shift.
    converged : bool
        The last horizontal increment was below the tolerance.
    cells : int
        Stable cells with a usable slope that entered the last fit.
    """

    dx: float
    dy: float
    dz: float
    iterations: int
    residual_nmad: Optional[float]
    converged: bool
    cells: int = 0

    def to_dict(self) -> Dict[str, Any]:
        return asdict(self)


def apply_shift(dem_array: ArrayLike, transform: Affine, dx: float, dy: float,
                dz: float) -> Tuple[NDArray[Any], Affine]:
    """Apply a co-registration shift without resampling.

    Returns ``(dem_array + dz, Affine.translation(dx, dy) * transform)``: the same cells, moved
    by ``(dx, dy)`` and raised by ``dz`` (NaN stays NaN).
    """
    return np.asarray(dem_array) + dz, Affine.translation(dx, dy) * transform


def _nmad(x: NDArray[np.float64]) -> float:
    med = np.median(x)
    return float(1.4826 * np.median(np.abs(x - med)))


def nuth_kaab(
    dem: ArrayLike,
    reference: ArrayLike,
    transform: Affine,
    stable: Optional[ArrayLike] = None,
    max_iter: int = 20,
    tol: float = 0.01,
    min_slope_deg: float = 3.0,
    max_slope_deg: float = 75.0,
    max_cells: int = 4_000_000,
) -> CoregResult:
    """Estimate the shift of ``dem`` against ``reference`` on a common grid (Nuth & Kääb 2011).

    Parameters
    ----------
    dem, reference : (rows, cols) array_like
        Heights on the same grid, NaN = no data.
    transform : Affine
        Geotransform of that grid (north-up, no rotation).
    stable : (rows, cols) array_like of bool, optional
        True on stable terrain (the only cells used); default all cells.
    max_iter : int
        Maximum iterations.
    tol : float
        Stop when the horizontal increment is below this (CRS units, default 1 cm).
    min_slope_deg, max_slope_deg : float
        Cells flatter than this carry no horizontal information (Δh/tan α explodes); steeper
        ones are mostly edges and blunders. Both are left out of the horizontal fit.
    max_cells : int
        Larger grids are decimated by taking every k-th row and column (the shift has three
        parameters; it needs no more cells). Give a grid averaged to a coarser resolution
        instead if the DEM is rough at the cell scale.

    Returns
    -------
    CoregResult

    Raises
    ------
    InputError
        Too few stable cells with slope to estimate a shift.
    """
    z = np.asarray(dem, dtype=np.float64)
    ref = np.asarray(reference, dtype=np.float64)
    if z.shape != ref.shape or z.ndim != 2:
        raise ValueError("dem and reference must be 2-D arrays of the same shape")
    if transform.b != 0 or transform.d != 0:
        raise ValueError("co-registration needs a north-up grid (no rotation terms)")
    mask = np.ones(z.shape, bool) if stable is None else np.asarray(stable, dtype=bool)
    if z.size > max_cells:
        k = math.ceil(math.sqrt(z.size / max_cells))
        z, ref, mask = z[::k, ::k], ref[::k, ::k], mask[::k, ::k]
        transform = transform * Affine.scale(k)
    res_x, res_y = transform.a, transform.e  # res_y < 0 for north-up grids
    grow, gcol = np.gradient(ref)
    gx = gcol / res_x  # ∂h/∂easting
    gy = grow / res_y  # ∂h/∂northing
    tan = np.hypot(gx, gy)
    base = mask & np.isfinite(ref)
    use = base & np.isfinite(tan) & (tan >= math.tan(math.radians(min_slope_deg))) \
        & (tan <= math.tan(math.radians(max_slope_deg)))
    if np.count_nonzero(use) < 100:
        raise InputError(
            "Too few stable cells with slope (at least 100 are needed) to co-register the DEMs; "
            "give a larger stable area or compare without co-registration."
        )
    r_all, c_all = np.nonzero(base)
    ref_all = ref[base]
    sel = use[base]  # which of the stable cells enter the horizontal fit
    ux, uy, tv = gx[use] / tan[use], gy[use] / tan[use], tan[use]
    del grow, gcol, gx, gy, tan

    def sample(dx: float, dy: float) -> NDArray[np.float64]:
        # corrected DEM at p is the original DEM at p − d (bilinear; NaN where a neighbour is NaN)
        rows = r_all - dy / res_y
        cols = c_all - dx / res_x
        return ndimage.map_coordinates(z, [rows, cols], order=1, mode="constant",
                                       cval=np.nan, prefilter=False)

    dx = dy = 0.0
    converged = False
    it = 0
    n_fit = 0
    for it in range(1, max_iter + 1):  # noqa: B007 — `it` is reported
        dh = sample(dx, dy) - ref_all
        dhs = dh[sel]
        ok = np.isfinite(dhs)
        if np.count_nonzero(ok) < 100:
            raise InputError("The DEMs overlap on too few stable cells after shifting; "
                             "co-registration failed (shift too large or stable area too small).")
        dhs = dhs - np.median(dhs[ok])
        y = dhs / tv
        A = np.column_stack([ux, uy, np.ones_like(ux)])
        keep = ok.copy()
        coef = np.zeros(3)
        for _ in range(3):  # least squares, then twice again without the 3-NMAD outliers
            coef, *_ = np.linalg.lstsq(A[keep], y[keep], rcond=None)
            resid = y - A @ coef
            r_ok = resid[ok]
            scale = _nmad(r_ok)
            keep = ok & (np.abs(resid - np.median(r_ok)) <= 3.0 * max(scale, 1e-9))
        n_fit = int(np.count_nonzero(keep))
        ddx, ddy = float(coef[0]), float(coef[1])
        dx += ddx
        dy += ddy
        if math.hypot(ddx, ddy) < tol:
            converged = True
            break
    dh = sample(dx, dy) - ref_all
    dh = dh[np.isfinite(dh)]
    dz = -float(np.median(dh))
    return CoregResult(dx=dx, dy=dy, dz=dz, iterations=it, residual_nmad=_nmad(dh + dz),
                       converged=converged, cells=n_fit)
