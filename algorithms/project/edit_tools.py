"""What the editing tools need beneath the map: heights from a surface, crossing checks, snapping.

The QGIS map tools and the standalone tool only translate clicks and layers; every answer comes
from here, so both faces behave the same:

* :func:`sample_height` — the bilinear height of a DSM/DTM at a map point (start points, ground
  and check points); the point may be in another CRS than the surface and is reprojected.
* :func:`drape_line` — Z per vertex of a line from a surface, or linear in the 2-D length
  between two typed end heights (breaklines).
* :func:`snap_to_lines` — a seamline point snapped to the mosaic's seamlines.

The checks of an edit while it is drawn (crossings, polygon repair, one edit's values, the
stereo models at a point) are in :mod:`.edit_checks`.

Heights are read through a small window around the points (never the whole raster) and
interpolated with the one bilinear sampler, :func:`..raster.sample.bilinear_grid`. Inside the
raster but in its outer half cells (outside the hull of cell centres) the edge values are taken
(``edge="clamp"``): a click on the visible raster always gets a height. Outside the raster, or
next to nodata, the answer says so instead of raising, so that the tool can ask for a typed
height.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, List, Optional, Sequence, Tuple, Union

import numpy as np
import pyproj
import rasterio
from numpy.typing import NDArray
from rasterio.windows import Window
from shapely.geometry import LineString, MultiLineString, Point
from shapely.ops import nearest_points

from ..crs_check import crs_label, same_horizontal_crs
from ..errors import InputError
from ..input_errors import reading
from ..raster.sample import bilinear_grid, world_to_grid
from .edits import read_geometries

PathLike = Union[str, Path]
XY = Tuple[float, float]

#: Why a point has no height (:attr:`HeightSample.cause`).
OUTSIDE = "outside"
NODATA = "nodata"


@dataclass
class HeightSample:
    """The answer of :func:`sample_height`.

    Attributes
    ----------
    z : float or None
        The bilinear height (m), ``None`` when there is none.
    reason : str or None
        ``None`` with a height; else a sentence for the operator (outside the surface, nodata).
    cause : str or None
        :data:`OUTSIDE` or :data:`NODATA` when there is no height.
    """

    z: Optional[float]
    reason: Optional[str] = None
    cause: Optional[str] = None

    @property
    def ok(self) -> bool:
        return self.z is not None


@dataclass
class DrapedLine:
    """The answer of :func:`drape_line`.

    Attributes
    ----------
    coords : list of (x, y, z)
        The vertices with their heights (NaN where the surface gives none), x and y as given.
    missing : list of int
        Indices of the vertices without a height (outside the surface or on nodata).
    reason : str or None
        A sentence for the operator when vertices are missing.
    """

    coords: List[Tuple[float, float, float]]
    missing: List[int] = field(default_factory=list)
    reason: Optional[str] = None

    @property
    def ok(self) -> bool:
        return not self.missing

    def line(self) -> LineString:
        """The 3-D line (NaN heights where :attr:`missing`)."""
        return LineString(self.coords)


# -- heights from a surface ------------------------------------------------------------------------
def _surface_path(surface: PathLike) -> Path:
    path = Path(surface)
    if not path.is_file():
        raise InputError.of("Surface '{path}' not found; choose a DSM or DTM of the project.",
                            path=path)
    return path


def _to_surface_crs(path: Path, surface_crs: Any, x: NDArray, y: NDArray,
                    crs: Any) -> Tuple[NDArray, NDArray]:
    """Points in the surface's CRS: reprojected when ``crs`` is another CRS.

    Raises
    ------
    InputError
        When the points have a CRS and the surface has none.
    """
    if crs is None or same_horizontal_crs(crs, surface_crs or crs):
        if crs is not None and surface_crs is None:
            raise InputError.of("Surface '{name}' has no CRS, so a point in {crs} cannot be "
                                "placed on it; assign the surface its CRS first.",
                                name=path.name, crs=crs_label(crs))
        return x, y
    try:
        tf = pyproj.Transformer.from_crs(pyproj.CRS.from_user_input(crs),
                                         pyproj.CRS.from_user_input(surface_crs.to_wkt()),
                                         always_xy=True)
    except pyproj.exceptions.CRSError as exc:
        raise InputError.of("The point CRS '{crs}' is not understood: {error}",
                            crs=str(crs)[:60], error=exc) from exc
    sx, sy = tf.transform(x, y)
    return np.asarray(sx, dtype=float), np.asarray(sy, dtype=float)


#: Largest window (cells) read at once; points further apart are read one small window each
#: (a long breakline on a fine DSM must not read most of the raster).
MAX_WINDOW_CELLS = 1_000_000


def _inside(col: NDArray, row: NDArray, width: int, height: int) -> NDArray:
    """Fractional positions on the raster (cell centres at integers: edges at −0.5)."""
    return (col >= -0.5) & (col <= width - 0.5) & (row >= -0.5) & (row <= height - 0.5)


def _window_heights(src: Any, col: NDArray, row: NDArray) -> NDArray:
    """Bilinear heights at fractional (col, row) of the open raster ``src``, all on the raster;
    NaN next to nodata. Only the window around the points is read (one window around each
    point when they lie far apart)."""
    c0 = max(int(np.floor(col.min())), 0)
    r0 = max(int(np.floor(row.min())), 0)
    c1 = min(int(np.floor(col.max())) + 2, src.width)
    r1 = min(int(np.floor(row.max())) + 2, src.height)
    if len(col) > 1 and (c1 - c0) * (r1 - r0) > MAX_WINDOW_CELLS:
        return np.concatenate([_window_heights(src, col[k:k + 1], row[k:k + 1])
                               for k in range(len(col))])
    data = src.read(1, window=Window(c0, r0, c1 - c0, r1 - r0), masked=True)
    array = data.astype(float).filled(np.nan)
    # clamp: the outer half cells of the raster take the edge values (module notes)
    return bilinear_grid(array, col - c0, row - r0, edge="clamp")


def surface_heights(surface: PathLike, x: Sequence[float], y: Sequence[float],
                    crs: Any = None) -> Tuple[NDArray, NDArray]:
    """Bilinear heights of a surface raster at many map points (band 1).

    Parameters
    ----------
    surface : path
        A DSM/DTM GeoTIFF (any raster rasterio reads).
    x, y : sequence of float
        Map coordinates, in ``crs``.
    crs : CRS-like, optional
        The points' CRS; ``None``: the surface's own.

    Returns
    -------
    z : ndarray
        Heights, NaN where there is none.
    outside : ndarray of bool
        True where the point lies outside the raster (else a NaN is nodata).

    Raises
    ------
    InputError
        A missing or unreadable surface, or points with a CRS on a surface without one.
    """
    path = _surface_path(surface)
    x = np.atleast_1d(np.asarray(x, dtype=float))
    y = np.atleast_1d(np.asarray(y, dtype=float))
    with reading(path, "surface"), rasterio.open(path) as src:
        sx, sy = _to_surface_crs(path, src.crs, x, y, crs)
        bad = ~(np.isfinite(sx) & np.isfinite(sy))  # not representable in the surface's CRS
        sx, sy = np.where(bad, np.nan, sx), np.where(bad, np.nan, sy)
        col, row = world_to_grid(src.transform, sx, sy)
        on = _inside(col, row, src.width, src.height)
        z = np.full(col.shape, np.nan)
        if on.any():
            z[on] = _window_heights(src, col[on], row[on])
    return z, ~on


def sample_height(surface: PathLike, x: float, y: float, crs: Any = None) -> HeightSample:
    """The bilinear height of a surface at one map point.

    Parameters
    ----------
    surface : path
        A DSM/DTM raster.
    x, y : float
        The map point, in ``crs``.
    crs : CRS-like, optional
        The point's CRS (reprojected to the surface's); ``None``: the surface's own.

    Returns
    -------
    HeightSample
        The height, or ``None`` with the reason (outside the surface, nodata).

    Raises
    ------
    InputError
        A missing or unreadable surface, or a point with a CRS on a surface without one.
    """
    z, outside = surface_heights(surface, [x], [y], crs)
    name = Path(surface).name
    if outside[0]:
        return HeightSample(None, f"({x:.2f}, {y:.2f}) lies outside the surface '{name}'; "
                                  "type the height.", OUTSIDE)
    if not math.isfinite(z[0]):
        return HeightSample(None, f"The surface '{name}' has no height (nodata) at "
                                  f"({x:.2f}, {y:.2f}); type the height.", NODATA)
    return HeightSample(float(z[0]))


def drape_line(surface: Optional[PathLike], coords: Sequence[Sequence[float]], crs: Any = None,
               mode: str = "drape",
               end_heights: Optional[Tuple[float, float]] = None) -> DrapedLine:
    """Heights for the vertices of a line.

    Parameters
    ----------
    surface : path or None
        The DSM/DTM for ``mode="drape"`` (not used by ``"interpolate"``).
    coords : sequence of (x, y[, z])
        The vertices, in ``crs``; a Z given is replaced.
    crs : CRS-like, optional
        The vertices' CRS; ``None``: the surface's own.
    mode : {"drape", "interpolate"}
        ``"drape"``: each vertex's bilinear height on the surface; ``"interpolate"``: linear in
        the 2-D length along the line from ``end_heights[0]`` to ``end_heights[1]``.
    end_heights : (float, float), optional
        The typed heights of the first and last vertex (``"interpolate"`` only).

    Returns
    -------
    DrapedLine
        Vertices with heights; those without one are listed in ``missing``.

    Raises
    ------
    InputError
        Fewer than two vertices, an unknown mode, missing or non-finite end heights, or the
        errors of :func:`surface_heights`.
    """
    xy = np.asarray([(float(c[0]), float(c[1])) for c in coords], dtype=float).reshape(-1, 2)
    if len(xy) < 2:
        raise InputError.of("A line needs at least two vertices.")
    if mode == "interpolate":
        z = _interpolated(xy, end_heights)
        return DrapedLine([(x, y, float(h)) for (x, y), h in zip(xy, z)])
    if mode != "drape":
        raise InputError.of("Height mode '{mode}' is not one of drape, interpolate.", mode=mode)
    if surface is None:
        raise InputError.of("Choose a surface (DSM or DTM) to drape the line on, or type the "
                            "end heights to interpolate between them.")
    z, outside = surface_heights(surface, xy[:, 0], xy[:, 1], crs)
    missing = [int(i) for i in np.flatnonzero(~np.isfinite(z))]
    reason = None
    if missing:
        off = sum(bool(outside[i]) for i in missing)
        reason = (f"{len(missing)} of {len(xy)} vertices have no height on the surface "
                  f"'{Path(str(surface)).name}' ({off} outside it, {len(missing) - off} on "
                  "nodata); type their heights or interpolate between the end heights.")
    return DrapedLine([(x, y, float(h)) for (x, y), h in zip(xy, z)], missing, reason)


def _interpolated(xy: NDArray, end_heights: Optional[Tuple[float, float]]) -> NDArray:
    """Heights linear in the 2-D length along the line between the two end heights."""
    if end_heights is None or len(end_heights) != 2:
        raise InputError.of("Type the heights of the first and the last vertex to interpolate "
                            "between them.")
    z0, z1 = (float(v) for v in end_heights)
    if not (math.isfinite(z0) and math.isfinite(z1)):
        raise InputError.of("The end heights ({z0}, {z1}) must be numbers (m).", z0=z0, z1=z1)
    length = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(xy, axis=0).T))])
    if length[-1] <= 0:
        raise InputError.of("The line has no length; its first and last vertex are the same "
                            "point.")
    return z0 + (z1 - z0) * length / length[-1]


# -- re-drape ------------------------------------------------------------------------------------
#: The edit layers whose heights come from a surface: Z of breaklines, ground and check points,
#: the ``height`` field of start points.
REDRAPE_LAYERS = ("breaklines", "start_points", "ground_points", "check_points")


@dataclass
class Redraped:
    """The answer of :func:`redrape_feature`.

    Attributes
    ----------
    geometry : shapely geometry or None
        The feature with its new heights (Z); ``None`` for a start point (its height is a
        field) or when there is no height (:attr:`reason`).
    height : float or None
        The new ``height`` of a start point.
    reason : str or None
        Why the feature got no new heights (a vertex outside the surface or on nodata).
    """

    geometry: Any = None
    height: Optional[float] = None
    reason: Optional[str] = None

    @property
    def ok(self) -> bool:
        return self.reason is None


def redrape_feature(surface: PathLike, layer: str, geometry: Any, crs: Any = None) -> Redraped:
    """New heights of one edit feature from a surface (the *Re-drape* of both faces).

    Breaklines get the bilinear Z of every vertex (each part of a multi-line), ground and check
    points their Z, start points their ``height`` field; x and y stay as they are.

    Parameters
    ----------
    surface : path
        The DSM/DTM.
    layer : str
        One of :data:`REDRAPE_LAYERS`.
    geometry : shapely geometry
        The feature, in ``crs``.
    crs : CRS-like, optional
        The feature's CRS; ``None``: the surface's own.

    Raises
    ------
    InputError
        A layer without heights, or the errors of :func:`surface_heights`.
    """
    if layer not in REDRAPE_LAYERS:
        raise InputError.of("The layer '{layer}' has no heights to re-drape; use one of "
                            "{layers}.", layer=layer, layers=", ".join(REDRAPE_LAYERS))
    if layer == "breaklines":
        parts = []
        for part in getattr(geometry, "geoms", [geometry]):
            draped = drape_line(surface, list(part.coords), crs=crs)
            if draped.reason:
                return Redraped(reason=draped.reason)
            parts.append(draped.line())
        return Redraped(MultiLineString(parts) if hasattr(geometry, "geoms") else parts[0])
    point = sample_height(surface, geometry.x, geometry.y, crs=crs)
    if point.reason:
        return Redraped(reason=point.reason)
    if layer == "start_points":
        return Redraped(height=point.z)
    return Redraped(Point(geometry.x, geometry.y, point.z))


# -- snapping --------------------------------------------------------------------------------------
@dataclass
class Snap:
    """The answer of :func:`snap_to_lines`: the snapped point, which line, how far it moved, and
    whether it landed on a vertex of that line."""

    point: XY
    line: int
    distance: float
    vertex: bool


def snap_to_lines(point: Sequence[float], lines: Sequence[Any],
                  tolerance: float) -> Optional[Snap]:
    """Snap a map point to the nearest of some lines (seamlines to the mosaic's seamlines).

    A vertex within ``tolerance`` wins over a nearer point on a segment, so that seamlines meet
    at the mosaic's nodes; otherwise the nearest point on the nearest line.

    Parameters
    ----------
    point : (x, y)
    lines : sequence of shapely lines
        In the point's CRS; empty or non-line geometries are skipped.
    tolerance : float
        Largest snapping distance (map units, > 0).

    Returns
    -------
    Snap or None
        ``None`` when no line is within ``tolerance``.
    """
    if not tolerance > 0:
        raise InputError.of("The snapping tolerance must be positive, got {tolerance}.",
                            tolerance=tolerance)
    p = Point(float(point[0]), float(point[1]))
    best_vertex: Optional[Snap] = None
    best_edge: Optional[Snap] = None
    for k, line in enumerate(lines):
        if line is None or line.is_empty or "LineString" not in line.geom_type:
            continue
        for vx, vy in (c[:2] for part in getattr(line, "geoms", [line]) for c in part.coords):
            d = math.hypot(vx - p.x, vy - p.y)
            if d <= tolerance and (best_vertex is None or d < best_vertex.distance):
                best_vertex = Snap((vx, vy), k, d, True)
        d = line.distance(p)
        if d <= tolerance and (best_edge is None or d < best_edge.distance):
            q = nearest_points(line, p)[0]
            best_edge = Snap((q.x, q.y), k, d, False)
    return best_vertex or best_edge


def mosaic_seamlines(path: PathLike, crs: Any = None) -> List[Any]:
    """The lines of a mosaic's seamline file (its ``seamlines`` layer), in ``crs``.

    The snapping targets of :func:`snap_to_lines` for the standalone tool (QGIS snaps to the
    loaded layer itself).

    Raises
    ------
    InputError
        A missing or unreadable file.
    """
    return read_geometries(path, ("LineString",), crs, ("seamlines",))


__all__ = ["NODATA", "OUTSIDE", "REDRAPE_LAYERS", "DrapedLine", "HeightSample", "Redraped",
           "Snap", "drape_line", "mosaic_seamlines", "redrape_feature", "sample_height",
           "snap_to_lines", "surface_heights"]
