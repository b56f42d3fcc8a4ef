r"""Importers for the orientation files users have.

* **Orthority-style OPK CSV** (``filename,x,y,z,omega,phi,kappa``, header optional, extra columns
  allowed, optional ``camera`` column) with the orthority **interior-parameter YAML**;
* **plain OPK text** (``name x y z omega phi kappa [camera]``, whitespace separated, ``#``
  comments);
* **OpenSfM** ``reconstruction.json`` (ODM's ``opensfm/reconstruction.json``).

OPK angles are PATB ω-φ-κ (camera→world, :math:`R = R_x(\omega) R_y(\varphi) R_z(\kappa)`), as
used by orthority; their unit (degrees, gon or radians) must always be stated. The CRS of an OPK
file comes from a ``.prj`` beside it (same stem; WKT, PROJ string or ``EPSG:xxxx``) or from the
``crs`` argument, which wins when both are given.

Orthority interior parameters (from orthority's documentation, ``docs/file_formats/yaml.rst``
and ``csv.rst``): a mapping camera id → parameters with

* ``type``: ``pinhole``, ``brown``, ``opencv`` (``fisheye`` is not supported here);
* ``im_size``: ``[width, height]`` in pixels;
* ``focal_len``: focal length in the units of ``sensor_size`` (a number or an ``[fx, fy]``
  pair). **Without** ``sensor_size`` pixels are square and ``focal_len`` is normalised and
  unitless: focal length divided by max(sensor width, sensor height), i.e.
  :math:`f_{px} = \mathrm{focal\_len}\cdot\max(w, h)`;
* ``sensor_size``: optional ``[width, height]`` (mm for PhotoDEM's purposes);
* ``cx``, ``cy``: principal-point offsets in OpenSfM *normalised image coordinates*: origin at
  the image centre, x right, **y down**, divided by max(w, h) (pixels). Hence in PhotoDEM's
  image frame (mm, y up) :math:`x_p = c_x \max(w,h)\,p_x`, :math:`y_p = -c_y \max(w,h)\,p_y`;
* ``k1, k2, k3, p1, p2``: Brown/OpenCV distortion (same model as :class:`..geometry.camera.Camera`).

When no sensor size is known (normalised focal length, and every OpenSfM camera) PhotoDEM uses a
*nominal* sensor whose larger side is 1 mm: pixel size ``1 / max(w, h)`` mm, so the focal length
in "mm" equals the normalised focal length. Ground geometry (rays, GSD in m) is unaffected.

OpenSfM stores positions in a topocentric frame (east-north-up at ``reference_lla``) and
rotations world→camera as axis-angle (x right, y down, z forward). :func:`read_opensfm`
converts the centres through ECEF into the target CRS (default: the UTM zone of
``reference_lla``, WGS 84 ellipsoidal heights) and carries the rotation along: the camera axes
are offset by ±``d`` from the centre in ENU, transformed, and the rotation is the orthonormal
(polar) factor of the resulting Jacobian, which absorbs the grid convergence and the curvature
between the reference point and the camera.
"""

from __future__ import annotations

import csv
import functools
import io
import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np
import pyproj
import yaml
from numpy.typing import ArrayLike, NDArray

from ..errors import InputError
from ..geometry.camera import Camera
from ..geometry.orientation import ExteriorOrientation, check_angle_unit, opensfm_to_patb
from .model import ImageRecord, Project

PathLike = Union[str, Path]
IMAGE_EXTENSIONS = (".tif", ".tiff", ".jpg", ".jpeg", ".png")
_WGS84_A = 6378137.0
_WGS84_F = 1.0 / 298.257223563


@dataclass
class ImportedImage:
    """One image of an exterior-orientation file, before it is matched to a file."""

    name: str
    eo: ExteriorOrientation
    camera: Optional[str] = None
    source_name: str = ""  # the name as written in the file (may carry an extension)


