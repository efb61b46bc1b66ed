"""Train an NN or GP surrogate on sweep datasets (``hapticrom train --data SWEEP --kind nn``
or ``--kind gp``, which calls :func:`train_sweep` when every dataset is a sweep dataset).
The GP's fit, variance and float64 graph: :mod:`surrogate.sweep.gp`,
:mod:`surrogate.sweep.gp_export`; what follows is the NN's, and the pipeline both share.

The model learns, per design, the complex-band representation of
:class:`surrogate.sweep.targets.BandTargets` and ships it through the one graph contract of
:mod:`surrogate.estimators.export` (the decode to the requested frequency is inside the graph,
:mod:`surrogate.sweep.export`): its inputs are the space's design inputs plus
``frequency_hz`` over the band, so the predictor, the planner and ``hapticrom predict`` use it
as they use a single-frequency model.

* The held-out split is by design (every frequency of a held-out design is held out).
* ``loss`` (``--options``): ``"magnitude"`` (default) first fits the members to the
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
* The card's metrics and interval calibration are computed on (design, band frequency) pairs
  *through the exported graph and the run-time encoder*, as for single-frequency models
  (:func:`surrogate.train.evaluate`, :mod:`surrogate.intervals`), plus the tails (p99, max,
  and the largest error on the field's scale |error| / max(centre, edge)).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from fieldspec import FieldError
from surrogate.estimators.params import check_choice, check_number
from surrogate.intervals import calibrate, residuals
from surrogate.kinds import get as get_kind
from surrogate.registry import check_model_out, package_versions, write_model
from surrogate.runtime.encoding import encode
from surrogate.runtime.predictor import CALIBRATION_KEY, Predictor, make_session
from surrogate.sweep.export import (
    BandDecoder,
    export_sweep_nn,
    magnitude_error,
    member_targets,
    reference_log_outputs,
)
from surrogate.sweep.gp import fit_sweep_gp, split_gp_options
from surrogate.sweep.gp_export import export_sweep_gp, gp_parity
from surrogate.sweep.targets import BandTargets, SweepData, load_sweep_datasets, pair_rows
from surrogate.train import (
    _calibration_rows,
    _plain,
    card_head,
    check_outputs,
    evaluate,
    fit_kind,
    split,
)

__all__ = ["LOSSES", "PARITY_TOL", "SWEEP_KINDS", "band_tails", "fit_sweep", "sweep_metrics",
           "train_sweep"]

#: The kinds sweep datasets train (their graphs decode the complex band).
SWEEP_KINDS = ("nn", "gp")
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


def _split_options(options: dict[str, Any]) -> tuple[dict[str, Any], dict[str, Any]]:
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


def band_tails(pred: dict[str, np.ndarray], center_um: np.ndarray, profile_um: np.ndarray
               ) -> dict[str, dict[str, float]]:
    """p99 and max relative errors of centre and edge, their largest error on the field's
    scale (|error| / max(centre, edge)) and the profile's p99 relative L2 error."""
    field = np.maximum(center_um, profile_um[:, 0])
    out: dict[str, dict[str, float]] = {}
    for name, y in (("center_amplitude_um", center_um), ("edge_amplitude_um", profile_um[:, 0])):
        rel = np.abs(pred[name] / y - 1.0)
        out[name] = {"p99_rel_err": float(np.percentile(rel, 99)), "max_rel_err": float(rel.max()),
                     "max_abs_err_over_field": float(np.max(np.abs(pred[name] - y) / field))}
    l2 = np.linalg.norm(pred["profile_um"] - profile_um, axis=1) / np.linalg.norm(profile_um,
                                                                                 axis=1)
    out["profile_um"] = {"p99_rel_l2": float(np.percentile(l2, 99)), "max_rel_l2": float(l2.max())}
    return out


def sweep_metrics(predictor: Predictor, data: SweepData, designs: np.ndarray,
                  extra: Sequence[str]) -> dict[str, Any]:
    """:func:`surrogate.train.evaluate` with :func:`band_tails` on every (design, band
    frequency) pair of ``designs``, through ``predictor``."""
    codes, centre, profile, ext = pair_rows(data, designs, "profile_normal_um" in extra)
    pred = predictor.predict(codes)
    out = evaluate(pred, centre, profile, ext)
    for name, more in band_tails(pred, centre, profile).items():
        out[name].update(more)
    return out


def _parity(est: Any, targets: BandTargets, predictor: Predictor, data: SweepData,
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
              options: dict[str, Any] | None = None) -> tuple[Any, BandTargets]:
    """(fitted :class:`surrogate.estimators.nn.MLPEnsembleRegressor`, fitted
    :class:`BandTargets`) of the rows ``designs`` of ``data`` (``options``: the sweep options of
    the module docstring and the estimator's)."""
    ours, est_options = _split_options(dict(options or {}))
    X = encode(data.codes[designs], data.specs)
    targets = BandTargets(centre_modes=ours["centre_modes"], profile_modes=n_modes or 128,
                          spatial_tol=ours["spatial_tol"])
    T = targets.fit_transform(data.response[designs])
    est = fit_kind(get_kind("nn"), X, T, seed, est_options)
    if ours["loss"] == "magnitude":
        est.refit(X, magnitude_error(BandDecoder(targets, normal), data.response[designs],
                                     centre_weight=ours["centre_weight"]),
                  max_epochs=ours["refit_epochs"], patience=ours["refit_patience"],
                  learning_rate=ours["refit_learning_rate"])
    return est, targets


