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
    for M in (A, A - 0.5 * sp.eye(A.shape[0]) * (1 - 0.3j)):  # SPD; complex symmetric
        b = rng.normal(size=(A.shape[0], 2))
        x = linalg.factorize(M, backend=backend).solve(b.astype(M.dtype))
        assert np.abs(M @ x - b).max() <= 1e-12 * np.abs(b).max()
        assert np.iscomplexobj(x) == np.iscomplexobj(M.data)


def test_backend_choice_and_errors(monkeypatch):
    monkeypatch.delenv(linalg.ENV_VAR, raising=False)
    assert linalg.default_backend() == linalg.available_backends()[0]
    assert linalg.available_backends()[-1] == "superlu"
    with pytest.raises(ValueError, match="backend = 'umfpack': allowed superlu, pardiso"):
        linalg.factorize(_laplacian(3), backend="umfpack")
    monkeypatch.setenv(linalg.ENV_VAR, "mumps")
    with pytest.raises(ValueError, match="HAPTICROM_SOLVER = 'mumps'"):
        linalg.default_backend()
    monkeypatch.setenv(linalg.ENV_VAR, "superlu")
    assert linalg.default_backend() == "superlu"
    assert isinstance(linalg.factorize(_laplacian(3)), type(linalg.superlu(_laplacian(3))))


def test_pardiso_absent_is_a_clear_error(monkeypatch):
    monkeypatch.delenv(linalg.ENV_VAR, raising=False)
    monkeypatch.setattr(linalg.pardiso, "available", lambda: False)
    assert linalg.available_backends() == ["superlu"]
    assert linalg.default_backend() == "superlu"
    with pytest.raises(ValueError, match=r"needs the MKL runtime \(pip install hapticrom\[mkl\]\)"):
        linalg.factorize(_laplacian(3), backend="pardiso")
    monkeypatch.setenv(linalg.ENV_VAR, "pardiso")
    with pytest.raises(ValueError, match="HAPTICROM_SOLVER = 'pardiso' needs the MKL runtime"):
        linalg.default_backend()


def test_one_blas_thread_inside_the_block():
    from threadpoolctl import threadpool_info

    with linalg.one_blas_thread():
        inside = [i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"]
    assert inside and all(n == 1 for n in inside)
