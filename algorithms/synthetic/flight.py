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

**Height precision and the "aerial" size.** In the normal case the depth is
:math:`D = f B / p` (f in px, parallax p in px), so a parallax error :math:`\sigma_{px}` gives

.. math::

   \sigma_Z = \frac{D^2}{f B}\,\sigma_{px}
   \quad\Longrightarrow\quad
   \frac{\sigma_Z}{H} = \frac{\sigma_{px}}{B_{px}}, \qquad
   B_{px} = \frac{B}{\mathrm{GSD}} = (1-p)\,W .

The small sizes have :math:`B_{px} = 0.4\,W` ≈ 90 px (tiny) … 960 px (large); a target of
0.1 ‰ H would need :math:`\sigma_{px}` ≈ 0.01–0.1 px. A real film camera (23 cm format scanned
at 20 µm: W = 11 500 px) has :math:`B_{px}` = 4600 px at 60 % overlap, where 0.1 ‰ H means
:math:`\sigma_{px}` ≈ 0.46 px — what matching actually delivers. The size ``aerial`` therefore
flies a *real* wide-angle geometry — format 11 500 × 11 500 px, pixel 20 µm, c = 153 mm
(f = 7650 px), B/H = 0.4 · 230/153 = 0.60, GSD 0.15 m → H = 1147.5 m, B = 690 m — with three
images in one strip, but renders only a **window** (crop, default 1024 × 1024 px) of each
frame. All three windows are centred on the image of the same ground point, the planned nadir of
the middle image at the mean terrain height (the triple-overlap area), so every point of the
patch is seen by three images, the in-strip models 1–2 and 2–3 have B_px ≈ 4600 px, and the
render cost is that of three small images instead of three 132-Mpx frames.

A window is an ordinary :class:`~..geometry.camera.Camera` whose width/height are the window
size and whose principal point is shifted by the window position. With the window's top-left
pixel at (c₀, r₀) of the full frame (W_f × H_f px, pitch δ):

.. math::

   x_p = \left(\tfrac{W_f - 1}{2} - c_0 - \tfrac{w - 1}{2}\right)\delta,\qquad
   y_p = \left(r_0 + \tfrac{h - 1}{2} - \tfrac{H_f - 1}{2}\right)\delta,

so that window pixel (c, r) is exactly frame pixel (c₀ + c, r₀ + r); distortion (none here) is
centred on the principal point, which lies outside the windows of the outer images. Each image
gets its own camera (``synthetic_aerial_<image>``).

**The "drone" size** (:func:`plan_drone`) leaves the normal case: a 1/2.3" 4:3 camera scaled to
768 × 576 px (c = 0.9 w, f = 691 px) flies H = GSD·f ≈ 69 m above the mean terrain in two strips
of three frames, each aimed at a ground point of a common patch (:data:`DRONE_LAYOUT`), so the
frames are tilted 0–35° in varying directions (forward, backward, sideways). B/H is no longer
(1 − p)·0.9: each model's B/H and convergence (angle between the optical axes, 19–55°) come
from the stereo-model detection on the terrain; ``base`` is the mean in-strip distance.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Dict, List, Optional, Tuple

import numpy as np

from ..errors import GeometryError, InputError
from ..geometry.camera import Camera
from ..geometry.orientation import ExteriorOrientation
from ..geometry.projection import border_at_height, world_to_pixel

#: along-track sensor format divided by the principal distance
FORMAT_OVER_FOCAL = 0.9
FOCAL_LENGTH_MM = 100.0


