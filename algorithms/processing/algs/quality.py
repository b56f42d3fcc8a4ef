"""Algorithm declarations: quality control of DEMs."""

from __future__ import annotations

from pathlib import Path
from typing import Any, Dict

from ...feedback import Feedback
from ...raster.io import staged_folder
from ..spec import Algorithm, Output, Parameter
from ..tiled import scheduler_parameter

# Domain modules are imported inside each run(), not here: keeps `photodem list` fast.

GROUP = "Quality control"
GROUP_ID = "quality"


class DemCompare(Algorithm):
    id = "dem_compare"
    name = "Compare DEM with reference"
    group = GROUP
    group_id = GROUP_ID
    help = (
        "Compares a DEM (DSM or DTM) with a reference DEM on their common area; the reference "
        "may have another grid, extent or CRS (the DEM is resampled onto it). Optionally "
        "co-registers the DEM first (horizontal shift and vertical bias after Nuth & Kääb, "
        "estimated on stable terrain). Writes the difference model Δh = DEM − reference (with "
        "a QGIS style), a hillshade and a slope raster of the DEM, statistics (mean, median, "
        "std, RMS, NMAD, quantiles of |Δh|, 0.5 m classes) overall, per class and per slope "
        "class, in m and in ‰ of the flying height, and an HTML report with plots. With the "
        "reference's terrain model (DTM) the cells are also classed into object interior, "
        "object edge, open terrain and other by their height above the DTM; with classes or a "
        "DTM the completeness per class is reported too: the share of the reference cells "
        "the DEM measures, and the shares within ±0.5 m and ±1 m (empty cells count as misses)."
    )
    parameters = (
        Parameter("dem", "raster", "DEM to check"),
        Parameter("reference", "raster", "Reference DEM"),
        Parameter("output", "output_folder", "Output folder",
                  help="Receives difference.tif (+ .qml style), hillshade.tif, slope.tif, "
                       "report.html, stats.json and stats.csv; with classes or a DTM also "
                       "completeness.csv."),
        Parameter("coregister", "bool", "Co-register before comparing", default=False,
                  help="Estimate and remove a horizontal shift and a vertical bias (Nuth & "
                       "Kääb) on stable terrain first."),
        Parameter("stable", "file", "Stable terrain (mask raster or polygons)", optional=True,
                  help="Where the terrain has not changed (co-registration only): a raster "
                       "(non-zero = stable) or polygons. Default: the whole common area."),
        Parameter("classes", "file", "Classes (polygons or raster)", optional=True,
                  help="Statistics per class: a class raster such as land cover, or polygons "
                       "with a class attribute."),
        Parameter("class_field", "string", "Class attribute of the polygons", optional=True,
                  help="Attribute of the class polygons that names the class."),
        Parameter("class_legend", "file", "Class names (legend of a class raster)",
                  optional=True,
                  help="Names of the codes of a class raster: a table with one 'value,name' "
                       "per line, or a QGIS style (.qml). Default: the style beside the "
                       "raster (landcover.qml for landcover.tif), else the codes."),
        Parameter("flying_height", "number", "Flying height above ground [m]", optional=True,
                  minimum=1.0, unit="m",
                  help="For the statistics in ‰ of the flying height."),
        Parameter("dtm", "raster", "Terrain model (DTM) of the reference", optional=True,
                  help="When the reference is a DSM: its terrain model. Cells at least the "
                       "object height above it are objects (buildings, trees); statistics and "
                       "completeness per object class."),
        Parameter("object_height", "number", "Object height [m]", default=2.5, minimum=0.1,
                  unit="m", help="Height above the DTM from which a reference cell belongs to "
                                 "an object."),
        Parameter("tile", "integer", "Tile size [cells]", default=1024, minimum=16,
                  maximum=16384, unit="cells",
                  help="The comparison grid is processed in tiles of this many cells a side "
                       "(memory about 60 bytes per cell of a tile)."),
        scheduler_parameter(),
    )
    outputs = (
        Output("stats", "json", "Statistics of Δh [m]"),
        Output("shift", "json", "Co-registration shift dx, dy, dz [m]"),
        Output("per_class", "json", "Statistics per class"),
        Output("class_names", "json", "Names of the class codes"),
        Output("per_slope", "json", "Statistics per slope class"),
        Output("per_object", "json", "Statistics per object class"),
        Output("completeness", "json", "Completeness per class"),
        Output("difference", "raster", "Difference model (DEM − reference)"),
        Output("hillshade", "raster", "Hillshade of the DEM"),
        Output("slope", "raster", "Slope of the DEM [°]"),
        Output("report", "html", "HTML report"),
        Output("json", "file", "Statistics as JSON"),
        Output("csv", "file", "Statistics as CSV"),
        Output("completeness_csv", "file", "Completeness as CSV"),
    )

    def run(self, params: Dict[str, Any], feedback: Feedback) -> Dict[str, Any]:
        from ...quality.compare_run import run_dem_compare  # lazy: keeps photodem list fast

        return run_dem_compare(
            params["dem"], params["reference"], params["output"],
            coregister=bool(params["coregister"]), stable=params.get("stable"),
            classes=params.get("classes"), class_field=params.get("class_field"),
            flying_height=params.get("flying_height"), dtm=params.get("dtm"),
            object_height=params.get("object_height"),
            class_legend=params.get("class_legend"), window_size=params.get("tile") or 1024,
            scheduler=params.get("scheduler") or "", feedback=feedback)


