"""Held-out error summary shared by the surrogate benches (not a bench itself)."""

from __future__ import annotations

import numpy as np


def amplitude_errors(log_pred: np.ndarray, center: np.ndarray,
                     edge: np.ndarray) -> dict[str, float]:
    """Median and 95th-percentile relative errors of exp(log_pred[:, 0]) against the center
    and exp(log_pred[:, 1]) against the edge amplitudes (any unit, the same in both)."""
    out = {}
    for j, (name, y) in enumerate((("center", center), ("edge", edge))):
        rel = np.abs(np.exp(log_pred[:, j]) / y - 1.0)
        out[f"{name}_median"] = float(np.median(rel))
        out[f"{name}_p95"] = float(np.percentile(rel, 95))
    return out
