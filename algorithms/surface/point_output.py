r"""Matched points with their quality to GeoPackage or LAS 1.4, atomically and in chunks.

The format follows the suffix of the target:

``.gpkg``
    One layer (named after the file) of 3-D points (``Point Z``) with one attribute per field
    (e.g. ``sigma_z``, ``rho``, ``flags``, ``level``, ``n``); floats as REAL, integers and
    booleans as INTEGER, strings as TEXT; the CRS in the layer. Written with fiona's
    ``writerecords`` in batches of ``chunk`` points. fiona converts feature by feature in
    Python: about 15 000–30 000 points/s on the reference machine (10⁶ points ≈ 1 min), so
    LAS is the format for big sets.
``.las`` / ``.laz``
    LAS 1.4, point format 6, written with laspy (optional: ``pip install laspy``; ``.laz``
    also needs a LAZ backend, ``pip install "laspy[lazrs]"``). Coordinates are stored as
    integers :math:`X_{int} = \mathrm{round}((X - X_{off}) / s)` with the scale
    :math:`s` = 1 mm (projected CRS; 10⁻⁷ ° ≈ 1 cm for a geographic CRS) and offsets at whole
    kilometres below the minima, so that every coordinate of a 2 000 km extent fits the int32
    range. A field named like a standard LAS dimension (``classification``, ``intensity``,
    ``user_data``, ``point_source_id``, ``gps_time``) fills that dimension; every other field
    becomes an *extra bytes* dimension of its own type (booleans as uint8). The CRS is stored
    as an OGC WKT VLR (the global-encoding WKT bit is set). Vectorised; millions of points/s.

Points with a non-finite coordinate are skipped (with a warning). Nothing is left
half-written: the file is written beside the target and renamed when complete
(:func:`..raster.io.atomic_output`).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any, Dict, List, Optional, Tuple, Union

import fiona
import numpy as np
from numpy.typing import ArrayLike, NDArray
from pyproj import CRS

from ..errors import InputError
from ..feedback import Feedback, ensure_feedback
from ..project.points_io import import_laspy as _import_laspy
from ..project.points_io import laz_check as _laz_check
from ..project.points_io import read_las
from ..raster.io import atomic_output

PathLike = Union[str, Path]
Array = NDArray[Any]

#: Suffixes and their formats.
FORMATS = {".gpkg": "gpkg", ".las": "las", ".laz": "las"}

#: Points per batch written (GeoPackage) or per chunk (LAS).
CHUNK = 100_000

#: Standard dimensions of LAS point format 6 that a field of the same name fills.
LAS_STANDARD_FIELDS = ("classification", "intensity", "user_data", "point_source_id",
                       "gps_time", "scan_angle")

#: Coordinate scale of LAS files: metres (projected) and degrees (geographic).
LAS_SCALE_M = 0.001
LAS_SCALE_DEG = 1e-7


def _crs(crs: Any) -> Any:
    """A pyproj CRS from anything pyproj or rasterio understands (None stays None)."""
    if crs is None or crs == "":
        return None

    try:
        if hasattr(crs, "to_wkt") and not isinstance(crs, CRS):
            return CRS.from_wkt(crs.to_wkt())  # rasterio CRS
        return CRS.from_user_input(crs)
    except Exception as exc:  # pyproj raises CRSError
        raise InputError(f"'{crs}' is not a CRS (give e.g. EPSG:25832).") from exc


def _prepare(x: ArrayLike, y: ArrayLike, z: ArrayLike, fields: Optional[Dict[str, ArrayLike]],
             feedback: Feedback) -> Tuple[Array, Array, Array, Dict[str, Array]]:
    x = np.ravel(np.asarray(x, dtype=np.float64))
    y = np.ravel(np.asarray(y, dtype=np.float64))
    z = np.ravel(np.asarray(z, dtype=np.float64))
    if not (x.size == y.size == z.size):
        raise InputError(f"x, y, z have different lengths ({x.size}, {y.size}, {z.size}).")
    cols: Dict[str, Array] = {}
    seen = set()
    for name, values in (fields or {}).items():
        key = str(name)
        if not key or key.lower() in ("x", "y", "z", "fid", "geom", "geometry") or \
                key.lower() in seen:
            raise InputError(f"The point field name '{key}' is empty, reserved (x, y, z, fid, "
                             "geom) or given twice; rename it.")
        seen.add(key.lower())
        arr = np.ravel(np.asarray(values))
        if arr.size != x.size:
            raise InputError(f"The point field '{key}' has {arr.size} values for {x.size} "
                             "points.")
        cols[key] = arr
    ok = np.isfinite(x) & np.isfinite(y) & np.isfinite(z)
    if not ok.all():
        feedback.warning(f"{int(np.count_nonzero(~ok))} point(s) without finite coordinates "
                         "were not written.")
        x, y, z = x[ok], y[ok], z[ok]
        cols = {k: v[ok] for k, v in cols.items()}
    return x, y, z, cols


def write_points(path: PathLike, x: ArrayLike, y: ArrayLike, z: ArrayLike,
                 fields: Optional[Dict[str, ArrayLike]] = None, crs: Any = None, *,
                 chunk: int = CHUNK, feedback: Optional[Feedback] = None) -> Path:
    """Write points and per-point fields to a GeoPackage or LAS file (by the suffix).

    Parameters
    ----------
    path : path
        Target file: ``.gpkg``, ``.las`` or ``.laz``.
    x, y, z : array_like, shape (n,)
        Coordinates in ``crs``.
    fields : dict of str → array_like (n,), optional
        Attributes per point (floats, integers, booleans; strings for GeoPackage only).
    crs : str, pyproj or rasterio CRS, optional
        CRS of the points, stored in the file.
    chunk : int
        Points per batch written.

    Returns
    -------
    Path
        ``path``.

    Raises
    ------
    InputError
        Unknown suffix, laspy (or a LAZ backend) missing, bad fields or CRS.
    """
    feedback = ensure_feedback(feedback)
    path = Path(path)
    fmt = FORMATS.get(path.suffix.lower())
    if fmt is None:
        raise InputError(f"Cannot write points to '{path.name}': use a file ending in "
                         f"{', '.join(FORMATS)}.")
    pcrs = _crs(crs)
    x, y, z, cols = _prepare(x, y, z, fields, feedback)
    chunk = max(int(chunk), 1)
    if fmt == "gpkg":
        return _write_gpkg(path, x, y, z, cols, pcrs, chunk, feedback)
    return _write_las(path, x, y, z, cols, pcrs, chunk, feedback)


# -- GeoPackage ------------------------------------------------------------------------------------
def _fiona_type(arr: Array) -> str:
    if arr.dtype.kind == "b" or arr.dtype.kind in "iu":
        return "int"
    if arr.dtype.kind == "f":
        return "float"
    if arr.dtype.kind in "US":
        return "str"
    raise InputError(f"Point fields of type {arr.dtype} cannot be written; use numbers or "
                     "text.")


def _write_gpkg(path: Path, x: Array, y: Array, z: Array, cols: Dict[str, Array], crs: Any,
                chunk: int, feedback: Feedback) -> Path:
    schema = {"geometry": "3D Point",
              "properties": {k: _fiona_type(v) for k, v in cols.items()}}
    names = list(cols)
    n = x.size
    with atomic_output(path) as tmp:
        kwargs: Dict[str, Any] = {}
        if crs is not None:
            kwargs["crs_wkt"] = crs.to_wkt()
        with fiona.open(str(tmp), "w", driver="GPKG", layer=path.stem, schema=schema,
                        **kwargs) as dst:
            for s in range(0, n, chunk):
                feedback.progress(100.0 * s / max(n, 1))
                e = min(s + chunk, n)
                xs, ys, zs = x[s:e].tolist(), y[s:e].tolist(), z[s:e].tolist()
                # tolist gives Python numbers (NaN stays NaN; GeoPackage stores it as REAL)
                values: List[List[Any]] = [_py_values(cols[k][s:e]) for k in names]
                rows = zip(*values) if values else ((),) * (e - s)
                dst.writerecords(
                    {"geometry": {"type": "Point", "coordinates": (a, b, c)},
                     "properties": dict(zip(names, row))}
                    for a, b, c, row in zip(xs, ys, zs, rows))
    feedback.progress(100.0)
    return path


def _py_values(arr: Array) -> List[Any]:
    if arr.dtype.kind == "b":
        return arr.astype(np.int64).tolist()
    if arr.dtype.kind == "f":  # NaN → None (a NULL attribute)
        out = arr.astype(np.float64).tolist()
        if not np.isfinite(arr).all():
            out = [v if math.isfinite(v) else None for v in out]
        return out
    return arr.tolist()


# -- LAS ------------------------------------------------------------------------------------------
def _las_extra_type(arr: Array) -> Any:
    if arr.dtype.kind == "b":
        return np.uint8
    if arr.dtype.kind in "iuf" and arr.dtype.itemsize <= 8:
        return arr.dtype.newbyteorder("<").type
    raise InputError(f"Point fields of type {arr.dtype} cannot be written to LAS; use numbers.")


def _las_scale_offset(v: Array, scale: float) -> float:
    """Offset at a whole km (or degree) below the minimum; checks the int32 range."""
    if v.size == 0:
        return 0.0
    unit = 1000.0 if scale >= 1e-4 else 1.0
    lo, hi = float(v.min()), float(v.max())
    offset = math.floor(lo / unit) * unit
    if (hi - offset) / scale > 2 ** 31 - 2:
        raise InputError(f"The points span {hi - lo:.0f} units, too far for LAS integer "
                         f"coordinates at the scale {scale:g}; split the point set.")
    return offset


def _write_las(path: Path, x: Array, y: Array, z: Array, cols: Dict[str, Array], crs: Any,
               chunk: int, feedback: Feedback) -> Path:
    laspy = _import_laspy()
    _laz_check(laspy, path)
    header = laspy.LasHeader(point_format=6, version="1.4")
    xy_scale = LAS_SCALE_DEG if crs is not None and crs.is_geographic else LAS_SCALE_M
    header.scales = np.array([xy_scale, xy_scale, LAS_SCALE_M])
    header.offsets = np.array([_las_scale_offset(x, xy_scale), _las_scale_offset(y, xy_scale),
                               _las_scale_offset(z, LAS_SCALE_M)])
    extra = [k for k in cols if k.lower() not in LAS_STANDARD_FIELDS]
    for k in extra:
        if len(k.encode("ascii", "replace")) > 32:
            raise InputError(f"The point field name '{k}' is longer than the 32 characters "
                             "LAS allows; shorten it.")
        header.add_extra_dim(laspy.ExtraBytesParams(name=k, type=_las_extra_type(cols[k])))
    if crs is not None:
        header.add_crs(crs)
    n = x.size
    with atomic_output(path) as tmp, laspy.open(str(tmp), mode="w", header=header,
                    do_compress=path.suffix.lower() == ".laz") as writer:
        for s in range(0, max(n, 1), chunk):
            feedback.progress(100.0 * s / max(n, 1))
            e = min(s + chunk, n)
            if e <= s:
                break
            rec = laspy.ScaleAwarePointRecord.zeros(e - s, header=header)
            rec.x = x[s:e]
            rec.y = y[s:e]
            rec.z = z[s:e]
            for k, v in cols.items():
                name = k.lower() if k.lower() in LAS_STANDARD_FIELDS else k
                part = v[s:e]
                rec[name] = part.astype(np.uint8) if part.dtype.kind == "b" else part
            writer.write_points(rec)
    feedback.progress(100.0)
    return path


__all__ = ["FORMATS", "read_las", "write_points"]
