"""``stereo_disparity``: dense disparity raster of an epipolar pair, tile by tile.

The two images are read window by window (:func:`grey_source`: mean of the colour bands,
NaN where GDAL's mask says no data), matched by :func:`.dense.iter_disparity_tiles` and the
tiles are written into a float32 GeoTIFF in the geometry of the left image (its
georeference kept when it has one). Nothing is left behind on error or cancel
(:func:`..raster.io.atomic_output`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Dict, Iterable, Optional, Tuple, Union

import numpy as np
from rasterio.enums import ColorInterp
from rasterio.windows import Window

from ..errors import InputError
from ..feedback import Feedback, ensure_feedback
from ..raster.io import atomic_output, gtiff_profile, open_image
from .dense import METHODS, Array, DenseOptions, GreySource, iter_disparity_tiles

PathLike = Union[str, Path]


def grey_source(src: Any) -> Tuple[GreySource, Tuple[int, int]]:
    """Window reader of a rasterio dataset: mean of the colour bands, NaN where masked.

    The mask is GDAL's (alpha band, nodata value or internal mask): 0 → no data. Windows
    reaching beyond the image are NaN there.

    Returns
    -------
    read : GreySource
        ``read(r0, r1, c0, c1)`` → float32 (r1 − r0, c1 − c0).
    shape : (int, int)
        (height, width) of the image.
    """
    interp = list(src.colorinterp)
    bands = [i + 1 for i, c in enumerate(interp) if c != ColorInterp.alpha] or [1]
    bands = bands[:3]
    h, w = src.height, src.width

    def read(r0: int, r1: int, c0: int, c1: int) -> np.ndarray:
        out = np.full((r1 - r0, c1 - c0), np.nan, np.float32)
        rr0, rr1, cc0, cc1 = max(r0, 0), min(r1, h), max(c0, 0), min(c1, w)
        if rr1 <= rr0 or cc1 <= cc0:
            return out
        win = Window(cc0, rr0, cc1 - cc0, rr1 - rr0)
        grey = src.read(bands, window=win).astype(np.float32).mean(axis=0)
        mask = src.read_masks(bands[0], window=win) == 0
        grey[mask | ~np.isfinite(grey)] = np.nan
        out[rr0 - r0:rr1 - r0, cc0 - c0:cc1 - c0] = grey
        return out

    return read, (h, w)


@dataclass
class DisparityStats:
    """Valid pixels and disparity range over the written tiles."""

    n_valid: int = 0
    d_min: float = math.inf
    d_max: float = -math.inf

    def add(self, block: Array) -> None:
        """Count the finite disparities of a tile."""
        ok = np.isfinite(block)
        if ok.any():
            self.n_valid += int(ok.sum())
            self.d_min = min(self.d_min, float(block[ok].min()))
            self.d_max = max(self.d_max, float(block[ok].max()))


def _check_parameters(output: PathLike, min_disparity: int, max_disparity: int,
                      block_size: int) -> None:
    """Raise InputError for a non-GeoTIFF output, an empty range or an even block size."""
    if not str(output).lower().endswith((".tif", ".tiff")):
        raise InputError(f"The output '{output}' must be a GeoTIFF (.tif).")
    if int(max_disparity) < int(min_disparity):
        raise InputError("max_disparity must not be smaller than min_disparity.")
    if block_size % 2 == 0:
        raise InputError(f"Parameter 'block_size' = {block_size} px must be odd "
                         "(1, 3, 5 … 11): the window needs a centre pixel.")


def _write_tiles(dst: Any, tiles: Iterable[Tuple[int, int, Array]]) -> DisparityStats:
    """Write every tile into ``dst`` (band 1) and gather the statistics."""
    stats = DisparityStats()
    for r0, c0, block in tiles:
        dst.write(block[None], window=Window(c0, r0, block.shape[1], block.shape[0]))
        stats.add(block)
    return stats


def run_stereo_disparity(left: PathLike, right: PathLike, output: PathLike,
                         min_disparity: int = 0, max_disparity: int = 63,
                         method: str = METHODS[0], block_size: int = 5,
                         p1: Optional[int] = None, p2: Optional[int] = None,
                         uniqueness: int = 10, lr_max_diff: float = 1.0,
                         fill_max_width: int = 32, memory_mb: float = 256.0,
                         feedback: Optional[Feedback] = None) -> Dict[str, Any]:
    """Disparity raster d = x_left − x_right of an epipolar pair (``stereo_disparity``).

    Parameters
    ----------
    left, right : path
        Epipolar images (rows correspond); alpha bands and nodata are honoured.
    output : path
        Float32 GeoTIFF in left-image geometry, NaN where no disparity.
    min_disparity, max_disparity : int
        Search range (px), may be negative.
    method : {"sgm", "opencv_sgbm"}
    block_size : int
        Odd side of the matching window (px).
    p1, p2 : int, optional
        SGM penalties (default 8 and 32 × block size²).
    uniqueness : int
        Percent by which the best match must beat the second best.
    lr_max_diff : float
        Left–right tolerance (px); negative = no check.
    fill_max_width : int
        Invalid runs along a row up to this width are filled; 0 = none.
    memory_mb : float
        Memory per tile (sets the tile size).
    feedback : Feedback, optional

    Returns
    -------
    dict
        ``disparity`` (path), ``valid_share``, ``min`` and ``max`` (None without any).
    """
    feedback = ensure_feedback(feedback)
    _check_parameters(output, min_disparity, max_disparity, block_size)
    with open_image(left) as src_l, open_image(right) as src_r:
        if src_l.height != src_r.height:
            feedback.warning(f"The images have {src_l.height} and {src_r.height} rows; "
                             "rows are matched by index (epipolar images share rows).")
        read_l, shape_l = grey_source(src_l)
        read_r, shape_r = grey_source(src_r)
        h, w = shape_l
        profile = gtiff_profile(w, h, 1, "float32", nodata=float("nan"), predictor=3)
        if src_l.crs is not None:  # keep a georeference if the left image has one
            profile.update(crs=src_l.crs, transform=src_l.transform)
        with atomic_output(output) as tmp, open_image(tmp, "w", **profile) as dst:
            options = DenseOptions(method=method, block_size=block_size, p1=p1, p2=p2,
                                   uniqueness=uniqueness, lr_max_diff=lr_max_diff,
                                   fill_max_width=fill_max_width)
            tiles = iter_disparity_tiles(read_l, read_r, shape_l, shape_r, min_disparity,
                                         max_disparity, options, max_memory_mb=memory_mb,
                                         feedback=feedback)
            stats = _write_tiles(dst, tiles)
    share = stats.n_valid / float(max(h * w, 1))
    feedback.info(f"Disparity for {100.0 * share:.1f} % of the pixels.")
    return {
        "disparity": str(output),
        "valid_share": share,
        "min": stats.d_min if stats.n_valid else None,
        "max": stats.d_max if stats.n_valid else None,
    }


__all__ = ["DisparityStats", "grey_source", "run_stereo_disparity"]
