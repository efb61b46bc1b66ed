"""Seeded, extendable space-filling designs on the unit hypercube [0, 1)^d.

Every design is addressed by *sample index*: ``unit_points(sampler, d, seed, start, n)`` returns
the points with indices ``start .. start + n - 1`` and the result does not depend on how the
index range is split into calls. That is what makes a dataset extendable (asking for N more
points continues the sequence instead of repeating it) and a generation run resumable.

Samplers
--------
``sobol``
    Scrambled Sobol' sequence (scipy.stats.qmc.Sobol, Owen scrambling seeded by ``seed``).
    Index ``i`` is the i-th point of one infinite sequence; a range is produced by
    ``fast_forward(start)`` then ``random(n)``. Balance properties are best when the dataset
    size is a power of two, but every prefix is low-discrepancy.
``halton``
    Scrambled Halton sequence, addressed the same way.
``lhs``
    Latin hypercube designs cannot be extended in place: an LHS of size N is not a prefix of an
    LHS of size N + M. We therefore cut the index axis into *batches* of ``lhs_batch`` points
    (default 256). Batch ``k`` is an independent LHS of size ``lhs_batch`` drawn from the
    random stream ``SeedSequence(seed, spawn_key=(k,))``; index ``i`` is row ``i % lhs_batch``
    of batch ``i // lhs_batch``. Every complete batch is stratified in every dimension (one
    point per 1/lhs_batch slab), so a dataset made of whole batches is a union of Latin
    hypercubes and stays space-filling when extended; a trailing partial batch is a uniform
    random subset of an LHS. Use sizes that are multiples of ``lhs_batch`` for best coverage.
``random``
    Plain uniform random numbers, stream ``SeedSequence(seed, spawn_key=(k,))`` per batch of
    ``lhs_batch`` indices (a baseline for comparisons).
"""

from __future__ import annotations

import warnings

import numpy as np
from scipy.stats import qmc

SAMPLERS = ("sobol", "halton", "lhs", "random")
LHS_BATCH_DEFAULT = 256
# Sobol' in scipy supports up to 2**bits points with bits <= 64; 2**30 is the default and
# far beyond any dataset this toolkit will generate.
MAX_INDEX = 2**30


def check_sampler(sampler: str) -> None:
    """Raise ValueError unless ``sampler`` is one of :data:`SAMPLERS`."""
    if sampler not in SAMPLERS:
        raise ValueError(f"sampler: unknown value {sampler!r}; allowed: {', '.join(SAMPLERS)}")


def unit_points(
    sampler: str,
    d: int,
    seed: int,
    start: int,
    n: int,
    lhs_batch: int = LHS_BATCH_DEFAULT,
) -> np.ndarray:
    """Design points with indices ``start .. start + n - 1`` as an (n, d) array in [0, 1).

    Deterministic in (sampler, d, seed, lhs_batch, index): splitting one range into several
    calls returns the same rows.
    """
    check_sampler(sampler)
    if d < 1:
        raise ValueError(f"d: need at least 1 dimension, got {d}")
    if start < 0 or n < 0 or start + n > MAX_INDEX:
        raise ValueError(f"index range [{start}, {start + n}) outside [0, {MAX_INDEX})")
    if lhs_batch < 1:
        raise ValueError(f"lhs_batch: must be >= 1, got {lhs_batch}")
    if n == 0:
        return np.empty((0, d))
    if sampler in ("sobol", "halton"):
        return _sequence_points(sampler, d, seed, start, n)
    return _batched_points(sampler, d, seed, start, n, lhs_batch)


def _sequence_points(sampler: str, d: int, seed: int, start: int, n: int) -> np.ndarray:
    engine_cls = qmc.Sobol if sampler == "sobol" else qmc.Halton
    engine = engine_cls(d, scramble=True, rng=np.random.default_rng(seed))
    if start:
        engine.fast_forward(start)
    with warnings.catch_warnings():
        # Sobol warns when n is not a power of two; prefixes of any length are still valid.
        warnings.simplefilter("ignore", UserWarning)
        return engine.random(n)


def _batch(sampler: str, d: int, seed: int, k: int, size: int) -> np.ndarray:
    rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(k,)))
    if sampler == "lhs":
        return qmc.LatinHypercube(d, rng=rng).random(size)
    return rng.random((size, d))


def _batched_points(
    sampler: str, d: int, seed: int, start: int, n: int, batch: int
) -> np.ndarray:
    first, last = start // batch, (start + n - 1) // batch
    blocks = [_batch(sampler, d, seed, k, batch) for k in range(first, last + 1)]
    rows = np.concatenate(blocks, axis=0)
    offset = start - first * batch
    return rows[offset : offset + n]
