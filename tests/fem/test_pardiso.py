"""MKL PARDISO through ctypes: answers for every matrix type, pattern reuse, errors.

Skipped where the MKL runtime is not installed (``pip install hapticrom[mkl]``); the development
and CI environments install it."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from fem import pardiso

pytestmark = pytest.mark.skipif(not pardiso.available(), reason="MKL runtime not installed")


def _laplacian(n: int) -> sp.csr_matrix:
    main = sp.diags([2.0 * np.ones(n), -np.ones(n - 1), -np.ones(n - 1)], [0, -1, 1])
    return sp.csr_matrix(sp.kron(main, sp.eye(n)) + sp.kron(sp.eye(n), main))


def _residual(A, x, b) -> float:
    return float(np.abs(A @ x - b).max() / np.abs(b).max())


def test_matrix_types_and_answers():
    A = _laplacian(15)
    n = A.shape[0]
    rng = np.random.default_rng(1)
    b = rng.normal(size=n)
    spd = pardiso.PardisoFactorization(A)
    assert spd.mtype == pardiso.REAL_SPD
    assert _residual(A, spd.solve(b), b) < 1e-12
    # shifted past the smallest eigenvalue: indefinite, Cholesky fails, L D L^T takes over
    indefinite = A - 1.0 * sp.eye(n)
    fac = pardiso.PardisoFactorization(indefinite)
    assert fac.mtype == pardiso.REAL_SYMMETRIC_INDEFINITE
    assert _residual(indefinite, fac.solve(b), b) < 1e-10
    # complex symmetric (not Hermitian): a lossy, PML-like shift
    Z = sp.csr_matrix(A - (1.0 - 0.4j) * sp.eye(n))
    cz = pardiso.PardisoFactorization(Z)
    assert cz.mtype == pardiso.COMPLEX_SYMMETRIC
    bz = b + 1j * rng.normal(size=n)
    x = cz.solve(bz)
    assert _residual(Z, x, bz) < 1e-12
    np.testing.assert_allclose(x, sp.linalg.spsolve(sp.csc_matrix(Z), bz), rtol=1e-10)
    assert cz.factor_nnz >= sp.triu(Z).nnz


def test_several_right_hand_sides_and_complex_rhs_on_real_matrix():
    A = _laplacian(10)
    fac = pardiso.PardisoFactorization(A)
    B = np.random.default_rng(2).normal(size=(A.shape[0], 3))
    X = fac.solve(B)
    assert X.shape == B.shape
    for j in range(3):
        np.testing.assert_allclose(X[:, j], fac.solve(B[:, j]), rtol=1e-13, atol=1e-15)
    z = fac.solve(B[:, 0] + 2j * B[:, 1])
    np.testing.assert_allclose(z, X[:, 0] + 2j * X[:, 1], rtol=1e-13, atol=1e-15)


def test_missing_diagonal_entries_are_stored_as_zeros():
    # [[0, 1], [1, 0]] block structure: a symmetric matrix with no diagonal at all
    A = sp.csr_matrix(np.array([[0.0, 2.0, 0.0], [2.0, 0.0, 1.0], [0.0, 1.0, 3.0]]))
    A.eliminate_zeros()
    b = np.array([1.0, 2.0, 3.0])
    np.testing.assert_allclose(pardiso.PardisoFactorization(A, positive_definite=False).solve(b),
                               np.linalg.solve(A.toarray(), b), rtol=1e-12)


def test_same_pattern_reuses_the_analysis_with_new_values():
    pardiso.clear_pool()
    A = _laplacian(12)
    b = np.ones(A.shape[0])
    first = pardiso.PardisoFactorization(A)
    assert not first.reused_analysis
    del first  # its handle returns to the pool
    B = sp.csr_matrix(A * 3.0 + sp.eye(A.shape[0]))  # same pattern, other values
    second = pardiso.PardisoFactorization(B)
    assert second.reused_analysis
    assert _residual(B, second.solve(b), b) < 1e-12
    # while `second` lives, a third factorisation of the pattern gets its own handle
    third = pardiso.PardisoFactorization(A)
    assert not third.reused_analysis
    assert _residual(A, third.solve(b), b) < 1e-12
    assert _residual(B, second.solve(b), b) < 1e-12  # untouched by the third


def test_pool_is_bounded():
    pardiso.clear_pool()
    for n in range(5, 5 + pardiso.POOL_SIZE + 3):
        pardiso.PardisoFactorization(_laplacian(n))  # dropped at once: pooled
    assert sum(len(h) for h in pardiso._pool.free.values()) == pardiso.POOL_SIZE
    pardiso.clear_pool()
    assert not pardiso._pool.free


def test_errors_name_the_problem():
    with pytest.raises(ValueError, match=r"shape \(3, 4\): PARDISO needs a square matrix"):
        pardiso.PardisoFactorization(sp.csr_matrix((3, 4)))
    fac = pardiso.PardisoFactorization(_laplacian(4))
    with pytest.raises(ValueError, match=r"right-hand side shape \(5,\): need \(16,\)"):
        fac.solve(np.ones(5))
    singular = sp.csr_matrix(np.diag([1.0, 0.0, 2.0]))
    with pytest.raises(pardiso.PardisoError, match=r"phase 22: error -4 \(zero pivot"):
        pardiso.PardisoFactorization(singular, positive_definite=True)
    # L D L^T perturbs the zero pivot instead: the answer cannot satisfy A x = b
    fac = pardiso.PardisoFactorization(singular, positive_definite=False)
    assert fac.perturbed_pivots >= 1
    b = np.ones(3)
    assert _residual(singular, fac.solve(b), b) > 1e-6
