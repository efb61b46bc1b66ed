"""The band basis of a sweep model factored for a cheap decode: per POD block, a spatial basis
shared by every band frequency.

A block of :class:`surrogate.sweep_targets.BandTargets` rebuilds the weighted normalised
components of its ``L`` values (locations x 6 parts) at band frequency ``f`` as
``mean[f] + c @ modes[f]`` with ``modes[f]`` of shape (k, L). Factored::

    modes[f] ~= A[f] @ Psi,   mean[f] ~= a0[f] @ Psi,   A[f]: (k, S), Psi: (S, L), S <= L

with ``Psi`` the leading right singular vectors of the block's weighted components over the
fitting designs and every band frequency (uncentred: the mean is rebuilt too), so a row of
the decode gathers ``A`` at its two grid points (k x S each) and all rows share one dense
product by ``Psi``. The rank ``S`` is the smallest whose relative error of those components,
sqrt(discarded / total squared singular values), is at most ``tol``; at ``S = L`` ``Psi`` is
orthogonal and the factorisation exact.

Arrays are dimensionless (components divided by the band's RMS centre amplitude and, in the
weighted space, by a per-location weight; :attr:`SpatialFactor.psi` has the weights folded
back in, so it maps to normalised components).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["SpatialFactor", "factor_block"]


@dataclass(frozen=True)
class SpatialFactor:
    """One block's factored basis. ``coef``: (n_f, k, S) per band frequency, ``mean``:
    (n_f, S), ``psi``: (S, L) with the location weights folded in; ``rel_error``: the relative
    error of the block's weighted components on the fitting designs at this rank;
    ``spectrum``: (L,) all squared singular values, descending (the rank choice's data)."""

    coef: np.ndarray
    mean: np.ndarray
    psi: np.ndarray
    rel_error: float
    spectrum: np.ndarray

    @property
    def rank(self) -> int:
        """S, the spatial basis's size."""
        return int(self.psi.shape[0])

    def modes(self) -> np.ndarray:
        """The effective basis (n_f, k, L): ``coef[f] @ psi``."""
        return self.coef @ self.psi

    def means(self) -> np.ndarray:
        """The effective means (n_f, L): ``mean[f] @ psi``."""
        return self.mean @ self.psi


def tail_error(spectrum: np.ndarray) -> np.ndarray:
    """(L + 1,) relative error sqrt(discarded / total) of keeping the first S = 0..L of the
    squared singular values ``spectrum`` (descending)."""
    total = float(spectrum.sum())
    tail = np.concatenate([np.cumsum(spectrum[::-1])[::-1], [0.0]])
    return np.sqrt(np.maximum(tail, 0.0) / total) if total > 0 else np.zeros(tail.size)


def factor_block(modes: np.ndarray, mean: np.ndarray, coefficients: np.ndarray,
                 weights: np.ndarray, *, tol: float = 1e-3, rank: int | None = None
                 ) -> SpatialFactor:
    """Factor one block: weighted ``modes`` (n_f, k, L), ``mean`` (n_f, L), the fitting
    designs' ``coefficients`` (n, k) and the per-value ``weights`` (L,) (a location's weight on
    each of its 6 parts). The rank is ``rank`` when given, else the smallest with relative
    error <= ``tol`` (at least 1; ``tol`` 0: L, exact)."""
    n_f, L = modes.shape[0], modes.shape[2]
    gram = np.zeros((L, L))
    for f in range(n_f):  # the (n * n_f, L) components, one frequency at a time
        z = mean[f] + coefficients @ modes[f]
        gram += z.T @ z
    spectrum, vectors = np.linalg.eigh(gram)
    order = np.argsort(spectrum)[::-1]
    spectrum, vectors = np.maximum(spectrum[order], 0.0), vectors[:, order]
    errors = tail_error(spectrum)
    if rank is None:  # tol 0: every vector (the discarded tail may round to 0 before L)
        rank = L if tol <= 0 else max(1, int(np.argmax(errors <= tol)))
    if not 1 <= rank <= L:
        raise ValueError(f"spatial rank {rank}: must be in 1..{L}")
    keep = vectors[:, :rank]                                 # (L, S), orthonormal columns
    return SpatialFactor(coef=modes @ keep, mean=mean @ keep, psi=keep.T * weights[None, :],
                         rel_error=float(errors[rank]), spectrum=spectrum)