@dataclass(frozen=True)
class SizeSpec:
    """One size of synthetic block.

    Attributes
    ----------
    width, height : int
        Image size in pixels (width along track, height across track); for a windowed size
        (``frame > 0``) the size of the rendered window.
    gsd : float
        Nominal ground sample distance (m) on gentle terrain (steep terrain uses 2.5 ×).
    strips, images_per_strip : int
        Block layout.
    supersample : int
        Sub-samples per pixel and axis (area average of ss × ss rays).
    tile_rays : int
        Rays traced at once (bounds the render memory: ≈ 200 bytes per ray).
    frame : int
        0: the image is the whole frame of a normal-angle camera (format 0.9 c along track).
        > 0: a square film-like frame of ``frame`` × ``frame`` px with ``pixel_mm`` and
        ``focal_mm``, of which only a ``width`` × ``height`` window over the common ground
        patch is rendered (module notes).
    pixel_mm, focal_mm : float
        Pixel pitch and principal distance (mm) of the windowed frame camera, or of the drone
        camera (``layout="drone"``).
    layout : {"strips", "drone"}
        ``strips``: near-vertical images in strips (normal case); ``drone``: two strips of
        frames tilted 0–35° towards a common patch (:func:`plan_drone`).
    """

    width: int
    height: int
    gsd: float
    strips: int
    images_per_strip: int
    supersample: int
    tile_rays: int = 1 << 20
    frame: int = 0
    pixel_mm: float = 0.0
    focal_mm: float = FOCAL_LENGTH_MM
    layout: str = "strips"

    @property
    def drone(self) -> bool:
        """A low drone flight with tilted, convergent frames (:func:`plan_drone`)."""
        return self.layout == "drone"

    @property
    def windowed(self) -> bool:
        return self.frame > 0

    def with_window(self, size: int) -> SizeSpec:
        """The same windowed size with a ``size`` × ``size`` px window (e.g. smaller for tests)."""
        if not self.windowed:
            raise InputError("Only a windowed block size (aerial) accepts a window size.")
        if not 64 <= int(size) <= self.frame:
            raise InputError(f"The window size must be 64…{self.frame} px, got {size}.")
        return replace(self, width=int(size), height=int(size))


SIZES: Dict[str, SizeSpec] = {
    "tiny": SizeSpec(224, 288, 0.30, 2, 3, 2, 1 << 19),
    "small": SizeSpec(704, 1000, 0.20, 2, 3, 2, 1 << 20),
    "medium": SizeSpec(1408, 2000, 0.15, 2, 4, 2, 1 << 20),
    "large": SizeSpec(2400, 3400, 0.12, 2, 4, 2, 1 << 20),
    # 23 cm film scanned at 20 µm, wide angle c = 153 mm: B/H = 0.6, B_px = 4600 at 60 %
    "aerial": SizeSpec(1024, 1024, 0.15, 1, 3, 2, 1 << 20, frame=11500, pixel_mm=0.020,
                       focal_mm=153.0),
    # 1/2.3" 4:3 drone camera scaled to 768 × 576 px (pitch 8.0 µm), c = 0.9 w = 5.53 mm;
    # GSD 10 cm at nadir → H ≈ 69 m; frames tilted 0–35° towards a common patch
    # one ray per pixel: the oblique frames see far (a large truth grid), and the block must
    # render in ≈ 15 s for the tests
    "drone": SizeSpec(768, 576, 0.10, 2, 3, 1, 1 << 19, pixel_mm=0.0080,
                      focal_mm=0.9 * 768 * 0.0080, layout="drone"),
}

#: GSD factor of the steep terrain type (flying higher keeps the relief < ½ flying height)
STEEP_GSD_FACTOR = 2.5


@dataclass
class PlannedImage:
    """One image of the flight plan.

    ``camera`` is the image's own (window) camera of a windowed size, else None (the plan's
    camera); ``window`` the (col, row) of the window's top-left pixel in the full frame.
    """

    name: str
    strip: int
    index: int
    eo: ExteriorOrientation
    camera: Optional[Camera] = None
    window: Optional[Tuple[int, int]] = None


@dataclass
class FlightPlan:
    """Camera and images of a synthetic block.

    ``camera`` is the common camera; for a windowed size the full frame (not rendered), each
    image then carries its window camera (:meth:`camera_of`).
    """

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

    @property
    def base_px(self) -> float:
        """Planned base in pixels, B / GSD (σ_Z/H = σ_px / B_px)."""
        return self.base / self.gsd

    def camera_of(self, image: PlannedImage) -> Camera:
        """The camera an image is rendered with."""
        return self.camera if image.camera is None else image.camera

    @property
    def cameras(self) -> Dict[str, Camera]:
        """Cameras of the rendered images by camera name (project order)."""
        out: Dict[str, Camera] = {}
        for im in self.images:
            cam = self.camera_of(im)
            out.setdefault(cam.name, cam)
        return out


