r"""OpenSfM and OpenDroneMap (ODM) reconstructions, each read in the frame it is written in.

OpenSfM's ``reconstruction.json`` is a list of reconstructions with ``cameras`` and ``shots``;
a shot's ``rotation`` is the world→camera axis-angle vector (camera x right, y down, z forward)
and ``translation`` is :math:`t = -R\,C`, so the centre is :math:`C = -R^T t`. The world frame
depends on who wrote the file:

``topocentric`` (plain OpenSfM; ODM's ``opensfm/reconstruction.topocentric.json``)
    East-north-up in metres at ``reference_lla`` (latitude, longitude, altitude on WGS 84), given
    in the reconstruction or in ``reference_lla.json`` beside it.
``odm_utm`` (ODM's ``opensfm/reconstruction.json`` of a georeferenced project)
    ODM runs OpenSfM's ``export_geocoords --reconstruction --offset-x X --offset-y Y`` and
    replaces ``reconstruction.json`` by its result (keeping the original as
    ``reconstruction.topocentric.json``): a linear map fitted at the reference point takes ENU
    to WGS 84 UTM minus the offset, :math:`C' = A\,C + b` with
    :math:`A_{:,i} = P(e_i) - P(0)`, :math:`b = P(0) - (X, Y, 0)` (``P``: ENU → UTM easting,
    northing, ellipsoidal height; ``e_i`` the unit steps), and :math:`R' = R\,A^{-1}`. The
    UTM zone and offset are the two first lines of ``odm_georeferencing/coords.txt``
    (``WGS84 UTM 32N`` / ``X Y``; older ODM: ``odm_georeferencing_model_geo.txt``), and ODM
    puts ``reference_lla`` at that offset with altitude 0. The map is already grid-aligned:
    reading it as ENU would turn the block by the grid convergence once more (the bug of
    issue 22: 0.9° at −0.86° convergence).

OpenSfM's ``Pose`` keeps :math:`R A^{-1}` as it is — not quite a rotation: :math:`A` carries the
UTM scale factor (0.9996 on the central meridian) — and writes Eigen's axis-angle of it
(:func:`eigen_angle_axis`; up to 60″ from the nearest rotation) and
:math:`t = -R A^{-1} C'`. PhotoDEM inverts exactly this (:func:`odm_utm_to_enu`: the rotation
by Newton iterations, then :math:`C = -R^T t - A^{-1} b`) and converts the topocentric poses
through ECEF to the target CRS (:func:`enu_to_crs`, :func:`transform_pose`), so both ODM files
give the same poses. ODM's own tools read the file's poses as they stand (centre
:math:`-R_{file}^T t`, i.e. without the scale factor; plus the offset), and so do its DSM and
orthophoto: that frame departs from the exact one by about :math:`(1-k)\,d` horizontally and
:math:`d^2/2R_E` vertically at a distance :math:`d` from the reference (0.13 m and 7 mm at
300 m on the central meridian, 0.44 m and 8 cm at 1 km); the import reports the largest
difference in the block.

Shots may carry ``gps_position`` (the image's GPS, always topocentric: ``export_geocoords``
leaves it as it is). Every import compares the camera centres with them — median and largest
distance and the angle of a fitted 2-D similarity — and warns when the angle exceeds 0.1° or a
distance 5 m. When nothing beside the file tells the frame (no ``coords.txt``, no topocentric
file), both readings are tried and the one that agrees with the GPS positions is taken (ODM's
reference point is recognised by its whole-metre UTM position at altitude 0).
"""

from __future__ import annotations

import functools
import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple

import numpy as np
import pyproj
from numpy.typing import ArrayLike, NDArray

from ..errors import InputError
from ..geometry.camera import Camera
from ..geometry.orientation import (
    FLIP_YZ,
    ExteriorOrientation,
    axis_angle_to_matrix,
    matrix_to_axis_angle,
    opensfm_to_patb,
)
from .importers_common import (
    ImportedBlock,
    ImportedImage,
    PathLike,
    camera_from_normalised,
    image_stem,
    normalise_crs,
)

