r"""Stereo geometry of single images: footprints on the terrain and axial directions.

Footprint
    The image outline (corners plus points along the edges, so that distortion bends it;
    :func:`~.projection.border_at_height`) is intersected with a horizontal plane
    :math:`Z = h`. With a DEM, :math:`h` is iterated: start at the DEM height below the
    projection centre, intersect a 9 × 9 grid of image rays with :math:`Z = h`, set :math:`h` to
    the mean DEM height at those ground points, repeat until it changes by less than 1 cm (a few
    iterations; the mean height under the footprint).

Directions
    Strips of a block are found from axial directions (mod 180°) of image bases:
    :func:`dominant_direction` is their mode.

The stereo models of a project (base, B/H, overlap, detection and order) are built from these
in :mod:`..project.stereo_models`.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any, Dict, Optional, Sequence, Tuple, Union

import numpy as np
import rasterio
from numpy.typing import NDArray
from shapely.geometry import Polygon

from ..crs_check import check_surface_crs
from ..errors import GeometryError, InputError
from ..input_errors import check_encodable, reading
from ..raster.sample import DemSampler
from .camera import Camera
from .orientation import ExteriorOrientation
from .projection import border_at_height, ray_at_height

DemLike = Union[None, str, Path, Any]  # path or raster.sample.DemSampler
#: image name → (footprint polygon, terrain height under it in m)
Footprints = Dict[str, Tuple[Polygon, float]]


# -- DEM -------------------------------------------------------------------------------------------
def load_dem(dem: DemLike, bounds: Optional[Sequence[float]] = None, crs: Any = None) -> Any:
    """A :class:`~..raster.sample.DemSampler` from a path (window ``bounds``), or ``dem`` as is.

    With ``crs`` (the project CRS) a DEM file in another CRS is refused, naming both
    (:func:`~..crs_check.check_surface_crs`): its heights would be sampled at wrong places.
    """
    if dem is None:
        return None
    if isinstance(dem, (str, Path)):
        if crs:
            check_encodable(dem, "DEM")
            if Path(dem).is_file():
                with reading(dem, "raster"), rasterio.open(dem) as src:
                    file_crs = src.crs
                check_surface_crs(dem, file_crs, crs, "DEM")

        return DemSampler.from_file(dem, bounds=None if bounds is None else tuple(bounds))
    return dem


def _dem_height(dem: Any, x: NDArray, y: NDArray) -> NDArray:
    return np.asarray(dem.height(x, y), dtype=float)


# -- footprints ------------------------------------------------------------------------------------
def _polygon(points: NDArray) -> Polygon:
    ok = np.all(np.isfinite(points[:, :2]), axis=1)
    if ok.sum() < 3:
        raise GeometryError(
            "The image footprint cannot be computed: its rays do not reach the terrain "
            "(camera below the terrain or looking above the horizon?). Check the exterior "
            "orientation and the terrain height."
        )
    poly = Polygon(points[ok, :2])
    if not poly.is_valid:
        poly = poly.buffer(0)
    return poly


def mean_dem_height(camera: Camera, eo: ExteriorOrientation, dem: DemLike,
                    max_iter: int = 10) -> float:
    """The mean DEM height under the footprint, iterated (module notes).

    Raises
    ------
    GeometryError
        When the image rays meet no DEM height.
    """
    sampler = load_dem(dem)
    h = float(_dem_height(sampler, eo.position[0:1], eo.position[1:2])[0])
    if not math.isfinite(h):
        h = float(np.nanmean(sampler.array))
    g = np.linspace(0.0, 1.0, 9)
    cols = -0.5 + g * camera.width
    rows = -0.5 + g * camera.height
    cc, rr = np.meshgrid(cols, rows)
    for _ in range(max_iter):
        pts = ray_at_height(cc.ravel(), rr.ravel(), h, camera, eo)
        z = _dem_height(sampler, pts[:, 0], pts[:, 1])
        if not np.isfinite(z).any():
            raise GeometryError(
                "The image footprint lies outside the DEM (or over its nodata); use a DEM "
                "that covers the images."
            )
        h_new = float(np.nanmean(z))
        done = abs(h_new - h) < 0.01
        h = h_new
        if done:
            break
    return h


def footprint_and_height(camera: Camera, eo: ExteriorOrientation,
                         height: Optional[float] = None, dem: DemLike = None,
                         per_edge: int = 8, max_iter: int = 10) -> Tuple[Polygon, float]:
    """Footprint polygon and the terrain height it was computed at (see module notes).

    Parameters
    ----------
    height : float, optional
        Terrain height (m) of the horizontal plane; used when no DEM is given.
    dem : path or DemSampler, optional
        Terrain model; the footprint plane is iterated to the mean DEM height under it.
    per_edge : int
        Outline points per image edge.
    """
    if dem is None and height is None:
        raise InputError("A footprint needs a terrain height or a DEM.")
    if dem is not None:
        h = mean_dem_height(camera, eo, dem, max_iter)
    else:
        h = float(height)  # type: ignore[arg-type]
    return _polygon(border_at_height(camera, eo, h, per_edge)), h


def image_footprint(camera: Camera, eo: ExteriorOrientation, height: Optional[float] = None,
                    dem: DemLike = None, per_edge: int = 8) -> Polygon:
    """The image outline projected onto the terrain (plane at ``height`` or DEM mean height).

    The one footprint polygon of the package (``per_edge`` outline points per image edge);
    the ortho's rectangular extent on a DEM is :func:`~..ortho.rectify.dem_footprint_box`.
    """
    return footprint_and_height(camera, eo, height=height, dem=dem, per_edge=per_edge)[0]


def mean_terrain_height(footprints: Footprints) -> float:
    """Mean of the terrain heights under the footprints (m)."""
    return float(np.mean([h for _, h in footprints.values()]))


# -- directions ------------------------------------------------------------------------------------
def axial_diff(a: Any, b: Any) -> NDArray:
    """Smallest difference (rad) between axial directions (mod π)."""
    d = np.mod(np.asarray(a) - np.asarray(b), np.pi)
    return np.minimum(d, np.pi - d)


def dominant_direction(angles: NDArray, tolerance: float) -> float:
    """Mode of axial directions (rad, mod π): the direction with most others within
    ``tolerance`` (rad), refined by the doubled-angle mean of those inliers."""
    a = np.mod(np.asarray(angles, dtype=float), np.pi)
    counts = (axial_diff(a[:, None], a[None, :]) <= tolerance).sum(axis=1)
    best = a[int(np.argmax(counts))]
    inl = a[axial_diff(a, best) <= tolerance]
    return float(np.mod(0.5 * np.arctan2(np.sin(2 * inl).mean(), np.cos(2 * inl).mean()), np.pi))


__all__ = [
    "DemLike",
    "Footprints",
    "axial_diff",
    "dominant_direction",
    "footprint_and_height",
    "image_footprint",
    "load_dem",
    "mean_dem_height",
    "mean_terrain_height",
]
