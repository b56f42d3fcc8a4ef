"""Algorithm declarations: DSM → DTM filtering (low-pass, linear prediction, evaluation)."""

from __future__ import annotations

from typing import Any, Dict

from ...feedback import Feedback
from ..spec import Algorithm, Output, Parameter
from ..tiled import scheduler_parameter, tile_parameter

# Domain modules are imported inside each run(), not here: keeps `photodem list` fast.

GROUP = "DTM filtering"
GROUP_ID = "filtering"

#: Preset names shared by both filters (tables in ``algorithms/filtering/presets.py``); ``auto``
#: (the default) picks one from the input. It comes last so that the positions Processing
#: gives the older names stay (same tuple as ``presets.FILTER_PRESET_CHOICES``).
PRESETS = ("default", "flat", "hilly", "urban", "forest", "steep", "auto")

#: Input extensions the filters accept (raster or points).
FILTER_INPUT_EXTENSIONS = (".tif", ".tiff", ".vrt", ".img", ".xyz", ".txt", ".csv", ".asc",
                           ".pts", ".gpkg", ".las", ".laz")


def common_filter_parameters() -> tuple:
    """The parameters both filters share: input, output, preset, project, spacing."""
    return (
        Parameter("input", "file", "DSM raster or points", extensions=FILTER_INPUT_EXTENSIONS,
                  help="A DSM GeoTIFF (nodata = no height), or points: XYZ text with whitespace, "
                       "comma, semicolon or tab separators (extra columns ignored), GeoPackage "
                       "points from matching (with sigma_z), LAS/LAZ when laspy is installed."),
        Parameter("output", "output_folder", "Output folder",
                  help="Receives dtm.tif, ndsm.tif, mask.tif (raster input) or labels.txt "
                       "(point input), report.json and report.html. Written completely or not "
                       "at all."),
        Parameter("preset", "enum", "Parameter preset", default="auto", options=PRESETS,
                  help="auto (the default) measures the input's terrain slope and vegetated "
                       "share and takes steep for steep vegetated ground, else default, and "
                       "reports why; default serves most terrain types; flat, hilly, urban, "
                       "forest and steep are tuned variants. Options given below override the "
                       "preset."),
        Parameter("project", "project", "Project (edits.gpkg)", optional=True,
                  help="Its exclusion areas (keep/remove), manual ground points and breaklines "
                       "are honoured."),
        Parameter("spacing", "number", "Grid spacing for point input [m]", optional=True,
                  minimum=0.0, unit="m",
                  help="Default: about the mean point spacing. Ignored for raster input."),
        Parameter("crs", "crs", "CRS of point input", optional=True,
                  help="CRS of text points. Default: the project's, else the input's own."),
    )


