r"""The one conjugate-gradient solver of the core (ground floor: numpy and scipy only).

:func:`pcg` solves a symmetric positive definite system :math:`N x = b` by conjugate
gradients with the Jacobi (diagonal) preconditioner :math:`M = \mathrm{diag}(N)`:

.. math::

   r_0 = b - N x_0,\quad z_0 = M^{-1} r_0,\quad p_0 = z_0;\qquad
   \alpha_k = \frac{r_k^T z_k}{p_k^T N p_k},\quad x_{k+1} = x_k + \alpha_k p_k,\quad
   r_{k+1} = r_k - \alpha_k N p_k,

   z_{k+1} = M^{-1} r_{k+1},\quad \beta_k = \frac{r_{k+1}^T z_{k+1}}{r_k^T z_k},\quad
   p_{k+1} = z_{k+1} + \beta_k p_k,

until :math:`\|r\| \le \mathrm{tol}\,\|b\|` or ``max_iter`` iterations.

Instead of the diagonal, the caller may give any symmetric positive definite preconditioner
as a function :math:`r \mapsto M^{-1} r` (the FE plate passes a multigrid V-cycle).

Determinism
    Every inner product goes through a :class:`CGRule`'s ``dot``, never BLAS ``ddot``: BLAS
    kernels sum in an order that depends on the build and the thread count, and a last-bit
    difference in one product changes the iteration count and so the result. Both dots here
    give the same bits in every process (Python, CLI, QGIS).

Bits of the callers
    The object-space matching, the finite-element gridding and the linear-prediction filter
    each had their own copy of this solver, with small differences in the arithmetic. A
    :class:`CGRule` names each choice so that every caller keeps its exact results (their
    products, and the ``make bench`` figures, are compared bit for bit):
    :data:`CG_OBJECT_SPACE`, :data:`CG_FE` and :data:`CG_LP`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Callable, Optional, Tuple, Union

import numpy as np
from numpy.typing import NDArray

from .feedback import Feedback

Array = NDArray[Any]
#: A sparse (or dense) matrix, or a function v ↦ N v that returns a new array.
Operator = Union[Any, Callable[[Array], Array]]
#: An inverse diagonal (array), or a function r ↦ M⁻¹ r that returns a new array.
Preconditioner = Union[Array, Callable[[Array], Array]]


def dot_pairwise(a: Array, b: Array) -> float:
    """Σ a·b by numpy's pairwise summation (float64 vectors)."""
    return float(np.sum(a * b))


def dot_einsum(a: Array, b: Array) -> float:
    """Σ a·b by ``einsum``'s own loop with float64 accumulation (any float dtype or shape).

    No thread start-up per call (several times faster than BLAS on a busy machine), and
    float32 grids are summed in float64.
    """
    return float(np.einsum("i,i->", a.ravel(), b.ravel(), dtype=np.float64))


@dataclass(frozen=True)
class CGRule:
    """The arithmetic choices of :func:`pcg` (each keeps one caller's results bit-identical).

    Attributes
    ----------
    dot : callable
        Inner product, :func:`dot_pairwise` or :func:`dot_einsum`.
    norm_test : bool
        True: stop when ``sqrt(r·r) <= tol·sqrt(b·b)``; False: when ``r·r <= tol²·b·b``
        (the same test, other rounding).
    rhs_floor : float
        ``b·b`` enters the squared test as at least this (keeps the limit positive for b = 0).
    zero_rhs : bool
        Return the zero vector without iterating when ``b·b`` is 0 or, with the squared
        test, the limit tol²·b·b is 0 (else iterate from the start vector).
    start_test : bool
        Test the start residual before the first iteration (and return the start vector
        with 0 iterations when it passes); useful with a warm start.
    denominator_floor : float
        Lower bound of the denominators pᵀNp and rᵀz (0: none).
    check_every : int
        Call ``feedback.check()`` (cancellation) every this many iterations (0: never).
    """

    dot: Callable[[Array, Array], float] = dot_pairwise
    norm_test: bool = False
    rhs_floor: float = 0.0
    zero_rhs: bool = True
    start_test: bool = False
    denominator_floor: float = 0.0
    check_every: int = 0


#: Object-space matching: float64, pairwise dots, zero start, r·r ≤ tol²·b·b.
CG_OBJECT_SPACE = CGRule()
#: Finite-element gridding: warm starts (start residual tested), einsum dots, b·b ≥ 1e-300.
CG_FE = CGRule(dot=dot_einsum, rhs_floor=1e-300, zero_rhs=False, start_test=True,
               check_every=100)
#: Linear prediction: float32 grids with float64 dots, ‖r‖ ≤ tol·‖b‖, floored denominators.
CG_LP = CGRule(dot=dot_einsum, norm_test=True, denominator_floor=1e-300, check_every=1)


def jacobi(N: Any) -> Array:
    """Inverse diagonal of a matrix as Jacobi preconditioner; 1 where the diagonal is ≤ 0."""
    d = N.diagonal()
    return np.where(d > 0, 1.0 / np.where(d > 0, d, 1.0), 1.0)


