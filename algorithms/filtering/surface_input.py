r"""What the DSM → DTM filters work on, the operator's constraints, and what they write.

Input (:func:`read_filter_input`)
    A DSM raster (band 1; nodata → NaN) or points. Points are gridded at a spacing ``s``
    (default: about the mean point spacing, :math:`s \approx \sqrt{A/n}` with ``A`` the area of
    the points' bounding box, rounded to a "nice" value) taking the **lowest** point of every
    cell — a DSM for filtering whose cells prefer the ground — and every point keeps the flat
    index of its cell, so the filter's result can be given back point by point.

Low outliers (:func:`low_outliers`)
    Pits of one or two cells deeper than a threshold below their second lowest neighbour —
    a slope-invariant "net cut" from below, shared by both filters before they start.

Constraints (:func:`read_filter_constraints`)
    From the project's ``edits.gpkg``: exclusion areas with action ``keep`` (the DSM stays the
    DTM there: embankments, dams), ``remove``/``exclude`` (no ground there: bridged), manual
    3-D ground points (hard constraints) and breaklines (no smoothing across; rasterised as
    barrier cells).

Outputs (:func:`write_filter_outputs`)
    In one staged folder (complete or not at all): ``dtm.tif``, ``ndsm.tif`` (DSM − DTM),
    ``mask.tif`` (raster input: uint8 1 = object, 0 = ground, 255 = no data) or ``labels.txt``
    (point input: one label per input point in input order, 0 = ground, 1 = object; a point is
    ground if :math:`|z - z_{DTM}(x, y)| \le t + k\,|\nabla z_{DTM}|\,s` with
    ``t = report["ground_tolerance_m"]``, ``k = report["ground_slope_factor"]`` (default 0), ``s``
    the spacing and :math:`z_{DTM}` bilinear, or if it is the lowest point of a cell the filter
    kept as ground, see :func:`point_labels`), ``report.json`` and
    ``report.html``, and extra rasters such as the difference model of every iteration.
"""

from __future__ import annotations

import html
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

import fiona
import numpy as np
import rasterio
from numpy.typing import NDArray
from rasterio.crs import CRS
from rasterio.warp import transform, transform_geom
from scipy import ndimage
from shapely.geometry import mapping
from shapely.geometry import shape as to_shape

from ..errors import InputError
from ..feedback import Feedback, ensure_feedback
from ..input_errors import reading, warn_input
from ..project.edits import read_layer
from ..project.model import Project
from ..project.points_io import check_distinct_points, import_laspy, laz_check, read_points
from ..quality.names import report_path
from ..quality.report import _CSS, _embed, _table, new_figure, write_json
from ..raster.io import staged_folder, write_raster
from ..raster.sample import bilinear_grid
from ..surface.gridding import Grid, line_barrier, polygon_mask

PathLike = Union[str, Path]
Array = NDArray[Any]

#: File endings read as points (everything else is tried as a raster).
POINT_SUFFIXES = (".xyz", ".txt", ".csv", ".pts", ".asc", ".gpkg", ".shp", ".geojson", ".json",
                  ".las", ".laz")

#: Fewest points (or valid DSM cells) a filter accepts.
MIN_POINTS = 10

#: Default ground tolerance (m) for labelling points against the DTM.
DEFAULT_GROUND_TOLERANCE = 0.5

#: "Nice" grid spacings (m) the default spacing of point input is rounded to.
NICE_SPACINGS = (0.05, 0.1, 0.2, 0.25, 0.5, 0.75, 1.0, 1.5, 2.0, 2.5, 3.0, 4.0, 5.0, 10.0,
                 20.0, 25.0, 50.0, 100.0)


@dataclass
class FilterInput:
    """What a filter works on.

    Attributes
    ----------
    z : ndarray (rows, cols) float32
        DSM grid, NaN = no data (point input: the lowest point per cell).
    grid : Grid
        Transform, width, height and spacing of ``z``.
    crs : rasterio CRS or None
    points : ndarray (n, 3) or None
        x, y, z of point input in input order.
    point_cells : ndarray (n,) int64 or None
        Flat cell index of every point (−1: outside the grid / not finite).
    sigma : ndarray (n,) or None
        σ_z per point (GeoPackage field ``sigma_z``), else None.
    source : str
        ``"raster"`` or ``"points"``.
    path : str
        The file read (for the report).
    """

    z: Array
    grid: Grid
    crs: Any
    points: Optional[Array] = None
    point_cells: Optional[Array] = None
    sigma: Optional[Array] = None
    source: str = "raster"
    path: str = ""


@dataclass
class FilterConstraints:
    """The operator's edits, on the filter grid.

    Attributes
    ----------
    keep : ndarray of bool
        Exclusion areas with action ``keep``: the DSM stays the DTM.
    remove : ndarray of bool
        Exclusion areas with action ``remove``/``exclude`` (or none): no ground, bridged.
    ground_points : ndarray (k, 3)
        Manual 3-D ground points (hard constraints).
    breaklines : list
        Shapely (3-D) LineStrings: no smoothing across them.
    barrier : ndarray of bool
        Cells the breaklines touch.
    barrier_z : ndarray float32
        The breaklines' heights in those cells (NaN for 2-D lines).
    """

    keep: Array
    remove: Array
    ground_points: Array
    breaklines: List[Any] = field(default_factory=list)
    barrier: Optional[Array] = None
    barrier_z: Optional[Array] = None

    @classmethod
    def empty(cls, grid: Grid) -> FilterConstraints:
        """No constraints (no project)."""
        return cls(np.zeros(grid.shape, bool), np.zeros(grid.shape, bool), np.zeros((0, 3)),
                   [], np.zeros(grid.shape, bool), np.full(grid.shape, np.nan, np.float32))


