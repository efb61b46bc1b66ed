"""The search: a well-kept optimiser for mixed spaces walks the design space
(:class:`planner.design.space.DesignSpace`) and asks the evaluator for batches of designs.

* ``tpe``: Optuna's tree-structured Parzen estimator, define-by-run so the ring entries a
  ring count does not use are not sampled (a conditional space), asked a batch of trials at a
  time with the constant liar (Bergstra et al. 2011; Optuna, Akiba et al. 2019); on a
  discrete space it keeps proposing designs already seen and each ask costs more with every
  trial, so it stops after :data:`TPE_ASKS` trials per design of the budget;
* ``cmaes``: CMA-ES of the ``cma`` package (Hansen) with its integer handling, restarted with
  the next seed when it stops early;
* ``de``: scipy's differential evolution with ``integrality`` (one vectorised call per
  generation);
* ``grid``: every design of the exhaustive grid (:meth:`DesignSpace.grid`), the reference
  the others are measured against (bench/planner/design.py).

Entries with a single value (a space narrowed to one orientation, say) are held fixed. Every
method stops once ``budget`` distinct designs were evaluated (the grid: all of it); a run
that has converged (:data:`STALL` batches without a new design) is restarted with the next
seed (cmaes, de; at most :data:`MAX_RESTARTS` times) or ends (tpe). Each is deterministic for
a seed.
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Callable
from typing import Any

import numpy as np

from planner.design.evaluate import Evaluation
from planner.design.space import DesignSpace

__all__ = ["METHODS", "run_search"]

STALL = 25  # batches in a row without a new design: the run has converged (restarted)
MAX_RESTARTS = 20  # converged runs (cmaes, de) before the space counts as exhausted
TPE_ASKS = 10  # tpe: trials asked per design of the budget, at most (its asks cost O(trials))

Evaluate = Callable[[list[dict[str, Any]]], list[Evaluation]]


class _Walk:
    """The free entries of the space's box, and the evaluation of points in it."""

    def __init__(self, space: DesignSpace, evaluator: Any, budget: int) -> None:
        lo, hi, integer = space.bounds
        self.space, self.evaluator, self.budget = space, evaluator, budget
        self.free = hi > lo
        self.lo, self.hi, self.integer = lo, hi, integer
        self.points = 0
        self.stalled = 0
        self.restarts = 0

    @property
    def done(self) -> bool:
        """The budget is spent, or the current run has converged."""
        return self.evaluator.unique >= self.budget or self.stalled >= STALL

    def restart(self) -> bool:
        """Whether to start another run (a converged one restarts with the next seed)."""
        if self.evaluator.unique >= self.budget or self.restarts >= MAX_RESTARTS:
            return False
        self.restarts += 1
        self.stalled = 0
        return True

    def full(self, z: np.ndarray) -> np.ndarray:
        x = self.lo.copy()
        x[self.free] = z
        return x

    def scores(self, Z: np.ndarray) -> np.ndarray:
        """Scores of the free-entry points ``Z`` (k, n_free), one batch."""
        before = self.evaluator.unique
        evs = self.evaluator([self.space.decode(self.full(z)) for z in Z])
        self.points += len(Z)
        self.stalled = 0 if self.evaluator.unique > before else self.stalled + 1
        return np.array([e.score for e in evs], dtype=float)


def _grid(w: _Walk, batch: int, seed: int) -> None:
    designs = w.space.grid()
    for i in range(0, len(designs), batch):
        w.evaluator(designs[i:i + batch])
        w.points += len(designs[i:i + batch])


