"""Epipolar images of a stereo model written to a folder (the ``epipolar_pair`` product).

Both images are resampled to normal-case geometry block by block; beside them go maps back to
the original pixels and ``epipolar.json`` with the homographies, for matching and
triangulation.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any, Dict

import numpy as np
from rasterio.windows import Window

from ..feedback import Feedback
from ..geometry.epipolar import RESAMPLE_BLOCK_PIXELS, SIDES, EpipolarPair
from ..geometry.projection import ray_at_height, world_to_pixel
from ..jsonable import json_ready
from ..project.model import Project
from ..raster.io import gtiff_profile, open_image, staged_folder
from .model_setup import model_heights, model_pair, overlap_areas


def _y_parallax_check(pair: EpipolarPair, height: float, n: int = 15) -> float:
    """Largest |row_left − row_right| (px) of a grid of points in the left image, intersected
    with the plane Z = ``height`` and mapped through both original images."""
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
    w, h = pair.sizes[SIDES.index(side)]
    chunk = max(1, RESAMPLE_BLOCK_PIXELS // max(w, 1))
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


def write_epipolar_pair(project: Project, model_name: str, out_dir: Path, scale: float,
                        feedback: Feedback, product: str = "epipolar_pair") -> Dict[str, Any]:
    """Resample the two images of a stereo model to epipolar geometry into ``out_dir``.

    Parameters
    ----------
    project : Project
        The loaded project.
    model_name : str
        Name of the stereo model.
    out_dir : Path
        Output folder (staged: replaced only when complete).
    scale : float
        Epipolar pixel density relative to the originals (0.5 = half resolution).
    feedback : Feedback
        Progress, messages and cancellation.
    product : str
        Algorithm id recorded in the folder's product marker.

    Returns
    -------
    dict
        Paths of the written files, the largest y-parallax of check points (px) and the left
        image's size ``[w, h]``.
    """
    model = project.model(model_name)
    recs = [project.image(model.left), project.image(model.right)]
    cams = [project.camera_of(r) for r in recs]
    # the geometry matching uses: a convergent pair is rectified with minimal distortion and
    # cut to its overlap at the model's height range
    z_min, z_mid, z_max, _ = model_heights(project, model, recs)
    pair = model_pair(cams, recs, overlap_areas(cams, recs, (z_min, z_mid, z_max)), scale)
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
    with staged_folder(out_dir, replace=True, product=product) as tmp:
        done = 0
        for side, img in zip(SIDES, images):
            done = _write_side(pair, side, img, tmp, feedback, done, total_rows)
        meta = pair.to_dict()
        meta.update({
            "model": model.name,
            "images": {"left": recs[0].name, "right": recs[1].name},
            "image_files": {"left": str(project.image_path(recs[0])),
                            "right": str(project.image_path(recs[1]))},
            "scale": scale,
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
