"""Calibrated 95 % intervals: split-conformal scaling of a model's predictive log-std.

A surrogate's ``log_std`` (the spread of a deep ensemble, a GP's posterior std) is a shape,
not a calibrated width: the shipped NN's exp(mu +- 1.96 sigma) covered 82-86 % of its held-out
rows. On calibration rows the model never fitted, the normalised residual

    r = |ln y - mu| / sigma

is computed for every output column of a group -- ``center`` (column 0), ``edge`` (the edge
amplitude and the normalized edge, columns 1-2) and ``profile`` (columns 3+, pooled over
rows and radii) -- and the group's factor is f = r_(k) / 1.959964 with r_(k) the
k = ceil((n + 1) 0.95)-th smallest of its n residuals (split conformal: exp(mu +- 1.96 f sigma)
then covers at least 95 % of exchangeable new rows, marginally). The card stores it as

    "interval_calibration": {"method": "split-conformal", "level": 0.95,
                             "log_std_scale": [f for each log output column],
                             "groups": {name: {"columns": [...], "factor": f, "rows": n}}, ...}

and the run-time predictor multiplies its ``log_std`` column k by ``log_std_scale[k]`` (a card
without the key: 1). :func:`calibrate` computes it from a model's raw predictions;
:func:`surrogate.interval_calibration.calibrate_model_dir` (``hapticrom models
calibrate-intervals``) does it for a trained model on held-out rows of its own data that it
never saw, and re-seals the card.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

__all__ = ["GROUPS", "LEVEL", "Z95", "calibrate", "coverage", "residuals"]

LEVEL = 0.95
Z95 = 1.959964
#: Output groups sharing one factor: name -> (first column, stop column or None = to the end)
GROUPS: dict[str, tuple[int, int | None]] = {"center": (0, 1), "edge": (1, 3),
                                             "profile": (3, None)}


def residuals(pred: dict[str, np.ndarray], center_um: np.ndarray,
              profile_um: np.ndarray) -> np.ndarray:
    """(n, K) normalised residuals |ln y - mu| / sigma of every log output column, from a
    predictor's outputs (``pred``, raw log-std) and the true center and profile [um]."""
    truth = np.column_stack([np.log(center_um), np.log(profile_um[:, 0]),
                             np.log(profile_um[:, 0] / center_um), np.log(profile_um)])
    mu = np.column_stack([np.log(pred["center_amplitude_um"]),
                          np.log(pred["edge_amplitude_um"]), np.log(pred["normalized_edge"]),
                          np.log(pred["profile_um"])])
    sigma = np.column_stack([pred["center_amplitude_um_log_std"],
                             pred["edge_amplitude_um_log_std"],
                             pred["normalized_edge_log_std"], pred["profile_um_log_std"]])
    return np.abs(truth - mu) / np.maximum(sigma, 1e-300)


def _columns(group: str, k: int) -> list[int]:
    a, b = GROUPS[group]
    return list(range(a, k if b is None else b))


def calibrate(r: np.ndarray, level: float = LEVEL) -> dict[str, Any]:
    """The ``interval_calibration`` entry for residuals ``r`` (n, K) of calibration rows."""
    n, k = r.shape
    if n < 20:
        raise ValueError(f"{n} calibration rows: at least 20 are needed for a 95 % factor")
    scale = np.ones(k)
    groups = {}
    for name in GROUPS:
        cols = _columns(name, k)
        pooled = np.sort(r[:, cols].ravel())
        rank = min(math.ceil((pooled.size + 1) * level), pooled.size)
        factor = float(pooled[rank - 1] / Z95)
        scale[cols] = factor
        groups[name] = {"columns": cols, "factor": factor, "rows": int(n)}
    return {"method": "split-conformal", "level": level, "z": Z95,
            "log_std_scale": scale.tolist(), "groups": groups}


def coverage(r: np.ndarray, scale: Sequence[float] | np.ndarray | None = None
             ) -> dict[str, float]:
    """Share of residuals inside the 95 % interval (with the per-column ``scale``, or raw),
    per output: center, edge, normalized_edge and the profile pooled."""
    s = np.ones(r.shape[1]) if scale is None else np.asarray(scale, dtype=float)
    inside = r <= Z95 * s[None, :]
    return {"center_amplitude_um": float(inside[:, 0].mean()),
            "edge_amplitude_um": float(inside[:, 1].mean()),
            "normalized_edge": float(inside[:, 2].mean()),
            "profile_um": float(inside[:, 3:].mean())}
