"""The card's ``test_set``: a sweep model scored on fresh designs (``hapticrom train --data
SWEEP_DIR --test-data TEST_DIR``; TEST_DIR a dataset of the same space at another Sobol seed,
``datasets/spaces/default-sweep-test.toml``).

Every (design, band frequency) pair of the test datasets is predicted through the exported
graph and the run-time encoder and scored as the held-out split is
(:func:`surrogate.sweep.train.sweep_metrics`: median / p95 / p99 / max relative errors, the
largest error on the field's scale, profile relative L2 over the whole grid, 95 % coverage).
The entry records each test dataset's manifest digest, space hash, Sobol seed and size, so the
card says which designs it was scored on.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from fieldspec import FieldError
from surrogate.data.store import Store
from surrogate.sweep.targets import SweepData, load_sweep_datasets

__all__ = ["load_test_data", "score_test_set"]


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