def _fit(kind: str, checked: Any, data: SweepData, designs: np.ndarray, seed: int,
         n_modes: int | None, normal: bool) -> tuple[Any, BandTargets, dict[str, Any]]:
    """(estimator, targets, the card's training entries of the fit) of ``kind`` on ``designs``
    with its checked options (the GP's dict, or the NN's (ours, estimator's) pair)."""
    if kind == "gp":
        est, targets = fit_sweep_gp(data, designs, seed=seed, n_modes=n_modes, options=checked)
        return est, targets, {"gp": est.card(), "estimator": {
            k: _plain(v) for k, v in est.get_params().items()}}
    ours, est_options = checked
    est, targets = fit_sweep(data, designs, seed=seed, n_modes=n_modes, normal=normal,
                             options={**ours, **est_options})
    refit = ({"refit": {"epochs": ours["refit_epochs"], "patience": ours["refit_patience"],
                        "learning_rate": ours["refit_learning_rate"],
                        "centre_weight": ours["centre_weight"],
                        "best_epoch": list(est.refit_best_epoch_)}}
             if ours["loss"] == "magnitude" else {})
    return est, targets, {"loss": ours["loss"], **refit,
                          "estimator": {k: _plain(v) for k, v in est.get_params().items()}}


def train_sweep(paths: Sequence[str | Path], kind: str, out: str | Path, *,
                test_fraction: float = 0.2, seed: int = 0, n_modes: int | None = None,
                overwrite: bool = False, categorical: str = "onehot",
                options: dict[str, Any] | None = None, outputs: Sequence[str] = ("profile_um",),
                calibration_fraction: float | None = None) -> dict[str, Any]:
    """Train an NN or GP sweep model on the sweep datasets ``paths`` and write ``out``
    (arguments as :func:`surrogate.train.train`; the split and the calibration rows are
    designs); return its card. ``hapticrom train`` calls it when every dataset is a sweep
    dataset. The GP: :mod:`surrogate.sweep.gp` (``options``: its ``GP_OPTIONS``)."""
    spec = get_kind(kind)
    if kind not in SWEEP_KINDS:
        raise FieldError("--kind", f"--kind {kind}: sweep datasets train the "
                         f"{' and '.join(SWEEP_KINDS)} kinds (their graphs decode the complex "
                         f"band); give single-frequency datasets for {kind}")
    extra = check_outputs(outputs)
    # checked before anything is read or written: a bad option fails at once
    checked = split_gp_options(options) if kind == "gp" else _split_options(dict(options or {}))
    check_model_out(out, overwrite)
    data = load_sweep_datasets(paths, categorical=categorical)
    normal = "profile_normal_um" in extra
    tr, te = split(len(data.codes), test_fraction, seed)
    tr, cal = _calibration_rows(tr, calibration_fraction, seed)
    specs = data.all_specs
    est, targets, fitted = _fit(kind, checked, data, tr, seed, n_modes, normal)
    representation = {**targets.to_dict(), **({"loss": fitted["loss"]} if "loss" in fitted
                                              else {}),
                      "band_hz": {"start": float(data.band_hz[0]),
                                  "stop": float(data.band_hz[-1]),
                                  "step": float(data.band_hz[1] - data.band_hz[0])}}
    card: dict[str, Any] = {
        **card_head(kind, spec.dtype, specs, data, extra),
        "representation": representation,
        "training": {"rows": int(tr.size), "held_out": int(te.size), "split": "by design",
                     "held_out_pairs": int(te.size * data.band_hz.size), "seed": seed,
                     "test_fraction": test_fraction, "pod_modes": targets.n_modes,
                     "pod_energy": min(representation["pod_energy"].values()), **fitted},
        "versions": package_versions()}
    meta = {k: card[k] for k in ("kind", "inputs", "outputs", "profile_distance_mm",
                                 "training_data", "representation")}
    export = export_sweep_gp if kind == "gp" else export_sweep_nn
    onnx_bytes = export(est, targets, normal, specs[-1].low, specs[-1].high, data.band_hz, meta)
    predictor = Predictor({**card, "files": {}}, make_session(onnx_bytes))
    if kind == "gp":
        parity = gp_parity(est, targets, predictor.session, data, specs, te, normal)
        card["export_parity_max_abs_dln"] = parity["log_mean"]
        card["export_parity"] = parity  # with log_std's relative difference
    else:
        X = encode(data.codes, data.specs)
        card["export_parity_max_abs_dln"] = _parity(est, targets, predictor, data, X, te, normal)
    if cal.size:
        codes, centre, profile, ext = pair_rows(data, cal, normal)
        entry = calibrate(residuals(predictor.predict(codes), centre, profile, ext), extra=extra,
                          group=np.repeat(cal, data.band_hz.size))  # designs, not pairs
        entry["rows"] = {"from": "training designs kept out of the fit (seed + 1), every band "
                         "frequency", "calibration": int(cal.size),
                         "pairs": int(cal.size * data.band_hz.size)}
        card[CALIBRATION_KEY] = entry
        card["training"]["calibration_rows"] = int(cal.size)
        predictor = Predictor({**card, "files": {}}, predictor.session)
    card["metrics"] = sweep_metrics(predictor, data, te, extra)
    write_model(out, card, {"model.onnx": onnx_bytes}, overwrite=overwrite)
    return card
