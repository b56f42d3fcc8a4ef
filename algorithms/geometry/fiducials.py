r"""Interior orientation of scanned film from fiducial marks.

The scan's pixel grid is related to the calibrated image coordinate system (the fiducial frame,
in mm, x right, y up, origin at the fiducial centre as in the calibration certificate) by a
2-D affine transformation, estimated by least squares from :math:`n \ge 4` marks:

.. math::

   \begin{pmatrix} x \\ y \end{pmatrix} =
   \begin{pmatrix} a_{11} & a_{12} \\ a_{21} & a_{22} \end{pmatrix}
   \begin{pmatrix} col \\ row \end{pmatrix} + \begin{pmatrix} a_{13} \\ a_{23} \end{pmatrix}

Six unknowns, :math:`2n` observations, redundancy :math:`r = 2n - 6`. The residuals
:math:`v = \hat{x} - x_{cal}` are reported per mark (µm in the image, and px), with
:math:`\mathrm{RMS} = \sqrt{\sum |v_i|^2 / n}` and the a-posteriori standard deviation of unit
weight :math:`\sigma_0 = \sqrt{v^T v / r}`. Three marks determine the affine exactly and leave
no check, hence four are required.

:class:`~.camera.Camera` with ``fiducial_affine`` maps pixel → fiducial frame with this affine
and then subtracts the principal point, which is therefore given in the fiducial frame
(the calibrated ``xp, yp``).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Optional, Tuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InputError
from .camera import Camera

Array = NDArray[np.float64]


@dataclass(frozen=True)
class FiducialFit:
    """Result of :func:`fit_fiducials`.

    Attributes
    ----------
    affine : ndarray, shape (2, 3)
        Pixel (col, row) → fiducial-frame mm, ``[[a11, a12, a13], [a21, a22, a23]]``.
    residuals_mm : ndarray, shape (n, 2)
        Fitted minus calibrated position of each mark (mm).
    residuals_px : ndarray, shape (n, 2)
        The same residuals expressed in scan pixels (col, row).
    sigma0_um : float
        :math:`\\sigma_0 = \\sqrt{v^T v / (2n-6)}` in µm (NaN when n = 3 is forced).
    """

    affine: Array
    residuals_mm: Array
    residuals_px: Array
    sigma0_um: float

    @property
    def n(self) -> int:
        return int(self.residuals_mm.shape[0])

    @property
    def residuals_um(self) -> Array:
        """Residual vectors per mark in µm."""
        return self.residuals_mm * 1000.0

    @property
    def residual_norms_um(self) -> Array:
        """Length of each mark's residual vector in µm."""
        return np.hypot(self.residuals_um[:, 0], self.residuals_um[:, 1])

    @property
    def rms_um(self) -> float:
        """RMS of the residual vector lengths in µm."""
        return float(np.sqrt(np.mean(self.residual_norms_um ** 2)))

    @property
    def rms_px(self) -> float:
        """RMS of the residual vector lengths in pixels."""
        return float(np.sqrt(np.mean(np.sum(self.residuals_px ** 2, axis=1))))

    @property
    def pixel_size_mm(self) -> Tuple[float, float]:
        """Scan pixel size (x, y) in mm: lengths of the affine's columns."""
        A = self.affine[:, :2]
        return float(np.hypot(A[0, 0], A[1, 0])), float(np.hypot(A[0, 1], A[1, 1]))

    def pixel_to_fiducial(self, col: ArrayLike, row: ArrayLike) -> Tuple[Array, Array]:
        """Apply the affine: pixel → fiducial-frame mm."""
        col, row = np.asarray(col, dtype=float), np.asarray(row, dtype=float)
        A = self.affine
        return A[0, 0] * col + A[0, 1] * row + A[0, 2], A[1, 0] * col + A[1, 1] * row + A[1, 2]

    def to_dict(self) -> dict:
        """A JSON-friendly report (for logs and QC)."""
        return {
            "affine": self.affine.tolist(),
            "residuals_um": self.residuals_um.tolist(),
            "residuals_px": self.residuals_px.tolist(),
            "rms_um": self.rms_um,
            "rms_px": self.rms_px,
            "sigma0_um": self.sigma0_um,
            "pixel_size_mm": list(self.pixel_size_mm),
        }


