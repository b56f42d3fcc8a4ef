"""Algorithm declarations: surfaces (DSM merge, interpolation of points to a DEM)."""

from __future__ import annotations

from pathlib import Path
from typing import Any, Dict, List, Optional

from ...feedback import Feedback
from ..spec import Algorithm, Output, Parameter, project_product
from ..tiled import scheduler_parameter

# Domain modules are imported inside each run(), not here: keeps `photodem list` fast.

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
        "(Δh = a − b: count, mean, median, std, RMS, NMAD) as <name>_seams.json and .csv. "
        "Walls are kept: where the inputs of a cell differ by more than the step threshold "
        "(one has the roof, another the ground), the largest consistent group of heights is "
        "used instead of averaging them, and resampled inputs take the nearest cell at steps."
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
        Parameter("step", "number", "Step threshold [m]", default=1.0, minimum=0.0, unit="m",
                  help="Inputs of a cell that differ by more than this see different surfaces "
                       "(a wall): they are not averaged. 0 = plain median / mean."),
        Parameter("tile", "integer", "Tile size [cells]", default=512, minimum=16,
                  maximum=16384, unit="cells",
                  help="The merged DSM is processed in tiles of this many cells a side "
                       "(memory about 8 bytes per cell and input of a tile)."),
        scheduler_parameter(),
    )
    outputs = (
        Output("dsm", "raster", "Merged DSM"),
        Output("count", "raster", "Inputs per cell"),
        Output("seams", "json", "Seam statistics per overlapping pair"),
        Output("report", "file", "Seam statistics (JSON)"),
        Output("csv", "file", "Seam statistics (CSV)"),
        Output("coverage", "number", "Share of cells with a height"),
    )

    def sidecars(self, name: str, path: Path) -> List[Path]:
        """``<name>_count.tif``, ``<name>_seams.json`` and ``.csv`` beside the DSM."""
        from ...surface.merge import sibling_paths

        return [p for k, p in sibling_paths(path).items() if k != "dsm"]

    def run(self, params: Dict[str, Any], feedback: Feedback) -> Dict[str, Any]:
        from ...surface.merge import merge_dsms

        res = merge_dsms(params["inputs"], params["output"], mode=params.get("mode", "median"),
                         spacing=params.get("spacing") or None, feedback=feedback,
                         step=float(params.get("step", 1.0)), tile=params.get("tile") or 512,
                         scheduler=params.get("scheduler") or "")
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
        Parameter("method", "enum", "Interpolation method", default="membrane",
                  options=("membrane", "fe"),
                  help="membrane: median per cell, empty cells by membrane interpolation; fe: "
                       "finite elements fitted to all points with curvature regularisation "
                       "(smooth between sparse points, breaklines allow kinks)."),
        Parameter("smoothing", "number", "Smoothing (fe)", default=0.1, minimum=0.0,
                  help="Weight of the curvature equations relative to a point (fe only): "
                       "0.01–0.1 interpolates, 1–10 smooths noisy points."),
    )
    outputs = (
        Output("dem", "raster", "DEM"),
        Output("count", "raster", "Points per cell"),
        Output("points", "number", "Points read"),
        Output("used", "number", "Points in the grid"),
        Output("filled", "number", "Interpolated cells"),
        Output("coverage", "number", "Share of cells with a height"),
    )

    def sidecars(self, name: str, path: Path) -> List[Path]:
        """``<name>_count.tif`` beside the DEM."""
        return [path.with_name(f"{path.stem}_count.tif")]

    def run(self, params: Dict[str, Any], feedback: Feedback) -> Dict[str, Any]:
        from ...surface.interpolate import interpolate_dem

        res = interpolate_dem(params["points"], params["output"], spacing=params["spacing"],
                              crs=params.get("crs") or None, project=params.get("project"),
                              breaklines=params.get("breaklines") or None,
                              exclusions=params.get("exclusions") or None,
                              boundary=params.get("boundary") or None,
                              max_gap=params.get("max_gap"),
                              method=params.get("method") or "membrane",
                              smoothing=(0.1 if params.get("smoothing") is None
                                         else params["smoothing"]), feedback=feedback)
        return {k: res[k] for k in ("dem", "count", "points", "used", "filled", "coverage")}


