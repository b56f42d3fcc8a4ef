"""The whole of ``edits.gpkg`` read into memory and written back atomically (the standalone
tool's edit session, issue 21).

QGIS edits ``edits.gpkg`` in place through GDAL; the standalone tool keeps the operator's edits
in memory (with undo) and saves them at once. Saving must never leave a half-written file that
QGIS (or a run) could read, and must lose nothing the tool does not know about. So
:func:`save_edits`:

1. copies the current file to a hidden staging name in the same folder (SQLite's backup API: a
   consistent copy even while another program reads it) — layers, fields, styles, metadata and
   extensions the tool does not know are thereby kept unchanged;
2. replaces the rows of the edit layers in the copy, keeping each feature's fid, all columns of
   the table (also fields an operator added in QGIS) and Z (geometries are written as
   GeoPackage blobs of ISO WKB);
3. checks the copy (GDAL reads every edit layer and finds the expected feature counts);
4. renames it over ``edits.gpkg`` (``os.replace``, atomic on one file system).

Any error on the way removes the staging file and leaves ``edits.gpkg`` as it was. A missing
``edits.gpkg`` is created with every edit layer in the project CRS (:func:`.edits.create_edits`).

The reader (:func:`read_edits`) works on the same level (SQLite rows, not GDAL features), so a
load → save round trip gives the values back as they were stored; features without geometry
(QGIS allows them) are kept as well, with ``None`` for the geometry.
"""

from __future__ import annotations

import math
import os
import sqlite3
import struct
from collections import OrderedDict
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Dict, Iterable, List, Optional, Sequence, Tuple, Union

import fiona
from shapely import wkb

from .. import output_policy
from ..errors import InputError
from .edits import EDIT_LAYERS, add_edit_layers, create_edits, missing_edit_layers

PathLike = Union[str, Path]
#: One feature in memory: (fid, shapely geometry or None, attributes).
Feature = Tuple[int, Any, Dict[str, Any]]

#: Bytes of the envelope by the GeoPackage header's envelope indicator.
_ENVELOPE_BYTES = {0: 0, 1: 32, 2: 48, 3: 48, 4: 64}


@dataclass
class EditsContent:
    """What :func:`read_edits` found in ``edits.gpkg``.

    Attributes
    ----------
    layers : dict
        Edit layer name → its features ``(fid, geometry or None, attributes)`` in fid order.
        Only the layers of :data:`.edits.EDIT_LAYERS` that the file holds.
    columns : dict
        Edit layer name → its attribute columns (in table order; fid and geometry left out).
    crs_wkt : str
        The CRS of the edit layers (WKT), empty when the file names none.
    """

    layers: Dict[str, List[Feature]] = field(default_factory=dict)
    columns: Dict[str, List[str]] = field(default_factory=dict)
    crs_wkt: str = ""


# -- GeoPackage geometry blobs -------------------------------------------------------------------
def blob_to_geometry(blob: Optional[bytes]) -> Any:
    """A GeoPackage geometry blob as a shapely geometry (Z kept); ``None`` for NULL or an
    empty geometry."""
    if blob is None:
        return None
    blob = bytes(blob)
    if blob[:2] != b"GP":
        raise InputError.of("A geometry of edits.gpkg is not a GeoPackage geometry blob.")
    flags = blob[3]
    if flags & 0x10:  # the empty flag
        return None
    start = 8 + _ENVELOPE_BYTES.get((flags >> 1) & 0x07, 0)
    return wkb.loads(blob[start:])


def geometry_to_blob(geometry: Any, srs_id: int) -> Optional[bytes]:
    """A shapely geometry as a GeoPackage blob (little endian, ISO WKB, XY envelope except for
    points, like GDAL writes it); ``None`` for ``None`` or an empty geometry."""
    if geometry is None or geometry.is_empty:
        return None
    point = geometry.geom_type == "Point"
    flags = 0x01 | (0 if point else 0x02)  # little endian; envelope [minx, maxx, miny, maxy]
    head = b"GP" + bytes([0, flags]) + struct.pack("<i", int(srs_id))
    if not point:
        xmin, ymin, xmax, ymax = geometry.bounds
        head += struct.pack("<4d", xmin, xmax, ymin, ymax)
    return head + iso_wkb(geometry)


