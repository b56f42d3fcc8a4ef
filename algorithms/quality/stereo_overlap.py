"""Where a stereo model can measure a surface at all: its frames' overlap on that surface.

A model's measuring area is the overlap of its frames at one (the mid) height. Where the
surface stands higher — roofs, crowns — or lower, a strip along that area's edge lies
outside one of the two frames: no stereo method can measure it. Figures "over the model's
overlap" against a true surface (``bench dsm_objects``, the demo's object rows) count only
the cells whose true surface point lies inside both frames (docs/decisions.md, issue 19).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Optional, Sequence, Tuple, Union

import numpy as np
import rasterio
from affine import Affine
from rasterio.features import shapes
from rasterio.transform import xy
from rasterio.windows import Window
from shapely.affinity import affine_transform
from shapely.geometry import shape
from shapely.ops import unary_union

from ..geometry.camera import Camera
from ..geometry.orientation import ExteriorOrientation
from ..geometry.projection import world_to_pixel

Frame = Tuple[Camera, ExteriorOrientation]
PathLike = Union[str, Path]


def inside_frames(frames: Sequence[Frame], points: np.ndarray, margin_px: float = 0.0
                  ) -> np.ndarray:
    """Whether each world point projects inside every frame (at least ``margin_px`` from its
    border).

    Parameters
    ----------
    frames : sequence of (Camera, ExteriorOrientation)
        The frames, e.g. a stereo model's left and right image.
    points : ndarray, shape (n, 3)
        World points (X, Y, Z in the project CRS); a point with a NaN is inside none.
    margin_px : float
        Distance (px, of each frame) a point must keep from the frame's border.

    Returns
    -------
    ndarray of bool, shape (n,)
    """
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    inside = np.isfinite(pts).all(axis=1)
    safe = np.where(inside[:, None], pts, 0.0)
    for cam, eo in frames:
        c, r = world_to_pixel(safe, cam, eo)  # NaN behind the camera: in no frame
        m = margin_px
        inside &= (c >= m) & (c <= cam.width - 1 - m) & (r >= m) & (r <= cam.height - 1 - m)
    return inside


def stereo_overlap(frames: Sequence[Frame], surface: PathLike, area: Optional[Any] = None,
                   cells_per_band: int = 1 << 20) -> Any:
    """The cells of a surface raster whose surface point lies inside every frame, as polygons.

    Parameters
    ----------
    frames : sequence of (Camera, ExteriorOrientation)
        The model's frames.
    surface : path
        Heights (e.g. a true DSM); nodata cells are outside.
    area : shapely geometry, optional
        Clip the result to it (e.g. the model's measuring area), in the surface's CRS.
    cells_per_band : int
        About this many cells are read and projected at a time (bands of whole rows, at
        least one): the memory is bounded for any raster width.

    Returns
    -------
    shapely geometry
        The union of the cells (their outlines on the raster's grid); empty if none.
    """
    parts = []
    with rasterio.open(surface) as src:
        t = src.transform
        rows_per_band = max(1, cells_per_band // src.width)
        for r0 in range(0, src.height, rows_per_band):
            win = Window(0, r0, src.width, min(rows_per_band, src.height - r0))
            z = src.read(1, window=win, masked=True).astype(np.float64).filled(np.nan)
            rows, cols = np.mgrid[0:z.shape[0], 0:z.shape[1]]
            xs, ys = xy(src.window_transform(win), rows.ravel(), cols.ravel())
            pts = np.column_stack([np.asarray(xs), np.asarray(ys), z.ravel()])
            mask = inside_frames(frames, pts).reshape(z.shape)
            if mask.any():
                # outlines in whole (col, row) numbers, so that the bands' edges meet exactly
                # (world coordinates of two bands differ in the last bits and leave slivers)
                parts += [shape(g) for g, v in shapes(mask.astype(np.uint8), mask=mask,
                                                      transform=Affine.translation(0, r0))
                          if v == 1]
    geom = affine_transform(unary_union(parts), [t.a, t.b, t.d, t.e, t.c, t.f])
    return geom.intersection(area) if area is not None else geom