# -- CRS ----------------------------------------------------------------------------------------
def to_crs(crs: Any) -> Any:
    """A rasterio CRS from any user input (None/"" → None).

    Raises
    ------
    InputError
        When the CRS is not understood.
    """
    if crs is None or (isinstance(crs, str) and not crs.strip()):
        return None
    if isinstance(crs, CRS):
        return crs
    try:
        return CRS.from_user_input(crs)
    except Exception as exc:  # rasterio.errors.CRSError and friends
        raise InputError.of("Unknown CRS '{crs}': give an EPSG code (e.g. EPSG:25832), WKT or "
                            "a PROJ string ({error}).", crs=crs, error=exc) from exc


# -- reading ------------------------------------------------------------------------------------
def nice_spacing(value: float) -> float:
    """The "nice" spacing of :data:`NICE_SPACINGS` closest to ``value`` (in log scale)."""
    if not value > 0 or not math.isfinite(value):
        return 1.0
    nice = np.asarray(NICE_SPACINGS)
    return float(nice[np.argmin(np.abs(np.log(nice / value)))])


def _read_raster(path: Path, crs: Any) -> FilterInput:
    try:
        with rasterio.open(path) as src:
            t = src.transform
            if t.b != 0 or t.d != 0 or t.e >= 0:
                raise InputError.of("The DSM '{name}' is rotated or not north-up; warp it to "
                                    "a north-up grid first (e.g. gdalwarp).", name=path.name)
            if not math.isclose(abs(t.a), abs(t.e), rel_tol=1e-6):
                raise InputError.of("The DSM '{name}' has non-square cells ({width:g} × "
                                    "{height:g}); resample it to square cells first.",
                                    name=path.name, width=abs(t.a), height=abs(t.e))
            data = src.read(1, masked=True)
            z = np.ma.filled(data.astype(np.float32), np.nan)
            src_crs = src.crs
            grid = Grid(t, src.width, src.height, float(abs(t.a)))
    except InputError:
        raise
    except Exception as exc:  # rasterio.errors.RasterioIOError and driver errors
        raise InputError.of("Cannot read '{name}' as a DSM raster or a points file: {error}",
                            name=path.name,
                            error=str(exc).splitlines()[0] if str(exc) else exc) from exc
    z[~np.isfinite(z)] = np.nan
    n_valid = int(np.count_nonzero(np.isfinite(z)))
    if n_valid == 0:
        raise InputError.of("The DSM '{name}' holds no height (every cell is nodata); check "
                            "the input.", name=path.name)
    if n_valid < MIN_POINTS:
        raise InputError.of("The DSM '{name}' has only {count} cells with a height; a filter "
                            "needs at least {minimum}.", name=path.name, count=n_valid,
                            minimum=MIN_POINTS)
    given = to_crs(crs)
    return FilterInput(z, grid, given if src_crs is None else src_crs, source="raster",
                       path=str(path))


def _read_las(path: Path) -> Tuple[Array, Any]:
    """x, y, z (n, 3) and the CRS (WKT or None) of a LAS/LAZ file; an InputError naming the
    missing package (laspy) or LAZ backend (lazrs) and the pip command."""
    laspy = import_laspy()
    laz_check(laspy, path)
    try:
        las = laspy.read(str(path))
    except Exception as exc:  # laspy raises its own errors
        raise InputError.of("Cannot read the LAS/LAZ file '{name}': {error}", name=path.name,
                            error=exc) from exc
    xyz = np.column_stack([np.asarray(las.x, float), np.asarray(las.y, float),
                           np.asarray(las.z, float)])
    crs = None
    try:
        parsed = las.header.parse_crs()
        crs = parsed.to_wkt() if parsed is not None else None
    except Exception:  # no or unreadable CRS VLR: the CRS then comes from the operator
        crs = None
    return xyz, crs


def _read_gpkg_sigma(path: Path, n: int) -> Optional[Array]:
    """``sigma_z`` of the first point layer, if it has one and the count matches."""
    try:
        for layer in fiona.listlayers(str(path)):
            with fiona.open(str(path), layer=layer) as src:
                if "Point" not in str(src.schema.get("geometry", "")):
                    continue
                fields = {f.lower(): f for f in src.schema["properties"]}
                name = fields.get("sigma_z") or fields.get("sigma")
                if name is None:
                    return None
                values = []
                for feat in src:
                    if feat["geometry"] is None:
                        continue
                    v = feat["properties"][name]
                    values.append(np.nan if v is None else float(v))
                return np.asarray(values, float) if len(values) == n else None
    except Exception:  # σ is optional: any reading problem means "no σ"
        return None
    return None