class FilterLowpass(Algorithm):
    id = "filter_lowpass"
    name = "Filter DSM to DTM (iterative low-pass)"
    group = GROUP
    group_id = GROUP_ID
    help = (
        "Iterative robust low-pass filtering (the 'Phoenics' method): the surface is smoothed "
        "with a window that shrinks from iteration to iteration (a least-squares plane through "
        "the remaining cells of the window), the difference model DSM − smoothed surface is "
        "formed, cells higher than the iteration's threshold (buildings, vegetation) or far "
        "below it (blunders) are eliminated, and the holes are filled from the surrounding "
        "ground by membrane interpolation. Exclusion areas with action 'keep' keep the DSM as "
        "DTM (embankments, dams); 'remove' areas are eliminated before the first iteration and "
        "bridged (forests); manual ground points are hard constraints (the DTM passes through "
        "them); smoothing and hole filling do not cross breaklines. The largest window should "
        "be 2–3 × the largest building width. Writes dtm.tif, ndsm.tif, mask.tif or labels.txt,"
        " report.json/html and, optionally, the difference model of every iteration."
    )
    parameters = common_filter_parameters() + (
        Parameter("max_window", "number", "Largest smoothing window [m]", optional=True,
                  minimum=0.0, unit="m",
                  help="Window of the first iteration; 2–3 × the largest building width. The "
                       "windows of later iterations shrink in the preset's proportions."),
        Parameter("iterations", "integer", "Iterations", optional=True, minimum=1, maximum=12,
                  help="Number of smoothing/elimination iterations."),
        Parameter("threshold", "number", "Final height threshold [m]", optional=True,
                  minimum=0.0, unit="m",
                  help="Cells higher than this above the smoothed surface are objects in the "
                       "last iteration; earlier iterations use the preset's larger thresholds."),
        Parameter("slope", "number", "Terrain slope allowance [%]", optional=True,
                  minimum=0.0, maximum=200.0, unit="%",
                  help="Allowance for breaks of slope (ridges, hill tops): every threshold "
                       "grows by slope/100 × window/4."),
        Parameter("write_iterations", "bool", "Write difference model of every iteration",
                  default=False,
                  help="Writes diff_01.tif, diff_02.tif … (DSM − smoothed surface) for "
                       "inspection."),
        tile_parameter(), scheduler_parameter(),
    )
    outputs = (
        Output("dtm", "raster", "DTM"),
        Output("ndsm", "raster", "Normalised DSM (DSM − DTM)"),
        Output("mask", "raster", "Object mask (raster input)"),
        Output("labels", "file", "Labels per input point (point input)"),
        Output("report", "file", "Report (JSON)"),
        Output("metrics", "json", "Eliminated share, parameters, ground-point check"),
    )

    def run(self, params: Dict[str, Any], feedback: Feedback) -> Dict[str, Any]:
        from ...filtering.lowpass import run_filter_lowpass  # lazy: keeps photodem list fast
        from ...filtering.tiles import tiling  # lazy: keeps photodem list fast

        with tiling(params.get("scheduler"), params.get("tile")):
            return run_filter_lowpass(
                params["input"], params["output"], preset=params.get("preset") or "auto",
                project=params.get("project"), spacing=params.get("spacing"),
                crs=params.get("crs") or None,
                overrides={k: params.get(k) for k in ("max_window", "iterations", "threshold",
                                                       "slope")},
                write_iterations=bool(params.get("write_iterations")), feedback=feedback)


class FilterEvaluate(Algorithm):
    id = "filter_evaluate"
    name = "Evaluate ground filtering (Type I/II, kappa, DTM accuracy)"
    group = GROUP
    group_id = GROUP_ID
    help = (
        "Compares a filter's ground/object labels with reference labels using the ISPRS filter "
        "test measures (Sithole & Vosselman 2004): Type I = ground rejected / all ground, "
        "Type II = objects accepted as ground / all objects, total error and Cohen's kappa, in "
        "percent. Labels: the filter's labels.txt (one 0/1 per input point) or mask.tif; "
        "reference: a text file whose last column (or the given column) is the label, e.g. "
        "the ISPRS samples 'X Y Z label' (0 = ground, 1 = object), or a reference mask raster. "
        "With a DTM, its differences to a reference DTM (mean, std, RMS, NMAD, 95 % |Δh|) and, "
        "for a reference with coordinates, at the reference ground points are reported. "
        "Writes report.json and report.csv."
    )
    parameters = (
        Parameter("labels", "file", "Filter labels (labels.txt or mask raster)",
                  extensions=(".txt", ".csv", ".xyz", ".tif", ".tiff"),
                  help="0 = ground, 1 = object; a text file lists the same points in the same "
                       "order as the reference."),
        Parameter("reference", "file", "Reference labels (text or mask raster)",
                  extensions=(".txt", ".csv", ".xyz", ".tif", ".tiff"),
                  help="Text with the label in the last column (or the column below), e.g. "
                       "'X Y Z label'; or a mask raster (1 = object, 0 = ground)."),
        Parameter("column", "integer", "Label column of the reference text", optional=True,
                  minimum=1,
                  help="1 = first column. Default: a column named label/class, else the last."),
        Parameter("dtm", "raster", "Filtered DTM", optional=True,
                  help="The filter's dtm.tif, checked against the reference DTM and/or the "
                       "reference ground points."),
        Parameter("reference_dtm", "raster", "Reference DTM", optional=True,
                  help="Δh = DTM − reference DTM on the reference grid."),
        Parameter("output", "output_folder", "Output folder",
                  help="Receives report.json and report.csv (written completely or not at "
                       "all)."),
    )
    outputs = (
        Output("report", "file", "Report (JSON)"),
        Output("csv", "file", "Report (CSV, one row)"),
        Output("metrics", "json", "Type I/II, total error, kappa [%], DTM statistics"),
    )

    def run(self, params: Dict[str, Any], feedback: Feedback) -> Dict[str, Any]:
        from ...filtering.evaluate import run_filter_evaluate

        return run_filter_evaluate(
            params["labels"], params["reference"], params["output"],
            column=params.get("column"), dtm=params.get("dtm"),
            reference_dtm=params.get("reference_dtm"), feedback=feedback)


