r"""Points (+ breaklines, exclusion areas, boundaries) → DEM grid.

Points are read with :func:`..project.points_io.read_points` (XYZ text, CSV with a header, or
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

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Dict, List, Optional, Tuple, Union

import numpy as np
from numpy.typing import NDArray
from rasterio.crs import CRS
from rasterio.warp import transform
from shapely.ops import unary_union

from ..errors import InputError
from ..feedback import Feedback, ensure_feedback
from ..project.edits import read_constraints, read_geometries
from ..project.model import Project
from ..project.points_io import PointSet, check_distinct_points, read_points
from ..raster.io import atomic_output, write_raster
from .fe_grid import fe_interpolate
from .gridding import Grid, GridAccumulator, GridResult, finish_grid

#: Fewest distinct point positions a DEM is interpolated from (a plane needs three).
MIN_DISTINCT_POINTS = 3

PathLike = Union[str, Path]
Array = NDArray[Any]


def _crs(value: Any) -> Any:
    """A rasterio CRS from anything it understands (None or "" stay None)."""
    if value is None or value == "":
        return None
    if isinstance(value, CRS):
        return value
    try:
        return CRS.from_user_input(value)
    except Exception as exc:  # rasterio raises CRSError
        raise InputError(f"'{value}' is not a CRS (give e.g. EPSG:25832).") from exc


def _check_options(output: Path, spacing: float, method: str, smoothing: float) -> None:
    """InputError for an output that is no GeoTIFF, a bad spacing, method or smoothing."""
    if output.suffix.lower() not in (".tif", ".tiff"):
        raise InputError(f"The output '{output}' must be a GeoTIFF (.tif).")
    if not spacing or not spacing > 0:
        raise InputError(f"The spacing must be positive, got {spacing}.")
    if method not in ("membrane", "fe"):
        raise InputError(f"Unknown interpolation method '{method}'; use 'membrane' or 'fe'.")
    if method == "fe" and not (smoothing is not None and smoothing > 0):
        raise InputError(f"The smoothing must be positive, got {smoothing}.")


@dataclass
class _Target:
    """The DEM's CRS and the project's edits file (if any)."""

    crs: Any
    edits: Optional[Path]


def _target(pts: PointSet, points: PathLike, crs: Any, project: Optional[PathLike]) -> _Target:
    """The DEM's CRS: ``crs``, else the project's, else the points' (see the module notes)."""
    edits: Optional[Path] = None
    target = _crs(crs)
    if project is not None and str(project) != "":
        prj = Project.load(project)
        if target is None and prj.crs:
            target = _crs(prj.crs)
        edits = Path(prj.edits_path)
    if target is None and pts.crs:
        target = _crs(pts.crs)
    if target is None:
        raise InputError(f"The points of '{Path(points).name}' carry no CRS; give the CRS "
                         "(e.g. --crs EPSG:25832) or a project.")
    return _Target(target, edits)


def _points_xyz(pts: PointSet, target: Any) -> Tuple[Array, Array, Array]:
    """The points' coordinates in the DEM's CRS."""
    pts_crs = _crs(pts.crs) if pts.crs else None
    x, y, z = pts.x, pts.y, pts.z
    if pts_crs is not None and pts_crs != target:
        xs, ys = transform(pts_crs, target, x.tolist(), y.tolist())
        x, y = np.asarray(xs, float), np.asarray(ys, float)
    return x, y, z


@dataclass
class _Constraints:
    """Exclusion areas, boundaries and breaklines in the DEM's CRS."""

    exclusions: List[Any] = field(default_factory=list)
    boundaries: List[Any] = field(default_factory=list)
    breaklines: List[Any] = field(default_factory=list)


def _constraints(target: _Target, breaklines: Optional[PathLike],
                 exclusions: Optional[PathLike], boundary: Optional[PathLike]) -> _Constraints:
    """The project's edits plus the given vector files."""
    out = _Constraints()
    if target.edits is not None and target.edits.is_file():
        out.exclusions, out.boundaries, out.breaklines = read_constraints(target.edits,
                                                                          target.crs)
    if exclusions:
        out.exclusions += read_geometries(exclusions, ("Polygon",), target.crs, skip_keep=True)
    if boundary:
        got = read_geometries(boundary, ("Polygon",), target.crs)
        if not got:
            raise InputError(f"'{Path(boundary).name}' holds no polygon; give the measuring "
                             "area as polygons.")
        out.boundaries += got
    if breaklines:
        out.breaklines += read_geometries(breaklines, ("LineString",), target.crs)
    return out


def _dem_grid(x: Array, y: Array, spacing: float, boundaries: List[Any]) -> Grid:
    """The points' extent (clipped to the boundaries' extent) on cells of ``spacing``."""
    # points on the upper edge still get a cell: pad the upper bounds slightly
    pad = 1e-6 * spacing
    xmin, ymin = float(x.min()), float(y.min())
    xmax, ymax = float(x.max()) + pad, float(y.max()) + pad
    if boundaries:
        bx0, by0, bx1, by1 = unary_union(boundaries).bounds
        xmin, ymin, xmax, ymax = max(xmin, bx0), max(ymin, by0), min(xmax, bx1), min(ymax, by1)
        if not (xmax > xmin and ymax > ymin):
            raise InputError("No point lies within the boundary's extent; check the boundary "
                             "and the CRS of the points.")
    grid = Grid.from_bounds(xmin, ymin, xmax, ymax, spacing)
    if grid.width * grid.height > 2 ** 28:
        raise InputError(f"The DEM would have {grid.width} × {grid.height} cells; give a larger "
                         "spacing.")
    return grid


