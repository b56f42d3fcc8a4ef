"""The one conjugate-gradient solver: closed forms, the three rules, determinism."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import sparse
from scipy.sparse.linalg import spsolve

from photodem.algorithms.errors import Cancelled
from photodem.algorithms.feedback import Feedback
from photodem.algorithms.linalg import (
    CG_FE,
    CG_LP,
    CG_OBJECT_SPACE,
    CGRule,
    dot_einsum,
    dot_pairwise,
    jacobi,
    pcg,
)

RULES = [CG_OBJECT_SPACE, CG_FE, CG_LP]


def _spd(n: int, seed: int = 0) -> sparse.csr_matrix:
    """A sparse symmetric positive definite n × n matrix with a varied diagonal."""
    rng = np.random.default_rng(seed)
    A = sparse.random(3 * n, n, density=0.05, random_state=seed, format="csr") \
        + sparse.eye(3 * n, n, format="csr")
    return (A.T @ A + sparse.diags(rng.uniform(0.1, 5.0, n))).tocsr()


def test_dots_are_the_inner_product() -> None:
    a, b = np.arange(7.0), np.linspace(-1, 1, 7)
    assert dot_pairwise(a, b) == pytest.approx(float(a @ b))
    assert dot_einsum(a.astype(np.float32).reshape(7, 1), b.astype(np.float32)) \
        == pytest.approx(float(a @ b), rel=1e-6)


@pytest.mark.parametrize("rule", RULES)
def test_small_spd_system_equals_the_closed_form(rule: CGRule) -> None:
    # 3 × 3 by hand: N x = b with x = (1, −2, 3)
    N = sparse.csr_matrix(np.array([[4.0, 1.0, 0.0], [1.0, 3.0, -1.0], [0.0, -1.0, 2.0]]))
    x_true = np.array([1.0, -2.0, 3.0])
    b = N @ x_true
    x, it = pcg(N, b, jacobi(N), tol=1e-14, max_iter=50, rule=rule)
    assert np.allclose(x, x_true, atol=1e-12) and 0 < it <= 3 + 2


@pytest.mark.parametrize("rule", RULES)
def test_equals_the_direct_solution(rule: CGRule) -> None:
    N = _spd(150)
    b = np.random.default_rng(1).standard_normal(150)
    x, it = pcg(N, b, jacobi(N), tol=1e-12, max_iter=1000, rule=rule, feedback=Feedback())
    assert np.allclose(x, np.linalg.solve(N.toarray(), b), atol=1e-8) and 0 < it < 400
    assert np.allclose(x, spsolve(N.tocsc(), b), atol=1e-8)


def test_warm_start_and_function_operator() -> None:
    N = _spd(80, seed=2)
    b = np.random.default_rng(3).standard_normal(80)
    exact = np.linalg.solve(N.toarray(), b)
    # a start at the solution passes the start test at once (FE rule)
    x, it = pcg(N, b, jacobi(N), exact.copy(), tol=1e-6, max_iter=100, rule=CG_FE)
    assert it == 0 and np.array_equal(x, exact)
    # a function v ↦ N v gives the same bits as the matrix
    x1, it1 = pcg(N, b, jacobi(N), tol=1e-10, max_iter=500)
    x2, it2 = pcg(lambda v: N @ v, b, jacobi(N), tol=1e-10, max_iter=500)
    assert it1 == it2 and np.array_equal(x1, x2)


def test_float32_grids_stay_float32() -> None:
    N = _spd(64, seed=4)
    b = np.random.default_rng(5).standard_normal(64).astype(np.float32).reshape(8, 8)
    N32 = N.astype(np.float32)
    minv = (1.0 / N.diagonal()).astype(np.float32).reshape(8, 8)

    def matvec(v: np.ndarray) -> np.ndarray:
        return (N32 @ v.ravel()).reshape(v.shape).astype(np.float32)

    x, it = pcg(matvec, b, minv, np.zeros_like(b), tol=1e-5, max_iter=200, rule=CG_LP)
    assert x.dtype == np.float32 and x.shape == (8, 8) and it > 0
    assert np.allclose(x.ravel(), np.linalg.solve(N.toarray(), b.ravel()), atol=1e-3)


@pytest.mark.parametrize("rule", RULES)
def test_zero_right_hand_side(rule: CGRule) -> None:
    N = _spd(20)
    x, it = pcg(N, np.zeros(20), jacobi(N), tol=1e-8, max_iter=10, rule=rule)
    assert it == 0 and not x.any()


def test_iteration_limit_and_guarded_diagonal() -> None:
    N = _spd(200, seed=6)
    b = np.ones(200)
    _, it = pcg(N, b, jacobi(N), tol=1e-14, max_iter=3)
    assert it == 3
    assert np.array_equal(jacobi(sparse.diags(np.array([2.0, 0.0, -1.0]))), [0.5, 1.0, 1.0])


def test_deterministic_bits() -> None:
    """The same system gives the same bits every time (no BLAS in the dot products)."""
    N = _spd(300, seed=7)
    b = np.random.default_rng(8).standard_normal(300)
    for rule in RULES:
        runs = [pcg(N, b.copy(), jacobi(N), np.zeros(300), tol=1e-10, max_iter=1000,
                    rule=rule) for _ in range(3)]
        assert all(r[1] == runs[0][1] and np.array_equal(r[0], runs[0][0]) for r in runs)


def test_cancellation_is_checked() -> None:
    fb = Feedback()
    fb.cancel()
    N = _spd(50)
    with pytest.raises(Cancelled):
        pcg(N, np.ones(50), jacobi(N), tol=1e-14, max_iter=10, rule=CG_LP, feedback=fb)
