r"""Collinearity: world → pixel and pixel → ray.

A world point :math:`X` is seen by an image with centre :math:`C` and camera→world rotation
:math:`R` at camera coordinates :math:`p = R^T (X - C)`, image coordinates
:math:`x = -c\,p_x/p_z,\; y = -c\,p_y/p_z`, then distortion and the pixel grid
(:mod:`.camera`). The inverse gives a ray :math:`X(\lambda) = C + \lambda\,R\,(x, y, -c)^T`.
Every function is vectorised over many points.

Image border
    :func:`border_pixels` samples the image outline (the outer pixel edges at −0.5 and
    width − 0.5, clockwise from the top-left corner); :func:`border_rays` gives the rays
    through those pixels and :func:`border_at_height` their points on a plane Z = h. Lens
    distortion bends the edges, so footprints and extents use points along the edges, not
    only the corners. Every image footprint and extent of the package starts here.
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


def rays_at_height(origin: Array, d: Array, height: ArrayLike) -> Array:
    """Points (..., 3) of rays ``origin + λ d`` on horizontal planes Z = ``height``.

    NaN where a ray does not reach its plane forwards (λ ≤ 0, or parallel to it).
    """
    with np.errstate(divide="ignore", invalid="ignore"):
        lam = (np.asarray(height, dtype=float) - origin[2]) / d[..., 2]
    lam = np.where(lam > 0, lam, np.nan)
    return origin + lam[..., None] * d


def ray_at_height(col: ArrayLike, row: ArrayLike, height: ArrayLike, camera: Camera,
                  eo: ExteriorOrientation) -> Array:
    """Intersect pixel rays with horizontal planes Z = ``height``; returns (..., 3) points."""
    origin, d = pixel_to_ray(col, row, camera, eo)
    return rays_at_height(origin, d, height)


def border_pixels(camera: Camera, per_edge: int = 16) -> Array:
    """Pixel (col, row) of the image outline, shape (4·per_edge, 2), clockwise from top left.

    Each edge starts at its corner (:meth:`Camera.corners`) and holds ``per_edge`` evenly
    spaced points, the next corner excluded: corner + t·(next corner − corner) for
    t = k / per_edge, k = 0 … per_edge − 1.
    """
    c = camera.corners()
    t = np.linspace(0.0, 1.0, per_edge, endpoint=False)[:, None]
    return np.concatenate([c[i] + t * (c[(i + 1) % 4] - c[i]) for i in range(4)])


def border_rays(camera: Camera, eo: ExteriorOrientation, per_edge: int = 16,
                unit: bool = True) -> Tuple[Array, Array, Array]:
    r"""Rays through the image outline (:func:`border_pixels`).

    Parameters
    ----------
    per_edge : int
        Points per image edge.
    unit : bool
        True: unit world directions, exactly as :func:`pixel_to_ray`. False: the unscaled
        world directions :math:`R\,(x, y, -c)^T` (length about the focal length in mm),
        summed term by term (no BLAS, so that the ortho's extents are the same on every
        machine); their z component then scales plane intersections directly.

    Returns
    -------
    pixels : ndarray, shape (4·per_edge, 2)
        Pixel (col, row) of the border points.
    origin : ndarray, shape (3,)
        The projection centre (a copy).
    directions : ndarray, shape (4·per_edge, 3)
        World ray directions.
    """
    px = border_pixels(camera, per_edge)
    if unit:
        origin, d = pixel_to_ray(px[:, 0], px[:, 1], camera, eo)
        return px, origin, d
    cols, rows = px[:, 0], px[:, 1]
    d = np.einsum("ij,nj->ni", eo.rotation, camera.pixel_to_camera(cols, rows))
    return px, eo.position.copy(), d


def border_at_height(camera: Camera, eo: ExteriorOrientation, height: float,
                     per_edge: int = 16) -> Array:
    """Points (4·per_edge, 3) of the image outline on the plane Z = ``height`` (NaN where a
    border ray does not reach it): the footprint outline on flat terrain."""
    _, origin, d = border_rays(camera, eo, per_edge)
    return rays_at_height(origin, d, height)