def grid_lowest(xyz: Array, spacing: float) -> Tuple[Array, Grid, Array]:
    """The lowest point per cell on a grid covering the points.

    Parameters
    ----------
    xyz : ndarray (n, 3)
    spacing : float
        Cell size (m).

    Returns
    -------
    (z grid float32 NaN-empty, Grid, flat cell index per point (−1 where not finite))
    """
    ok = np.all(np.isfinite(xyz), axis=1)
    x, y, z = xyz[ok, 0], xyz[ok, 1], xyz[ok, 2]
    pad = 1e-6 * spacing  # points on the upper edge still get a cell
    grid = Grid.from_bounds(float(x.min()), float(y.min()), float(x.max()) + pad,
                            float(y.max()) + pad, spacing)
    cells = np.full(len(xyz), -1, np.int64)
    row, col = grid.cell_of(x, y)
    flat = np.where(row >= 0, row * grid.width + col, -1)
    cells[ok] = flat
    zg = np.full(grid.width * grid.height, np.inf)
    inside = flat >= 0
    np.minimum.at(zg, flat[inside], z[inside])  # lowest point wins
    zg[~np.isfinite(zg)] = np.nan
    return zg.reshape(grid.shape).astype(np.float32), grid, cells


def _read_points(path: Path, spacing: Optional[float], crs: Any) -> FilterInput:
    sigma = None
    if path.suffix.lower() in (".las", ".laz"):
        xyz, file_crs = _read_las(path)
    else:
        try:
            pts = read_points(path)
        except InputError:
            raise
        except Exception as exc:  # a binary or garbled file
            raise InputError.of("Cannot read '{name}' as points: {error}", name=path.name,
                                error=exc) from exc
        xyz = np.column_stack([pts.x, pts.y, pts.z])
        file_crs = pts.crs
        if path.suffix.lower() == ".gpkg":
            sigma = _read_gpkg_sigma(path, len(xyz))
    ok = np.all(np.isfinite(xyz), axis=1)
    n = int(ok.sum())
    if n < MIN_POINTS:
        raise InputError.of("'{name}' has only {count} valid point(s); a filter needs at "
                            "least {minimum}.", name=path.name, count=n, minimum=MIN_POINTS)
    n = check_distinct_points(xyz[ok, 0], xyz[ok, 1], path.name, MIN_POINTS, "a filter")
    given = to_crs(crs)
    out_crs = given if given is not None else to_crs(file_crs)
    if out_crs is None:
        warn_input(f"The points of '{path.name}' carry no CRS; the DTM is written without one "
                   "(give the crs parameter or a project).")
    if given is not None and file_crs is not None and to_crs(file_crs) != given:
        xs, ys = transform(to_crs(file_crs), given, xyz[:, 0].tolist(), xyz[:, 1].tolist())
        xyz = np.column_stack([xs, ys, xyz[:, 2]])
    if spacing is None or not spacing > 0:
        x, y = xyz[ok, 0], xyz[ok, 1]
        dx, dy = float(np.ptp(x)), float(np.ptp(y))
        est = math.sqrt(max(dx * dy, 1e-12) / n)  # n: distinct positions
        # the points' bounding box misses half a spacing on every side: one correction step
        est = math.sqrt((dx + est) * (dy + est) / n)
        spacing = nice_spacing(est)
    cells_max = 20000 * 20000
    x, y = xyz[ok, 0], xyz[ok, 1]
    if np.ptp(x) / spacing * np.ptp(y) / spacing > cells_max:
        raise InputError.of("A {spacing:g} m grid over the points of '{name}' would have more "
                            "than 400 million cells; give a larger spacing.",
                            spacing=spacing, name=path.name)
    zg, grid, cells = grid_lowest(xyz, float(spacing))
    return FilterInput(zg, grid, out_crs, points=xyz, point_cells=cells, sigma=sigma,
                       source="points", path=str(path))


def read_filter_input(path: PathLike, spacing: Optional[float] = None, crs: Any = None,
                      feedback: Optional[Feedback] = None) -> FilterInput:
    """Read a DSM raster or points for filtering (see the module notes).

    Parameters
    ----------
    path : path
        GeoTIFF (or any raster GDAL reads), or points: XYZ text / CSV (extra columns ignored),
        GeoPackage points (field ``sigma_z`` kept), LAS/LAZ (needs laspy).
    spacing : float, optional
        Grid spacing for point input (m); default ≈ the mean point spacing.
    crs : optional
        CRS of the input when the file carries none (text points, raster without CRS); points
        with their own CRS are transformed to it.

    Raises
    ------
    InputError
        Missing/unreadable file, an all-nodata DSM, fewer than :data:`MIN_POINTS` points,
        an unknown CRS.
    """
    feedback = ensure_feedback(feedback)
    path = Path(path)
    if not path.is_file():
        raise InputError.of("The filter input '{path}' does not exist or is not a file.",
                            path=path)
    if path.suffix.lower() in POINT_SUFFIXES:
        inp = _read_points(path, spacing, crs)
        feedback.info(f"{len(inp.points)} points gridded at {inp.grid.spacing:g} m "
                      f"({inp.grid.width} × {inp.grid.height} cells, lowest point per cell).")
    else:
        inp = _read_raster(path, crs)
        feedback.info(f"DSM {inp.grid.width} × {inp.grid.height} cells at "
                      f"{inp.grid.spacing:g} m.")
    return inp