@dataclass
class ImportedBlock:
    """What an importer read: CRS, cameras (may be empty for OPK files) and images."""

    crs: Optional[str]
    cameras: Dict[str, Camera] = field(default_factory=dict)
    images: List[ImportedImage] = field(default_factory=list)
    warnings: List[str] = field(default_factory=list)


# -- CRS -------------------------------------------------------------------------------------------
def normalise_crs(crs: Any) -> str:
    """A CRS as ``EPSG:xxxx`` when it is exactly an EPSG CRS, else as WKT2.

    Raises
    ------
    InputError
        When pyproj does not understand ``crs``.
    """
    try:
        c = pyproj.CRS.from_user_input(crs)
    except Exception as exc:  # pyproj.exceptions.CRSError
        raise InputError(
            f"The CRS '{str(crs)[:80]}' is not understood ({exc}). Give it as EPSG:xxxx, WKT or "
            "a PROJ string."
        ) from exc
    code = c.to_epsg(min_confidence=100)
    return f"EPSG:{code}" if code else c.to_wkt()


def crs_from_prj(path: PathLike) -> Optional[str]:
    """The CRS in a ``.prj`` beside ``path`` (same stem), or ``None`` when there is none."""
    prj = Path(path).with_suffix(".prj")
    if not prj.is_file():
        return None
    text = prj.read_text(encoding="utf-8", errors="replace").strip()
    if not text:
        return None
    try:
        return normalise_crs(text)
    except InputError as exc:
        raise InputError(f"The CRS in '{prj}' is not understood: {exc}") from exc


def _resolve_crs(path: PathLike, crs: Optional[str], warnings: List[str]) -> Optional[str]:
    from_prj = crs_from_prj(path)
    if crs:
        given = normalise_crs(crs)
        if from_prj is not None and not _same_crs(given, from_prj):
            warnings.append(
                f"The CRS parameter differs from the .prj beside '{Path(path).name}'; "
                "the parameter is used."
            )
        return given
    return from_prj


def _same_crs(a: str, b: str) -> bool:
    return pyproj.CRS.from_user_input(a) == pyproj.CRS.from_user_input(b)


# -- interior orientation ------------------------------------------------------------------------
def _pair(value: Any, what: str) -> Tuple[float, float]:
    if isinstance(value, (list, tuple)):
        if len(value) != 2:
            raise InputError(f"{what} must be one number or a pair [x, y], not {value!r}.")
        return float(value[0]), float(value[1])
    return float(value), float(value)


def camera_from_normalised(name: str, width: int, height: int, focal: Any,
                           cx: float = 0.0, cy: float = 0.0,
                           sensor_size: Optional[Sequence[float]] = None,
                           **distortion: float) -> Camera:
    r"""A :class:`Camera` from orthority/OpenSfM-style interior parameters.

    Parameters
    ----------
    width, height : int
        Image size (pixels).
    focal : float or (float, float)
        Focal length in the units of ``sensor_size``; without ``sensor_size`` normalised by
        max(w, h) (then pixels are square and a nominal 1 mm sensor is used, see module notes).
    cx, cy : float
        Principal-point offsets in normalised image coordinates (y down, / max(w, h)).
    sensor_size : (float, float), optional
        Sensor width and height in mm.
    **distortion
        ``k1, k2, k3, p1, p2`` (others must be zero).

    Notes
    -----
    With :math:`f_x \ne f_y` the y pixel pitch is scaled, :math:`p_y' = p_y f_x / f_y`, so that
    both focal lengths in pixels are kept with the one focal length of :class:`Camera`.
    """
    w, h = int(width), int(height)
    s = float(max(w, h))
    fx, fy = _pair(focal, f"Camera '{name}': focal_len")
    if sensor_size is not None:
        sw, sh = _pair(sensor_size, f"Camera '{name}': sensor_size")
        px, py = sw / w, sh / h
    else:
        px = py = 1.0 / s  # nominal: larger sensor side = 1 "mm"
    if not (fx > 0 and fy > 0):
        raise InputError(f"Camera '{name}': focal length must be positive, not {focal!r}.")
    if fx != fy:
        py = py * fx / fy
    supported = {"k1", "k2", "k3", "p1", "p2"}
    extra = {k: float(v) for k, v in distortion.items() if k not in supported and float(v) != 0}
    if extra:
        raise InputError(
            f"Camera '{name}': distortion coefficients {', '.join(sorted(extra))} are not "
            "supported (PhotoDEM uses Brown k1-k3, p1-p2)."
        )
    dist = {k: float(distortion.get(k, 0.0) or 0.0) for k in supported}
    return Camera(
        name=name, width=w, height=h, focal_length=fx, pixel_size=(px, py),
        principal_point=(float(cx) * s * px + 0.0, -float(cy) * s * py + 0.0), **dist,
    )


