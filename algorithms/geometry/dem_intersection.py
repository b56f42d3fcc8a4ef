r"""Monoplotting: intersection of image rays with a DEM, robust on steep terrain.

A ray :math:`X(\lambda) = O + \lambda\,d` (unit :math:`d`) meets the DEM surface
:math:`Z = h(X, Y)` (bilinear, :mod:`..raster.sample`) at the smallest :math:`\lambda` with

.. math:: f(\lambda) = O_z + \lambda d_z - h(O_x + \lambda d_x,\; O_y + \lambda d_y) = 0 .

Iterating :math:`Z \to h(X, Y)` (the textbook monoplotting loop) diverges or lands on the wrong
side of a cliff on steep terrain. Instead every ray is *marched*: from where it is at the DEM's
maximum height down to where it is below the minimum height, in steps no longer than
``step_cells`` (default ½) DEM cells horizontally and ``step_cells`` cells vertically. The
**first** step at which :math:`f` changes sign brackets the visible surface point, so a ray that
passes close to a wall or a building is not fooled by the terrain behind it. The bracket is then
refined by regula falsi (Illinois variant, superlinear and never leaving the bracket) to a
bracket shorter than ``tol`` (1 mm by default).

A ray gives NaN where its first non-positive sample is nodata or outside the DEM, i.e. where it
leaves the DEM or meets a hole before it meets the ground, and where it does not point
downwards through the DEM's height range at all.

Everything is vectorised over rays; marching proceeds in blocks of steps for the rays that
are still unresolved, so memory is bounded by ``n_rays × block``.
"""

from __future__ import annotations

from typing import Optional, Tuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..raster.sample import DemSampler
from .camera import Camera
from .orientation import ExteriorOrientation
from .projection import border_rays, pixel_to_ray

Array = NDArray[np.float64]


