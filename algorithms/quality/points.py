r"""Check points (or matched points) against a DEM: residual table and statistics.

The residual of a point is

.. math:: \Delta z_i = z_{DEM}(x_i, y_i) - z_i

(DEM minus point, the sign convention of :func:`.compare.compare_dems`: positive = the DEM is
too high), with :math:`z_{DEM}` interpolated bilinearly between the four surrounding cell
centres (:mod:`..raster.sample`). Points outside the hull of cell centres, or next to a nodata
cell, are listed as ``outside`` / ``nodata`` and left out of the statistics.

Point files operators have:

* XYZ text: one point per line, fields separated by whitespace, commas, semicolons or tabs;
  ``x y z`` or ``id x y z`` (a first field that is not a number is the id); further columns are
  ignored; ``#`` starts a comment.
* CSV with a header: the columns are found by name (``x``/``easting``/``rechtswert``,
  ``y``/``northing``/``hochwert``, ``z``/``height``/``elevation``/``h``, optional
  ``id``/``name``).
* Vector files (GeoPackage, Shapefile, GeoJSON): 3-D points, or 2-D points with a height field;
  reprojected to the DEM's CRS when both CRSs are known.
* LAS / LAZ point clouds (when laspy is installed; LAZ needs a LAZ backend such as lazrs):
  x, y, z and the CRS from the WKT/GeoTIFF VLR; the ids are the point numbers 1…n.

Text files carry no CRS: their coordinates must be in the DEM's CRS.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InputError
from ..feedback import Feedback, ensure_feedback
from ..raster.io import atomic_output

PathLike = Union[str, Path]

#: File endings read with fiona; everything else is read as text.
VECTOR_SUFFIXES = (".gpkg", ".shp", ".geojson", ".json", ".gml", ".sqlite", ".fgb", ".kml")

#: Point-cloud file endings read with laspy (:func:`..surface.point_output.read_las`).
LAS_SUFFIXES = (".las", ".laz")

#: Accepted column / field names (lower case) of the coordinates and the id.
COLUMN_NAMES: Dict[str, Tuple[str, ...]] = {
    "x": ("x", "easting", "east", "e", "rechtswert", "rw", "lon", "longitude"),
    "y": ("y", "northing", "north", "n", "hochwert", "hw", "lat", "latitude"),
    "z": ("z", "height", "elevation", "elev", "h", "alt", "altitude", "hoehe", "höhe"),
    "id": ("id", "name", "point", "point_id", "pointid", "label", "nr", "number", "pid"),
}

#: Points per block of the DEM read at once when sampling (cells per side).
SAMPLE_BLOCK = 1024


@dataclass
class PointSet:
    """Points read from a file: ids, coordinates, and the CRS if the file has one."""

    ids: List[str]
    x: NDArray[np.float64]
    y: NDArray[np.float64]
    z: NDArray[np.float64]
    crs: Optional[str] = None
    skipped: int = 0

    def __len__(self) -> int:
        return len(self.ids)


def parse_number(token: str) -> Optional[float]:
    """The finite number a text field holds, else ``None``."""
    try:
        value = float(token)
    except ValueError:
        return None
    return value if math.isfinite(value) else None


def split_fields(line: str, sep: Optional[str]) -> List[str]:
    """Fields of a line: by ``sep`` (a CSV with a header), else by any run of separators."""
    parts = line.split(sep) if sep else re.split(r"[,;\s]+", line.strip())
    return [p.strip().strip('"').strip("'").strip() for p in parts]


def field_separator(line: str) -> Optional[str]:
    """The separator of a header line: comma, semicolon or tab; ``None`` = whitespace."""
    for sep in (",", ";", "\t"):
        if sep in line:
            return sep
    return None  # whitespace


def find_column(names: Sequence[str], candidates: Sequence[str]) -> Optional[int]:
    """Index of the first of ``candidates`` (lower case) among the column ``names``."""
    lowered = [n.lower() for n in names]
    for candidate in candidates:
        if candidate in lowered:
            return lowered.index(candidate)
    return None


def numbered_lines(text: str) -> List[Tuple[int, str]]:
    """The non-empty lines of a text file without ``#`` comments, with their numbers (from 1)."""
    lines = []
    for number, raw in enumerate(text.splitlines(), start=1):
        stripped = raw.split("#", 1)[0].strip()
        if stripped:
            lines.append((number, stripped))
    return lines


