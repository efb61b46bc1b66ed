"""Gaussian-process regression on encoded design features (scikit-learn).

``GPSurrogateRegressor`` wraps :class:`sklearn.gaussian_process.GaussianProcessRegressor`
with the kernel this project uses: an amplitude times an ARD kernel (one length scale per
feature; features are already scaled to [0, 1] from the space's ranges, log parameters on a
log scale) plus white noise (the FE data is not a smooth function at the resolution it is
sampled: the fitted noise level is part of the honest predictive std). Targets are normalised
(``normalize_y``); each target gets its own GP (own length scales and noise: a shared
kernel over targets as different as a center amplitude and a high POD coefficient collapses
to the shortest length scales and a large noise, measured on the shipped data).

GP fitting is O(n^3) in time and O(n^2) in memory: above ``max_train`` rows a random subset
(seeded) is used, and the subset size is recorded as ``n_train_``.
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np
from sklearn.base import BaseEstimator, RegressorMixin
from sklearn.exceptions import ConvergenceWarning
from sklearn.gaussian_process import GaussianProcessRegressor
from sklearn.gaussian_process.kernels import RBF, ConstantKernel, Kernel, Matern, WhiteKernel
from sklearn.utils.validation import check_is_fitted, validate_data

from surrogate.estimators.export import export_gp
from surrogate.estimators.params import check_choice, check_number
from surrogate.kind import SurrogateKind

__all__ = ["KERNELS", "KIND", "POD_MODES", "GPSurrogateRegressor"]

#: Kernels offered; both export to ONNX (surrogate.estimators.export) with a parity test each.
KERNELS = ("rbf", "matern52")
#: Length scales on features scaled to [0, 1]: below 0.05 a feature would vary faster than
#: any affordable sample spacing resolves (a GP then degenerates to white noise); above 1e3
#: the feature is irrelevant.
LENGTH_SCALE_BOUNDS = (5e-2, 1e3)


def ard_kernel(name: str, d: int, noise: float, noise_bounds: tuple[float, float]) -> Kernel:
    """amplitude * ARD(name) + white noise, for ``d`` features scaled to [0, 1]."""
    amplitude = ConstantKernel(1.0, (1e-2, 1e2))
    scales = np.ones(max(d, 1))
    if name == "rbf":
        core: Kernel = RBF(scales, LENGTH_SCALE_BOUNDS)
    elif name == "matern52":
        core = Matern(scales, LENGTH_SCALE_BOUNDS, nu=2.5)
    else:
        raise ValueError(f"kernel = {name!r}: allowed {', '.join(KERNELS)}")
    return amplitude * core + WhiteKernel(noise, noise_bounds)


class GPSurrogateRegressor(RegressorMixin, BaseEstimator):
    """ARD Gaussian processes with predictive std (one per target).

    Parameters:
        kernel: "rbf" or "matern52" (see ``KERNELS``).
        noise: initial white-noise variance (of normalised targets); noise_bounds its bounds.
        n_restarts_optimizer: extra random starts of the hyperparameter search.
        max_train: rows used at most (a seeded random subset above it).
        random_state: seed of the subset and the restarts.
    """

    def __init__(self, kernel: str = "rbf", noise: float = 1e-2,
                 noise_bounds: tuple[float, float] = (1e-5, 1.0),
                 n_restarts_optimizer: int = 0, max_train: int = 1000,
                 random_state: int = 0) -> None:
        self.kernel = kernel
        self.noise = noise
        self.noise_bounds = noise_bounds
        self.n_restarts_optimizer = n_restarts_optimizer
        self.max_train = max_train
        self.random_state = random_state

    def fit(self, X: Any, y: Any) -> GPSurrogateRegressor:
        self._check_params()
        X, y = validate_data(self, X, y, dtype=float, multi_output=True, y_numeric=True)
        rng = np.random.default_rng(self.random_state)
        if len(X) > self.max_train:
            keep = np.sort(rng.choice(len(X), self.max_train, replace=False))
            X, y = X[keep], y[keep]
        Y = y.reshape(len(y), -1)
        self.gps_ = []
        for t in range(Y.shape[1]):
            gp = GaussianProcessRegressor(
                ard_kernel(self.kernel, X.shape[1], self.noise, self.noise_bounds),
                normalize_y=True, n_restarts_optimizer=self.n_restarts_optimizer,
                random_state=int(rng.integers(2**31)))
            with warnings.catch_warnings():  # a length scale at its bound means "irrelevant"
                warnings.simplefilter("ignore", ConvergenceWarning)
                gp.fit(X, Y[:, t])
            self.gps_.append(gp)
        self._y_1d = y.ndim == 1
        self.n_train_ = len(X)
        return self

    def _check_params(self) -> None:
        check_choice("kernel", self.kernel, KERNELS)
        check_number("noise", self.noise, 0, 1e3, low_open=True)
        low, high = self.noise_bounds
        if not 0 < low <= self.noise <= high:
            raise ValueError(f"noise_bounds = {self.noise_bounds!r}: allowed 0 < low <= "
                             f"noise ({self.noise:g}) <= high")
        check_number("n_restarts_optimizer", self.n_restarts_optimizer, 0, 100, integer=True)
        check_number("max_train", self.max_train, 2, 20000, integer=True)
        check_number("random_state", self.random_state, 0, 2**32 - 1, integer=True)

    def __sklearn_tags__(self) -> Any:
        tags = super().__sklearn_tags__()
        tags.target_tags.multi_output = True
        return tags

    def predict(self, X: Any, return_std: bool = False) -> Any:
        check_is_fitted(self)
        X = validate_data(self, X, dtype=float, reset=False)
        parts = [gp.predict(X, return_std=True) for gp in self.gps_]
        mean = np.column_stack([m for m, _ in parts])
        std = np.column_stack([s for _, s in parts])
        if self._y_1d:
            mean, std = mean[:, 0], std[:, 0]
        return (mean, std) if return_std else mean

    def kernels(self) -> list[str]:
        """The fitted kernel of every target, as text."""
        check_is_fitted(self)
        return [str(gp.kernel_) for gp in self.gps_]


#: POD modes a GP learns by default (one GP each; the ONNX graph holds an N x N matrix per
#: target, so each mode costs N^2 doubles of model size).
POD_MODES = 4


def _card_extras(est: GPSurrogateRegressor) -> dict[str, Any]:
    return {"gp_kernels": est.kernels(), "gp_rows_used": int(est.n_train_)}


#: float64 graph: the GP std, a difference of nearly equal numbers near the data, agrees with
#: scikit-learn to about 1e-5 in log amplitude (the tolerance leaves a margin of 10).
KIND = SurrogateKind(
    name="gp", summary="Gaussian processes with predictive std (harmonic amplitudes)",
    estimator=GPSurrogateRegressor, export=export_gp, parity_tol=1e-4, dtype="float64",
    std_parity=True, pod_modes=POD_MODES, card_extras=_card_extras)