def intersect_rays_dem(origins: ArrayLike, directions: ArrayLike, dem: DemSampler,
                       step_cells: float = 0.5, tol: float = 1e-3, block: int = 64,
                       max_refine: int = 100, max_samples: int = 2_000_000) -> Array:
    """First intersection of rays with a DEM.

    Parameters
    ----------
    origins : array_like, shape (3,) or (..., 3)
        Ray origins (projection centres), broadcast against ``directions``.
    directions : array_like, shape (..., 3)
        Ray directions (need not be unit vectors).
    dem : DemSampler
        The surface.
    step_cells : float
        Longest marching step in DEM cells, horizontally and vertically.
    tol : float
        Length (m) of the final bracket along the ray; the returned point is within ``tol``
        of the exact intersection with the bilinear surface.
    block : int
        Steps evaluated at once per unresolved ray (fewer when many rays are unresolved).
    max_refine : int
        Cap on regula-falsi iterations.
    max_samples : int
        Samples evaluated per marching pass over all rays (bounds the memory).

    Returns
    -------
    ndarray, shape (..., 3)
        Ground points; NaN where the ray leaves the DEM, meets nodata or misses it.
    """
    d_in = np.asarray(directions, dtype=float)
    o_in = np.asarray(origins, dtype=float)
    shape = np.broadcast_shapes(o_in.shape, d_in.shape)
    d = np.broadcast_to(d_in, shape).reshape(-1, 3)
    o = np.broadcast_to(o_in, shape).reshape(-1, 3)
    with np.errstate(invalid="ignore", divide="ignore"):
        d = d / np.linalg.norm(d, axis=1, keepdims=True)
    n = d.shape[0]
    out = np.full((n, 3), np.nan)
    if n == 0:
        return out.reshape(shape)

    cell = dem.cell_size
    margin = 1e-3 * cell + 1e-6
    z_top, z_bottom = dem.max + margin, dem.min - margin
    dz = d[:, 2]
    dh = np.hypot(d[:, 0], d[:, 1])
    with np.errstate(invalid="ignore", divide="ignore"):
        lam0 = np.where(o[:, 2] > z_top, (z_top - o[:, 2]) / dz, 0.0)
        lam1 = (z_bottom - o[:, 2]) / dz
    usable = np.isfinite(lam0) & np.isfinite(lam1) & (dz < 0) & (lam1 > lam0)
    if not usable.any():
        return out.reshape(shape)
    # per-ray step: at most step_cells cells horizontally and vertically
    with np.errstate(divide="ignore"):
        step = np.minimum(step_cells * cell / np.where(dh > 0, dh, 0.0),
                          step_cells * cell / np.abs(dz))
    idx = np.flatnonzero(usable)
    n_steps = np.ceil((lam1[idx] - lam0[idx]) / step[idx]).astype(np.int64)
    step_i = (lam1[idx] - lam0[idx]) / n_steps  # exact division so the last sample is lam1

    def f(rows: NDArray[np.intp], lam: Array) -> Array:
        """Ray height above the DEM at parameter ``lam`` for rays ``rows`` (broadcast)."""
        oo, dd = o[rows], d[rows]
        if lam.ndim == 2:
            oo, dd = oo[:, None, :], dd[:, None, :]
        p = oo + lam[..., None] * dd
        return p[..., 2] - dem.height(p[..., 0], p[..., 1])

    lo = np.full(idx.size, np.nan)  # bracket: f(lo) > 0 ≥ f(hi)
    hi = np.full(idx.size, np.nan)
    f_lo = np.full(idx.size, np.nan)
    f_hi = np.full(idx.size, np.nan)
    hit = np.zeros(idx.size, dtype=bool)
    active = np.arange(idx.size)
    start = 0
    # the previous sample of every active ray (for the first block: the start point)
    prev_lam = lam0[idx].copy()
    prev_f = f(idx, prev_lam)
    # at z_top the ray is above all terrain; NaN there means it is outside the DEM
    bad_start = ~(prev_f > 0)
    active = active[~bad_start]
    while active.size:
        # fewer steps per pass when many rays are left: memory ~ rays × steps
        nb = int(np.clip(max_samples // active.size, 2, block))
        k = np.arange(start + 1, start + nb + 1)
        lam = lam0[idx[active], None] + k[None, :] * step_i[active, None]
        lam = np.minimum(lam, lam1[idx[active], None])
        vals = f(idx[active], lam)
        stop = ~(vals > 0)  # first sample at or below the surface, or NaN
        any_stop = stop.any(axis=1)
        first = np.argmax(stop, axis=1)
        r = np.flatnonzero(any_stop)
        j = first[r]
        a = active[r]
        v_stop = vals[r, j]
        ok = np.isfinite(v_stop)
        a_ok = a[ok]
        hit[a_ok] = True
        hi[a_ok] = lam[r[ok], j[ok]]
        f_hi[a_ok] = v_stop[ok]
        j_ok = j[ok]
        prev_in_block = j_ok > 0
        lo[a_ok] = np.where(prev_in_block, lam[r[ok], np.maximum(j_ok - 1, 0)], prev_lam[a_ok])
        f_lo[a_ok] = np.where(prev_in_block, vals[r[ok], np.maximum(j_ok - 1, 0)], prev_f[a_ok])
        # rays without a stop in this block continue; remember their last sample
        cont = ~any_stop & (start + nb < n_steps[active])
        prev_lam[active[cont]] = lam[cont, -1]
        prev_f[active[cont]] = vals[cont, -1]
        active = active[cont]
        start += nb

    h = np.flatnonzero(hit)
    lam_hit = _refine(o[idx[h]], d[idx[h]], dem, lo[h], hi[h], f_lo[h], f_hi[h], tol, max_refine)
    out[idx[h]] = o[idx[h]] + lam_hit[:, None] * d[idx[h]]
    return out.reshape(shape)


def _refine(o: Array, d: Array, dem: DemSampler, lo: Array, hi: Array, f_lo: Array,
            f_hi: Array, tol: float, max_iter: int) -> Array:
    """Illinois regula falsi on brackets ``f(lo) > 0 ≥ f(hi)``; returns λ (NaN on nodata)."""
    lo, hi, f_lo, f_hi = lo.copy(), hi.copy(), f_lo.copy(), f_hi.copy()
    result = np.where(f_hi == 0, hi, np.nan)
    active = np.flatnonzero(f_hi != 0)
    side = np.zeros(lo.size, dtype=np.int8)  # which end was kept last time (Illinois)
    for _ in range(max_iter):
        if active.size == 0:
            break
        a = active
        done = (hi[a] - lo[a]) <= tol
        result[a[done]] = hi[a[done]] - (hi[a[done]] - lo[a[done]]) * f_hi[a[done]] / (
            f_hi[a[done]] - f_lo[a[done]])
        a = a[~done]
        if a.size == 0:
            break
        lam = hi[a] - (hi[a] - lo[a]) * f_hi[a] / (f_hi[a] - f_lo[a])
        # keep the new point strictly inside, guarding against a stalled end
        lam = np.clip(lam, lo[a] + 1e-3 * tol, hi[a] - 1e-3 * tol)
        p = o[a] + lam[:, None] * d[a]
        fv = p[:, 2] - dem.height(p[:, 0], p[:, 1])
        nan = ~np.isfinite(fv)
        exact = fv == 0
        result[a[exact]] = lam[exact]
        go = ~(nan | exact)
        a, lam, fv = a[go], lam[go], fv[go]
        above = fv > 0
        # replace the end with the same sign; halve the other end's value if it was kept twice
        al, ah = a[above], a[~above]
        lo[al], f_lo[al] = lam[above], fv[above]
        f_hi[al] = np.where(side[al] == 1, 0.5 * f_hi[al], f_hi[al])
        side[al] = 1
        hi[ah], f_hi[ah] = lam[~above], fv[~above]
        f_lo[ah] = np.where(side[ah] == -1, 0.5 * f_lo[ah], f_lo[ah])
        side[ah] = -1
        active = a
    else:
        result[active] = 0.5 * (lo[active] + hi[active])
    return result


def pixel_to_ground(col: ArrayLike, row: ArrayLike, camera: Camera, eo: ExteriorOrientation,
                    dem: DemSampler, **kwargs: float) -> Array:
    """Monoplot pixels: the first DEM point seen at each (col, row).

    Parameters
    ----------
    col, row : array_like
        Pixel coordinates (broadcast).
    camera, eo :
        Interior and exterior orientation of the image.
    dem : DemSampler
    **kwargs :
        Passed to :func:`intersect_rays_dem` (``step_cells``, ``tol``).

    Returns
    -------
    ndarray, shape (..., 3)
        World points; NaN where the ray leaves the DEM or meets nodata first.
    """
    origin, directions = pixel_to_ray(col, row, camera, eo)
    return intersect_rays_dem(origin, directions, dem, **kwargs)  # type: ignore[arg-type]


def ground_footprint(camera: Camera, eo: ExteriorOrientation, dem: DemSampler,
                     per_edge: int = 16) -> Tuple[Array, Optional[str]]:
    """Ground points of the image border (clockwise from top left), for footprints.

    Returns the (4·per_edge, 3) points and a warning text when some border rays miss the DEM.
    """
    _, origin, directions = border_rays(camera, eo, per_edge)
    pts = intersect_rays_dem(origin, directions, dem)
    missing = int(np.isnan(pts[:, 0]).sum())
    warning = (f"{missing} of {len(pts)} border rays miss the DEM; the footprint is incomplete."
               if missing else None)
    return pts, warning
