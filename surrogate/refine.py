"""Active learning: run new FE samples where a Gaussian process is least certain.

Each round fits the project's GP (:class:`surrogate.estimators.gp.GPSurrogateRegressor`) to the log
center and log edge amplitudes of the dataset, scores a pool of candidate design points of
the dataset's own space (the next points of its design sequence, so every refined sample is
an ordinary, reproducible sample of the space), and runs the ``batch`` candidates with the
largest predictive variance, spread out by a minimum distance in feature space so one batch
does not spend itself on one corner. The new rows join the dataset (``generate(only=...)``);
retrain the shipped models from it with ``hapticrom train``.

Selection works on any pool: :func:`select_batch` is also what ``bench/surrogate/refine.py``
uses to compare refinement against plain Sobol order on the shipped dataset, and, with a sweep
model's :func:`band_disagreement` as the score, what ``bench/surrogate/refine_sweep.py``
(:mod:`studies.fewer_designs.active`) uses on a sweep dataset.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from surrogate.data.generate import generate
from surrogate.data.plan import plan_samples
from surrogate.data.store import Store
from surrogate.estimators.gp import GPSurrogateRegressor
from surrogate.features import codes_from_frame
from surrogate.runtime.encoding import encode
from surrogate.train import load_datasets

__all__ = ["RefineReport", "band_disagreement", "refine", "select_batch", "uncertainty"]

#: Candidates scored per sample asked for.
POOL_PER_SAMPLE = 16
#: Rows the GP of a round is fitted on at most (its cost is cubic in them).
MAX_GP_ROWS = 1000


@dataclass
class RefineReport:
    """What a refinement run did: per round the rows before, the samples added and the mean
    predictive log std of the picked points before they were solved."""

    path: Path
    rounds: list[dict[str, Any]] = field(default_factory=list)


def fit_log_amplitudes(X: np.ndarray, center_um: np.ndarray, edge_um: np.ndarray,
                       seed: int = 0, max_train: int = MAX_GP_ROWS) -> Any:
    """A GP on (log center, log edge) amplitudes of feature rows ``X``."""
    T = np.column_stack([np.log(center_um), np.log(edge_um)])
    return GPSurrogateRegressor(max_train=max_train, random_state=seed).fit(X, T)


def uncertainty(model: Any, X: np.ndarray) -> np.ndarray:
    """Total predictive variance of the log amplitudes at feature rows ``X``."""
    _, std = model.predict(X, return_std=True)
    return np.sum(np.atleast_2d(std.T).T ** 2, axis=1)


def band_disagreement(predictor: Any, codes: np.ndarray, band_hz: np.ndarray,
                      outputs: tuple[str, ...] = ("center_amplitude_um", "edge_amplitude_um"),
                      chunk: int = 256) -> np.ndarray:
    """Per design of ``codes`` (n, d: design codes without the frequency), a sweep model's
    disagreement with itself: its log std of ``outputs`` (for an NN ensemble the members'
    spread of ln |u|, for a GP its predictive std) averaged over the frequencies ``band_hz``
    and the outputs. ``predictor``: a :class:`surrogate.runtime.predictor.Predictor` whose
    last input is ``frequency_hz`` (load it with ``calibrated=False`` for the graph's raw
    spread)."""
    n_f = len(band_hz)
    out = np.empty(len(codes))
    for a in range(0, len(codes), chunk):
        block = codes[a:a + chunk]
        pairs = np.column_stack([np.repeat(block, n_f, axis=0), np.tile(band_hz, len(block))])
        pred = predictor.predict(pairs)
        std = np.stack([pred[f"{name}_log_std"] for name in outputs], axis=-1)
        out[a:a + chunk] = std.reshape(len(block), -1).mean(axis=1)
    return out


def select_batch(score: np.ndarray, X: np.ndarray, k: int,
                 min_distance: float | None = None) -> np.ndarray:
    """Indices of ``k`` rows of ``X`` with the highest ``score``, greedily skipping rows closer
    than ``min_distance`` (Euclidean, feature space) to a row already picked; the distance
    halves until ``k`` rows are found. Default distance: half the median nearest-neighbour
    spacing a pool of this size would have in the unit cube of ``X``'s width."""
    n, d = X.shape
    if not 0 < k <= n:
        raise ValueError(f"k = {k}: must be in [1, {n}] (the pool size)")
    radius = 0.5 * n ** (-1.0 / max(d, 1)) if min_distance is None else float(min_distance)
    order = np.argsort(-score, kind="stable")
    while True:
        picked: list[int] = []
        for i in order:
            if picked and np.min(np.linalg.norm(X[picked] - X[i], axis=1)) < radius:
                continue
            picked.append(int(i))
            if len(picked) == k:
                return np.array(picked)
        radius /= 2.0


def _round(path: Path, batch: int, seed: int, workers: int | None, progress: bool,
           command: str) -> dict[str, Any]:
    data = load_datasets([path])
    X = encode(data.codes, data.specs)
    model = fit_log_amplitudes(X, data.center_um, data.profile_um[:, 0], seed)
    store = Store.open(path)
    _, by_index = store.keys()
    n_pool = len(by_index) + POOL_PER_SAMPLE * batch
    planned, _ = plan_samples(store.space, n_pool)
    pool = [p for p in planned if p.index not in by_index]
    if len(pool) < batch:
        raise ValueError(f"batch = {batch}: only {len(pool)} new candidate points")
    frame = pd.DataFrame([p.values for p in pool])
    Xp = encode(codes_from_frame(frame, data.specs), data.specs)
    score = uncertainty(model, Xp)
    pick = select_batch(score, Xp, batch)
    rep = generate(store.space, n_pool, path, workers=workers, progress=progress,
                   command=command, only=[pool[i].index for i in pick])
    return {"rows_before": len(X), "added_ok": rep.new_ok, "added_failed": rep.new_failed,
            "pool": len(pool), "mean_log_std_picked": float(np.sqrt(score[pick]).mean()),
            "mean_log_std_pool": float(np.sqrt(score).mean())}


def refine(dataset: str | Path, batch: int, *, rounds: int = 1, seed: int = 0,
           workers: int | None = None, progress: bool = True, command: str = "",
           on_round: Callable[[dict[str, Any]], None] | None = None) -> RefineReport:
    """Add ``rounds`` x ``batch`` FE samples to ``dataset`` where the GP is least certain."""
    for name, value, lo in (("batch", batch, 1), ("rounds", rounds, 1)):
        if isinstance(value, bool) or not isinstance(value, int) or value < lo:
            raise ValueError(f"{name} = {value!r}: need an integer >= {lo}")
    path = Path(dataset)
    report = RefineReport(path)
    for r in range(rounds):
        info = _round(path, batch, seed + r, workers, progress, command)
        report.rounds.append(info)
        if on_round is not None:
            on_round(info)
    return report
