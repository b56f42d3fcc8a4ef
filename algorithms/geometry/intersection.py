r"""Forward intersection of 2…N image rays, with precision.

For each object point the unknowns :math:`X = (X, Y, Z)` are estimated from its image
observations :math:`(c_{ij}, r_{ij})` in the images :math:`j` that see it, by minimising the
reprojection error in pixels (unit weights, standard deviation :math:`\sigma_{px}` per
coordinate):

.. math:: \min_X \sum_j \| \pi_j(X) - (c_{ij}, r_{ij}) \|^2

with :math:`\pi_j` the collinearity projection including distortion (:mod:`.projection`).
Gauss–Newton starts from the linear midpoint solution — the point closest to all rays,

.. math:: \Big(\sum_j (I - d_j d_j^T)\Big) X = \sum_j (I - d_j d_j^T)\, C_j ,

and iterates :math:`X \leftarrow X + N^{-1} A^T v` with the Jacobian :math:`A` (2k × 3) and
:math:`N = A^T A`. Precision:

* a priori: :math:`\Sigma_{XX} = \sigma_{px}^2 N^{-1}`;
* a posteriori: :math:`\hat\sigma_0 = \sqrt{v^T v / (2k - 3)}` (px) and
  :math:`\hat\Sigma_{XX} = \hat\sigma_0^2 N^{-1}`.

**Normal case.** For two images with parallel axes, base B, flying height H above the point,
principal distance c and ground sample distance GSD = H·pixel/c, the height follows from the
x-parallax p (px) alone, :math:`Z = Z_0 - B c / p`, so

.. math:: \sigma_Z = \frac{H}{B}\,\mathrm{GSD}\,\sigma_p, \qquad \sigma_p = \sqrt{2}\,\sigma_{px}

where :math:`\sigma_p` is the standard deviation of the x-parallax; with independent image
coordinates of standard deviation :math:`\sigma_{px}` each, :math:`\sigma_p = \sqrt 2\,\sigma_{px}`
(see :func:`normal_case_sigma_z`).

Observations are batched: arrays of shape (n_points, n_images) with NaN where an image does
not see the point (or an explicit mask).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Optional, Sequence, Tuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import GeometryError, InputError
from .camera import Camera
from .orientation import ExteriorOrientation
from .projection import pixel_to_ray, world_to_camera

Array = NDArray[np.float64]


@dataclass
class IntersectionResult:
    """Forward-intersected points and their precision.

    Attributes
    ----------
    xyz : ndarray, (n, 3)
        Object points; NaN where fewer than 2 rays were given or the solution failed.
    covariance : ndarray, (n, 3, 3)
        :math:`N^{-1}` scaled by :math:`\\sigma_{px}^2` (a priori), m².
    sigma0 : ndarray, (n,)
        A-posteriori standard deviation of unit weight in px (NaN for ... never with k ≥ 2).
    residuals : ndarray, (n, m, 2)
        Reprojection residuals (observed − projected) in px (col, row); NaN where not observed.
    n_rays : ndarray, (n,)
        Number of images used per point.
    sigma_px : float
        The a-priori σ of one image coordinate (px).
    iterations : int
        Gauss–Newton iterations done.
    """

    xyz: Array
    covariance: Array
    sigma0: Array
    residuals: Array
    n_rays: NDArray[np.int64]
    sigma_px: float
    iterations: int

    @property
    def sigma_apriori(self) -> Array:
        """σX, σY, σZ (m) from the a-priori σ_px, shape (n, 3)."""
        return np.sqrt(np.diagonal(self.covariance, axis1=1, axis2=2))

    @property
    def sigma_aposteriori(self) -> Array:
        """σX, σY, σZ (m) scaled by the a-posteriori σ0, shape (n, 3)."""
        return self.sigma_apriori * (self.sigma0 / self.sigma_px)[:, None]

    @property
    def rms_px(self) -> Array:
        """RMS reprojection residual per point (px)."""
        sq = np.nansum(self.residuals ** 2, axis=(1, 2))
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.sqrt(sq / (2 * self.n_rays))


def normal_case_sigma_z(height: ArrayLike, base: ArrayLike, gsd: ArrayLike,
                        sigma_parallax_px: ArrayLike) -> Array:
    r"""Height precision of the normal case: :math:`\sigma_Z = (H/B)\cdot GSD\cdot\sigma_p`.

    ``sigma_parallax_px`` is the σ of the x-parallax; for independent image coordinates of
    σ each, pass :math:`\sqrt 2\,\sigma`.
    """
    return (np.asarray(height, float) / np.asarray(base, float)) * np.asarray(gsd, float) \
        * np.asarray(sigma_parallax_px, float)


def _projection_jacobian(points: Array, camera: Camera, eo: ExteriorOrientation
                         ) -> Tuple[Array, Array, Array]:
    """Pixel (col, row) of points (n, 3) and the Jacobian d(col, row)/dX, shape (n, 2, 3)."""
    p = world_to_camera(points, eo)
    c = camera.focal_length
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.where(p[:, 2] < 0, -c / p[:, 2], np.nan)
        x, y = p[:, 0] * s, p[:, 1] * s
        # d(x, y)/dp = -c/p_z [[1, 0, -p_x/p_z], [0, 1, -p_y/p_z]]
        J_p = np.zeros((len(p), 2, 3))
        J_p[:, 0, 0] = s
        J_p[:, 1, 1] = s
        J_p[:, 0, 2] = -x / p[:, 2]
        J_p[:, 1, 2] = -y / p[:, 2]
    J = J_p @ eo.rotation.T  # dp/dX = Rᵀ
    if camera.has_distortion:
        # distortion is computed in the OpenCV frame (x/c, −y/c): flip the off-diagonal signs
        j11, j12, j21, j22 = camera._jacobian(x / c, -y / c)
        D = np.empty((len(p), 2, 2))
        D[:, 0, 0], D[:, 0, 1], D[:, 1, 0], D[:, 1, 1] = j11, -j12, -j21, j22
        J = D @ J
        x, y = camera.distort(x, y)
    col, row = camera.image_to_pixel(x, y)
    # image → pixel is affine: its linear part from unit steps
    c0, r0 = camera.image_to_pixel(0.0, 0.0)
    c1, r1 = camera.image_to_pixel(1.0, 0.0)
    c2, r2 = camera.image_to_pixel(0.0, 1.0)
    P = np.array([[c1 - c0, c2 - c0], [r1 - r0, r2 - r0]])
    return col, row, P @ J


def _well_conditioned(M: Array, rcond: float = 1e-12) -> NDArray[np.bool_]:
    """True for 3×3 matrices that are safely invertible (reciprocal condition > ``rcond``)."""
    if M.shape[0] == 0:
        return np.zeros(0, dtype=bool)
    s = np.linalg.svd(M, compute_uv=False)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.isfinite(s).all(axis=1) & (s[:, -1] > rcond * s[:, 0])


def forward_intersection(cols: ArrayLike, rows: ArrayLike, cameras: Sequence[Camera],
                         eos: Sequence[ExteriorOrientation], mask: Optional[ArrayLike] = None,
                         sigma_px: float = 1.0, max_iter: int = 10, tol: float = 1e-7
                         ) -> IntersectionResult:
    """Least-squares intersection of many points, each seen in 2…N images.

    Parameters
    ----------
    cols, rows : array_like, shape (n, m)
        Pixel observations of n points in m images; NaN where an image does not see a point.
        A 1-D input is one point.
    cameras, eos : sequences of length m
        Interior and exterior orientation of each image.
    mask : array_like of bool, shape (n, m), optional
        Which observations to use (in addition to the finite ones).
    sigma_px : float
        A-priori σ of one image coordinate (px).
    max_iter : int
        Gauss–Newton iterations at most.
    tol : float
        Stop when every correction is below ``tol`` metres.

    Returns
    -------
    IntersectionResult
    """
    cols = np.atleast_2d(np.asarray(cols, dtype=float))
    rows = np.atleast_2d(np.asarray(rows, dtype=float))
    if cols.shape != rows.shape:
        raise InputError("Forward intersection: cols and rows must have the same shape.")
    n, m = cols.shape
    if len(cameras) != m or len(eos) != m:
        raise InputError(f"Forward intersection: {m} image columns but {len(cameras)} cameras "
                         f"and {len(eos)} orientations.")
    seen = np.isfinite(cols) & np.isfinite(rows)
    if mask is not None:
        seen &= np.asarray(mask, dtype=bool).reshape(n, m)
    k = seen.sum(axis=1)
    good = k >= 2

    # linear start: closest point to all rays
    A = np.zeros((n, 3, 3))
    b = np.zeros((n, 3))
    eye = np.eye(3)
    for j in range(m):
        sel = np.flatnonzero(seen[:, j])
        if sel.size == 0:
            continue
        C, dirs = pixel_to_ray(cols[sel, j], rows[sel, j], cameras[j], eos[j])
        Pj = eye - dirs[:, :, None] * dirs[:, None, :]
        A[sel] += Pj
        b[sel] += Pj @ C
    X = np.full((n, 3), np.nan)
    gi = np.flatnonzero(good)
    gi = gi[_well_conditioned(A[gi])]
    X[gi] = np.linalg.solve(A[gi], b[gi][..., None])[..., 0]

    # Gauss–Newton on the reprojection error
    iterations = 0
    N = np.zeros((n, 3, 3))
    for it in range(max_iter):
        iterations = it + 1
        N[:] = 0.0
        g = np.zeros((n, 3))
        for j in range(m):
            sel = np.flatnonzero(seen[:, j] & np.isfinite(X[:, 0]))
            if sel.size == 0:
                continue
            col, row, J = _projection_jacobian(X[sel], cameras[j], eos[j])
            v = np.stack([cols[sel, j] - col, rows[sel, j] - row], axis=1)
            N[sel] += np.transpose(J, (0, 2, 1)) @ J
            g[sel] += np.einsum("nij,ni->nj", J, v)
        live = np.flatnonzero(np.isfinite(X[:, 0]) & np.isfinite(g).all(axis=1))
        regular = _well_conditioned(N[live])
        X[live[~regular]] = np.nan  # (nearly) parallel rays: no intersection
        live = live[regular]
        dX = np.zeros((n, 3))
        dX[live] = np.linalg.solve(N[live], g[live][..., None])[..., 0]
        X[live] += dX[live]
        if live.size == 0 or np.max(np.abs(dX[live])) < tol:
            break
    bad = ~np.isfinite(X).all(axis=1)
    X[bad] = np.nan

    # residuals and precision at the solution
    residuals = np.full((n, m, 2), np.nan)
    N[:] = 0.0
    for j in range(m):
        sel = np.flatnonzero(seen[:, j] & ~bad)
        if sel.size == 0:
            continue
        col, row, J = _projection_jacobian(X[sel], cameras[j], eos[j])
        residuals[sel, j, 0] = cols[sel, j] - col
        residuals[sel, j, 1] = rows[sel, j] - row
        N[sel] += np.transpose(J, (0, 2, 1)) @ J
    cov = np.full((n, 3, 3), np.nan)
    valid = np.flatnonzero(~bad)
    regular = _well_conditioned(N[valid])
    bad[valid[~regular]] = True
    X[valid[~regular]] = np.nan
    residuals[valid[~regular]] = np.nan
    valid = valid[regular]
    cov[valid] = np.linalg.inv(N[valid]) * sigma_px ** 2
    vtv = np.nansum(residuals ** 2, axis=(1, 2))
    with np.errstate(invalid="ignore", divide="ignore"):
        sigma0 = np.where(~bad & (k >= 2), np.sqrt(vtv / (2 * k - 3)), np.nan)
    return IntersectionResult(xyz=X, covariance=cov, sigma0=sigma0, residuals=residuals,
                              n_rays=k.astype(np.int64), sigma_px=float(sigma_px),
                              iterations=iterations)


def intersect_pair(col_l: ArrayLike, row_l: ArrayLike, col_r: ArrayLike, row_r: ArrayLike,
                   cameras: Tuple[Camera, Camera],
                   eos: Tuple[ExteriorOrientation, ExteriorOrientation],
                   sigma_px: float = 1.0) -> IntersectionResult:
    """Convenience wrapper of :func:`forward_intersection` for a stereo pair."""
    cols = np.stack([np.ravel(col_l), np.ravel(col_r)], axis=1)
    rows = np.stack([np.ravel(row_l), np.ravel(row_r)], axis=1)
    if cols.size == 0:
        raise GeometryError("No point pairs to intersect.")
    return forward_intersection(cols, rows, list(cameras), list(eos), sigma_px=sigma_px)
