"""Calibrated 95 % intervals: split-conformal scaling of a model's predictive log-std.

A surrogate's ``log_std`` (the spread of a deep ensemble, a GP's posterior std) is a shape,
not a calibrated width: the shipped NN's exp(mu +- 1.96 sigma) covered 82-86 % of its held-out
rows. On calibration rows the model never fitted, the normalised residual

    r = |ln y - mu| / sigma

is computed for every output column of a group -- ``center`` (column 0), ``edge`` (the edge
amplitude and the normalized edge, columns 1-2), ``profile`` (the next m columns, pooled over
rows and radii) and one group per extra profile output a model learns (e.g.
``profile_normal_um``, m columns each, in the order of the card's ``log_output_columns``) --
and the group's factor is f = r_(k) / 1.959964 with r_(k) the k = ceil((n + 1) 0.95)-th
smallest of its n residuals (split conformal: exp(mu +- 1.96 f sigma) then covers at least
95 % of exchangeable new rows, marginally). The card stores it as

    "interval_calibration": {"method": "split-conformal", "level": 0.95,
                             "log_std_scale": [f for each log output column],
                             "groups": {name: {"columns": [...], "factor": f, "rows": n}}, ...}

and the run-time predictor multiplies its ``log_std`` column k by ``log_std_scale[k]`` (a card
without the key: 1).

Rows that come in groups -- a sweep model's (design, band frequency) pairs, where the residuals
of one design's frequencies move together -- are not exchangeable one by one, only the groups
are. For them (``group`` given) the factor is the hierarchical split-conformal quantile: every
group carries the same mass 1 / (K + 1) shared equally by its scores, one mass 1 / (K + 1) sits
at +infinity, and r_(level) is the smallest score at which the cumulative mass reaches the
level. A new group's score at a random one of its points is then covered with probability at
least the level for exchangeable groups (K groups; the hierarchical conformal prediction of
Lee, Barber and Willett, 2023). With K equal groups of N scores it is the
ceil(level (K + 1) N)-th smallest of the K N pooled scores: the pooled quantile at the level
(1 + 1 / K) -- 95.6 % for 161 calibration designs, where the pooled 95 % quantile covered
92-95 % of new designs.
 :func:`calibrate` computes it from a model's raw predictions;
:func:`surrogate.calibrate_intervals.calibrate_model_dir` (``hapticrom models
calibrate-intervals``) does it for a trained model on held-out rows of its own data that it
never saw, and re-seals the card.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

__all__ = ["AUTO_CALIBRATION_FRACTION", "AUTO_CALIBRATION_ROWS", "LEVEL", "Z95", "calibrate",
           "conformal_quantile", "coverage", "groups", "normalised_residual", "residuals"]

LEVEL = 0.95
Z95 = 1.959964
#: Interval calibration by default (``hapticrom train``): this share of the training rows, when
#: it is at least AUTO_CALIBRATION_ROWS rows (a 95 % quantile of fewer is too noisy to ship by
#: default; surrogate.card_warnings says so on a model trained on fewer)
AUTO_CALIBRATION_FRACTION = 0.1
AUTO_CALIBRATION_ROWS = 100


def groups(k: int, extra: Sequence[str] = ()) -> dict[str, list[int]]:
    """Output groups sharing one factor, by name -> log output columns, for ``k`` columns of
    which the profiles (``profile_um`` and each ``extra`` output) take equal shares."""
    m, rest = divmod(k - 3, 1 + len(extra))
    if k < 4 or rest:
        raise ValueError(f"{k} log output columns do not hold 3 scalars and "
                         f"{1 + len(extra)} profiles of equal length")
    out = {"center": [0], "edge": [1, 2]}
    for j, name in enumerate(("profile", *extra)):
        out[name] = list(range(3 + j * m, 3 + (j + 1) * m))
    return out


def normalised_residual(truth: np.ndarray, value: np.ndarray, log_std: np.ndarray
                        ) -> np.ndarray:
    """|ln truth - ln value| / log_std: the error of a prediction ``value`` in units of its
    predictive log-std (inside the 95 % interval when at most :data:`Z95`)."""
    return np.abs(np.log(truth) - np.log(value)) / np.maximum(log_std, 1e-300)


def residuals(pred: dict[str, np.ndarray], center_um: np.ndarray, profile_um: np.ndarray,
              extra_um: Mapping[str, np.ndarray] | None = None) -> np.ndarray:
    """(n, K) normalised residuals |ln y - mu| / sigma of every log output column, from a
    predictor's outputs (``pred``, raw log-std), the true center and profile [um] and the
    true extra profiles [um] by output name (``extra_um``, in the card's column order)."""
    extra_um = extra_um or {}
    truth = np.column_stack([center_um, profile_um[:, 0], profile_um[:, 0] / center_um,
                             profile_um, *extra_um.values()])
    names = ["center_amplitude_um", "edge_amplitude_um", "normalized_edge", "profile_um",
             *extra_um]
    value = np.column_stack([pred[name] for name in names])
    log_std = np.column_stack([pred[f"{name}_log_std"] for name in names])
    return normalised_residual(truth, value, log_std)


def calibrate(r: np.ndarray, level: float = LEVEL, extra: Sequence[str] = (),
              group: np.ndarray | None = None) -> dict[str, Any]:
    """The ``interval_calibration`` entry for residuals ``r`` (n, K) of calibration rows (of a
    model with the extra profile outputs ``extra``); ``group`` (n,): the group of each row
    (e.g. its design) when rows are exchangeable only as groups (the module docstring)."""
    n, k = r.shape
    if n < 20:
        raise ValueError(f"{n} calibration rows: at least 20 are needed for a 95 % factor")
    n_groups = None if group is None else np.unique(group).size
    if n_groups is not None and level * (n_groups + 1) / n_groups >= 1.0:
        raise ValueError(f"{n_groups} calibration groups: a {level:.0%} factor needs more than "
                         f"{math.ceil(level / (1 - level))}")
    scale = np.ones(k)
    entries = {}
    for name, cols in groups(k, extra).items():
        factor = float(conformal_quantile(r[:, cols], level, group) / Z95)
        scale[cols] = factor
        entries[name] = {"columns": cols, "factor": factor, "rows": int(n)}
        if n_groups is not None:
            entries[name]["groups"] = int(n_groups)
    method = "split-conformal" if group is None else "hierarchical split-conformal"
    return {"method": method, "level": level, "z": Z95,
            "log_std_scale": scale.tolist(), "groups": entries}


def conformal_quantile(scores: np.ndarray, level: float, group: np.ndarray | None = None
                       ) -> float:
    """The conformal quantile of ``scores`` (n rows, any columns pooled): the
    ceil((n_scores + 1) level)-th smallest when every score is exchangeable (``group`` None),
    the hierarchical one over the groups of the rows otherwise (the module docstring)."""
    if group is None:
        pooled = np.sort(scores.ravel())
        rank = min(math.ceil((pooled.size + 1) * level), pooled.size)
        return float(pooled[rank - 1])
    labels, index, size = np.unique(group, return_inverse=True, return_counts=True)
    per_score = np.repeat(1.0 / ((labels.size + 1) * size[index] * scores.shape[1]),
                          scores.shape[1])
    order = np.argsort(scores.ravel(), kind="stable")
    mass = np.cumsum(per_score[order])
    # the first score whose cumulative mass reaches the level (a relative tolerance keeps an
    # exact tie, e.g. level (K + 1) N an integer, from rounding one score too far)
    at = int(np.searchsorted(mass, level * (1 - 1e-12)))
    return float(scores.ravel()[order[at]])


def coverage(r: np.ndarray, scale: Sequence[float] | np.ndarray | None = None,
             extra: Sequence[str] = ()) -> dict[str, float]:
    """Share of residuals inside the 95 % interval (with the per-column ``scale``, or raw),
    per output: center, edge, normalized_edge, the profile pooled and each extra profile."""
    s = np.ones(r.shape[1]) if scale is None else np.asarray(scale, dtype=float)
    inside = r <= Z95 * s[None, :]
    cols = groups(r.shape[1], extra)
    out = {"center_amplitude_um": float(inside[:, 0].mean()),
           "edge_amplitude_um": float(inside[:, 1].mean()),
           "normalized_edge": float(inside[:, 2].mean()),
           "profile_um": float(inside[:, cols["profile"]].mean())}
    out.update({name: float(inside[:, cols[name]].mean()) for name in extra})
    return out
