"""Intel MKL PARDISO through its C interface (ctypes), for symmetric sparse matrices.

Why a direct call: the one wrapper with wheels (pypardiso) handles real matrices only, and the
harmonic systems are complex symmetric (A = A^T, not Hermitian). PARDISO factors them as
L D L^T with Bunch-Kaufman pivoting inside supernodes (matrix type 6): on the default forearm
matrix (12,298 complex unknowns, 0.56 M non-zeros, one thread) ordering + symbolic analysis
45 ms, numeric factorisation 80 ms, solve 12 ms, 1.46 M factor entries, against SuperLU's
2.43 M entries and 280-360 ms (``python bench/fem/solver.py --solvers``).

Matrix types used: 6 complex symmetric, 2 real symmetric positive definite (static and
transient systems; Cholesky), -2 real symmetric indefinite (tried when Cholesky meets a
non-positive pivot). Only the upper triangle is passed, zero-based (iparm[34] = 1).

Per-pattern reuse: the ordering and symbolic analysis (PARDISO phase 11) depend only on the
sparsity pattern. A factorisation keeps its PARDISO handle while alive; when it is dropped the
handle goes back to a small per-process pool keyed by the pattern, and the next matrix with the
same pattern (the next frequency of a sweep, the next dataset sample on the same mesh) runs the
numeric phase 22 only. Handles evicted from the pool release their memory (phase -1).

MKL runs sequentially (:func:`fem.mkl.library`): on the 2-core machine two threads gave no
gain on these matrices.
"""

from __future__ import annotations

import ctypes
import hashlib
import threading
from collections import OrderedDict

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

from fem import mkl
from fieldspec import WorkError

__all__ = ["PardisoError", "PardisoFactorization", "available", "clear_pool"]

COMPLEX_SYMMETRIC, REAL_SPD, REAL_SYMMETRIC_INDEFINITE = 6, 2, -2
#: Free PARDISO handles kept per process (each holds one factorisation's memory).
POOL_SIZE = 4

#: PARDISO error codes (MKL reference, "pardiso" return value ``error``).
_ERRORS = {-1: "input inconsistent", -2: "not enough memory", -3: "reordering problem",
           -4: "zero pivot, numerical factorization or iterative refinement problem",
           -5: "unclassified (internal) error", -6: "reordering failed",
           -7: "diagonal matrix is singular", -8: "32-bit integer overflow problem",
           -9: "not enough memory for out-of-core solver",
           -10: "error opening out-of-core files", -11: "read/write error with OOC files"}


class PardisoError(WorkError):
    """PARDISO returned an error code (``code``)."""

    def __init__(self, code: int, phase: int) -> None:
        super().__init__(f"PARDISO phase {phase}: error {code} ({_ERRORS.get(code, 'unknown')})")
        self.code = code


def available() -> bool:
    """True when the MKL runtime is installed (``pip install hapticrom[mkl]``); loads nothing."""
    return mkl.available()


def _mkl() -> ctypes.CDLL:
    lib = mkl.library()
    lib.pardiso.restype = None
    lib.pardisoinit.restype = None
    return lib


