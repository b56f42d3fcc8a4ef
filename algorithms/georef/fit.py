"""The final image → map transform from control points (seed-001 §2.16).

Affine (6 parameters, default), projective (8) or second-order polynomial (12), by least squares
on normalised coordinates. Normal equations are summed with ``einsum`` and solved as small
dense systems, so the result is the same in every environment (no BLAS-dependent sums).
Robust step (optional): the point with the largest residual is dropped while it exceeds
``k·σ0`` (iterative max-residual removal, as in ARMIES). Residuals in map units and in image
pixels (map residual divided by the pixel size √|det A| of the affine part); leave-one-out
residuals by refitting without each point.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Dict, List, Optional, Tuple

import numpy as np
from numpy.typing import NDArray

from .correspondence import apply

KINDS = ("affine", "projective", "poly2")
MIN_POINTS = {"affine": 3, "projective": 4, "poly2": 6}


def _normaliser(p: NDArray[np.float64]) -> NDArray[np.float64]:
    m = p.mean(axis=0)
    s = float(np.sqrt(np.mean(np.sum((p - m) ** 2, axis=1)))) or 1.0
    return np.array([[1 / s, 0, -m[0] / s], [0, 1 / s, -m[1] / s], [0, 0, 1.0]])


def _h(p: NDArray[np.float64], N: NDArray[np.float64]) -> NDArray[np.float64]:
    return p * N[0, 0] + N[:2, 2]


def _solve(A: NDArray[np.float64], b: NDArray[np.float64]) -> NDArray[np.float64]:
    N = np.einsum("ki,kj->ij", A, A)
    rhs = np.einsum("ki,k->i", A, b)
    if np.linalg.cond(N) > 1e12:
        raise ValueError("degenerate control point geometry")
    return np.linalg.solve(N, rhs)


def _poly_terms(p: NDArray[np.float64]) -> NDArray[np.float64]:
    x, y = p[:, 0], p[:, 1]
    return np.column_stack([np.ones_like(x), x, y, x * x, x * y, y * y])


def fit_matrix(src: NDArray[np.float64], dst: NDArray[np.float64], kind: str = "affine"
               ) -> NDArray[np.float64]:
    """3 × 3 affine or projective src → dst by least squares (normalised coordinates)."""
    src = np.asarray(src, float)
    dst = np.asarray(dst, float)
    if len(src) < MIN_POINTS.get(kind, 3):
        raise ValueError("too few points")
    Ns, Nd = _normaliser(src), _normaliser(dst)
    a, b = _h(src, Ns), _h(dst, Nd)
    one = np.ones(len(a))
    if kind == "affine":
        A = np.column_stack([a[:, 0], a[:, 1], one])
        px, py = _solve(A, b[:, 0]), _solve(A, b[:, 1])
        M = np.array([px, py, [0.0, 0.0, 1.0]])
    elif kind == "projective":
        # linearised DLT with h33 = 1: x' (h31 x + h32 y + 1) = h11 x + h12 y + h13
        z = np.zeros(len(a))
        Ax = np.column_stack([a[:, 0], a[:, 1], one, z, z, z, -a[:, 0] * b[:, 0],
                              -a[:, 1] * b[:, 0]])
        Ay = np.column_stack([z, z, z, a[:, 0], a[:, 1], one, -a[:, 0] * b[:, 1],
                              -a[:, 1] * b[:, 1]])
        h = _solve(np.vstack([Ax, Ay]), np.concatenate([b[:, 0], b[:, 1]]))
        M = np.array([h[0:3], h[3:6], [h[6], h[7], 1.0]])
    else:
        raise ValueError(f"unknown transform '{kind}'")
    return np.linalg.inv(Nd) @ M @ Ns


@dataclass
class TransformFit:
    """A fitted image → map transform and its quality."""

    kind: str
    matrix: Optional[NDArray[np.float64]]  # 3 × 3 for affine / projective
    poly: Optional[Tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]]
    pixel_size: float  # √|det| of the affine part (map units per pixel)
    residuals_map: NDArray[np.float64]  # (n, 2) fitted − measured, map units (used points)
    used: NDArray[np.bool_]
    loo_map: NDArray[np.float64]  # leave-one-out residual length (map units), used points
    sigma0: float
    extras: Dict[str, Any] = field(default_factory=dict)

    def forward(self, xy: NDArray[np.float64]) -> NDArray[np.float64]:
        """Image (col, row) → map."""
        xy = np.asarray(xy, float)
        if self.matrix is not None:
            return apply(self.matrix, xy)
        Ns, Nd, coef = self.poly
        t = _poly_terms(_h(xy, Ns))
        out = np.column_stack([np.einsum("ki,i->k", t, coef[0]),
                               np.einsum("ki,i->k", t, coef[1])])
        return (out - Nd[:2, 2]) / Nd[0, 0]  # undo the normalisation of the map side

    @property
    def rmse_map(self) -> float:
        return rmse(self.residuals_map)

    @property
    def rmse_px(self) -> float:
        return self.rmse_map / self.pixel_size


def _fit_once(img: NDArray[np.float64], mp: NDArray[np.float64], kind: str) -> TransformFit:
    if kind in ("affine", "projective"):
        M = fit_matrix(img, mp, kind)
        fit = TransformFit(kind, M, None, float(np.sqrt(abs(np.linalg.det(M[:2, :2])))),
                           np.zeros((0, 2)), np.ones(len(img), bool), np.zeros(0), 0.0)
    elif kind == "poly2":
        if len(img) < MIN_POINTS["poly2"]:
            raise ValueError("too few points")
        Ns, Nd = _normaliser(img), _normaliser(mp)
        t = _poly_terms(_h(img, Ns))
        b = _h(mp, Nd)
        coef = (_solve(t, b[:, 0]), _solve(t, b[:, 1]))
        A = fit_matrix(img, mp, "affine")
        fit = TransformFit(kind, None, (Ns, Nd, coef),
                           float(np.sqrt(abs(np.linalg.det(A[:2, :2])))), np.zeros((0, 2)),
                           np.ones(len(img), bool), np.zeros(0), 0.0)
    else:
        raise ValueError(f"unknown transform '{kind}'; use one of {', '.join(KINDS)}")
    return fit


def fit_transform(image_xy: NDArray[np.float64], map_xy: NDArray[np.float64],
                  kind: str = "affine", robust: bool = True, k: float = 3.0,
                  max_drop: float = 0.2, enabled: Optional[NDArray[np.bool_]] = None
                  ) -> TransformFit:
    """Fit the image → map transform to control points.

    Parameters
    ----------
    kind : {"affine", "projective", "poly2"}
    robust : bool
        Drop the largest residual while it exceeds ``k·σ0`` (at most ``max_drop`` of the
        points).
    enabled : array of bool, optional
        The points that may take part (default: all). The others are check points: they get
        residuals (in ``extras["all_residuals_map"]``) but do not influence the fit.
    """
    img = np.asarray(image_xy, float)
    mp = np.asarray(map_xy, float)
    n = len(img)
    used = np.ones(n, bool) if enabled is None else np.asarray(enabled, bool).copy()
    n_enabled = int(used.sum())
    npar = {"affine": 6, "projective": 8, "poly2": 12}.get(kind, 6)
    while True:
        fit = _fit_once(img[used], mp[used], kind)
        res = fit.forward(img) - mp
        dist = np.hypot(res[:, 0], res[:, 1])
        dof = max(2 * int(used.sum()) - npar, 1)
        sigma0 = float(np.sqrt(np.sum(dist[used] ** 2) / dof))
        if not robust or n_enabled - int(used.sum()) + 1 > max_drop * n_enabled:
            break
        worst = int(np.argmax(np.where(used, dist, -1.0)))
        if dist[worst] <= k * sigma0 or used.sum() - 1 < MIN_POINTS[kind] + 2:
            break
        used[worst] = False
    loo = np.full(n, np.nan)
    idx = np.nonzero(used)[0]
    if len(idx) > MIN_POINTS[kind] + 1:
        for i in idx:
            keep = used.copy()
            keep[i] = False
            try:
                f = _fit_once(img[keep], mp[keep], kind)
                loo[i] = float(np.hypot(*(f.forward(img[i:i + 1]) - mp[i:i + 1])[0]))
            except (ValueError, np.linalg.LinAlgError):
                pass
    fit.residuals_map = res[used]
    fit.used = used
    fit.loo_map = loo
    fit.sigma0 = sigma0
    fit.extras = {"all_residuals_map": res}
    return fit


def inverse_for_resampling(fit: TransformFit, img: NDArray[np.float64],
                           map_xy: NDArray[np.float64]) -> Optional[TransformFit]:
    """The map → image transform a poly2 ``fit`` needs for resampling (it has no closed
    inverse): a poly2 fitted the other way on the points given; ``None`` for the kinds with
    a matrix, whose inverse is exact."""
    if fit.kind != "poly2":
        return None
    return fit_transform(map_xy, img, "poly2", robust=False)


def centre_matrix(transform: Any) -> NDArray[np.float64]:
    """3 × 3 image → map matrix of a raster's geotransform (a rasterio ``Affine``), with the
    project's pixel convention: pixel centres at integer (col, row)."""
    t = transform
    return np.array([[t.a, t.b, t.c + 0.5 * (t.a + t.b)], [t.d, t.e, t.f + 0.5 * (t.d + t.e)],
                     [0.0, 0.0, 1.0]])


