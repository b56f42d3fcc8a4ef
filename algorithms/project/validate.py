"""Checks of a project before any work is done, with messages an operator can act on.

These are the *content* checks: a project file whose structure is broken (wrong types, unknown
references, duplicate names, an unsupported format version) is refused by
:meth:`.model.Project.load` already (see :mod:`.model`). Callers decide what to do with the
report: :meth:`ValidationReport.raise_if_errors` raises all errors on one line.

Errors (the project cannot be used as it is):

* an image, camera or model name cannot become a folder name (see
  :func:`.model.check_identifier`);
* the CRS is missing, not understood by pyproj, or geographic (positions must be metric);
* two images share a name; an image names an unknown camera;
* an image file is missing, or its size differs from its camera's (read from the header only);
* a camera looking up: the optical axis at or above the horizon (a tilt from the nadir of 90°
  or more), which no aerial image has — usually a wrong angle unit or rotation convention;
* implausible heights: a projection centre at or below the terrain (DEM mean under the
  footprint, else the project's terrain height, else 0 m), more than 100 km above it, or a
  non-finite position.

Warnings (the run goes on): |ω| or |φ| above ``max_tilt`` (default 30°; drone and oblique frames
are tilted on purpose, but a wrong angle unit or rotation convention looks the same), a flying
height above ground below 20 m or above 15 km, and images without any stereo partner (no stereo
model contains them). Tilt is a fact to report: geometry, matching and orthos work for any frame
orientation that looks down.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Dict, List, Optional

import numpy as np
import pyproj

from ..errors import InputError
from ..geometry.stereo import footprint_and_height, load_dem
from ..raster.io import open_image
from .model import Project, identifier_errors
from .stereo_models import block_bounds, detect_stereo_models

#: Flying heights above ground (m) outside this range are reported as a warning.
PLAUSIBLE_HEIGHT_M = (20.0, 15000.0)
#: Heights above ground (m) beyond this are an error (swapped coordinates, wrong units…).
ABSURD_HEIGHT_M = 100000.0
#: |ω| or |φ| (degrees) above this is reported as a warning by default.
DEFAULT_MAX_TILT = 30.0


@dataclass
class ValidationReport:
    """Errors and warnings of :func:`validate_project` (operator-readable sentences)."""

    errors: List[str] = field(default_factory=list)
    warnings: List[str] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        return not self.errors

    def raise_if_errors(self) -> None:
        """Raise one :class:`InputError` listing every error on one line (joined with "; ")."""
        if self.errors:
            raise InputError(f"The project has {_count(self.errors)}: " + "; ".join(
                e.rstrip(".") for e in self.errors) + ".")

    def raise_first_error(self) -> None:
        """Raise one :class:`InputError` naming the number of errors and the first one, for
        callers that have reported every error already (through their feedback)."""
        if self.errors:
            raise InputError(f"The project has {_count(self.errors)} (listed above): "
                             f"{self.errors[0]}")

    def to_dict(self) -> Dict[str, List[str]]:
        return {"errors": list(self.errors), "warnings": list(self.warnings)}


def _count(errors: List[str]) -> str:
    """``"1 error"`` or ``"N errors"``."""
    return f"{len(errors)} error{'s' if len(errors) != 1 else ''}"


def check_crs(crs: Optional[str]) -> Optional[str]:
    """An error message for an unusable project CRS, or ``None``."""
    if not crs:
        return ("The project has no CRS. Give the crs parameter or a .prj file beside the "
                "exterior orientation.")
    try:
        c = pyproj.CRS.from_user_input(crs)
    except Exception as exc:  # pyproj.exceptions.CRSError
        return f"The project CRS '{str(crs)[:60]}' is not understood by PROJ ({exc})."
    if c.is_geographic:
        return (f"The project CRS '{c.name}' is geographic (degrees); photogrammetry needs a "
                "projected CRS in metres (e.g. the UTM zone of the block).")
    return None


def validate_project(project: Project, check_files: bool = True, dem: Any = None,
                     max_tilt: float = DEFAULT_MAX_TILT,
                     stereo_partners: bool = True) -> ValidationReport:
    """Check a project (see module notes for the list of checks).

    Parameters
    ----------
    project : Project
    check_files : bool
        Check that image files exist and match their camera's size (header read only).
    dem : path or DemSampler, optional
        Terrain for the height checks and footprints; default ``project.terrain_height``.
    max_tilt : float
        |ω| or |φ| above this (degrees) is reported as a warning (30° suits vertical aerial
        images; drone and oblique frames need more). A camera looking up is always an error.
    stereo_partners : bool
        Warn about images without a stereo partner; uses ``project.models`` or, when the project
        has none, :func:`~.stereo_models.detect_stereo_models` with its defaults.

    Returns
    -------
    ValidationReport
    """
    rep = ValidationReport()
    crs_error = check_crs(project.crs)
    if crs_error:
        rep.errors.append(crs_error)

    rep.errors += identifier_errors(project)  # names become folder names
    if not project.images:
        rep.errors.append("The project has no images.")
    counts: Dict[str, int] = {}
    for rec in project.images:
        counts[rec.name] = counts.get(rec.name, 0) + 1
    for name, n in counts.items():
        if n > 1:
            rep.errors.append(f"Image name '{name}' occurs {n} times; image names must be unique.")

    known = set(project.cameras)
    usable = []
    for rec in project.images:
        if rec.camera not in known:
            rep.errors.append(
                f"Image '{rec.name}' uses camera '{rec.camera}', which is not defined "
                f"(cameras: {', '.join(sorted(known)) or 'none'})."
            )
            continue
        if not np.all(np.isfinite(rec.eo.position)) or not np.all(np.isfinite(rec.eo.rotation)):
            rep.errors.append(f"Image '{rec.name}' has a non-finite position or rotation.")
            continue
        usable.append(rec)
        _check_tilt(rec, max_tilt, rep)

    if check_files:
        _check_files(project, usable, rep)
    _check_heights(project, usable, dem, rep)

    if stereo_partners and not rep.errors and len(project.images) > 0:
        models = project.models
        if not models:
            try:
                models = detect_stereo_models(project, dem=dem)
            except Exception as exc:  # geometry failures are reported, not raised, here
                rep.warnings.append(f"Stereo models could not be detected: {exc}")
                models = None
        if models is not None:
            paired = {m.left for m in models} | {m.right for m in models}
            alone = [r.name for r in project.images if r.name not in paired]
            for name in alone:
                rep.warnings.append(
                    f"Image '{name}' has no stereo partner (no other image overlaps it enough); "
                    "it can be orthorectified but not used for matching."
                )
    return rep


def tilt_from_nadir(rec: Any) -> float:
    """Angle (degrees) between an image's optical axis and the nadir (0° for a vertical image,
    90° for a camera looking at the horizon)."""
    down = -float(rec.eo.viewing_direction[2])
    return math.degrees(math.acos(max(-1.0, min(1.0, down))))


def _check_tilt(rec: Any, max_tilt: float, rep: ValidationReport) -> None:
    """An error for a camera looking up (tilt ≥ 90°), a warning for |ω| or |φ| above
    ``max_tilt``."""
    omega, phi, _ = rec.eo.opk("degrees")
    hint = ("Check the angle unit (degrees/gon/radians) and the rotation convention (PATB "
            "omega-phi-kappa, camera to world).")
    tilt = tilt_from_nadir(rec)
    if tilt >= 90.0:
        rep.errors.append(
            f"Image '{rec.name}': omega = {omega:.3f}°, phi = {phi:.3f}° point the camera "
            f"{tilt:.1f}° away from the nadir, i.e. at or above the horizon; an aerial camera "
            f"looks down. {hint}")
    elif abs(omega) > max_tilt or abs(phi) > max_tilt:
        rep.warnings.append(
            f"Image '{rec.name}': omega = {omega:.3f}°, phi = {phi:.3f}° exceed ±{max_tilt:g}° "
            f"(max_tilt; tilt from the nadir {tilt:.1f}°). Fine for a drone or oblique frame; "
            f"otherwise {hint[0].lower()}{hint[1:]}")


def _check_files(project: Project, records: List[Any], rep: ValidationReport) -> None:
    for rec in records:
        path = project.image_path(rec)
        if not path.is_file():
            rep.errors.append(f"Image '{rec.name}': file '{path}' not found.")
            continue
        try:
            with open_image(path) as src:
                w, h = src.width, src.height
        except Exception as exc:  # rasterio.errors.RasterioIOError
            rep.errors.append(f"Image '{rec.name}': '{path}' cannot be read as a raster ({exc}).")
            continue
        cam = project.cameras[rec.camera]
        if (w, h) != (cam.width, cam.height):
            hint = " (width and height swapped?)" if (h, w) == (cam.width, cam.height) else ""
            rep.errors.append(
                f"Image '{rec.name}' is {w} × {h} px but camera '{cam.name}' is "
                f"{cam.width} × {cam.height} px{hint}; fix the interior orientation or use the "
                "original images."
            )


def _check_heights(project: Project, records: List[Any], dem: Any,
                   rep: ValidationReport) -> None:
    sampler = None
    if dem is not None and records:
        try:
            sampler = load_dem(dem, block_bounds(project), crs=project.crs or None)
        except InputError as exc:  # another CRS, a DEM that does not cover the block…
            rep.errors.append(f"The DEM cannot be used for this block: {exc}")
            return
    known = sampler is not None or project.terrain_height is not None
    for rec in records:
        z_cam = float(rec.eo.position[2])
        if sampler is not None:
            terrain = float(sampler.height(rec.eo.position[0:1], rec.eo.position[1:2])[0])
            if math.isfinite(terrain) and z_cam > terrain:
                try:  # the mean under the footprint is the better reference
                    _, terrain = footprint_and_height(project.cameras[rec.camera], rec.eo,
                                                      dem=sampler)
                except Exception:  # keep the height below the camera
                    terrain = terrain
            where = "the DEM"
        elif project.terrain_height is not None:
            terrain, where = float(project.terrain_height), "the terrain height"
        else:
            terrain, where = 0.0, "0 m (no terrain height given)"
        if not math.isfinite(terrain):
            rep.warnings.append(f"Image '{rec.name}': the DEM has no height below the camera.")
            continue
        H = z_cam - terrain
        if H <= 0:
            rep.errors.append(
                f"Image '{rec.name}': the camera (Z = {z_cam:.1f} m) is not above {where} "
                f"({terrain:.1f} m). Check the height datum and the coordinate order (x, y, z)."
            )
        elif H > ABSURD_HEIGHT_M:
            rep.errors.append(
                f"Image '{rec.name}': the camera is {H / 1000:.0f} km above {where}, which is not "
                "an aerial image. Check the coordinate order (x, y, z), the units and the CRS."
            )
        elif known and not PLAUSIBLE_HEIGHT_M[0] <= H <= PLAUSIBLE_HEIGHT_M[1]:
            rep.warnings.append(
                f"Image '{rec.name}': flying height above ground {H:.1f} m is unusual for aerial "
                f"images ({PLAUSIBLE_HEIGHT_M[0]:g}–{PLAUSIBLE_HEIGHT_M[1]:g} m); check the "
                "heights and their datum."
            )


__all__ = ["ABSURD_HEIGHT_M", "DEFAULT_MAX_TILT", "PLAUSIBLE_HEIGHT_M", "ValidationReport",
           "check_crs", "tilt_from_nadir", "validate_project"]