class _Handle:
    """One PARDISO internal handle (``pt``) with its parameter array and pattern."""

    def __init__(self, mtype: int) -> None:
        self.pt = np.zeros(64, dtype=np.int64)
        self.iparm = np.zeros(64, dtype=np.int32)
        self.mtype = mtype
        lib = _mkl()
        mt = ctypes.c_int32(mtype)
        lib.pardisoinit(self.pt.ctypes.data_as(ctypes.c_void_p), ctypes.byref(mt),
                        self.iparm.ctypes.data_as(ctypes.c_void_p))
        self.iparm[0] = 1    # parameters below are set, not defaults
        self.iparm[1] = 0    # minimum degree (AMD): on both matrices (alternating runs,
        #                      bench/fem/backends.py) 8 % less fill than METIS
        #                      (1.34 M against 1.46 M entries on the default forearm, 2.29 M
        #                      against 2.48 M on the transient), a cheaper analysis (cold
        #                      factor 155 against 182 ms), equal numeric time, solves 5-10 %
        #                      faster
        self.iparm[7] = 0    # no iterative refinement unless pivots were perturbed: the default
        #                      two steps doubled the solve (12 -> 24 ms) at a residual of 4e-14;
        #                      fem.solve.checked_solve checks every residual anyway
        self.iparm[34] = 1   # zero-based ia / ja
        self.analysed = False

    def call(self, phase: int, n: int, a: NDArray, ia: NDArray, ja: NDArray,
             b: NDArray | None = None, x: NDArray | None = None, nrhs: int = 1) -> None:
        err = ctypes.c_int32(0)
        i32 = ctypes.c_int32
        null = ctypes.c_void_p()

        def ptr(arr: NDArray | None) -> ctypes.c_void_p:
            return null if arr is None else arr.ctypes.data_as(ctypes.c_void_p)

        _mkl().pardiso(ptr(self.pt), ctypes.byref(i32(1)), ctypes.byref(i32(1)),
                       ctypes.byref(i32(self.mtype)), ctypes.byref(i32(phase)),
                       ctypes.byref(i32(n)), ptr(a), ptr(ia), ptr(ja), null,
                       ctypes.byref(i32(nrhs)), ptr(self.iparm), ctypes.byref(i32(0)),
                       ptr(b), ptr(x), ctypes.byref(err))
        if err.value != 0:
            raise PardisoError(err.value, phase)

    def release(self) -> None:
        """Free PARDISO's internal memory (phase -1)."""
        if self.analysed or self.pt.any():
            dummy = np.zeros(1, dtype=np.int32)
            try:
                self.call(-1, 1, np.zeros(1), dummy, dummy)
            finally:
                self.analysed = False


class _Pool:
    """Free analysed handles by (matrix type, pattern digest), least recently used evicted."""

    def __init__(self, size: int) -> None:
        self.size = size
        self.free: OrderedDict[tuple[int, bytes], list[_Handle]] = OrderedDict()
        self.lock = threading.Lock()

    def take(self, key: tuple[int, bytes]) -> _Handle | None:
        with self.lock:
            handles = self.free.get(key)
            if not handles:
                return None
            handle = handles.pop()
            if not handles:
                del self.free[key]
            return handle

    def give(self, key: tuple[int, bytes], handle: _Handle) -> None:
        with self.lock:
            self.free.setdefault(key, []).append(handle)
            self.free.move_to_end(key)
            evicted = []
            while sum(len(h) for h in self.free.values()) > self.size:
                old_key = next(iter(self.free))
                evicted.append(self.free[old_key].pop(0))
                if not self.free[old_key]:
                    del self.free[old_key]
        for old in evicted:
            old.release()

    def clear(self) -> None:
        with self.lock:
            handles = [h for hs in self.free.values() for h in hs]
            self.free.clear()
        for h in handles:
            h.release()


_pool = _Pool(POOL_SIZE)


def clear_pool() -> None:
    """Release every pooled PARDISO handle (frees their memory)."""
    _pool.clear()


def _upper_csr(A: sp.spmatrix | sp.sparray) -> sp.csr_matrix:
    """Upper triangle in CSR, sorted column indices, every diagonal entry stored (PARDISO's
    symmetric types need the diagonal, zero or not).

    Fast path (1-2 ms on the default matrix against 14 ms through scipy's triu): a canonical CSR
    or CSC matrix with a full diagonal. A CSC matrix's arrays are the CSR arrays of its
    transpose, which is the same symmetric matrix, so they are read as they are."""
    if sp.issparse(A) and A.format in ("csr", "csc") and A.has_canonical_format:
        n = A.shape[0]
        row = np.repeat(np.arange(n, dtype=np.int32), np.diff(A.indptr))
        if np.count_nonzero(A.indices == row) == n:
            keep = A.indices >= row
            indptr = np.zeros(n + 1, dtype=np.int32)
            np.cumsum(np.bincount(row[keep], minlength=n), out=indptr[1:])
            return sp.csr_matrix((A.data[keep], A.indices[keep], indptr), shape=A.shape)
    # general path: an explicit zero where a diagonal entry is absent (COO -> CSR sums
    # duplicates and keeps explicit zeros)
    U = sp.triu(A, format="coo")
    n = U.shape[0]
    diag = np.arange(n)
    rows = np.concatenate([U.row, diag])
    cols = np.concatenate([U.col, diag])
    data = np.concatenate([U.data, np.zeros(n, dtype=U.dtype)])
    out = sp.csr_matrix((data, (rows, cols)), shape=U.shape)
    out.sum_duplicates()
    out.sort_indices()
    return out


