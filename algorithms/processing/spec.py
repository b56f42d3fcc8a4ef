"""One declaration per operation: typed parameters, typed outputs and a ``run`` function.

From these specs the project builds its four faces: the QGIS Processing provider, the standalone
toolbox, the ``photodem`` CLI and batch steps. A spec never imports Qt or QGIS.

Parameter values reach :meth:`Algorithm.run` already checked and converted by
:func:`prepare_parameters` (the same function for every face), so a run gives the same result
whichever face started it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

from ..errors import InputError, Message, msg
from ..feedback import Feedback
from ..input_errors import display_path
from ..output_policy import PROJECT_FILE, PROJECT_PARTS, Target, contained

#: Parameter kinds. Paths are passed on as ``str``.
INPUT_PATH_KINDS = ("raster", "vector", "file", "folder", "project")
OUTPUT_KINDS = ("output_file", "output_folder", "output_raster", "output_vector")
PARAMETER_KINDS = (
    *INPUT_PATH_KINDS,
    *OUTPUT_KINDS,
    "model",  # name of a stereo model in the project, e.g. "0182_0184"
    "image",  # name of an image in the project
    "number",
    "integer",
    "enum",
    "bool",
    "crs",
    "extent",
    "string",
    "multiple_rasters",
)
#: ``html`` is a file the faces may show as a report (QGIS: the Results Viewer); the CLI treats it
#: like ``file``.
OUTPUT_VALUE_KINDS = ("file", "html", "folder", "raster", "vector", "number", "string", "json")


@dataclass(frozen=True)
class Parameter:
    """A typed input of an algorithm.

    Parameters
    ----------
    name : str
        snake_case name; the CLI flag is ``--name-with-dashes``.
    kind : str
        One of :data:`PARAMETER_KINDS`.
    description : str
        Short label (English; translated in the GUIs), with the unit in brackets.
    default : object, optional
        Default value; ``None`` with ``optional=False`` means the parameter is required.
    optional : bool
        The parameter may be left empty (value ``None``).
    minimum, maximum : float, optional
        Bounds for ``number`` and ``integer``.
    options : tuple of str
        Choices of an ``enum``; the value is the option string.
    aliases : tuple of str
        Old names an ``enum`` still accepts (not offered as choices); the value is the alias
        itself, so that the algorithm can map it and tell the operator the new name.
    unit : str
        Unit of a number (``"m"``, ``"px"``, ``"%"``, ``"°"``); shown to the operator.
    extensions : tuple of str
        File name endings accepted for file parameters (``".csv"``); empty accepts all.
    help : str
        One or two sentences for the help text.
    """

    name: str
    kind: str
    description: str
    default: Any = None
    optional: bool = False
    minimum: Optional[float] = None
    maximum: Optional[float] = None
    options: Tuple[str, ...] = ()
    aliases: Tuple[str, ...] = ()
    unit: str = ""
    extensions: Tuple[str, ...] = ()
    help: str = ""

    def __post_init__(self) -> None:
        if self.kind not in PARAMETER_KINDS:
            raise ValueError(f"unknown parameter kind {self.kind!r} for {self.name!r}")
        if self.is_choice and not self.options:
            raise ValueError(f"enum parameter {self.name!r} needs options")

    @property
    def flag(self) -> str:
        """The CLI flag, ``--name-with-dashes``."""
        return "--" + self.name.replace("_", "-")

    @property
    def required(self) -> bool:
        return not self.optional and self.default is None

    # -- what the kind means (the faces switch on these, not on the kind strings) ------------
    @property
    def is_output(self) -> bool:
        """A path the run writes (``output_*``)."""
        return self.kind in OUTPUT_KINDS

    @property
    def is_input_path(self) -> bool:
        """One path the run reads (raster, vector, file, folder, project)."""
        return self.kind in INPUT_PATH_KINDS

    @property
    def is_list(self) -> bool:
        """A list of input paths (``multiple_rasters``; text: comma-separated)."""
        return self.kind == "multiple_rasters"

    @property
    def is_path(self) -> bool:
        """The value is a path or a list of paths, read or written."""
        return self.is_input_path or self.is_output or self.is_list

    @property
    def is_folder(self) -> bool:
        """The path names a folder (a project is a folder too)."""
        return self.kind in ("folder", "project", "output_folder")

    @property
    def is_project(self) -> bool:
        """A PhotoDEM project folder (or its ``project.toml``)."""
        return self.kind == "project"

    @property
    def is_item_name(self) -> bool:
        """The name of a stereo model or an image of the project."""
        return self.kind in ("model", "image")

    @property
    def is_numeric(self) -> bool:
        """A number (``number``) or a whole number (``integer``)."""
        return self.kind in ("number", "integer")

    @property
    def is_integer(self) -> bool:
        """A whole number."""
        return self.kind == "integer"

    @property
    def is_choice(self) -> bool:
        """One of :attr:`options` (``enum``)."""
        return self.kind == "enum"

    @property
    def is_bool(self) -> bool:
        """A yes/no value."""
        return self.kind == "bool"

    @property
    def is_text(self) -> bool:
        """Passed on as ``str`` unchanged: a name, a CRS or free text."""
        return self.kind in ("model", "image", "string", "crs")

    def paths(self, value: Any) -> List[str]:
        """The paths of a converted value of a path parameter (``[]`` for ``None``)."""
        if value is None:
            return []
        return list(value) if self.is_list else [value]

    # -- conversion ---------------------------------------------------------------------------
    def convert(self, value: Any) -> Any:
        """Check ``value`` and convert it to the type ``run`` receives.

        Strings (from the CLI or a batch file) are parsed; ``None`` and ``""`` mean "not given".

        Raises
        ------
        InputError
            With a message naming the parameter and the accepted values.
        """
        if value is None or (isinstance(value, str) and value.strip() == ""):
            if self.default is not None:
                value = self.default
            elif self.optional:
                return None
            else:
                # the description is a spec string: the GUIs translate it like the form does
                raise InputError.of("Parameter '{name}' ({description}) is required.",
                                    name=self.name, description=Message(self.description))
        try:
            if self.is_input_path or self.is_output:
                return self._path_text(value)
            if self.is_text:
                return str(value)
            if self.is_numeric:
                return self._to_number(value)
            if self.is_bool:
                return _to_bool(value)
            if self.is_choice:
                return self._to_option(value)
            if self.kind == "extent":
                return _to_extent(value)
            if self.is_list:
                return [self._path_text(part) for part in split_list(value)]
        except InputError:
            raise
        except (TypeError, ValueError, OverflowError):  # OverflowError: int(inf)
            pass
        raise InputError.of("Parameter '{name}': {value} is not a valid {expected}.",
                            name=self.name, value=repr(value), expected=self._expected())

    def _path_text(self, value: Any) -> str:
        """A path as ``str``. Output names that are not valid UTF-8 are refused: GDAL writes
        UTF-8 names only. Such input names pass; a raster among them is refused by the
        pre-flight check (:func:`~..input_errors.check_raster_parameters`), text files work."""
        text = str(Path(str(value)).expanduser())
        if self.is_output:
            try:
                text.encode("utf-8")
            except UnicodeEncodeError:
                raise InputError.of(
                    "Parameter '{name}': the path '{path}' is not valid UTF-8; rename it (GDAL "
                    "reads and writes UTF-8 names only).", name=self.name, path=display_path(text)
                ) from None
        return text

    def _to_number(self, value: Any) -> Any:
        """A ``float`` (``number``) or an ``int`` (``integer``), checked against the range."""
        number = float(value)
        if self.is_integer:
            if number != int(number):
                raise ValueError(value)
            self._check_range(number)
            return int(number)
        self._check_range(number)
        return number

    def _check_range(self, number: float) -> None:
        if not math.isfinite(number):
            raise InputError.of("Parameter '{name}' must be a finite number, not {number}.",
                                name=self.name, number=number)
        low = -math.inf if self.minimum is None else self.minimum
        high = math.inf if self.maximum is None else self.maximum
        if not low <= number <= high:
            unit = f" {self.unit}" if self.unit else ""
            raise InputError.of(
                "Parameter '{name}' = {number:g}{unit} is outside the allowed range "
                "{low:g}…{high:g}{unit}.", name=self.name, number=number, unit=unit, low=low,
                high=high)

    def _to_option(self, value: Any) -> str:
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            index = int(value)
            if 0 <= index < len(self.options) and index == value:
                return self.options[index]
        text = str(value).strip().lower()
        for option in self.options + self.aliases:
            if option.lower() == text:
                return option
        raise InputError.of("Parameter '{name}': {value} is not one of {options}.",
                            name=self.name, value=repr(value), options=", ".join(self.options))

    def _expected(self) -> Union[Message, str]:
        """What a value of this kind is: a phrase the GUIs translate, else the kind."""
        return {
            "number": msg("number"),
            "integer": msg("whole number"),
            "bool": msg("yes/no value (true/false)"),
            "extent": msg("extent 'xmin,ymin,xmax,ymax'"),
        }.get(self.kind, self.kind)

    def to_dict(self) -> Dict[str, Any]:
        """A JSON-friendly description (for ``photodem help --json`` and the GUIs)."""
        return {
            "name": self.name,
            "kind": self.kind,
            "description": self.description,
            "default": self.default,
            "optional": self.optional,
            "minimum": self.minimum,
            "maximum": self.maximum,
            "options": list(self.options),
            "unit": self.unit,
            "extensions": list(self.extensions),
            "help": self.help,
        }


@dataclass(frozen=True)
class Output:
    """A typed result of an algorithm (a key of the dict ``run`` returns)."""

    name: str
    kind: str
    description: str

    def __post_init__(self) -> None:
        if self.kind not in OUTPUT_VALUE_KINDS:
            raise ValueError(f"unknown output kind {self.kind!r} for {self.name!r}")

    @property
    def is_path(self) -> bool:
        """The value is the path of a file or folder the run wrote."""
        return self.kind in ("file", "html", "folder", "raster", "vector")


class Algorithm:
    """Base class of every PhotoDEM operation.

    Subclasses set the class attributes and implement :meth:`run`. ``run`` receives the
    converted parameters (see :func:`prepare_parameters`) and a :class:`Feedback`, and returns a
    dict whose keys are the names of :attr:`outputs` (paths as ``str``, numbers, JSON-friendly
    dicts). It must leave no output behind when it fails or is cancelled.
    """

    id: str = ""
    name: str = ""
    group: str = ""
    group_id: str = ""
    help: str = ""
    parameters: Tuple[Parameter, ...] = ()
    outputs: Tuple[Output, ...] = ()
    #: Parameter that batch runs iterate over ("model" or "image"), if any.
    iterates_over: Optional[str] = None

    def parameter(self, name: str) -> Parameter:
        for p in self.parameters:
            if p.name == name:
                return p
        raise KeyError(name)

    def run(self, params: Dict[str, Any], feedback: Feedback) -> Dict[str, Any]:
        raise NotImplementedError

    # -- outputs: where a run writes, known before it starts ---------------------------------
    def default_output(self, params: Dict[str, Any]) -> Optional[Path]:
        """The ``output`` used when none is given (derived from the project), or ``None``.

        Algorithms with a derived default override this; :meth:`output_path` (used by
        :meth:`run`) and :meth:`output_targets` (checked before the run) both go through it.
        """
        return None

    def output_path(self, params: Dict[str, Any], name: str = "output") -> Optional[Path]:
        """The path of output parameter ``name``: the given one, else the derived default."""
        value = params.get(name)
        if value:
            return Path(value)
        return self.default_output(params) if name == "output" else None

    def sidecars(self, name: str, path: Path) -> List[Path]:
        """Files written beside the file output ``name`` at ``path`` (reports, masks)."""
        return []

    def output_targets(self, params: Dict[str, Any]) -> List[Target]:
        """Every path a run with ``params`` writes, for the output policy."""
        targets: List[Target] = []
        for p in self.parameters:
            if not p.is_output:
                continue
            path = self.output_path(params, p.name)
            if path is None:
                continue
            kind = "folder" if p.is_folder else "file"
            targets.append(Target(path, kind, p.name))
            if kind == "file" and path.name and not path.is_dir():  # else refused as a target
                targets += [Target(side, "file", p.name, owner=path)
                            for side in self.sidecars(p.name, path)]
        return targets

    def input_paths(self, params: Dict[str, Any]) -> Tuple[List[Path], List[Path]]:
        """The input paths of a run and the files a ``project`` input brings in.

        Returns
        -------
        inputs, protected : list of Path
            The paths given as inputs; the project files (``project.toml``, ``edits.gpkg``,
            ``images/`` and every image it references) of project inputs.
        """
        inputs: List[Path] = []
        protected: List[Path] = []
        for p in self.parameters:
            value = params.get(p.name)
            if value is None:
                continue
            if p.is_list or p.is_input_path:
                inputs += [Path(v) for v in p.paths(value)]
            if p.is_project:
                protected += project_files(Path(value))
        return inputs, protected

    def to_dict(self) -> Dict[str, Any]:
        return {
            "id": self.id,
            "name": self.name,
            "group": self.group,
            "help": self.help,
            "parameters": [p.to_dict() for p in self.parameters],
            "outputs": [{"name": o.name, "kind": o.kind, "description": o.description}
                        for o in self.outputs],
        }


def prepare_parameters(algorithm: Algorithm, values: Dict[str, Any]) -> Dict[str, Any]:
    """Check and convert raw parameter values for ``algorithm``.

    Unknown names are an error (a typo must not silently fall back to a default); missing
    optional ones become their default or ``None``; input paths must exist. Where the outputs
    may go (not onto an input, a project, a foreign file) is the output policy's matter,
    checked next by :func:`.registry.check_outputs`.

    Raises
    ------
    InputError
        Naming the first parameter that is wrong.
    """
    known = {p.name for p in algorithm.parameters}
    unknown = sorted(set(values) - known)
    if unknown:
        raise InputError.of("{algorithm}: unknown parameter(s) {unknown}; known are {known}.",
                            algorithm=algorithm.id, unknown=", ".join(unknown),
                            known=", ".join(sorted(known)))
    params = {p.name: p.convert(values.get(p.name)) for p in algorithm.parameters}
    for p in algorithm.parameters:
        if p.is_input_path or p.is_list:
            for path in p.paths(params[p.name]):
                if not Path(path).exists():
                    raise InputError.of("Parameter '{name}': '{path}' does not exist.",
                                        name=p.name, path=path)
    return params


def split_list(value: Any) -> List[str]:
    """The items of a list parameter: a list, or text with commas (``"a.tif,b.tif"``), or a
    list of such texts; blanks around the items and empty items are dropped."""
    items = [value] if isinstance(value, str) else list(value)
    parts = [part for item in items for part in str(item).split(",")]
    return [part.strip() for part in parts if part.strip()]


def project_product(params: Dict[str, Any], step: str, name: str, what: str) -> Path:
    """``<project>/products/<step>/<name>``, checked to stay inside ``products/<step>/``.

    ``what`` names the source of ``name`` in the message (e.g. "Stereo model 'x'").
    """
    base = _read_project(params["project"])[0].products_dir(step)
    return contained(base / name, base, what)


def model_product(params: Dict[str, Any], step: str) -> Path:
    """``<project>/products/<step>/<model>/`` of the ``model`` parameter."""
    name = _read_project(params["project"])[0].model(params["model"]).name
    return project_product(params, step, name, f"Stereo model '{name}'")


def project_files(path: Path) -> List[Path]:
    """The files of the project at ``path`` that no output may replace, resolved:
    ``project.toml``, ``edits.gpkg``, ``images/``, ``.photodem/`` and every image.

    A project that cannot be read yields its parts by name only: the run that reads it names
    the problem itself, and the parts stay protected meanwhile.
    """
    try:
        return _read_project(path)[1]
    except InputError:
        root = Path(path).parent if Path(path).suffix == ".toml" else Path(path)
        return [(root / part).resolve() for part in PROJECT_PARTS]


#: Projects read for the output checks, by file identity (path, mtime, size) → (project, its
#: resolved files). The checks of a batch over hundreds of models would otherwise parse
#: ``project.toml`` and resolve every image path several times per task. Read-only use.
_PROJECTS: Dict[Tuple[str, int, int], Tuple[Any, List[Path]]] = {}


def _read_project(path: Any) -> Tuple[Any, List[Path]]:
    """The project at ``path`` and its resolved files, read again only when the file changed."""
    from ..project.model import Project  # lazy: keeps photodem list fast (numpy and friends)

    file = Path(path) / PROJECT_FILE if Path(path).is_dir() else Path(path)
    try:
        stat = file.stat()
    except OSError:
        Project.load(path)  # names the problem
        raise
    key = (str(file.resolve()), stat.st_mtime_ns, stat.st_size)
    entry = _PROJECTS.get(key)
    if entry is None:
        project = Project.load(path)
        files = [project.project_file, project.edits_path, project.root / "images",
                 project.root / ".photodem", *(project.image_path(r) for r in project.images)]
        entry = (project, [f.resolve() for f in files])
        if len(_PROJECTS) >= 16:
            _PROJECTS.clear()
        _PROJECTS[key] = entry
    return entry


def _to_bool(value: Any) -> bool:
    if isinstance(value, bool):
        return value
    if isinstance(value, (int, float)) and value in (0, 1):
        return bool(value)
    text = str(value).strip().lower()
    if text in ("1", "true", "yes", "y", "on", "ja"):
        return True
    if text in ("0", "false", "no", "n", "off", "nein"):
        return False
    raise ValueError(value)


def _to_extent(value: Any) -> Tuple[float, float, float, float]:
    if isinstance(value, str):
        text = value.split("[")[0]  # QGIS appends " [EPSG:xxxx]"
        parts: Sequence[Any] = [v for v in text.replace(";", ",").split(",") if v.strip()]
    else:
        parts = list(value)
    xmin, ymin, xmax, ymax = (float(v) for v in parts)
    if not (xmin < xmax and ymin < ymax):
        raise ValueError(value)
    return (xmin, ymin, xmax, ymax)


__all__ = [
    "OUTPUT_KINDS",
    "PARAMETER_KINDS",
    "Algorithm",
    "Output",
    "Parameter",
    "model_product",
    "prepare_parameters",
    "project_product",
    "split_list",
]
