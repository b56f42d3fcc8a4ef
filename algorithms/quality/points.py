r"""Check points (or matched points) against a DEM: residual table and statistics.

The residual of a point is

.. math:: \Delta z_i = z_{DEM}(x_i, y_i) - z_i

(DEM minus point, the sign convention of :func:`.compare.compare_dems`: positive = the DEM is
too high), with :math:`z_{DEM}` interpolated bilinearly between the four surrounding cell
centres (:mod:`..raster.sample`). Points outside the hull of cell centres, or next to a nodata
cell, are listed as ``outside`` / ``nodata`` and left out of the statistics.

The points are read by :func:`..project.points_io.read_points` (XYZ text, CSV with a header,
vector points, LAS / LAZ); vector and LAS points are reprojected to the DEM's CRS when both CRSs
are known. Text files carry no CRS: their coordinates must be in the DEM's CRS.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any, Dict, Optional, Sequence, Tuple, Union

import numpy as np
import rasterio
from numpy.typing import ArrayLike, NDArray
from rasterio.crs import CRS
from rasterio.warp import transform
from rasterio.windows import Window

from ..errors import InputError
from ..feedback import Feedback, ensure_feedback
from ..project.points_io import PointSet, check_distinct_points, read_points
from ..raster.io import atomic_output
from ..raster.sample import bilinear_grid, world_to_grid
from .stats import difference_stats

PathLike = Union[str, Path]

#: Points per block of the DEM read at once when sampling (cells per side).
SAMPLE_BLOCK = 1024


def _to_dem_crs(src: Any, x: NDArray[Any], y: NDArray[Any],
               crs: Any) -> Tuple[NDArray[Any], NDArray[Any]]:
    """Points in ``crs`` → the CRS of the open raster ``src`` (unchanged if either is unknown)."""
    if crs is None or src.crs is None:
        return x, y
    src_crs = crs if isinstance(crs, CRS) else CRS.from_user_input(crs)
    if src_crs == src.crs:
        return x, y
    xs, ys = transform(src_crs, src.crs, np.asarray(x).tolist(), np.asarray(y).tolist())
    return np.asarray(xs, dtype=float), np.asarray(ys, dtype=float)


def sample_dem(dem: PathLike, x: ArrayLike, y: ArrayLike, crs: Any = None,
               block: int = SAMPLE_BLOCK) -> NDArray[np.float64]:
    """Bilinear DEM heights at world points, reading the DEM block by block.

    Parameters
    ----------
    dem : path
        DEM raster (band 1; nodata honoured).
    x, y : array_like, shape (n,)
        Coordinates, in ``crs`` (or in the DEM's CRS when ``crs`` is None).
    crs : str or CRS, optional
        CRS of the points; transformed to the DEM's CRS when both are known.
    block : int
        Cells per side of the DEM blocks read; only blocks holding points are read, so memory
        is bounded by ``block`` whatever the DEM size.

    Returns
    -------
    ndarray, shape (n,)
        Heights; NaN outside the hull of cell centres or next to nodata.
    """
    x = np.asarray(x, dtype=float).ravel()
    y = np.asarray(y, dtype=float).ravel()
    out = np.full(x.shape, np.nan)
    with rasterio.open(dem) as src:
        x, y = _to_dem_crs(src, x, y, crs)
        col, row = world_to_grid(src.transform, x, y)
        ok = np.isfinite(col) & np.isfinite(row) & (col >= 0) & (row >= 0) & \
            (col <= src.width - 1) & (row <= src.height - 1)
        if not ok.any():
            return out
        idx = np.flatnonzero(ok)
        tr = (np.floor(row[idx]).astype(np.int64) // block)
        tc = (np.floor(col[idx]).astype(np.int64) // block)
        key = tr * (src.width // block + 1) + tc
        order = np.argsort(key, kind="stable")
        starts = np.unique(key[order], return_index=True)[1]
        for s, e in zip(starts, [*starts[1:], len(order)]):
            sel = idx[order[s:e]]
            r0 = int(tr[order[s]]) * block
            c0 = int(tc[order[s]]) * block
            h = min(block + 1, src.height - r0)  # +1: the neighbour row/column of the last cell
            w = min(block + 1, src.width - c0)
            data = src.read(1, window=Window(c0, r0, w, h), masked=True)
            arr = np.ma.filled(data.astype(np.float64), np.nan)
            out[sel] = bilinear_grid(arr, col[sel] - c0, row[sel] - r0)
    return out


def _fmt(value: float, digits: str) -> str:
    return "" if not math.isfinite(value) else format(value, digits)


def write_residuals(path: PathLike, points: PointSet, dem_z: NDArray[Any],
                    status: Sequence[str]) -> Path:
    """Residual table ``id,x,y,z,dem_z,dz,status`` (CSV, atomically)."""
    dz = dem_z - points.z
    rows = ["id,x,y,z,dem_z,dz,status"]
    for i, name in enumerate(points.ids):
        safe = name.replace(",", ";").replace("\n", " ")
        rows.append(",".join([safe, _fmt(points.x[i], ".12g"), _fmt(points.y[i], ".12g"),
                              _fmt(points.z[i], ".4f"), _fmt(dem_z[i], ".4f"),
                              _fmt(dz[i], ".4f"), status[i]]))
    with atomic_output(path) as tmp:
        tmp.write_text("\n".join(rows) + "\n", encoding="utf-8")
    return Path(path)


def point_compare(points: PathLike, dem: PathLike, *, residuals_path: PathLike,
                  flying_height: Optional[float] = None,
                  feedback: Optional[Feedback] = None) -> Dict[str, Any]:
    """Compare points with a DEM: residual table and the statistics of Δz = DEM − point.

    Parameters
    ----------
    points : path
        Points file (see the module notes for the formats).
    dem : path
        The DEM to check.
    residuals_path : path
        CSV to write: ``id, x, y, z, dem_z, dz, status`` (status ``ok``, ``outside`` or
        ``nodata``).
    flying_height : float, optional
        Flying height above ground (m) for the statistics in ‰ of H.

    Returns
    -------
    dict
        ``stats`` (:func:`.stats.difference_stats` of the points on the DEM), ``points``
        (number read), ``used``, ``outside``, ``nodata`` (counts), ``outside_ids`` (up to 50),
        ``skipped_rows`` and ``residuals`` (path).

    Raises
    ------
    InputError
        No valid point, or no point on the DEM.
    """
    feedback = ensure_feedback(feedback)
    pts = read_points(points)
    check_distinct_points(pts.x, pts.y, Path(points).name, 1, "a comparison")
    if pts.skipped:
        feedback.warning(f"{pts.skipped} line(s)/feature(s) of '{Path(points).name}' were not "
                         "points with x, y, z and were skipped.")
    dem_z = sample_dem(dem, pts.x, pts.y, crs=pts.crs)
    feedback.progress(60.0)
    # outside the DEM or on nodata? (outside = beyond the hull of cell centres)
    with rasterio.open(dem) as src:
        x, y = _to_dem_crs(src, pts.x, pts.y, pts.crs)
        col, row = world_to_grid(src.transform, x, y)
        inside = (col >= 0) & (row >= 0) & (col <= src.width - 1) & (row <= src.height - 1)
    valid = np.isfinite(dem_z)
    status = np.where(valid, "ok", np.where(inside, "nodata", "outside"))
    n_out = int(np.count_nonzero(status == "outside"))
    n_nodata = int(np.count_nonzero(status == "nodata"))
    if not valid.any():
        raise InputError(
            f"None of the {len(pts)} points of '{Path(points).name}' lies on valid cells of the "
            f"DEM '{Path(dem).name}' ({n_out} outside, {n_nodata} on nodata); check that both "
            "use the same CRS."
        )
    if n_out or n_nodata:
        feedback.warning(f"{n_out} point(s) outside the DEM and {n_nodata} on nodata cells are "
                         "listed in the residual table but not used in the statistics.")
    write_residuals(residuals_path, pts, dem_z, list(status))
    stats = difference_stats(dem_z[valid] - pts.z[valid], flying_height=flying_height)
    outside_ids = [pts.ids[i] for i in np.flatnonzero(status == "outside")[:50]]
    feedback.progress(100.0)
    return {
        "stats": stats,
        "points": len(pts),
        "used": int(valid.sum()),
        "outside": n_out,
        "nodata": n_nodata,
        "outside_ids": outside_ids,
        "skipped_rows": pts.skipped,
        "residuals": str(residuals_path),
    }


__all__ = ["point_compare", "sample_dem", "write_residuals"]