def read_interior_yaml(path: PathLike) -> Dict[str, Camera]:
    """Cameras from an orthority interior-parameter YAML (see module notes).

    Raises
    ------
    InputError
        When the file is not such a YAML or a camera is incomplete or unsupported.
    """
    path = Path(path)
    try:
        data = yaml.safe_load(path.read_text(encoding="utf-8"))
    except Exception as exc:
        raise InputError(f"Cannot read the interior parameters '{path}': {exc}") from exc
    if not isinstance(data, dict) or not data:
        raise InputError(f"'{path}' holds no cameras (expected 'camera id: {{type, im_size, …}}').")
    cameras: Dict[str, Camera] = {}
    for name, d in data.items():
        name = str(name)
        if not isinstance(d, dict):
            raise InputError(f"'{path}': camera '{name}' is not a mapping of parameters.")
        kind = str(d.get("type", "pinhole")).lower()
        if kind not in ("pinhole", "brown", "opencv"):
            raise InputError(
                f"'{path}': camera '{name}' has type '{kind}'; PhotoDEM supports pinhole, brown "
                "and opencv (frame cameras with Brown distortion)."
            )
        try:
            w, h = (int(v) for v in d["im_size"])
            focal = d["focal_len"]
        except (KeyError, TypeError, ValueError) as exc:
            raise InputError(
                f"'{path}': camera '{name}' needs im_size [width, height] and focal_len."
            ) from exc
        dist = {k: v for k, v in d.items()
                if k not in ("type", "im_size", "focal_len", "sensor_size", "cx", "cy")}
        if kind == "pinhole" and any(float(v) for v in dist.values()):
            raise InputError(f"'{path}': pinhole camera '{name}' cannot have distortion.")
        cameras[name] = camera_from_normalised(
            name, w, h, focal, cx=float(d.get("cx", 0.0) or 0.0),
            cy=float(d.get("cy", 0.0) or 0.0), sensor_size=d.get("sensor_size"), **dist,
        )
    return cameras


# -- OPK CSV and text ------------------------------------------------------------------------------
_OPK_FIELDS = ("filename", "x", "y", "z", "omega", "phi", "kappa")
#: Other header names of the OPK fields (orthority's older CSVs: easting, northing, altitude).
_OPK_ALIASES = {"easting": "x", "northing": "y", "altitude": "z", "image": "filename",
                "name": "filename", "camera_id": "camera"}


def sniff_csv_dialect(lines: Sequence[str]) -> Tuple[str, str]:
    """Delimiter (comma, semicolon, tab or space) and quote character (``"`` or ``'``) of CSV
    lines, from their first rows.

    Orthority's example files are space separated with single-quoted fields
    (``'filename' 'x' … 'camera'`` and quoted camera names that contain spaces); spreadsheets
    write comma or semicolon CSV with double quotes.
    """
    sample = "\n".join(lines[:20])
    try:
        dialect = csv.Sniffer().sniff(sample, delimiters=",;\t ")
        delimiter, quote = dialect.delimiter, dialect.quotechar or '"'
    except csv.Error:  # too few rows or no consistent delimiter: count in the first line
        first = lines[0]
        delimiter = next((d for d in (",", ";", "\t") if d in first), " ")
        quote = "'" if first.lstrip().startswith("'") else '"'
    return delimiter, quote


