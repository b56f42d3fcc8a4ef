r"""Flight plan of a synthetic block: sizes, camera, strips, exterior orientations.

Strips run along the world X axis (east–west), alternately eastwards (κ = 0°) and westwards
(κ = 180°), so the base of two consecutive images of a strip lies along the camera x axis and
the long side of the image (rows) lies across the track. With an along-track format of
:math:`W` pixels, ground sample distance GSD, forward overlap :math:`p` and side overlap
:math:`q`:

.. math::

   B = (1 - p)\,W\,\mathrm{GSD}, \qquad S = (1 - q)\,H_{px}\,\mathrm{GSD}, \qquad
   H = \mathrm{GSD}\,c / \delta,

with :math:`H_{px}` the across-track format (pixels), :math:`c` the principal distance and
:math:`\delta` the pixel pitch. The camera has the along-track format equal to
:data:`FORMAT_OVER_FOCAL` × c, so :math:`B/H = (1-p)\cdot 0.9 = 0.36` at 60 % overlap — a
normal-angle frame camera. Small random tilts (ω, φ ≈ N(0, 0.8°), clipped to ±2°), κ jitter and
position jitter make the orientation realistic.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Dict, List, Tuple

import numpy as np

from ..geometry.camera import Camera
from ..geometry.orientation import ExteriorOrientation

#: along-track sensor format divided by the principal distance
FORMAT_OVER_FOCAL = 0.9
FOCAL_LENGTH_MM = 100.0


@dataclass(frozen=True)
class SizeSpec:
    """One size of synthetic block.

    Attributes
    ----------
    width, height : int
        Image size in pixels (width along track, height across track).
    gsd : float
        Nominal ground sample distance (m) on gentle terrain (steep terrain uses 2.5 ×).
    strips, images_per_strip : int
        Block layout.
    supersample : int
        Sub-samples per pixel and axis (area average of ss × ss rays).
    tile_rays : int
        Rays traced at once (bounds the render memory: ≈ 200 bytes per ray).
    """

    width: int
    height: int
    gsd: float
    strips: int
    images_per_strip: int
    supersample: int
    tile_rays: int = 1 << 20


SIZES: Dict[str, SizeSpec] = {
    "tiny": SizeSpec(224, 288, 0.30, 2, 3, 2, 1 << 19),
    "small": SizeSpec(704, 1000, 0.20, 2, 3, 2, 1 << 20),
    "medium": SizeSpec(1408, 2000, 0.15, 2, 4, 2, 1 << 20),
    "large": SizeSpec(2400, 3400, 0.12, 2, 4, 2, 1 << 20),
}

#: GSD factor of the steep terrain type (flying higher keeps the relief < ½ flying height)
STEEP_GSD_FACTOR = 2.5


@dataclass
class PlannedImage:
    """One image of the flight plan."""

    name: str
    strip: int
    index: int
    eo: ExteriorOrientation


@dataclass
class FlightPlan:
    """Camera and images of a synthetic block."""

    camera: Camera
    images: List[PlannedImage]
    gsd: float
    flying_height: float  # above the mean terrain (m)
    base: float
    strip_spacing: float
    terrain_height: float  # mean terrain height (m)

    @property
    def projection_height(self) -> float:
        return self.terrain_height + self.flying_height


def make_camera(spec: SizeSpec, name: str) -> Camera:
    """A distortion-free frame camera with along-track format 0.9 c (c = 100 mm)."""
    pixel = FORMAT_OVER_FOCAL * FOCAL_LENGTH_MM / spec.width
    return Camera(name=name, width=spec.width, height=spec.height, focal_length=FOCAL_LENGTH_MM,
                  pixel_size=(pixel, pixel))


def plan_flight(spec: SizeSpec, size_name: str, gsd: float, origin: Tuple[float, float],
                terrain_height: float, rng: np.random.Generator,
                forward_overlap: float = 0.6, side_overlap: float = 0.3) -> FlightPlan:
    """Strips along +X / −X with the given overlaps, centred on ``origin``.

    Parameters
    ----------
    spec : SizeSpec
    size_name : str
        Used in the camera name.
    gsd : float
        Ground sample distance at the mean terrain height (m).
    origin : (float, float)
        Block centre (X, Y) in the project CRS.
    terrain_height : float
        Mean terrain height (m); the projection centres fly at terrain_height + H.
    rng : numpy.random.Generator
        Source of the orientation jitter.
    """
    camera = make_camera(spec, f"synthetic_{size_name}")
    H = gsd * camera.focal_length / camera.pixel_size[0]
    base = (1.0 - forward_overlap) * spec.width * gsd
    spacing = (1.0 - side_overlap) * spec.height * gsd
    images: List[PlannedImage] = []
    n = spec.images_per_strip
    for s in range(spec.strips):
        eastward = s % 2 == 0
        y = origin[1] + (s - (spec.strips - 1) / 2.0) * spacing
        for i in range(n):
            k = i if eastward else n - 1 - i  # image i is the i-th exposure of the strip
            x = origin[0] + (k - (n - 1) / 2.0) * base
            jitter = rng.normal(0.0, [0.01 * base, 0.01 * spacing, 0.005 * H])
            omega, phi = np.clip(rng.normal(0.0, 0.8, 2), -2.0, 2.0)
            kappa = (0.0 if eastward else 180.0) + float(np.clip(rng.normal(0.0, 0.7), -2, 2))
            pos = np.array([x, y, terrain_height + H]) + jitter
            eo = ExteriorOrientation.from_opk(pos, float(omega), float(phi), kappa, "degrees")
            images.append(PlannedImage(f"{s + 1:02d}{i + 1:02d}", s, i, eo))
    return FlightPlan(camera, images, gsd, H, base, spacing, terrain_height)


def footprint_points(camera: Camera, eo: ExteriorOrientation, height: float,
                     per_edge: int = 8) -> np.ndarray:
    """Ground points (N, 2) of the image outline intersected with the plane Z = ``height``."""
    from ..geometry.projection import ray_at_height

    w, h = camera.width - 0.5, camera.height - 0.5
    s = np.linspace(0.0, 1.0, per_edge, endpoint=False)
    cols = np.concatenate([-0.5 + s * (w + 0.5), np.full_like(s, w), w - s * (w + 0.5),
                           np.full_like(s, -0.5)])
    rows = np.concatenate([np.full_like(s, -0.5), -0.5 + s * (h + 0.5), np.full_like(s, h),
                           h - s * (h + 0.5)])
    return ray_at_height(cols, rows, height, camera, eo)[:, :2]