#: ISO WKB type codes (+1000 with Z).
_WKB_TYPES = {"Point": 1, "LineString": 2, "Polygon": 3, "MultiPoint": 4, "MultiLineString": 5,
              "MultiPolygon": 6, "GeometryCollection": 7}


def iso_wkb(geometry: Any) -> bytes:
    """Little-endian ISO WKB of a shapely geometry (Z as type + 1000), as the GeoPackage
    standard asks; written here because shapely < 2 (Debian's, tier B) writes only the older
    extended flavour."""
    z = geometry.has_z
    head = struct.pack("<BI", 1, _WKB_TYPES[geometry.geom_type] + (1000 if z else 0))

    def points(coords: Any) -> bytes:
        flat = [float(v) for c in coords for v in (tuple(c) + (0.0,))[:3 if z else 2]]
        return struct.pack(f"<{len(flat)}d", *flat)

    kind = geometry.geom_type
    if kind == "Point":
        return head + points(geometry.coords)
    if kind == "LineString":
        return head + struct.pack("<I", len(geometry.coords)) + points(geometry.coords)
    if kind == "Polygon":
        rings = [geometry.exterior] + list(geometry.interiors)
        return head + struct.pack("<I", len(rings)) + b"".join(
            struct.pack("<I", len(r.coords)) + points(r.coords) for r in rings)
    parts = list(geometry.geoms)
    return head + struct.pack("<I", len(parts)) + b"".join(iso_wkb(p) for p in parts)


def _bounds_of_blob(blob: Optional[bytes]) -> Optional[Tuple[float, float, float, float]]:
    geometry = blob_to_geometry(blob)
    return None if geometry is None else geometry.bounds


def register_gpkg_functions(con: sqlite3.Connection) -> None:
    """The SQL functions GDAL's R-tree triggers call (GDAL registers them itself)."""
    def part(k: int) -> Any:
        def value(blob: Optional[bytes]) -> Optional[float]:
            b = _bounds_of_blob(blob)
            return None if b is None else b[k]
        return value

    con.create_function("ST_IsEmpty", 1, lambda b: int(blob_to_geometry(b) is None),
                        deterministic=True)
    for name, k in (("ST_MinX", 0), ("ST_MinY", 1), ("ST_MaxX", 2), ("ST_MaxY", 3)):
        con.create_function(name, 1, part(k), deterministic=True)


# -- reading ---------------------------------------------------------------------------------
def _quote(name: str) -> str:
    return '"' + name.replace('"', '""') + '"'


@dataclass
class _Table:
    name: str
    fid: str
    geometry: str
    srs_id: int
    columns: List[str]


def _tables(con: sqlite3.Connection) -> Dict[str, _Table]:
    """The feature tables of the GeoPackage that are edit layers, with their key and columns."""
    out: Dict[str, _Table] = {}
    rows = con.execute("SELECT table_name, column_name, srs_id FROM gpkg_geometry_columns")
    for table, geom_col, srs_id in rows.fetchall():
        if table not in EDIT_LAYERS:
            continue
        info = con.execute(f"PRAGMA table_info({_quote(table)})").fetchall()
        keys = [r[1] for r in info if r[5]]
        fid = keys[0] if keys else "rowid"
        columns = [r[1] for r in info if r[1] not in (fid, geom_col)]
        out[table] = _Table(table, fid, geom_col, int(srs_id), columns)
    return out


def _crs_wkt(con: sqlite3.Connection, tables: Dict[str, _Table]) -> str:
    for table in tables.values():
        row = con.execute("SELECT definition FROM gpkg_spatial_ref_sys WHERE srs_id = ?",
                          (table.srs_id,)).fetchone()
        if row and row[0] and row[0] != "undefined":
            return str(row[0])
    return ""