def _opk_header_index(header: Sequence[str], path: Path) -> Tuple[List[int], Optional[int]]:
    """Column indices of the OPK fields (and of ``camera``, if any) in a header row, matched
    case-insensitively after stripping quotes; an InputError naming the header found."""
    names = [c.strip().strip("'\"").strip().lower() for c in header]
    names = [_OPK_ALIASES.get(n, n) for n in names]
    missing = [f for f in _OPK_FIELDS if f not in names]
    if missing:
        found = ", ".join(f"'{c.strip()}'" for c in header)
        raise InputError(
            f"'{path}': the header lacks {', '.join(missing)}; it has {found}. Expected "
            f"{','.join(_OPK_FIELDS)} (any case, comma, semicolon, tab or space separated, "
            "optionally quoted; and optionally camera)."
        )
    cam = names.index("camera") if "camera" in names else None
    return [names.index(f) for f in _OPK_FIELDS], cam


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _opk_image(name: str, values: Sequence[str], unit: str, where: str,
               camera: Optional[str]) -> ImportedImage:
    try:
        x, y, z, omega, phi, kappa = (float(v) for v in values)
    except ValueError as exc:
        raise InputError(f"{where}: x, y, z, omega, phi, kappa must be numbers ({exc}).") from exc
    eo = ExteriorOrientation.from_opk([x, y, z], omega, phi, kappa, unit=unit)
    return ImportedImage(name=_stem(name), eo=eo, camera=camera or None, source_name=name)


def _stem(name: str) -> str:
    p = Path(name.strip())
    return p.stem if p.suffix.lower() in IMAGE_EXTENSIONS else p.name


def read_opk_csv(path: PathLike, *, angle_unit: str, crs: Optional[str] = None) -> ImportedBlock:
    """Exterior orientation from an orthority-style OPK CSV.

    Parameters
    ----------
    path : path
        CSV with the fields ``filename, x, y, z, omega, phi, kappa`` (and optionally ``camera``
        and others, ignored). With a header the columns are found by name (any case, quoted or
        not; ``easting, northing, altitude`` for x, y, z); without one they are taken in that
        order. Comma, semicolon, tab or space delimited, fields optionally quoted with ``"`` or
        ``'`` (the delimiter and the quote are sniffed: orthority's space-separated, quoted
        files are read as they are).
    angle_unit : {"degrees", "gon", "radians"}
        Unit of ω, φ, κ (required: never guessed).
    crs : str, optional
        CRS of x, y, z; default from the ``.prj`` beside the CSV.
    """
    unit = check_angle_unit(angle_unit)
    path = Path(path)
    text = path.read_text(encoding="utf-8-sig", errors="replace")
    lines = [ln for ln in text.splitlines() if ln.strip() and not ln.lstrip().startswith("#")]
    if not lines:
        raise InputError(f"'{path}' holds no exterior orientation rows.")
    delimiter, quote = sniff_csv_dialect(lines)
    rows = [[c.strip() for c in r] for r in
            csv.reader(io.StringIO("\n".join(lines)), delimiter=delimiter, quotechar=quote,
                       skipinitialspace=True)]
    rows = [[c for c in r if c != ""] if delimiter == " " else r for r in rows]
    first = rows[0]
    if len(first) >= 4 and not _is_number(first[1]):  # a header row
        idx, cam_idx = _opk_header_index(first, path)
        body, first_line = rows[1:], 2
    else:
        idx, cam_idx, body, first_line = list(range(7)), None, rows, 1
    warnings: List[str] = []
    block = ImportedBlock(crs=_resolve_crs(path, crs, warnings), warnings=warnings)
    for n, row in enumerate(body, start=first_line):
        if len(row) < max(idx) + 1:
            raise InputError(f"'{path}' line {n}: expected {max(idx) + 1} fields, got {len(row)}.")
        camera = row[cam_idx] if cam_idx is not None and cam_idx < len(row) else None
        block.images.append(_opk_image(row[idx[0]], [row[i] for i in idx[1:]], unit,
                                       f"'{path}' line {n}", camera))
    return block