class PardisoFactorization:
    """L D L^T (or Cholesky) of a symmetric matrix by PARDISO; ``solve(b)`` for b of shape
    (n,) or (n, k). The matrix must be symmetric (A = A^T); only its upper triangle is read.

    A singular matrix is not always an error here: the indefinite types perturb tiny pivots
    (``perturbed_pivots``) and the answer then fails the caller's residual check
    (:func:`fem.solve.checked_solve`); Cholesky of a matrix declared positive definite raises.

    Args:
        A: square sparse symmetric matrix, real or complex.
        positive_definite: for a real matrix: True = Cholesky only (a non-positive pivot
            raises :class:`PardisoError` -4), None = Cholesky first, L D L^T if a pivot is not
            positive, False = L D L^T. Ignored for complex matrices.
    """

    def __init__(self, A: sp.spmatrix | sp.sparray,
                 positive_definite: bool | None = None) -> None:
        if A.shape[0] != A.shape[1]:
            raise ValueError(f"matrix shape {A.shape}: PARDISO needs a square matrix")
        U = _upper_csr(A)
        self.n = U.shape[0]
        self.is_complex = np.iscomplexobj(U.data)
        self.dtype = np.complex128 if self.is_complex else np.float64
        self._a = np.ascontiguousarray(U.data, dtype=self.dtype)
        self._ia = np.ascontiguousarray(U.indptr, dtype=np.int32)
        self._ja = np.ascontiguousarray(U.indices, dtype=np.int32)
        digest = hashlib.blake2b(self._ia.tobytes(), digest_size=16)
        digest.update(self._ja.tobytes())
        self._pattern = digest.digest()
        self._handle: _Handle | None = None
        self._key: tuple[int, bytes] | None = None
        if self.is_complex:
            self._factor(COMPLEX_SYMMETRIC)
        elif positive_definite is True:
            self._factor(REAL_SPD)
        elif positive_definite is None:
            try:
                self._factor(REAL_SPD)
            except PardisoError as err:
                if err.code != -4:
                    raise
                self._factor(REAL_SYMMETRIC_INDEFINITE)
        else:
            self._factor(REAL_SYMMETRIC_INDEFINITE)

    @property
    def mtype(self) -> int:
        """The PARDISO matrix type the factorisation used (6, 2 or -2)."""
        assert self._key is not None
        return self._key[0]

    @property
    def reused_analysis(self) -> bool:
        """True when the ordering and symbolic analysis came from a pooled handle."""
        return self._reused

    def _factor(self, mtype: int) -> None:
        key = (mtype, self._pattern)
        handle = _pool.take(key)
        self._reused = handle is not None
        if handle is None:
            handle = _Handle(mtype)
        try:
            if not handle.analysed:
                handle.call(11, self.n, self._a, self._ia, self._ja)
                handle.analysed = True
            handle.call(22, self.n, self._a, self._ia, self._ja)
        except PardisoError:
            handle.release()
            raise
        self._handle, self._key = handle, key

    def solve(self, b: NDArray) -> NDArray:
        """Solve A x = b; b real or complex, shape (n,) or (n, k)."""
        b = np.asarray(b)
        if b.shape[0] != self.n or b.ndim not in (1, 2):
            raise ValueError(f"right-hand side shape {b.shape}: need ({self.n},) or "
                             f"({self.n}, k)")
        if not self.is_complex and np.iscomplexobj(b):
            return self.solve(b.real) + 1j * self.solve(b.imag)
        nrhs = 1 if b.ndim == 1 else b.shape[1]
        # PARDISO reads the right-hand sides column after column (Fortran order)
        rhs = np.asfortranarray(b, dtype=self.dtype)
        x = np.empty_like(rhs, order="F")
        assert self._handle is not None
        self._handle.call(33, self.n, self._a, self._ia, self._ja, rhs, x, nrhs)
        return np.ascontiguousarray(x)  # row-major like b and like SuperLU's answer

    @property
    def perturbed_pivots(self) -> int:
        """Pivots PARDISO perturbed during the numeric factorisation (iparm[13])."""
        assert self._handle is not None
        return int(self._handle.iparm[13])

    @property
    def factor_nnz(self) -> int:
        """Entries of the factor L (PARDISO's iparm[17] after phase 11)."""
        assert self._handle is not None
        return int(abs(self._handle.iparm[17]))

    def __del__(self) -> None:
        handle, key = getattr(self, "_handle", None), getattr(self, "_key", None)
        if handle is not None and key is not None:
            self._handle = None
            _pool.give(key, handle)
