"""The learners of the study, each ``fit(x, y) -> predict`` on standardised inputs.

* ``mlp``: scikit-learn ``MLPRegressor`` 3 x 128, early stopping (the issue's MLP peer);
* ``gp``: one scikit-learn GP for every target, Matern 5/2 ARD + white noise, on standardised
  targets (a shared kernel: the hyperparameters fit the targets jointly);
* ``gp-each``: one GP per target, each with its own Matern 5/2 ARD kernel (the scale and every
  POD coefficient get their own length scales); ``restarts`` optimiser restarts for the
  ``lead`` leading targets, none for the minor ones;
* ``lgbm``: LightGBM, one booster of ``trees`` trees per target (the issue's LightGBM peer).

A GP's O(n^3) fit is capped at ``max_rows`` training rows (the first ones: the designs are in
Sobol order, so the first rows cover the space); the study reports the rows each learner used.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from joblib import Parallel, delayed
from sklearn.gaussian_process import GaussianProcessRegressor
from sklearn.gaussian_process.kernels import ConstantKernel, Matern, WhiteKernel
from sklearn.neural_network import MLPRegressor
from sklearn.preprocessing import StandardScaler

__all__ = ["LEARNERS", "Learner", "LearnerKind", "gp_each", "importable", "lightgbm_available",
           "make"]

Predict = Callable[[np.ndarray], np.ndarray]


@dataclass
class Learner:
    """A named ``fit(x, y) -> predict(q) -> y`` with an optional row cap (``max_rows``)."""

    name: str
    fit_fn: Callable[[np.ndarray, np.ndarray], Predict]
    max_rows: int | None = None
    notes: dict[str, object] = field(default_factory=dict)

    def rows(self, n: int) -> int:
        """Training rows this learner uses of ``n``."""
        return n if self.max_rows is None else min(n, self.max_rows)

    def fit(self, x: np.ndarray, y: np.ndarray) -> Predict:
        k = self.rows(len(x))
        return self.fit_fn(x[:k], y[:k])


def _scaled(fit: Callable[[np.ndarray, np.ndarray], Predict]
            ) -> Callable[[np.ndarray, np.ndarray], Predict]:
    """``fit`` on standardised inputs and targets, answers in the targets' units."""
    def wrapped(x: np.ndarray, y: np.ndarray) -> Predict:
        sx, sy = StandardScaler().fit(x), StandardScaler().fit(y)
        inner = fit(sx.transform(x), sy.transform(y))
        return lambda q: sy.inverse_transform(inner(sx.transform(q)).reshape(len(q), -1))
    return wrapped


def _kernel(d: int) -> object:
    return ConstantKernel() * Matern(np.ones(d), nu=2.5) + WhiteKernel(1e-4)


def mlp(seed: int) -> Callable[[np.ndarray, np.ndarray], Predict]:
    def fit(x: np.ndarray, y: np.ndarray) -> Predict:
        net = MLPRegressor(hidden_layer_sizes=(128, 128, 128), early_stopping=True,
                           max_iter=3000, n_iter_no_change=50, random_state=seed,
                           learning_rate_init=1e-3)
        net.fit(x, y)
        return net.predict
    return _scaled(fit)


def gp(seed: int) -> Callable[[np.ndarray, np.ndarray], Predict]:
    def fit(x: np.ndarray, y: np.ndarray) -> Predict:
        model = GaussianProcessRegressor(_kernel(x.shape[1]), random_state=seed,
                                         n_restarts_optimizer=0)
        model.fit(x, y)
        return model.predict
    return _scaled(fit)


def gp_each(seed: int, restarts: int = 1, lead: int = 4
            ) -> Callable[[np.ndarray, np.ndarray], Predict]:
    """One GP per target column, own ARD Matern 5/2 kernel; ``restarts`` restarts of the
    optimiser for the first ``lead`` columns (the scale and the leading POD coefficients)."""
    def fit(x: np.ndarray, y: np.ndarray) -> Predict:
        models = []
        for j in range(y.shape[1]):
            m = GaussianProcessRegressor(_kernel(x.shape[1]), random_state=seed + j,
                                         n_restarts_optimizer=restarts if j < lead else 0)
            models.append(m.fit(x, y[:, j]))
        return lambda q: np.column_stack([m.predict(q) for m in models])
    return _scaled(fit)