def fit_fiducials(pixel_xy: ArrayLike, calibrated_mm: ArrayLike) -> FiducialFit:
    """Least-squares affine from measured fiducial marks to their calibrated positions.

    Parameters
    ----------
    pixel_xy : array_like, shape (n, 2)
        Measured mark positions in the scan, (col, row) px, pixel centres at integers.
    calibrated_mm : array_like, shape (n, 2)
        Calibrated positions (x, y) in mm from the camera's calibration certificate.

    Returns
    -------
    FiducialFit

    Raises
    ------
    InputError
        Fewer than 4 marks, mismatched shapes, non-finite values, or marks on one line.
    """
    px = np.asarray(pixel_xy, dtype=float)
    mm = np.asarray(calibrated_mm, dtype=float)
    if px.ndim != 2 or px.shape[1] != 2 or px.shape != mm.shape:
        raise InputError("Fiducial marks: give (n, 2) pixel positions and (n, 2) calibrated "
                         "positions in the same order.")
    n = px.shape[0]
    if n < 4:
        raise InputError(
            f"Interior orientation needs at least 4 fiducial marks, got {n}: an affine from 3 "
            "marks has no redundancy and no check. Measure more marks."
        )
    if not (np.isfinite(px).all() and np.isfinite(mm).all()):
        raise InputError("Fiducial marks contain missing (NaN) coordinates.")
    # centre and scale for conditioning; the design is the same for x and y
    centre = px.mean(axis=0)
    scale = max(float(np.abs(px - centre).max()), 1.0)
    u = (px - centre) / scale
    M = np.column_stack([u, np.ones(n)])
    if np.linalg.matrix_rank(M, tol=1e-9) < 3:
        raise InputError("The fiducial marks lie on one line; measure marks around the frame.")
    coef, *_ = np.linalg.lstsq(M, mm, rcond=None)  # (3, 2): rows u_col, u_row, 1
    # undo the conditioning: x = c0*(col-cc)/s + c1*(row-rc)/s + c2
    lin = coef[:2].T / scale  # (2, 2), rows x, y
    offset = coef[2] - lin @ centre
    affine = np.column_stack([lin, offset])
    fitted = px @ lin.T + offset
    v = fitted - mm
    v_px = v @ np.linalg.inv(lin).T
    dof = 2 * n - 6
    sigma0 = float(np.sqrt(np.sum(v ** 2) / dof) * 1000.0)
    return FiducialFit(affine=affine, residuals_mm=v, residuals_px=v_px, sigma0_um=sigma0)


def camera_from_fiducials(fit: FiducialFit, name: str, width: int, height: int,
                          focal_length: float,
                          principal_point: Tuple[float, float] = (0.0, 0.0),
                          base: Optional[Camera] = None, **distortion: float) -> Camera:
    """A :class:`Camera` for a scanned frame whose pixels map to mm by ``fit``.

    Parameters
    ----------
    fit : FiducialFit
    name, width, height, focal_length :
        Camera name, scan size (px) and calibrated principal distance (mm).
    principal_point : (float, float)
        Calibrated principal point (xp, yp) in mm **in the fiducial frame**.
    base : Camera, optional
        Copy distortion and other fields from this camera (``distortion`` keywords override).
    **distortion : float
        ``k1, k2, k3, p1, p2``.

    Notes
    -----
    ``pixel_size`` is set to the scan pixel size of the affine (used for GSD and the focal
    length in pixels); the pixel → mm relation itself is the affine.
    """
    affine = tuple(tuple(float(v) for v in r) for r in fit.affine)
    if base is not None:
        return dataclasses.replace(base, name=name, width=width, height=height,
                                   focal_length=focal_length, pixel_size=fit.pixel_size_mm,
                                   principal_point=principal_point, fiducial_affine=affine,
                                   **distortion)
    return Camera(name=name, width=width, height=height, focal_length=focal_length,
                  pixel_size=fit.pixel_size_mm, principal_point=principal_point,
                  fiducial_affine=affine, **distortion)  # type: ignore[arg-type]
