r"""Exterior orientation: rotation conventions and angle units.

PhotoDEM's internal convention is PATB: the rotation matrix :math:`R` turns camera coordinates
into world coordinates, :math:`X = C + R\,p`, with

.. math:: R = R_x(\omega)\,R_y(\varphi)\,R_z(\kappa)

and camera axes x right, y up, z backwards (the camera looks along −z). OpenSfM (and OpenCV)
store the world→camera rotation as an axis-angle vector with camera axes x right, y down,
z forward; :func:`opensfm_to_patb` converts.

Angle units are always explicit: ``"degrees"``, ``"gon"`` or ``"radians"``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Tuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InputError

ANGLE_UNITS = ("degrees", "gon", "radians")
_PER_RADIAN = {"degrees": 180.0 / np.pi, "gon": 200.0 / np.pi, "radians": 1.0}
#: camera frame flip between PATB (y up, z back) and OpenCV/OpenSfM (y down, z forward)
FLIP_YZ = np.diag([1.0, -1.0, -1.0])


def check_angle_unit(unit: str) -> str:
    """Return ``unit`` if it is one of :data:`ANGLE_UNITS`, else raise :class:`InputError`."""
    if unit not in _PER_RADIAN:
        raise InputError(f"Unknown angle unit '{unit}'; use one of {', '.join(ANGLE_UNITS)}.")
    return unit


def to_radians(angles: ArrayLike, unit: str) -> NDArray[np.float64]:
    """Convert angles from ``unit`` to radians."""
    return np.asarray(angles, dtype=float) / _PER_RADIAN[check_angle_unit(unit)]


def from_radians(angles: ArrayLike, unit: str) -> NDArray[np.float64]:
    """Convert angles from radians to ``unit``."""
    return np.asarray(angles, dtype=float) * _PER_RADIAN[check_angle_unit(unit)]


def opk_to_matrix(omega: ArrayLike, phi: ArrayLike, kappa: ArrayLike,
                  unit: str = "degrees") -> NDArray[np.float64]:
    r"""Rotation matrices :math:`R = R_x(\omega) R_y(\varphi) R_z(\kappa)` (camera→world).

    Parameters
    ----------
    omega, phi, kappa : float or array_like
        Angles in ``unit``; arrays broadcast against each other.
    unit : {"degrees", "gon", "radians"}

    Returns
    -------
    ndarray, shape (..., 3, 3)
    """
    w, p, k = np.broadcast_arrays(*(to_radians(a, unit) for a in (omega, phi, kappa)))
    cw, sw, cp, sp, ck, sk = np.cos(w), np.sin(w), np.cos(p), np.sin(p), np.cos(k), np.sin(k)
    R = np.empty(w.shape + (3, 3))
    R[..., 0, 0] = cp * ck
    R[..., 0, 1] = -cp * sk
    R[..., 0, 2] = sp
    R[..., 1, 0] = cw * sk + sw * sp * ck
    R[..., 1, 1] = cw * ck - sw * sp * sk
    R[..., 1, 2] = -sw * cp
    R[..., 2, 0] = sw * sk - cw * sp * ck
    R[..., 2, 1] = sw * ck + cw * sp * sk
    R[..., 2, 2] = cw * cp
    return R


def matrix_to_opk(R: ArrayLike, unit: str = "degrees") -> NDArray[np.float64]:
    r"""Angles (ω, φ, κ) of camera→world rotation matrices, inverse of :func:`opk_to_matrix`.

    :math:`\varphi = \arcsin R_{02}`, :math:`\omega = \operatorname{atan2}(-R_{12}, R_{22})`,
    :math:`\kappa = \operatorname{atan2}(-R_{01}, R_{00})`; φ is in [−90°, 90°].

    Returns
    -------
    ndarray, shape (..., 3)
        ω, φ, κ in ``unit``.
    """
    R = np.asarray(R, dtype=float)
    phi = np.arcsin(np.clip(R[..., 0, 2], -1.0, 1.0))
    omega = np.arctan2(-R[..., 1, 2], R[..., 2, 2])
    kappa = np.arctan2(-R[..., 0, 1], R[..., 0, 0])
    return from_radians(np.stack([omega, phi, kappa], axis=-1), unit)


def axis_angle_to_matrix(rotvec: ArrayLike) -> NDArray[np.float64]:
    r"""Rodrigues' formula: :math:`R = I + \sin\theta\,K + (1-\cos\theta)\,K^2`.

    Parameters
    ----------
    rotvec : array_like, shape (..., 3)
        Rotation axis times angle in radians.
    """
    v = np.asarray(rotvec, dtype=float)
    theta = np.linalg.norm(v, axis=-1)[..., None, None]
    safe = np.where(theta > 1e-15, theta, 1.0)
    k = v / safe[..., 0]
    K = np.zeros(v.shape[:-1] + (3, 3))
    K[..., 0, 1], K[..., 0, 2] = -k[..., 2], k[..., 1]
    K[..., 1, 0], K[..., 1, 2] = k[..., 2], -k[..., 0]
    K[..., 2, 0], K[..., 2, 1] = -k[..., 1], k[..., 0]
    eye = np.broadcast_to(np.eye(3), K.shape)
    return eye + np.sin(theta) * K + (1.0 - np.cos(theta)) * (K @ K)


def matrix_to_axis_angle(R: ArrayLike) -> NDArray[np.float64]:
    """Axis-angle vector (radians) of rotation matrices; inverse of :func:`axis_angle_to_matrix`."""
    R = np.asarray(R, dtype=float)
    cos_t = np.clip((np.trace(R, axis1=-2, axis2=-1) - 1.0) / 2.0, -1.0, 1.0)
    theta = np.arccos(cos_t)
    w = np.stack([R[..., 2, 1] - R[..., 1, 2], R[..., 0, 2] - R[..., 2, 0],
                  R[..., 1, 0] - R[..., 0, 1]], axis=-1)
    sin_t = np.sin(theta)
    small = sin_t < 1e-6
    scale = np.where(small, 0.5, theta / (2.0 * np.where(small, 1.0, sin_t)))
    out = w * scale[..., None]
    # near 180° the antisymmetric part vanishes: take the axis from R + I instead
    near_pi = small & (cos_t < 0)
    if np.any(near_pi):
        B = (R[near_pi] + np.eye(3)) / 2.0
        idx = np.argmax(np.diagonal(B, axis1=-2, axis2=-1), axis=-1)
        axis = B[np.arange(len(idx)), :, idx]
        axis /= np.linalg.norm(axis, axis=-1, keepdims=True)
        out[near_pi] = axis * theta[near_pi][..., None]
    return out


@dataclass(frozen=True)
class ExteriorOrientation:
    """Projection centre and camera→world rotation (PATB) of one image.

    Attributes
    ----------
    position : ndarray, shape (3,)
        Projection centre X0, Y0, Z0 in the project CRS (m).
    rotation : ndarray, shape (3, 3)
        Camera→world rotation, x right, y up, z backwards.
    """

    position: NDArray[np.float64]
    rotation: NDArray[np.float64]

    def __post_init__(self) -> None:
        object.__setattr__(self, "position", np.asarray(self.position, dtype=float).reshape(3))
        object.__setattr__(self, "rotation", np.asarray(self.rotation, dtype=float).reshape(3, 3))

    @classmethod
    def from_opk(cls, position: ArrayLike, omega: float, phi: float, kappa: float,
                 unit: str = "degrees") -> ExteriorOrientation:
        """From PATB angles in ``unit``."""
        return cls(np.asarray(position, dtype=float), opk_to_matrix(omega, phi, kappa, unit))

    def opk(self, unit: str = "degrees") -> Tuple[float, float, float]:
        """PATB angles (ω, φ, κ) in ``unit``."""
        w, p, k = matrix_to_opk(self.rotation, unit)
        return float(w), float(p), float(k)

    @property
    def viewing_direction(self) -> NDArray[np.float64]:
        """Unit vector of the optical axis in world coordinates (camera −z)."""
        return -self.rotation[:, 2]

    def to_opensfm(self) -> Tuple[NDArray[np.float64], NDArray[np.float64]]:
        """OpenSfM ``(rotation, translation)``: world→camera axis-angle and t = −R_wc·C."""
        R_wc = FLIP_YZ @ self.rotation.T
        return matrix_to_axis_angle(R_wc), -R_wc @ self.position


def opensfm_to_patb(rotation: ArrayLike, translation: ArrayLike) -> ExteriorOrientation:
    r"""Convert an OpenSfM shot pose to PATB.

    OpenSfM maps world to camera (x right, y down, z forward) by
    :math:`x_c = R_{wc} X + t` with :math:`R_{wc}` from the axis-angle ``rotation``. Hence the
    centre is :math:`C = -R_{wc}^T t` and the PATB rotation :math:`R = R_{wc}^T\,F` with
    :math:`F = \mathrm{diag}(1, -1, -1)`.
    """
    R_wc = axis_angle_to_matrix(rotation)
    t = np.asarray(translation, dtype=float)
    return ExteriorOrientation(-R_wc.T @ t, R_wc.T @ FLIP_YZ)
