"""What a project holds, for the operator: images, cameras, stereo models and validation."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any, Dict, Union

from ..feedback import Feedback
from .model import Project
from .validate import DEFAULT_MAX_TILT, validate_project


def project_info(path: Union[str, Path], feedback: Feedback,
                 max_tilt: float = DEFAULT_MAX_TILT) -> Dict[str, Any]:
    """List a project's CRS, images, cameras and stereo models and validate it.

    Validation warnings and errors go to ``feedback`` (errors as warnings starting with
    ``ERROR:``), so the operator sees all of them; then the first error is raised.

    Parameters
    ----------
    path : str or Path
        Project folder or ``project.toml``.
    feedback : Feedback
        Receives the validation messages.
    max_tilt : float
        |ω| or |φ| above this (degrees) is reported as a warning.

    Returns
    -------
    dict
        ``name``, ``crs``, ``images`` (position, angles in degrees, whether the file exists),
        ``cameras``, ``models`` (non-finite figures as ``None``) and ``validation``.

    Raises
    ------
    InputError
        The first validation error, after all were reported.
    """
    project = Project.load(path)
    images = []
    for rec in project.images:
        omega, phi, kappa = rec.eo.opk("degrees")
        x, y, z = (float(v) for v in rec.eo.position)
        images.append({
            "name": rec.name, "camera": rec.camera, "path": rec.path,
            "x": x, "y": y, "z": z, "omega": omega, "phi": phi, "kappa": kappa,
            "exists": project.image_path(rec).is_file(),
        })
    cameras = {name: cam.to_dict() for name, cam in project.cameras.items()}
    models = [m.to_dict() for m in project.models]
    report = validate_project(project, check_files=True, max_tilt=max_tilt)
    for w in report.warnings:
        feedback.warning(w)
    for e in report.errors:
        feedback.warning("ERROR: " + e)
    report.raise_first_error()  # every error is listed above; exit 2 with the first
    return {
        "name": project.name,
        "crs": project.crs,
        "images": images,
        "cameras": cameras,
        "models": [{k: (None if isinstance(v, float) and not math.isfinite(v) else v)
                    for k, v in m.items()} for m in models],
        "validation": report.to_dict(),
    }
