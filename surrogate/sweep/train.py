"""Train an NN or GP surrogate on sweep datasets (``hapticrom train --data SWEEP --kind nn``
or ``--kind gp``, which calls :func:`train_sweep` when every dataset is a sweep dataset).
What differs between the kinds is each kind's :class:`surrogate.kind.SweepKind` (its
options, fit, graph and parity): the NN's in :mod:`surrogate.sweep.nn`, the GP's in
:mod:`surrogate.sweep.gp` and :mod:`surrogate.sweep.gp_export`; what follows is the pipeline
both share.

The model learns, per design, the complex-band representation of
:class:`surrogate.sweep.targets.BandTargets` and ships it through the one graph contract of
:mod:`surrogate.estimators.export` (the decode to the requested frequency is inside the graph,
:mod:`surrogate.sweep.export`): its inputs are the space's design inputs plus
``frequency_hz`` over the band, so the predictor, the planner and ``hapticrom predict`` use it
as they use a single-frequency model.

* The held-out split is by design (every frequency of a held-out design is held out).
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
from surrogate.intervals import calibrate, residuals
from surrogate.kinds import SWEEP_KINDS
from surrogate.kinds import get as get_kind
from surrogate.registry import check_model_out, package_versions, write_model
from surrogate.runtime.predictor import CALIBRATION_KEY, Predictor, make_session
from surrogate.sweep.scoring import load_test_data, score_test_set
from surrogate.sweep.targets import SweepData, load_sweep_datasets, pair_rows
from surrogate.train import _calibration_rows, card_head, check_outputs, evaluate, split

__all__ = ["band_tails", "design_ranges", "sweep_metrics", "train_sweep"]



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


def design_ranges(designs: Sequence[int] | np.ndarray, n: int) -> dict[str, Any]:
    """What a card records of a design subset: how many of the ``n`` ok designs, and which,
    as sorted half-open ranges [start, stop) of row positions."""
    idx = np.sort(np.asarray(designs))
    breaks = np.flatnonzero(np.diff(idx) != 1) + 1 if idx.size else np.array([], int)
    ranges = [[int(r[0]), int(r[-1]) + 1] for r in np.split(idx, breaks) if r.size]
    return {"designs": int(idx.size), "of": int(n), "ranges": ranges,
            "rows": "positions among the training datasets' ok designs in design-sequence "
            "order"}


def train_sweep(paths: Sequence[str | Path], kind: str, out: str | Path, *,
                test_fraction: float = 0.2, seed: int = 0, n_modes: int | None = None,
                overwrite: bool = False, categorical: str = "onehot",
                options: dict[str, Any] | None = None, outputs: Sequence[str] = ("profile_um",),
                calibration_fraction: float | None = None,
                test_data: Sequence[str | Path] = (),
                designs: Sequence[int] | np.ndarray | None = None) -> dict[str, Any]:
    """Train an NN or GP sweep model on the sweep datasets ``paths`` and write ``out``
    (arguments as :func:`surrogate.train.train`; the split and the calibration rows are
    designs); return its card. ``test_data``: sweep datasets of fresh designs the card is also
    scored on (its ``test_set``, :mod:`surrogate.sweep.scoring`). ``hapticrom train`` calls
    it when every dataset is a sweep dataset. The GP: :mod:`surrogate.sweep.gp` (``options``:
    its ``GP_OPTIONS``). ``designs``: train on these designs only (row positions among the
    datasets' ok designs, each dataset in its design-sequence order, the datasets one after
    the other); the split and the calibration rows are then drawn from them, and the card
    records them (``training.design_subset``). None: every design."""
    spec = get_kind(kind)
    if spec.sweep is None:
        raise FieldError("--kind", f"--kind {kind}: sweep datasets train the "
                         f"{' and '.join(SWEEP_KINDS)} kinds (their graphs decode the complex "
                         f"band); give single-frequency datasets for {kind}")
    extra = check_outputs(outputs)
    # checked before anything is read or written: a bad option fails at once
    checked = spec.sweep.check_options(options)
    check_model_out(out, overwrite)
    data = load_sweep_datasets(paths, categorical=categorical)
    subset = None
    if designs is not None:
        n_all = len(data.codes)
        data = data.take(designs)
        subset = design_ranges(designs, n_all)
    test = load_test_data(test_data, data, categorical) if test_data else None
    normal = "profile_normal_um" in extra
    tr, te = split(len(data.codes), test_fraction, seed)
    tr, cal = _calibration_rows(tr, calibration_fraction, seed)
    specs = data.all_specs
    est, targets, fitted = spec.sweep.fit(checked, data, tr, seed, n_modes, normal)
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
                     "pod_energy": min(representation["pod_energy"].values()),
                     **({"design_subset": subset} if subset is not None else {}), **fitted},
        "versions": package_versions()}
    meta = {k: card[k] for k in ("kind", "inputs", "outputs", "profile_distance_mm",
                                 "training_data", "representation")}
    onnx_bytes = spec.sweep.export(est, targets, normal, specs[-1].low, specs[-1].high,
                                   data.band_hz, meta)
    predictor = Predictor({**card, "files": {}}, make_session(onnx_bytes))
    card.update(spec.sweep.parity(est, targets, predictor, data, te, normal))
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
    if test is not None:
        card["test_set"] = score_test_set(
            test, lambda d, designs: sweep_metrics(predictor, d, designs, extra))
    write_model(out, card, {"model.onnx": onnx_bytes}, overwrite=overwrite)
    return card
