"""Proper orthogonal decomposition of log amplitude profiles, and the training targets.

Surrogates learn a few numbers per design instead of the whole amplitude-distance profile:
the natural log of the center amplitude and the POD coefficients of the log profile (a
profile spans two decades from the edge outwards; in logs its shape varies smoothly and a
handful of modes hold nearly all the variance). Every output is then a *linear* function of
those targets, given by :meth:`ProfileTargets.output_map`::

    log_outputs = targets @ B + b,   columns  [center, edge, normalized_edge, profile...,
                                              extra profile blocks...]

with edge = the profile at distance 0 from the unit's edge and normalized_edge = edge /
center, each defined once here. A model may learn further profiles on the same grid (e.g.
``profile_normal_um``, the normal component an LDV sees): each is one more block of POD
coefficients among the targets and one more block of columns ``NAME[j]`` among the outputs.
Because the map is linear it goes into the exported graphs, and a model's predictive variance
propagates through it exactly.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from sklearn.base import BaseEstimator, TransformerMixin
from sklearn.utils.validation import check_is_fitted, validate_data

__all__ = ["POD", "ProfileTargets", "output_columns"]


def output_columns(m: int, extra: Sequence[str] = ()) -> list[str]:
    """Names of the log-output columns for profiles of ``m`` points: the magnitude outputs,
    then one block ``NAME[j]`` per extra profile output ``NAME``."""
    return ["center_amplitude_um", "edge_amplitude_um", "normalized_edge"] + \
        [f"{name}[{j}]" for name in ("profile_um", *extra) for j in range(m)]


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
    """Targets [log center, POD coefficients of the log profile, POD coefficients of each
    extra log profile] and their linear output map.

    ``extra``: names of further profile outputs (their columns in :func:`output_columns`);
    each gets its own POD (``n_modes`` when given, else the fewest modes holding ``energy``).
    """

    def __init__(self, n_modes: int | None = None, energy: float = 0.9999,
                 extra: Sequence[str] = ()) -> None:
        self.pod = POD(n_modes=n_modes, energy=energy)
        self.extra = tuple(extra)
        self.extra_pods = [POD(n_modes=n_modes, energy=energy) for _ in self.extra]

    @property
    def pods(self) -> dict[str, POD]:
        """The POD of every profile output by name (``profile_um`` first)."""
        return dict(zip(("profile_um", *self.extra), (self.pod, *self.extra_pods),
                        strict=True))

    def fit_transform(self, center_um: np.ndarray, profile_um: np.ndarray,
                      extra_um: Sequence[np.ndarray] = ()) -> np.ndarray:
        """Fit the PODs on the log profiles; return the (n, 1 + k + sum k_extra) targets.
        ``extra_um``: one (n, m) array per extra profile, in the order of ``extra``."""
        if len(extra_um) != len(self.extra):
            raise ValueError(f"{len(extra_um)} extra profiles given for {list(self.extra)}")
        _check_positive(center_um, "center_amplitude_um")
        _check_positive(profile_um, "profile_um")
        blocks = [np.log(center_um)[:, None], self.pod.fit_transform(np.log(profile_um))]
        for name, pod, values in zip(self.extra, self.extra_pods, extra_um, strict=True):
            _check_positive(values, name)
            blocks.append(pod.fit_transform(np.log(values)))
        return np.column_stack(blocks)

    def output_map(self) -> tuple[np.ndarray, np.ndarray]:
        """(B (1 + k + sum k_extra, 3 + m (1 + n_extra)), b) with log_outputs = targets @ B + b;
        each extra block maps only its own coefficients to its own columns."""
        modes, mean = self.pod.modes_, self.pod.mean_
        k, m = modes.shape
        rows = 1 + k + sum(p.modes_.shape[0] for p in self.extra_pods)
        B = np.zeros((rows, 3 + m * (1 + len(self.extra))))
        b = np.zeros(B.shape[1])
        B[0, 0] = 1.0                       # center
        B[1:1 + k, 1], b[1] = modes[:, 0], mean[0]  # edge = profile at distance 0
        B[0, 2] = -1.0                      # normalized = edge / center
        B[1:1 + k, 2], b[2] = modes[:, 0], mean[0]
        B[1:1 + k, 3:3 + m], b[3:3 + m] = modes, mean      # profile
        r, c = 1 + k, 3 + m
        for pod in self.extra_pods:          # extra profiles, block by block
            kj = pod.modes_.shape[0]
            B[r:r + kj, c:c + m], b[c:c + m] = pod.modes_, pod.mean_
            r, c = r + kj, c + m
        return B, b


def _check_positive(a: np.ndarray, name: str) -> None:
    a = np.asarray(a, dtype=float)
    if not np.all(np.isfinite(a)) or np.any(a <= 0):
        raise ValueError(f"{name}: amplitudes must be finite and > 0 to take logs")