def corner_error(matrix_or_fit: Any, truth: NDArray[np.float64], width: int, height: int
                 ) -> NDArray[np.float64]:
    """Distance (image pixels) between the image corners mapped by the recovered and by the
    true image → map transform, measured back in the image by the true one."""
    corners = np.array([[-0.5, -0.5], [width - 0.5, -0.5], [-0.5, height - 0.5],
                        [width - 0.5, height - 0.5]])
    if isinstance(matrix_or_fit, TransformFit):
        mapped = matrix_or_fit.forward(corners)
    else:
        mapped = apply(np.asarray(matrix_or_fit, float), corners)
    back = apply(np.linalg.inv(truth), mapped)
    return np.hypot(*(back - corners).T)


def rmse(residuals: NDArray[np.float64]) -> float:
    """Root mean square length of (n, 2) residual vectors (NaN without any)."""
    r = np.asarray(residuals, float).reshape(-1, 2)
    return float(np.sqrt(np.mean(np.sum(r * r, axis=1)))) if len(r) else float("nan")


def residual_fields(r: NDArray[np.float64], pixel_size: float) -> Dict[str, float]:
    """One point's residual (fitted − measured, map units) as the reports give it: dx, dy,
    length in map units and in pixels.

    Rounded to 1e-4 map units and 1e-5 px: a residual is the difference of two map coordinates
    (10⁵–10⁶ m in a projected CRS), so digits below about 1e-9 m are round-off and differ
    between builds of the numerical libraries.
    """
    d = float(np.hypot(*r))
    return {"dx_map": round(float(r[0]), 4), "dy_map": round(float(r[1]), 4),
            "residual_map": round(d, 4), "residual_px": round(d / pixel_size, 5)}


def points_summary(fit: TransformFit) -> List[Dict[str, float]]:
    """Per point: residuals (map, px; :func:`residual_fields`), leave-one-out, used flag."""
    res = fit.extras["all_residuals_map"]
    return [{**residual_fields(r, fit.pixel_size), "loo_map": round(float(fit.loo_map[k]), 4),
             "used": bool(u)} for k, (r, u) in enumerate(zip(res, fit.used))]
