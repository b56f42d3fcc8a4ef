"""The project: a folder with ``project.toml`` and ``edits.gpkg``.

``project.toml`` holds the CRS, the cameras, the images with their exterior orientation (PATB
ω-φ-κ, angle unit stated in the file), the stereo models and parameter presets. Image paths are
stored relative to the project folder when they lie below it, else absolute, so a project can be
moved together with its images. ``edits.gpkg`` holds the operator's edits (see :mod:`.edits`).
Products go to ``products/<model or step>/``, logs and reports to ``runs/<timestamp>/``.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Dict, List, Optional, Union

import numpy as np

from ..errors import InputError
from ..geometry.camera import Camera
from ..geometry.orientation import ExteriorOrientation, check_angle_unit
from . import toml_io

PROJECT_FILE = "project.toml"
EDITS_FILE = "edits.gpkg"
FORMAT_VERSION = 1

#: Characters an identifier that becomes a path part (model, image, camera, step name) may not
#: hold: path separators; control characters are refused as well (see :func:`check_identifier`).
_SEPARATORS = ("/", "\\")


def identifier_problem(name: Any) -> Optional[str]:
    """Why ``name`` cannot be an identifier that becomes a path part, or ``None`` if it can.

    Model, image, camera and batch step names become folder and file names
    (``products/<model>/``), so they must be non-empty text without path separators, not
    ``.``/``..``, without a leading dot (hidden files, staging names) and without control
    characters.
    """
    if not isinstance(name, str):
        return f"it must be text, not {type(name).__name__}"
    if not name.strip():
        return "it is empty"
    if any(sep in name for sep in _SEPARATORS):
        return "it contains a path separator ('/' or '\\')"
    if name in (".", ".."):
        return "'.' and '..' name folders"
    if name.startswith("."):
        return "it starts with a dot"
    if any(ord(c) < 32 or ord(c) == 127 or 0x80 <= ord(c) < 0xA0 for c in name):
        return "it contains a control character"
    if any(0xD800 <= ord(c) <= 0xDFFF for c in name):
        return "it is not valid UTF-8 text"
    return None


def check_identifier(name: Any, what: str, where: str = "") -> str:
    """Return ``name`` if it can become a path part, else raise :class:`InputError`.

    Parameters
    ----------
    name : object
        The identifier (model, image, camera or step name).
    what : str
        What it names ("stereo model", "image", "camera", "batch step"), for the message.
    where : str
        Where it was read (e.g. the project file), prefixed to the message.

    Raises
    ------
    InputError
        Naming the identifier, why it is refused and what to do.
    """
    problem = identifier_problem(name)
    if problem is None:
        return name
    prefix = f"{where}: " if where else ""
    shown = repr(name) if not isinstance(name, str) else "'" + name.encode(
        "utf-8", "surrogateescape").decode("utf-8", "backslashreplace").encode(
        "unicode_escape").decode("ascii") + "'"
    raise InputError(
        f"{prefix}the {what} name {shown} cannot be used: {problem}. Names become folder names; "
        "use letters, digits, '-' and '_'."
    )


def identifier_errors(project: Project) -> List[str]:
    """Operator-readable messages for every image, camera and model name of ``project`` that
    cannot become a path part (see :func:`check_identifier`)."""
    named = ([("camera", n) for n in project.cameras]
             + [("image", r.name) for r in project.images]
             + [("camera", r.camera) for r in project.images]
             + [("stereo model", m.name) for m in project.models]
             + [("image", n) for m in project.models for n in (m.left, m.right)])
    errors: List[str] = []
    for what, name in named:
        try:
            check_identifier(name, what)
        except InputError as exc:
            if str(exc) not in errors:
                errors.append(str(exc))
    return errors


def check_identifiers(project: Project, where: str = "") -> None:
    """Raise one :class:`InputError` for the first unusable name of ``project``, if any."""
    errors = identifier_errors(project)
    if errors:
        prefix = f"{where}: " if where else ""
        raise InputError(prefix + errors[0][0].upper() + errors[0][1:])


@dataclass
class ImageRecord:
    """One oriented image of the block."""

    name: str
    path: str  # as written in project.toml: relative to the project folder, or absolute
    camera: str
    eo: ExteriorOrientation


@dataclass
class StereoModel:
    """Two images that form a stereo model.

    Attributes
    ----------
    name : str
        ``<left>_<right>`` unless the operator named it.
    left, right : str
        Image names; ``left`` is the one with the smaller coordinate along the base direction.
    kind : str
        ``"in-strip"``, ``"cross-strip"`` or ``"manual"``.
    base : float
        Base length B (m).
    b_h : float
        Base-to-height ratio B/H with H the mean flying height above ground.
    overlap : float
        Share of the smaller footprint covered by both images (0–1).
    gsd : float
        Mean ground sample distance of the two images (m).
    height_above_ground : float
        Mean flying height above the terrain (m).
    """

    name: str
    left: str
    right: str
    kind: str = "manual"
    base: float = float("nan")
    b_h: float = float("nan")
    overlap: float = float("nan")
    gsd: float = float("nan")
    height_above_ground: float = float("nan")

    def to_dict(self) -> Dict[str, Any]:
        return {
            "name": self.name,
            "left": self.left,
            "right": self.right,
            "kind": self.kind,
            "base_m": round(self.base, 4),
            "b_h": round(self.b_h, 5),
            "overlap_pct": round(100.0 * self.overlap, 3),
            "gsd_m": round(self.gsd, 5),
            "height_above_ground_m": round(self.height_above_ground, 3),
        }

    @classmethod
    def from_dict(cls, d: Dict[str, Any]) -> StereoModel:
        return cls(
            name=str(d["name"]),
            left=str(d["left"]),
            right=str(d["right"]),
            kind=str(d.get("kind", "manual")),
            base=float(d.get("base_m", float("nan"))),
            b_h=float(d.get("b_h", float("nan"))),
            overlap=float(d.get("overlap_pct", float("nan"))) / 100.0,
            gsd=float(d.get("gsd_m", float("nan"))),
            height_above_ground=float(d.get("height_above_ground_m", float("nan"))),
        )


@dataclass
class Project:
    """A photogrammetric block with its operator edits.

    Attributes
    ----------
    root : Path
        The project folder.
    crs : str
        The project CRS as WKT, ``EPSG:xxxx`` or a PROJ string; every product carries it.
    terrain_height : float or None
        Mean terrain height (m) used for footprints and flying heights above ground when no DEM
        is at hand.
    """

    root: Path
    name: str
    crs: str
    cameras: Dict[str, Camera] = field(default_factory=dict)
    images: List[ImageRecord] = field(default_factory=list)
    models: List[StereoModel] = field(default_factory=list)
    terrain_height: Optional[float] = None
    presets: Dict[str, Any] = field(default_factory=dict)
    products: Dict[str, Any] = field(default_factory=dict)
    angle_unit: str = "degrees"

    # -- look-ups ------------------------------------------------------------------------------
    def image(self, name: str) -> ImageRecord:
        for rec in self.images:
            if rec.name == name:
                return rec
        raise InputError(
            f"Image '{name}' is not in project '{self.name}'. Images: "
            f"{', '.join(r.name for r in self.images[:20])}{' …' if len(self.images) > 20 else ''}."
        )

    def model(self, name: str) -> StereoModel:
        for m in self.models:
            if m.name == name:
                return m
        raise InputError(
            f"Stereo model '{name}' is not in project '{self.name}'. Models: "
            f"{', '.join(m.name for m in self.models) or 'none'}."
        )

    def camera_of(self, image: Union[str, ImageRecord]) -> Camera:
        rec = self.image(image) if isinstance(image, str) else image
        return self.cameras[rec.camera]

    def image_path(self, image: Union[str, ImageRecord]) -> Path:
        """Absolute path of an image file."""
        rec = self.image(image) if isinstance(image, str) else image
        p = Path(rec.path)
        return p if p.is_absolute() else (self.root / p)

    def read_image(self, image: Union[str, ImageRecord], colour_only: bool = False) -> Any:
        """The pixels of an image, (bands, rows, cols), checked against its camera.

        ``colour_only`` drops alpha bands and keeps at most three bands.

        Raises
        ------
        InputError
            When the file is missing or its size differs from the camera's.
        """
        from ..raster.io import open_image

        rec = self.image(image) if isinstance(image, str) else image
        cam = self.camera_of(rec)
        path = self.image_path(rec)
        if not path.is_file():
            raise InputError(f"Image file '{path}' of image '{rec.name}' does not exist; "
                             "fix its path in project.toml.")
        from ..input_errors import check_encodable, reading

        check_encodable(path, "image")
        with reading(path, "image"), open_image(path) as src:
            if (src.width, src.height) != (cam.width, cam.height):
                raise InputError(f"Image '{rec.name}' is {src.width}×{src.height} px but camera "
                                 f"'{cam.name}' is {cam.width}×{cam.height} px.")
            if not colour_only:
                return src.read()
            from rasterio.enums import ColorInterp

            bands = [i + 1 for i, c in enumerate(src.colorinterp) if c != ColorInterp.alpha]
            return src.read((bands or [1])[:3])

    @property
    def project_file(self) -> Path:
        return self.root / PROJECT_FILE

    @property
    def edits_path(self) -> Path:
        return self.root / EDITS_FILE

    def products_dir(self, step: str) -> Path:
        return self.root / "products" / step

    def relative_path(self, path: Union[str, Path]) -> str:
        """``path`` relative to the project folder if it lies below it, else absolute."""
        p = Path(path).resolve()
        try:
            return p.relative_to(self.root.resolve()).as_posix()
        except ValueError:
            return str(p)

    # -- file I/O ------------------------------------------------------------------------------
    def to_dict(self) -> Dict[str, Any]:
        unit = check_angle_unit(self.angle_unit)
        head: Dict[str, Any] = {
            "name": self.name,
            "format_version": FORMAT_VERSION,
            "crs": self.crs,
            "angle_unit": unit,
            "rotation_convention": (
                "PATB omega-phi-kappa, camera to world, R = Rx(omega) Ry(phi) Rz(kappa)"
            ),
        }
        if self.terrain_height is not None:
            head["terrain_height_m"] = float(self.terrain_height)
        return {
            "project": head,
            "cameras": {name: cam.to_dict() for name, cam in self.cameras.items()},
            "images": [
                {
                    "name": r.name,
                    "path": r.path,
                    "camera": r.camera,
                    "position": [float(v) for v in r.eo.position],
                    "opk": [float(v) for v in r.eo.opk(unit)],
                }
                for r in self.images
            ],
            "models": [m.to_dict() for m in self.models],
            "presets": self.presets,
            "products": self.products,
        }

    def save(self) -> Path:
        """Write ``project.toml`` atomically (temporary file, then rename)."""
        check_identifiers(self)  # names become folder names: never write one that cannot
        self.root.mkdir(parents=True, exist_ok=True)
        target = self.project_file
        tmp = target.with_name(f".{target.name}.{os.getpid()}.tmp")
        tmp.write_text(toml_io.dumps(_drop_empty(self.to_dict())), encoding="utf-8")
        os.replace(tmp, target)
        return target

    @classmethod
    def load(cls, path: Union[str, Path]) -> Project:
        """Read a project from its folder or its ``project.toml``.

        Raises
        ------
        InputError
            When the folder holds no readable ``project.toml``.
        """
        p = Path(path)
        file = p / PROJECT_FILE if p.is_dir() else p
        if not file.is_file():
            raise InputError(
                f"'{path}' is not a PhotoDEM project: {PROJECT_FILE} not found. "
                "Create one with project_create or synthetic_block."
            )
        where = f"'{file}'"
        try:
            data = toml_io.loads(file.read_text(encoding="utf-8"))
        except UnicodeDecodeError as exc:
            raise InputError(f"{where} is not UTF-8 text (byte 0x{exc.object[exc.start]:02x} at "
                             f"position {exc.start}); save it as UTF-8.") from None
        except toml_io.tomllib.TOMLDecodeError as exc:
            raise InputError(f"{where} is not valid TOML ({exc}); fix the line it names."
                             ) from None
        except OSError as exc:
            raise InputError(f"Cannot read {where}: {exc.strerror or exc}.") from None
        top = _Table(data, where, "")
        head = top.table("project")
        try:
            unit = check_angle_unit(head.text("angle_unit", "degrees"))
        except InputError as exc:
            raise InputError(f"{head.where}: {exc}") from None
        cameras = {}
        for cam_name, cam in top.table("cameras").tables_by_name():
            check_identifier(cam_name, "camera", where)
            cameras[cam_name] = cam.camera(cam_name)
        images = []
        for d in top.table_list("images"):
            name = check_identifier(d.text("name"), "image", d.where)
            d = d.named(f"image '{name}'")
            images.append(ImageRecord(
                name=name,
                path=d.text("path"),
                camera=check_identifier(d.text("camera"), "camera", d.where),
                eo=ExteriorOrientation.from_opk(np.asarray(d.numbers("position", 3)),
                                                *d.numbers("opk", 3), unit=unit),
            ))
        models = []
        for d in top.table_list("models"):
            name = check_identifier(d.text("name"), "stereo model", d.where)
            d = d.named(f"stereo model '{name}'")
            models.append(StereoModel(
                name=name,
                left=check_identifier(d.text("left"), "image", d.where),
                right=check_identifier(d.text("right"), "image", d.where),
                kind=d.text("kind", "manual"),
                base=d.number("base_m", float("nan")),
                b_h=d.number("b_h", float("nan")),
                overlap=d.number("overlap_pct", float("nan")) / 100.0,
                gsd=d.number("gsd_m", float("nan")),
                height_above_ground=d.number("height_above_ground_m", float("nan")),
            ))
        terrain = head.number("terrain_height_m", None)
        return cls(
            root=file.parent,
            name=head.text("name", file.parent.name),
            crs=head.text("crs", ""),
            cameras=cameras,
            images=images,
            models=models,
            terrain_height=terrain,
            presets=top.table("presets").data,
            products=top.table("products").data,
            angle_unit=unit,
        )


_MISSING: Any = object()


class _Table:
    """Typed access to one table of ``project.toml``: a missing key or a value of the wrong type
    is an :class:`InputError` naming the file, the entry and the key.

    Parameters
    ----------
    data : dict
        The table as parsed.
    file : str
        The project file, quoted, for messages.
    label : str
        The entry, e.g. ``[[images]] #2``; empty for the whole file.
    """

    def __init__(self, data: Any, file: str, label: str) -> None:
        self.data: Dict[str, Any] = data
        self.file = file
        self.where = f"{file} {label}" if label else file

    def named(self, label: str) -> _Table:
        """The same table, its messages naming it by ``label`` instead of its position."""
        return _Table(self.data, self.file, label)

    def _fail(self, key: str, problem: str) -> InputError:
        return InputError(f"{self.where}: '{key}' {problem}; fix it in the project file.")

    def _get(self, key: str, default: Any) -> Any:
        if key in self.data:
            return self.data[key]
        if default is _MISSING:
            raise self._fail(key, "is missing")
        return default

    def text(self, key: str, default: Any = _MISSING) -> str:
        """A string value (a whole number is accepted and written as text)."""
        value = self._get(key, default)
        if isinstance(value, bool) or not isinstance(value, (str, int)):
            raise self._fail(key, f"must be text, not {_shown(value)}")
        return str(value)

    def number(self, key: str, default: Any = _MISSING) -> Any:
        """A number (int or float) as float; ``default`` when absent."""
        value = self._get(key, default)
        if value is default and default is not _MISSING:
            return default
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise self._fail(key, f"must be a number, not {_shown(value)}")
        return float(value)

    def integer(self, key: str, default: Any = _MISSING) -> int:
        """A whole number."""
        value = self.number(key, default)
        if value is None or value != int(value):
            raise self._fail(key, f"must be a whole number, not {_shown(self.data.get(key))}")
        return int(value)

    def numbers(self, key: str, length: int, default: Any = _MISSING) -> List[float]:
        """A list of exactly ``length`` numbers."""
        value = self._get(key, default)
        if value is default and default is not _MISSING:
            return default
        if (not isinstance(value, list) or len(value) != length
                or any(isinstance(v, bool) or not isinstance(v, (int, float)) for v in value)):
            raise self._fail(key, f"must be a list of {length} numbers, not {_shown(value)}")
        return [float(v) for v in value]

    def table(self, key: str) -> _Table:
        """A sub-table (empty when absent)."""
        value = self._get(key, {})
        if not isinstance(value, dict):
            raise self._fail(key, f"must be a table ([{key}]), not {_shown(value)}")
        label = self.where[len(self.file):].strip()
        return _Table(value, self.file, f"{label} [{key}]".strip())

    def table_list(self, key: str) -> List[_Table]:
        """An array of tables (``[[key]]``; empty when absent)."""
        value = self._get(key, [])
        if not isinstance(value, list) or not all(isinstance(v, dict) for v in value):
            raise self._fail(key, f"must be an array of tables ([[{key}]]), not {_shown(value)}")
        return [_Table(v, self.file, f"[[{key}]] #{i + 1}") for i, v in enumerate(value)]

    def tables_by_name(self) -> List[Any]:
        """``(name, sub-table)`` pairs of a table of tables (``[cameras.<name>]``)."""
        out = []
        for name, value in self.data.items():
            if not isinstance(value, dict):
                raise self._fail(name, f"must be a table, not {_shown(value)}")
            out.append((name, _Table(value, self.file, f"camera '{name}'")))
        return out

    def camera(self, name: str) -> Camera:
        """The camera this table describes (checked key by key first)."""
        d = dict(self.data)
        d["width"] = self.integer("width")
        d["height"] = self.integer("height")
        d["focal_length_mm"] = self.number("focal_length_mm")
        d["pixel_size_mm"] = self.numbers("pixel_size_mm", 2)
        d["principal_point_mm"] = self.numbers("principal_point_mm", 2, [0.0, 0.0])
        dist = self.table("distortion")
        d["distortion"] = {k: dist.number(k, 0.0) for k in ("k1", "k2", "k3", "p1", "p2")}
        fid = self._get("fiducial_affine", None)
        if fid is not None:
            rows = fid if isinstance(fid, list) and len(fid) == 2 else None
            if rows is None or not all(
                    isinstance(r, list) and len(r) == 3
                    and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in r)
                    for r in rows):
                raise self._fail("fiducial_affine", "must be 2 rows of 3 numbers, not "
                                 + _shown(fid))
        try:
            return Camera.from_dict(name, d)
        except InputError as exc:
            raise InputError(f"{self.where}: {exc}") from None


def _shown(value: Any) -> str:
    """A short description of a wrong value for a message."""
    text = repr(value)
    return text if len(text) <= 40 else text[:37] + "…"


def _drop_empty(d: Dict[str, Any]) -> Dict[str, Any]:
    return {k: v for k, v in d.items() if not (isinstance(v, (dict, list)) and len(v) == 0)}
