r"""Point files operators give: XYZ text, CSV with a header, vector points, LAS / LAZ.

Read by :func:`read_points` into a :class:`PointSet`:

* XYZ text: one point per line, fields separated by whitespace, commas, semicolons or tabs;
  ``x y z`` or ``id x y z`` (a first field that is not a number is the id); further columns are
  ignored; ``#`` starts a comment.
* CSV with a header: the columns are found by name (``x``/``easting``/``rechtswert``,
  ``y``/``northing``/``hochwert``, ``z``/``height``/``elevation``/``h``, optional
  ``id``/``name``).
* Vector files (GeoPackage, Shapefile, GeoJSON): 3-D points, or 2-D points with a height field;
  the file's CRS is kept.
* LAS / LAZ point clouds (when laspy is installed; LAZ needs a LAZ backend such as lazrs):
  x, y, z and the CRS from the WKT/GeoTIFF VLR; the ids are the point numbers 1…n.

Text files carry no CRS. The module is input I/O below the domains: check points
(:mod:`..quality.points`), DEM interpolation (:mod:`..surface.interpolate`) and the DTM filters
(:mod:`..filtering.surface_input`) read their points here.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

import fiona
import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InputError
from ..input_errors import warn_input

PathLike = Union[str, Path]
Array = NDArray[Any]

#: File endings read with fiona; everything else is read as text.
VECTOR_SUFFIXES = (".gpkg", ".shp", ".geojson", ".json", ".gml", ".sqlite", ".fgb", ".kml")

#: Point-cloud file endings read with laspy (:func:`read_las`).
LAS_SUFFIXES = (".las", ".laz")

#: Accepted column / field names (lower case) of the coordinates and the id.
COLUMN_NAMES: Dict[str, Tuple[str, ...]] = {
    "x": ("x", "easting", "east", "e", "rechtswert", "rw", "lon", "longitude"),
    "y": ("y", "northing", "north", "n", "hochwert", "hw", "lat", "latitude"),
    "z": ("z", "height", "elevation", "elev", "h", "alt", "altitude", "hoehe", "höhe"),
    "id": ("id", "name", "point", "point_id", "pointid", "label", "nr", "number", "pid"),
}


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


# -- LAS ------------------------------------------------------------------------------------------
def import_laspy() -> Any:
    """The laspy module (an optional dependency), or an InputError that says how to install it."""
    try:
        import laspy  # optional dependency: imported where LAS is read or written
    except ImportError as exc:
        raise InputError("LAS/LAZ files need the Python package laspy: install laspy "
                         "(pip install laspy; for .laz: pip install \"laspy[lazrs]\"), or "
                         "write a GeoPackage (.gpkg).") from exc
    return laspy


def laz_check(laspy: Any, path: Path) -> None:
    """An InputError when ``path`` is LAZ and laspy has no LAZ backend."""
    if path.suffix.lower() == ".laz" and not laspy.LazBackend.detect_available():
        raise InputError(f"'{path.name}' is a compressed LAZ file, but laspy has no LAZ backend "
                         "(lazrs or laszip) installed: pip install \"laspy[lazrs]\" (or pip "
                         "install lazrs), or use .las.")


def read_las(path: PathLike, chunk: int = 2_000_000) -> Tuple[Array, Array, Array, Any,
                                                               Dict[str, Array]]:
    """Read the coordinates, the CRS (WKT or None) and the extra-bytes fields of a LAS file.

    Raises
    ------
    InputError
        laspy (or the LAZ backend) missing, or the file is not LAS.
    """
    laspy = import_laspy()
    path = Path(path)
    laz_check(laspy, path)
    try:
        with laspy.open(str(path)) as reader:
            n = int(reader.header.point_count)
            try:
                pcrs = reader.header.parse_crs()
            except Exception:  # a broken or unsupported CRS record: the points are still read
                pcrs = None
            names = list(reader.header.point_format.extra_dimension_names)
            x, y, z = np.empty(n), np.empty(n), np.empty(n)
            extra: Dict[str, Array] = {}
            pos = 0
            for part in reader.chunk_iterator(chunk):
                k = len(part)
                x[pos:pos + k] = np.asarray(part.x, dtype=np.float64)
                y[pos:pos + k] = np.asarray(part.y, dtype=np.float64)
                z[pos:pos + k] = np.asarray(part.z, dtype=np.float64)
                for name in names:
                    values = np.asarray(part[name])
                    if name not in extra:
                        extra[name] = np.empty(n, dtype=values.dtype)
                    extra[name][pos:pos + k] = values
                pos += k
    except InputError:
        raise
    except Exception as exc:  # laspy raises LaspyException, OSError, ValueError…
        raise InputError(f"Cannot read the LAS file '{path.name}': {exc}") from exc
    wkt = pcrs.to_wkt() if pcrs is not None else None
    return x[:pos], y[:pos], z[:pos], wkt, {k: v[:pos] for k, v in extra.items()}


__all__ = ["COLUMN_NAMES", "LAS_SUFFIXES", "VECTOR_SUFFIXES", "PointSet", "check_distinct_points",
           "distinct_positions", "field_separator", "find_column", "import_laspy", "laz_check",
           "numbered_lines", "parse_number", "read_las", "read_points", "split_fields"]
