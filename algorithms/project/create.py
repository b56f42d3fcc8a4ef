"""A new project from a folder of images and their orientation (``project_create``).

import (OPK list + camera YAML, or an OpenSfM reconstruction) → structural validation →
terrain height (mean of a DEM under the footprints, a given height, or 0 m with a warning) →
geometric validation → stereo models → ``project.toml`` and an empty ``edits.gpkg``, written
into a staged folder that becomes the project only when everything succeeded.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Dict, List, Optional, Union

from ..errors import InputError
from ..feedback import Feedback, ensure_feedback
from ..geometry.stereo import load_dem, mean_terrain_height
from ..raster.io import staged_folder
from .edits import create_edits
from .importers import import_project
from .model import Project
from .stereo_models import block_bounds, block_footprints, detect_stereo_models
from .validate import DEFAULT_MAX_TILT, validate_project

PathLike = Union[str, Path]


def create_project(output: PathLike, images: PathLike, exterior: PathLike,
                   interior: Optional[PathLike] = None, crs: Optional[str] = None,
                   angle_unit: str = "degrees", dem: Optional[PathLike] = None,
                   terrain_height: Optional[float] = None, max_tilt: float = DEFAULT_MAX_TILT,
                   feedback: Optional[Feedback] = None) -> Dict[str, Any]:
    """Create the project folder ``output`` (new or empty); nothing is left when it fails.

    Parameters
    ----------
    output : path
        The project folder.
    images : path
        Folder of the images.
    exterior : path
        Exterior orientation: OPK CSV/text (x, y, z in the project CRS; omega, phi, kappa
        PATB) or an OpenSfM ``reconstruction.json``.
    interior : path, optional
        Camera YAML (orthority format); not needed for OpenSfM.
    crs : str, optional
        Project CRS; optional when a ``.prj`` file lies beside ``exterior``.
    angle_unit : {"degrees", "gon", "radians"}
        Unit of omega, phi, kappa.
    dem : path, optional
        DEM for the terrain height and the footprints.
    terrain_height : float, optional
        Mean terrain height (m), used when no DEM is given.
    max_tilt : float
        |ω| or |φ| above this (degrees) is a warning, not an error (drone and oblique frames).
    feedback : Feedback, optional
        Progress, log and cancellation.

    Returns
    -------
    dict
        ``project`` (path), ``images``, ``cameras`` (counts), ``models`` (names) and
        ``warnings`` (validation warnings, also sent to ``feedback``).

    Raises
    ------
    InputError
        An output folder that is not empty, unreadable inputs, validation errors.
    """
    feedback = ensure_feedback(feedback)
    out = Path(output)
    if out.exists() and any(out.iterdir()):
        raise InputError(
            f"The output folder '{out}' exists and is not empty; choose a new project folder."
        )
    feedback.progress(2)
    project, warnings = import_project(out, images, exterior, interior, crs=crs,
                                       angle_unit=angle_unit)
    feedback.info(f"Read {len(project.images)} images and {len(project.cameras)} camera(s).")
    feedback.progress(20)
    # structural errors first: without them the geometry below is meaningful
    validate_project(project, check_files=True, max_tilt=max_tilt,
                     stereo_partners=False).raise_if_errors()
    feedback.progress(35)
    dem_grid, footprints = _terrain(project, dem, terrain_height, warnings, feedback)
    feedback.progress(55)
    report = validate_project(project, check_files=False, dem=dem_grid, max_tilt=max_tilt,
                              stereo_partners=False)
    report.raise_if_errors()
    project.models = detect_stereo_models(project, footprints=footprints)
    warnings += _unpaired_images(project)
    warnings += report.warnings
    for w in warnings:
        feedback.warning(w)
    kinds = [m.kind for m in project.models]
    feedback.info(f"Stereo models: {kinds.count('in-strip')} in-strip, "
                  f"{kinds.count('cross-strip')} cross-strip.")
    feedback.progress(80)
    _write_project(out, project, feedback)
    return {
        "project": str(out),
        "images": len(project.images),
        "cameras": len(project.cameras),
        "models": [m.name for m in project.models],
        "warnings": warnings,
    }


def _terrain(project: Project, dem: Optional[PathLike], terrain_height: Optional[float],
             warnings: List[str], feedback: Feedback) -> tuple:
    """Set ``project.terrain_height`` and return the loaded DEM (or ``None``) and the image
    footprints on the terrain.

    With a DEM: the mean DEM height under the footprints (rounded to mm); else the given
    height, else 0 m with a warning appended to ``warnings``.
    """
    if dem is not None:
        grid = load_dem(dem, block_bounds(project), crs=project.crs)
        footprints = block_footprints(project, dem=grid)
        project.terrain_height = round(mean_terrain_height(footprints), 3)
        feedback.info(f"Mean terrain height under the footprints (DEM): "
                      f"{project.terrain_height:.1f} m.")
        return grid, footprints
    if terrain_height is not None:
        project.terrain_height = float(terrain_height)
    else:
        project.terrain_height = 0.0
        warnings.append("No DEM and no terrain height given: the terrain is assumed at "
                        "0 m for footprints, overlaps and B/H.")
    return None, block_footprints(project)


def _unpaired_images(project: Project) -> List[str]:
    """A warning for every image that belongs to no stereo model."""
    paired = {m.left for m in project.models} | {m.right for m in project.models}
    return [f"Image '{rec.name}' has no stereo partner (no other image overlaps it enough); "
            "it cannot be used for matching." for rec in project.images
            if rec.name not in paired]


def _write_project(out: Path, project: Project, feedback: Feedback) -> None:
    """Write ``project.toml`` and an empty ``edits.gpkg`` into a staged folder that becomes
    ``out`` when both are complete."""
    with staged_folder(out, product="project_create") as tmp:
        staged = Project(root=tmp, name=project.name, crs=project.crs,
                         cameras=project.cameras, images=project.images,
                         models=project.models, terrain_height=project.terrain_height,
                         angle_unit=project.angle_unit)
        staged.save()
        create_edits(staged.edits_path, project.crs)
        feedback.check()
