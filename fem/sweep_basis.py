"""A reduced basis of one sweep operator that grows a block of columns at a time, with its
projected terms, load and outputs kept up to date incrementally.

The reduced model of ``fem.sweep_rom`` is the Galerkin projection V^H A(omega) V y = V^H b of
the operator :class:`fem.sweep_operator.SweepOperator` onto the orthonormal columns of V. Every
expansion point appends a few columns; recomputing V^H A_k V from scratch after each would
cost the square of the basis size in element products, so only the new rows and columns are
formed (each as one batched product over the elements of a term group), and the basis lives in
one preallocated column-major array, so appending copies nothing.

Because the columns are appended in order, the model on the first s columns is the leading
s x s block of the projected terms: every smaller model the greedy compares against is a slice.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from .sweep_operator import SweepOperator, TermGroup

#: A new direction is dropped when less than this share of it lies outside the basis.
DEPENDENT = 1e-8


class GrowingBasis:
    """V (n_free, r) with orthonormal columns and its projected operator, load and outputs.

    Attributes:
        size: columns held (r).
        reduced: (n_terms, r, r) V^H A_k V (a view of the first r rows and columns).
        load: (r,) V^H b; outputs: (n_out, 3, r) the output points' values of each column.
    """

    def __init__(self, op: SweepOperator, output_map: Callable[[NDArray], NDArray],
                 capacity: int) -> None:
        self.op = op
        self.output_map = output_map
        self._V = np.zeros((op.dofmap.n_free, capacity), dtype=complex, order="F")
        self._reduced = np.zeros((op.n_terms, capacity, capacity), dtype=complex)
        self._load = np.zeros(capacity, dtype=complex)
        self._outputs: NDArray | None = None
        # per term group, the conjugated element values of the basis, a row per column
        # (r, ne m): the leading rows of the first r columns are one contiguous block
        self._local = [np.zeros((capacity, t.group.dofs.size), dtype=complex)
                       for t in op.term_groups()]
        self.size = 0

    @property
    def capacity(self) -> int:
        return self._V.shape[1]

    @property
    def basis(self) -> NDArray:
        return self._V[:, : self.size]

    @property
    def reduced(self) -> NDArray:
        return self._reduced[:, : self.size, : self.size]

    @property
    def load(self) -> NDArray:
        return self._load[: self.size]

    @property
    def outputs(self) -> NDArray:
        assert self._outputs is not None
        return self._outputs[..., : self.size]

    def orthogonal_part(self, w: NDArray, pending: list[NDArray] = ()) -> NDArray | None:
        """``w`` orthogonalised against the basis and the orthonormal columns ``pending``
        (not yet appended), by classical Gram-Schmidt twice, and normalised; None when less
        than :data:`DEPENDENT` of it lies outside their span."""
        return orthonormalised(w, [self.basis, *([np.column_stack(pending)] if pending
                                                  else [])])

    def append(self, columns: list[NDArray]) -> None:
        """Append orthonormal columns (each orthogonal to the basis and to each other) and
        project the operator's terms, the load and the outputs onto them."""
        if not columns:
            return
        if self.size + len(columns) > self.capacity:
            self._grow(self.size + len(columns))
        old, new = self.size, self.size + len(columns)
        self._V[:, old:new] = np.column_stack(columns)
        Vn = self._V[:, old:new]
        for terms, local in zip(self.op.term_groups(), self._local, strict=True):
            values = terms.group.local(Vn)  # (ne, m, k)
            local[old:new] = values.reshape(-1, new - old).T.conj()
            self._project_new(terms, values, local[:new], old)
        self._load[old:new] = Vn.conj().T @ self.op.load
        out = self.output_map(Vn)
        if self._outputs is None:
            self._outputs = np.zeros((*out.shape[:2], self.capacity), dtype=complex)
        self._outputs[..., old:new] = out
        self.size = new

    def _project_new(self, terms: TermGroup, values: NDArray, local: NDArray,
                     old: int) -> None:
        """Add the new rows and columns (index >= ``old``) of V^H A_k V for the terms of one
        group: ``values`` (ne, m, k) the new columns' element values, ``local`` (r, ne m)
        the conjugated element values of every column.

        Every element matrix is complex symmetric (Z^T = Z), so the new rows follow from the
        products with the new columns alone: V_new^H Z V_old = (V_old^T Z conj(V_new))^T, and
        with Z = Zr + i Zi, P = Zr V_new and Q = Zi V_new give both Z V_new = P + i Q and
        Z conj(V_new) = conj(P - i Q) for the price of one complex product."""
        ne, m, k = values.shape
        r = local.shape[0]
        P = _real_product(terms.real, values)  # (t, ne, m, k)
        Q = None if terms.imag is None else _real_product(terms.imag, values)
        for j, term in enumerate(terms.index):
            Pj = P[j].reshape(ne * m, k)
            ZV = Pj if Q is None else Pj + 1j * Q[j].reshape(ne * m, k)
            self._reduced[term, :r, old:r] = local @ ZV  # V^H Z V_new
            if old:
                Zc = ZV if Q is None else Pj - 1j * Q[j].reshape(ne * m, k)
                # V_old^T Z conj(V_new) = conj(V_old^H (Zr - i Zi) V_new)
                self._reduced[term, old:r, :old] = (local[:old] @ Zc).conj().T

    def _grow(self, needed: int) -> None:
        cap = max(needed, 2 * self.capacity)
        self._V = _padded(self._V, cap, (1,), order="F")
        self._reduced = _padded(self._reduced, cap, (1, 2))
        self._load = _padded(self._load, cap, (0,))
        if self._outputs is not None:
            self._outputs = _padded(self._outputs, cap, (2,))
        self._local = [_padded(loc, cap, (0,)) for loc in self._local]

    def solve(self, coefficients: NDArray, size: int | None = None) -> NDArray:
        """Reduced coordinates (n_f, s) at the frequencies whose term coefficients are the
        rows of ``coefficients`` (n_f, n_terms), on the first ``size`` columns (all: None)."""
        s = self.size if size is None else size
        return galerkin_solve(self._reduced[:, :s, :s], self._load[:s], coefficients)

    def evaluate(self, coefficients: NDArray, size: int | None = None) -> NDArray:
        """Outputs (n_f, n_out, 3) of the model on the first ``size`` columns."""
        s = self.size if size is None else size
        return galerkin_outputs(self._reduced[:, :s, :s], self._load[:s],
                                self.outputs[..., :s], coefficients)

    def residual(self, coefficients: NDArray) -> float:
        """||A(omega) V y - b|| / ||b|| of the full operator at one frequency."""
        y = self.solve(coefficients[None])[0]
        r = self.op.apply(coefficients, self.basis @ y) - self.op.load
        return float(np.linalg.norm(r) / np.linalg.norm(self.op.load))


