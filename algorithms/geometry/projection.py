r"""Collinearity: world → pixel and pixel → ray.

A world point :math:`X` is seen by an image with centre :math:`C` and camera→world rotation
:math:`R` at camera coordinates :math:`p = R^T (X - C)`, image coordinates
:math:`x = -c\,p_x/p_z,\; y = -c\,p_y/p_z`, then distortion and the pixel grid
(:mod:`.camera`). The inverse gives a ray :math:`X(\lambda) = C + \lambda\,R\,(x, y, -c)^T`.
Every function is vectorised over many points.
"""

from __future__ import annotations

from typing import Tuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .camera import Camera
from .orientation import ExteriorOrientation

Array = NDArray[np.float64]


def world_to_camera(points: ArrayLike, eo: ExteriorOrientation) -> Array:
    """World points (..., 3) → camera-frame coordinates (..., 3): p = Rᵀ (X − C)."""
    X = np.asarray(points, dtype=float)
    return (X - eo.position) @ eo.rotation


def world_to_pixel(points: ArrayLike, camera: Camera, eo: ExteriorOrientation
                   ) -> Tuple[Array, Array]:
    """Project world points (..., 3) to pixel (col, row); NaN for points behind the camera."""
    return camera.camera_to_pixel(world_to_camera(points, eo))


def pixel_to_ray(col: ArrayLike, row: ArrayLike, camera: Camera, eo: ExteriorOrientation
                 ) -> Tuple[Array, Array]:
    """Rays through pixels: origin (3,) and unit directions (..., 3) in world coordinates."""
    d = camera.pixel_to_camera(col, row) @ eo.rotation.T
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    return eo.position.copy(), d


def ray_at_height(col: ArrayLike, row: ArrayLike, height: ArrayLike, camera: Camera,
                  eo: ExteriorOrientation) -> Array:
    """Intersect pixel rays with horizontal planes Z = ``height``; returns (..., 3) points."""
    origin, d = pixel_to_ray(col, row, camera, eo)
    with np.errstate(divide="ignore", invalid="ignore"):
        lam = (np.asarray(height, dtype=float) - origin[2]) / d[..., 2]
    lam = np.where(lam > 0, lam, np.nan)
    return origin + lam[..., None] * d
