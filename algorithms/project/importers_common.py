"""What every orientation importer shares: the imported block, CRS helpers, interior orientation
from normalised (orthority/OpenSfM) parameters and image-name stems.

See :mod:`.importers` for the formats and their conventions.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

import pyproj

from ..errors import InputError
from ..geometry.camera import Camera
from ..geometry.orientation import ExteriorOrientation

PathLike = Union[str, Path]
IMAGE_EXTENSIONS = (".tif", ".tiff", ".jpg", ".jpeg", ".png")


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
    #: numbers of the import's checks (e.g. camera centres against the file's GPS positions)
    checks: Dict[str, Any] = field(default_factory=dict)


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


def resolve_crs(path: PathLike, crs: Optional[str], warnings: List[str]) -> Optional[str]:
    from_prj = crs_from_prj(path)
    if crs:
        given = normalise_crs(crs)
        if from_prj is not None and not same_crs(given, from_prj):
            warnings.append(
                f"The CRS parameter differs from the .prj beside '{Path(path).name}'; "
                "the parameter is used."
            )
        return given
    return from_prj


def same_crs(a: str, b: str) -> bool:
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


def image_stem(name: str) -> str:
    """``name`` without an image extension (``DJI_0001.JPG`` → ``DJI_0001``), else as it is."""
    p = Path(name.strip())
    return p.stem if p.suffix.lower() in IMAGE_EXTENSIONS else p.name