_WGS84_A = 6378137.0
_WGS84_F = 1.0 / 298.257223563
FRAME_TOPOCENTRIC = "topocentric"
FRAME_ODM_UTM = "odm_utm"
FRAMES = (FRAME_TOPOCENTRIC, FRAME_ODM_UTM)
TOPOCENTRIC_NAME = "reconstruction.topocentric.json"
#: limits of the GPS check: above them the import warns that the frame may be wrong
GPS_MAX_ROTATION_DEG = 0.1
GPS_MAX_DISTANCE_M = 5.0
LLA = Tuple[float, float, float]


# -- geodesy ---------------------------------------------------------------------------------------
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


def polar_rotation(matrix: ArrayLike) -> NDArray[np.float64]:
    """The orthonormal polar factor :math:`U V^T` of a 3×3 matrix (:math:`M = U S V^T`).

    Raises
    ------
    InputError
        When the factor is a reflection (a left-handed frame, e.g. lat/lon axis order).
    """
    U, _, Vt = np.linalg.svd(np.asarray(matrix, dtype=float))
    R = U @ Vt
    if np.linalg.det(R) < 0:
        raise InputError("The target CRS has left-handed axes; choose a projected CRS (x east).")
    return R


def transform_pose(eo: ExteriorOrientation, transform: Callable[[Any], Any], step: float = 10.0
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
    return ExteriorOrientation(out[0], polar_rotation(J))


# -- ODM's linearised UTM frame ------------------------------------------------------------------
@dataclass(frozen=True)
class OdmGeoref:
    """ODM's georeferencing: the WGS 84 UTM CRS and the whole-metre offset of ``coords.txt``."""

    crs: str
    offset: Tuple[float, float]
    source: str  # the file it came from, or "reference_lla"


def odm_affine(reference_lla: Sequence[float], georef: OdmGeoref
               ) -> Tuple[NDArray[np.float64], NDArray[np.float64]]:
    """ODM's (OpenSfM ``export_geocoords``) map ENU → UTM − offset: ``(A, b)``, x' = A x + b.

    The columns of ``A`` are the UTM images of the unit ENU steps at the reference minus the
    image of the reference; ``b`` is the reference's image minus the offset (height kept).
    """
    steps = np.array([[1.0, 0, 0], [0, 1.0, 0], [0, 0, 1.0], [0, 0, 0]])
    q = enu_to_crs(steps, reference_lla, georef.crs)
    A = (q[:3] - q[3]).T
    b = q[3] - np.array([georef.offset[0], georef.offset[1], 0.0])
    return A, b


def eigen_angle_axis(matrix: ArrayLike) -> NDArray[np.float64]:
    r"""The axis-angle vector Eigen's ``AngleAxisd(Matrix3d)`` gives for a 3×3 matrix, also one
    that is not orthonormal (as OpenSfM stores ODM's :math:`R A^{-1}`).

    Eigen goes through an unnormalised quaternion (Shoemake: from the trace, else from the
    largest diagonal element) and takes the angle :math:`2\,\mathrm{atan2}(|v|, |w|)`; for a
    rotation matrix this is the ordinary axis-angle vector.
    """
    m = np.asarray(matrix, dtype=float)
    trace = float(np.trace(m))
    v = np.zeros(3)
    if trace > 0.0:
        root = math.sqrt(trace + 1.0)
        w = 0.5 * root
        v[:] = np.array([m[2, 1] - m[1, 2], m[0, 2] - m[2, 0], m[1, 0] - m[0, 1]]) * (0.5 / root)
    else:
        i = 1 if m[1, 1] > m[0, 0] else 0
        i = 2 if m[2, 2] > m[i, i] else i
        j, k = (i + 1) % 3, (i + 2) % 3
        root = math.sqrt(m[i, i] - m[j, j] - m[k, k] + 1.0)
        v[i] = 0.5 * root
        w = (m[k, j] - m[j, k]) * (0.5 / root)
        v[j] = (m[j, i] + m[i, j]) * (0.5 / root)
        v[k] = (m[k, i] + m[i, k]) * (0.5 / root)
    n = float(np.linalg.norm(v))
    if n == 0.0:
        return np.zeros(3)
    return (v / n if w >= 0 else -v / n) * 2.0 * math.atan2(n, abs(w))


def enu_to_odm_utm(eo: ExteriorOrientation, A: NDArray[np.float64], b: NDArray[np.float64]
                   ) -> Tuple[NDArray[np.float64], NDArray[np.float64]]:
    r"""OpenSfM's ``rotation`` and ``translation`` of a topocentric pose after ODM's
    ``export_geocoords``: world→camera :math:`M = R A^{-1}` (not quite orthonormal: the UTM
    scale factor), origin :math:`C' = A C + b`, stored as OpenSfM's ``Pose`` does —
    ``rotation`` = Eigen's axis-angle of :math:`M` (:func:`eigen_angle_axis`),
    ``translation`` = :math:`-M C'`."""
    m = FLIP_YZ @ eo.rotation.T @ np.linalg.inv(A)
    return -eigen_angle_axis(m.T), -m @ (A @ eo.position + b)


def odm_utm_to_enu(rotation: ArrayLike, translation: ArrayLike, A: NDArray[np.float64],
                   b: NDArray[np.float64]) -> ExteriorOrientation:
    """The topocentric pose of a shot of ODM's UTM-with-offset file (exact inverse of
    :func:`enu_to_odm_utm`): the rotation R for which Eigen's axis-angle of :math:`R A^{-1}`
    is the file's (Newton, from the polar factor; < 1e-14 rad), then :math:`C = -R^T t -
    A^{-1} b`."""
    target = axis_angle_to_matrix(rotation)
    a_inv = np.linalg.inv(A)

    def error(r: NDArray[np.float64]) -> NDArray[np.float64]:
        return matrix_to_axis_angle(axis_angle_to_matrix(-eigen_angle_axis((r @ a_inv).T))
                                    @ target.T)

    R = polar_rotation(target @ A)
    for _ in range(10):
        err = error(R)
        if float(np.linalg.norm(err)) < 1e-14:
            break
        h = 1e-7
        J = np.column_stack([(error(axis_angle_to_matrix(h * e) @ R) - err) / h
                             for e in np.eye(3)])
        R = axis_angle_to_matrix(np.linalg.solve(J, -err)) @ R
    t = np.asarray(translation, dtype=float)
    return ExteriorOrientation(-R.T @ t - a_inv @ b, R.T @ FLIP_YZ)


def parse_odm_coords(path: PathLike) -> OdmGeoref:
    """The CRS and offset of ODM's ``coords.txt`` (or ``odm_georeferencing_model_geo.txt``).

    Line 1: ``WGS84 UTM <zone><N|S>`` (or ``EPSG:xxxx`` / a PROJ string); line 2: ``X Y``.
    """
    path = Path(path)
    lines = [ln.strip() for ln in path.read_text(encoding="utf-8", errors="replace").splitlines()]
    if len(lines) < 2:
        raise InputError(f"'{path}' needs the CRS on line 1 and the offset 'X Y' on line 2.")
    head = lines[0].split()
    try:
        if len(head) == 3 and head[0].upper() == "WGS84" and head[1].upper() == "UTM":
            zone, hemi = int(head[2][:-1]), head[2][-1].upper()
            if not 1 <= zone <= 60 or hemi not in "NS":
                raise ValueError(head[2])
            crs = f"EPSG:{(32600 if hemi == 'N' else 32700) + zone}"
        else:
            crs = normalise_crs(lines[0].strip("'"))  # ODM allows a quoted PROJ string
        x_off, y_off = (float(v) for v in lines[1].split()[:2])
    except (ValueError, IndexError) as exc:
        raise InputError(
            f"'{path}': expected 'WGS84 UTM <zone><N|S>' (or EPSG:xxxx) on line 1 and the "
            f"offset 'X Y' on line 2, found '{lines[0]}' / '{lines[1]}'."
        ) from exc
    return OdmGeoref(crs, (x_off, y_off), path.name)


def odm_georef_from_reference(reference_lla: LLA) -> Optional[OdmGeoref]:
    """ODM's georeferencing guessed from ``reference_lla`` alone: ODM puts it on the whole-metre
    UTM offset at altitude 0; any other reference (OpenSfM's mean GPS position) gives ``None``."""
    lat, lon, alt = reference_lla
    if alt != 0.0:
        return None
    crs = utm_crs_of(lat, lon)
    e, n, _ = enu_to_crs(np.zeros(3), reference_lla, crs)
    if abs(e - round(e)) > 1e-3 or abs(n - round(n)) > 1e-3:
        return None
    return OdmGeoref(crs, (float(round(e)), float(round(n))), "reference_lla")


# -- where the files are ---------------------------------------------------------------------------
@dataclass(frozen=True)
class OpensfmSource:
    """A reconstruction file and what lies around it."""

    reconstruction: Path
    frame: Optional[str]  # None: decided by the GPS positions
    coords: Optional[Path]  # ODM's coords.txt (or the older model_geo.txt)
    why: str  # how the frame was found, for the report


def _odm_coords_file(project_root: Path) -> Optional[Path]:
    for name in ("coords.txt", "odm_georeferencing_model_geo.txt"):
        p = project_root / "odm_georeferencing" / name
        if p.is_file():
            return p
    return None


def locate_opensfm(path: PathLike) -> OpensfmSource:
    """The reconstruction to read and its frame, for an ODM project folder, an ``opensfm``
    folder or a reconstruction file.

    An ODM project or ``opensfm`` folder gives its ``reconstruction.json`` (the frame of ODM's
    products). ``reconstruction.topocentric.json`` is topocentric; a ``reconstruction.json``
    with that file beside it is in ODM's UTM frame; with only ``coords.txt`` or nothing beside
    it the frame is left to the GPS check.
    """
    path = Path(path)
    if path.is_dir():
        folder = path / "opensfm" if (path / "opensfm").is_dir() else path
        for name in ("reconstruction.json", TOPOCENTRIC_NAME):
            if (folder / name).is_file():
                path = folder / name
                break
        else:
            raise InputError(
                f"'{path}' holds neither an ODM project (opensfm/reconstruction.json) nor an "
                "OpenSfM reconstruction (reconstruction.json)."
            )
    if not path.is_file():
        raise InputError(f"The OpenSfM reconstruction '{path}' does not exist.")
    coords = _odm_coords_file(path.parent.parent)
    if path.name == TOPOCENTRIC_NAME:
        return OpensfmSource(path, FRAME_TOPOCENTRIC, coords, f"the name {TOPOCENTRIC_NAME}")
    if (path.parent / TOPOCENTRIC_NAME).is_file():
        return OpensfmSource(path, FRAME_ODM_UTM, coords,
                             f"ODM's {TOPOCENTRIC_NAME} lies beside it")
    return OpensfmSource(path, None, coords, "")


# -- reading -------------------------------------------------------------------------------------
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


def _load_reconstructions(path: Path, reconstruction: Optional[int]) -> List[Dict[str, Any]]:
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except Exception as exc:
        raise InputError(f"Cannot read the OpenSfM reconstruction '{path}': {exc}") from exc
    recs = data if isinstance(data, list) else [data]
    if reconstruction is not None:
        if not 0 <= reconstruction < len(recs):
            raise InputError(f"'{path}' has {len(recs)} reconstruction(s), not #{reconstruction}.")
        recs = [recs[reconstruction]]
    for rec in recs:
        if not isinstance(rec, dict) or "shots" not in rec or "cameras" not in rec:
            raise InputError(f"'{path}' is not an OpenSfM reconstruction (no cameras/shots).")
    return recs


def _reference_lla(rec: Dict[str, Any], path: Path) -> LLA:
    lla = rec.get("reference_lla")
    if lla is None:
        side = path.with_name("reference_lla.json")
        if not side.is_file():
            raise InputError(
                f"'{path}' has no reference_lla and there is no reference_lla.json beside it; "
                "the coordinates cannot be georeferenced."
            )
        try:
            lla = json.loads(side.read_text(encoding="utf-8"))
        except Exception as exc:
            raise InputError(f"Cannot read '{side}': {exc}") from exc
    try:
        return float(lla["latitude"]), float(lla["longitude"]), float(lla["altitude"])
    except (KeyError, TypeError, ValueError) as exc:
        raise InputError(f"'{path}': reference_lla needs latitude, longitude, altitude.") from exc


@dataclass
class _Reading:
    """One reading of the shots in one frame, in the target CRS."""

    frame: str
    images: List[ImportedImage]
    gps: Dict[str, NDArray[np.float64]]  # image name → GPS position in the target CRS
    linear_gap: float = 0.0  # largest distance between ODM's reading and the exact centres


def _shot_pose(shot: Any, name: str, path: Path
               ) -> Tuple[NDArray[np.float64], NDArray[np.float64]]:
    """A shot's ``rotation`` and ``translation`` (3 numbers each), checked."""
    try:
        rotation = np.asarray(shot["rotation"], dtype=float).reshape(3)
        translation = np.asarray(shot["translation"], dtype=float).reshape(3)
        str(shot["camera"])
    except (KeyError, TypeError, ValueError) as exc:
        raise InputError(f"'{path}': shot '{name}' needs rotation, translation (3 numbers each) "
                         f"and camera ({exc}).") from exc
    if not (np.isfinite(rotation).all() and np.isfinite(translation).all()):
        raise InputError(f"'{path}': shot '{name}' has a rotation or translation that is not "
                         "a finite number.")
    return rotation, translation


def _read_shots(recs: List[Dict[str, Any]], path: Path, frame: str, target: str,
                georef: Optional[OdmGeoref]) -> _Reading:
    """All shots of ``recs`` read in ``frame`` and converted to ``target``."""
    reading = _Reading(frame, [], {})
    seen: Dict[str, str] = {}
    for rec in recs:
        ref = _reference_lla(rec, path)
        to_target = functools.partial(enu_to_crs, reference_lla=ref, crs=target)
        affine = odm_affine(ref, georef) if frame == FRAME_ODM_UTM and georef else None
        for shot_name, shot in rec["shots"].items():
            rotation, translation = _shot_pose(shot, shot_name, path)
            pose = opensfm_to_patb(rotation, translation)
            if affine is not None:
                assert georef is not None
                # where ODM's own tools put the camera: the file's centre plus the offset
                linear = pose.position + (georef.offset[0], georef.offset[1], 0.0)
                pose = odm_utm_to_enu(rotation, translation, *affine)
            eo = transform_pose(pose, to_target)
            if affine is not None:
                exact = enu_to_crs(pose.position, ref, georef.crs)
                reading.linear_gap = max(reading.linear_gap,
                                         float(np.linalg.norm(exact - linear)))
            name = image_stem(shot_name)
            if name in seen:
                raise InputError(f"'{path}': image '{name}' appears in two reconstructions.")
            seen[name] = shot_name
            reading.images.append(ImportedImage(name=name, eo=eo, camera=str(shot["camera"]),
                                                source_name=shot_name))
            if shot.get("gps_position") is not None:
                reading.gps[name] = to_target(np.asarray(shot["gps_position"], dtype=float))
    return reading


def fit_similarity_2d(src: ArrayLike, dst: ArrayLike) -> Tuple[float, float]:
    """Angle (degrees, counter-clockwise) and scale of the 2-D similarity that best maps the
    points ``src`` (n, 2) onto ``dst`` (least squares, Umeyama)."""
    a = np.asarray(src, dtype=float)[:, :2]
    b = np.asarray(dst, dtype=float)[:, :2]
    a, b = a - a.mean(axis=0), b - b.mean(axis=0)
    # closed form of the 2-D Procrustes rotation: atan2 of the cross and dot sums
    dot = float(np.sum(a * b))
    cross = float(np.sum(a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]))
    angle = math.atan2(cross, dot)
    scale = math.hypot(dot, cross) / float(np.sum(a * a))
    return math.degrees(angle), scale


