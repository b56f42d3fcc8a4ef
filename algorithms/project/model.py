"""The project: a folder with ``project.toml`` and ``edits.gpkg``.

``project.toml`` holds the CRS, the cameras, the images with their exterior orientation (PATB
ω-φ-κ, angle unit stated in the file), the stereo models and parameter presets. Image paths are
stored relative to the project folder when they lie below it, else absolute, so a project can be
moved together with its images. ``edits.gpkg`` holds the operator's edits (see :mod:`.edits`).
Products go to ``products/<model or step>/``, logs and reports to ``runs/<timestamp>/``.

What is wrong with a project file is sorted by kind (issue 16):

* **Structure** — :meth:`Project.load` raises one :class:`~..errors.InputError` naming
  ``project.toml``, the entry and what to do, because nothing downstream can work with such a
  file: no ``[project]`` table (an empty file), an unsupported ``format_version``, a value of the
  wrong type (``crs``, names, ``left``/``right`` not text; ``images`` not an array of tables…),
  a name that cannot become a path part (:func:`check_identifier`), an image naming an unknown
  camera, a stereo model naming an unknown image (or the same image twice), and image or model
  names used twice. A model is never silently dropped.
* **Content** — the file is well formed but the block cannot be used as it is: a CRS that PROJ
  does not understand, no images, a camera looking up, missing image files, implausible
  heights… These are errors and warnings of :func:`.validate.validate_project`; each algorithm
  decides when to raise them (``project_info`` lists them all and then exits with an error).
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Dict, List, Optional, Union

import numpy as np
from rasterio.enums import ColorInterp

from ..errors import InputError, Message, msg
from ..geometry.camera import Camera
from ..geometry.orientation import ExteriorOrientation, check_angle_unit
from ..input_errors import check_encodable, reading
from ..raster.io import open_image
from . import toml_io

PROJECT_FILE = "project.toml"
EDITS_FILE = "edits.gpkg"
FORMAT_VERSION = 1

#: Characters an identifier that becomes a path part (model, image, camera, step name) may not
#: hold: path separators; control characters are refused as well (see :func:`check_identifier`).
_SEPARATORS = ("/", "\\")


def identifier_problem(name: Any) -> Optional[Message]:
    """Why ``name`` cannot be an identifier that becomes a path part, or ``None`` if it can.

    Model, image, camera and batch step names become folder and file names
    (``products/<model>/``), so they must be non-empty text without path separators, not
    ``.``/``..``, without a leading dot (hidden files, staging names) and without control
    characters.
    """
    if not isinstance(name, str):
        return msg("it must be text, not {type}", type=type(name).__name__)
    if not name.strip():
        return msg("it is empty")
    if any(sep in name for sep in _SEPARATORS):
        return msg("it contains a path separator ('/' or '\\')")
    if name in (".", ".."):
        return msg("'.' and '..' name folders")
    if name.startswith("."):
        return msg("it starts with a dot")
    if any(ord(c) < 32 or ord(c) == 127 or 0x80 <= ord(c) < 0xA0 for c in name):
        return msg("it contains a control character")
    if any(0xD800 <= ord(c) <= 0xDFFF for c in name):
        return msg("it is not valid UTF-8 text")
    return None


#: The items whose names :func:`check_identifier` checks, as words the GUIs translate.
_ITEM_WORDS = {"camera": msg("camera"), "image": msg("image"),
               "stereo model": msg("stereo model")}


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
    shown = repr(name) if not isinstance(name, str) else "'" + name.encode(
        "utf-8", "surrogateescape").decode("utf-8", "backslashreplace").encode(
        "unicode_escape").decode("ascii") + "'"
    if not where:  # a part of a longer message (identifier_errors)
        raise InputError(f"the {what} name {shown} cannot be used: {problem}. Names become "
                         "folder names; use letters, digits, '-' and '_'.")
    raise InputError.of("{where}: the {what} name {shown} cannot be used: {problem}. Names "
                        "become folder names; use letters, digits, '-' and '_'.", where=where,
                        what=_ITEM_WORDS.get(what, what), shown=shown, problem=problem)


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


def structure_errors(project: Project) -> List[str]:
    """What makes ``project`` a file that :meth:`Project.load` would refuse, beyond its names:
    image or model names used twice, an image naming an unknown camera, a stereo model naming
    an unknown image or the same image twice (see the module notes)."""
    errors: List[str] = []
    images = [r.name for r in project.images]
    models = [m.name for m in project.models]
    for what, names in (("image", images), ("stereo model", models)):
        errors += [f"the {what} name '{n}' is used {names.count(n)} times"
                   for n in sorted(set(names)) if names.count(n) > 1]
    errors += [f"image '{r.name}' names camera '{r.camera}', which is not defined"
               for r in project.images if r.camera not in project.cameras]
    errors += [f"stereo model '{m.name}' names image '{n}', which is not defined"
               for m in project.models for n in dict.fromkeys((m.left, m.right))
               if n not in images]
    errors += [f"stereo model '{m.name}' has image '{m.left}' on both sides"
               for m in project.models if m.left == m.right]
    return errors


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
    convergence : float
        Angle (°) between the two optical axes (0 for parallel vertical images; a convergent
        drone or oblique pair 20–60°); NaN when unknown.
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
    convergence: float = float("nan")

    def to_dict(self) -> Dict[str, Any]:
        out: Dict[str, Any] = {
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
        if math.isfinite(self.convergence):
            out["convergence_deg"] = round(self.convergence, 3)
        return out

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
            convergence=float(d.get("convergence_deg", float("nan"))),
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
        raise InputError.of(
            "Image '{name}' is not in project '{project}'. Images: {images}.", name=name,
            project=self.name, images=(", ".join(r.name for r in self.images[:20])
                                       + (" …" if len(self.images) > 20 else "")))

    def model(self, name: str) -> StereoModel:
        for m in self.models:
            if m.name == name:
                return m
        if not self.models:
            raise InputError.of("Stereo model '{name}' is not in project '{project}'. Models: "
                                "none.", name=name, project=self.name)
        raise InputError.of("Stereo model '{name}' is not in project '{project}'. Models: "
                            "{models}.", name=name, project=self.name,
                            models=", ".join(m.name for m in self.models))

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
        rec = self.image(image) if isinstance(image, str) else image
        cam = self.camera_of(rec)
        path = self.image_path(rec)
        if not path.is_file():
            raise InputError(f"Image file '{path}' of image '{rec.name}' does not exist; "
                             "fix its path in project.toml.")

        check_encodable(path, "image")
        with reading(path, "image"), open_image(path) as src:
            if (src.width, src.height) != (cam.width, cam.height):
                raise InputError(f"Image '{rec.name}' is {src.width}×{src.height} px but camera "
                                 f"'{cam.name}' is {cam.width}×{cam.height} px.")
            if not colour_only:
                return src.read()

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
        """Write ``project.toml`` atomically (temporary file, then rename).

        Raises
        ------
        InputError
            When the project holds a name that cannot become a path part or a broken reference
            (see :func:`structure_errors`): a file :meth:`load` would refuse is never written.
        """
        check_identifiers(self)  # names become folder names: never write one that cannot
        broken = structure_errors(self)
        if broken:
            raise InputError(f"Project '{self.name}' cannot be saved: {broken[0]}. Fix the "
                             "project's images, cameras and stereo models first.")
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
            raise InputError.of("'{path}' is not a PhotoDEM project: {file} not found. Create "
                                "one with project_create or synthetic_block.", path=path,
                                file=PROJECT_FILE)
        where = f"'{file}'"
        try:
            data = toml_io.loads(file.read_text(encoding="utf-8"))
        except UnicodeDecodeError as exc:
            raise InputError.of("{where} is not UTF-8 text (byte 0x{byte:02x} at position "
                                "{position}); save it as UTF-8.", where=where,
                                byte=exc.object[exc.start], position=exc.start) from None
        except toml_io.tomllib.TOMLDecodeError as exc:
            raise InputError.of("{where} is not valid TOML ({error}); fix the line it names.",
                                where=where, error=exc) from None
        except OSError as exc:
            raise InputError.of("Cannot read {where}: {error}.", where=where,
                                error=exc.strerror or exc) from None
        top = _Table(data, where, "")
        if "project" not in data:
            if not data:
                raise InputError.of("{where} has no [project] table (it is empty); restore it "
                                    "from a copy or create the project again with "
                                    "project_create.", where=where)
            raise InputError.of("{where} has no [project] table (it is not a PhotoDEM project "
                                "file); restore it from a copy or create the project again "
                                "with project_create.", where=where)
        head = top.table("project")
        _check_format_version(head)
        try:
            unit = check_angle_unit(head.text("angle_unit", "degrees"))
        except InputError as exc:
            raise InputError.of("{where}: {error}", where=head.where, error=exc) from None
        cameras = {}
        for cam_name, cam in top.table("cameras").tables_by_name():
            check_identifier(cam_name, "camera", where)
            cameras[cam_name] = cam.camera(cam_name)
        images: List[ImageRecord] = []
        seen: Dict[str, str] = {}  # name -> entry that used it first
        for d in top.table_list("images"):
            name = check_identifier(d.text("name"), "image", d.where)
            _check_unique(name, "image", d, seen)
            d = d.named(f"image '{name}'")
            camera = check_identifier(d.text("camera"), "camera", d.where)
            _check_known(camera, "camera", cameras, d, "[cameras]", "camera")
            images.append(ImageRecord(
                name=name,
                path=d.text("path"),
                camera=camera,
                eo=ExteriorOrientation.from_opk(np.asarray(d.numbers("position", 3)),
                                                *d.numbers("opk", 3), unit=unit),
            ))
        image_names = set(seen)
        models = []
        seen = {}
        for d in top.table_list("models"):
            name = check_identifier(d.text("name"), "stereo model", d.where)
            _check_unique(name, "stereo model", d, seen)
            d = d.named(f"stereo model '{name}'")
            left, right = (check_identifier(d.text(k), "image", d.where) for k in ("left", "right"))
            for key, image in (("left", left), ("right", right)):
                _check_known(image, "image", image_names, d, "[[images]]", key)
            if left == right:
                raise InputError(f"{d.where}: 'left' and 'right' are both image '{left}'; a "
                                 "stereo model needs two images: fix it in the project file.")
            models.append(StereoModel(
                name=name,
                left=left,
                right=right,
                kind=d.text("kind", "manual"),
                base=d.number("base_m", float("nan")),
                b_h=d.number("b_h", float("nan")),
                overlap=d.number("overlap_pct", float("nan")) / 100.0,
                gsd=d.number("gsd_m", float("nan")),
                height_above_ground=d.number("height_above_ground_m", float("nan")),
                convergence=d.number("convergence_deg", float("nan")),
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


def _check_format_version(head: _Table) -> None:
    """Refuse a ``format_version`` this PhotoDEM cannot read (absent means the current one)."""
    version = head.integer("format_version", FORMAT_VERSION)
    if version == FORMAT_VERSION:
        return
    why = (msg("it was written by a newer PhotoDEM; update PhotoDEM to open it")
           if version > FORMAT_VERSION else msg("no PhotoDEM wrote it; fix the value"))
    raise InputError.of("{where}: 'format_version' is {version} but this PhotoDEM reads "
                        "format_version {supported} only: {why}.", where=head.where,
                        version=version, supported=FORMAT_VERSION, why=why)


def _check_unique(name: str, what: str, entry: _Table, seen: Dict[str, str]) -> None:
    """Refuse a second image or model of the same name (``seen``: name -> first entry)."""
    if name in seen:
        raise InputError(f"{entry.where}: the {what} name '{name}' is used already by "
                         f"{seen[name]}; give each {what} its own name in the project file.")
    seen[name] = entry.where[len(entry.file):].strip()


def _check_known(name: str, what: str, known: Any, entry: _Table, table: str, key: str) -> None:
    """Refuse a reference (``key`` of ``entry``) to a camera or image that the project file does
    not define in ``table``."""
    if name in known:
        return
    listed = ", ".join(sorted(known)[:10]) + (" …" if len(known) > 10 else "")
    defined = f"defined: {listed}" if listed else "it is empty"
    raise InputError(f"{entry.where}: '{key}' names {what} '{name}', which is not defined in "
                     f"{table} ({defined}); fix the name or add the {what} in the project file.")


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

    def _fail(self, key: str, problem: Message) -> InputError:
        return InputError.of("{where}: '{key}' {problem}; fix it in the project file.",
                             where=self.where, key=key, problem=problem)

    def _get(self, key: str, default: Any) -> Any:
        if key in self.data:
            return self.data[key]
        if default is _MISSING:
            raise self._fail(key, msg("is missing"))
        return default

    def text(self, key: str, default: Any = _MISSING) -> str:
        """A string value; anything else (a number too) is refused, since names and CRS codes
        written without quotes change their meaning (``left = 101`` is not image "0101")."""
        value = self._get(key, default)
        if not isinstance(value, str):
            raise self._fail(key, msg("must be text in quotes, not {value}",
                                      value=_shown(value)))
        return value

    def number(self, key: str, default: Any = _MISSING) -> Any:
        """A number (int or float) as float; ``default`` when absent."""
        value = self._get(key, default)
        if value is default and default is not _MISSING:
            return default
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise self._fail(key, msg("must be a number, not {value}", value=_shown(value)))
        return float(value)

    def integer(self, key: str, default: Any = _MISSING) -> int:
        """A whole number."""
        value = self.number(key, default)
        if value is None or value != int(value):
            raise self._fail(key, msg("must be a whole number, not {value}",
                                      value=_shown(self.data.get(key))))
        return int(value)

    def numbers(self, key: str, length: int, default: Any = _MISSING) -> List[float]:
        """A list of exactly ``length`` numbers."""
        value = self._get(key, default)
        if value is default and default is not _MISSING:
            return default
        if (not isinstance(value, list) or len(value) != length
                or any(isinstance(v, bool) or not isinstance(v, (int, float)) for v in value)):
            raise self._fail(key, msg("must be a list of {length} numbers, not {value}",
                                      length=length, value=_shown(value)))
        return [float(v) for v in value]

    def table(self, key: str) -> _Table:
        """A sub-table (empty when absent)."""
        value = self._get(key, {})
        if not isinstance(value, dict):
            raise self._fail(key, msg("must be a table ([{key}]), not {value}", key=key,
                                      value=_shown(value)))
        label = self.where[len(self.file):].strip()
        return _Table(value, self.file, f"{label} [{key}]".strip())

    def table_list(self, key: str) -> List[_Table]:
        """An array of tables (``[[key]]``; empty when absent)."""
        value = self._get(key, [])
        if not isinstance(value, list) or not all(isinstance(v, dict) for v in value):
            raise self._fail(key, msg("must be an array of tables ([[{key}]]), not {value}",
                                      key=key, value=_shown(value)))
        return [_Table(v, self.file, f"[[{key}]] #{i + 1}") for i, v in enumerate(value)]

    def tables_by_name(self) -> List[Any]:
        """``(name, sub-table)`` pairs of a table of tables (``[cameras.<name>]``)."""
        out = []
        for name, value in self.data.items():
            if not isinstance(value, dict):
                raise self._fail(name, msg("must be a table, not {value}",
                                           value=_shown(value)))
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
                raise self._fail("fiducial_affine", msg("must be 2 rows of 3 numbers, not "
                                                        "{value}", value=_shown(fid)))
        try:
            return Camera.from_dict(name, d)
        except InputError as exc:
            raise InputError.of("{where}: {error}", where=self.where, error=exc) from None


def _shown(value: Any) -> str:
    """A short description of a wrong value for a message."""
    text = repr(value)
    return text if len(text) <= 40 else text[:37] + "…"


def _drop_empty(d: Dict[str, Any]) -> Dict[str, Any]:
    return {k: v for k, v in d.items() if not (isinstance(v, (dict, list)) and len(v) == 0)}
