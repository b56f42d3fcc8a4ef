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
        with open_image(path) as src:
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
        try:
            data = toml_io.loads(file.read_text(encoding="utf-8"))
        except Exception as exc:  # tomllib.TOMLDecodeError and friends
            raise InputError(f"Cannot read {file}: {exc}") from exc
        head = data.get("project", {})
        unit = check_angle_unit(head.get("angle_unit", "degrees"))
        cameras = {n: Camera.from_dict(n, d) for n, d in data.get("cameras", {}).items()}
        images = [
            ImageRecord(
                name=str(d["name"]),
                path=str(d["path"]),
                camera=str(d["camera"]),
                eo=ExteriorOrientation.from_opk(np.asarray(d["position"], float), *d["opk"],
                                                unit=unit),
            )
            for d in data.get("images", [])
        ]
        return cls(
            root=file.parent,
            name=str(head.get("name", file.parent.name)),
            crs=str(head.get("crs", "")),
            cameras=cameras,
            images=images,
            models=[StereoModel.from_dict(d) for d in data.get("models", [])],
            terrain_height=head.get("terrain_height_m"),
            presets=dict(data.get("presets", {})),
            products=dict(data.get("products", {})),
            angle_unit=unit,
        )


def _drop_empty(d: Dict[str, Any]) -> Dict[str, Any]:
    return {k: v for k, v in d.items() if not (isinstance(v, (dict, list)) and len(v) == 0)}