def read_opk_text(path: PathLike, *, angle_unit: str, crs: Optional[str] = None
                  ) -> ImportedBlock:
    """Exterior orientation from a plain text list ``name x y z omega phi kappa [camera]``.

    Whitespace separated, ``#`` starts a comment; see :func:`read_opk_csv` for the arguments.
    """
    unit = check_angle_unit(angle_unit)
    path = Path(path)
    warnings: List[str] = []
    block = ImportedBlock(crs=_resolve_crs(path, crs, warnings), warnings=warnings)
    for n, line in enumerate(path.read_text(encoding="utf-8-sig", errors="replace").splitlines(),
                             start=1):
        fields = line.split("#", 1)[0].split()
        if not fields:
            continue
        if len(fields) < 7:
            raise InputError(
                f"'{path}' line {n}: expected 'name x y z omega phi kappa', got {len(fields)} "
                "fields."
            )
        if n == 1 and not _is_number(fields[1]):  # a header line
            continue
        camera = fields[7] if len(fields) > 7 else None
        block.images.append(_opk_image(fields[0], fields[1:7], unit, f"'{path}' line {n}",
                                       camera))
    if not block.images:
        raise InputError(f"'{path}' holds no exterior orientation rows.")
    return block


# -- OpenSfM ---------------------------------------------------------------------------------------
def _ecef_from_enu_matrix(lat_deg: float, lon_deg: float) -> NDArray[np.float64]:
    """Columns: east, north, up unit vectors of the local frame at (lat, lon) in ECEF."""
    lat, lon = math.radians(lat_deg), math.radians(lon_deg)
    sl, cl, sp, cp = math.sin(lon), math.cos(lon), math.sin(lat), math.cos(lat)
    return np.array([[-sl, -sp * cl, cp * cl],
                     [cl, -sp * sl, cp * sl],
                     [0.0, cp, sp]])


def _lla_to_ecef(lat: float, lon: float, alt: float) -> NDArray[np.float64]:
    e2 = _WGS84_F * (2.0 - _WGS84_F)
    la, lo = math.radians(lat), math.radians(lon)
    n = _WGS84_A / math.sqrt(1.0 - e2 * math.sin(la) ** 2)
    return np.array([(n + alt) * math.cos(la) * math.cos(lo),
                     (n + alt) * math.cos(la) * math.sin(lo),
                     (n * (1.0 - e2) + alt) * math.sin(la)])


def utm_crs_of(lat: float, lon: float) -> str:
    """``EPSG:326zz`` / ``EPSG:327zz``: the WGS 84 UTM zone of a point."""
    zone = math.floor((lon + 180.0) / 6.0) % 60 + 1
    return f"EPSG:{(32600 if lat >= 0 else 32700) + zone}"


@functools.lru_cache(maxsize=16)
def _ecef_transformer(crs: str, inverse: bool = False) -> Any:
    target = pyproj.CRS.from_user_input(crs)
    if not target.is_projected and not target.is_geographic:
        raise InputError(f"The target CRS '{target.name}' must be projected or geographic.")
    target3d = target.to_3d() if len(target.axis_info) < 3 else target
    src, dst = pyproj.CRS.from_epsg(4978), target3d
    if inverse:
        src, dst = dst, src
    return pyproj.Transformer.from_crs(src, dst, always_xy=True)