class FilterLinearPrediction(Algorithm):
    id = "filter_linear_prediction"
    name = "Filter DSM to DTM (robust linear prediction)"
    group = GROUP
    group_id = GROUP_ID
    help = (
        "Hierarchical robust linear prediction (Kraus & Pfeifer): on a pyramid of the DSM "
        "(lowest cell of every 2×2 block, up to the preset's coarse cell size) the terrain is "
        "predicted level by level, coarse to fine. At every level a trend (a robust plane, "
        "then the coarser level's DTM) is removed, a Gaussian covariance (signal variance, "
        "noise share, correlation length) is estimated from the data, and the heights are "
        "predicted with filtering; robust iterations give cells below the surface full weight "
        "and cells above it less (zero beyond the cut-off), so the surface sinks onto the "
        "ground and buildings and woods are bridged. Exclusion areas 'keep' keep the DSM as "
        "DTM, 'remove' areas are bridged, manual ground points are hard constraints and "
        "breaklines stop the prediction from reaching across. Writes dtm.tif, ndsm.tif, "
        "mask.tif or labels.txt, report.json/html and, optionally, the DTM of every level."
    )
    parameters = common_filter_parameters() + (
        Parameter("coarse_spacing", "number", "Coarsest pyramid cell [m]", optional=True,
                  minimum=0.0, unit="m",
                  help="About the width of the largest building or wood to bridge."),
        Parameter("cutoff", "number", "Weight cut-off above the surface [m]", optional=True,
                  minimum=0.0, unit="m",
                  help="Cells more than this above the predicted surface (plus its shift) get "
                       "weight 0 (objects)."),
        Parameter("half_weight", "number", "Half-weight residual [m]", optional=True,
                  minimum=0.0, unit="m",
                  help="Residual above the surface at which a cell keeps half its weight."),
        Parameter("slope", "number", "Terrain slope allowance [%]", optional=True,
                  minimum=0.0, maximum=200.0, unit="%",
                  help="Widens the cut-off and the candidate band at coarse levels by "
                       "slope × cell/2, so hill tops and embankment edges are not cut."),
        Parameter("noise_share", "number", "Noise share (0 = pure interpolation)",
                  optional=True, minimum=0.0, maximum=0.99,
                  help="Fixed σ²_noise / variance; empty = estimated from the data."),
        Parameter("iterations", "integer", "Robust iterations per level", optional=True,
                  minimum=1, maximum=12),
        Parameter("ground_tolerance", "number", "Ground tolerance [m]", optional=True,
                  minimum=0.0, unit="m",
                  help="Cells and points within this of the DTM are labelled ground."),
        Parameter("write_levels", "bool", "Write the DTM of every pyramid level",
                  default=False, help="Writes level_0.tif … level_k.tif for inspection."),
        tile_parameter(), scheduler_parameter(),
    )
    outputs = (
        Output("dtm", "raster", "DTM"),
        Output("ndsm", "raster", "Normalised DSM (DSM − DTM)"),
        Output("mask", "raster", "Object mask (raster input)"),
        Output("labels", "file", "Labels per input point (point input)"),
        Output("report", "file", "Report (JSON)"),
        Output("metrics", "json", "Eliminated share, covariance per level, ground-point check"),
    )

    def run(self, params: Dict[str, Any], feedback: Feedback) -> Dict[str, Any]:
        from ...filtering.linear_prediction import run_filter_linear_prediction
        from ...filtering.tiles import tiling  # lazy: keeps photodem list fast

        overrides = {k: params.get(k) for k in ("coarse_spacing", "cutoff", "half_weight",
                                                 "noise_share", "iterations",
                                                 "ground_tolerance")}
        if params.get("slope") is not None:
            overrides["slope"] = float(params["slope"]) / 100.0  # % → m/m
        with tiling(params.get("scheduler"), params.get("tile")):
            return run_filter_linear_prediction(
                params["input"], params["output"], preset=params.get("preset") or "auto",
                project=params.get("project"), spacing=params.get("spacing"),
                crs=params.get("crs") or None, overrides=overrides,
                write_levels=bool(params.get("write_levels")), feedback=feedback)


ALGORITHMS = [FilterLowpass, FilterEvaluate, FilterLinearPrediction]
