"""Algorithm declarations: project.

The domain modules are imported inside ``run`` (lazy: keeps ``photodem list`` fast).
"""

from __future__ import annotations

from typing import Any, Dict

from ...feedback import Feedback
from ..spec import Algorithm, Output, Parameter


class ProjectCreate(Algorithm):
    id = "project_create"
    name = "Create project"
    group = "Project"
    group_id = "project"
    help = (
        "Creates a PhotoDEM project (project.toml + edits.gpkg) from a folder of images and their "
        "orientation: an OPK CSV or text file with the camera YAML (orthority format), "
        "orthority's exterior GeoJSON, or an OpenSfM/ODM reconstruction.json (in an ODM "
        "project: opensfm/reconstruction.json; its frame is read from ODM's georeferencing "
        "files and checked against the GPS positions). The block is validated and its stereo "
        "models are "
        "detected (overlap ≥ 25 %, B/H 0.2–1.2, in-strip neighbours first)."
    )
    parameters = (
        Parameter("images", "folder", "Images folder"),
        Parameter("exterior", "file", "Exterior orientation (OPK CSV/text, GeoJSON or "
                  "reconstruction.json)",
                  extensions=(".csv", ".txt", ".json", ".geojson", ".opk"),
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
        Parameter("max_tilt", "number", "Largest tilt without a warning [°]", default=30.0,
                  minimum=0.0, maximum=90.0, unit="°",
                  help="|omega| or |phi| above this is reported as a warning (30° suits "
                       "vertical aerial images; drone and oblique frames are tilted more). Only "
                       "a camera looking up is refused."),
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
        from ...project.create import create_project

        return create_project(
            params["output"], params["images"], params["exterior"], params.get("interior"),
            crs=params.get("crs"), angle_unit=params["angle_unit"], dem=params.get("dem"),
            terrain_height=params.get("terrain_height"), max_tilt=params["max_tilt"],
            feedback=feedback)


class ProjectInfo(Algorithm):
    id = "project_info"
    name = "Project information"
    group = "Project"
    group_id = "project"
    help = (
        "Lists a project's CRS, images (position, angles in degrees, whether the file exists), "
        "cameras and stereo models (B/H, overlap %, GSD, flying height above ground), and the "
        "result of its validation. Validation warnings (tilts above max_tilt, unusual flying "
        "heights, images without a stereo partner) and errors are reported; a project with "
        "errors (a CRS PROJ does not know, no images, missing image files, a camera looking "
        "up…) ends with an error naming the first of them (exit code 2 on the command line)."
    )
    parameters = (
        Parameter("project", "project", "Project folder"),
        Parameter("max_tilt", "number", "Largest tilt without a warning [°]", default=30.0,
                  minimum=0.0, maximum=90.0, unit="°",
                  help="|omega| or |phi| above this is reported as a warning (30° suits "
                       "vertical aerial images; drone and oblique frames are tilted more). Only "
                       "a camera looking up is refused."),
    )
    outputs = (
        Output("name", "string", "Project name"),
        Output("crs", "string", "Project CRS"),
        Output("images", "json", "Images"),
        Output("cameras", "json", "Cameras"),
        Output("models", "json", "Stereo models"),
        Output("validation", "json", "Validation errors and warnings"),
    )

    def run(self, params: Dict[str, Any], feedback: Feedback) -> Dict[str, Any]:
        from ...project.info import project_info

        return project_info(params["project"], feedback, max_tilt=params["max_tilt"])


class StereoModels(Algorithm):
    id = "stereo_models"
    name = "Stereo models"
    group = "Project"
    group_id = "project"
    help = (
        "Sets the stereo models of a project: detected automatically from the image footprints "
        "(overlap, B/H and strip thresholds as given; in-strip neighbours first) and/or chosen "
        "by hand as pairs of images. The models are written to project.toml; the images, "
        "orientations and edits are not touched."
    )
    parameters = (
        Parameter("project", "project", "Project folder"),
        Parameter("detect", "bool", "Detect models automatically", default=True),
        Parameter("min_overlap", "number", "Minimum overlap [%]", default=25.0, minimum=0.0,
                  maximum=100.0, unit="%",
                  help="Share of the smaller footprint that both images cover."),
        Parameter("b_h_min", "number", "Minimum B/H", default=0.2, minimum=0.0, maximum=10.0),
        Parameter("b_h_max", "number", "Maximum B/H", default=1.2, minimum=0.0, maximum=10.0),
        Parameter("strip_angle_tolerance", "number", "Strip direction tolerance [°]",
                  default=20.0, minimum=0.0, maximum=90.0, unit="°",
                  help="A pair is in-strip when its base is this close to the strip direction."),
        Parameter("in_strip_only", "bool", "In-strip models only", default=False),
        Parameter("manual", "string", "Manual pairs", optional=True,
                  help="Image pairs 'left,right; left,right' (image names or their short "
                       "labels as in the model names), added as kind 'manual'."),
        Parameter("dem", "raster", "DEM for terrain heights and footprints", optional=True,
                  help="Default: the project's mean terrain height."),
    )
    outputs = (
        Output("models", "json", "Stereo models"),
        Output("count", "number", "Number of stereo models"),
        Output("unpaired", "json", "Images without a stereo partner"),
    )

    def run(self, params: Dict[str, Any], feedback: Feedback) -> Dict[str, Any]:
        from ...project.stereo_models import run_stereo_models

        return run_stereo_models(
            params["project"], detect=params["detect"],
            min_overlap=params["min_overlap"] / 100.0,
            b_h_range=(params["b_h_min"], params["b_h_max"]),
            strip_angle_tolerance=params["strip_angle_tolerance"],
            in_strip_only=params["in_strip_only"], manual=params["manual"], dem=params["dem"],
            feedback=feedback)


ALGORITHMS: list = [ProjectCreate, ProjectInfo, StereoModels]
