r"""Interior orientation of a frame camera: pinhole, Brown distortion, scanned-film fiducials.

Coordinate frames (DESIGN.md §3):

* **pixel** ``(col, row)``: pixel centres at integer values, row down (numpy indexing);
* **image** ``(x, y)`` in mm: origin at the principal point, x right, y up — the classical
  photogrammetric image coordinates, *with* lens distortion (what the sensor recorded);
* **camera**: x right, y up, z backwards; the ray of an undistorted image point is
  ``(x, y, -f)``.

Distortion follows Brown's model in the normalised OpenCV frame used by OpenCV, ODM and
orthority (x right, **y down**, units of the focal length), so calibrations from those tools
carry over unchanged:

.. math::

   x_d = x\,(1 + k_1 r^2 + k_2 r^4 + k_3 r^6) + 2 p_1 x y + p_2 (r^2 + 2 x^2) \\
   y_d = y\,(1 + k_1 r^2 + k_2 r^4 + k_3 r^6) + p_1 (r^2 + 2 y^2) + 2 p_2 x y

The inverse has no closed form; :meth:`Camera.undistort` solves it by Newton iterations
(to < 1e-12 of the focal length).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Dict, Optional, Tuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InputError

Array = NDArray[np.float64]


@dataclass(frozen=True)
class Camera:
    """A frame camera.

    Parameters
    ----------
    name : str
        Identifier used by the images of a project.
    width, height : int
        Image size in pixels.
    focal_length : float
        Principal distance c in mm.
    pixel_size : (float, float)
        Pixel pitch (x, y) in mm.
    principal_point : (float, float)
        Offset (xp, yp) of the principal point from the image centre in mm, x right, y up.
    k1, k2, k3, p1, p2 : float
        Brown distortion in the normalised OpenCV frame (see module notes).
    fiducial_affine : (2, 3) array_like, optional
        Scanned film: affine pixel → image mm (relative to the fiducial centre) from
        :func:`fit_fiducials`. When given it replaces the pixel size/centre relation.
    """

    name: str
    width: int
    height: int
    focal_length: float
    pixel_size: Tuple[float, float]
    principal_point: Tuple[float, float] = (0.0, 0.0)
    k1: float = 0.0
    k2: float = 0.0
    k3: float = 0.0
    p1: float = 0.0
    p2: float = 0.0
    fiducial_affine: Optional[Tuple[Tuple[float, float, float], Tuple[float, float, float]]] = None
    extra: Dict[str, float] = field(default_factory=dict, compare=False)

    def __post_init__(self) -> None:
        if self.width <= 0 or self.height <= 0:
            raise InputError(f"Camera '{self.name}': image size must be positive.")
        if not self.focal_length > 0:
            raise InputError(f"Camera '{self.name}': focal length must be positive (mm).")
        px, py = self.pixel_size
        if not (px > 0 and py > 0):
            raise InputError(f"Camera '{self.name}': pixel size must be positive (mm).")
        object.__setattr__(self, "pixel_size", (float(px), float(py)))
        object.__setattr__(self, "principal_point", tuple(float(v) for v in self.principal_point))

    # -- properties ----------------------------------------------------------------------------
    @property
    def has_distortion(self) -> bool:
        return any(v != 0.0 for v in (self.k1, self.k2, self.k3, self.p1, self.p2))

    @property
    def sensor_size(self) -> Tuple[float, float]:
        """Sensor width and height in mm."""
        return self.width * self.pixel_size[0], self.height * self.pixel_size[1]

    @property
    def focal_length_px(self) -> float:
        """Focal length in (x) pixels."""
        return self.focal_length / self.pixel_size[0]

    def gsd(self, height_above_ground: ArrayLike) -> Array:
        """Ground sample distance (m) at a flying height above ground (m): GSD = H·px/c."""
        return np.asarray(height_above_ground, dtype=float) * self.pixel_size[0] / self.focal_length

    def corners(self) -> Array:
        """Pixel coordinates of the outer image corners (4, 2), clockwise from top left."""
        w, h = self.width - 0.5, self.height - 0.5
        return np.array([[-0.5, -0.5], [w, -0.5], [w, h], [-0.5, h]])

    # -- pixel <-> image (mm) ------------------------------------------------------------------
    def pixel_to_image(self, col: ArrayLike, row: ArrayLike) -> Tuple[Array, Array]:
        """Pixel (col, row) → distorted image coordinates (x, y) in mm from the principal point."""
        col, row = np.asarray(col, dtype=float), np.asarray(row, dtype=float)
        if self.fiducial_affine is not None:
            A = np.asarray(self.fiducial_affine, dtype=float)
            x = A[0, 0] * col + A[0, 1] * row + A[0, 2]
            y = A[1, 0] * col + A[1, 1] * row + A[1, 2]
        else:
            x = (col - (self.width - 1) / 2.0) * self.pixel_size[0]
            y = -(row - (self.height - 1) / 2.0) * self.pixel_size[1]
        return x - self.principal_point[0], y - self.principal_point[1]

    def image_to_pixel(self, x: ArrayLike, y: ArrayLike) -> Tuple[Array, Array]:
        """Image coordinates (mm, from the principal point) → pixel (col, row)."""
        x = np.asarray(x, dtype=float) + self.principal_point[0]
        y = np.asarray(y, dtype=float) + self.principal_point[1]
        if self.fiducial_affine is not None:
            A = np.asarray(self.fiducial_affine, dtype=float)
            inv = np.linalg.inv(A[:, :2])
            dx, dy = x - A[0, 2], y - A[1, 2]
            return inv[0, 0] * dx + inv[0, 1] * dy, inv[1, 0] * dx + inv[1, 1] * dy
        col = x / self.pixel_size[0] + (self.width - 1) / 2.0
        row = -y / self.pixel_size[1] + (self.height - 1) / 2.0
        return col, row

    # -- distortion ----------------------------------------------------------------------------
    def distort(self, x: ArrayLike, y: ArrayLike) -> Tuple[Array, Array]:
        """Undistorted → distorted image coordinates (mm)."""
        x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
        if not self.has_distortion:
            return x.copy(), y.copy()
        f = self.focal_length
        xd, yd = self._distort_normalised(x / f, -y / f)
        return xd * f, -yd * f

    def undistort(self, x: ArrayLike, y: ArrayLike, max_iter: int = 20) -> Tuple[Array, Array]:
        """Distorted → undistorted image coordinates (mm), by Newton iterations."""
        x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
        if not self.has_distortion:
            return x.copy(), y.copy()
        f = self.focal_length
        xd, yd = x / f, -y / f
        xu, yu = xd.copy(), yd.copy()
        for _ in range(max_iter):
            fx, fy = self._distort_normalised(xu, yu)
            ex, ey = fx - xd, fy - yd
            if np.all(np.abs(ex) + np.abs(ey) < 1e-13):
                break
            j11, j12, j21, j22 = self._jacobian(xu, yu)
            det = j11 * j22 - j12 * j21
            xu = xu - (j22 * ex - j12 * ey) / det
            yu = yu - (-j21 * ex + j11 * ey) / det
        return xu * f, -yu * f

    def _distort_normalised(self, x: Array, y: Array) -> Tuple[Array, Array]:
        r2 = x * x + y * y
        radial = 1.0 + r2 * (self.k1 + r2 * (self.k2 + r2 * self.k3))
        xd = x * radial + 2.0 * self.p1 * x * y + self.p2 * (r2 + 2.0 * x * x)
        yd = y * radial + self.p1 * (r2 + 2.0 * y * y) + 2.0 * self.p2 * x * y
        return xd, yd

    def _jacobian(self, x: Array, y: Array) -> Tuple[Array, Array, Array, Array]:
        r2 = x * x + y * y
        radial = 1.0 + r2 * (self.k1 + r2 * (self.k2 + r2 * self.k3))
        dradial = self.k1 + r2 * (2.0 * self.k2 + 3.0 * self.k3 * r2)  # d radial / d r2
        j11 = radial + 2 * x * x * dradial + 2 * self.p1 * y + 6 * self.p2 * x
        j12 = 2 * x * y * dradial + 2 * self.p1 * x + 2 * self.p2 * y
        j21 = 2 * x * y * dradial + 2 * self.p1 * x + 2 * self.p2 * y
        j22 = radial + 2 * y * y * dradial + 6 * self.p1 * y + 2 * self.p2 * x
        return j11, j12, j21, j22

    # -- pixel <-> camera frame ----------------------------------------------------------------
    def pixel_to_camera(self, col: ArrayLike, row: ArrayLike) -> Array:
        """Ray directions in the camera frame, shape (..., 3), not normalised: (x, y, −c)."""
        xu, yu = self.undistort(*self.pixel_to_image(col, row))
        return np.stack([xu, yu, np.full_like(xu, -self.focal_length)], axis=-1)

    def camera_to_pixel(self, p: ArrayLike) -> Tuple[Array, Array]:
        r"""Camera-frame points (..., 3) → pixel (col, row): :math:`x = -c\,p_x/p_z`.

        Points behind the camera (p_z ≥ 0) give NaN.
        """
        p = np.asarray(p, dtype=float)
        with np.errstate(divide="ignore", invalid="ignore"):
            scale = np.where(p[..., 2] < 0, -self.focal_length / p[..., 2], np.nan)
        return self.image_to_pixel(*self.distort(p[..., 0] * scale, p[..., 1] * scale))

    def to_dict(self) -> Dict[str, object]:
        """Project-file form (see :mod:`..project.model`)."""
        d: Dict[str, object] = {
            "width": self.width,
            "height": self.height,
            "focal_length_mm": self.focal_length,
            "pixel_size_mm": list(self.pixel_size),
            "principal_point_mm": list(self.principal_point),
        }
        if self.has_distortion:
            d["distortion"] = {"k1": self.k1, "k2": self.k2, "k3": self.k3,
                               "p1": self.p1, "p2": self.p2}
        if self.fiducial_affine is not None:
            d["fiducial_affine"] = [list(map(float, r)) for r in self.fiducial_affine]
        return d

    @classmethod
    def from_dict(cls, name: str, d: Dict[str, object]) -> Camera:
        dist = dict(d.get("distortion", {}) or {})  # type: ignore[arg-type]
        fid = d.get("fiducial_affine")
        return cls(
            name=name,
            width=int(d["width"]),  # type: ignore[arg-type]
            height=int(d["height"]),  # type: ignore[arg-type]
            focal_length=float(d["focal_length_mm"]),  # type: ignore[arg-type]
            pixel_size=tuple(d["pixel_size_mm"]),  # type: ignore[arg-type]
            principal_point=tuple(d.get("principal_point_mm", (0.0, 0.0))),  # type: ignore[arg-type]
            fiducial_affine=None if fid is None else tuple(tuple(r) for r in fid),  # type: ignore[arg-type, union-attr]
            **{k: float(dist.get(k, 0.0)) for k in ("k1", "k2", "k3", "p1", "p2")},
        )