def read_edits(path: PathLike) -> EditsContent:
    """Every edit layer of ``edits.gpkg`` as stored: fids, geometries (Z kept), all columns.

    Raises
    ------
    InputError
        When the file is missing, not a GeoPackage, or a geometry cannot be read; the message
        names the file and the cause.
    """
    path = Path(path)
    if not path.is_file():
        raise InputError.of("The edits file '{path}' does not exist.", path=path)
    try:
        con = sqlite3.connect(f"file:{path}?mode=ro", uri=True, timeout=2.0)
    except sqlite3.Error as exc:
        raise InputError.of("Cannot open the edits file '{path}': {error}", path=path,
                            error=exc) from exc
    try:
        tables = _tables(con)
        content = EditsContent(crs_wkt=_crs_wkt(con, tables))
        for name in EDIT_LAYERS:
            if name in tables:
                content.layers[name] = _read_table(con, tables[name])
                content.columns[name] = list(tables[name].columns)
        return content
    except (sqlite3.Error, ValueError, struct.error) as exc:  # also shapely's WKB errors
        raise InputError.of("The edits file '{path}' is not a readable GeoPackage ({error}); "
                            "it is damaged or not a GeoPackage.", path=path, error=exc) from exc
    except Exception as exc:  # shapely.errors.GEOSException and kin: a damaged geometry
        raise InputError.of("The edits file '{path}' holds a geometry that cannot be read "
                            "({error}).", path=path, error=exc) from exc
    finally:
        con.close()


def _read_table(con: sqlite3.Connection, table: _Table) -> List[Feature]:
    cols = [table.fid, table.geometry] + table.columns
    sql = (f"SELECT {', '.join(_quote(c) for c in cols)} FROM {_quote(table.name)} "
           f"ORDER BY {_quote(table.fid)}")
    out: List[Feature] = []
    for row in con.execute(sql):
        attrs = OrderedDict(zip(table.columns, row[2:]))
        out.append((int(row[0]), blob_to_geometry(row[1]), dict(attrs)))
    return out


# -- writing ---------------------------------------------------------------------------------
def _numbered(features: Iterable[Sequence[Any]]) -> List[Feature]:
    """``(geometry, attrs)`` or ``(fid, geometry, attrs)`` items with fids (new ones after the
    largest given); a fid used twice is an error."""
    items = [tuple(f) for f in features]
    given = [int(f[0]) for f in items if len(f) == 3 and f[0] is not None]
    if len(set(given)) != len(given):
        raise InputError.of("Two features of one edit layer have the same fid.")
    next_fid = max(given, default=0) + 1
    out: List[Feature] = []
    for item in items:
        if len(item) == 3 and item[0] is not None:
            out.append((int(item[0]), item[1], dict(item[2] or {})))
        else:
            out.append((next_fid, item[-2], dict(item[-1] or {})))
            next_fid += 1
    return sorted(out, key=lambda f: f[0])


def _write_table(con: sqlite3.Connection, table: _Table, features: List[Feature]) -> None:
    """Replace the rows of one edit layer (fids kept) and update its extent and count."""
    unknown = sorted({k for _, _, a in features for k in a} - set(table.columns))
    if unknown:
        raise InputError.of("Layer '{layer}' of edits.gpkg has no field(s) {fields}.",
                            layer=table.name, fields=", ".join(unknown))
    con.execute(f"DELETE FROM {_quote(table.name)}")
    cols = [table.fid, table.geometry] + table.columns
    sql = (f"INSERT INTO {_quote(table.name)} ({', '.join(_quote(c) for c in cols)}) "
           f"VALUES ({', '.join('?' * len(cols))})")
    rows = [[fid, geometry_to_blob(g, table.srs_id)] + [_plain(a.get(c)) for c in table.columns]
            for fid, g, a in features]
    con.executemany(sql, rows)
    bounds = [g.bounds for _, g, _ in features if g is not None and not g.is_empty]
    box = ((min(b[0] for b in bounds), min(b[1] for b in bounds), max(b[2] for b in bounds),
            max(b[3] for b in bounds)) if bounds else (None, None, None, None))
    con.execute("UPDATE gpkg_contents SET min_x = ?, min_y = ?, max_x = ?, max_y = ?, "
                "last_change = strftime('%Y-%m-%dT%H:%M:%fZ','now') WHERE table_name = ?",
                (*box, table.name))
    if con.execute("SELECT 1 FROM sqlite_master WHERE name = 'gpkg_ogr_contents'").fetchone():
        con.execute("UPDATE gpkg_ogr_contents SET feature_count = ? WHERE lower(table_name) = "
                    "lower(?)", (len(features), table.name))