def _as_function(op: Operator) -> Callable[[Array], Array]:
    """v ↦ N v for a matrix (anything with ``shape`` and ``@``) or a function."""
    if callable(op) and not hasattr(op, "shape"):
        return op
    return op.__matmul__


@dataclass(frozen=True)
class _Stop:
    """The convergence test of one solve: r·r (or its root) against a fixed limit."""

    limit: float
    norm_test: bool

    @classmethod
    def of(cls, bb: float, tol: float, rule: CGRule) -> _Stop:
        """The limit for ``b·b = bb`` and the relative tolerance ``tol``."""
        if rule.norm_test:
            return cls(tol * math.sqrt(bb), True)
        return cls(tol * tol * max(bb, rule.rhs_floor), False)

    def reached(self, rr: float) -> bool:
        """True when the residual with ``r·r = rr`` is small enough."""
        return (math.sqrt(rr) if self.norm_test else rr) <= self.limit


def _ratio(num: float, den: float, floor: float) -> float:
    """num / den, the denominator bounded below by ``floor`` when one is set."""
    return num / (max(den, floor) if floor else den)


def pcg(op: Operator, b: Array, minv: Preconditioner, x0: Optional[Array] = None, *, tol: float,
        max_iter: int, rule: CGRule = CG_OBJECT_SPACE, feedback: Optional[Feedback] = None
        ) -> Tuple[Array, int]:
    r"""Preconditioned conjugate gradients for an SPD system (see the module notes).

    Parameters
    ----------
    op : matrix or callable
        :math:`N`: a sparse or dense matrix, or a function ``v ↦ N v`` of vectors shaped like
        ``b`` that returns a new array (it is scaled in place).
    b : ndarray
        Right-hand side (float64, or float32 grids with ``rule.dot = dot_einsum``).
    minv : ndarray or callable
        Inverse diagonal :math:`M^{-1}` (:func:`jacobi` for a matrix), shaped like ``b``; or
        a function ``r ↦ M⁻¹ r`` returning a new array (any SPD preconditioner, e.g. a
        multigrid V-cycle).
    x0 : ndarray, optional
        Start vector, used as the iterate and overwritten; default zeros (then the first
        residual is ``b`` itself, no product).
    tol : float
        Relative residual :math:`\|r\|/\|b\|` to reach.
    max_iter : int
        Iterations at most (≥ 0).
    rule : CGRule
        Arithmetic choices; the default is :data:`CG_OBJECT_SPACE`.
    feedback : Feedback, optional
        Checked for cancellation every ``rule.check_every`` iterations.

    Returns
    -------
    x : ndarray
        The solution (``x0`` itself when one was given).
    iterations : int
        Iterations done (``max_iter`` when the tolerance was not reached).
    """
    dot = rule.dot
    matvec = _as_function(op)
    bb = dot(b, b)
    if rule.zero_rhs and bb == 0:
        return np.zeros_like(b), 0
    stop = _Stop.of(bb, tol, rule)
    if rule.zero_rhs and not rule.norm_test and stop.limit == 0.0:  # tol = 0 (or underflow)
        return np.zeros_like(b), 0
    x = np.zeros_like(b) if x0 is None else x0
    r = b.copy() if x0 is None else b - matvec(x)
    if rule.start_test and stop.reached(dot(r, r)):
        return x, 0
    return x, _iterate(matvec, x, r, minv, stop, max_iter, rule, feedback)


def _iterate(matvec: Callable[[Array], Array], x: Array, r: Array,
             minv: Preconditioner, stop: _Stop,
             max_iter: int, rule: CGRule, feedback: Optional[Feedback]) -> int:
    """The CG iterations from the residual ``r`` of ``x`` (both updated in place).

    Returns the number of iterations done. Step sizes are cast to the vectors' dtype, so
    float32 grids stay float32.
    """
    dot, floor, scalar = rule.dot, rule.denominator_floor, x.dtype.type
    precond = minv if callable(minv) else None
    z = precond(r) if precond is not None else minv * r
    p = z.copy()
    rz = dot(r, z)
    for it in range(1, max_iter + 1):
        if feedback is not None and rule.check_every and it % rule.check_every == 0:
            feedback.check()
        q = matvec(p)
        alpha = scalar(_ratio(rz, dot(p, q), floor))
        x += alpha * p  # in place where possible: grids of 16 M cells
        q *= alpha
        r -= q
        if stop.reached(dot(r, r)):
            return it
        if precond is not None:
            z = precond(r)
        else:
            np.multiply(minv, r, out=z)
        rz_new = dot(r, z)
        p *= scalar(_ratio(rz_new, rz, floor))
        p += z
        rz = rz_new
    return max_iter


__all__ = [
    "CG_FE",
    "CG_LP",
    "CG_OBJECT_SPACE",
    "CGRule",
    "dot_einsum",
    "dot_pairwise",
    "jacobi",
    "pcg",
]