def gps_check(reading: _Reading) -> Dict[str, Any]:
    """Camera centres against the file's GPS positions: number of shots, median and largest
    distance (m) and the angle (°) of a fitted 2-D similarity (when the positions spread over
    more than 1 m)."""
    names = [img.name for img in reading.images if img.name in reading.gps]
    if not names:
        return {"gps_shots": 0}
    centres = np.array([img.eo.position for img in reading.images if img.name in reading.gps])
    gps = np.array([reading.gps[n] for n in names])
    dist = np.linalg.norm(centres - gps, axis=1)
    out: Dict[str, Any] = {"gps_shots": len(names), "gps_median_m": float(np.median(dist)),
                           "gps_max_m": float(dist.max()), "gps_rotation_deg": None}
    spread = np.sqrt(np.mean(np.sum((gps[:, :2] - gps[:, :2].mean(axis=0)) ** 2, axis=1)))
    if len(names) >= 2 and spread > 1.0:
        out["gps_rotation_deg"], out["gps_scale"] = fit_similarity_2d(gps, centres)
    return out


def _check_text(frame: str, why: str, check: Dict[str, Any]) -> str:
    """One line on the frame used and the GPS check; loud when the check fails."""
    text = f"OpenSfM frame: {frame} ({why})."
    if not check.get("gps_shots"):
        return text + " The file has no gps_position to check the camera centres against."
    rot = check.get("gps_rotation_deg")
    rot_text = "no rotation (positions too close)" if rot is None else f"rotation {rot:.3f}°"
    text += (f" Camera centres vs the file's gps_position ({check['gps_shots']} shots): median "
             f"{check['gps_median_m']:.2f} m, max {check['gps_max_m']:.2f} m, {rot_text}.")
    if (rot is not None and abs(rot) > GPS_MAX_ROTATION_DEG) \
            or check["gps_max_m"] > GPS_MAX_DISTANCE_M:
        text += (f" CHECK THE FRAME: more than {GPS_MAX_ROTATION_DEG}° or "
                 f"{GPS_MAX_DISTANCE_M:.0f} m between the centres and the GPS positions; the "
                 "reconstruction may be in another frame than assumed (see the README on ODM "
                 "projects) or the GPS is poor.")
    return text