def _plain(value: Any) -> Any:
    """A value SQLite stores (numpy numbers as Python numbers, NaN as NULL)."""
    if hasattr(value, "item") and not isinstance(value, (bytes, str)):
        value = value.item()
    if isinstance(value, float) and math.isnan(value):
        return None
    return value


def _copy(src: Path, dst: Path) -> None:
    """A consistent copy of a GeoPackage (SQLite backup), in rollback-journal mode so that no
    ``-wal`` file belongs to it."""
    source = sqlite3.connect(f"file:{src}?mode=ro", uri=True, timeout=5.0)
    target = sqlite3.connect(str(dst))
    try:
        source.backup(target)
        target.execute("PRAGMA journal_mode=DELETE")
    finally:
        source.close()
        target.close()


def _fill(staging: Path, layers: Dict[str, List[Feature]]) -> None:
    """Write the features of ``layers`` into the staging GeoPackage in one transaction."""
    con = sqlite3.connect(str(staging))
    try:
        register_gpkg_functions(con)
        tables = _tables(con)
        with con:
            for name, features in layers.items():
                if name not in tables:
                    raise InputError.of("edits.gpkg has no layer '{layer}' to write.",
                                        layer=name)
                _write_table(con, tables[name], features)
    finally:
        con.close()


def _check(staging: Path, layers: Dict[str, List[Feature]]) -> None:
    """GDAL reads every written layer back with the expected number of features."""
    for name, features in layers.items():
        try:
            with fiona.open(str(staging), layer=name) as src:
                count = len(src)
        except Exception as exc:  # fiona's driver errors
            raise InputError.of("The new edits.gpkg cannot be read back ({error}); the old "
                                "file is kept.", error=exc) from exc
        if count != len(features):
            raise InputError.of("The new edits.gpkg holds {count} features in '{layer}' instead "
                                "of {expected}; the old file is kept.", count=count, layer=name,
                                expected=len(features))


def save_edits(path: PathLike, layers: Dict[str, Iterable[Sequence[Any]]],
               crs: str = "") -> Path:
    """Write the edit layers ``layers`` into ``edits.gpkg`` atomically (see the module notes).

    Parameters
    ----------
    path : path
        ``<project>/edits.gpkg``; created when missing.
    layers : dict
        Edit layer name → its features, each ``(geometry, attributes)`` or ``(fid, geometry,
        attributes)`` (shapely geometries in the file's CRS; ``None`` for a feature without
        geometry). The layer's rows are replaced by these; layers not named are kept as they
        are, as is everything else in the file.
    crs : str
        The project CRS, used only to create a missing file or missing edit layers.

    Returns
    -------
    Path
        ``path``.

    Raises
    ------
    InputError
        An unknown layer or field, a CRS not understood, or a write that failed; ``path`` is
        then unchanged and no staging file is left.
    """
    path = Path(path)
    numbered = {name: _numbered(features) for name, features in layers.items()}
    for name in numbered:
        if name not in EDIT_LAYERS:
            raise InputError.of("'{layer}' is not an edit layer; use one of {layers}.",
                                layer=name, layers=", ".join(EDIT_LAYERS))
    staging = path.with_name(output_policy.staging_name(path.stem, suffix=path.suffix))
    try:
        if path.exists():
            _copy(path, staging)
        else:
            if not crs:
                raise InputError.of("'{path}' does not exist and no CRS was given to create it.",
                                    path=path)
            create_edits(staging, crs)
        missing = [n for n in missing_edit_layers(staging) if n in numbered]
        if missing:
            add_edit_layers(staging, crs or read_edits(staging).crs_wkt, missing)
        _fill(staging, numbered)
        _check(staging, numbered)
        with output_policy.sigint_blocked():
            os.replace(staging, path)
    except sqlite3.Error as exc:
        raise InputError.of("Cannot write '{path}': {error}; the old file is kept.", path=path,
                            error=exc) from exc
    finally:
        for leftover in (staging, Path(f"{staging}-journal"), Path(f"{staging}-wal"),
                         Path(f"{staging}-shm")):
            if leftover.exists():
                leftover.unlink()
    return path


__all__ = ["EditsContent", "blob_to_geometry", "geometry_to_blob", "iso_wkb", "read_edits",
           "register_gpkg_functions", "save_edits"]
