"""Algorithm declarations: orthophotos (rectification, mosaics, displacement analysis)."""

from __future__ import annotations

from pathlib import Path
from typing import Any, Dict, List, Optional

from ...errors import InputError
from ...feedback import Feedback
from ...project.model import Project
from ..spec import Algorithm, Output, Parameter, project_product
from ..tiled import scheduler_parameter

# Domain modules are imported inside each run(), not here: keeps `photodem list` fast.

GROUP = "Orthophotos"
GROUP_ID = "ortho"


class Orthorectify(Algorithm):
    id = "orthorectify"
    name = "Orthorectify image"
    group = GROUP
    group_id = GROUP_ID
    help = (
        "Indirect differential rectification of one image of the project onto a DEM: for every "
        "output cell the height comes from the DEM (bilinear), the cell is projected into the "
        "image by the collinearity equations (with distortion) and the image is resampled there "
        "(nearest, bilinear or cubic), tile by tile. A DTM gives a classical ortho (buildings "
        "lean away from the nadir by Δr = h·r/H); a true ortho needs the DSM: cells the camera "
        "cannot see because a building or tree hides them are marked occluded (alpha 0, "
        "visibility 2) so that a mosaic fills them from another image. Writes a Cloud-Optimised "
        "GeoTIFF (COG) with overviews (the image bands plus an alpha band) and "
        "<name>_visibility.tif (0 "
        "outside the image, 1 visible, 2 occluded). A DEM in another CRS is reprojected on the "
        "fly (with a warning)."
    )
    parameters = (
        Parameter("project", "project", "Project folder or project.toml"),
        Parameter("image", "image", "Image"),
        Parameter("dem", "raster", "DEM (DTM, or DSM for a true ortho)",
                  help="Heights of the surface to rectify onto; any CRS (reprojected on the "
                       "fly)."),
        Parameter("output", "output_raster", "Orthophoto", optional=True, extensions=(".tif",),
                  help="Default: <project>/products/ortho/<image>.tif."),
        Parameter("gsd", "number", "Cell size (GSD) [m]", optional=True, minimum=0.0,
                  unit="m", help="Default: the image's ground sample distance at the DEM's "
                                 "mean height, rounded."),
        Parameter("resampling", "enum", "Resampling", default="bilinear",
                  options=("nearest", "bilinear", "cubic")),
        Parameter("true_ortho", "bool", "True ortho (occlusion test)", default=False,
                  help="Mask cells hidden from the camera by the DSM; needs the DSM."),
        Parameter("dsm", "raster", "DSM for the occlusion test", optional=True,
                  help="Needed for a true ortho; the DEM should then be this DSM too."),
        Parameter("extent", "extent", "Extent", optional=True,
                  help="xmin,ymin,xmax,ymax in the project CRS. Default: the image footprint "
                       "on the DEM."),
    )
    outputs = (
        Output("ortho", "raster", "Orthophoto"),
        Output("visibility", "raster", "Visibility (0 outside, 1 visible, 2 occluded)"),
        Output("gsd", "number", "Cell size (m)"),
        Output("occluded_pct", "number", "Occluded cells (% of the cells inside the image)"),
        Output("cells", "json", "Size [width, height] (cells)"),
    )
    iterates_over = "image"

    def default_output(self, params: Dict[str, Any]) -> Optional[Path]:
        """``<project>/products/ortho/<image>.tif``."""
        name = Path(params["image"]).name
        return project_product(params, "ortho", f"{name}.tif", f"The image name '{name}'")

    def sidecars(self, name: str, path: Path) -> List[Path]:
        """``<name>_visibility.tif`` beside the ortho."""
        from ...ortho.rectify import visibility_path  # lazy: keeps photodem list fast

        return [visibility_path(path)]

    def run(self, params: Dict[str, Any], feedback: Feedback) -> Dict[str, Any]:
        from ...ortho.rectify import orthorectify_image  # lazy: keeps photodem list fast

        dsm = params.get("dsm")
        if params.get("true_ortho") and not dsm:
            raise InputError("A true ortho needs a DSM: set 'dsm' (and use the DSM as 'dem' "
                             "too), or switch true_ortho off.")
        project = Project.load(params["project"])
        output = str(self.output_path(params))
        res = orthorectify_image(
            project, params["image"], params["dem"], output,
            gsd=params.get("gsd") or None, resampling=params.get("resampling") or "bilinear",
            dsm=dsm if params.get("true_ortho") else None, extent=params.get("extent"),
            feedback=feedback)
        return {k: res[k] for k in ("ortho", "visibility", "gsd", "occluded_pct", "cells")}


