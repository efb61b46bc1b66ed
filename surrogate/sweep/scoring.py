"""The card's ``test_set``: a sweep model scored on fresh designs (``hapticrom train --data
SWEEP_DIR --test-data TEST_DIR``; TEST_DIR a dataset of the same space at another Sobol seed,
``datasets/spaces/default-sweep-test.toml``).

Every (design, band frequency) pair of the test datasets is predicted through the exported
graph and the run-time encoder and scored as the held-out split is
(:func:`surrogate.sweep.train.sweep_metrics`: median / p95 / p99 / max relative errors, the
largest error on the field's scale, profile relative L2 over the whole grid, 95 % coverage).
The entry records each test dataset's manifest digest, space hash, Sobol seed and size, so the
card says which designs it was scored on.

The benches and the accuracy study score any model the same way at the same pairs with
:func:`predict_pairs` (a run-time predictor, its profile on its own grid) and
:func:`score_pairs` (``bench/surrogate/sweep_nn.py``, ``hapticrom bench accuracy``).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from fieldspec import FieldError
from surrogate.data.store import Store
from surrogate.runtime.predictor import Predictor
from surrogate.sweep.targets import SweepData, load_sweep_datasets

__all__ = ["load_test_data", "named_inputs", "predict_pairs", "score_pairs", "score_test_set"]


def _seed(path: str | Path) -> int:
    return int(Store.open(path).space.seed)


def load_test_data(paths: Sequence[str | Path], train: SweepData, categorical: str
                   ) -> SweepData:
    """The test datasets, refused (:class:`FieldError` ``--test-data``) when they are not
    sweeps on the training data's band and profile grid or repeat a training dataset's
    designs (the same space at the same seed)."""
    test = load_sweep_datasets(paths, categorical=categorical)
    if not (np.array_equal(test.band_hz, train.band_hz)
            and np.array_equal(test.grid_mm, train.grid_mm)):
        raise FieldError("--test-data", "--test-data: the test datasets' band "
                         f"({test.band_hz[0]:g}-{test.band_hz[-1]:g} Hz, {test.band_hz.size} "
                         f"frequencies) or profile grid ({test.grid_mm.size} points) differ "
                         "from the training data's; give a dataset of the same space at "
                         "another seed")
    trained = {(s["space_hash"], _seed(s["path"])) for s in train.sources}
    for s in test.sources:
        if (s["space_hash"], _seed(s["path"])) in trained:
            raise FieldError("--test-data", f"--test-data {s['path']}: the same space at the "
                             "same seed as a training dataset (the same designs); a test set "
                             "needs a seed the training never used")
    return test


def score_test_set(test: SweepData, score: Callable[[SweepData, np.ndarray], dict[str, Any]]
                   ) -> dict[str, Any]:
    """The card's ``test_set``: the datasets (digest, space hash, seed, designs), the sizes
    and ``score(test, every design)``."""
    n = len(test.codes)
    return {"data": [{k: s[k] for k in ("path", "manifest_sha256", "space_hash", "rows")}
                     | {"seed": _seed(s["path"])} for s in test.sources],
            "designs": n, "pairs": int(n * test.band_hz.size),
            "metrics": score(test, np.arange(n))}


def named_inputs(codes: np.ndarray, specs: Sequence[Any]) -> dict[str, np.ndarray]:
    """The columns of ``codes`` (n, len(specs)) by input name, categorical ones by their choice
    names: what a run-time predictor takes as a dict."""
    return {s.name: (codes[:, j] if s.type != "categorical"
                     else np.asarray(s.choices)[codes[:, j].astype(int)])
            for j, s in enumerate(specs)}


def predict_pairs(predictor: Predictor, data: SweepData, codes: np.ndarray
                  ) -> dict[str, np.ndarray]:
    """A run-time predictor's outputs at (design, frequency) ``codes`` (columns: the inputs of
    ``data``, frequency last; :func:`surrogate.sweep.targets.pair_rows`), given as a dict of
    named inputs (categorical ones by their choice) with ``extrapolate=True``; its profile
    grid under ``grid_mm`` (a single-frequency model's is its own, e.g. 0-20 mm)."""
    inputs = named_inputs(codes, data.all_specs)
    out = predictor.predict({name: inputs[name] for name in predictor.input_names},
                            extrapolate=True)
    out["grid_mm"] = predictor.profile_distance_mm
    return out


def score_pairs(pred: dict[str, np.ndarray], centre: np.ndarray, profile: np.ndarray,
                grid_mm: np.ndarray) -> dict[str, Any]:
    """Errors of ``pred`` (``center_amplitude_um``, ``edge_amplitude_um`` (pairs,) and
    ``profile_um`` (pairs, m) [um], optional ``*_log_std`` and ``grid_mm``, the prediction's
    profile grid, default ``grid_mm``) against the FE ``centre`` (pairs,) and ``profile``
    (pairs, n_p) on ``grid_mm`` (the edge is its first point), over every pair.

    ``centre`` and ``edge``: [median, p95, p99, max] relative error and the largest error on
    the field's scale max |error| / max(FE centre, FE edge); ``centre_coverage95`` and
    ``edge_coverage95`` when the prediction has a log-std (share of pairs inside
    exp(mu +- 1.96 sigma)); the profile's relative L2 error [median, p95] over 0-20 mm
    (``profile_0_20mm``, the grid points the prediction's grid shares) and, when the grids
    are the same, over the whole grid (``profile_all``)."""
    field = np.maximum(centre, profile[:, 0])
    out: dict[str, Any] = {}
    for name, y in (("centre", centre), ("edge", profile[:, 0])):
        p = pred[f"{'center' if name == 'centre' else 'edge'}_amplitude_um"]
        rel = np.abs(p / y - 1.0)
        out[name] = [float(np.median(rel)), *np.percentile(rel, [95, 99]).tolist(),
                     float(rel.max()), float(np.max(np.abs(p - y) / field))]
        key = f"{'center' if name == 'centre' else 'edge'}_amplitude_um_log_std"
        if key in pred:  # coverage of the model's 95 % interval
            z = np.abs(np.log(y) - np.log(p)) / np.maximum(pred[key], 1e-300)
            out[f"{name}_coverage95"] = float(np.mean(z <= 1.959964))
    pg = pred.get("grid_mm", grid_mm)
    near = [j for j, d in enumerate(grid_mm) if d <= 20.0 + 1e-9 and np.isclose(pg, d).any()]
    cols = [int(np.argmin(np.abs(pg - grid_mm[j]))) for j in near]
    same_grid = pg.shape == grid_mm.shape and np.allclose(pg, grid_mm)
    for label, truth, got in (("profile_0_20mm", profile[:, near], pred["profile_um"][:, cols]),
                              *((("profile_all", profile, pred["profile_um"]),)
                                if same_grid else ())):
        l2 = np.linalg.norm(got - truth, axis=1) / np.linalg.norm(truth, axis=1)
        out[label] = [float(np.median(l2)), float(np.percentile(l2, 95))]
    return out