def _grid_heights(x: Array, y: Array, z: Array, grid: Grid, cons: _Constraints, gap: float,
                  method: str, smoothing: float, robust: bool,
                  feedback: Feedback) -> Tuple[GridResult, int, Dict[str, Any]]:
    """The DEM by finite elements or by median per cell + membrane filling.

    Returns
    -------
    (grid result, points used, finite-element statistics or {})
    """
    if method == "fe":
        zf, fe_info = fe_interpolate(x, y, z, grid, smoothing=float(smoothing),
                                     breaklines=cons.breaklines, exclusions=cons.exclusions,
                                     boundaries=cons.boundaries, max_gap=gap, robust=robust,
                                     feedback=feedback.step(10.0, 90.0))
        count = fe_info["count"]
        return (GridResult(zf, count, np.isfinite(zf) & (count == 0), grid), fe_info["used"],
                fe_info)
    acc = GridAccumulator(grid)
    try:
        acc.add(x, y, z)
        used = acc.points
        zg, count = acc.reduce(feedback.step(10.0, 40.0))
    finally:
        acc.close()
    feedback.progress(45.0)
    res = finish_grid(zg, count, grid, gap, exclusions=cons.exclusions,
                      boundary=cons.boundaries, breaklines=cons.breaklines)
    return res, used, {}


def _write_dem(output: Path, res: GridResult, crs: Any) -> Path:
    """Write the DEM and ``<stem>_count.tif`` (points per cell) together; the count's path."""
    count_path = output.with_name(f"{output.stem}_count.tif")
    counts = np.minimum(res.count, np.iinfo(np.uint16).max).astype(np.uint16)
    with atomic_output(count_path) as tmp_count:
        write_raster(tmp_count, counts, transform=res.grid.transform, crs=crs, nodata=None,
                     overviews=True)
        write_raster(output, res.z.astype(np.float32), transform=res.grid.transform, crs=crs,
                     overviews=True)
    return count_path


def _report(result: Dict[str, Any], fe_info: Dict[str, Any], smoothing: float, robust: bool,
            n_points: int, feedback: Feedback) -> None:
    """Tell the operator what the DEM holds."""
    feedback.info(f"DEM {result['width']} × {result['height']} cells of "
                  f"{result['spacing']:g} m from {result['used']} points: "
                  f"{result['measured']} cells measured, {result['filled']} interpolated, "
                  f"{100.0 * result['coverage']:.1f} % with a height.")
    if fe_info:
        feedback.info(f"Finite elements (smoothing {smoothing:g}): point residuals RMS "
                      f"{fe_info['rms']:.3f} m, σ(MAD) {fe_info['sigma_mad']:.3f} m"
                      + (f", {fe_info['downweighted']} point(s) down-weighted as blunders."
                         if robust else "."))
    if result["used"] < n_points:
        feedback.warning(f"{n_points - result['used']} point(s) lie outside the grid "
                         "(boundary).")


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
    _check_options(output, spacing, method, smoothing)
    pts = read_points(points)
    target = _target(pts, points, crs, project)
    x, y, z = _points_xyz(pts, target.crs)
    feedback.progress(5.0)
    cons = _constraints(target, breaklines, exclusions, boundary)
    ok = np.isfinite(x) & np.isfinite(y) & np.isfinite(z)
    if not ok.any():
        raise InputError(f"'{Path(points).name}' has no point with finite coordinates.")
    check_distinct_points(x[ok], y[ok], Path(points).name, MIN_DISTINCT_POINTS,
                          "an interpolated DEM")
    grid = _dem_grid(x[ok], y[ok], spacing, cons.boundaries)
    gap = float("inf") if max_gap is None else float(max_gap)
    res, used, fe_info = _grid_heights(x[ok], y[ok], z[ok], grid, cons, gap, method, smoothing,
                                       robust, feedback)
    feedback.progress(90.0)
    count_path = _write_dem(output, res, target.crs)
    cells = grid.width * grid.height
    result = {
        "dem": str(output), "count": str(count_path), "points": len(pts), "used": int(used),
        "width": grid.width, "height": grid.height, "spacing": float(spacing), "cells": cells,
        "measured": int((res.count > 0).sum()), "filled": int(res.filled.sum()),
        "coverage": int(np.isfinite(res.z).sum()) / float(cells),
        "breaklines": len(cons.breaklines), "exclusions": len(cons.exclusions),
        "boundaries": len(cons.boundaries), "method": method,
    }
    if fe_info:
        result.update(residual_rms=fe_info["rms"], residual_sigma_mad=fe_info["sigma_mad"],
                      downweighted=fe_info["downweighted"])
    feedback.progress(100.0)
    _report(result, fe_info, smoothing, robust, len(pts), feedback)
    return result


__all__ = ["interpolate_dem"]
