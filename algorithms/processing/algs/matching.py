"""Algorithm declarations: image matching."""

from __future__ import annotations

from pathlib import Path
from typing import Any, Dict, Optional

from ...errors import InputError
from ...feedback import Feedback
from ...matching.dense import METHODS
from ...matching.disparity_run import run_stereo_disparity
from ...matching.presets import DEFAULT_PRESET, PRESET_ALIASES, PRESET_NAMES
from ..spec import Algorithm, Output, Parameter, model_product

# Domain modules are imported inside each run(), not here: keeps `photodem list` fast.

GROUP = "Matching"
GROUP_ID = "matching"


class StereoDisparity(Algorithm):
    id = "stereo_disparity"
    name = "Stereo disparity (dense matching)"
    group = GROUP
    group_id = GROUP_ID
    help = (
        "Dense matching of an epipolar (rectified) image pair, e.g. left.tif and right.tif of "
        "'Epipolar pair': a disparity d = x_left − x_right for every pixel of the left image, by "
        "semi-global matching with radiometric normalisation, left–right check, sub-pixel "
        "refinement, speckle removal and filling of narrow gaps along the epipolar lines. "
        "Alpha bands and nodata are honoured. Works in tiles, so large images fit in memory."
    )
    parameters = (
        Parameter("left", "raster", "Left epipolar image"),
        Parameter("right", "raster", "Right epipolar image"),
        Parameter("min_disparity", "integer", "Minimum disparity [px]", default=0, unit="px",
                  minimum=-100000, maximum=100000,
                  help="Smallest x_left − x_right searched; may be negative."),
        Parameter("max_disparity", "integer", "Maximum disparity [px]", default=63, unit="px",
                  minimum=-100000, maximum=100000,
                  help="Largest x_left − x_right searched."),
        Parameter("method", "enum", "Method", default=METHODS[0], options=METHODS,
                  help="sgm: 8-path semi-global matching with radiometric normalisation, "
                       "left–right check and gap filling; opencv_sgbm: plain OpenCV StereoSGBM "
                       "for comparison."),
        Parameter("output", "output_raster", "Disparity raster", extensions=(".tif",),
                  help="Float32 GeoTIFF in left-image geometry, NaN where no disparity."),
        Parameter("block_size", "integer", "Block size [px]", default=5, minimum=1, maximum=11,
                  unit="px", help="Odd side of the matching window."),
        Parameter("p1", "integer", "Penalty P1", optional=True, minimum=1,
                  help="SGM penalty for 1 px disparity steps. Default: 8 × block size²."),
        Parameter("p2", "integer", "Penalty P2", optional=True, minimum=2,
                  help="SGM penalty for larger disparity steps. Default: 32 × block size²."),
        Parameter("uniqueness", "integer", "Uniqueness [%]", default=10, minimum=0, maximum=100,
                  unit="%", help="Percent by which the best match must beat the second best."),
        Parameter("lr_max_diff", "number", "Left–right tolerance [px]", default=1.0,
                  minimum=-1.0, maximum=100.0, unit="px",
                  help="Largest difference of left and right disparity; negative = no check."),
        Parameter("fill_max_width", "integer", "Fill gaps up to [px]", default=32, minimum=0,
                  unit="px", help="Invalid runs along a row up to this width get the farther "
                                  "(smaller) neighbouring disparity; 0 = no filling."),
        Parameter("memory_mb", "number", "Memory per tile [MB]", default=256.0, minimum=16.0,
                  unit="MB", help="Bounds the memory of the matching; sets the tile size."),
    )
    outputs = (
        Output("disparity", "raster", "Disparity raster"),
        Output("valid_share", "number", "Share of pixels with a disparity"),
        Output("min", "number", "Smallest disparity [px]"),
        Output("max", "number", "Largest disparity [px]"),
    )

    def run(self, params: Dict[str, Any], feedback: Feedback) -> Dict[str, Any]:
        return run_stereo_disparity(
            params["left"], params["right"], params["output"],
            min_disparity=params["min_disparity"], max_disparity=params["max_disparity"],
            method=params["method"], block_size=params["block_size"], p1=params.get("p1"),
            p2=params.get("p2"), uniqueness=params["uniqueness"],
            lr_max_diff=params["lr_max_diff"], fill_max_width=params["fill_max_width"],
            memory_mb=params["memory_mb"], feedback=feedback)