# -- constraints --------------------------------------------------------------------------------
def read_filter_constraints(project: Optional[PathLike], grid: Grid,
                            crs: Any = None) -> FilterConstraints:
    """The operator's edits of a project on the filter grid (empty without a project).

    Parameters
    ----------
    project : path, optional
        Project folder or ``project.toml``; its ``edits.gpkg`` is read (a missing file means no
        edits).
    grid : Grid
        The filter grid.
    crs : optional
        CRS of the grid; edits are transformed to it. Default: the project's CRS.

    Raises
    ------
    InputError
        When the grid's CRS is unknown and the project has none either, while there are edits.
    """
    cons = FilterConstraints.empty(grid)
    if project is None or str(project) == "":
        return cons
    prj = Project.load(project)
    edits = Path(prj.edits_path)
    if not edits.is_file():
        return cons
    target = to_crs(crs) if crs is not None else None
    if target is None:
        target = to_crs(prj.crs) if prj.crs else None
    with reading(edits, "GeoPackage"):
        layers = fiona.listlayers(str(edits))
    wanted = [name for name in ("exclusion_areas", "ground_points", "breaklines")
              if name in layers]
    features: Dict[str, List[Tuple[Any, Dict[str, Any]]]] = {}
    src_crs: Dict[str, Any] = {}
    for name in wanted:
        features[name] = read_layer(edits, name)
        with fiona.open(str(edits), layer=name) as src:
            src_crs[name] = to_crs(src.crs_wkt) if src.crs_wkt else None
    if not any(features.values()):
        return cons
    if target is None:
        raise InputError.of("The filter input has no CRS and neither has the project; give the "
                            "CRS of the input (e.g. --crs EPSG:25832) so the edits can be "
                            "placed.")

    def _geoms(name: str) -> List[Tuple[Any, Dict[str, Any]]]:
        out = []
        for geom, props in features.get(name, []):
            s = src_crs.get(name)
            if s is not None and s != target:
                geom = to_shape(transform_geom(s, target, mapping(geom)))
            out.append((geom, props))
        return out

    keep_polys, remove_polys = [], []
    for geom, props in _geoms("exclusion_areas"):
        action = props.get("action") or "remove"  # checked by read_layer
        (keep_polys if action == "keep" else remove_polys).append(geom)
    cons.keep = polygon_mask(keep_polys, grid)
    cons.remove = polygon_mask(remove_polys, grid) & ~cons.keep
    gp = []
    for geom, _ in _geoms("ground_points"):
        for part in getattr(geom, "geoms", [geom]):
            c = part.coords[0]
            if len(c) >= 3 and all(math.isfinite(v) for v in c[:3]):
                gp.append(c[:3])
    cons.ground_points = np.asarray(gp, float).reshape(-1, 3)
    cons.breaklines = [g for g, _ in _geoms("breaklines")]
    cons.barrier, cons.barrier_z = line_barrier(cons.breaklines, grid)
    return cons


# -- checks -------------------------------------------------------------------------------------
def sample_bilinear(z: Array, grid: Grid, x: Array, y: Array) -> Array:
    """Bilinear heights of a grid at world points (cell centres as nodes).

    Outside the hull of cell centres the nearest edge value is used (points on the outer half
    cells); NaN where a used node is NaN (:func:`..raster.sample.bilinear_grid` with
    ``edge="clamp"``, ``nodata="any"``).
    """
    t = grid.transform
    col = (np.asarray(x, float) - t.c) / t.a - 0.5
    row = (np.asarray(y, float) - t.f) / t.e - 0.5
    return bilinear_grid(z, col, row, edge="clamp", nodata="any", order="columns")


def check_ground_points(dtm: Array, grid: Grid, ground_points: Array,
                        tol: float) -> List[Dict[str, Any]]:
    """Manual ground points the DTM disagrees with.

    Δh = DTM − point with the DTM value of the cell holding the point (the cell a filter sets
    to the point's height). Points outside the grid or on NaN cells are listed with
    ``status`` ``outside`` / ``nodata``.

    Returns
    -------
    list of dict
        ``index, x, y, z, dtm, dh, status`` for every point with |Δh| > ``tol`` or no DTM height.
    """
    gp = np.asarray(ground_points, float).reshape(-1, 3)
    out: List[Dict[str, Any]] = []
    if gp.size == 0:
        return out
    row, col = grid.cell_of(gp[:, 0], gp[:, 1])
    inside = row >= 0
    val = np.full(len(gp), np.nan)
    val[inside] = np.asarray(dtm, float)[row[inside], col[inside]]
    dh = val - gp[:, 2]
    for i in range(len(gp)):  # a handful of operator points
        if not inside[i]:
            status = "outside"
        elif not np.isfinite(val[i]):
            status = "nodata"
        elif abs(dh[i]) > tol:
            status = "disagrees"
        else:
            continue
        out.append({"index": i, "x": float(gp[i, 0]), "y": float(gp[i, 1]),
                    "z": float(gp[i, 2]), "dtm": float(val[i]) if np.isfinite(val[i]) else None,
                    "dh": float(dh[i]) if np.isfinite(dh[i]) else None, "status": status})
    return out


def dtm_slope(dtm: Array, spacing: float) -> Array:
    r"""Gradient magnitude :math:`|\nabla z|` (m/m) of a grid by central differences.

    NaN cells give NaN (and so do their neighbours' one-sided differences: no slope is
    invented at data borders; :func:`point_labels` then uses no slope allowance).
    """
    z = np.asarray(dtm, np.float64)
    if min(z.shape) < 2:
        return np.zeros(z.shape)
    gy, gx = np.gradient(z, float(spacing))
    return np.hypot(gx, gy)


