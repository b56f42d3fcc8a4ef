"""Algorithm declarations: project."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any, Dict

from ...errors import InputError
from ...project.model import Project
from ..feedback import Feedback
from ..spec import Algorithm, Output, Parameter


class ProjectCreate(Algorithm):
    id = "project_create"
    name = "Create project"
    group = "Project"
    group_id = "project"
    help = (
        "Creates a PhotoDEM project (project.toml + edits.gpkg) from a folder of images and their "
        "orientation: an OPK CSV or text file with the camera YAML (orthority format), or an "
        "OpenSfM/ODM reconstruction.json. The block is validated and its stereo models are "
        "detected (overlap ≥ 25 %, B/H 0.2–1.2, in-strip neighbours first)."
    )
    parameters = (
        Parameter("images", "folder", "Images folder"),
        Parameter("exterior", "file", "Exterior orientation (OPK CSV/text or reconstruction.json)",
                  extensions=(".csv", ".txt", ".json", ".opk"),
                  help="x, y, z in the project CRS; omega, phi, kappa PATB (camera to world)."),
        Parameter("interior", "file", "Interior orientation (camera YAML)", optional=True,
                  extensions=(".yaml", ".yml"),
                  help="Orthority interior-parameter YAML; not needed for OpenSfM."),
        Parameter("crs", "crs", "Project CRS", optional=True,
                  help="Optional when a .prj file lies beside the exterior file."),
        Parameter("angle_unit", "enum", "Angle unit of omega, phi, kappa", default="degrees",
                  options=("degrees", "gon", "radians")),
        Parameter("dem", "raster", "DEM for terrain heights and footprints", optional=True),
        Parameter("terrain_height", "number", "Mean terrain height [m]", optional=True,
                  unit="m", help="Used when no DEM is given."),
        Parameter("output", "output_folder", "Project folder"),
    )
    outputs = (
        Output("project", "folder", "Project folder"),
        Output("images", "number", "Number of images"),
        Output("cameras", "number", "Number of cameras"),
        Output("models", "json", "Names of the stereo models"),
        Output("warnings", "json", "Validation warnings"),
    )

    def run(self, params: Dict[str, Any], feedback: Feedback) -> Dict[str, Any]:
        from ...geometry.stereo import (
            _block_bounds,
            block_footprints,
            detect_stereo_models,
            load_dem,
            mean_terrain_height,
        )
        from ...project.edits import create_edits
        from ...project.importers import import_project
        from ...project.validate import validate_project
        from ...raster.io import staged_folder

        out = Path(params["output"])
        if out.exists() and any(out.iterdir()):
            raise InputError(
                f"The output folder '{out}' exists and is not empty; choose a new project folder."
            )
        feedback.progress(2)
        project, warnings = import_project(
            out, params["images"], params["exterior"], params.get("interior"),
            crs=params.get("crs"), angle_unit=params["angle_unit"],
        )
        feedback.info(f"Read {len(project.images)} images and {len(project.cameras)} camera(s).")
        feedback.progress(20)

        # structural errors first: without them the geometry below is meaningful
        report = validate_project(project, check_files=True, stereo_partners=False)
        report.raise_if_errors()
        feedback.progress(35)

        dem = params.get("dem")
        if dem is not None:
            dem = load_dem(dem, _block_bounds(project))
            footprints = block_footprints(project, dem=dem)
            project.terrain_height = round(mean_terrain_height(footprints), 3)
            feedback.info(f"Mean terrain height under the footprints (DEM): "
                          f"{project.terrain_height:.1f} m.")
        else:
            if params.get("terrain_height") is not None:
                project.terrain_height = float(params["terrain_height"])
            else:
                project.terrain_height = 0.0
                warnings.append("No DEM and no terrain height given: the terrain is assumed at "
                                "0 m for footprints, overlaps and B/H.")
            footprints = block_footprints(project)
        feedback.progress(55)

        report = validate_project(project, check_files=False, dem=dem, stereo_partners=False)
        report.raise_if_errors()
        project.models = detect_stereo_models(project, footprints=footprints)
        paired = {m.left for m in project.models} | {m.right for m in project.models}
        for rec in project.images:
            if rec.name not in paired:
                warnings.append(f"Image '{rec.name}' has no stereo partner (no other image "
                                "overlaps it enough); it cannot be used for matching.")
        warnings += report.warnings
        for w in warnings:
            feedback.warning(w)
        kinds = [m.kind for m in project.models]
        feedback.info(f"Stereo models: {kinds.count('in-strip')} in-strip, "
                      f"{kinds.count('cross-strip')} cross-strip.")
        feedback.progress(80)

        with staged_folder(out, product=self.id) as tmp:
            staged = Project(root=tmp, name=project.name, crs=project.crs,
                             cameras=project.cameras, images=project.images,
                             models=project.models, terrain_height=project.terrain_height,
                             angle_unit=project.angle_unit)
            staged.save()
            create_edits(staged.edits_path, project.crs)
            feedback.check()
        return {
            "project": str(out),
            "images": len(project.images),
            "cameras": len(project.cameras),
            "models": [m.name for m in project.models],
            "warnings": warnings,
        }


class ProjectInfo(Algorithm):
    id = "project_info"
    name = "Project information"
    group = "Project"
    group_id = "project"
    help = (
        "Lists a project's CRS, images (position, angles in degrees, whether the file exists), "
        "cameras and stereo models (B/H, overlap %, GSD, flying height above ground), and the "
        "result of its validation."
    )
    parameters = (Parameter("project", "project", "Project folder"),)
    outputs = (
        Output("name", "string", "Project name"),
        Output("crs", "string", "Project CRS"),
        Output("images", "json", "Images"),
        Output("cameras", "json", "Cameras"),
        Output("models", "json", "Stereo models"),
        Output("validation", "json", "Validation errors and warnings"),
    )

    def run(self, params: Dict[str, Any], feedback: Feedback) -> Dict[str, Any]:
        from ...project.validate import validate_project

        project = Project.load(params["project"])
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
        report = validate_project(project, check_files=True)
        for w in report.warnings:
            feedback.warning(w)
        for e in report.errors:
            feedback.warning("ERROR: " + e)
        return {
            "name": project.name,
            "crs": project.crs,
            "images": images,
            "cameras": cameras,
            "models": [{k: (None if isinstance(v, float) and not math.isfinite(v) else v)
                        for k, v in m.items()} for m in models],
            "validation": report.to_dict(),
        }

ALGORITHMS: list = [ProjectCreate, ProjectInfo]
