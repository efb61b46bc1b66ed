"""Validation of estimator parameters: each error names the parameter and its allowed range.

scikit-learn validates its own estimators' parameters at ``fit``; these helpers give ours the
same behaviour with messages in the form this project uses everywhere (``name = value:
allowed ...``).
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray
from sklearn.utils.validation import validate_data

__all__ = ["check_choice", "check_number", "training_data"]


def check_number(name: str, value: Any, low: float, high: float = math.inf, *,
                 integer: bool = False, low_open: bool = False) -> None:
    """Raise ValueError unless ``value`` is a (integer) number in [low, high] ((low, high]
    with ``low_open``)."""
    kind = "an integer" if integer else "a number"
    ok_type = isinstance(value, numbers.Integral if integer else numbers.Real)
    if isinstance(value, bool) or not ok_type or not math.isfinite(value):
        raise ValueError(f"{name} = {value!r}: must be {kind} in {_range(low, high, low_open)}")
    below = value <= low if low_open else value < low
    if below or value > high:
        raise ValueError(f"{name} = {value!r}: allowed {_range(low, high, low_open)}")


def check_choice(name: str, value: Any, choices: Sequence[Any]) -> None:
    """Raise ValueError unless ``value`` is one of ``choices``."""
    if value not in choices:
        raise ValueError(f"{name} = {value!r}: allowed {', '.join(map(repr, choices))}")


def _range(low: float, high: float, low_open: bool) -> str:
    left = "(" if low_open else "["
    right = "]" if high < math.inf else ")"
    return f"{left}{low:g}, {high:g}{right}"


def training_data(estimator: Any, X: Any, y: Any) -> tuple[NDArray, NDArray, bool]:
    """Features X (n, d) and targets as (n, t), validated by scikit-learn (which records
    ``n_features_in_`` on ``estimator``) with finite targets required, and whether ``y`` was
    one-dimensional (so that ``predict`` answers in the same shape)."""
    X, y = validate_data(estimator, X, y, dtype=float, multi_output=True, y_numeric=True)
    if not np.all(np.isfinite(y)):
        raise ValueError("y contains NaN or infinity")
    return X, y.reshape(len(y), -1), y.ndim == 1

