"""The band basis of a sweep model factored for a cheap decode: per POD block, a spatial basis
shared by every band frequency, and per group of modes its own number of spatial vectors.

A block of :class:`surrogate.sweep.targets.BandTargets` rebuilds the weighted normalised
components of its ``L`` values (locations x 6 parts) at band frequency ``f`` as
``mean[f] + c @ modes[f]`` with ``modes[f]`` of shape (k, L). Factored::

    modes[f][g] ~= A_g[f] @ Psi[:S_g],   mean[f] ~= a[f] @ Psi,   Psi: (S, L), S = max S_g

with ``Psi`` the right singular vectors of the block's weighted components over the fitting
designs and every band frequency (uncentred: the mean is rebuilt too) and ``g`` the groups of
consecutive POD modes (:data:`GROUP_EDGES`). A row of the decode gathers, per group, ``A_g`` at
its two grid points (k_g x S_g each) and all rows share one dense product by ``Psi``, so the
per-row work is sum_g k_g S_g rather than k L.

The POD coefficients of the fitting designs are centred and mutually orthogonal, so the
squared error of the components over those designs is exactly the sum of each mode's
(coefficient energy x its basis energy beyond S_g) plus the mean's: the ranks are the
cheapest (least sum_g k_g S_g, by a Lagrangian sweep) whose relative error
sqrt(error / total) is at most ``tol``. At S_g = L ``Psi`` is orthogonal and the
factorisation exact.

Arrays are dimensionless (components divided by the band's RMS centre amplitude and, in the
weighted space, by a per-location weight; :attr:`SpatialFactor.psi` has the weights folded
back in, so it maps to normalised components).
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

__all__ = ["GROUP_EDGES", "SpatialFactor", "factor_block", "tail_error"]

#: First mode of each group after the first (groups of 16, 16, 32, 64, 128, ... modes): the
#: leading modes carry most of the energy and need the most spatial vectors.
GROUP_EDGES = (16, 32, 64, 128, 256, 512, 1024)
#: Numbers per row a group must save to stay apart from its neighbour (its own gather,
#: product and padding cost about as much at batch 10,000; and some 20 us at batch 1)
GROUP_OVERHEAD = 256


@dataclass(frozen=True)
class SpatialFactor:
    """One block's factored basis. ``groups``: the groups' mode ranges in the block,
    ``coefs``: per group (n_f, k_g, S_g), ``mean``: (n_f, S), ``psi``: (S, L) with the
    location weights folded in (S = the largest S_g); ``rel_error``: the relative error of
    the block's weighted components on the fitting designs at these ranks; ``spectrum``:
    (L,) the squared singular values of those components, descending."""

    groups: tuple[slice, ...]
    coefs: tuple[np.ndarray, ...]
    mean: np.ndarray
    psi: np.ndarray
    rel_error: float
    spectrum: np.ndarray

    @property
    def ranks(self) -> tuple[int, ...]:
        """S_g of each group."""
        return tuple(int(c.shape[2]) for c in self.coefs)

    @property
    def rank(self) -> int:
        """S, the spatial basis's size (the largest S_g)."""
        return int(self.psi.shape[0])

    def row_work(self) -> int:
        """Numbers gathered per row and grid point: sum_g k_g S_g."""
        return sum(int(c.shape[1] * c.shape[2]) for c in self.coefs)

    def modes(self) -> np.ndarray:
        """The effective basis (n_f, k, L)."""
        return np.concatenate([c @ self.psi[:c.shape[2]] for c in self.coefs], axis=1)

    def means(self) -> np.ndarray:
        """The effective means (n_f, L): ``mean[f] @ psi``."""
        return self.mean @ self.psi


def tail_error(spectrum: np.ndarray) -> np.ndarray:
    """(L + 1,) relative error sqrt(discarded / total) of keeping the first S = 0..L of the
    squared singular values ``spectrum`` (descending)."""
    total = float(spectrum.sum())
    tail = np.concatenate([np.cumsum(spectrum[::-1])[::-1], [0.0]])
    return np.sqrt(np.maximum(tail, 0.0) / total) if total > 0 else np.zeros(tail.size)


def mode_groups(k: int) -> tuple[slice, ...]:
    """The groups of ``k`` consecutive modes (:data:`GROUP_EDGES`)."""
    edges = [0, *(e for e in GROUP_EDGES if e < k), k]
    return tuple(slice(a, b) for a, b in itertools.pairwise(edges))


def _ranks(tails: np.ndarray, sizes: np.ndarray, budget: float) -> np.ndarray:
    """Per group the rank S_g in 1..L of least sum sizes_g S_g with sum_g tails[g, S_g] <=
    ``budget`` (``tails`` (G, L + 1): each group's squared error keeping S vectors), over
    the Lagrangian's choices argmin_S tails[g, S] + mu sizes_g S."""
    L = tails.shape[1] - 1
    S = np.arange(1, L + 1)

    def choose(mu: float) -> np.ndarray:
        return 1 + np.argmin(tails[:, 1:] + mu * sizes[:, None] * S[None, :], axis=1)

    def error(ranks: np.ndarray) -> float:
        return float(tails[np.arange(len(ranks)), ranks].sum())

    if error(choose(0.0)) > budget:
        return np.full(len(sizes), L)
    lo, hi = 0.0, float(tails.max()) + 1.0  # at hi every group keeps one vector
    if error(choose(hi)) <= budget:
        return choose(hi)
    for _ in range(100):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if error(choose(mid)) <= budget else (lo, mid)
    return choose(lo)