def make_camera(spec: SizeSpec, name: str) -> Camera:
    """The block's camera, distortion-free.

    Normal sizes: along-track format 0.9 c (c = 100 mm). Windowed sizes: the full square frame
    (``spec.frame`` px of ``spec.pixel_mm``, c = ``spec.focal_mm``).
    """
    if spec.drone:
        return Camera(name=name, width=spec.width, height=spec.height, focal_length=spec.focal_mm,
                      pixel_size=(spec.pixel_mm, spec.pixel_mm))
    if spec.windowed:
        return Camera(name=name, width=spec.frame, height=spec.frame, focal_length=spec.focal_mm,
                      pixel_size=(spec.pixel_mm, spec.pixel_mm))
    pixel = FORMAT_OVER_FOCAL * FOCAL_LENGTH_MM / spec.width
    return Camera(name=name, width=spec.width, height=spec.height, focal_length=FOCAL_LENGTH_MM,
                  pixel_size=(pixel, pixel))


def window_camera(frame: Camera, name: str, col0: int, row0: int, width: int, height: int
                  ) -> Camera:
    """A ``width`` × ``height`` window of ``frame`` whose top-left pixel is frame pixel
    (``col0``, ``row0``): same c, pitch and distortion, principal point shifted (module notes).
    """
    if frame.fiducial_affine is not None:
        raise InputError("A window of a fiducial-calibrated camera is not supported.")
    px, py = frame.pixel_size
    xp0, yp0 = frame.principal_point
    xp = xp0 + ((frame.width - 1) / 2.0 - col0 - (width - 1) / 2.0) * px
    yp = yp0 + (row0 + (height - 1) / 2.0 - (frame.height - 1) / 2.0) * py
    return Camera(name=name, width=int(width), height=int(height),
                  focal_length=frame.focal_length, pixel_size=frame.pixel_size,
                  principal_point=(round(xp, 9), round(yp, 9)),  # no float dust in the toml
                  k1=frame.k1, k2=frame.k2, k3=frame.k3, p1=frame.p1, p2=frame.p2)


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

    For a windowed size every image gets a window camera centred on the image of the ground
    point (origin, terrain_height) — the planned nadir of the middle image.
    """
    camera = make_camera(spec, f"synthetic_{size_name}")
    if spec.drone:
        return plan_drone(camera, gsd, origin, terrain_height, rng)
    H = gsd * camera.focal_length / camera.pixel_size[0]
    base = (1.0 - forward_overlap) * camera.width * gsd
    spacing = (1.0 - side_overlap) * camera.height * gsd
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
    if spec.windowed:
        centre = np.array([origin[0], origin[1], terrain_height])
        for im in images:
            im.window, im.camera = _window(camera, im, centre, spec)
    return FlightPlan(camera, images, gsd, H, base, spacing, terrain_height)


#: Drone layout in units of the flying height H, relative to the block centre: per image the
#: projection centre (x, y) and the ground point (x, y) the optical axis aims at. Strip 1 flies
#: east (images 0101–0103), strip 2 west (0201–0203), so the camera x axis (= flight direction)
#: flips between the strips. 0101/0103 look forward/backward at the same patch (convergence
#: ≈ 50°), 0201–0203 look sideways (south) at 25–35° — convergent with each other and with the
#: first strip; 0102 is near-nadir.
DRONE_LAYOUT: Tuple[Tuple[Tuple[float, float], Tuple[float, float]], ...] = (
    ((-0.45, -0.25), (0.00, -0.20)),
    ((0.00, -0.25), (0.05, -0.22)),
    ((0.45, -0.25), (0.00, -0.15)),
    ((0.40, 0.30), (0.10, -0.05)),
    ((0.00, 0.30), (0.00, -0.15)),
    ((-0.45, 0.32), (-0.05, -0.25)),
)


def aim_rotation(position: np.ndarray, target: np.ndarray, heading: np.ndarray) -> np.ndarray:
    r"""Camera→world rotation (PATB) of a camera at ``position`` looking at ``target`` with its
    x axis as close as possible to the horizontal ``heading`` (the flight direction).

    The camera looks along −z, so :math:`z = (C - T)/\lVert C - T\rVert`; x is the heading
    orthogonalised to z and y = z × x (a nadir camera flying east gets R = I).
    """
    z = np.asarray(position, float) - np.asarray(target, float)
    z /= np.linalg.norm(z)
    x = np.asarray(heading, float) - (np.asarray(heading, float) @ z) * z
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(z, x), z])


def plan_drone(camera: Camera, gsd: float, origin: Tuple[float, float], terrain_height: float,
               rng: np.random.Generator) -> FlightPlan:
    """A drone flight of six frames tilted 0–35° in varying directions (:data:`DRONE_LAYOUT`).

    H = GSD · c/δ above the mean terrain; each aim point gets ±2 % H of jitter and each centre
    ±1 % H (and ±0.5 % H in height), so the tilts vary by about ±1°. The plan's ``base`` is
    the mean distance of consecutive in-strip images, ``strip_spacing`` that of the strips.
    """
    H = gsd * camera.focal_length / camera.pixel_size[0]
    images: List[PlannedImage] = []
    ox, oy = origin
    for k, ((px, py), (tx, ty)) in enumerate(DRONE_LAYOUT):
        s, i = divmod(k, 3)
        pos = np.array([ox + px * H, oy + py * H, terrain_height + H])
        pos += rng.normal(0.0, [0.01 * H, 0.01 * H, 0.005 * H])
        target = np.array([ox + tx * H, oy + ty * H, terrain_height])
        target[:2] += rng.normal(0.0, 0.02 * H, 2)
        heading = np.array([1.0, 0.0, 0.0]) if s == 0 else np.array([-1.0, 0.0, 0.0])
        rot = aim_rotation(pos, target, heading)
        images.append(PlannedImage(f"{s + 1:02d}{i + 1:02d}", s, i,
                                   ExteriorOrientation(pos, rot)))
    pos = np.array([im.eo.position for im in images])
    base = float(np.mean([np.linalg.norm(pos[k + 1] - pos[k]) for k in (0, 1, 3, 4)]))
    spacing = float(abs(pos[3:, 1].mean() - pos[:3, 1].mean()))
    return FlightPlan(camera, images, gsd, H, base, spacing, terrain_height)


def tilt_degrees(eo: ExteriorOrientation) -> float:
    """Angle (°) between the optical axis and the nadir."""
    return float(np.degrees(np.arccos(np.clip(eo.rotation[2, 2], -1.0, 1.0))))


def _window(frame: Camera, image: PlannedImage, centre: np.ndarray, spec: SizeSpec
            ) -> Tuple[Tuple[int, int], Camera]:
    """Window of ``spec.width`` × ``spec.height`` px of ``frame`` centred on ``centre``."""
    col, row = world_to_pixel(centre[None, :], frame, image.eo)
    # integer offsets keep the window pixels on the frame's pixel grid
    col0 = int(np.rint(float(col[0]) - (spec.width - 1) / 2.0))
    row0 = int(np.rint(float(row[0]) - (spec.height - 1) / 2.0))
    if not (0 <= col0 <= frame.width - spec.width and 0 <= row0 <= frame.height - spec.height):
        raise GeometryError(f"The window of image {image.name} at ({col0}, {row0}) leaves the "
                            f"{frame.width} × {frame.height} px frame; use a smaller window.")
    cam = window_camera(frame, f"{frame.name}_{image.name}", col0, row0, spec.width, spec.height)
    return (col0, row0), cam


def footprint_points(camera: Camera, eo: ExteriorOrientation, height: float,
                     per_edge: int = 8) -> np.ndarray:
    """Ground points (N, 2) of the image outline intersected with the plane Z = ``height``."""
    return border_at_height(camera, eo, height, per_edge)[:, :2]
