r"""Points (+ breaklines, exclusion areas, boundaries) → DEM grid.

Points are read with :func:`..quality.points.read_points` (XYZ text, CSV with a header, or
3-D points / points with a height field in a GeoPackage, Shapefile, GeoJSON). They are reduced
to one height per cell of side ``spacing`` — the median of the cell's points — and the empty
cells are interpolated by the membrane (Laplace) interpolation of
:mod:`.gridding` (:math:`\sum_{j \in N_4(i)} (z_i - z_j) = 0` per empty cell), which does
not cross breaklines (3-D breakline heights are used on the breakline cells), leaves exclusion
areas and everything outside the boundary polygons NaN, and fills only gaps whose inscribed
diameter is at most ``max_gap`` (default: every gap).

``method="fe"`` instead fits finite elements to all the points (:func:`.fe_grid.fe_interpolate`:
bilinear elements on the cell centres, thin-plate curvature regularisation of weight
``smoothing``, breaklines allow slope and height jumps and give their 3-D heights, optional
robust reweighting), the same masks and gap rule. It uses every point rather than one median per
cell and bends smoothly between sparse points, where the membrane has kinks at the data.

CRS
    The DEM's CRS is ``crs`` if given, else the project's, else the points'. Points and vector
    files that carry another CRS are transformed to it; text points carry none and are taken
    to be in the DEM's CRS. Without any CRS the operator is asked for one.

Grid
    The points' extent (clipped to the boundary polygons' extent when there are any), cell
    corners at multiples of ``spacing`` (:meth:`.gridding.Grid.from_bounds`).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Dict, List, Optional, Union

import numpy as np

from ..errors import InputError
from ..feedback import Feedback, ensure_feedback
from ..project.edits import read_constraints, read_geometries
from ..quality.points import check_distinct_points, read_points
from ..raster.io import atomic_output, write_raster
from .fe_grid import fe_interpolate
from .gridding import Grid, GridAccumulator, GridResult, finish_grid

#: Fewest distinct point positions a DEM is interpolated from (a plane needs three).
MIN_DISTINCT_POINTS = 3

PathLike = Union[str, Path]


def _crs(value: Any) -> Any:
    from rasterio.crs import CRS

    if value is None or value == "":
        return None
    if isinstance(value, CRS):
        return value
    try:
        return CRS.from_user_input(value)
    except Exception as exc:  # rasterio raises CRSError
        raise InputError(f"'{value}' is not a CRS (give e.g. EPSG:25832).") from exc


def interpolate_dem(points: PathLike, output: PathLike, spacing: float,
                    crs: Any = None, project: Optional[PathLike] = None,
                    breaklines: Optional[PathLike] = None,
                    exclusions: Optional[PathLike] = None,
                    boundary: Optional[PathLike] = None, max_gap: Optional[float] = None,
                    method: str = "membrane", smoothing: float = 0.1, robust: bool = False,
                    feedback: Optional[Feedback] = None) -> Dict[str, Any]:
    """Grid points to a DEM that honours breaklines, exclusion areas and boundaries.

    Parameters
    ----------
    points : path
        XYZ text, CSV or vector points.
    output : path
        DEM GeoTIFF (float32, NaN nodata); ``<stem>_count.tif`` (points per cell) beside it.
    spacing : float
        Cell size (m).
    crs : str or CRS, optional
        CRS of the DEM (and of text points); default the project's, else the points'.
    project : path, optional
        Project folder or project.toml: its edits.gpkg gives breaklines, exclusion areas
        (action ≠ keep) and boundaries.
    breaklines, exclusions, boundary : path, optional
        Vector files with (3-D) lines / polygons, in addition to the project's.
    max_gap : float, optional
        Largest gap (inscribed diameter, m) that is interpolated; default every gap.
    method : {"membrane", "fe"}
        Median per cell + membrane gap filling, or finite elements over all points.
    smoothing : float
        ``fe`` only: dimensionless weight of the curvature equations relative to a point
        (see :mod:`.fe_grid`); 0.01–0.1 interpolates, 1–10 smooths noisy points.
    robust : bool
        ``fe`` only: iteratively reweighted fit that ignores blunders.
    feedback : Feedback, optional

    Returns
    -------
    dict
        ``dem, count`` (paths), ``points`` (read), ``used`` (in the grid), ``width, height,
        spacing, cells, measured, filled, coverage``, ``breaklines, exclusions, boundaries``
        (numbers of geometries), ``method``; with ``fe`` also ``residual_rms``,
        ``residual_sigma_mad`` (m) and ``downweighted`` (points).
    """
    feedback = ensure_feedback(feedback)
    output = Path(output)
    if output.suffix.lower() not in (".tif", ".tiff"):
        raise InputError(f"The output '{output}' must be a GeoTIFF (.tif).")
    if not spacing or not spacing > 0:
        raise InputError(f"The spacing must be positive, got {spacing}.")
    if method not in ("membrane", "fe"):
        raise InputError(f"Unknown interpolation method '{method}'; use 'membrane' or 'fe'.")
    if method == "fe" and not (smoothing is not None and smoothing > 0):
        raise InputError(f"The smoothing must be positive, got {smoothing}.")
    pts = read_points(points)
    edits: Optional[Path] = None
    target = _crs(crs)
    if project is not None and str(project) != "":
        from ..project.model import Project

        prj = Project.load(project)
        if target is None and prj.crs:
            target = _crs(prj.crs)
        edits = Path(prj.edits_path)
    pts_crs = _crs(pts.crs) if pts.crs else None
    if target is None:
        target = pts_crs
    if target is None:
        raise InputError(f"The points of '{Path(points).name}' carry no CRS; give the CRS "
                         "(e.g. --crs EPSG:25832) or a project.")
    x, y, z = pts.x, pts.y, pts.z
    if pts_crs is not None and pts_crs != target:
        from rasterio.warp import transform

        xs, ys = transform(pts_crs, target, x.tolist(), y.tolist())
        x, y = np.asarray(xs, float), np.asarray(ys, float)
    feedback.progress(5.0)
    excl: List[Any] = []
    bnds: List[Any] = []
    lines: List[Any] = []
    if edits is not None and edits.is_file():
        excl, bnds, lines = read_constraints(edits, target)
    if exclusions:
        excl += read_geometries(exclusions, ("Polygon",), target, skip_keep=True)
    if boundary:
        got = read_geometries(boundary, ("Polygon",), target)
        if not got:
            raise InputError(f"'{Path(boundary).name}' holds no polygon; give the measuring "
                             "area as polygons.")
        bnds += got
    if breaklines:
        lines += read_geometries(breaklines, ("LineString",), target)
    ok = np.isfinite(x) & np.isfinite(y) & np.isfinite(z)
    if not ok.any():
        raise InputError(f"'{Path(points).name}' has no point with finite coordinates.")
    check_distinct_points(x[ok], y[ok], Path(points).name, MIN_DISTINCT_POINTS,
                          "an interpolated DEM")
    # points on the upper edge still get a cell: pad the upper bounds slightly
    pad = 1e-6 * spacing
    xmin, ymin = float(x[ok].min()), float(y[ok].min())
    xmax, ymax = float(x[ok].max()) + pad, float(y[ok].max()) + pad
    if bnds:
        from shapely.ops import unary_union

        bx0, by0, bx1, by1 = unary_union(bnds).bounds
        xmin, ymin, xmax, ymax = max(xmin, bx0), max(ymin, by0), min(xmax, bx1), min(ymax, by1)
        if not (xmax > xmin and ymax > ymin):
            raise InputError("No point lies within the boundary's extent; check the boundary "
                             "and the CRS of the points.")
    grid = Grid.from_bounds(xmin, ymin, xmax, ymax, spacing)
    if grid.width * grid.height > 2 ** 28:
        raise InputError(f"The DEM would have {grid.width} × {grid.height} cells; give a larger "
                         "spacing.")
    gap = float("inf") if max_gap is None else float(max_gap)
    fe_info: Dict[str, Any] = {}
    if method == "fe":
        zf, fe_info = fe_interpolate(x[ok], y[ok], z[ok], grid, smoothing=float(smoothing),
                                     breaklines=lines, exclusions=excl, boundaries=bnds,
                                     max_gap=gap, robust=robust,
                                     feedback=feedback.step(10.0, 90.0))
        count = fe_info["count"]
        used = fe_info["used"]
        res = GridResult(zf, count, np.isfinite(zf) & (count == 0), grid)
    else:
        acc = GridAccumulator(grid)
        try:
            acc.add(x[ok], y[ok], z[ok])
            used = acc.points
            zg, count = acc.reduce(feedback.step(10.0, 40.0))
        finally:
            acc.close()
        feedback.progress(45.0)
        res = finish_grid(zg, count, grid, gap, exclusions=excl, boundary=bnds,
                          breaklines=lines)
    feedback.progress(90.0)
    count_path = output.with_name(f"{output.stem}_count.tif")
    counts = np.minimum(res.count, np.iinfo(np.uint16).max).astype(np.uint16)
    with atomic_output(count_path) as tmp_count:
        write_raster(tmp_count, counts, transform=grid.transform, crs=target, nodata=None,
                     overviews=True)
        write_raster(output, res.z.astype(np.float32), transform=grid.transform, crs=target,
                     overviews=True)
    cells = grid.width * grid.height
    valid = int(np.isfinite(res.z).sum())
    measured = int((res.count > 0).sum())
    result = {
        "dem": str(output), "count": str(count_path), "points": len(pts), "used": int(used),
        "width": grid.width, "height": grid.height, "spacing": float(spacing), "cells": cells,
        "measured": measured, "filled": int(res.filled.sum()), "coverage": valid / float(cells),
        "breaklines": len(lines), "exclusions": len(excl), "boundaries": len(bnds),
        "method": method,
    }
    if fe_info:
        result.update(residual_rms=fe_info["rms"], residual_sigma_mad=fe_info["sigma_mad"],
                      downweighted=fe_info["downweighted"])
    feedback.progress(100.0)
    feedback.info(f"DEM {grid.width} × {grid.height} cells of {spacing:g} m from {used} points: "
                  f"{measured} cells measured, {result['filled']} interpolated, "
                  f"{100.0 * result['coverage']:.1f} % with a height.")
    if fe_info:
        feedback.info(f"Finite elements (smoothing {smoothing:g}): point residuals RMS "
                      f"{fe_info['rms']:.3f} m, σ(MAD) {fe_info['sigma_mad']:.3f} m"
                      + (f", {fe_info['downweighted']} point(s) down-weighted as blunders."
                         if robust else "."))
    if used < len(pts):
        feedback.warning(f"{len(pts) - used} point(s) lie outside the grid (boundary).")
    return result


__all__ = ["interpolate_dem"]