def lowest_points(inp: FilterInput) -> Array:
    """Index of the lowest point of every non-empty cell (the point whose height the grid
    holds, :func:`grid_lowest`), in cell order; ties go to the first point in input order.

    Returns
    -------
    ndarray int64
        Point indices, one per non-empty cell (empty for raster input).
    """
    if inp.points is None or inp.point_cells is None:
        return np.zeros(0, np.int64)
    cells = np.asarray(inp.point_cells)
    idx = np.flatnonzero((cells >= 0) & np.isfinite(inp.points[:, 2]))
    order = idx[np.lexsort((idx, inp.points[idx, 2], cells[idx]))]
    first = np.concatenate([[True], cells[order][1:] != cells[order][:-1]])
    return order[first]


def point_labels(inp: FilterInput, dtm: Array, tol: float, slope_factor: float = 0.0,
                 ground: Optional[Array] = None) -> Array:
    r"""0 = ground, 1 = object per input point, against the DTM (bilinear).

    A point is ground if

    .. math:: |z - z_{DTM}(x, y)| \le t + k \cdot |\nabla z_{DTM}(x, y)| \cdot s

    with ``t = tol``, ``k = slope_factor`` and ``s`` the grid spacing: a DTM at cell
    resolution misses the heights between its nodes by up to about slope × spacing on steep
    terrain (break lines, lowest-point gridding, the ±½ cell position of the node), so the
    tolerance grows with the local slope as in SMRF's elevation threshold (Pingel et al.
    2013: ``t + k·slope`` at 1 m cells). ``k = 0`` gives the plain tolerance. Points without
    a DTM height are objects. With the filter's ``ground`` mask, the lowest point of every
    ground cell is ground too: its height is the cell's, which the filter kept as terrain
    (the DTM may pass beside it where it smooths or interpolates across a break of slope),
    so the labels agree with the mask a raster input gets.
    """
    pts = inp.points
    if pts is None:
        raise ValueError("point labels need point input")
    zd = sample_bilinear(dtm, inp.grid, pts[:, 0], pts[:, 1])
    limit = np.full(len(pts), float(tol))
    if slope_factor > 0:
        g = sample_bilinear(dtm_slope(dtm, inp.grid.spacing), inp.grid, pts[:, 0], pts[:, 1])
        limit += float(slope_factor) * np.where(np.isfinite(g), g, 0.0) * inp.grid.spacing
    with np.errstate(invalid="ignore"):
        is_ground = np.isfinite(zd) & np.isfinite(pts[:, 2]) & (np.abs(pts[:, 2] - zd) <= limit)
    if ground is not None:
        low = lowest_points(inp)
        is_ground[low] |= np.asarray(ground, bool).ravel()[inp.point_cells[low]]
    return np.where(is_ground, 0, 1).astype(np.uint8)


def low_outliers(z: Array, depth: float, radius: int = 2, passes: int = 2) -> Array:
    r"""Isolated low blunders of a DSM grid (multipath, mismatches): a "net cut" from below.

    A cell is a low outlier if it lies more than ``depth`` below the **second lowest** of its
    valid neighbours in the :math:`(2r+1)^2` window (the centre excluded):

    .. math:: z_c < z_{(2)}(N_r(c)) - d .

    On any plane — however steep — several neighbours of a cell lie below it (the window is
    symmetric), so :math:`z_{(2)} \le z_c` and nothing is flagged; at the foot of a wall or
    in a valley the lower side supplies such neighbours as well. Only cells with valid
    neighbours on all four sides (above, below, left, right of the centre row/column) are
    judged, so the lowest cell at the border of a steep grid or hole is no pit. Taking the
    second lowest tolerates a second blunder next to the first. The test is repeated
    ``passes`` times (a removed blunder may have hidden its neighbour).

    Returns
    -------
    ndarray of bool
        True at low outliers.
    """
    zz = np.asarray(z, np.float32)
    out = np.zeros(zz.shape, bool)
    if not depth > 0 or zz.size == 0:
        return out
    r = int(radius)
    h, w = zz.shape
    cur = np.where(np.isfinite(zz), zz, np.inf).astype(np.float32)
    for _ in range(max(int(passes), 1)):
        pad = np.pad(cur, r, mode="constant", constant_values=np.inf)
        up = np.zeros((h, w), bool)
        down = np.zeros((h, w), bool)
        left = np.zeros((h, w), bool)
        right = np.zeros((h, w), bool)
        # lowest and second lowest neighbour by a running pair of minima (elementwise, so
        # the same bits on every platform; no sort per cell)
        m1 = np.full((h, w), np.inf, np.float32)
        m2 = np.full((h, w), np.inf, np.float32)
        for dr in range(-r, r + 1):
            for dc in range(-r, r + 1):
                if dr == 0 and dc == 0:
                    continue
                v = pad[r + dr:r + dr + h, r + dc:r + dc + w]
                ok = np.isfinite(v)
                if dr < 0:
                    up |= ok
                elif dr > 0:
                    down |= ok
                if dc < 0:
                    left |= ok
                elif dc > 0:
                    right |= ok
                np.minimum(m2, np.maximum(m1, v), out=m2)
                np.minimum(m1, v, out=m1)
        new = (np.isfinite(cur) & np.isfinite(m2) & up & down & left & right
               & (cur < m2 - np.float32(depth)))
        if not new.any():
            break
        out |= new
        cur[new] = np.inf
    return out