class OrthoDisplacement(Algorithm):
    id = "ortho_displacement"
    name = "Ortho displacement from DEM errors"
    group = GROUP
    group_id = GROUP_ID
    help = (
        "Shows where a DEM error moves an orthophoto. Predicted: for an image of the project "
        "and a DEM error e = DEM − reference (a difference raster, or the DEM and the reference "
        "DEM) the exact ray geometry gives the displacement d = −e·(X − X0, Y − Y0)/(Z0 − Zref), "
        "|d| = ΔR = Δh·R/H (R: distance from the nadir point, H: flying height above the "
        "cell); written as displacement.tif (|d|, dx, dy and the signed radial part, m, + away "
        "from the nadir). Measured: two orthos of the same area are matched in windows on a "
        "grid (NCC search, then least-squares refinement to a fraction of a pixel); shifts.gpkg "
        "and shifts.csv hold dx, dy (m and px), NCC and a status per window, summary.json the "
        "mean and RMS shift. With both, the predicted shift is added to every window."
    )
    parameters = (
        Parameter("project", "project", "Project folder or project.toml", optional=True,
                  help="Needed for the predicted displacement."),
        Parameter("image", "image", "Image", optional=True,
                  help="The image whose ortho is analysed (predicted displacement)."),
        Parameter("error", "raster", "DEM error (DEM − reference) [m]", optional=True,
                  help="E.g. difference.tif of 'Compare DEM with reference'; its grid is the "
                       "output grid."),
        Parameter("dem", "raster", "DEM of the ortho", optional=True,
                  help="With the reference DEM instead of an error raster: e = DEM − "
                       "reference on the DEM's grid."),
        Parameter("reference", "raster", "Reference DEM (true heights)", optional=True),
        Parameter("terrain_height", "number", "Terrain height [m]", optional=True, unit="m",
                  help="True height for H when only the error raster is given (default: the "
                       "project's terrain height)."),
        Parameter("ortho", "raster", "Ortho to check", optional=True,
                  help="Measured shift: this ortho is matched against the reference ortho."),
        Parameter("reference_ortho", "raster", "Reference ortho", optional=True,
                  help="Its grid defines the windows and the pixel unit (e.g. the ortho on "
                       "the reference DEM, or a neighbouring ortho)."),
        Parameter("window", "integer", "Matching window [px]", default=31, minimum=5,
                  maximum=255, unit="px", help="Odd size of the matched windows."),
        Parameter("radius", "integer", "Search radius [px]", default=8, minimum=1,
                  maximum=200, unit="px", help="Largest shift that is searched for."),
        Parameter("spacing", "integer", "Window spacing [px]", optional=True, minimum=1,
                  unit="px", help="Default: the window size."),
        Parameter("min_ncc", "number", "Minimum correlation", default=0.6, minimum=-1.0,
                  maximum=1.0),
        Parameter("output", "output_folder", "Output folder",
                  help="Receives displacement.tif, shifts.gpkg, shifts.csv and summary.json."),
    )
    outputs = (
        Output("displacement", "raster", "Predicted displacement (|d|, dx, dy, radial) [m]"),
        Output("predicted", "json", "Statistics of the predicted displacement"),
        Output("points", "vector", "Measured shifts per window (GeoPackage)"),
        Output("csv", "file", "Measured shifts per window (CSV)"),
        Output("measured", "json", "Statistics of the measured shifts"),
        Output("comparison", "json", "Measured against predicted shifts"),
        Output("json", "file", "Summary (JSON)"),
    )
    iterates_over = "image"

    def run(self, params: Dict[str, Any], feedback: Feedback) -> Dict[str, Any]:
        # lazy: keeps photodem list fast
        from ...ortho.displacement_run import (
            DisplacementInputs,
            MatchSettings,
            run_ortho_displacement,
        )

        g = params.get
        inputs = DisplacementInputs(
            project=g("project"), image=g("image"), error=g("error"), dem=g("dem"),
            reference=g("reference"), terrain_height=g("terrain_height"), ortho=g("ortho"),
            reference_ortho=g("reference_ortho"))
        match = MatchSettings(window=int(params["window"]), radius=int(params["radius"]),
                              spacing=g("spacing"), min_ncc=float(params["min_ncc"]))
        return run_ortho_displacement(params["output"], inputs, match, feedback=feedback)


