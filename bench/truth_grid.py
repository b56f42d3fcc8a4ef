"""Rasters resampled onto a truth grid (bench helper shared by the object and drone benches)."""

from __future__ import annotations

from pathlib import Path
from typing import Any, Tuple, Union

import numpy as np

PathLike = Union[str, Path]


def on_grid(path: PathLike, shape: Tuple[int, int], transform: Any, crs: Any,
            nearest: bool = False) -> np.ndarray:
    """Band 1 of ``path`` resampled (bilinear, or nearest) onto a grid; NaN where it has no
    value."""
    import rasterio
    from rasterio.warp import Resampling, reproject

    out = np.full(shape, np.nan, np.float32)
    with rasterio.open(path) as src:
        reproject(rasterio.band(src, 1), out, src_nodata=src.nodata, dst_transform=transform,
                  dst_crs=crs, dst_nodata=np.nan,
                  resampling=Resampling.nearest if nearest else Resampling.bilinear)
    return out
