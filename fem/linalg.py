"""The one sparse direct solver layer every FE solve goes through.

The systems are symmetric: complex symmetric (A = A^T, not Hermitian) for a harmonic solve with
hysteretic damping or a PML, real symmetric positive definite for a static solve and for the
effective matrix of a transient. Every backend here factors once and re-solves cheaply.

Backends and why (medians on the real matrices, one thread, a shared 2-core machine; reproduce
with ``python bench/fem/backends.py``): the default forearm harmonic matrix (mode 1, Q9
condensed, 12,298 complex unknowns, 0.56 M non-zeros) and the transient example's effective
matrix (25,324 real unknowns, 1.17 M non-zeros, two right-hand sides every step).

- ``pardiso`` (the general default when MKL is installed: ``pip install hapticrom[mkl]``, which
  the development environment includes): Intel MKL PARDISO called directly
  (:mod:`fem.pardiso`), L D L^T of the complex symmetric matrix, Cholesky of real SPD ones,
  L D L^T of real indefinite ones. Harmonic: first factorisation of a pattern 145-180 ms
  (ordering and analysis included), later ones of the same pattern 80-115 ms (the analysis is
  reused: a frequency sweep, dataset samples on one mesh), solve 10-14 ms, 1.34 M factor
  entries, relative residual 4e-14. It is an extra because the MKL wheel is about 220 MB to
  download (0.9 GB installed).
- ``superlu`` (the general default without MKL, ships with scipy): SuperLU in symmetric mode,
  i.e. the minimum-degree ordering of A + A^T (``MMD_AT_PLUS_A``) and diagonal pivots
  (``diag_pivot_thresh = 0``): harmonic factor 280-365 ms + solve 13 ms, 2.43 M factor
  entries. It halves the fill of SuperLU's default COLAMD with partial pivoting (factor 704 ms)
  and beats UMFPACK through cvxopt (factor 310 ms + solve 50 ms, the conversion to cvxopt
  included), which is why cvxopt is no longer a dependency. A geometric nested-dissection
  ordering of the structured grid gave 2.41 M entries and no speed-up. Diagonal pivoting is
  safe here because every matrix is symmetric with a dominant diagonal block per node;
  :func:`fem.solve.checked_solve` still checks the residual of every solve.
- ``cholmod`` (a dependency: cholespy's 14 MB wheel carries SuiteSparse CHOLMOD): supernodal
  Cholesky, for matrices the caller declares positive definite (the transient's), where the
  per-step solve is what counts (3,000 steps in the transient example): two right-hand sides
  7.0 ms against PARDISO's 8.7 ms on the quiet machine (alternating in one process), 12.6
  against 15.8 ms under load, and against SuperLU's 9.4-14.5 ms. Its factorisation (490 ms on
  the reference BLAS the wheel carries, PARDISO 130 ms) happens once per run.

Other wheels were measured and not used: qdldl (real L D L^T: 20 ms per right-hand side on
the transient matrix against SuperLU's 22 ms for two), python-mumps (only a numpy-1 wheel),
scikit-umfpack and scikit-sparse (no wheels).

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

from fem import mkl, pardiso

__all__ = ["BACKENDS", "Factorization", "Product", "available_backends", "default_backend",
           "factorize", "one_blas_thread", "product"]

#: Backend names accepted by :func:`factorize` (and the ``HAPTICROM_SOLVER`` variable).
BACKENDS = ("superlu", "pardiso", "cholmod")

#: Environment variable that forces a backend (one of :data:`BACKENDS`).
ENV_VAR = "HAPTICROM_SOLVER"


_controller = None


@contextlib.contextmanager
def one_blas_thread() -> Iterator[None]:
    """Limit the BLAS libraries loaded in this process to one thread inside the block (also
    usable as a decorator). Costs about 0.1 ms."""
    global _controller
    # optional: limits the BLAS threads when installed
    from threadpoolctl import ThreadpoolController

    if _controller is None:  # after numpy and scipy loaded their BLAS
        _controller = ThreadpoolController()
    with _controller.limit(limits=1, user_api="blas"):
        yield


class Factorization(Protocol):
    """A factorised matrix: ``solve(b)`` for b of shape (n,) or (n, k)."""

    def solve(self, b: NDArray) -> NDArray: ...


def available_backends() -> list[str]:
    """Backends that can run in this environment: the general ones fastest first, then
    ``cholmod`` (real SPD matrices only) when cholespy is installed."""
    general = ["pardiso", "superlu"] if pardiso.available() else ["superlu"]
    return general + (["cholmod"] if importlib.util.find_spec("cholespy") else [])


def default_backend(positive_definite: bool | None = None) -> str:
    """The backend :func:`factorize` uses: ``HAPTICROM_SOLVER`` if set; else CHOLMOD for a
    matrix known to be SPD (the transient's: its solves are the fastest measured) when
    installed; else the fastest general backend installed (PARDISO, then SuperLU)."""
    forced = os.environ.get(ENV_VAR, "").strip().lower()
    if forced:
        _check_backend(forced, ENV_VAR)
        return forced
    found = available_backends()
    if positive_definite is True and "cholmod" in found:
        return "cholmod"
    return found[0]


def _check_backend(name: str, field: str) -> None:
    if name not in BACKENDS:
        raise ValueError(f"{field} = {name!r}: allowed {', '.join(BACKENDS)}")
    if name not in available_backends():
        need = {"pardiso": "the MKL runtime (pip install hapticrom[mkl])",
                "cholmod": "cholespy (pip install cholespy)"}[name]
        raise ValueError(f"{field} = {name!r} needs {need}")


class _Cholmod:
    """CHOLMOD's supernodal Cholesky (SuiteSparse, through cholespy) of a real SPD matrix."""

    def __init__(self, A: sp.spmatrix) -> None:
        # optional: the CHOLMOD backend, tried when installed
        from cholespy import CholeskySolverD, MatrixType

        if np.iscomplexobj(A.data):
            raise ValueError("backend 'cholmod' needs a real symmetric positive definite "
                             "matrix; got a complex one")
        csr = sp.csr_matrix(A, dtype=np.float64)
        csr.sum_duplicates()
        self.n = csr.shape[0]
        try:
            self._chol = CholeskySolverD(self.n, csr.indptr.astype(np.int32),
                                         csr.indices.astype(np.int32), csr.data,
                                         MatrixType.CSR)
        except ValueError as err:  # "Matrix is not positive definite!"
            raise RuntimeError(f"CHOLMOD: {err}") from err

    def solve(self, b: NDArray) -> NDArray:
        if np.iscomplexobj(b):
            return self.solve(b.real) + 1j * self.solve(b.imag)
        rhs = np.ascontiguousarray(b, dtype=np.float64)
        x = np.empty_like(rhs)
        self._chol.solve(rhs, x)
        return x


def superlu(A: sp.spmatrix) -> spla.SuperLU:
    """SuperLU in symmetric mode: MMD ordering of A + A^T, diagonal pivots."""
    return spla.splu(sp.csc_matrix(A), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                     options={"SymmetricMode": True})


def factorize(A: sp.spmatrix, backend: str | None = None,
              positive_definite: bool | None = None) -> Factorization:
    """Factor a symmetric (real or complex) sparse matrix once for any number of solves.

    Args:
        A: square sparse matrix, symmetric (A = A^T).
        backend: one of :data:`BACKENDS`, or None for :func:`default_backend`.
        positive_definite: True when A is known to be real symmetric positive definite (a
            transient's effective matrix, a mass matrix): PARDISO then runs Cholesky only and
            a non-positive pivot raises; None lets it try Cholesky and fall back to L D L^T.
            SuperLU ignores it.

    Raises:
        ValueError: unknown or unavailable backend.
        RuntimeError: the matrix is singular (SuperLU), not positive definite (CHOLMOD), or
            PARDISO reported an error (:class:`fem.pardiso.PardisoError`).
    """
    name = default_backend(positive_definite) if backend is None else backend
    _check_backend(name, "backend")
    if name == "pardiso":
        return pardiso.PardisoFactorization(A, positive_definite)
    if name == "cholmod":
        return _Cholmod(A)
    return superlu(A)


class Product(Protocol):
    """A fixed sparse matrix ready to multiply: ``accumulate(X, out, alpha)`` does
    out += alpha A X in place (X, out C-contiguous float64, (n,) or (n, k))."""

    def accumulate(self, X: NDArray, out: NDArray, alpha: float = 1.0) -> NDArray: ...


class _ScipyProduct:
    """scipy's CSR product behind the :class:`Product` interface."""

    def __init__(self, A: sp.spmatrix) -> None:
        self._A = sp.csr_matrix(A)

    def accumulate(self, X: NDArray, out: NDArray, alpha: float = 1.0) -> NDArray:
        out += alpha * (self._A @ X) if alpha != 1.0 else self._A @ X
        return out


def product(A: sp.spmatrix, columns: int = 1) -> Product:
    """A real sparse matrix prepared for many products with ``columns``-column blocks: MKL's
    analysed product (:class:`fem.mkl.SparseProduct`, 3x faster than scipy's on the transient
    stiffness) when MKL is installed and ``HAPTICROM_SOLVER`` does not ask for another
    backend, else scipy's."""
    if mkl.available() and os.environ.get(ENV_VAR, "").strip().lower() in ("", "pardiso"):
        return mkl.SparseProduct(A, columns)
    return _ScipyProduct(A)