def _choose(readings: List[_Reading]) -> Tuple[_Reading, str]:
    """The reading whose centres agree best with the GPS positions (median distance)."""
    scored = [(gps_check(r).get("gps_median_m", math.inf), r) for r in readings]
    scored.sort(key=lambda s: s[0])
    best, other = scored[0], scored[1]
    if not math.isfinite(best[0]):
        return readings[0], "no GPS positions to decide; ODM's georeferencing found"
    return best[1], (f"closer to the GPS positions: median {best[0]:.2f} m against "
                     f"{other[0]:.2f} m as {other[1].frame}")


def read_opensfm(path: PathLike, crs: Optional[str] = None,
                 reconstruction: Optional[int] = None,
                 frame: Optional[str] = None) -> ImportedBlock:
    """Cameras and poses from an OpenSfM or ODM reconstruction, read in its own frame.

    Parameters
    ----------
    path : path
        An ODM project folder, an ``opensfm`` folder, a ``reconstruction.json`` or
        ``reconstruction.topocentric.json`` (see the module notes for the frames).
    crs : str, optional
        Target CRS; default ODM's UTM zone (``coords.txt``) or the WGS 84 UTM zone of
        ``reference_lla``.
    reconstruction : int, optional
        Import only this reconstruction (0 = the largest, first one); default all.
    frame : {"topocentric", "odm_utm"}, optional
        Force the frame; default found from the files around (:func:`locate_opensfm`) or the GPS.

    Returns
    -------
    ImportedBlock
        ``checks`` holds ``frame``, ``gps_shots``, ``gps_median_m``, ``gps_max_m``,
        ``gps_rotation_deg`` (and ``odm_linear_gap_m`` for ODM's UTM frame); ``warnings`` a line
        on the frame and the check (loud when the check fails).
    """
    source = locate_opensfm(path)
    if frame is not None and frame not in FRAMES:
        raise InputError(f"Unknown OpenSfM frame '{frame}'; use one of {', '.join(FRAMES)}.")
    recs = _load_reconstructions(source.reconstruction, reconstruction)
    ref = _reference_lla(recs[0], source.reconstruction)
    georef = (parse_odm_coords(source.coords) if source.coords is not None
              else odm_georef_from_reference(ref))
    target = normalise_crs(crs) if crs else (georef.crs if georef else utm_crs_of(ref[0], ref[1]))
    frames, why = ([frame], "as asked") if frame else ([source.frame], source.why)
    if frames == [None]:
        frames = [FRAME_ODM_UTM, FRAME_TOPOCENTRIC] if georef else [FRAME_TOPOCENTRIC]
        why = "no ODM files beside it"
    if FRAME_ODM_UTM in frames and georef is None:
        raise InputError(
            f"'{source.reconstruction}' is in ODM's UTM frame but neither "
            "odm_georeferencing/coords.txt nor an ODM reference_lla gives its UTM zone and offset."
        )
    readings = [_read_shots(recs, source.reconstruction, f, target, georef) for f in frames]
    reading = readings[0]
    if len(readings) > 1:
        reading, why = _choose(readings)
    block = ImportedBlock(crs=target)
    for rec in recs:
        for cam_name, cam in rec["cameras"].items():
            block.cameras.setdefault(cam_name, _opensfm_camera(cam_name, cam))
    block.images = reading.images
    if not block.images:
        raise InputError(f"'{source.reconstruction}' holds no oriented images.")
    block.checks = {"frame": reading.frame, "reconstruction": str(source.reconstruction),
                    **gps_check(reading)}
    if reading.frame == FRAME_ODM_UTM and georef is not None:
        block.checks.update(odm_crs=georef.crs, odm_offset=list(georef.offset),
                            odm_linear_gap_m=reading.linear_gap)
        why += (f"; {georef.crs} minus ({georef.offset[0]:.0f}, {georef.offset[1]:.0f}) from "
                f"{georef.source}; ODM's own reading of the file (the frame of its DSM and "
                f"orthophoto) differs by up to {reading.linear_gap:.3f} m")
    block.warnings.append(_check_text(reading.frame, why, block.checks))
    return block


__all__ = [
    "FRAMES",
    "FRAME_ODM_UTM",
    "FRAME_TOPOCENTRIC",
    "OdmGeoref",
    "OpensfmSource",
    "crs_to_enu",
    "eigen_angle_axis",
    "enu_to_crs",
    "enu_to_odm_utm",
    "fit_similarity_2d",
    "gps_check",
    "locate_opensfm",
    "odm_affine",
    "odm_georef_from_reference",
    "odm_utm_to_enu",
    "parse_odm_coords",
    "polar_rotation",
    "read_opensfm",
    "transform_pose",
    "utm_crs_of",
]