class Mosaic(Algorithm):
    id = "mosaic"
    name = "Orthophoto mosaic"
    group = GROUP
    group_id = GROUP_ID
    help = (
        "Mosaics orthos into one Cloud-Optimised GeoTIFF (COG) with overviews (colour bands + "
        "alpha). Inputs: "
        "orthos (PhotoDEM orthos carry their projection centre), or a project and a DEM: then "
        "every image is rectified first (a true ortho on the DSM with true_ortho). Seamlines: "
        "auto starts from the nadir partition (each cell to the image with the nearest "
        "projection centre) and routes every seam along a least-cost path through low image "
        "difference and low DSM height above the DTM (give dsm and dtm), so seams do not cut "
        "through buildings or trees; nadir keeps the partition; edits takes the 'seamlines' "
        "layer of the project's edits.gpkg; or give a vector file: lines cut the area (each "
        "part to the image nearest in nadir), polygons with an 'image' attribute take their "
        "area from that image (the footprints layer a mosaic writes can be edited and reused). "
        "Occluded cells (alpha 0) are filled from the next best image. Balancing: gain and "
        "offset per image and band by least squares over all overlaps (gain_offset), plus "
        "histogram matching (histogram), or none; feathering blends across seams over the "
        "given width. Writes the mosaic, <name>_seamlines.gpkg (footprints: one polygon per "
        "source image; seamlines) and <name>_balance.json (gains, offsets, mean difference of "
        "the overlaps before and after). Works tile by tile; seams and balancing use a seam "
        "grid of at most seam_cells cells a side, so memory does not grow with the mosaic."
    )
    parameters = (
        Parameter("project", "project", "Project folder or project.toml", optional=True,
                  help="Needed with 'dem' (rectify every image) and for seamlines=edits."),
        Parameter("inputs", "multiple_rasters", "Orthos", optional=True,
                  help="Orthos to mosaic (same CRS, bands and data type)."),
        Parameter("dem", "raster", "DEM to rectify the project images on", optional=True,
                  help="Instead of 'inputs': every image of the project is rectified onto it."),
        Parameter("true_ortho", "bool", "True orthos (occlusion test)", default=False,
                  help="With 'dem': rectify on the DSM with the occlusion test; needs 'dsm'."),
        Parameter("dsm", "raster", "DSM", optional=True,
                  help="Surface for true orthos and, with the DTM, for seams that avoid "
                       "buildings and trees."),
        Parameter("dtm", "raster", "DTM", optional=True,
                  help="Terrain for the height above ground (DSM − DTM) of the seam cost. "
                       "Default with 'dem': the DEM when it is not the DSM."),
        Parameter("gsd", "number", "Cell size (GSD) [m]", optional=True, minimum=0.0, unit="m",
                  help="Default: the finest input (or the images' GSD when rectifying)."),
        Parameter("resampling", "enum", "Resampling (rectification)", default="bilinear",
                  options=("nearest", "bilinear", "cubic")),
        Parameter("seamlines", "string", "Seamlines", default="auto",
                  help="auto, nadir, edits, or a vector file (lines, or polygons with an "
                       "'image' attribute)."),
        Parameter("balance", "enum", "Radiometric balancing", default="gain_offset",
                  options=("none", "gain_offset", "histogram")),
        Parameter("reference", "string", "Reference image", optional=True,
                  help="Image kept unchanged by the balancing. Default: mean gain 1, mean "
                       "offset 0."),
        Parameter("feather", "number", "Feather width [m]", optional=True, minimum=0.0,
                  unit="m", help="Blend width across seams. Default: 10 cells; 0 = hard."),
        Parameter("corridor", "number", "Seam corridor half-width [m]", optional=True,
                  minimum=0.0, unit="m",
                  help="How far a seam may leave the nadir boundary. Default: a quarter of the "
                       "distance between neighbouring projection centres."),
        Parameter("min_height", "number", "Object height [m]", default=2.0, minimum=0.0,
                  unit="m", help="Cells at least this high above the DTM are avoided by seams."),
        Parameter("tile", "integer", "Tile size [cells]", default=1024, minimum=64,
                  maximum=8192, unit="cells", help="Side of the processing tiles."),
        Parameter("seam_cells", "integer", "Seam grid size [cells]", default=1024,
                  minimum=64, maximum=8192, unit="cells",
                  help="Longest side of the reduced grid for seams and balancing."),
        scheduler_parameter(),
        Parameter("output", "output_raster", "Mosaic", optional=True, extensions=(".tif",),
                  help="Default: <project>/products/mosaic/mosaic.tif."),
    )
    outputs = (
        Output("mosaic", "raster", "Mosaic"),
        Output("seamlines", "vector", "Footprints and seamlines (GeoPackage)"),
        Output("report", "file", "Balancing report (JSON)"),
        Output("gsd", "number", "Cell size (m)"),
        Output("cells", "json", "Size [width, height] (cells)"),
        Output("seams", "json", "Seam statistics"),
        Output("balance", "json", "Mean difference in the overlaps before/after balancing"),
    )

    def default_output(self, params: Dict[str, Any]) -> Optional[Path]:
        """``<project>/products/mosaic/mosaic.tif`` when a project is given."""
        if not params.get("project"):
            return None
        return project_product(params, "mosaic", "mosaic.tif", "The mosaic")

    def sidecars(self, name: str, path: Path) -> List[Path]:
        """``<name>_seamlines.gpkg`` and ``<name>_balance.json`` beside the mosaic."""
        from ...ortho.mosaic import sibling_paths  # lazy: keeps photodem list fast

        return [p for k, p in sibling_paths(path).items() if k != "mosaic"]

    def run(self, params: Dict[str, Any], feedback: Feedback) -> Dict[str, Any]:
        # lazy: keeps photodem list fast
        from ...ortho.mosaic import MosaicOptions, MosaicSources, run_mosaic

        g = params.get
        project = Project.load(params["project"]) if g("project") else None
        output = self.output_path(params)
        if output is None:
            raise InputError("Give the output file of the mosaic (or a project, whose "
                             "products/mosaic/ folder is then used).")
        sources = MosaicSources(
            inputs=g("inputs"), project=project, dem=g("dem"), dsm=g("dsm"), dtm=g("dtm"),
            gsd=g("gsd") or None, resampling=g("resampling") or "bilinear",
            true_ortho=bool(g("true_ortho")))
        options = MosaicOptions(
            seamlines=g("seamlines") or "auto", balance=g("balance") or "gain_offset",
            feather=g("feather"), reference=g("reference") or None,
            corridor=g("corridor") or None,
            min_height=2.0 if g("min_height") is None else params["min_height"],
            tile=g("tile") or 1024, seam_cells=g("seam_cells") or 1024,
            scheduler=g("scheduler") or "")
        res = run_mosaic(output, sources, options, feedback)
        return {k: res[k] for k in ("mosaic", "seamlines", "report", "gsd", "cells", "seams",
                                    "balance")}


ALGORITHMS = [Orthorectify, OrthoDisplacement, Mosaic]
