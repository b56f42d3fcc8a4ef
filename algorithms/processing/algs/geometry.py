"""Algorithm declarations: geometry."""

from __future__ import annotations

from pathlib import Path
from typing import Any, Dict, Optional

from ...feedback import Feedback
from ...project.model import Project
from ..spec import Algorithm, Output, Parameter, model_product

# Domain modules are imported inside each run(), not here: keeps `photodem list` fast.


class EpipolarPairAlgorithm(Algorithm):
    id = "epipolar_pair"
    name = "Epipolar pair"
    group = "Geometry"
    group_id = "geometry"
    help = (
        "Resamples the two images of a stereo model to normal-case (epipolar) geometry: both "
        "images share one rotation with x along the base, so a ground point has the same row in "
        "both. Writes left.tif and right.tif (input bands plus an alpha band), left_map.tif and "
        "right_map.tif (original col, row of every epipolar pixel, NaN outside) and "
        "epipolar.json (homographies, focal length in px, base, sizes) for matching and "
        "triangulation."
    )
    parameters = (
        Parameter("project", "project", "Project folder or project.toml"),
        Parameter("model", "model", "Stereo model"),
        Parameter("output", "output_folder", "Output folder", optional=True,
                  help="Default: <project>/products/epipolar/<model>/. Must not exist or be "
                       "empty."),
        Parameter("scale", "number", "Resolution scale", default=1.0, minimum=0.05,
                  maximum=4.0, help="Epipolar pixel density relative to the originals (0.5 = "
                                    "half resolution)."),
    )
    outputs = (
        Output("folder", "folder", "Output folder"),
        Output("left", "raster", "Left epipolar image"),
        Output("right", "raster", "Right epipolar image"),
        Output("left_map", "raster", "Left map to original pixels (col, row)"),
        Output("right_map", "raster", "Right map to original pixels (col, row)"),
        Output("metadata", "file", "epipolar.json"),
        Output("y_parallax_check_px", "number", "Largest y-parallax of check points (px)"),
        Output("size", "json", "Epipolar image size [w, h] (left)"),
    )
    iterates_over = "model"

    def default_output(self, params: Dict[str, Any]) -> Optional[Path]:
        """``<project>/products/epipolar/<model>/``."""
        return model_product(params, "epipolar")

    def run(self, params: Dict[str, Any], feedback: Feedback) -> Dict[str, Any]:
        from ...matching.epipolar_images import write_epipolar_pair

        return write_epipolar_pair(Project.load(params["project"]), params["model"],
                                   self.output_path(params), float(params["scale"]), feedback,
                                   product=self.id)


ALGORITHMS: list = [EpipolarPairAlgorithm]