def enu_to_crs(points: ArrayLike, reference_lla: Sequence[float], crs: str) -> NDArray[np.float64]:
    r"""Topocentric ENU points (..., 3) at ``reference_lla`` → ``crs`` (x, y, ellipsoidal h).

    :math:`X_{ECEF} = X_0 + M\,(e, n, u)^T` with :math:`M` the ENU→ECEF matrix at the reference
    (WGS 84), then pyproj ECEF → ``crs`` (promoted to 3-D; heights stay ellipsoidal).
    """
    lat, lon, alt = (float(v) for v in reference_lla)
    p = np.asarray(points, dtype=float)
    ecef = _lla_to_ecef(lat, lon, alt) + p @ _ecef_from_enu_matrix(lat, lon).T
    t = _ecef_transformer(crs)
    x, y, z = t.transform(ecef[..., 0], ecef[..., 1], ecef[..., 2])
    return np.stack([np.asarray(x), np.asarray(y), np.asarray(z)], axis=-1)


def crs_to_enu(points: ArrayLike, reference_lla: Sequence[float], crs: str) -> NDArray[np.float64]:
    """Inverse of :func:`enu_to_crs`."""
    lat, lon, alt = (float(v) for v in reference_lla)
    p = np.asarray(points, dtype=float)
    t = _ecef_transformer(crs, inverse=True)
    x, y, z = t.transform(p[..., 0], p[..., 1], p[..., 2])
    ecef = np.stack([np.asarray(x), np.asarray(y), np.asarray(z)], axis=-1)
    return (ecef - _lla_to_ecef(lat, lon, alt)) @ _ecef_from_enu_matrix(lat, lon)


def transform_pose(eo: ExteriorOrientation, transform: Any, step: float = 10.0
                   ) -> ExteriorOrientation:
    r"""Carry a pose through a point transformation (e.g. ENU → map CRS).

    The centre is transformed; the rotation is the orthonormal polar factor of the Jacobian
    :math:`J_{:,i} \approx (T(C + d\,r_i) - T(C - d\,r_i)) / 2d` along the camera axes
    :math:`r_i` (columns of R), :math:`R' = U V^T` from the SVD :math:`J = U S V^T`. Central
    differences make the error :math:`O(d^2)` (≈ 1e-12 rad for d = 10 m on the Earth).

    Parameters
    ----------
    transform : callable
        Maps points (..., 3) to points (..., 3).
    """
    C, R = eo.position, eo.rotation
    pts = np.concatenate([C[None], C + step * R.T, C - step * R.T])  # rows: C, C+d r_i, C-d r_i
    out = np.asarray(transform(pts), dtype=float)
    J = (out[1:4] - out[4:7]).T / (2.0 * step)
    U, _, Vt = np.linalg.svd(J)
    R_new = U @ Vt
    if np.linalg.det(R_new) < 0:  # a left-handed target (e.g. lat/lon axis order) is unusable
        raise InputError("The target CRS has left-handed axes; choose a projected CRS (x east).")
    return ExteriorOrientation(out[0], R_new)


def _opensfm_camera(name: str, d: Dict[str, Any]) -> Camera:
    kind = str(d.get("projection_type", "perspective")).lower()
    if kind not in ("perspective", "brown", "simple_radial", "radial"):
        raise InputError(
            f"OpenSfM camera '{name}' has projection_type '{kind}'; PhotoDEM supports "
            "perspective, simple_radial, radial and brown frame cameras."
        )
    w, h = int(d["width"]), int(d["height"])
    if "focal" in d:
        focal: Any = float(d["focal"])
    else:
        focal = [float(d["focal_x"]), float(d.get("focal_y", d["focal_x"]))]
    dist = {k: float(d.get(k, 0.0)) for k in ("k1", "k2", "k3", "p1", "p2")}
    return camera_from_normalised(name, w, h, focal, cx=float(d.get("c_x", 0.0)),
                                  cy=float(d.get("c_y", 0.0)), **dist)