def _tpe(w: _Walk, batch: int, seed: int) -> None:
    # lazy: optuna (the `design` extra, 0.22 s to import) only for search.optimiser = "tpe"
    import optuna

    optuna.logging.set_verbosity(optuna.logging.WARNING)
    with warnings.catch_warnings():  # constant_liar is "experimental"
        warnings.simplefilter("ignore", optuna.exceptions.ExperimentalWarning)
        sampler = optuna.samplers.TPESampler(seed=seed, constant_liar=True,
                                             n_startup_trials=max(10, w.budget // 10))
    study = optuna.create_study(direction="minimize", sampler=sampler)
    dims = [d for d, f in zip(w.space.dimensions, w.free, strict=True) if f]
    rings = w.space.spec.n_rings
    while not w.done and w.points < TPE_ASKS * w.budget:
        trials = [study.ask() for _ in range(batch)]
        Z = np.array([_suggest(t, dims, rings) for t in trials])
        for t, s in zip(trials, w.scores(Z), strict=True):
            study.tell(t, float(s))


def _suggest(trial: Any, dims: list, rings: tuple[int, ...]) -> list[float]:
    """One trial's free entries; ring entries beyond its ring count are not sampled."""
    z, n = [], (rings[0] if len(rings) == 1 else None)
    for d in dims:
        if n is not None and d.min_rings > n:
            z.append(d.low)
            continue
        v = (trial.suggest_categorical(d.name, list(range(int(d.high) + 1))) if d.integer
             else trial.suggest_float(d.name, d.low, d.high))
        if d.name == "n_rings":
            n = rings[int(v)]
        z.append(float(v))
    return z


def _cmaes(w: _Walk, batch: int, seed: int) -> None:
    # lazy: cma (the `design` extra, 2.3 s to import) only for search.optimiser = "cmaes"
    import cma

    lo, hi, integer = w.lo[w.free], w.hi[w.free], w.integer[w.free]
    while True:
        opts = {"seed": seed + 1 + w.restarts, "bounds": [list(lo - 0.49 * integer),
                                                      list(hi + 0.49 * integer)],
                "CMA_stds": list(0.3 * (hi - lo + integer)), "popsize": max(batch, 4),
                "integer_variables": [int(i) for i in np.flatnonzero(integer)],
                "verbose": -9, "verb_log": 0, "verb_disp": 0}
        es = cma.CMAEvolutionStrategy(list(0.5 * (lo + hi)), 1.0, opts)
        while not es.stop() and not w.done:
            X = es.ask()
            es.tell(X, list(w.scores(np.array(X))))
        if not w.restart():
            return


def _de(w: _Walk, batch: int, seed: int) -> None:
    # lazy: scipy.optimize only for the optimiser that runs (the others import their own)
    from scipy.optimize import differential_evolution

    lo, hi, integer = w.lo[w.free], w.hi[w.free], w.integer[w.free]

    def stop(intermediate_result: Any) -> bool:
        return w.done

    while True:
        differential_evolution(lambda Z: w.scores(np.atleast_2d(Z.T)), list(zip(lo, hi,
                                                                                 strict=True)),
                               integrality=integer, seed=seed + w.restarts, vectorized=True,
                               updating="deferred", polish=False, maxiter=100_000, tol=0.0,
                               popsize=max(2, -(-batch // max(1, len(lo)))), callback=stop)
        if not w.restart():
            return


METHODS: dict[str, Callable[[_Walk, int, int], None]] = {"tpe": _tpe, "cmaes": _cmaes,
                                                         "de": _de, "grid": _grid}


def run_search(space: DesignSpace, evaluator: Any, optimiser: str, budget: int, batch: int,
               seed: int) -> dict[str, Any]:
    """Search ``space`` with ``optimiser`` (:data:`METHODS`), ``evaluator`` a
    :class:`planner.design.evaluate.Evaluator`; returns what the search did (its history is
    the evaluator's)."""
    t0 = time.perf_counter()
    w = _Walk(space, evaluator, budget)
    if not w.free.any():  # one design: nothing to search
        evaluator([space.decode(w.lo)])
    else:
        METHODS[optimiser](w, batch, seed)
    return {"optimiser": optimiser, "seed": seed, "budget": budget, "batch": batch,
            "points_asked": w.points, "designs_evaluated": evaluator.unique,
            "batches": evaluator.batches, "restarts": w.restarts,
            "exhausted": w.evaluator.unique < budget and optimiser != "grid",
            "wall_s": round(time.perf_counter() - t0, 3),
            "evaluation_wall_s": round(evaluator.wall_s, 3)}
