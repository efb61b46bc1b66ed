"""Proper orthogonal decomposition of log amplitude profiles, and the training targets.

Surrogates learn a few numbers per design instead of the whole amplitude-distance profile:
the natural log of the center amplitude and the POD coefficients of the log profile (a
profile spans two decades from the edge outwards; in logs its shape varies smoothly and a
handful of modes hold nearly all the variance). Every output is then a *linear* function of
those targets, given by :meth:`ProfileTargets.output_map`::

    log_outputs = targets @ B + b,   columns  [center, edge, normalized_edge, profile...]

with edge = the profile at distance 0 from the unit's edge and normalized_edge = edge /
center, each defined once here. Because the map is linear it goes into the exported graphs,
and a model's predictive variance propagates through it exactly.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from sklearn.base import BaseEstimator, TransformerMixin
from sklearn.utils.validation import check_is_fitted, validate_data

__all__ = ["POD", "ProfileTargets", "output_columns"]


def output_columns(m: int) -> list[str]:
    """Names of the log-output columns for a profile of ``m`` points."""
    return ["center_amplitude_um", "edge_amplitude_um", "normalized_edge"] + \
        [f"profile_um[{j}]" for j in range(m)]


class POD(TransformerMixin, BaseEstimator):
    """POD (principal components without whitening) of row snapshots.

    Parameters: ``n_modes`` (int) or, when None, the fewest modes holding ``energy`` of the
    variance about the mean. Fitted: ``mean_`` (m,), ``modes_`` (k, m) orthonormal rows,
    ``energy_`` (k,) cumulative captured fraction."""

    def __init__(self, n_modes: int | None = None, energy: float = 0.9999) -> None:
        self.n_modes = n_modes
        self.energy = energy

    def fit(self, X: Any, y: Any = None) -> POD:
        X = validate_data(self, X, dtype=float)
        if not 0 < self.energy <= 1:
            raise ValueError(f"energy = {self.energy}: must be in (0, 1]")
        self.mean_ = X.mean(axis=0)
        _, s, vt = np.linalg.svd(X - self.mean_, full_matrices=False)
        power = s**2
        total = power.sum()
        cum = np.cumsum(power) / total if total > 0 else np.ones_like(power)
        if self.n_modes is not None:
            if not 1 <= self.n_modes <= len(s):
                raise ValueError(f"n_modes = {self.n_modes}: must be in 1..{len(s)}")
            k = self.n_modes
        else:
            k = int(np.searchsorted(cum, self.energy - 1e-15) + 1)
        self.modes_ = vt[:k]
        self.energy_ = cum[:k]
        return self

    def transform(self, X: Any) -> np.ndarray:
        check_is_fitted(self)
        X = validate_data(self, X, dtype=float, reset=False)
        return (X - self.mean_) @ self.modes_.T

    def inverse_transform(self, C: Any) -> np.ndarray:
        check_is_fitted(self)
        return self.mean_ + np.asarray(C, dtype=float) @ self.modes_


class ProfileTargets:
    """Targets [log center, POD coefficients of log profile] and their linear output map."""

    def __init__(self, n_modes: int | None = None, energy: float = 0.9999) -> None:
        self.pod = POD(n_modes=n_modes, energy=energy)

    def fit_transform(self, center_um: np.ndarray, profile_um: np.ndarray) -> np.ndarray:
        """Fit the POD on the log profiles; return the (n, 1 + k) target matrix."""
        _check_positive(center_um, "center_amplitude_um")
        _check_positive(profile_um, "profile_um")
        coeffs = self.pod.fit_transform(np.log(profile_um))
        return np.column_stack([np.log(center_um), coeffs])

    def output_map(self) -> tuple[np.ndarray, np.ndarray]:
        """(B (1 + k, 3 + m), b (3 + m,)) with log_outputs = targets @ B + b."""
        modes, mean = self.pod.modes_, self.pod.mean_
        k, m = modes.shape
        B = np.zeros((1 + k, 3 + m))
        b = np.zeros(3 + m)
        B[0, 0] = 1.0                       # center
        B[1:, 1], b[1] = modes[:, 0], mean[0]  # edge = profile at distance 0
        B[0, 2] = -1.0                      # normalized = edge / center
        B[1:, 2], b[2] = modes[:, 0], mean[0]
        B[1:, 3:], b[3:] = modes, mean      # profile
        return B, b


def _check_positive(a: np.ndarray, name: str) -> None:
    a = np.asarray(a, dtype=float)
    if not np.all(np.isfinite(a)) or np.any(a <= 0):
        raise ValueError(f"{name}: amplitudes must be finite and > 0 to take logs")
