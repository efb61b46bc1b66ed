"""MKL's analysed sparse product and the product chosen by fem.linalg."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from fem import linalg, mkl

needs_mkl = pytest.mark.skipif(not mkl.available(), reason="MKL runtime not installed")


def _matrix(n: int = 300, seed: int = 0) -> sp.csr_matrix:
    A = sp.random(n, n, density=0.03, random_state=seed, format="csr")
    return sp.csr_matrix(A + A.T + sp.eye(n))


@needs_mkl
@pytest.mark.parametrize("columns", [1, 2, 5])
def test_product_equals_scipy(columns):
    A = _matrix()
    rng = np.random.default_rng(columns)
    X = rng.normal(size=(A.shape[0], columns)) if columns > 1 else rng.normal(size=A.shape[0])
    out = rng.normal(size=X.shape)
    expected = out - 2.5 * (A @ X)
    prod = mkl.SparseProduct(A, columns)
    assert prod.accumulate(X, out, -2.5) is out
    np.testing.assert_allclose(out, expected, rtol=1e-13, atol=1e-13 * np.abs(expected).max())


@needs_mkl
def test_product_keeps_its_own_copy_and_checks_shapes():
    A = _matrix(50)
    prod = mkl.SparseProduct(A, 2)
    X = np.ones((50, 2))
    before = prod.accumulate(X, np.zeros((50, 2)))
    A.data[:] = 0.0  # the caller's matrix changes: the analysed product does not
    np.testing.assert_array_equal(prod.accumulate(X, np.zeros((50, 2))), before)
    with pytest.raises(ValueError, match=r"shapes \(49, 2\) -> \(50, 2\) do not fit"):
        prod.accumulate(np.ones((49, 2)), np.zeros((50, 2)))
    with pytest.raises(ValueError, match="out must be a C-contiguous float64 array"):
        prod.accumulate(X, np.zeros((50, 2), order="F"))


def test_linalg_product_follows_the_backend(monkeypatch):
    A = _matrix(40)
    X = np.random.default_rng(3).normal(size=(40, 2))
    monkeypatch.setenv(linalg.ENV_VAR, "superlu")
    plain = linalg.product(A, 2)
    assert not isinstance(plain, mkl.SparseProduct)
    np.testing.assert_allclose(plain.accumulate(X, np.ones((40, 2)), -1.0), 1.0 - A @ X,
                               rtol=1e-14)
    if mkl.available():
        monkeypatch.setenv(linalg.ENV_VAR, "pardiso")
        assert isinstance(linalg.product(A, 2), mkl.SparseProduct)
        monkeypatch.delenv(linalg.ENV_VAR)
        assert isinstance(linalg.product(A, 2), mkl.SparseProduct)