def read_opensfm(path: PathLike, crs: Optional[str] = None,
                 reconstruction: Optional[int] = None) -> ImportedBlock:
    """Cameras and poses from an OpenSfM/ODM ``reconstruction.json``.

    Parameters
    ----------
    path : path
        The ``reconstruction.json`` (a list of reconstructions).
    crs : str, optional
        Target CRS; default the WGS 84 UTM zone of ``reference_lla``.
    reconstruction : int, optional
        Import only this reconstruction (0 = the largest, first one); default all.

    Notes
    -----
    ``reference_lla`` is read from the reconstruction, else from ``reference_lla.json`` beside
    the file. Shot names lose their image extension (``DJI_0001.JPG`` → ``DJI_0001``).
    """
    path = Path(path)
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except Exception as exc:
        raise InputError(f"Cannot read the OpenSfM reconstruction '{path}': {exc}") from exc
    recs = data if isinstance(data, list) else [data]
    if reconstruction is not None:
        if not 0 <= reconstruction < len(recs):
            raise InputError(f"'{path}' has {len(recs)} reconstruction(s), not #{reconstruction}.")
        recs = [recs[reconstruction]]
    warnings: List[str] = []
    block: Optional[ImportedBlock] = None
    seen: Dict[str, str] = {}
    for rec in recs:
        if not isinstance(rec, dict) or "shots" not in rec or "cameras" not in rec:
            raise InputError(f"'{path}' is not an OpenSfM reconstruction (no cameras/shots).")
        lla = rec.get("reference_lla")
        if lla is None:
            side = path.with_name("reference_lla.json")
            if not side.is_file():
                raise InputError(
                    f"'{path}' has no reference_lla and there is no reference_lla.json beside "
                    "it; the topocentric coordinates cannot be georeferenced."
                )
            lla = json.loads(side.read_text(encoding="utf-8"))
        ref = (float(lla["latitude"]), float(lla["longitude"]), float(lla["altitude"]))
        if block is None:
            target = normalise_crs(crs) if crs else utm_crs_of(ref[0], ref[1])
            block = ImportedBlock(crs=target, warnings=warnings)
        assert block.crs is not None
        target_crs = block.crs
        for cam_name, cam in rec["cameras"].items():
            if cam_name not in block.cameras:
                block.cameras[cam_name] = _opensfm_camera(cam_name, cam)
        for shot_name, shot in rec["shots"].items():
            pose = opensfm_to_patb(shot["rotation"], shot["translation"])
            eo = transform_pose(pose, lambda p, r=ref, c=target_crs: enu_to_crs(p, r, c))
            name = _stem(shot_name)
            if name in seen:
                raise InputError(f"'{path}': image '{name}' appears in two reconstructions.")
            seen[name] = shot_name
            block.images.append(ImportedImage(name=name, eo=eo, camera=str(shot["camera"]),
                                              source_name=shot_name))
    if block is None or not block.images:
        raise InputError(f"'{path}' holds no oriented images.")
    return block


# -- detection and project assembly --------------------------------------------------------------
def detect_exterior_format(path: PathLike) -> str:
    """``"opensfm"``, ``"csv"`` or ``"text"`` from the extension and the first lines."""
    path = Path(path)
    if path.suffix.lower() == ".json":
        return "opensfm"
    with open(path, encoding="utf-8-sig", errors="replace") as f:
        head = f.read(4096)
    if head.lstrip().startswith(("[", "{")):
        return "opensfm"
    for line in head.splitlines():
        if line.strip() and not line.lstrip().startswith("#"):
            quoted = '"' in line or "'" in line  # orthority's quoted, space-separated CSV
            return "csv" if ("," in line or ";" in line or quoted
                             or path.suffix.lower() == ".csv") else "text"
    raise InputError(f"'{path}' is empty.")


def find_image_file(folder: PathLike, name: str) -> Optional[Path]:
    """The image file for ``name`` in ``folder``: exact name, then name + a known extension.

    The match is case-sensitive first, then case-insensitive (``.TIF`` vs ``.tif``).
    """
    folder = Path(folder)
    for candidate in [name, *(name + ext for ext in IMAGE_EXTENSIONS)]:
        p = folder / candidate
        if p.is_file():
            return p
    stem = _stem(name).lower()
    for p in sorted(folder.iterdir()) if folder.is_dir() else []:
        if p.is_file() and p.suffix.lower() in IMAGE_EXTENSIONS and p.stem.lower() == stem:
            return p
    return None


