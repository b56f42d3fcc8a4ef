"""Orientation files in other tools' formats, written from a :class:`Project`: the round trip of
the importers (:mod:`.importers`, :mod:`.importers_opensfm`) against a synthetic truth.

* :func:`write_opensfm` — plain OpenSfM: ``reconstruction.json`` topocentric at
  ``reference_lla`` (also in ``reference_lla.json``), cameras ``perspective``/``brown`` with
  focal lengths and principal point normalised by max(w, h), ``gps_position`` = the centre;
* :func:`write_odm` — an ODM project as ODM leaves it after its OpenSfM stage:
  ``odm_georeferencing/coords.txt`` (``WGS84 UTM 32N`` and the whole-metre offset, the floor of
  the mean camera position), ``opensfm/reference_lla.json`` on that offset at altitude 0,
  ``opensfm/reconstruction.topocentric.json`` and ``opensfm/reconstruction.json`` mapped to
  UTM − offset by OpenSfM's ``export_geocoords`` linearisation (``gps_position`` left
  topocentric, as ``export_geocoords`` leaves it);
* :func:`write_orthority` — orthority's exterior GeoJSON (``world_crs``, ``xyz``, ``opk`` in
  radians), its OPK CSV (space separated, quoted, with a ``.prj``) and its interior YAML.

Poses go from the project CRS to the topocentric frame through ECEF with pyproj
(:func:`.importers_opensfm.crs_to_enu`); ODM's CRS is the WGS 84 UTM zone of the block. For an
ETRS89 project (EPSG:258zz) pyproj applies the null ETRS89 → WGS 84 transformation (EPSG:1149),
so the numbers stay those of the project, as ODM's GPS-based georeferencing would have them
(the real difference, ≈ 0.9 m in 2026, is ignored by both).
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any, Dict, Optional, Sequence, Tuple

import numpy as np
import pyproj
import yaml

from ..geometry.camera import Camera
from ..geometry.orientation import ExteriorOrientation
from ..raster.io import staged_folder
from .importers_common import PathLike
from .importers_opensfm import (
    OdmGeoref,
    crs_to_enu,
    enu_to_crs,
    enu_to_odm_utm,
    odm_affine,
    transform_pose,
    utm_crs_of,
)
from .model import Project

LLA = Tuple[float, float, float]
PRODUCT = "export_orientation"


def _write_json(path: Path, data: Any) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(data, indent=1), encoding="utf-8")


def opensfm_camera(camera: Camera) -> Dict[str, Any]:
    """OpenSfM camera parameters (normalised by max(w, h), principal point y down).

    ``perspective`` (one focal length, k1, k2) when that describes the camera exactly, else
    ``brown`` (focal_x/y, c_x/y, k1–k3, p1–p2).
    """
    s = float(max(camera.width, camera.height))
    px, py = camera.pixel_size
    fx, fy = camera.focal_length / (px * s), camera.focal_length / (py * s)
    cx, cy = camera.principal_point[0] / (px * s), -camera.principal_point[1] / (py * s)
    d: Dict[str, Any] = {"width": int(camera.width), "height": int(camera.height)}
    if fx == fy and cx == cy == 0.0 and camera.k3 == camera.p1 == camera.p2 == 0.0:
        d.update(projection_type="perspective", focal=fx, k1=camera.k1, k2=camera.k2)
    else:
        d.update(projection_type="brown", focal_x=fx, focal_y=fy, c_x=cx, c_y=cy, k1=camera.k1,
                 k2=camera.k2, k3=camera.k3, p1=camera.p1, p2=camera.p2)
    return d


def _lla_of(points: np.ndarray, crs: str) -> np.ndarray:
    """(lat, lon) of projected points (n, 2)."""
    t = pyproj.Transformer.from_crs(crs, "EPSG:4326", always_xy=True)
    lon, lat = t.transform(points[:, 0], points[:, 1])
    return np.stack([np.asarray(lat), np.asarray(lon)], axis=-1)


def _centres(project: Project) -> np.ndarray:
    return np.array([rec.eo.position for rec in project.images], dtype=float)


def _shot(eo: Any, camera: str, gps: Sequence[float]) -> Dict[str, Any]:
    """A shot from a pose (:class:`ExteriorOrientation` or OpenSfM's (rotation, translation))."""
    rotation, translation = eo.to_opensfm() if isinstance(eo, ExteriorOrientation) else eo
    return {"rotation": rotation.tolist(), "translation": translation.tolist(),
            "camera": camera, "orientation": 1, "capture_time": 0.0,
            "gps_position": [float(v) for v in gps], "gps_dop": 0.05}


def _topocentric_poses(project: Project, reference: LLA) -> Dict[str, ExteriorOrientation]:
    """The images' poses in the ENU frame at ``reference`` (name → pose)."""
    return {rec.name: transform_pose(rec.eo, lambda p: crs_to_enu(p, reference, project.crs))
            for rec in project.images}


def _reconstruction(project: Project, poses: Dict[str, Any],
                    gps: Dict[str, np.ndarray], reference: LLA) -> list:
    """One OpenSfM reconstruction (as a one-element list) of the project's images."""
    shots = {rec.path.rsplit("/", 1)[-1] if rec.path else rec.name:
             _shot(poses[rec.name], rec.camera, gps[rec.name]) for rec in project.images}
    cams = {name: opensfm_camera(cam) for name, cam in project.cameras.items()}
    lla = {"latitude": reference[0], "longitude": reference[1], "altitude": reference[2]}
    return [{"cameras": cams, "shots": shots, "points": {}, "reference_lla": lla}]


def write_opensfm(project: Project, folder: PathLike,
                  reference_lla: Optional[Sequence[float]] = None) -> Path:
    """A plain OpenSfM folder: ``reconstruction.json`` (topocentric) and ``reference_lla.json``.

    Parameters
    ----------
    project : Project
        Cameras and exterior orientations (in ``project.crs``).
    folder : path
        New or empty folder (written staged: complete or not at all).
    reference_lla : (lat, lon, alt), optional
        Default: the mean camera position at the mean camera height, as OpenSfM takes the mean
        of the GPS positions.

    Returns
    -------
    Path
        The ``reconstruction.json``.
    """
    centres = _centres(project)
    if reference_lla is None:
        lat, lon = _lla_of(centres.mean(axis=0)[None, :2], project.crs)[0]
        reference_lla = (float(lat), float(lon), round(float(centres[:, 2].mean()), 3))
    ref = tuple(float(v) for v in reference_lla)
    poses = _topocentric_poses(project, ref)
    gps = {name: eo.position for name, eo in poses.items()}
    with staged_folder(folder, product=PRODUCT) as tmp:
        _write_json(tmp / "reconstruction.json", _reconstruction(project, poses, gps, ref))
        _write_json(tmp / "reference_lla.json",
                    {"latitude": ref[0], "longitude": ref[1], "altitude": ref[2]})
    return Path(folder) / "reconstruction.json"


def odm_georef_of(project: Project) -> Tuple[OdmGeoref, LLA]:
    """ODM's georeferencing of the block: the WGS 84 UTM zone of its centre, the offset (floor of
    the mean camera easting and northing there) and ``reference_lla`` on it at altitude 0."""
    centres = _centres(project)
    lat, lon = _lla_of(centres.mean(axis=0)[None, :2], project.crs)[0]
    crs = utm_crs_of(float(lat), float(lon))
    t = pyproj.Transformer.from_crs(project.crs, crs, always_xy=True)
    e, n = t.transform(centres[:, 0], centres[:, 1])
    offset = (float(math.floor(np.mean(e))), float(math.floor(np.mean(n))))
    ref_lat, ref_lon = _lla_of(np.array([offset]), crs)[0]
    return OdmGeoref(crs, offset, "coords.txt"), (float(ref_lat), float(ref_lon), 0.0)


def _coords_text(georef: OdmGeoref, centres_odm: np.ndarray) -> str:
    code = int(georef.crs.split(":")[1])
    zone, hemi = code % 100, "N" if code < 32700 else "S"
    lines = [f"WGS84 UTM {zone}{hemi}", f"{georef.offset[0]:.0f} {georef.offset[1]:.0f}"]
    lines += [f"{x - georef.offset[0]:.3f} {y - georef.offset[1]:.3f} {z:.3f}"
              for x, y, z in centres_odm]
    return "\n".join(lines) + "\n"


def write_odm(project: Project, folder: PathLike) -> Path:
    """An ODM project folder as ODM leaves it after its OpenSfM stage (see module notes); the
    images are not copied (put them in ``images/`` for an import).

    Returns
    -------
    Path
        The project folder (``folder``).
    """
    georef, ref = odm_georef_of(project)
    poses = _topocentric_poses(project, ref)
    gps = {name: eo.position for name, eo in poses.items()}
    A, b = odm_affine(ref, georef)
    utm = {name: enu_to_odm_utm(eo, A, b) for name, eo in poses.items()}  # (rotation, t)
    centres = enu_to_crs(np.array([eo.position for eo in poses.values()]), ref, georef.crs)
    with staged_folder(folder, product=PRODUCT) as tmp:
        osfm = tmp / "opensfm"
        _write_json(osfm / "reconstruction.topocentric.json",
                    _reconstruction(project, poses, gps, ref))
        _write_json(osfm / "reconstruction.json", _reconstruction(project, utm, gps, ref))
        _write_json(osfm / "reference_lla.json",
                    {"latitude": ref[0], "longitude": ref[1], "altitude": ref[2]})
        (tmp / "odm_georeferencing").mkdir()
        (tmp / "odm_georeferencing" / "coords.txt").write_text(_coords_text(georef, centres),
                                                               encoding="utf-8")
    return Path(folder)


def orthority_interior(camera: Camera) -> Dict[str, Any]:
    """Orthority interior parameters of a camera (focal length and sensor size in mm, principal
    point normalised by max(w, h) with y down)."""
    s = float(max(camera.width, camera.height))
    px, py = camera.pixel_size
    d: Dict[str, Any] = {
        "type": "brown" if camera.has_distortion else "pinhole",
        "im_size": [int(camera.width), int(camera.height)],
        "focal_len": float(camera.focal_length),
        "sensor_size": [camera.width * px, camera.height * py],
        "cx": camera.principal_point[0] / (px * s), "cy": -camera.principal_point[1] / (py * s),
    }
    if camera.has_distortion:
        d.update(k1=camera.k1, k2=camera.k2, k3=camera.k3, p1=camera.p1, p2=camera.p2)
    return d


def write_orthority(project: Project, folder: PathLike) -> Dict[str, Path]:
    """Orthority's files: ``ext_param.geojson``, ``ext_param.csv`` (+ ``.prj``) and
    ``int_param.yaml`` in a new or empty ``folder``; returns them by kind (``geojson``, ``csv``,
    ``yaml``)."""
    crs = pyproj.CRS.from_user_input(project.crs)
    lla_t = pyproj.Transformer.from_crs(crs, "EPSG:4979", always_xy=True)
    features, rows = [], ["'filename' 'x' 'y' 'z' 'omega' 'phi' 'kappa' 'camera'"]
    for rec in project.images:
        filename = rec.path.rsplit("/", 1)[-1] if rec.path else rec.name
        xyz = [float(v) for v in rec.eo.position]
        opk = list(rec.eo.opk("radians"))
        lon, lat, h = lla_t.transform(*xyz)
        features.append({"type": "Feature", "geometry": {"type": "Point",
                                                        "coordinates": [lon, lat, h]},
                         "properties": {"filename": filename, "camera": rec.camera,
                                        "xyz": xyz, "opk": opk}})
        deg = rec.eo.opk("degrees")
        rows.append(" ".join([f"'{filename}'", *(repr(v) for v in xyz),
                              *(repr(v) for v in deg), f"'{rec.camera}'"]))
    names = {"geojson": "ext_param.geojson", "csv": "ext_param.csv", "yaml": "int_param.yaml"}
    with staged_folder(folder, product=PRODUCT) as tmp:
        _write_json(tmp / names["geojson"], {"type": "FeatureCollection",
                                             "world_crs": project.crs, "features": features})
        (tmp / names["csv"]).write_text("\n".join(rows) + "\n", encoding="utf-8")
        (tmp / "ext_param.prj").write_text(crs.to_wkt(), encoding="utf-8")
        interior = {name: orthority_interior(cam) for name, cam in project.cameras.items()}
        (tmp / names["yaml"]).write_text(yaml.safe_dump(interior, sort_keys=False),
                                         encoding="utf-8")
    return {kind: Path(folder) / name for kind, name in names.items()}


__all__ = [
    "odm_georef_of",
    "opensfm_camera",
    "orthority_interior",
    "write_odm",
    "write_opensfm",
    "write_orthority",
]