def _read_text(path: Path) -> PointSet:
    lines = numbered_lines(path.read_text(encoding="utf-8-sig", errors="replace"))
    if not lines:
        raise InputError(f"The points file '{path.name}' holds no points (only comments or "
                         "empty lines).")
    sep = field_separator(lines[0][1])
    first = split_fields(lines[0][1], sep)
    columns: Optional[Tuple[Optional[int], int, int, int]] = None
    names = {n for key in ("x", "y", "z") for n in COLUMN_NAMES[key]}
    header = all(parse_number(t) is None for t in first if t) and \
        (sep is not None or any(t.lower() in names for t in first))
    if not header:
        sep = None  # XYZ text: any mix of separators
    else:
        cx, cy, cz = (find_column(first, COLUMN_NAMES[k]) for k in ("x", "y", "z"))
        if cx is None or cy is None or cz is None:
            raise InputError(
                f"The header of '{path.name}' has no x/y/z columns (found: {', '.join(first)}); "
                "name them x, y, z (or easting, northing, height)."
            )
        columns = (find_column(first, COLUMN_NAMES["id"]), cx, cy, cz)
        lines = lines[1:]
    ids: List[str] = []
    xyz: List[Tuple[float, float, float]] = []
    skipped = 0
    for number, text in lines:
        tokens = split_fields(text, sep)
        if columns is not None:
            cid, cx, cy, cz = columns
            if max(cx, cy, cz) >= len(tokens):
                skipped += 1
                continue
            values = [parse_number(tokens[c]) for c in (cx, cy, cz)]
            name = tokens[cid] if cid is not None and cid < len(tokens) else str(number)
        else:
            offset = 1 if tokens and parse_number(tokens[0]) is None else 0
            values = [parse_number(t) for t in tokens[offset:offset + 3]]
            name = tokens[0] if offset else str(number)
            if len(values) < 3:
                skipped += 1
                continue
        if any(v is None for v in values):
            skipped += 1
            continue
        ids.append(name)
        xyz.append((values[0], values[1], values[2]))  # type: ignore[arg-type]
    arr = np.array(xyz, dtype=float).reshape(-1, 3)
    return PointSet(ids, arr[:, 0], arr[:, 1], arr[:, 2], None, skipped)


def _read_vector(path: Path) -> PointSet:
    import fiona

    try:
        layers = fiona.listlayers(str(path))
    except Exception as exc:  # fiona raises driver-specific errors
        raise InputError(f"Cannot read the points file '{path.name}': {exc}") from exc
    ids: List[str] = []
    xyz: List[Tuple[float, float, float]] = []
    skipped = 0
    crs = None
    for layer in layers:
        with fiona.open(str(path), layer=layer) as src:
            if "Point" not in str(src.schema.get("geometry", "")):
                continue
            fields = list(src.schema["properties"])
            zf = find_column(fields, COLUMN_NAMES["z"])
            idf = find_column(fields, COLUMN_NAMES["id"])
            crs = src.crs_wkt or None
            for feature in src:
                geom = feature["geometry"]
                props = feature["properties"]
                coords = geom["coordinates"] if geom else None
                if geom and geom["type"] == "MultiPoint":
                    coords = coords[0] if coords else None
                if not coords:
                    skipped += 1
                    continue
                z = coords[2] if len(coords) > 2 else None
                if (z is None or not math.isfinite(float(z))) and zf is not None:
                    z = props[fields[zf]]
                try:
                    values = (float(coords[0]), float(coords[1]), float(z))  # type: ignore
                except (TypeError, ValueError):
                    skipped += 1
                    continue
                if not all(math.isfinite(v) for v in values):
                    skipped += 1
                    continue
                ids.append(str(props[fields[idf]]) if idf is not None else str(feature["id"]))
                xyz.append(values)
        break  # the first point layer
    else:
        raise InputError(f"'{path.name}' has no point layer; give points (3-D, or with a "
                         "height field z/height/elevation).")
    if not xyz and skipped:
        raise InputError(f"The points of '{path.name}' have no height: use 3-D points or add "
                         "a field z (or height, elevation).")
    arr = np.array(xyz, dtype=float).reshape(-1, 3)
    return PointSet(ids, arr[:, 0], arr[:, 1], arr[:, 2], crs, skipped)


