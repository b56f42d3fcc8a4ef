r"""Epipolar (normal-case) resampling of a stereo pair.

Both images are re-projected onto a common image plane of two *normal* cameras that keep the
original projection centres :math:`C_l, C_r` but share one rotation :math:`R_n`
(camera→world, PATB axes) with

.. math::

   x_n = \frac{C_r - C_l}{\|C_r - C_l\|},\quad
   z_n = \frac{\bar z - (\bar z\cdot x_n)\,x_n}{\|\cdot\|},\quad y_n = z_n \times x_n ,

where :math:`\bar z` is the mean of the two original camera z axes (so the normal image plane
is as close as possible to both originals). In the normal case a world point has the same row
in both images (no y-parallax) and its depth follows from the x-parallax.

An epipolar pixel (col, row) of side s is the normal-camera direction
:math:`v = (col - c_{x,s},\; -(row - c_y),\; -f_n)` (a common :math:`c_y` and height for both
sides, a column offset :math:`c_{x,s}` and width per side). The map to the *undistorted*
original pixel is the homography

.. math:: H_s = P_s\,\mathrm{diag}(c_s, c_s, -1)\,R_s^T R_n\,M_n,\qquad
          M_n = \begin{pmatrix}1&0&-c_{x,s}\\0&-1&c_y\\0&0&-f_n\end{pmatrix}

with :math:`P_s` the (affine) image-mm → pixel map of the original camera. Lens distortion is
then applied in the original camera (:meth:`EpipolarPair.to_original`), so the mapping is exact
for distorted cameras too; :meth:`EpipolarPair.from_original` inverts it through the camera's
undistortion.

**Convergent pairs** (optical axes more than :data:`CONVERGENT_DEG` apart, e.g. drone frames
tilted towards each other): the mean-axis rotation and the mean focal length leave the local
scale of the resampling far from 1 (one image shrunk where the other is stretched) and the
epipolar images hold all of both frames, most of it outside the stereo overlap. With ground
points of the overlap (``overlap_points``) the pair is instead rectified with the *minimal
distortion* rotation (:func:`minimal_distortion_rotation`, in the spirit of Loop & Zhang): the
normal plane turns about the base by the angle α, and :math:`f_n` is chosen, so that the
local area scale of both images over the overlap is as close to 1 as possible — for a ray
:math:`v` with angles :math:`\theta_s, \theta_n` to the optical axes of the original and the
normal camera, one epipolar pixel covers

.. math:: s_s(v) = \frac{f_s}{f_n}\left(\frac{\cos\theta_n}{\cos\theta_s}\right)^{3/2}

original pixels (linear, from the area ratio of the two image planes); α minimises
:math:`\sum (\log s - \overline{\log s})^2` over both images and the points, and
:math:`f_n` sets :math:`\overline{\log s} = 0`. The epipolar images are then cut to the
projection of the overlap points (plus a margin), so no pixel is spent outside the overlap.

Triangulation in the normal case: with :math:`x_s = col_s - c_{x,s}`, parallax
:math:`p = x_l - x_r` (px), depth :math:`D = f_n B / p`, and the point is
:math:`X = C_l + R_n\,(x_l, -(row - c_y), -f_n)\,D / f_n`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Dict, Iterator, Optional, Tuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import GeometryError, InputError
from .camera import Camera
from .orientation import ExteriorOrientation
from .projection import border_pixels

Array = NDArray[np.float64]
SIDES = ("left", "right")

#: Pixels per row block when writing resampled epipolar images (bounds the memory).
RESAMPLE_BLOCK_PIXELS = 1_000_000
#: Angle (°) between the two optical axes above which a pair with known overlap points is
#: rectified with minimal distortion and cut to the overlap (module notes).
CONVERGENT_DEG = 10.0
#: Margin (px) around the projected overlap of a cropped (convergent) epipolar pair.
CROP_MARGIN_PX = 16


def _side_index(side: str) -> int:
    if side not in SIDES:
        raise InputError(f"Epipolar side must be 'left' or 'right', not {side!r}.")
    return SIDES.index(side)


def normal_rotation(eo_left: ExteriorOrientation, eo_right: ExteriorOrientation
                    ) -> Tuple[Array, float]:
    """Common camera→world rotation of the normal case and the base length (m)."""
    b = eo_right.position - eo_left.position
    base = float(np.linalg.norm(b))
    if not base > 0:
        raise GeometryError("The two images have the same projection centre: no stereo base.")
    x = b / base
    z_mean = eo_left.rotation[:, 2] + eo_right.rotation[:, 2]
    z = z_mean - (z_mean @ x) * x
    nz = np.linalg.norm(z)
    if nz < 1e-6:
        raise GeometryError("The stereo base is parallel to the viewing direction; the pair "
                            "cannot be normalised (convergent or along-track oblique images).")
    z /= nz
    y = np.cross(z, x)
    return np.column_stack([x, y, z]), base


def convergence_deg(eo_left: ExteriorOrientation, eo_right: ExteriorOrientation) -> float:
    """Angle (°) between the optical axes of two images."""
    c = float(np.clip(eo_left.rotation[:, 2] @ eo_right.rotation[:, 2], -1.0, 1.0))
    return float(np.degrees(np.arccos(c)))


def _rotated_about_base(R_n: Array, alpha: float) -> Array:
    """``R_n`` turned by ``alpha`` (rad) about its x axis (the base)."""
    c, s = np.cos(alpha), np.sin(alpha)
    return R_n @ np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def _log_scales(R_n: Array, eos: Tuple[ExteriorOrientation, ExteriorOrientation],
                focals: Tuple[float, float], points: Array) -> Array:
    """log of f_s (cos θ_n / cos θ_s)^{3/2} (the scale without 1/f_n), (2, n); NaN behind a
    camera or the normal plane."""
    out = []
    for eo, f in zip(eos, focals):
        v = points - eo.position
        v = v / np.linalg.norm(v, axis=1)[:, None]
        cos_s = -(v @ eo.rotation[:, 2])
        cos_n = -(v @ R_n[:, 2])
        with np.errstate(divide="ignore", invalid="ignore"):
            out.append(np.where((cos_s > 0.05) & (cos_n > 0.05),
                                np.log(f) + 1.5 * (np.log(cos_n) - np.log(cos_s)), np.nan))
    return np.array(out)


def minimal_distortion_rotation(eo_left: ExteriorOrientation, eo_right: ExteriorOrientation,
                                focals: Tuple[float, float], points: ArrayLike,
                                max_angle: float = 60.0) -> Tuple[Array, float, float]:
    """Normal rotation and focal length (px) with the least resampling distortion.

    Parameters
    ----------
    focals : (float, float)
        Principal distances (px) of the original images.
    points : array (n, 3)
        World points of the stereo overlap (e.g. its outline and centre at the terrain
        heights).
    max_angle : float
        Largest turn (°) about the base from the mean-axis rotation that is tried.

    Returns
    -------
    rotation : ndarray (3, 3)
    focal_px : float
        :math:`f_n` with a mean log scale of 0 over both images (module notes).
    spread : float
        RMS of the log scales (0 = no distortion; 0.1 ≈ ±10 %).
    """
    pts = np.asarray(points, dtype=float).reshape(-1, 3)
    R0, _ = normal_rotation(eo_left, eo_right)
    eos = (eo_left, eo_right)

    def cost(alpha: float) -> float:
        ls = _log_scales(_rotated_about_base(R0, alpha), eos, focals, pts)
        if not np.isfinite(ls).all():
            return np.inf  # a point behind the normal plane: not a usable rotation
        return float(np.mean((ls - ls.mean()) ** 2))

    lim = np.radians(max_angle)
    grid = np.linspace(-lim, lim, 121)
    costs = np.array([cost(a) for a in grid])
    k = int(np.argmin(costs))
    if not np.isfinite(costs[k]):
        raise GeometryError("No rotation about the base keeps the overlap in front of both "
                            "normal images; the pair cannot be normalised.")
    lo, hi = grid[max(k - 1, 0)], grid[min(k + 1, len(grid) - 1)]
    for _ in range(40):  # golden-section refinement inside the bracketing grid cells
        a = hi - 0.618 * (hi - lo)
        b = lo + 0.618 * (hi - lo)
        if cost(a) < cost(b):
            hi = b
        else:
            lo = a
    R_n = _rotated_about_base(R0, 0.5 * (lo + hi))
    ls = _log_scales(R_n, eos, focals, pts)
    return R_n, float(np.exp(ls.mean())), float(np.sqrt(np.mean((ls - ls.mean()) ** 2)))


def _pixel_affine(camera: Camera) -> Array:
    """3×3 matrix of the affine image-mm (from the principal point) → pixel map."""
    c0, r0 = camera.image_to_pixel(0.0, 0.0)
    c1, r1 = camera.image_to_pixel(1.0, 0.0)
    c2, r2 = camera.image_to_pixel(0.0, 1.0)
    return np.array([[c1 - c0, c2 - c0, c0], [r1 - r0, r2 - r0, r0], [0.0, 0.0, 1.0]],
                    dtype=float)


@dataclass
class EpipolarPair:
    """A normalised stereo pair and its mappings to the original images.

    Attributes
    ----------
    cameras, eos : (left, right)
        The original interior and exterior orientations.
    rotation : ndarray (3, 3)
        Common camera→world rotation :math:`R_n` of the normal images.
    base : float
        Base length B (m), along the normal x axis from left to right.
    focal_px : float
        Principal distance :math:`f_n` of the normal images in pixels.
    cx : (float, float)
        Column of the normal principal point in the left and right epipolar image.
    cy : float
        Row of the normal principal point (common to both).
    sizes : ((w_l, h), (w_r, h))
        Epipolar image sizes in pixels.
    homographies : ndarray (2, 3, 3)
        Epipolar pixel → undistorted original pixel (see module notes).
    """

    cameras: Tuple[Camera, Camera]
    eos: Tuple[ExteriorOrientation, ExteriorOrientation]
    rotation: Array
    base: float
    focal_px: float
    cx: Tuple[float, float]
    cy: float
    sizes: Tuple[Tuple[int, int], Tuple[int, int]]
    homographies: Array
    names: Tuple[str, str] = ("left", "right")

    # -- construction --------------------------------------------------------------------------
    @classmethod
    def from_orientations(cls, camera_left: Camera, eo_left: ExteriorOrientation,
                          camera_right: Camera, eo_right: ExteriorOrientation,
                          scale: float = 1.0, names: Tuple[str, str] = ("left", "right"),
                          border_samples: int = 64, overlap_points: Optional[ArrayLike] = None,
                          rectification: str = "auto") -> EpipolarPair:
        """Normalise a pair.

        Parameters
        ----------
        scale : float
            Epipolar pixel size relative to the originals: 1 keeps the mean resolution,
            0.5 halves it.
        border_samples : int
            Points per image edge used to find the epipolar image extents (distortion bends
            the edges, so the four corners are not enough).
        overlap_points : array (n, 3), optional
            World points of the stereo overlap (outline at the lowest and highest terrain):
            needed for the minimal-distortion rectification, which also cuts the images to
            their projection (module notes).
        rectification : {"auto", "mean_axis", "minimal_distortion"}
            ``auto``: minimal distortion when ``overlap_points`` are given and the optical axes
            are more than :data:`CONVERGENT_DEG` apart, else the mean-axis rotation.
        """
        if not scale > 0:
            raise InputError(f"Epipolar scale must be positive, got {scale}.")
        if rectification not in ("auto", "mean_axis", "minimal_distortion"):
            raise InputError(f"Unknown rectification {rectification!r}; use auto, mean_axis or "
                             "minimal_distortion.")
        pts = None if overlap_points is None else np.asarray(overlap_points, float).reshape(-1, 3)
        minimal = pts is not None and (
            rectification == "minimal_distortion"
            or (rectification == "auto" and convergence_deg(eo_left, eo_right) > CONVERGENT_DEG))
        if rectification == "minimal_distortion" and pts is None:
            raise InputError("The minimal-distortion rectification needs overlap points.")
        R_n, base = normal_rotation(eo_left, eo_right)
        f_n = 0.5 * (camera_left.focal_length_px + camera_right.focal_length_px)
        if minimal:
            R_n, f_opt, _ = minimal_distortion_rotation(
                eo_left, eo_right, (camera_left.focal_length_px, camera_right.focal_length_px),
                pts)
            # never coarser than the originals' mean: a DSM cell of one GSD keeps its points
            f_n = max(f_n, f_opt)
        pair = cls((camera_left, camera_right), (eo_left, eo_right), R_n, base, scale * f_n,
                   (0.0, 0.0), 0.0, ((1, 1), (1, 1)), np.zeros((2, 3, 3)), tuple(names))
        pair._set_extents(border_samples, pts if minimal else None)
        return pair

    def _set_extents(self, border_samples: int, crop: Optional[Array]) -> None:
        """Sizes and principal points from the original borders in normal coordinates, cut to
        the projected ``crop`` points (plus :data:`CROP_MARGIN_PX`) when given."""
        u_rng, w_rng = [], []
        for s, cam in enumerate(self.cameras):
            border = border_pixels(cam, border_samples)
            u, w = self._original_to_normal(s, border[:, 0], border[:, 1])
            if not (np.isfinite(u).all() and np.isfinite(w).all()):
                raise GeometryError("An image border looks away from the normal image plane; "
                                    "the pair cannot be normalised.")
            lo_u, hi_u, lo_w, hi_w = u.min(), u.max(), w.min(), w.max()
            if crop is not None:
                cu, cw = self._world_to_normal(s, crop)
                m = CROP_MARGIN_PX
                lo_u, hi_u = max(lo_u, np.nanmin(cu) - m), min(hi_u, np.nanmax(cu) + m)
                lo_w, hi_w = max(lo_w, np.nanmin(cw) - m), min(hi_w, np.nanmax(cw) + m)
            u_rng.append((lo_u, hi_u))
            w_rng.append((lo_w, hi_w))
        if crop is not None:  # rows: where both images see the overlap
            w_lo, w_hi = max(r[0] for r in w_rng), min(r[1] for r in w_rng)
        else:
            w_lo, w_hi = min(r[0] for r in w_rng), max(r[1] for r in w_rng)
        if not w_hi > w_lo or any(not hi > lo for lo, hi in u_rng):
            raise GeometryError("The stereo overlap does not project into both images.")
        cy = float(np.ceil(w_hi))
        height = int(cy - np.floor(w_lo)) + 1
        cx, sizes = [], []
        for lo, hi in u_rng:
            cx.append(float(-np.floor(lo)))
            sizes.append((int(np.ceil(hi) - np.floor(lo)) + 1, height))
        self.cx = (cx[0], cx[1])
        self.cy = cy
        self.sizes = (sizes[0], sizes[1])
        self.homographies = np.stack([self._homography(0), self._homography(1)])

    def _world_to_normal(self, s: int, points: Array) -> Tuple[Array, Array]:
        """World points → normal image coordinates (u right, w up) in px of side ``s``."""
        v = (points - self.eos[s].position) @ self.rotation
        with np.errstate(divide="ignore", invalid="ignore"):
            scale = np.where(v[..., 2] < 0, -self.focal_px / v[..., 2], np.nan)
        return v[..., 0] * scale, v[..., 1] * scale

    def local_scale(self, side: str, points: ArrayLike) -> Array:
        """Original pixels per epipolar pixel (linear, from the area ratio) at world points.

        1 means no resampling distortion; see the module notes.
        """
        s = _side_index(side)
        v = np.asarray(points, dtype=float).reshape(-1, 3) - self.eos[s].position
        v = v / np.linalg.norm(v, axis=1)[:, None]
        cos_s = -(v @ self.eos[s].rotation[:, 2])
        cos_n = -(v @ self.rotation[:, 2])
        f_s = self.cameras[s].focal_length_px
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where((cos_s > 0) & (cos_n > 0),
                            f_s / self.focal_px * (cos_n / cos_s) ** 1.5, np.nan)

    def _homography(self, s: int) -> Array:
        cam, eo = self.cameras[s], self.eos[s]
        M_n = np.array([[1.0, 0.0, -self.cx[s]], [0.0, -1.0, self.cy], [0.0, 0.0, -self.focal_px]])
        K = np.diag([cam.focal_length, cam.focal_length, -1.0])
        H = _pixel_affine(cam) @ K @ eo.rotation.T @ self.rotation @ M_n
        # normalise, keeping the sign so that q2 > 0 means "in front of the camera"
        return H / abs(H[2, 2])

    def _original_to_normal(self, s: int, col: ArrayLike, row: ArrayLike) -> Tuple[Array, Array]:
        """Original pixel → normal image coordinates (u right, w up) in px, no offsets."""
        cam, eo = self.cameras[s], self.eos[s]
        v = cam.pixel_to_camera(col, row) @ eo.rotation.T @ self.rotation
        with np.errstate(divide="ignore", invalid="ignore"):
            scale = np.where(v[..., 2] < 0, -self.focal_px / v[..., 2], np.nan)
        return v[..., 0] * scale, v[..., 1] * scale

    # -- mappings ------------------------------------------------------------------------------
    @property
    def height(self) -> int:
        return self.sizes[0][1]

    def from_original(self, side: str, col: ArrayLike, row: ArrayLike) -> Tuple[Array, Array]:
        """Original pixel (col, row) of ``side`` → epipolar pixel (col, row)."""
        s = _side_index(side)
        u, w = self._original_to_normal(s, col, row)
        return u + self.cx[s], self.cy - w

    def to_original(self, side: str, col: ArrayLike, row: ArrayLike) -> Tuple[Array, Array]:
        """Epipolar pixel (col, row) of ``side`` → original pixel (col, row), with distortion."""
        s = _side_index(side)
        cam = self.cameras[s]
        H = self.homographies[s]
        col = np.asarray(col, dtype=float)
        row = np.asarray(row, dtype=float)
        q0 = H[0, 0] * col + H[0, 1] * row + H[0, 2]
        q1 = H[1, 0] * col + H[1, 1] * row + H[1, 2]
        q2 = H[2, 0] * col + H[2, 1] * row + H[2, 2]
        with np.errstate(divide="ignore", invalid="ignore"):
            q2 = np.where(q2 > 0, q2, np.nan)  # behind the original camera
            cu, ru = q0 / q2, q1 / q2
        if not cam.has_distortion:
            return cu, ru
        return cam.image_to_pixel(*cam.distort(*cam.pixel_to_image(cu, ru)))

    def original_map(self, side: str, row_start: int = 0, row_stop: Optional[int] = None
                     ) -> Tuple[Array, Array]:
        """Original (col, row) for every epipolar pixel of rows ``row_start:row_stop``.

        NaN where the epipolar pixel falls outside the original image.
        """
        s = _side_index(side)
        w, h = self.sizes[s]
        row_stop = h if row_stop is None else min(row_stop, h)
        rr, cc = np.mgrid[row_start:row_stop, 0:w].astype(float)
        oc, orow = self.to_original(side, cc, rr)
        cam = self.cameras[s]
        inside = ((oc >= -0.5) & (oc <= cam.width - 0.5)
                  & (orow >= -0.5) & (orow <= cam.height - 0.5))
        return np.where(inside, oc, np.nan), np.where(inside, orow, np.nan)

    def iter_resample(self, image: NDArray, side: str, chunk_rows: Optional[int] = None,
                      max_pixels: int = 2_000_000
                      ) -> Iterator[Tuple[int, NDArray, NDArray[np.bool_], Array, Array]]:
        """Resample an original image to epipolar geometry, one block of rows at a time.

        Yields ``(row_start, block (bands, rows, w), valid (rows, w), map_col, map_row)``;
        bilinear interpolation (:func:`scipy.ndimage.map_coordinates`, order 1) of every band,
        0 outside the original image. Integer inputs are rounded and clipped to their type.
        """
        from scipy.ndimage import map_coordinates  # lazy: keeps photodem list fast

        img = np.asarray(image)
        if img.ndim == 2:
            img = img[None]
        s = _side_index(side)
        cam = self.cameras[s]
        if img.shape[1:] != (cam.height, cam.width):
            raise InputError(
                f"The {side} image is {img.shape[2]}×{img.shape[1]} px but its camera "
                f"'{cam.name}' is {cam.width}×{cam.height} px."
            )
        w, h = self.sizes[s]
        if chunk_rows is None:
            chunk_rows = max(1, max_pixels // max(w, 1))
        integer = np.issubdtype(img.dtype, np.integer)
        info = np.iinfo(img.dtype) if integer else None
        for r0 in range(0, h, chunk_rows):
            r1 = min(r0 + chunk_rows, h)
            mc, mr = self.original_map(side, r0, r1)
            valid = np.isfinite(mc)
            coords = np.stack([np.where(valid, mr, 0.0), np.where(valid, mc, 0.0)])
            out = np.empty((img.shape[0], r1 - r0, w), dtype=img.dtype)
            for b in range(img.shape[0]):
                # interpolation runs in double precision whatever the input type
                vals = map_coordinates(img[b], coords, output=np.float64, order=1,
                                       mode="nearest")
                vals = np.where(valid, vals, 0.0)
                if info is not None:
                    vals = np.clip(np.rint(vals), info.min, info.max)
                out[b] = vals.astype(img.dtype)
            yield r0, out, valid, mc, mr

    def resample(self, image: NDArray, side: str, chunk_rows: Optional[int] = None
                 ) -> Tuple[NDArray, NDArray[np.bool_]]:
        """The whole epipolar image (bands, h, w) (2-D in → 2-D out) and its valid mask."""
        s = _side_index(side)
        w, h = self.sizes[s]
        img = np.asarray(image)
        bands = 1 if img.ndim == 2 else img.shape[0]
        out = np.zeros((bands, h, w), dtype=img.dtype)
        valid = np.zeros((h, w), dtype=bool)
        for r0, block, ok, _, _ in self.iter_resample(img, side, chunk_rows):
            out[:, r0:r0 + block.shape[1]] = block
            valid[r0:r0 + block.shape[1]] = ok
        return (out[0] if img.ndim == 2 else out), valid

    # -- triangulation -------------------------------------------------------------------------
    def epipolar_point_to_world(self, col_left: ArrayLike, row: ArrayLike,
                                col_right: ArrayLike) -> Array:
        """World points (..., 3) from matching epipolar columns on a common row.

        NaN where the parallax is not positive (point at or behind infinity).
        """
        x_l = np.asarray(col_left, dtype=float) - self.cx[0]
        x_r = np.asarray(col_right, dtype=float) - self.cx[1]
        y = -(np.asarray(row, dtype=float) - self.cy)
        p = x_l - x_r
        with np.errstate(divide="ignore", invalid="ignore"):
            depth = np.where(p > 0, self.focal_px * self.base / p, np.nan)
        x_l, y, depth = np.broadcast_arrays(x_l, y, depth)
        v = np.stack([x_l, y, np.full_like(x_l, -self.focal_px)], axis=-1) \
            * (depth / self.focal_px)[..., None]
        return self.eos[0].position + v @ self.rotation.T

    def disparity_to_world(self, disparity: ArrayLike,
                           col_left: Optional[ArrayLike] = None,
                           row: Optional[ArrayLike] = None) -> Array:
        """World points from disparities ``d = col_left − col_right`` (px).

        With only ``disparity`` (a (h, w) map over the left epipolar image) the pixel grid
        supplies the columns and rows; returns (h, w, 3), NaN where d is NaN.
        """
        d = np.asarray(disparity, dtype=float)
        if col_left is None or row is None:
            row, col_left = np.mgrid[0:d.shape[0], 0:d.shape[1]].astype(float)
        return self.epipolar_point_to_world(col_left, row, np.asarray(col_left, float) - d)

    def world_to_epipolar(self, points: ArrayLike, side: str) -> Tuple[Array, Array]:
        """World points (..., 3) → epipolar pixel (col, row) of ``side`` (no distortion)."""
        s = _side_index(side)
        u, w = self._world_to_normal(s, np.asarray(points, dtype=float))
        return u + self.cx[s], self.cy - w

    def disparity_range(self, z_min: float, z_max: float,
                        xy: Optional[ArrayLike] = None) -> Tuple[float, float]:
        """Disparity interval for terrain between ``z_min`` and ``z_max``.

        Evaluated at the ground points ``xy`` ((n, 2), e.g. the vertices of the stereo overlap)
        at both heights, by default below the midpoint of the projection centres only. With
        tilted images the disparity of one height varies across the overlap, so give ``xy``
        where it matters.
        """
        if xy is None:
            centre = 0.5 * (self.eos[0].position + self.eos[1].position)
            xy = centre[None, :2]
        xy = np.asarray(xy, dtype=float).reshape(-1, 2)
        pts = np.concatenate([np.column_stack([xy, np.full(len(xy), z)])
                              for z in (z_min, z_max)])
        cl, _ = self.world_to_epipolar(pts, "left")
        cr, _ = self.world_to_epipolar(pts, "right")
        d = cl - cr
        return float(np.nanmin(d)), float(np.nanmax(d))

    # -- serialisation -------------------------------------------------------------------------
    def to_dict(self) -> Dict[str, Any]:
        """JSON-ready description (``epipolar.json``)."""
        return {
            "names": list(self.names),
            "base_m": self.base,
            "focal_px": self.focal_px,
            "cx": list(self.cx),
            "cy": self.cy,
            "sizes": [list(s) for s in self.sizes],
            "rotation": self.rotation.tolist(),
            "homographies": {side: self.homographies[i].tolist()
                             for i, side in enumerate(SIDES)},
            "homography_maps": "epipolar pixel (col,row,1) -> undistorted original pixel; "
                               "apply the original camera's distortion after it",
            "disparity": "d = col_left - col_right; parallax p = d - (cx_left - cx_right); "
                         "depth = focal_px * base_m / p",
            "cameras": {side: {"name": self.cameras[i].name, **self.cameras[i].to_dict()}
                        for i, side in enumerate(SIDES)},
            "orientations": {side: {"position": self.eos[i].position.tolist(),
                                    "rotation": self.eos[i].rotation.tolist()}
                             for i, side in enumerate(SIDES)},
        }

    @classmethod
    def from_dict(cls, d: Dict[str, Any]) -> EpipolarPair:
        """Inverse of :meth:`to_dict`."""
        cams = []
        eos = []
        for side in SIDES:
            cd = dict(d["cameras"][side])
            name = str(cd.pop("name"))
            cams.append(Camera.from_dict(name, cd))
            o = d["orientations"][side]
            eos.append(ExteriorOrientation(np.asarray(o["position"]), np.asarray(o["rotation"])))
        sizes = tuple(tuple(int(v) for v in s) for s in d["sizes"])
        return cls((cams[0], cams[1]), (eos[0], eos[1]), np.asarray(d["rotation"], float),
                   float(d["base_m"]), float(d["focal_px"]),
                   (float(d["cx"][0]), float(d["cx"][1])), float(d["cy"]),
                   sizes,  # type: ignore[arg-type]
                   np.stack([np.asarray(d["homographies"][s], float) for s in SIDES]),
                   tuple(d.get("names", SIDES)))  # type: ignore[arg-type]
