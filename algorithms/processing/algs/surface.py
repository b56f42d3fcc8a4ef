"""Algorithm declarations: surfaces (DSM merge, interpolation of points to a DEM)."""

from __future__ import annotations

from typing import Any, Dict

from ..feedback import Feedback
from ..spec import Algorithm, Output, Parameter

GROUP = "Surfaces"
GROUP_ID = "surface"


class DsmMerge(Algorithm):
    id = "dsm_merge"
    name = "Merge DSMs"
    group = GROUP
    group_id = GROUP_ID
    help = (
        "Merges model DSMs into one DSM on a common grid: the union of their extents at the "
        "finest input cell size (or at the given spacing), in the CRS of the first input; "
        "inputs with another grid or CRS are resampled bilinearly, window by window. Modes: "
        "median or mean of the heights per cell; best_sigma takes the height of the input with "
        "the smallest σ, where σ is a second band of the input or a raster <name>_sigma.tif or "
        "sigma.tif beside it — inputs without σ are used only where no input with σ has a "
        "height (as their median), so without any σ best_sigma is the median. Writes the DSM, "
        "<name>_count.tif (inputs per cell) and the seam statistics of every overlapping pair "
        "(Δh = a − b: count, mean, median, std, RMS, NMAD) as <name>_seams.json and .csv."
    )
    parameters = (
        Parameter("inputs", "multiple_rasters", "Input DSMs",
                  help="Model DSMs (NaN or nodata = no height), any extents, grids and CRSs."),
        Parameter("output", "output_raster", "Merged DSM", extensions=(".tif",),
                  help="Float32 GeoTIFF, NaN where no input has a height."),
        Parameter("mode", "enum", "Merge mode", default="median",
                  options=("median", "mean", "best_sigma"),
                  help="median: robust against one wrong model where three or more overlap; "
                       "mean: average; best_sigma: the height with the smallest σ."),
        Parameter("spacing", "number", "Cell size [m]", optional=True, minimum=0.0, unit="m",
                  help="Default: the finest cell size of the inputs."),
    )
    outputs = (
        Output("dsm", "raster", "Merged DSM"),
        Output("count", "raster", "Inputs per cell"),
        Output("seams", "json", "Seam statistics per overlapping pair"),
        Output("report", "file", "Seam statistics (JSON)"),
        Output("csv", "file", "Seam statistics (CSV)"),
        Output("coverage", "number", "Share of cells with a height"),
    )

    def run(self, params: Dict[str, Any], feedback: Feedback) -> Dict[str, Any]:
        from ...surface.merge import merge_dsms

        res = merge_dsms(params["inputs"], params["output"], mode=params.get("mode", "median"),
                         spacing=params.get("spacing") or None, feedback=feedback)
        return {k: res[k] for k in ("dsm", "count", "seams", "report", "csv", "coverage")}


class InterpolateDem(Algorithm):
    id = "interpolate_dem"
    name = "Interpolate DEM from points"
    group = GROUP
    group_id = GROUP_ID
    help = (
        "Grids points (XYZ text, CSV with x, y, z columns, or 3-D points in a GeoPackage) to a "
        "DEM: the median of the points in each cell, then membrane interpolation of the empty "
        "cells that does not cross breaklines (3-D breaklines give their own heights). "
        "Exclusion areas are NaN, and so is everything outside the boundary polygons. "
        "Breaklines, exclusion areas and boundaries come from the project's edits.gpkg and/or "
        "from the given vector files. Writes the DEM and <name>_count.tif (points per cell)."
    )
    parameters = (
        Parameter("points", "file", "Points (XYZ text, CSV or GeoPackage)"),
        Parameter("output", "output_raster", "DEM", extensions=(".tif",),
                  help="Float32 GeoTIFF, NaN where there is no height."),
        Parameter("spacing", "number", "Cell size [m]", default=1.0, minimum=0.0, unit="m"),
        Parameter("crs", "crs", "CRS", optional=True,
                  help="CRS of the DEM and of text points. Default: the project's, else the "
                       "points' own."),
        Parameter("project", "project", "Project (edits.gpkg)", optional=True,
                  help="Its breaklines, exclusion areas and boundaries are honoured."),
        Parameter("breaklines", "file", "Breaklines (vector file)", optional=True,
                  help="(3-D) lines the interpolation does not cross."),
        Parameter("exclusions", "file", "Exclusion areas (vector file)", optional=True,
                  help="Polygons that stay empty (NaN)."),
        Parameter("boundary", "file", "Boundary (vector file)", optional=True,
                  help="Polygons of the measuring area; NaN outside."),
        Parameter("max_gap", "number", "Interpolate gaps up to [m]", optional=True,
                  minimum=0.0, unit="m",
                  help="Larger gaps stay empty (NaN). Default: every gap is interpolated."),
    )
    outputs = (
        Output("dem", "raster", "DEM"),
        Output("count", "raster", "Points per cell"),
        Output("points", "number", "Points read"),
        Output("used", "number", "Points in the grid"),
        Output("filled", "number", "Interpolated cells"),
        Output("coverage", "number", "Share of cells with a height"),
    )

    def run(self, params: Dict[str, Any], feedback: Feedback) -> Dict[str, Any]:
        from ...surface.interpolate import interpolate_dem

        res = interpolate_dem(params["points"], params["output"], spacing=params["spacing"],
                              crs=params.get("crs") or None, project=params.get("project"),
                              breaklines=params.get("breaklines") or None,
                              exclusions=params.get("exclusions") or None,
                              boundary=params.get("boundary") or None,
                              max_gap=params.get("max_gap"), feedback=feedback)
        return {k: res[k] for k in ("dem", "count", "points", "used", "filled", "coverage")}


ALGORITHMS = [DsmMerge, InterpolateDem]
