"""The sparse solver layer: answers, backend choice and its errors, one BLAS thread."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from fem import linalg


def _laplacian(n: int) -> sp.csr_matrix:
    main = sp.diags([2.0 * np.ones(n), -np.ones(n - 1), -np.ones(n - 1)], [0, -1, 1])
    return sp.csr_matrix(sp.kron(main, sp.eye(n)) + sp.kron(sp.eye(n), main))


@pytest.mark.parametrize("backend", linalg.available_backends())
def test_real_spd_and_complex_symmetric_solves(backend):
    A = _laplacian(12)
    rng = np.random.default_rng(0)
    matrices = [A] if backend == "cholmod" else [A, A - 0.5 * sp.eye(A.shape[0]) * (1 - 0.3j)]
    for M in matrices:  # SPD; complex symmetric
        b = rng.normal(size=(A.shape[0], 2))
        x = linalg.factorize(M, backend=backend).solve(b.astype(M.dtype))
        assert np.abs(M @ x - b).max() <= 1e-12 * np.abs(b).max()
        assert np.iscomplexobj(x) == np.iscomplexobj(M.data)
        x1 = linalg.factorize(M, backend=backend).solve(b[:, 1].astype(M.dtype))
        np.testing.assert_allclose(x1, x[:, 1], rtol=1e-12)


def test_backend_choice_and_errors(monkeypatch):
    monkeypatch.delenv(linalg.ENV_VAR, raising=False)
    general = [b for b in linalg.available_backends() if b != "cholmod"]
    assert linalg.default_backend() == general[0]
    assert general[-1] == "superlu"
    spd = "cholmod" if "cholmod" in linalg.available_backends() else general[0]
    assert linalg.default_backend(positive_definite=True) == spd
    with pytest.raises(ValueError, match="backend = 'umfpack': allowed superlu, pardiso, cholmod"):
        linalg.factorize(_laplacian(3), backend="umfpack")
    monkeypatch.setenv(linalg.ENV_VAR, "mumps")
    with pytest.raises(ValueError, match="HAPTICROM_SOLVER = 'mumps'"):
        linalg.default_backend()
    monkeypatch.setenv(linalg.ENV_VAR, "superlu")
    assert linalg.default_backend() == "superlu"
    assert linalg.default_backend(positive_definite=True) == "superlu"
    assert isinstance(linalg.factorize(_laplacian(3)), type(linalg.superlu(_laplacian(3))))


def test_absent_backends_are_clear_errors(monkeypatch):
    monkeypatch.delenv(linalg.ENV_VAR, raising=False)
    monkeypatch.setattr(linalg.pardiso, "available", lambda: False)
    if "cholmod" in linalg.available_backends():  # SPD matrices go to CHOLMOD
        assert linalg.default_backend(positive_definite=True) == "cholmod"
        assert isinstance(linalg.factorize(_laplacian(3), positive_definite=True),
                          linalg._Cholmod)
    monkeypatch.setattr(linalg.importlib.util, "find_spec", lambda name: None)
    assert linalg.available_backends() == ["superlu"]
    assert linalg.default_backend(positive_definite=True) == "superlu"
    with pytest.raises(ValueError, match=r"needs the MKL runtime \(pip install hapticrom\[mkl\]\)"):
        linalg.factorize(_laplacian(3), backend="pardiso")
    with pytest.raises(ValueError, match=r"'cholmod' needs cholespy"):
        linalg.factorize(_laplacian(3), backend="cholmod")
    monkeypatch.setenv(linalg.ENV_VAR, "pardiso")
    with pytest.raises(ValueError, match="HAPTICROM_SOLVER = 'pardiso' needs the MKL runtime"):
        linalg.default_backend()


@pytest.mark.skipif("cholmod" not in linalg.available_backends(), reason="no cholespy")
def test_cholmod_refuses_what_it_cannot_factor():
    A = _laplacian(5)
    with pytest.raises(RuntimeError, match="CHOLMOD: Matrix is not positive definite"):
        linalg.factorize(A - 3.0 * sp.eye(A.shape[0]), backend="cholmod")
    with pytest.raises(ValueError, match="'cholmod' needs a real symmetric positive definite"):
        linalg.factorize(sp.csr_matrix(A, dtype=complex), backend="cholmod")


def test_one_blas_thread_inside_the_block():
    from threadpoolctl import threadpool_info

    with linalg.one_blas_thread():
        inside = [i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"]
    assert inside and all(n == 1 for n in inside)