def importable(package: str) -> bool:
    """Whether ``package`` imports (the ``bench`` extra installs the optional peers)."""
    try:
        importlib.import_module(package)
    except ImportError:
        return False
    return True


def lightgbm_available() -> bool:
    """Whether the ``lightgbm`` package imports (the ``bench`` extra installs it)."""
    return importable("lightgbm")


def lgbm(seed: int, trees: int = 3000,
         workers: int = 1) -> Callable[[np.ndarray, np.ndarray], Predict]:
    """LightGBM: one booster per target column, ``trees`` trees at a learning rate of 0.02,
    the boosters fitted by ``workers`` processes (each booster single-threaded and seeded, so
    the models do not depend on ``workers``)."""
    def fit(x: np.ndarray, y: np.ndarray) -> Predict:
        # optional (the `bench` extra): only the LightGBM peer needs it
        import lightgbm

        def booster(j: int) -> Any:
            return lightgbm.LGBMRegressor(
                n_estimators=trees, learning_rate=0.02, num_leaves=31, min_child_samples=5,
                subsample=0.8, subsample_freq=1, colsample_bytree=0.9, random_state=seed,
                n_jobs=1, verbose=-1).fit(x, y[:, j])

        models = Parallel(n_jobs=workers)(delayed(booster)(j) for j in range(y.shape[1]))
        return lambda q: np.column_stack([m.predict(q) for m in models])
    return _scaled(fit)


@dataclass(frozen=True)
class LearnerKind:
    """One learner of the study: what it is, how it is made from the options of :func:`make`
    (``seed``, ``restarts``, ``lead``, ``trees``), whether the GP row cap applies, and the
    package it needs beyond the study's own (None: none)."""

    summary: str
    build: Callable[[dict[str, int]], Callable[[np.ndarray, np.ndarray], Predict]]
    capped: bool = False
    notes: tuple[str, ...] = ()
    needs: str | None = None


#: Learner name on the command line -> what it is.
LEARNERS: dict[str, LearnerKind] = {
    "mlp": LearnerKind("scikit-learn MLPRegressor 3x128, early stopping",
                       lambda o: mlp(o["seed"])),
    "gp": LearnerKind("scikit-learn GP, Matern 5/2 ARD, one kernel for all targets",
                      lambda o: gp(o["seed"]), capped=True),
    "gp-each": LearnerKind("one scikit-learn GP per target, each its own Matern 5/2 ARD kernel",
                           lambda o: gp_each(o["seed"], o["restarts"], o["lead"]), capped=True,
                           notes=("restarts", "lead")),
    "lgbm": LearnerKind("LightGBM, one booster per target",
                        lambda o: lgbm(o["seed"], o["trees"], o["workers"]),
                        notes=("trees",), needs="lightgbm"),
}


def make(name: str, seed: int, *, gp_rows: int | None = None, restarts: int = 1,
         lead: int = 4, trees: int = 3000, workers: int = 1) -> Learner:
    """The learner called ``name`` (:data:`LEARNERS`); GPs capped at ``gp_rows`` rows;
    ``workers`` processes fit LightGBM's boosters."""
    if name not in LEARNERS:
        raise ValueError(f"learner {name!r}: allowed {', '.join(LEARNERS)}")
    kind = LEARNERS[name]
    if kind.needs is not None and not importable(kind.needs):
        raise ValueError(f"learner {name} needs the {kind.needs} package (pip install "
                         "'hapticrom[bench]')")
    options = {"seed": seed, "restarts": restarts, "lead": lead, "trees": trees,
               "workers": workers}
    return Learner(name, kind.build(options), gp_rows if kind.capped else None,
                   {k: options[k] for k in kind.notes})
