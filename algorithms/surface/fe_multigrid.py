r"""A geometric multigrid V-cycle as the preconditioner of the FE plate's conjugate gradients.

Why
    The plate's normal matrix is a thin-plate (biharmonic) stencil plus the point weights:
    with the Jacobi preconditioner its condition grows as the fourth power of the gap sizes,
    CG needs thousands of iterations, and the relative-residual test stops while smooth,
    long-wavelength errors (centimetres to decimetres in gaps) are still in the solution.
    A V-cycle removes the error on every scale in each iteration, so CG converges in a few
    tens of iterations and a tight tolerance costs little.

Levels
    Node grids coarsened by 2 per side down to ≤ ``coarsest`` nodes per side (then sparse LU).
    The prolongation :math:`P` is bilinear (fine node *i* at coarse coordinate
    :math:`i/2 - 1/4`, as the cascade's ``_prolong``), extrapolated linearly on the outer
    half cells so that planes stay exact up to the border; rows of
    fine nodes that are not unknowns are zero, so the correction never touches them. The
    coarse matrices are Galerkin products :math:`P^T N P` (breaklines, exclusions and weights
    carry over without rediscretising); a coarse node without any fine unknown gets a unit
    diagonal and stays zero.

Smoother
    Chebyshev polynomials in :math:`D^{-1}N` on :math:`[λ_{max}/ \text{ratio}, λ_{max}]`
    (Gershgorin's bound, which is sharp for the biharmonic stencil): only products with the
    matrix, and the same polynomial before and after the coarse correction, so the V-cycle is
    a symmetric positive definite operator, as conjugate gradients require.
"""

from __future__ import annotations

from typing import Any, List, Tuple

import numpy as np
from numpy.typing import NDArray
from scipy import sparse
from scipy.sparse.linalg import splu

Array = NDArray[Any]


def _prolong_1d(n_fine: int, n_coarse: int) -> Any:
    """Linear prolongation along one axis (fine node i at coarse coordinate i/2 − ¼).

    The outer half cells extrapolate linearly (weights 1¼, −¼), so that planes, which the
    plate does not penalise, are exactly in the coarse grids' range up to the border.
    """
    i = np.arange(n_fine)
    k = np.minimum(i // 2, n_coarse - 1)
    side = np.where(i % 2 == 0, -1, 1)  # the second coarse node: towards the fine node
    other = k + side
    outside = (other < 0) | (other > n_coarse - 1)
    other = np.where(outside, k - side, other)  # extrapolate from the inner neighbour
    w_k = np.where(outside, 1.25, 0.75)
    w_other = np.where(outside, -0.25, 0.25)
    if n_coarse == 1:  # a single coarse node: constant
        other, w_k, w_other = k, np.ones(n_fine), np.zeros(n_fine)
    rows = np.r_[i, i]
    cols = np.r_[k, other]
    return sparse.csr_matrix((np.r_[w_k, w_other], (rows, cols)), shape=(n_fine, n_coarse))


def prolongation(shape: Tuple[int, int], keep: Array) -> Tuple[Any, Tuple[int, int], Array]:
    """Prolongation from the grid coarsened by 2 to ``shape``, zero on rows not in ``keep``.

    Parameters
    ----------
    shape : (int, int)
        Fine node grid (rows, columns); nodes flattened row by row.
    keep : ndarray of bool, flat
        Fine nodes that take part (the unknowns).

    Returns
    -------
    P : sparse matrix (n_fine, n_coarse), CSR
    coarse_shape : (int, int)
    coarse_keep : ndarray of bool, flat
        Coarse nodes that reach at least one fine node of ``keep``.
    """
    h, w = shape
    hc, wc = (h + 1) // 2, (w + 1) // 2
    P = sparse.kron(_prolong_1d(h, hc), _prolong_1d(w, wc), format="csr")
    P = sparse.diags(keep.astype(float)) @ P
    P.eliminate_zeros()
    coarse_keep = np.diff(P.tocsc().indptr) > 0
    return P.tocsr(), (hc, wc), coarse_keep


class _Smoother:
    """Chebyshev smoothing in D⁻¹A on [λmax/ratio, λmax] (a fixed polynomial: symmetric)."""

    def __init__(self, A: Any, degree: int, ratio: float) -> None:
        d = A.diagonal()
        self.A, self.degree = A, int(degree)
        self.dinv = np.where(d > 0, 1.0 / np.where(d > 0, d, 1.0), 0.0)
        lmax = 1.05 * float(np.max(abs(A) @ np.ones(A.shape[0]) * self.dinv))
        lmin = lmax / ratio
        self.theta, self.delta = 0.5 * (lmax + lmin), 0.5 * (lmax - lmin)

    def __call__(self, b: Array, x: Array, zero_start: bool) -> Array:
        """``degree`` Chebyshev steps for A x = b from ``x`` (updated in place)."""
        r = b.copy() if zero_start else b - self.A @ x
        sigma = self.theta / self.delta
        rho = 1.0 / sigma
        d = self.dinv * r / self.theta
        for k in range(self.degree):
            x += d
            if k == self.degree - 1:
                break
            r -= self.A @ d
            rho_new = 1.0 / (2.0 * sigma - rho)
            d *= rho_new * rho
            d += (2.0 * rho_new / self.delta) * self.dinv * r
            rho = rho_new
        return x


class VCycle:
    """One V-cycle as the preconditioner z = M⁻¹ r of a node-grid system (module notes).

    Parameters
    ----------
    A : sparse matrix
        The SPD normal matrix of all nodes of ``shape`` (flattened row by row).
    shape : (int, int)
        The node grid.
    keep : ndarray of bool, flat
        The unknowns; other nodes are decoupled (z = 0 there).
    coarsest : int
        Nodes per side at or below which the level is solved directly.
    degree, ratio : int, float
        Chebyshev smoother: steps before and after the coarse correction, eigenvalue range.
    """

    def __init__(self, A: Any, shape: Tuple[int, int], keep: Array, coarsest: int = 64,
                 degree: int = 3, ratio: float = 20.0) -> None:
        self.mats: List[Any] = [A.tocsr()]
        self.prolongs: List[Any] = []
        self.smoothers: List[_Smoother] = []
        self.keep = keep.astype(bool)
        keep_k = self.keep
        while max(shape) > coarsest:
            P, shape, keep_k = prolongation(shape, keep_k)
            self.smoothers.append(_Smoother(self.mats[-1], degree, ratio))
            Ac = (P.T @ self.mats[-1] @ P).tocsr()
            # coarse nodes without fine unknowns: unit diagonal (their correction stays 0)
            self.mats.append((Ac + sparse.diags((~keep_k).astype(float))).tocsr())
            self.prolongs.append(P)
        self.lu = splu(self.mats[-1].tocsc(), permc_spec="MMD_AT_PLUS_A")

    @property
    def levels(self) -> int:
        """Number of grids (the finest included)."""
        return len(self.mats)

    def __call__(self, r: Array) -> Array:
        """z = M⁻¹ r (a new array; zero at nodes that are not unknowns)."""
        z = self._cycle(0, np.where(self.keep, r, 0.0))
        z[~self.keep] = 0.0
        return z

    def _cycle(self, k: int, b: Array) -> Array:
        if k == len(self.prolongs):
            return self.lu.solve(b)
        A, P, smooth = self.mats[k], self.prolongs[k], self.smoothers[k]
        x = smooth(b, np.zeros_like(b), zero_start=True)
        x += P @ self._cycle(k + 1, P.T @ (b - A @ x))
        return smooth(b, x, zero_start=False)


__all__ = ["VCycle", "prolongation"]