def read_exterior(path: PathLike, *, angle_unit: Optional[str] = None,
                  crs: Optional[str] = None) -> ImportedBlock:
    """Read any supported exterior-orientation file (format from :func:`detect_exterior_format`).

    ``angle_unit`` is required for OPK files and ignored for OpenSfM.
    """
    kind = detect_exterior_format(path)
    if kind == "opensfm":
        return read_opensfm(path, crs=crs)
    if angle_unit is None:
        raise InputError("The angle unit of OPK files must be given (degrees, gon or radians).")
    reader = read_opk_csv if kind == "csv" else read_opk_text
    return reader(path, angle_unit=angle_unit, crs=crs)


def import_project(
    root: PathLike,
    images: PathLike,
    exterior: PathLike,
    interior: Optional[PathLike] = None,
    *,
    crs: Optional[str] = None,
    angle_unit: Optional[str] = None,
    name: Optional[str] = None,
) -> Tuple[Project, List[str]]:
    """Assemble a :class:`Project` (not saved) from an images folder and orientation files.

    Parameters
    ----------
    root : path
        The project folder the paths are made relative to (it need not exist yet).
    images : path
        Folder with the image files; names in the exterior file are matched with or without
        extension (:data:`IMAGE_EXTENSIONS`).
    exterior : path
        OPK CSV, OPK text or OpenSfM ``reconstruction.json``.
    interior : path, optional
        Orthority camera YAML; required for OPK files, optional for OpenSfM (its cameras win).
    crs : str, optional
        Project CRS; for OPK files default from the ``.prj`` beside ``exterior``.
    angle_unit : {"degrees", "gon", "radians"}
        Required for OPK files.

    Returns
    -------
    project : Project
        Images whose file was not found keep the path ``<images>/<name>`` (validation reports
        them).
    warnings : list of str

    Raises
    ------
    InputError
        Unreadable files, no CRS, no or ambiguous camera.
    """
    block = read_exterior(exterior, angle_unit=angle_unit, crs=crs)
    warnings = list(block.warnings)
    if block.crs is None:
        raise InputError(
            f"No CRS for '{Path(exterior).name}': give the crs parameter or put a .prj file "
            f"('{Path(exterior).with_suffix('.prj').name}') beside it."
        )
    cameras = dict(block.cameras)
    if interior is not None:
        cameras.update(read_interior_yaml(interior))
    elif not cameras:
        raise InputError(
            "OPK files carry no interior orientation: give the camera YAML (interior parameter)."
        )
    project = Project(root=Path(root), name=name or Path(root).name, crs=block.crs,
                      cameras=cameras, angle_unit="degrees")
    for img in block.images:
        cam = img.camera
        if cam is None:
            if len(cameras) != 1:
                raise InputError(
                    f"Image '{img.name}' names no camera but the interior file has "
                    f"{len(cameras)} ({', '.join(cameras)}); add a 'camera' column."
                )
            cam = next(iter(cameras))
        found = find_image_file(images, img.source_name or img.name)
        path = found if found is not None else Path(images) / (img.source_name or img.name)
        project.images.append(ImageRecord(name=img.name, path=project.relative_path(path),
                                          camera=cam, eo=img.eo))
    return project, warnings


__all__ = [
    "IMAGE_EXTENSIONS",
    "ImportedBlock",
    "ImportedImage",
    "camera_from_normalised",
    "crs_from_prj",
    "crs_to_enu",
    "detect_exterior_format",
    "enu_to_crs",
    "find_image_file",
    "import_project",
    "normalise_crs",
    "read_exterior",
    "read_interior_yaml",
    "read_opensfm",
    "read_opk_csv",
    "read_opk_text",
    "transform_pose",
    "utm_crs_of",
]
