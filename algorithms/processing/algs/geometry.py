"""Algorithm declarations: geometry."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any, Dict, Optional

import numpy as np

from ...feedback import Feedback
from ...geometry.epipolar import SIDES, EpipolarPair
from ...jsonable import json_ready
from ...project.model import Project
from ...raster.io import gtiff_profile, open_image, staged_folder
from ..spec import Algorithm, Output, Parameter, model_product

# Domain modules are imported inside each run(), not here: keeps `photodem list` fast.

#: Pixels per resampled row block (per band): bounds the memory of the resampling.
_BLOCK_PIXELS = 1_000_000



def _y_parallax_check(pair: EpipolarPair, height: float, n: int = 15) -> float:
    """Largest |row_left − row_right| (px) of a grid of points in the left image, intersected
    with the plane Z = ``height`` and mapped through both original images."""
    from ...geometry.projection import ray_at_height, world_to_pixel

    cam_l, cam_r = pair.cameras
    cc, rr = np.meshgrid(np.linspace(0, cam_l.width - 1, n), np.linspace(0, cam_l.height - 1, n))
    pts = ray_at_height(cc.ravel(), rr.ravel(), height, cam_l, pair.eos[0])
    c_r, r_r = world_to_pixel(pts, cam_r, pair.eos[1])
    inside = (c_r >= 0) & (c_r <= cam_r.width - 1) & (r_r >= 0) & (r_r <= cam_r.height - 1)
    if not inside.any():
        return float("nan")
    _, row_l = pair.from_original("left", cc.ravel()[inside], rr.ravel()[inside])
    _, row_r = pair.from_original("right", c_r[inside], r_r[inside])
    # below 1e-6 px it is round-off of the homographies, which differs between LAPACK builds
    return round(float(np.max(np.abs(row_l - row_r))), 6)


def _write_side(pair: EpipolarPair, side: str, img: np.ndarray, folder: Path,
                feedback: Feedback, done_rows: int, total_rows: int) -> int:
    """Write ``<side>.tif`` (bands + alpha) and ``<side>_map.tif`` block by block.

    Returns the updated count of rows written (for the progress of both sides).
    """
    from rasterio.windows import Window

    w, h = pair.sizes[SIDES.index(side)]
    chunk = max(1, _BLOCK_PIXELS // max(w, 1))
    bands = img.shape[0]
    photometric = "RGB" if bands == 3 else "MINISBLACK"
    img_profile = gtiff_profile(w, h, bands + 1, img.dtype.name, photometric=photometric,
                                alpha="YES")
    map_profile = gtiff_profile(w, h, 2, "float32", nodata=float("nan"), predictor=3)
    alpha_max = np.iinfo(img.dtype).max if np.issubdtype(img.dtype, np.integer) else 1.0
    # epipolar images live in image space: no geotransform, on purpose
    with open_image(folder / f"{side}.tif", "w", **img_profile) as dst, \
            open_image(folder / f"{side}_map.tif", "w", **map_profile) as dmap:
        dmap.descriptions = ("original_col", "original_row")
        for r0, block, valid, mc, mr in pair.iter_resample(img, side, chunk):
            rows = block.shape[1]
            window = Window(0, r0, w, rows)
            alpha = np.where(valid, alpha_max, 0).astype(img.dtype)
            dst.write(np.concatenate([block, alpha[None]]), window=window)
            dmap.write(np.stack([mc, mr]).astype(np.float32), window=window)
            done_rows += rows
            feedback.progress(99.0 * done_rows / total_rows)  # also checks cancel
    return done_rows


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
        project = Project.load(params["project"])
        model = project.model(params["model"])
        recs = [project.image(model.left), project.image(model.right)]
        cams = [project.camera_of(r) for r in recs]
        out_dir = self.output_path(params)
        pair = EpipolarPair.from_orientations(cams[0], recs[0].eo, cams[1], recs[1].eo,
                                              scale=float(params["scale"]),
                                              names=(recs[0].name, recs[1].name))
        # read both inputs first: a bad file fails before any output exists
        images = [project.read_image(rec) for rec in recs]
        feedback.info(f"Epipolar pair {model.name}: base {pair.base:.2f} m, "
                      f"f {pair.focal_px:.2f} px, sizes {pair.sizes[0]} / {pair.sizes[1]}.")
        height = project.terrain_height
        if height is None:
            mean_z = 0.5 * (recs[0].eo.position[2] + recs[1].eo.position[2])
            h = model.height_above_ground
            height = mean_z - h if np.isfinite(h) else mean_z - 10.0 * pair.base
        y_check = _y_parallax_check(pair, float(height))

        total_rows = sum(s[1] for s in pair.sizes)
        with staged_folder(out_dir, replace=True, product=self.id) as tmp:
            done = 0
            for side, img in zip(SIDES, images):
                done = _write_side(pair, side, img, tmp, feedback, done, total_rows)
            meta = pair.to_dict()
            meta.update({
                "model": model.name,
                "images": {"left": recs[0].name, "right": recs[1].name},
                "image_files": {"left": str(project.image_path(recs[0])),
                                "right": str(project.image_path(recs[1]))},
                "scale": float(params["scale"]),
                "alpha_band": int(images[0].shape[0] + 1),
                "y_parallax_check_px": y_check,
                "crs": project.crs,
            })
            (tmp / "epipolar.json").write_text(json.dumps(json_ready(meta), indent=1),
                                               encoding="utf-8")
            feedback.check()
        feedback.info(f"y-parallax check: {y_check:.2e} px.")
        return {
            "folder": str(out_dir),
            "left": str(out_dir / "left.tif"),
            "right": str(out_dir / "right.tif"),
            "left_map": str(out_dir / "left_map.tif"),
            "right_map": str(out_dir / "right_map.tif"),
            "metadata": str(out_dir / "epipolar.json"),
            "y_parallax_check_px": y_check,
            "size": [int(pair.sizes[0][0]), int(pair.sizes[0][1])],
        }


ALGORITHMS: list = [EpipolarPairAlgorithm]
