"""The one sparse direct solver layer every FE solve goes through.

The systems are symmetric: complex symmetric (A = A^T, not Hermitian) for a harmonic solve with
hysteretic damping or a PML, real symmetric positive definite for a static solve and for the
effective matrix of a transient. Every backend here factors once and re-solves cheaply.

Backends and why (measured on the dumped default forearm matrix: mode 1, Q9 condensed, 12,298
complex unknowns, 0.56 M non-zeros; one loaded 2-core machine; medians of 3 runs;
reproduce with ``python bench/bench_solver.py --solvers``):

- ``superlu`` (default, ships with scipy): SuperLU in symmetric mode, i.e. the minimum-degree
  ordering of A + A^T (``MMD_AT_PLUS_A``) and diagonal pivots (``diag_pivot_thresh = 0``):
  factor 241 ms + solve 13 ms, relative residual 1.7e-13. It halves the fill of SuperLU's default
  COLAMD with partial pivoting (factor 704 ms + solve 19 ms, same residual) and beats UMFPACK
  through cvxopt (factor 310 ms + solve 50 ms, the conversion to cvxopt included), which is why
  cvxopt is no longer a dependency. A geometric nested-dissection ordering of the structured grid
  was tried as well: 2.41 M factor entries against MMD's 2.43 M and no faster, so it is not used.
  Diagonal pivoting is safe here because every matrix is symmetric with a dominant diagonal
  block per node; :func:`fem.solve.checked_solve` still checks the residual of every solve.
- ``pardiso`` (optional, ``pip install hapticrom[mkl]``; chosen automatically when
  ``pypardiso`` imports): Intel MKL PARDISO for real matrices (static, transient); the issue
  that motivated this layer measured PARDISO 7.5 ms against SuperLU 10.5 ms per transient step.
  pypardiso handles real matrices only, so complex harmonic systems stay on SuperLU. The MKL
  wheel is about 0.9 GB and was not installed on the machine this was written on: this path is
  untested here.

BLAS runs on one thread inside every solve (:func:`one_blas_thread`): SuperLU's supernodal
kernels call BLAS on small blocks, where OpenBLAS's default thread pool only contends. On the
loaded 2-core machine the default factorisation took 1.7-2.0 s with 2 OpenBLAS threads and
0.35-0.41 s with one (the same matrix, same process kind); dataset workers run one thread each
for the same reason (surrogate.data.pool).

Iterative refinement is off: scipy's ``SuperLU.solve`` is the plain pair of triangular solves
(UMFPACK's default refinement cost 34 ms of a default solve and gained nothing); the residual
check of every solve guards the answer instead.
"""

from __future__ import annotations

import contextlib
import importlib.util
import os
from collections.abc import Iterator
from typing import Protocol

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from numpy.typing import NDArray

__all__ = ["BACKENDS", "Factorization", "available_backends", "default_backend", "factorize",
           "one_blas_thread"]

#: Backend names accepted by :func:`factorize` (and the ``HAPTICROM_SOLVER`` variable).
BACKENDS = ("superlu", "pardiso")

#: Environment variable that forces a backend (one of :data:`BACKENDS`).
ENV_VAR = "HAPTICROM_SOLVER"


_controller = None


@contextlib.contextmanager
def one_blas_thread() -> Iterator[None]:
    """Limit the BLAS libraries loaded in this process to one thread inside the block (also
    usable as a decorator). Costs about 0.1 ms."""
    global _controller
    from threadpoolctl import ThreadpoolController

    if _controller is None:  # after numpy and scipy loaded their BLAS
        _controller = ThreadpoolController()
    with _controller.limit(limits=1, user_api="blas"):
        yield


class Factorization(Protocol):
    """A factorised matrix: ``solve(b)`` for b of shape (n,) or (n, k)."""

    def solve(self, b: NDArray) -> NDArray: ...


def available_backends() -> list[str]:
    """Backends that can run in this environment, fastest first."""
    found = ["pardiso"] if importlib.util.find_spec("pypardiso") is not None else []
    return [*found, "superlu"]


def default_backend(is_complex: bool) -> str:
    """The backend :func:`factorize` uses for a real or complex matrix: ``HAPTICROM_SOLVER`` if
    set, else PARDISO for real matrices when installed, else SuperLU."""
    forced = os.environ.get(ENV_VAR, "").strip().lower()
    if forced:
        _check_backend(forced, ENV_VAR)
        return forced
    if not is_complex and "pardiso" in available_backends():
        return "pardiso"
    return "superlu"


def _check_backend(name: str, field: str) -> None:
    if name not in BACKENDS:
        raise ValueError(f"{field} = {name!r}: allowed {', '.join(BACKENDS)}")
    if name == "pardiso" and "pardiso" not in available_backends():
        raise ValueError(f"{field} = 'pardiso' needs pypardiso (pip install hapticrom[mkl])")


class _Pardiso:
    """MKL PARDISO through pypardiso (real matrices only)."""

    def __init__(self, A: sp.spmatrix) -> None:
        import pypardiso

        self._solve = pypardiso.factorized(sp.csr_matrix(A, dtype=float))

    def solve(self, b: NDArray) -> NDArray:
        return np.asarray(self._solve(np.asarray(b, dtype=float)))


def superlu(A: sp.spmatrix) -> spla.SuperLU:
    """SuperLU in symmetric mode: MMD ordering of A + A^T, diagonal pivots."""
    return spla.splu(sp.csc_matrix(A), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                     options={"SymmetricMode": True})


def factorize(A: sp.spmatrix, backend: str | None = None) -> Factorization:
    """Factor a symmetric (real or complex) sparse matrix once for any number of solves.

    Args:
        A: square sparse matrix, symmetric (A = A^T).
        backend: one of :data:`BACKENDS`, or None for :func:`default_backend`.

    Raises:
        ValueError: unknown or unavailable backend. A complex matrix asked of PARDISO goes to
            SuperLU (pypardiso is real only).
        RuntimeError: SuperLU found the matrix exactly singular.
    """
    is_complex = np.iscomplexobj(A.data) if sp.issparse(A) else np.iscomplexobj(A)
    name = default_backend(is_complex) if backend is None else backend
    _check_backend(name, "backend")
    if name == "pardiso":
        if is_complex:
            # pypardiso wraps real PARDISO only; fall back rather than fail a forced run
            return superlu(A)
        return _Pardiso(A)
    return superlu(A)