def orthonormalised(w: NDArray, bases: list[NDArray]) -> NDArray | None:
    """``w`` orthogonalised against the orthonormal columns of every matrix in ``bases``
    (classical Gram-Schmidt twice) and normalised; None when less than :data:`DEPENDENT` of
    it lies outside their span."""
    norm0 = np.linalg.norm(w)
    if norm0 == 0.0:
        return None
    w = w / norm0
    for _ in range(2):
        for V in bases:
            if V.shape[1]:
                # (w^H V)^H instead of V^H w: conjugates a few numbers, not the whole basis
                w = w - V @ (w.conj() @ V).conj()
    norm = np.linalg.norm(w)
    return None if norm < DEPENDENT else w / norm


def galerkin_solve(reduced: NDArray, load: NDArray, coefficients: NDArray) -> NDArray:
    """Coordinates (n_f, s) solving sum_k c_k R_k y = l for reduced terms R (n_terms, s, s),
    load l (s,) and term coefficients c (n_f, n_terms), one frequency a row."""
    A = np.tensordot(coefficients, reduced, axes=1)  # (n_f, s, s)
    b = np.broadcast_to(load, (A.shape[0], load.size))[..., None]
    return np.linalg.solve(A, b)[..., 0]


def galerkin_outputs(reduced: NDArray, load: NDArray, outputs: NDArray,
                     coefficients: NDArray) -> NDArray:
    """Outputs (n_f, n_out, 3) of a reduced model: :func:`galerkin_solve` mapped through the
    output values (n_out, 3, s) of its columns."""
    return np.einsum("ocr,fr->foc", outputs, galerkin_solve(reduced, load, coefficients))


def _padded(a: NDArray, capacity: int, axes: tuple[int, ...], order: str = "C") -> NDArray:
    """``a`` copied into zeros whose ``axes`` have length ``capacity`` (the held columns
    first)."""
    shape = [capacity if k in axes else n for k, n in enumerate(a.shape)]
    out = np.zeros(shape, dtype=a.dtype, order=order)
    out[tuple(slice(0, n) for n in a.shape)] = a
    return out


def _real_product(Z: NDArray, X: NDArray) -> NDArray:
    """Z X for real element matrices Z (t, ne, m, m) and complex element values X (ne, m, k):
    one real product on the interleaved real and imaginary parts (half the work of a complex
    one)."""
    Xr = np.ascontiguousarray(X).view(np.float64)  # (ne, m, 2k): re, im interleaved
    return np.matmul(Z, Xr).view(complex)  # (t, ne, m, k)