class MatchModel(Algorithm):
    id = "match_model"
    name = "Match stereo model (DSM)"
    group = GROUP
    group_id = GROUP_ID
    help = (
        "Matches the two images of a stereo model and grids the points to a DSM. fbm_lsm: "
        "image pyramids coarse to fine from the start points of edits.gpkg (or the height "
        "range), Förstner points, feature-based matching with robust consistency and a "
        "left–right check, least-squares matching at the finest level; failed windows are "
        "marked and matching goes on around them; groundel reduction (robust plane, σ1, σ2) "
        "and a finite-element surface that honours breaklines. dense: semi-global matching of "
        "every pixel of the epipolar pair, median per cell. Exclusion areas and boundaries of "
        "edits.gpkg are honoured (NaN). Writes dsm.tif, count.tif, report.json and "
        "report.html; fbm_lsm also sigma.tif and the raw and reduced points."
    )
    parameters = (
        Parameter("project", "project", "Project folder or project.toml"),
        Parameter("model", "model", "Stereo model"),
        Parameter("method", "enum", "Method", default="fbm_lsm", options=("fbm_lsm", "dense"),
                  help="fbm_lsm: hierarchical feature-based matching + LSM under the "
                       "operator's control; dense: semi-global matching of every pixel."),
        Parameter("output", "output_folder", "Output folder", optional=True,
                  help="Default: <project>/products/dsm/<model>/."),
        Parameter("spacing", "number", "DSM spacing [m]", optional=True, minimum=0.0,
                  unit="m", help="Default: 2 × the model's ground sample distance for fbm_lsm, "
                                 "1 × for dense."),
        Parameter("min_height", "number", "Lowest height [m]", optional=True, unit="m",
                  minimum=-100000.0, maximum=100000.0,
                  help="Lowest terrain/object height searched. Default: terrain height − 0.3 × "
                       "flying height above ground."),
        Parameter("max_height", "number", "Highest height [m]", optional=True, unit="m",
                  minimum=-100000.0, maximum=100000.0,
                  help="Highest terrain/object height searched. Default: terrain height + 0.3 × "
                       "flying height above ground."),
        Parameter("max_gap", "number", "Interpolate gaps up to [m]", optional=True,
                  minimum=0.0, unit="m",
                  help="Larger gaps stay empty (NaN). Default: 3 × the groundel size for "
                       "fbm_lsm, 10 × spacing for dense."),
        Parameter("preset", "enum", "Strategy preset (fbm_lsm)", default=DEFAULT_PRESET,
                  options=PRESET_NAMES, aliases=tuple(PRESET_ALIASES),
                  help="general (default): keeps buildings and trees (a DSM; roofs are "
                       "searched up to 15 m above the ground), open terrain nearly as accurate "
                       "as with terrain; urban: smaller windows "
                       "and groundels for built-up areas; terrain (formerly flat): large windows "
                       "and groundels, smooth surface without objects (nearly a DTM); hilly: "
                       "medium; forest: lower envelope of the points per groundel. The options "
                       "below override it."),
        Parameter("fbm_window", "integer", "Matching window [px] (fbm_lsm)", optional=True,
                  minimum=8, maximum=128, unit="px",
                  help="Side of the window of the robust consistency. Default: the preset's "
                       "(1.5 × on convergent drone and oblique pairs)."),
        Parameter("rho_min", "number", "Minimum correlation (fbm_lsm)", optional=True,
                  minimum=0.0, maximum=1.0,
                  help="Candidates with a smaller correlation coefficient are dropped. "
                       "Default: 0.6."),
        Parameter("lsm", "bool", "Refine by least-squares matching (fbm_lsm)", default=True,
                  help="LSM at every point of the finest level; points whose LSM fails keep "
                       "their feature-based value and a flag."),
        Parameter("groundel", "number", "Groundel size [m] (fbm_lsm)", optional=True,
                  minimum=0.0, unit="m",
                  help="Side of the cells of the robust reduction. Default: the preset's "
                       "multiple of the GSD (general: 20, urban: 10, terrain: 40 × GSD)."),
        Parameter("reduction", "enum", "Groundel reduction (fbm_lsm)", optional=True,
                  options=("l1", "median", "lower"),
                  help="l1: robust tilted plane; median; lower: lower envelope (vegetation). "
                       "Default: the preset's."),
        Parameter("points_format", "enum", "Point format (fbm_lsm)", default="gpkg",
                  options=("gpkg", "las"),
                  help="GeoPackage, or LAS (needs the Python package laspy)."),
        Parameter("use_start_points", "bool", "Use start points (fbm_lsm)", default=True,
                  help="Start from the start points of edits.gpkg; without any, the whole "
                       "height range is searched at the coarsest level."),
        Parameter("slant_passes", "bool",
                  "Match foreshortened slopes (dense, convergent or wide base)", default=True,
                  help="Convergent models and models with a base of at least half the flying "
                       "height: also match against the right image stretched by 0.7 and 1.4, "
                       "for slopes and roof faces one camera sees foreshortened, refined by "
                       "least-squares matching. More cells measured as precisely as the "
                       "others, about 5–6 × the time."),
        Parameter("guided_pass", "bool",
                  "Match once more along the first DSM (dense, convergent)", default=True,
                  help="Convergent models: match again within ± 8 px of the first DSM's "
                       "disparities, against the right image warped by them, and keep the new "
                       "heights where least-squares matching and a uniqueness test along the "
                       "row confirm them. Measures slopes across the base (embankments, ditch "
                       "sides) that the first pass flattens; about 1.3–1.4 × the time."),
    )
    outputs = (
        Output("dsm", "raster", "DSM"),
        Output("count", "raster", "Points per cell"),
        Output("sigma", "raster", "σ of the heights [m]"),
        Output("points", "file", "Points"),
        Output("reduced", "file", "Reduced points"),
        Output("report", "file", "Report (JSON)"),
        Output("report_html", "html", "Report (HTML)"),
        Output("metrics", "json", "Metrics"),
    )
    iterates_over = "model"

    def default_output(self, params: Dict[str, Any]) -> Optional[Path]:
        """``<project>/products/dsm/<model>/``."""
        return model_product(params, "dsm")

    def run(self, params: Dict[str, Any], feedback: Feedback) -> Dict[str, Any]:
        from ...project.model import Project

        project = Project.load(params["project"])
        model = project.model(params["model"])
        out = self.output_path(params)
        method = params.get("method") or "fbm_lsm"
        common = {"spacing": params.get("spacing") or None,
                  "min_height": params.get("min_height"),
                  "max_height": params.get("max_height"),
                  "max_gap": params.get("max_gap"), "feedback": feedback}
        if method == "dense":
            from ...matching.dense_model import match_model_dense

            return match_model_dense(project, model.name, out,
                                     slant_passes=bool(params["slant_passes"]),
                                     guided=bool(params["guided_pass"]),
                                     **common)
        if method != "fbm_lsm":
            raise InputError(f"Unknown matching method '{method}'; use fbm_lsm or dense.")
        from ...matching.fbm_model import match_model_fbm_lsm

        extra = {k: params.get(k) for k in ("fbm_window", "rho_min") if params.get(k)}
        return match_model_fbm_lsm(
            project, model.name, out, preset=params.get("preset") or DEFAULT_PRESET,
            groundel=params.get("groundel") or None, reduction=params.get("reduction") or None,
            points_format=params.get("points_format") or "gpkg",
            use_start_points=bool(params["use_start_points"]),
            lsm=bool(params.get("lsm", True)), **extra, **common)


ALGORITHMS = [StereoDisparity, MatchModel]
