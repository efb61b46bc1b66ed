"""What a learned model costs to get: held-out error against the number of FE samples and
against total compute (generation + training), for every kind the study trains (GP, NN, and
the peers: the scikit-learn MLP baseline and LightGBM; :func:`curves`).

Each size n trains on the first n training rows of the shipped dataset in its Sobol design
order (what a dataset of n samples would hold) and is measured on all held-out rows (the split
of ``hapticrom train``) with :mod:`.metric` against the dataset's FE answers. Generation cost
is the sum of the solver wall time the dataset recorded for those n rows (``wall_s``, one core
each); training cost is measured here. "How many simulations buy 1 %" is read off the curve:
the smallest measured n that reaches it, else a straight-line fit of log(median error) on
log(n) through the measured points, extrapolated (stated as such).
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from surrogate import kinds
from surrogate.kind import SurrogateKind
from surrogate.pod import ProfileTargets

from .designs import StudyData
from .metric import Answer, answer_from_log, errors, summary

__all__ = ["CAPPED_SIZES", "FULL_SIZES", "RUNTIME_KIND", "Fitted", "curve", "curves", "fit",
           "heldout_errors", "samples_for", "sizes"]

#: Training sizes (FE samples) of each kind the study trains. A kind with a row cap (the GP:
#: 500 rows, the size of the shipped gp-default; its O(n^3) fit takes tens of seconds there)
#: stops at its cap; the others (NN, MLP baseline, LightGBM) go to every training row.
CAPPED_SIZES = (64, 128, 256)
FULL_SIZES = (256, 512, 1024, 3277)
CAPPED_SIZES_QUICK = (32, 64)
FULL_SIZES_QUICK = (64, 128)
#: The kind also timed through the full run-time predictor.
RUNTIME_KIND = "nn"


def sizes(kind: SurrogateKind, quick: bool = False) -> tuple[int, ...]:
    """The training sizes of ``kind``'s curve: up to its row cap when it has one (``quick``:
    a smoke test of the pipeline)."""
    if kind.row_cap is None:
        return FULL_SIZES_QUICK if quick else FULL_SIZES
    return CAPPED_SIZES_QUICK if quick else (*CAPPED_SIZES, kind.row_cap)


def curves(quick: bool) -> dict[str, tuple[tuple[int, ...], dict[str, Any]]]:
    """Kind -> (training sizes, options) of a full or a ``quick`` run (its
    ``quick_options``: a smoke test of the pipeline, not a converged model), for every
    steady-state kind of the registry."""
    return {name: (sizes(kinds.KINDS[name], quick),
                   dict(kinds.KINDS[name].quick_options) if quick else {})
            for name in kinds.STEADY_KINDS}


@dataclass
class Fitted:
    """A fitted estimator with its linear output map (log outputs = est.predict(X) @ B + b)."""

    kind: str
    est: Any
    B: np.ndarray
    b: np.ndarray
    n: int
    train_s: float


def fit(kind: str, sd: StudyData, n: int, options: dict[str, Any] | None = None) -> Fitted:
    """Train ``kind`` (a steady-state kind of :mod:`surrogate.kinds`, with the defaults of
    ``hapticrom train``) on the first ``n`` training rows; time the fit (targets included) [s].
    An estimator that subsamples (``max_train``) is told to use all ``n`` rows."""
    spec = kinds.get(kind, "kind", steady=True)
    if not 2 <= n <= sd.train.size:
        raise ValueError(f"n = {n}: allowed 2..{sd.train.size} training rows")
    rows = sd.train[:n]
    d = sd.data
    t0 = time.perf_counter()
    targets = ProfileTargets(n_modes=spec.pod_modes)
    T = targets.fit_transform(d.center_um[rows], d.profile_um[rows])
    assert spec.estimator is not None
    est = spec.estimator(random_state=0, **dict(options or {}))
    if "max_train" in est.get_params():
        est.set_params(max_train=max(n, 2))
    est.fit(sd.X[rows], T)
    B, b = targets.output_map()
    return Fitted(kind, est, B, b, n, time.perf_counter() - t0)


def truth(sd: StudyData, rows: np.ndarray) -> Answer:
    """The dataset's FE answers of ``rows``."""
    d = sd.data
    return Answer(d.center_um[rows], d.profile_um[rows, 0], d.profile_um[rows])


def heldout_errors(m: Fitted, sd: StudyData) -> dict[str, float]:
    """Error summary of ``m`` (in-memory estimator, float64 map) on the held-out rows."""
    pred = answer_from_log(m.est.predict(sd.X[sd.test]) @ m.B + m.b)
    return summary(errors(pred, truth(sd, sd.test)))


def curve(kind: str, sd: StudyData, sizes: Sequence[int],
          options: dict[str, Any] | None = None) -> tuple[list[dict[str, Any]], Fitted]:
    """One row per size: n, generation [s], training [s], total [s] and the held-out error
    summary; and the model of the largest size."""
    rows, last = [], None
    for n in sizes:
        last = fit(kind, sd, n, options)
        gen = float(np.sum(sd.wall_s[sd.train[:n]]))
        rows.append({"kind": kind, "n": n, "generation_s": gen, "train_s": last.train_s,
                     "total_s": gen + last.train_s, **heldout_errors(last, sd)})
    assert last is not None
    return rows, last


def samples_for(rows: Sequence[dict[str, Any]], target: float = 0.01,
                key: str = "worst_median") -> dict[str, Any]:
    """FE samples (and total compute [s]) that reach ``target`` on ``key``: measured when a
    row does, else extrapolated on the log-log line through the rows (``extrapolated``)."""
    for r in rows:
        if r[key] <= target:
            return {"n": r["n"], "total_s": r["total_s"], "extrapolated": False, "slope": None}
    n = np.log([r["n"] for r in rows])
    e = np.log([r[key] for r in rows])
    if len(rows) < 2 or not np.all(np.isfinite(e)):
        return {"n": None, "total_s": None, "extrapolated": True, "slope": None}
    slope, icpt = np.polyfit(n, e, 1)
    if slope >= 0:
        return {"n": None, "total_s": None, "extrapolated": True, "slope": float(slope)}
    need = float(np.exp((np.log(target) - icpt) / slope))
    per_row = rows[-1]["generation_s"] / rows[-1]["n"]
    return {"n": need, "total_s": need * per_row, "extrapolated": True, "slope": float(slope)}