class _RowIds(Sequence[str]):
    """Ids "1" … "n" made on demand (no list of 10⁷ strings for a point cloud)."""

    def __init__(self, n: int) -> None:
        self._n = int(n)

    def __len__(self) -> int:
        return self._n

    def __getitem__(self, index: Any) -> Any:
        if isinstance(index, slice):
            return [str(i + 1) for i in range(*index.indices(self._n))]
        i = int(index)
        if i < 0:
            i += self._n
        if not 0 <= i < self._n:
            raise IndexError(index)
        return str(i + 1)


def _read_las(path: Path) -> PointSet:
    from ..surface.point_output import read_las

    x, y, z, crs, _ = read_las(path)
    ok = np.isfinite(x) & np.isfinite(y) & np.isfinite(z)
    if not ok.all():
        x, y, z = x[ok], y[ok], z[ok]
    return PointSet(_RowIds(x.size), x, y, z, crs,  # type: ignore[arg-type]
                    int(np.count_nonzero(~ok)))


def distinct_positions(x: ArrayLike, y: ArrayLike) -> int:
    """Number of distinct finite (x, y) positions."""
    xy = np.column_stack([np.asarray(x, float).ravel(), np.asarray(y, float).ravel()])
    xy = xy[np.all(np.isfinite(xy), axis=1)]
    if len(xy) == 0:
        return 0
    return len(np.unique(xy, axis=0))


def check_distinct_points(x: ArrayLike, y: ArrayLike, name: str, minimum: int,
                          purpose: str) -> int:
    """The number of distinct point positions; a warning when points repeat a position, an
    error when fewer than ``minimum`` distinct positions remain.

    Thousands of copies of one point carry no more information than one: they are kept (the
    per-cell rules — lowest, median — combine them), but the operator is told, and a surface
    is not built on fewer distinct positions than it needs.

    Parameters
    ----------
    x, y : array_like
        Point coordinates (non-finite ones are not counted).
    name : str
        The file, for the messages.
    minimum : int
        Fewest distinct positions ``purpose`` needs.
    purpose : str
        What the points are for ("a filter", "an interpolation"), for the messages.

    Raises
    ------
    InputError
        When fewer than ``minimum`` distinct positions remain.
    """
    from ..input_errors import warn_input

    n_ok = int(np.sum(np.isfinite(np.asarray(x, float)) & np.isfinite(np.asarray(y, float))))
    n_distinct = distinct_positions(x, y)
    if n_distinct < minimum:
        raise InputError(f"'{name}' has only {n_distinct} distinct point position(s) ({n_ok} "
                         f"valid points); {purpose} needs at least {minimum}.")
    if n_distinct < n_ok:
        warn_input(f"'{name}': {n_ok - n_distinct} of {n_ok} points repeat the x, y of another "
                   f"point ({n_distinct} distinct positions); check the file for duplicates.")
    return n_distinct


def read_points(path: PathLike) -> PointSet:
    """Read check points from XYZ text, CSV with a header, a vector file or LAS/LAZ.

    Raises
    ------
    InputError
        When the file is missing or holds no valid point.
    """
    path = Path(path)
    if not path.is_file():
        raise InputError(f"Points file '{path}' does not exist.")
    if path.suffix.lower() in LAS_SUFFIXES:
        points = _read_las(path)
    elif path.suffix.lower() in VECTOR_SUFFIXES:
        points = _read_vector(path)
    else:
        points = _read_text(path)
    if len(points) == 0:
        raise InputError(f"The points file '{path.name}' has no valid row (need x, y, z numbers "
                         f"per line; {points.skipped} line(s) could not be read).")
    return points


def _to_dem_crs(src: Any, x: NDArray[Any], y: NDArray[Any],
               crs: Any) -> Tuple[NDArray[Any], NDArray[Any]]:
    """Points in ``crs`` → the CRS of the open raster ``src`` (unchanged if either is unknown)."""
    if crs is None or src.crs is None:
        return x, y
    from rasterio.crs import CRS
    from rasterio.warp import transform

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
    import rasterio
    from rasterio.windows import Window

    from ..raster.sample import bilinear_grid, world_to_grid

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
    import rasterio

    from .stats import difference_stats

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
        from ..raster.sample import world_to_grid

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


__all__ = ["PointSet", "check_distinct_points", "distinct_positions", "point_compare",
           "read_points", "sample_dem", "write_residuals"]
