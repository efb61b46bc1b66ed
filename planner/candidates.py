"""Candidate designs for ``[[design]] any = true``: designs drawn from the model's trained
input ranges (run time only: numpy and the model card's input specs).

Every model input not fixed by the request (the ``[site]`` table, the drive frequency, the
keys given in the ``any`` design table) is free:

* categorical inputs and integer inputs (e.g. ``n_rings``) are enumerated: every combination
  of their values (at most ``MAX_COMBINATIONS``), cycled over the candidates, so each
  combination gets ``n_candidates / combinations`` of them (``n_candidates`` must be at least
  the number of combinations);
* continuous inputs are drawn on a stratified Latin hypercube of ``n_candidates`` points in
  the unit cube (one point per 1/n stratum in every dimension, McKay, Beckman & Conover 1979,
  Technometrics 21(2) 239-245), mapped to the trained range on the input's own scale (log
  inputs log-uniformly); numpy's generator with the design's ``seed`` makes it
  deterministic.

Conditional inputs (a ring modulus when there are fewer rings) are drawn like the others; the
model's encoding ignores them where they do not apply.
"""

from __future__ import annotations

import itertools
from typing import Any

import numpy as np

from surrogate.runtime.encoding import InputSpec

__all__ = ["MAX_COMBINATIONS", "expand_any", "latin_hypercube"]

MAX_COMBINATIONS = 1024  # enumerated categorical x integer combinations, at most


def latin_hypercube(n: int, d: int, seed: int) -> np.ndarray:
    """(n, d) points in [0, 1): column j holds one point in each stratum [k/n, (k+1)/n),
    in a random order (numpy's PCG64 generator seeded with ``seed``)."""
    rng = np.random.default_rng(seed)
    strata = np.column_stack([rng.permutation(n) for _ in range(d)]) if d else np.zeros((n, 0))
    return (strata + rng.random((n, d))) / n


def _to_range(u: np.ndarray, spec: InputSpec) -> np.ndarray:
    """Unit-cube values to the input's trained range (log-uniform for log inputs)."""
    lo, hi = float(spec.low), float(spec.high)  # type: ignore[arg-type]
    if spec.scale == "log":
        return np.exp(np.log(lo) + u * (np.log(hi) - np.log(lo)))
    return lo + u * (hi - lo)


def _levels(spec: InputSpec) -> list[Any]:
    if spec.type == "categorical":
        return list(spec.choices)
    return list(range(int(np.ceil(spec.low)), int(np.floor(spec.high)) + 1))  # type: ignore


def expand_any(design: dict[str, Any], specs: list[InputSpec], fixed: set[str],
               where: str) -> list[dict[str, Any]]:
    """The ``n_candidates`` designs of one ``any = true`` design table: ``{"name", "inputs"}``
    with every input of ``specs`` not in ``fixed`` (site and frequency) or in the table's
    own inputs. Raises ValueError (naming ``where``) when the enumeration does not fit."""
    n, seed, given = design["n_candidates"], design["seed"], design["inputs"]
    free = [s for s in specs if s.name not in fixed and s.name not in given]
    discrete = [s for s in free if s.type != "continuous"]
    continuous = [s for s in free if s.type == "continuous"]
    combos = list(itertools.islice(itertools.product(*[_levels(s) for s in discrete]),
                                   MAX_COMBINATIONS + 1))
    if len(combos) > MAX_COMBINATIONS or len(combos) > n:
        names = ", ".join(s.name for s in discrete)
        raise ValueError(f"{where}.n_candidates = {n}: the categorical and integer inputs "
                         f"({names}) have {len(combos)}"
                         f"{'+' if len(combos) > MAX_COMBINATIONS else ''} combinations; give "
                         "at least that many candidates or fix some of them in the design")
    u = latin_hypercube(n, len(continuous), seed)
    values = {s.name: _to_range(u[:, j], s) for j, s in enumerate(continuous)}
    out = []
    for k in range(n):
        inputs = dict(given)
        inputs.update(zip((s.name for s in discrete), combos[k % len(combos)], strict=True))
        inputs.update({name: float(v[k]) for name, v in values.items()})
        out.append({"name": f"{design['name']} #{k}", "inputs": inputs,
                    "family": design["name"]})
    return out