class RefineObjectSpace(Algorithm):
    id = "refine_object_space"
    name = "Refine DSM in object space (multi-image LSM)"
    group = GROUP
    group_id = GROUP_ID
    help = (
        "Refines a DSM with all images that see it (2 … N) by least-squares matching in object "
        "space: per DSM tile, heights on geometry nodes (every facet_px image pixels), object "
        "grey values on a finer grid and a gain and offset per image are adjusted together "
        "(Gauss–Newton, conjugate gradients) so that every image shows the same grey values at "
        "the projection of the surface, with curvature regularisation, coarse to fine over "
        "image-pyramid levels. The input DSM must be within a few pixels of parallax. Writes "
        "dsm.tif (refined heights, float32, NaN where not refined), sigma.tif (σ of the height "
        "per cell from the normal equations, m) and report.json (images and iterations per "
        "tile, σ0 in grey values, mean/median σ, failures). Exclusion areas and cells outside "
        "the boundaries of edits.gpkg are NaN."
    )
    parameters = (
        Parameter("project", "project", "Project folder or project.toml"),
        Parameter("dsm", "raster", "DSM to refine",
                  help="Float GeoTIFF in the project CRS (e.g. dsm.tif of 'Match stereo model')."),
        Parameter("output", "output_folder", "Output folder", optional=True,
                  help="Default: <project>/products/dsm_refined/<DSM name>/."),
        Parameter("spacing", "number", "DSM spacing [m]", optional=True, minimum=0.0, unit="m",
                  help="Cell size of the refined DSM. Default: the input DSM's."),
        Parameter("levels", "integer", "Pyramid levels", default=2, minimum=1, maximum=8,
                  help="Image-pyramid levels, coarse to fine; each level doubles the pull-in "
                       "range (≈ 2 px of parallax on the top level)."),
        Parameter("max_iter", "integer", "Iterations per level", default=8, minimum=0,
                  maximum=50, help="Gauss–Newton iterations per level at most."),
        Parameter("regularisation", "number", "Regularisation share", default=1.0,
                  minimum=0.0, maximum=1000.0,
                  help="Weight of the curvature regularisation relative to the image data on "
                       "the height diagonal of the normal equations (0 = none)."),
        Parameter("regularisation_mode", "enum", "Regularisation", default="correction",
                  options=("curvature", "correction"),
                  help="curvature: smooth surface (thesis); correction: smooth only the "
                       "change to the input DSM (keeps buildings and edges)."),
        Parameter("facet_px", "number", "Geometry facet [px]", default=8.0, minimum=1.0,
                  maximum=64.0, unit="px",
                  help="Spacing of the height unknowns in image pixels (thesis: 8)."),
        Parameter("grey_px", "number", "Grey-value facet [px]", default=2.0, minimum=0.5,
                  maximum=16.0, unit="px",
                  help="Spacing of the object grey values in image pixels (thesis: 2)."),
        Parameter("images", "string", "Images", optional=True,
                  help="Comma-separated image names. Default: every image whose footprint "
                       "covers a tile."),
        Parameter("tile", "integer", "Tile size [cells]", default=192, minimum=16,
                  maximum=4096, unit="cells",
                  help="Side of the computation windows (plus overlap); bounds the memory."),
    )
    outputs = (
        Output("dsm", "raster", "Refined DSM"),
        Output("sigma", "raster", "σ of the heights [m]"),
        Output("report", "file", "Report (JSON)"),
        Output("metrics", "json", "Metrics"),
    )

    def default_output(self, params: Dict[str, Any]) -> Optional[Path]:
        """``<project>/products/dsm_refined/<DSM name>/``."""
        stem = Path(params["dsm"]).stem
        return project_product(params, "dsm_refined", stem, f"The DSM name '{stem}'")

    def run(self, params: Dict[str, Any], feedback: Feedback) -> Dict[str, Any]:
        from ...matching.object_space import refine_object_space
        from ...project.model import Project

        project = Project.load(params["project"])
        dsm = Path(params["dsm"])
        out = self.output_path(params)
        images = [n.strip() for n in (params.get("images") or "").split(",") if n.strip()]
        return refine_object_space(
            project, dsm, out, spacing=params.get("spacing") or None,
            levels=params.get("levels"), max_iter=params.get("max_iter", 8),
            regularisation=params.get("regularisation", 1.0),
            regularisation_mode=params.get("regularisation_mode", "correction"),
            facet_px=params.get("facet_px", 8.0), grey_px=params.get("grey_px", 2.0),
            images=images or None, tile=params.get("tile", 192), feedback=feedback)


ALGORITHMS = [DsmMerge, InterpolateDem, RefineObjectSpace]
