"""Small GeoTIFFs for tests (plain functions, no fixtures), shared by the core and widget tests."""

from __future__ import annotations

from pathlib import Path
from typing import Any, Optional, Sequence

import numpy as np
import rasterio
from affine import Affine
from rasterio.enums import Resampling

#: The default grid: upper-left corner and cell size (m) in EPSG:25832.
X0, Y0, RES = 400000.0, 5600000.0, 0.5
CRS = "EPSG:25832"


def write_raster(path: Path, data: Any, crs: Optional[str] = CRS, transform: Any = None,
                 nodata: Optional[float] = None, overviews: Sequence[int] = ()) -> Path:
    """Write ``data`` ((rows, cols) or (bands, rows, cols)) as a tiled GeoTIFF on the default
    grid (or ``transform``); ``crs=None`` writes none; ``overviews`` are internal."""
    data = np.asarray(data)
    data = data[None] if data.ndim == 2 else data
    profile = {"driver": "GTiff", "width": data.shape[2], "height": data.shape[1],
               "count": data.shape[0], "dtype": str(data.dtype),
               "transform": transform or Affine(RES, 0, X0, 0, -RES, Y0),
               "tiled": True, "blockxsize": 256, "blockysize": 256}
    if crs:
        profile["crs"] = crs
    if nodata is not None:
        profile["nodata"] = nodata
    with rasterio.open(path, "w", **profile) as dst:
        dst.write(data)
        if overviews:
            dst.build_overviews(list(overviews), Resampling.average)
    return path
