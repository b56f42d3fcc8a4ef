"""Algorithm declarations: synthetic data."""

from __future__ import annotations

from typing import Any, Dict

from ...feedback import Feedback
from ..spec import Algorithm, Output, Parameter

# Domain modules are imported inside each run(), not here: keeps `photodem list` fast.


class SyntheticBlock(Algorithm):
    id = "synthetic_block"
    name = "Synthetic block with ground truth"
    group = "Synthetic data"
    group_id = "synthetic"
    help = (
        "Generates a deterministic synthetic aerial block: terrain (gentle, dunes or steep), an "
        "embankment and a ditch with breaklines, buildings, trees and a forest patch, textured "
        "ground with bright check-point discs, frame images in two or more strips (60 % forward, "
        "30 % side overlap; aerial: one strip of three windowed film frames) rendered by ray "
        "casting against the true DSM. Writes a complete "
        "project (project.toml, images, edits.gpkg, in-strip stereo models) and the ground truth "
        "(DTM, DSM, land cover, building footprints, 3-D breaklines, check points) below "
        "truth/. The same seed always gives the same block."
    )
    parameters = (
        Parameter("output", "output_folder", "Output project folder"),
        Parameter("size", "enum", "Block size", default="small",
                  options=("tiny", "small", "medium", "large", "aerial", "drone"),
                  help="tiny: 224×288 px images (tests); small: 704×1000 px (demo); medium: "
                       "1408×2000 px; large: 2400×3400 px (≈ 8 Mpx); aerial: three "
                       "wide-angle film frames in one strip (11500 px, c = 153 mm, B/H 0.6, "
                       "base 4600 px, H ≈ 1150 m) of which a 1024×1024 px window over the "
                       "common ground patch is rendered — for height accuracy in ‰ of H; "
                       "drone: six 768×576 px frames of a drone camera flown ≈ 70 m above "
                       "ground, tilted 0–35° in varying directions towards a common patch "
                       "(convergent pairs, GSD 10 cm at nadir)."),
        Parameter("terrain", "enum", "Terrain type", default="gentle",
                  options=("gentle", "dunes", "steep"),
                  help="steep: relief > 100 m with slopes of 45° and more (flown 2.5× higher)."),
        Parameter("seed", "integer", "Random seed", default=1, minimum=0,
                  maximum=2 ** 31 - 1),
        Parameter("texture_direction", "number", "Direction of the field furrows [°]",
                  default=0.0, minimum=-360.0, maximum=360.0, unit="°",
                  help="Counter-clockwise from the flight direction (+X): 0 = furrows along "
                       "the base, 90 = across it."),
    )
    outputs = (
        Output("project", "folder", "Project folder"),
        Output("truth_dtm", "raster", "True DTM"),
        Output("truth_dsm", "raster", "True DSM"),
        Output("truth_landcover", "raster", "Land cover (1 open, 2 road, 3 building, "
                                            "4 tree/forest, 5 water/ditch, 6 embankment, 7 field)"),
        Output("truth_buildings", "vector", "Building footprints"),
        Output("truth_breaklines", "vector", "3-D breaklines"),
        Output("truth_checkpoints", "vector", "Check points (3-D)"),
        Output("images", "number", "Number of images"),
        Output("models", "number", "Number of stereo models"),
        Output("gsd_m", "number", "Ground sample distance [m]"),
        Output("flying_height_m", "number", "Flying height above mean terrain [m]"),
        Output("base_px", "number", "Mean model base in pixels B/GSD (σZ/H = σpx/base_px)"),
        Output("b_h", "number", "Mean base-to-height ratio B/H of the models"),
    )

    def run(self, params: Dict[str, Any], feedback: Feedback) -> Dict[str, Any]:
        from ...synthetic.block import generate_block  # lazy: keeps photodem list fast

        result = generate_block(params["output"], size=params["size"],
                                terrain=params["terrain"], seed=params["seed"],
                                texture_direction=params["texture_direction"],
                                feedback=feedback)
        return result.outputs()


ALGORITHMS: list = [SyntheticBlock]
