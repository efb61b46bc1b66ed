"""The Intel MKL runtime, when installed (``pip install hapticrom[mkl]``): finding and loading it,
and its sparse matrix products (inspector-executor sparse BLAS) for the time-stepping loop.

MKL is optional: :func:`available` says whether it is there, without loading it. It is loaded
once per process with the sequential threading layer and 32-bit integers: on the 2-core machine
threads gave nothing on these small systems, dataset workers are one process per core, and the
sequential layer loads no OpenMP runtime beside the one torch or OpenBLAS may bring.

Why MKL's product: on the transient example's stiffness (25,324 unknowns, 1.17 M non-zeros) times
two right-hand sides, scipy's CSR product takes 5.9 ms and MKL's (matrix analysed once,
:class:`SparseProduct`) about 2 ms; a generalised-alpha step makes two such products
(``python bench/fem/solver.py --only transient``).
"""

from __future__ import annotations

import ctypes
import glob
import os
import sys
from functools import cache

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

__all__ = ["SparseProduct", "available", "library"]

_THREADING_SEQUENTIAL = 1
_INTERFACE_LP64 = 0
# enum values of mkl_spblas.h
_INDEX_BASE_ZERO = 0
_OPERATION_NON_TRANSPOSE = 10
_MATRIX_TYPE_GENERAL = 20
_FILL_MODE_FULL = 42
_DIAG_NON_UNIT = 50
_LAYOUT_ROW_MAJOR = 101
#: calls a product is analysed for (a hint to MKL's optimiser; any number works)
_EXPECTED_CALLS = 1000


def _library_candidates() -> list[str]:
    """Where the MKL single dynamic library may be: the active environment (the ``mkl`` wheel
    puts it in <prefix>/lib, conda on Windows in <prefix>/Library/bin)."""
    names = {"linux": "libmkl_rt.so*", "darwin": "libmkl_rt*.dylib", "win32": "mkl_rt*.dll"}
    pattern = names.get(sys.platform, "libmkl_rt.so*")
    found: list[str] = []
    for prefix in dict.fromkeys([sys.prefix, sys.base_prefix]):
        for sub in ("lib", os.path.join("Library", "bin")):
            found += sorted(glob.glob(os.path.join(prefix, sub, pattern)), reverse=True)
    return found


def available() -> bool:
    """True when an MKL runtime library is installed; cheap, loads nothing."""
    return bool(_library_candidates())


@cache
def library() -> ctypes.CDLL:
    """MKL's single dynamic library, loaded once: sequential, 32-bit integers."""
    errors = []
    for path in _library_candidates():
        try:
            lib = ctypes.CDLL(path)
        except OSError as err:  # a broken or foreign-architecture copy: try the next one
            errors.append(f"{path}: {err}")
            continue
        lib.MKL_Set_Threading_Layer(_THREADING_SEQUENTIAL)
        lib.MKL_Set_Interface_Layer(_INTERFACE_LP64)
        return lib
    raise ImportError("MKL runtime (libmkl_rt) not found: pip install hapticrom[mkl]"
                      + (f" ({'; '.join(errors)})" if errors else ""))


class _Descr(ctypes.Structure):
    _fields_ = [("type", ctypes.c_int), ("mode", ctypes.c_int), ("diag", ctypes.c_int)]


_GENERAL = _Descr(_MATRIX_TYPE_GENERAL, _FILL_MODE_FULL, _DIAG_NON_UNIT)


def _check(status: int, what: str) -> None:
    if status != 0:
        raise RuntimeError(f"MKL sparse BLAS {what}: status {status}")


class SparseProduct:
    """``out += alpha * A @ X`` for a fixed real sparse matrix A, analysed once by MKL.

    Args:
        A: real sparse matrix (any scipy format; copied to CSR with 32-bit indices).
        columns: the number of columns of the X it will be applied to (a hint).
    """

    def __init__(self, A: sp.spmatrix | sp.sparray, columns: int = 1) -> None:
        csr = sp.csr_matrix(A, dtype=np.float64)
        csr.sum_duplicates()
        self.shape = csr.shape
        # MKL keeps pointers into these arrays: they live as long as the handle
        self._data = np.ascontiguousarray(csr.data, dtype=np.float64)
        self._indptr = np.ascontiguousarray(csr.indptr, dtype=np.int32)
        self._indices = np.ascontiguousarray(csr.indices, dtype=np.int32)
        self._lib = library()
        self._handle = ctypes.c_void_p()
        p = ctypes.c_void_p
        _check(self._lib.mkl_sparse_d_create_csr(
            ctypes.byref(self._handle), _INDEX_BASE_ZERO, ctypes.c_int32(self.shape[0]),
            ctypes.c_int32(self.shape[1]), self._indptr.ctypes.data_as(p),
            p(self._indptr.ctypes.data + 4), self._indices.ctypes.data_as(p),
            self._data.ctypes.data_as(p)), "create")
        if columns > 1:
            _check(self._lib.mkl_sparse_set_mm_hint(
                self._handle, _OPERATION_NON_TRANSPOSE, _GENERAL, _LAYOUT_ROW_MAJOR,
                ctypes.c_int32(columns), ctypes.c_int32(_EXPECTED_CALLS)), "mm hint")
        else:
            _check(self._lib.mkl_sparse_set_mv_hint(
                self._handle, _OPERATION_NON_TRANSPOSE, _GENERAL,
                ctypes.c_int32(_EXPECTED_CALLS)), "mv hint")
        _check(self._lib.mkl_sparse_optimize(self._handle), "optimize")

    def accumulate(self, X: NDArray, out: NDArray, alpha: float = 1.0) -> NDArray:
        """out <- out + alpha A X in place, for C-contiguous float64 X and out of shape (n,)
        or (n, k); returns out."""
        if X.shape[0] != self.shape[1] or out.shape != (self.shape[0], *X.shape[1:]):
            raise ValueError(f"shapes {X.shape} -> {out.shape} do not fit a {self.shape} "
                             "matrix")
        X = np.ascontiguousarray(X, dtype=np.float64)
        if out.dtype != np.float64 or not out.flags.c_contiguous:
            raise ValueError("out must be a C-contiguous float64 array")
        p = ctypes.c_void_p
        a, one = ctypes.c_double(alpha), ctypes.c_double(1.0)
        if X.ndim == 1:
            status = self._lib.mkl_sparse_d_mv(_OPERATION_NON_TRANSPOSE, a, self._handle,
                                               _GENERAL, X.ctypes.data_as(p), one,
                                               out.ctypes.data_as(p))
        else:
            k = ctypes.c_int32(X.shape[1])
            status = self._lib.mkl_sparse_d_mm(_OPERATION_NON_TRANSPOSE, a, self._handle,
                                               _GENERAL, _LAYOUT_ROW_MAJOR, X.ctypes.data_as(p),
                                               k, k, one, out.ctypes.data_as(p), k)
        _check(status, "product")
        return out

    def __del__(self) -> None:
        handle = getattr(self, "_handle", None)
        if handle is not None and handle.value:
            self._lib.mkl_sparse_destroy(handle)
            self._handle = None
