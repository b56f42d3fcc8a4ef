r"""Importers for the orientation files users have.

* **Orthority-style OPK CSV** (``filename,x,y,z,omega,phi,kappa``, header optional, extra columns
  allowed, optional ``camera`` column) with the orthority **interior-parameter YAML**;
* **plain OPK text** (``name x y z omega phi kappa [camera]``, whitespace separated, ``#``
  comments);
* **OpenSfM / ODM** reconstructions and ODM project folders (:mod:`.importers_opensfm`);
* **orthority's exterior GeoJSON** (``oty`` format).

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

OpenSfM and ODM reconstructions (plain OpenSfM topocentric, ODM's UTM-with-offset
``reconstruction.json``, ODM's ``reconstruction.topocentric.json``, or an ODM project folder)
are read by :mod:`.importers_opensfm`, which describes the frames; orthority's exterior GeoJSON
(``world_crs``, ``xyz``, ``opk`` in radians) by :func:`read_oty_geojson`.
"""

from __future__ import annotations

import csv
import io
import json
from pathlib import Path
from typing import Dict, List, Optional, Sequence, Tuple

import yaml

from ..errors import InputError
from ..geometry.camera import Camera
from ..geometry.orientation import ExteriorOrientation, check_angle_unit
from .importers_common import (
    IMAGE_EXTENSIONS,
    ImportedBlock,
    ImportedImage,
    PathLike,
    camera_from_normalised,
    crs_from_prj,
    image_stem,
    normalise_crs,
    resolve_crs,
    same_crs,
)
from .importers_opensfm import (
    crs_to_enu,
    enu_to_crs,
    read_opensfm,
    transform_pose,
    utm_crs_of,
)
from .model import ImageRecord, Project

_stem = image_stem


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
    block = ImportedBlock(crs=resolve_crs(path, crs, warnings), warnings=warnings)
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
    block = ImportedBlock(crs=resolve_crs(path, crs, warnings), warnings=warnings)
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

def read_oty_geojson(path: PathLike, *, crs: Optional[str] = None) -> ImportedBlock:
    """Exterior orientation from orthority's GeoJSON (``oty`` exterior parameters).

    A FeatureCollection with ``world_crs`` and per feature the properties ``filename``,
    ``camera``, ``xyz`` (in ``world_crs``) and ``opk`` (PATB ω, φ, κ in **radians**); the point
    geometry (WGS 84 lon/lat) is not used. ``crs`` overrides ``world_crs`` (with a warning when
    they differ).
    """
    path = Path(path)
    try:
        data = json.loads(path.read_text(encoding="utf-8-sig"))
        features = data["features"]
    except Exception as exc:
        raise InputError(f"'{path}' is not orthority's exterior GeoJSON: {exc}") from exc
    warnings: List[str] = []
    world = data.get("world_crs")
    target = normalise_crs(crs) if crs else (normalise_crs(world) if world else None)
    if crs and world and not same_crs(target, normalise_crs(world)):
        warnings.append(f"The CRS parameter differs from world_crs of '{path.name}'; "
                        "the parameter is used.")
    block = ImportedBlock(crs=target, warnings=warnings)
    for n, feature in enumerate(features, start=1):
        try:
            props = feature["properties"]
            name = str(props["filename"])
            values = [*(float(v) for v in props["xyz"]), *(float(v) for v in props["opk"])]
        except (KeyError, TypeError, ValueError) as exc:
            raise InputError(f"'{path}' feature {n}: needs filename, xyz and opk ({exc}).") from exc
        block.images.append(_opk_image(name, [str(v) for v in values], "radians",
                                       f"'{path}' feature {n}", props.get("camera")))
    if not block.images:
        raise InputError(f"'{path}' holds no exterior orientation features.")
    return block


# -- detection and project assembly --------------------------------------------------------------
def detect_exterior_format(path: PathLike) -> str:
    """``"opensfm"``, ``"oty"``, ``"csv"`` or ``"text"`` from the extension and the first lines.

    A folder is an ODM project or OpenSfM folder (``"opensfm"``); a JSON object with
    ``"features"`` is orthority's exterior GeoJSON (``"oty"``).
    """
    path = Path(path)
    if path.is_dir():
        return "opensfm"
    with open(path, encoding="utf-8-sig", errors="replace") as f:
        head = f.read(4096)
    if path.suffix.lower() in (".json", ".geojson") or head.lstrip().startswith(("[", "{")):
        return "oty" if '"FeatureCollection"' in head or '"features"' in head else "opensfm"
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

    ``angle_unit`` is required for OPK files and ignored for OpenSfM/ODM and orthority's GeoJSON
    (radians by definition).
    """
    kind = detect_exterior_format(path)
    if kind == "opensfm":
        return read_opensfm(path, crs=crs)
    if kind == "oty":
        return read_oty_geojson(path, crs=crs)
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
        OPK CSV, OPK text, orthority's exterior GeoJSON, an OpenSfM/ODM reconstruction or an
        ODM project / ``opensfm`` folder (:func:`.importers_opensfm.read_opensfm`).
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
    "read_oty_geojson",
    "transform_pose",
    "utm_crs_of",
]
