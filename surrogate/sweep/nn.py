"""The NN's part of the sweep pipeline (:data:`SWEEP`, joined to its kind in
:mod:`surrogate.kinds`): its options, its two-stage fit on the complex-band representation and
its export parity; the pipeline itself is :func:`surrogate.sweep.train.train_sweep`.

``loss`` (``--options``): ``"magnitude"`` (default) first fits the members to the
standardised targets by MSE, then keeps training them through the differentiable decode on
ln |u| at band frequencies of the centre, the edge and the profile (what users meet);
``"coefficients"`` stops after the first stage. ``centre_modes`` (default 48) and ``--modes``
(the profile's, default 128) size the two POD blocks; ``refit_epochs`` (default 400),
``refit_patience`` (default 40), ``refit_learning_rate`` (default 1e-3) and
``centre_weight`` (default 6: the centre's squared ln error counts six times the edge's
and six times the whole profile's; docs/sweep-models.md has the measurement) drive the
second stage; ``spatial_tol`` (default 1e-3) bounds the relative error of the factored
basis the graph decodes through (:mod:`surrogate.sweep.basis`; 0: exact); every other
option is the estimator's (``hidden`` defaults to 256 x 256 here).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from surrogate.estimators import nn
from surrogate.estimators.params import check_choice, check_number
from surrogate.kind import SweepKind, estimator_params
from surrogate.runtime.encoding import encode
from surrogate.runtime.predictor import Predictor
from surrogate.sweep.export import (
    BandDecoder,
    export_sweep_nn,
    magnitude_error,
    member_targets,
    reference_log_outputs,
)
from surrogate.sweep.targets import BandTargets, SweepData, pair_rows

__all__ = ["LOSSES", "PARITY_TOL", "SWEEP", "fit_sweep", "split_nn_options"]

LOSSES = ("magnitude", "coefficients")
#: Largest |d ln| between the float32 graph and the float64 numpy rebuild of the same member
#: outputs (the single-frequency NN's tolerance; measured 2e-6 on default-sweep)
PARITY_TOL = 1e-4
_SWEEP_OPTIONS = {"loss": "magnitude", "centre_modes": 48, "refit_epochs": 400,
                  "refit_patience": 40, "refit_learning_rate": 1e-3, "centre_weight": 6.0,
                  "spatial_tol": 1e-3}
#: The estimator's defaults for sweep data where they differ from the single-frequency NN's
#: (bench/surrogate/sweep_nn.py on 1,248 designs, held-out centre / edge p95: 15 / 13 % with
#: 256 x 256 and the default refit, 19 / 17 % with 128 x 128 and 150 refit epochs at 3e-4)
_ESTIMATOR_DEFAULTS = {"hidden": (256, 256)}
#: Held-out designs checked for export parity (every band frequency of each)
_PARITY_DESIGNS = 32


def split_nn_options(options: dict[str, Any]) -> tuple[dict[str, Any], dict[str, Any]]:
    """(sweep options with defaults, the estimator's options), each checked."""
    ours = {k: options.pop(k, v) for k, v in _SWEEP_OPTIONS.items()}
    check_choice("loss", ours["loss"], LOSSES)
    check_number("centre_modes", ours["centre_modes"], 1, 10**4, integer=True)
    check_number("refit_epochs", ours["refit_epochs"], 1, 10**6, integer=True)
    check_number("refit_patience", ours["refit_patience"], 1, 10**6, integer=True)
    check_number("refit_learning_rate", ours["refit_learning_rate"], 0, 1, low_open=True)
    check_number("centre_weight", ours["centre_weight"], 0, 100, low_open=True)
    check_number("spatial_tol", ours["spatial_tol"], 0, 0.5)
    return ours, {**_ESTIMATOR_DEFAULTS, **options}


def _graph_parity(est: Any, targets: BandTargets, predictor: Predictor, data: SweepData,
            X: np.ndarray, designs: np.ndarray, normal: bool) -> float:
    """Largest |d ln| (mean and std) between the graph and the numpy rebuild of the same member
    outputs at every band frequency of up to :data:`_PARITY_DESIGNS` ``designs``; raises above
    :data:`PARITY_TOL`."""
    designs = designs[:_PARITY_DESIGNS]
    n_f = data.band_hz.size
    codes, *_ = pair_rows(data, designs)
    y = member_targets(est, np.repeat(X[designs], n_f, axis=0))
    ref_mean, ref_std = reference_log_outputs(targets, y, np.tile(np.arange(n_f), designs.size),
                                              normal)
    feats = encode(codes, predictor.specs).astype(np.float32)
    got_mean, got_std = predictor.session.run(["log_mean", "log_std"], {"x": feats})
    worst = float(max(np.abs(got_mean - ref_mean).max(), np.abs(got_std - ref_std).max()))
    if not worst <= PARITY_TOL:
        raise RuntimeError(f"exported sweep graph differs from its numpy rebuild by {worst:.3g} "
                           f"in log amplitude (tolerance {PARITY_TOL})")
    return worst


def fit_sweep(data: SweepData, designs: np.ndarray, *, seed: int = 0,
              n_modes: int | None = None, normal: bool = False,
              options: dict[str, Any] | None = None,
              features: np.ndarray | None = None) -> tuple[Any, BandTargets]:
    """(fitted :class:`surrogate.estimators.nn.MLPEnsembleRegressor`, fitted
    :class:`BandTargets`) of the rows ``designs`` of ``data`` (``options``: the sweep options of
    the module docstring and the estimator's). ``features`` (one row per design of ``data``):
    extra inputs appended to the encoded design features, e.g. another model's predictions
    (:mod:`studies.fewer_designs.multifidelity`); the exported graph cannot compute them, so
    such a fit is for measurement (:func:`member_targets` on the same columns), not export."""
    ours, est_options = split_nn_options(dict(options or {}))
    X = encode(data.codes[designs], data.specs)
    if features is not None:
        if len(features) != len(data.codes):
            raise ValueError(f"features: {len(features)} rows for {len(data.codes)} designs")
        X = np.column_stack([X, np.asarray(features, dtype=float)[designs]])
    targets = BandTargets(centre_modes=ours["centre_modes"], profile_modes=n_modes or 128,
                          spatial_tol=ours["spatial_tol"])
    T = targets.fit_transform(data.response[designs])
    est = nn.KIND.fit(X, T, seed, est_options)
    if ours["loss"] == "magnitude":
        est.refit(X, magnitude_error(BandDecoder(targets, normal), data.response[designs],
                                     centre_weight=ours["centre_weight"]),
                  max_epochs=ours["refit_epochs"], patience=ours["refit_patience"],
                  learning_rate=ours["refit_learning_rate"])
    return est, targets


def _check(options: Mapping[str, Any] | None) -> tuple[dict[str, Any], dict[str, Any]]:
    return split_nn_options(dict(options or {}))


def _fit(checked: tuple[dict[str, Any], dict[str, Any]], data: SweepData, designs: np.ndarray,
         seed: int, n_modes: int | None, normal: bool
         ) -> tuple[Any, BandTargets, dict[str, Any]]:
    """(estimator, targets, the card's training entries) of the NN on ``designs``."""
    ours, est_options = checked
    est, targets = fit_sweep(data, designs, seed=seed, n_modes=n_modes, normal=normal,
                             options={**ours, **est_options})
    refit = ({"refit": {"epochs": ours["refit_epochs"], "patience": ours["refit_patience"],
                        "learning_rate": ours["refit_learning_rate"],
                        "centre_weight": ours["centre_weight"],
                        "best_epoch": list(est.refit_best_epoch_)}}
             if ours["loss"] == "magnitude" else {})
    return est, targets, {"loss": ours["loss"], **refit, "estimator": estimator_params(est)}


def _parity(est: Any, targets: BandTargets, predictor: Predictor, data: SweepData,
            designs: np.ndarray, normal: bool) -> dict[str, Any]:
    X = encode(data.codes, data.specs)
    return {"export_parity_max_abs_dln": _graph_parity(est, targets, predictor, data, X, designs,
                                                       normal)}


#: The NN's part of the sweep pipeline.
SWEEP = SweepKind(check_options=_check, fit=_fit, export=export_sweep_nn, parity=_parity)