def grey_opening(z: Array, size: int) -> Array:
    r"""Grey-value opening (erosion, then dilation) of a grid with a square window.

    .. math:: (z \circ B)(c) = \max_{c' \in B(c)} \min_{c'' \in B(c')} z(c'')

    with :math:`B` the ``size`` × ``size`` window. The opening removes every peak narrower
    than the window (buildings, trees) and keeps any surface that is monotone along every
    line through the window exactly — a tilted plane, a slope, a terrace — so, unlike the
    plain minimum, it is not biased low on slopes; only ridges and hill tops narrower than the
    window are cut (by about their slope × half the window), and an object on a slope leaves
    a shelf at the ground height of its uphill edge. Beyond the border the grid is
    continued by point reflection (:math:`z(-k) = 2 z(0) - z(k)`), which continues a slope
    (a flat continuation would cut the uphill border strip by slope × half the window). NaN
    cells are ignored as support and stay NaN.

    Parameters
    ----------
    z : ndarray (h, w)
        Heights, NaN = no data.
    size : int
        Side of the window in cells (odd).

    Returns
    -------
    ndarray float32 (h, w)
    """
    zz = np.asarray(z, np.float32)
    h, w = zz.shape
    r = min(int(size) // 2, h - 1, w - 1)
    ext = np.pad(zz, r, mode="reflect", reflect_type="odd") if r > 0 else zz
    ok = np.isfinite(ext)
    ero = ndimage.minimum_filter(np.where(ok, ext, np.inf), size=int(size), mode="nearest")
    # windows without data have no erosion: they must not win the dilation
    ero[~np.isfinite(ero)] = -np.inf
    out = ndimage.maximum_filter(ero, size=int(size), mode="nearest")[r:r + h, r:r + w]
    return np.where(np.isfinite(zz) & np.isfinite(out), out, np.nan).astype(np.float32)


#: Window (m) of :func:`ground_bumps`: low objects narrower than this (bushes, cars, hedges,
#: low vegetation) stand out of the lower envelope of their neighbourhood.
BUMP_WINDOW_M = 5.0


def ground_bumps(z: Array, support: Array, surface: Array, spacing: float, tol: float,
                 slope_factor: float = 0.0, window_m: float = BUMP_WINDOW_M) -> Array:
    r"""Support cells that stand out of their neighbourhood by more than the label tolerance.

    With :math:`o(\cdot)` the grey opening (:func:`grey_opening`) over the support cells with
    a ``window_m`` window and :math:`T` the filter's smooth surface, a cell is a bump if

    .. math:: z - o(z) > t + k \cdot |\nabla T| \cdot s + \bigl(T - o(T)\bigr) + m

    (``t`` = ``tol``, ``k`` = ``slope_factor``, ``s`` the spacing: the tolerance a ground
    point gets, :func:`point_labels`). The opening reproduces planes, slopes and terraces, so
    ground stands at most its cell's share of the slope above it (lowest-point gridding); it
    cuts ridges and hill tops, by as much as it cuts the same shape in the surface, which the
    fourth term allows for; ``m`` is the median of :math:`z - o(z) - (T - o(T))` over the
    support (≥ 0): noise lifts every cell above the opening, by about σ in a matched DSM, and
    that typical lift is no object. What stands out are objects narrower than the window that the
    filters' larger windows and smooth surfaces accept as ground because they are low:
    bushes, cars, low vegetation, the edge cells of buildings. Objects wider than the window
    are the filters' business.

    Parameters
    ----------
    z : ndarray (h, w)
        Heights (NaN = no data).
    support : ndarray of bool (h, w)
        The cells judged (the ground so far); the others are no support of the openings.
    surface : ndarray (h, w)
        The filter's smooth terrain surface so far (NaN where it has none: no allowance for
        the cut there).
    spacing : float
        Cell size (m).
    tol, slope_factor : float
        Label tolerance (m) and its slope factor.
    window_m : float
        Side of the window (m); at least 3 cells.

    Returns
    -------
    ndarray of bool
        True at bumps (a subset of ``support``).
    """
    size = max(3, round(float(window_m) / float(spacing)) | 1)
    zs = np.where(support, np.asarray(z, np.float32), np.nan)
    ts = np.where(support, np.asarray(surface, np.float32), np.nan)
    cut = np.nan_to_num(ts - grey_opening(ts, size))
    slope = np.nan_to_num(dtm_slope(surface, spacing))
    allowance = float(tol) + float(slope_factor) * slope * spacing + cut
    lift = zs - grey_opening(zs, size)
    # noise lifts ground above its own opening (by about σ for a matched DSM): the typical
    # lift is no bump
    typical = (lift - cut)[support & np.isfinite(lift)]
    if typical.size:
        allowance += max(float(np.median(typical)), 0.0)
    with np.errstate(invalid="ignore"):
        return support & (lift > allowance)


# -- outputs ------------------------------------------------------------------------------------
def _iteration_figure(rows: Sequence[Dict[str, Any]]) -> Any:
    fig = new_figure(6.0, 3.2)
    ax = fig.add_subplot(111)
    it = [r.get("iteration", i + 1) for i, r in enumerate(rows)]
    share = [100.0 * float(r.get("eliminated_share", 0.0)) for r in rows]
    total = [100.0 * float(r.get("eliminated_total_share", np.nan)) for r in rows]
    ax.bar(it, share, color="#d9822b", label="eliminated in the iteration")
    if np.isfinite(total).any():
        ax.plot(it, total, "o-", color="#2b6cb0", label="eliminated so far")
    ax.set_xlabel("iteration")
    ax.set_ylabel("share of DSM cells [%]")
    ax.set_xticks(it)
    ax.grid(True, alpha=0.3)
    ax.legend(loc="upper left", fontsize=8)
    fig.tight_layout()
    return fig


#: How the report's parameter table names the parameters whose keys are not self-evident.
PARAMETER_LABELS = {
    "windows_m": "windows w_k [m]",
    "thresholds_m": "thresholds t_k of the preset [m] (before the slope allowance)",
    "thresholds_applied_m": "thresholds applied t_k + slope · w_k / 4 [m]",
    "down_threshold_m": "threshold below the surface d [m] (+ slope · w_k / 4)",
    "slope_pct": "slope allowance [%]",
}


def _elimination_figure(z: Array, ground: Array, max_side: int = 700) -> Any:
    """The DSM in grey with the eliminated cells (not ground) in orange, decimated."""
    step = max(1, math.ceil(max(z.shape) / max_side))
    zs, gs = z[::step, ::step], ground[::step, ::step]
    valid = np.isfinite(zs)
    fig = new_figure(6.0, min(7.0, 6.0 * zs.shape[0] / max(zs.shape[1], 1) + 0.4))
    ax = fig.add_subplot(111)
    if valid.any():
        lo, hi = np.nanpercentile(zs, [1, 99])
        ax.imshow(np.where(valid, zs, np.nan), cmap="Greys_r", vmin=lo, vmax=max(hi, lo + 1e-6),
                  interpolation="nearest")
    ax.imshow(np.ma.masked_where(~(valid & ~gs), np.ones_like(zs)), cmap="autumn", alpha=0.75,
              vmin=0, vmax=2, interpolation="nearest")
    ax.set_xticks([])
    ax.set_yticks([])
    ax.set_title("eliminated cells (orange) over the DSM", fontsize=9)
    fig.tight_layout()
    return fig


def _parameter_rows(params: Dict[str, Any]) -> List[List[str]]:
    def text(v: Any) -> str:
        if isinstance(v, (list, tuple)):
            return ", ".join(f"{x:g}" if isinstance(x, float) else str(x) for x in v)
        return str(v)
    return [[PARAMETER_LABELS.get(str(k), str(k)), text(v)] for k, v in params.items()]


def _html_report(report: Dict[str, Any], title: str, figure: Optional[Any] = None) -> str:
    parts = [f"<h1>{html.escape(title)}</h1>",
             f"<p>Input <b>{html.escape(report_path(str(report.get('input', ''))))}</b> "
             f"({html.escape(str(report.get('source', '')))}), preset "
             f"<b>{html.escape(str(report.get('preset', '')))}</b>.</p>"]
    choice = report.get("preset_choice") or {}
    if choice.get("reason"):
        parts.append(f"<p>Chosen automatically: {html.escape(str(choice['reason']))}.</p>")
    summary = [["cells with a height", str(report.get("cells_valid", ""))],
               ["ground cells", str(report.get("cells_ground", ""))],
               ["eliminated share", f"{100.0 * float(report.get('eliminated_share', 0.0)):.2f} %"],
               ["ground tolerance (labels)", f"{report.get('ground_tolerance_m', '')} m"]]
    if report.get("points") is not None:
        summary += [["points", str(report.get("points"))],
                    ["points labelled ground", str(report.get("points_ground", ""))]]
    parts += ["<h2>Summary</h2>", _table(["", "value"], summary)]
    rows = report.get("iterations") or []
    if rows:
        keys = [k for k in rows[0] if k != "iteration"]
        table_rows = []
        for r in rows:
            cells = [str(r.get("iteration", ""))]
            for k in keys:
                v = r.get(k)
                if isinstance(v, float):
                    cells.append(f"{100 * v:.2f} %" if k.endswith("share") else f"{v:.3g}")
                else:
                    cells.append(str(v))
            table_rows.append(cells)
        parts += ["<h2>Elimination per iteration</h2>",
                  _embed(_iteration_figure(rows), "eliminated share per iteration"),
                  _table(["iteration", *keys], table_rows)]
    if figure is not None:
        parts += ["<h2>Eliminated cells</h2>", _embed(figure, "map of the eliminated cells"),
                  '<p class="note">Drawn at reduced resolution; mask.tif holds every cell '
                  "(0 ground, 1 eliminated).</p>"]
    params = report.get("parameters") or {}
    if params:
        parts += ["<h2>Parameters used</h2>",
                  _table(["parameter", "value"], _parameter_rows(params))]
    cons = report.get("constraints") or {}
    if cons:
        parts += ["<h2>Operator edits</h2>",
                  _table(["edit", "value"], [[str(k), str(v)] for k, v in cons.items()])]
    bad = report.get("ground_points_disagreeing") or []
    parts.append("<h2>Manual ground points the filter disagrees with</h2>")
    if bad:
        parts.append(_table(["#", "x", "y", "z", "filter DTM", "Δh", "status"],
                            [[str(b["index"]), f"{b['x']:.3f}", f"{b['y']:.3f}",
                              f"{b['z']:.3f}", "" if b.get("dtm") is None else f"{b['dtm']:.3f}",
                              "" if b.get("dh") is None else f"{b['dh']:+.3f}", b["status"]]
                             for b in bad]))
        parts.append('<p class="note">Δh = filter surface − point, before the point was imposed '
                     "as a hard constraint; the DTM passes through every point.</p>")
    else:
        parts.append("<p>None.</p>")
    for w in report.get("warnings") or []:
        parts.append(f'<p class="note">⚠ {html.escape(str(w))}</p>')
    return ("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
            f"<title>{html.escape(title)}</title><style>{_CSS}</style></head><body>\n"
            + "\n".join(parts) + "\n</body></html>\n")


def write_filter_outputs(folder: PathLike, inp: FilterInput, dtm: Array, ground: Array,
                         report: Dict[str, Any], *,
                         extra_rasters: Optional[Dict[str, Array]] = None,
                         feedback: Optional[Feedback] = None,
                         title: str = "DSM → DTM filtering", product: str = "filter",
                         replace: bool = False) -> Dict[str, Any]:
    """Write the products of a filter run into ``folder`` (complete or not at all).

    Parameters
    ----------
    folder : path
        Output folder (new or empty; see :func:`~..raster.io.staged_folder`).
    inp : FilterInput
    dtm : ndarray (rows, cols)
        The DTM on ``inp.grid``.
    ground : ndarray of bool (rows, cols)
        Ground cells (raster mask: 0 ground, 1 object, 255 where the DSM has no height).
    report : dict
        The filter's report; ``ground_tolerance_m`` (default 0.5 m) labels the points. Written
        as report.json / report.html with ``labels`` counts added.
    extra_rasters : dict name → grid, optional
        Written as ``<name>.tif`` (e.g. the difference model of every iteration).

    Returns
    -------
    dict
        ``dtm``, ``ndsm``, ``mask`` (raster input) or None, ``labels`` (point input) or None,
        ``report`` (paths in their final place) and ``metrics`` (the report dict).
    """
    feedback = ensure_feedback(feedback)
    folder = Path(folder)
    dtm = np.asarray(dtm, np.float32)
    ground = np.asarray(ground, bool)
    tol = float(report.get("ground_tolerance_m") or DEFAULT_GROUND_TOLERANCE)
    slope_factor = float(report.get("ground_slope_factor") or 0.0)
    report = dict(report)
    report.setdefault("ground_tolerance_m", tol)
    report.setdefault("input", inp.path)
    report.setdefault("source", inp.source)
    labels = None
    if inp.source == "points" and inp.points is not None:
        labels = point_labels(inp, dtm, tol, slope_factor, ground)
        report["points"] = len(labels)
        report["points_ground"] = int(np.count_nonzero(labels == 0))
        report["points_object"] = int(np.count_nonzero(labels == 1))
    out: Dict[str, Any] = {"dtm": None, "labels": None, "mask": None, "ndsm": None,
                           "report": None, "metrics": None}
    crs = inp.crs
    with staged_folder(folder, product=product, replace=replace) as tmp:
        write_raster(tmp / "dtm.tif", dtm, transform=inp.grid.transform, crs=crs,
                     overviews=max(dtm.shape) > 512)
        ndsm = (inp.z - dtm).astype(np.float32)
        write_raster(tmp / "ndsm.tif", ndsm, transform=inp.grid.transform, crs=crs)
        feedback.progress(40.0)
        if inp.source == "raster":
            mask = np.where(ground, 0, 1).astype(np.uint8)
            mask[~np.isfinite(inp.z)] = 255
            write_raster(tmp / "mask.tif", mask, transform=inp.grid.transform, crs=crs,
                         nodata=255)
        if labels is not None:
            (tmp / "labels.txt").write_text("\n".join(map(str, labels.tolist())) + "\n",
                                            encoding="ascii")
        for name, arr in (extra_rasters or {}).items():
            write_raster(tmp / f"{name}.tif", np.asarray(arr, np.float32),
                         transform=inp.grid.transform, crs=crs)
        feedback.progress(70.0)
        write_json(tmp / "report.json", report)
        figure = (_elimination_figure(np.asarray(inp.z), ground)
                  if inp.source == "raster" else None)
        (tmp / "report.html").write_text(_html_report(report, title, figure),
                                         encoding="utf-8")
    out["dtm"] = str(folder / "dtm.tif")
    out["ndsm"] = str(folder / "ndsm.tif")
    out["mask"] = str(folder / "mask.tif") if inp.source == "raster" else None
    out["labels"] = str(folder / "labels.txt") if labels is not None else None
    out["report"] = str(folder / "report.json")
    out["metrics"] = report
    feedback.progress(100.0)
    return out


__all__ = ["BUMP_WINDOW_M", "DEFAULT_GROUND_TOLERANCE", "MIN_POINTS", "FilterConstraints",
           "FilterInput", "check_ground_points", "dtm_slope", "grey_opening", "grid_lowest",
           "ground_bumps", "low_outliers", "lowest_points", "nice_spacing", "point_labels",
           "read_filter_constraints", "read_filter_input", "sample_bilinear", "to_crs",
           "write_filter_outputs"]