def factor_block(modes: np.ndarray, mean: np.ndarray, coefficients: np.ndarray,
                 weights: np.ndarray, *, tol: float = 1e-3,
                 ranks: tuple[int, ...] | None = None, merge: bool = True) -> SpatialFactor:
    """Factor one block: weighted ``modes`` (n_f, k, L), ``mean`` (n_f, L), the fitting
    designs' (centred) POD ``coefficients`` (n, k) and the per-value ``weights`` (L,) (a
    location's weight on each of its 6 parts). The ranks are ``ranks`` (one per group of
    :func:`mode_groups`) when given, else the cheapest with relative error <= ``tol``
    (``tol`` 0: every S_g = L, exact); then adjacent groups merged (:func:`_merge`) unless
    not ``merge``."""
    k, L = modes.shape[1:]
    n = coefficients.shape[0]
    energy = np.sum(np.square(coefficients), axis=0)                   # (k,)
    gram = n * mean.T @ mean + np.einsum("fkl,k,fkm->lm", modes, energy, modes)
    spectrum, vectors = np.linalg.eigh(gram)
    order = np.argsort(spectrum)[::-1]
    spectrum, vectors = np.maximum(spectrum[order], 0.0), vectors[:, order]
    rotated = modes @ vectors                                          # (n_f, k, L)
    groups = mode_groups(k)
    # each group's and the mean's squared error keeping S = 0..L vectors
    per_mode = energy[:, None] * np.sum(np.square(rotated), axis=0)    # (k, L)
    tails = np.array([_tails(per_mode[g].sum(axis=0)) for g in groups])
    mean_tail = _tails(n * np.sum(np.square(mean @ vectors), axis=0))
    total = float(spectrum.sum())
    mean_rank = 1
    if ranks is None and tol <= 0:
        ranks = (L,) * len(groups)
    elif ranks is None:  # the mean as one more group, of one mode (S is then its rank or more)
        sizes = np.array([g.stop - g.start for g in groups] + [1], dtype=float)
        chosen = _ranks(np.vstack([tails, mean_tail]), sizes, tol**2 * total)
        ranks, mean_rank = tuple(int(r) for r in chosen[:-1]), int(chosen[-1])
    if len(ranks) != len(groups) or not all(1 <= r <= L for r in ranks):
        raise ValueError(f"spatial ranks {tuple(ranks)}: need {len(groups)} ranks in 1..{L}")
    merged, ranks = _merge(groups, tuple(ranks)) if merge else (groups, tuple(ranks))
    S = max(*ranks, mean_rank)
    kept = [r for g, r in zip(merged, ranks, strict=True) for h in groups
            if g.start <= h.start < g.stop]                   # each first group's rank now
    err = mean_tail[S] + sum(tails[j, r] for j, r in enumerate(kept))
    groups = merged
    return SpatialFactor(groups=groups,
                         coefs=tuple(rotated[:, g, :r] for g, r in zip(groups, ranks,
                                                                       strict=True)),
                         mean=mean @ vectors[:, :S], psi=vectors[:, :S].T * weights[None, :],
                         rel_error=float(np.sqrt(max(err, 0.0) / total)) if total > 0 else 0.0,
                         spectrum=spectrum)


def _merge(groups: tuple[slice, ...], ranks: tuple[int, ...]
           ) -> tuple[tuple[slice, ...], tuple[int, ...]]:
    """Adjacent groups as one, at the larger rank (the error only falls), while a merge adds
    at most :data:`GROUP_OVERHEAD` numbers to a row's gather: a group's own products cost
    more than that (fewer, larger products in the graph)."""
    groups, ranks = list(groups), list(ranks)
    while len(groups) > 1:
        extra = [(g0.stop - g0.start) * (max(r0, r1) - r0) + (g1.stop - g1.start)
                 * (max(r0, r1) - r1) for g0, g1, r0, r1
                 in zip(groups[:-1], groups[1:], ranks[:-1], ranks[1:], strict=True)]
        i = int(np.argmin(extra))
        if extra[i] > GROUP_OVERHEAD:
            break
        groups[i:i + 2] = [slice(groups[i].start, groups[i + 1].stop)]
        ranks[i:i + 2] = [max(ranks[i], ranks[i + 1])]
    return tuple(groups), tuple(ranks)


def _tails(energy_per_vector: np.ndarray) -> np.ndarray:
    """(L + 1,) the energy beyond the first S = 0..L vectors."""
    return np.concatenate([np.cumsum(energy_per_vector[::-1])[::-1], [0.0]])
