"""Algorithm declarations: automatic georeferencing against GIS polygons.

The domain modules are imported inside ``run`` (lazy: keeps ``photodem list`` fast).
"""

from __future__ import annotations

from typing import Any, Dict

from ...feedback import Feedback
from ..spec import Algorithm, Output, Parameter

GROUP = "Georeferencing"
GROUP_ID = "georef"


class GeoreferencePolygons(Algorithm):
    id = "georeference_polygons"
    name = "Georeference image against polygons"
    group = GROUP
    group_id = GROUP_ID
    iterates_over = "image"  # batch files: one task per image file (files = [...])
    help = (
        "Finds the georeference of an image without approximate values (position, scale, "
        "rotation and mirroring unknown) by matching area objects: the image is segmented by "
        "region growing at several thresholds, its regions and the reference polygons (one "
        "class of a vector layer, touching polygons dissolved — or a segmented orthophoto) are "
        "described by affine-invariant moment features, corresponding objects are found by a "
        "consistency search, verified, refined by ICP, and control points on their outlines "
        "give the final transform (affine, projective or 2nd-order polynomial). When no "
        "objects match (objects not homogeneous in the image), an area-based search compares "
        "the whole image with the rasterised polygons, or the polygons' individual outlines "
        "with the image's edge directions, instead. Writes a QGIS "
        "Georeferencer .points file, the control points as GeoPackage, the image resampled into "
        "the map CRS, a copy with the control points embedded and a report (overlay, "
        "residuals, RMSE in px and m). Too few matching objects give a failure message with "
        "the counts of every stage, not a wrong result."
    )
    parameters = (
        Parameter("image", "raster", "Image to georeference",
                  help="Any band count (default: the mean of the bands); its own georeference, "
                       "if any, is ignored."),
        Parameter("reference", "file", "Reference (polygon layer or orthophoto)",
                  extensions=(".gpkg", ".shp", ".geojson", ".json", ".tif", ".tiff"),
                  help="A polygon layer in any CRS (matched in its projected CRS, or the UTM "
                       "zone of its centre), or a georeferenced raster (an orthophoto or "
                       "satellite scene in a projected CRS): matched by keypoints first, else "
                       "segmented like the image."),
        Parameter("class_field", "string", "Class attribute", optional=True,
                  help="Attribute selecting the polygons to match (e.g. landuse); empty = all "
                       "polygons."),
        Parameter("class_value", "string", "Class value", optional=True,
                  help="Value of the class attribute (e.g. forest)."),
        Parameter("transform", "enum", "Transform", default="affine",
                  options=("affine", "projective", "poly2")),
        Parameter("output", "output_folder", "Output folder"),
        Parameter("thresholds", "string", "Segmentation thresholds [DN]", default="5,6,7,8",
                  help="Region-growing thresholds in grey values of 8-bit data (other data are "
                       "stretched to 0–255 first), small = over-segmentation."),
        Parameter("pyramid_level", "integer", "Pyramid level (−1 = auto)", default=-1,
                  minimum=-1, maximum=4,
                  help="Segment this pyramid level (factor 2 each); auto: the first level "
                       "with at most 4 Mpx."),
        Parameter("relative_difference", "number", "Invariant tolerance [%]", default=3.0,
                  minimum=0.1, maximum=20.0, unit="%",
                  help="Relative difference allowed for each of the six invariants."),
        Parameter("max_depth", "integer", "Search depth [pairs]", default=6, minimum=2,
                  maximum=20),
        Parameter("search", "enum", "Search", default="auto",
                  options=("auto", "objects", "area", "keypoints"),
                  help="objects: match image regions to the polygons as objects; area: "
                       "compare the whole image with the rasterised polygons (rotation and "
                       "scale by Fourier–Mellin, shift by correlation, refined by ECC), and "
                       "when that fails the polygons' individual outlines with the image's "
                       "edge directions — for objects that are not homogeneous in the image, "
                       "such as glaciers (polygon layers only); keypoints: SIFT keypoints of "
                       "the image and the mirrored image matched to a raster reference, "
                       "refined by correlating image patches (raster references only); auto: "
                       "for polygons objects, then the area-based search; for a raster "
                       "keypoints, then objects."),
        Parameter("objects", "enum", "Reference objects", default="auto",
                  options=("auto", "areas", "buildings"),
                  help="buildings: many small footprints (cadastre, OpenStreetMap) matched "
                       "by the configuration of neighbouring buildings; areas: forests, "
                       "fields, lakes, glaciers; auto: buildings when the layer has at least "
                       "15 mostly rectangular polygons whose median area is below 0.4 % of the "
                       "layer's extent and below 5000 m²."),
        Parameter("sigma_np", "number", "Control point tolerance σ_NP [px]", default=2.0,
                  minimum=0.1, maximum=50.0, unit="px",
                  help="Control points are accepted (best first) while the RMS of their "
                       "outline distances stays below this."),
        Parameter("unverified", "bool", "Write an unverified result", default=False,
                  help="A result is accepted only when independent evidence supports it: "
                       "control points spread over the image, halves of them agreeing at the "
                       "image corners, image and reference agreeing best at the result. "
                       "Without that the run fails with the figures; with this option the "
                       "result is written marked UNVERIFIED instead."),
        Parameter("time_limit", "number", "Time limit [s]", default=180.0, minimum=0.0,
                  maximum=3600.0, unit="s",
                  help="The search stops when this time is spent and the run fails with the "
                       "figures found so far (0: no limit)."),
    )
    outputs = (
        Output("transform", "json", "Transform (kind, 3 × 3 matrix image col/row → map)"),
        Output("rmse_px", "number", "RMSE of the control points (px)"),
        Output("rmse_m", "number", "RMSE of the control points (map units)"),
        Output("gcps", "file", "Control points (QGIS .points)"),
        Output("gcps_gpkg", "vector", "Control points (GeoPackage)"),
        Output("image", "raster", "Georeferenced image"),
        Output("report", "file", "Report (JSON; HTML beside it)"),
        Output("n_pairs", "number", "Verified object pairs"),
        Output("n_gcps", "number", "Control points used"),
        Output("verified", "string", "Verified by independent evidence (yes/no)"),
    )

    def run(self, params: Dict[str, Any], feedback: Feedback) -> Dict[str, Any]:
        from ...georef.pipeline import GeorefOptions, run_georeference_polygons

        level = params.get("pyramid_level", -1)
        options = GeorefOptions(
            class_field=params.get("class_field") or None,
            class_value=params.get("class_value") or None,
            transform=params.get("transform") or "affine",
            thresholds=params.get("thresholds") or None,
            pyramid_level="auto" if level is None or int(level) < 0 else int(level),
            rd=float(params.get("relative_difference", 3.0)) / 100.0,
            max_depth=int(params.get("max_depth", 6)),
            sigma_np_px=float(params.get("sigma_np", 2.0)),
            search=params.get("search") or "auto",
            objects=params.get("objects") or "auto",
            unverified=bool(params.get("unverified", False)),
            time_limit_s=float(params.get("time_limit", 180.0)))
        return run_georeference_polygons(params["image"], params["reference"],
                                         params["output"], options, feedback)


ALGORITHMS = [GeoreferencePolygons]