class DemProfile(Algorithm):
    id = "dem_profile"
    name = "DEM profiles along a line"
    group = GROUP
    group_id = GROUP_ID
    help = (
        "Samples several DEMs (bilinear) along a line at a constant spacing and writes the "
        "table profile.csv (distance, x, y, one height column per DEM) and the plot "
        "profile.png. The line is the first line feature of a vector file (any CRS) or a list "
        "of coordinates in the first DEM's CRS."
    )
    parameters = (
        Parameter("dems", "multiple_rasters", "DEMs"),
        Parameter("line", "file", "Profile line (vector file)", optional=True,
                  help="Its first line feature is the profile; it is transformed to the "
                       "first DEM's CRS."),
        Parameter("coordinates", "string", "Profile line as coordinates", optional=True,
                  help="'x1,y1;x2,y2;…' in the first DEM's CRS (when no line file is given)."),
        Parameter("spacing", "number", "Sample spacing [m]", optional=True, minimum=0.001,
                  unit="m", help="Default: the finest cell size of the DEMs."),
        Parameter("output", "output_folder", "Output folder"),
    )
    outputs = (
        Output("csv", "file", "Profile table (CSV)"),
        Output("png", "file", "Profile plot (PNG)"),
        Output("length", "number", "Line length [m]"),
        Output("samples", "number", "Number of samples"),
    )

    def run(self, params: Dict[str, Any], feedback: Feedback) -> Dict[str, Any]:
        from ...quality.profile import dem_profile  # lazy: keeps photodem list fast

        out = Path(params["output"])
        with staged_folder(out, replace=True, product=self.id) as tmp:
            result = dem_profile(params["dems"], csv_path=tmp / "profile.csv",
                                 png_path=tmp / "profile.png", line=params.get("line"),
                                 coordinates=params.get("coordinates"),
                                 spacing=params.get("spacing"), feedback=feedback)
        feedback.info(f"Profile of {result['length']:.1f} m, {result['samples']} samples every "
                      f"{result['spacing']:g} m.")
        return {"csv": str(out / "profile.csv"), "png": str(out / "profile.png"),
                "length": result["length"], "samples": result["samples"]}


class PointCompare(Algorithm):
    id = "point_compare"
    name = "Compare points with DEM"
    group = GROUP
    group_id = GROUP_ID
    help = (
        "Compares points (check points or matched points) with a DEM: Δz = DEM − point, the "
        "DEM interpolated bilinearly. Reads XYZ text ('x y z' or 'id x y z', whitespace or "
        "commas, '#' comments), CSV with a header (columns x, y, z by name) or a GeoPackage of "
        "3-D points (or with a height field). Writes residuals.csv (points outside the DEM "
        "are listed as such) and the same statistics as the DEM comparison."
    )
    parameters = (
        Parameter("points", "file", "Points (XYZ text, CSV or GeoPackage)"),
        Parameter("dem", "raster", "DEM to check"),
        Parameter("output", "output_folder", "Output folder"),
        Parameter("flying_height", "number", "Flying height above ground [m]", optional=True,
                  minimum=1.0, unit="m",
                  help="For the statistics in ‰ of the flying height."),
    )
    outputs = (
        Output("stats", "json", "Statistics of Δz [m]"),
        Output("points", "number", "Points read"),
        Output("used", "number", "Points on the DEM"),
        Output("outside", "number", "Points outside the DEM"),
        Output("residuals", "file", "Residual table (CSV)"),
        Output("json", "file", "Statistics as JSON"),
        Output("csv", "file", "Statistics as CSV"),
    )

    def run(self, params: Dict[str, Any], feedback: Feedback) -> Dict[str, Any]:
        from ...quality.compare_run import run_point_compare  # lazy: keeps photodem list fast

        return run_point_compare(params["points"], params["dem"], params["output"],
                                 flying_height=params.get("flying_height"), feedback=feedback)


ALGORITHMS: list = [DemCompare, DemProfile, PointCompare]
