"""Where a sweep model errs on a test set: its p95 error and interval coverage by group of
designs (glued, pogo, pogo units with lightly damped rings), then the designs it misses worst:
each design's worst (frequency,
output) pair on the field's scale (|error| / max(FE centre, FE edge), as the cards' largest
error), the design's inputs, and the test set's FE answer re-checked by a direct harmonic
solve of the same scene at that frequency (so that a large error is known to be the model's,
not the reduced-order sweep's).

    .venv/bin/python bench/surrogate/worst_designs.py --model models/nn-sweep \
        --test-data datasets/default-sweep-test [--worst 6] [--no-resolve] \
        [--by-attachment datasets/default-sweep]

One line per design, worst first: the error on the field's scale, the output and frequency,
model / sweep / direct values [um], whether the model's 95 % interval holds the FE value, then
the design's inputs (moduli in kPa, thickness in mm; rings beyond ``n_rings`` are unused).
"""

from __future__ import annotations

import argparse
import json
import time
from dataclasses import dataclass
from typing import Any

import numpy as np

import fem
from fem.scene import scene_from_dict
from surrogate.data.store import Store
from surrogate.intervals import Z95, calibrate, residuals
from surrogate.runtime.predictor import Predictor, load_predictor
from surrogate.sweep.scoring import named_inputs, predict_pairs, score_pairs
from surrogate.sweep.targets import SweepData, load_sweep_datasets, pair_rows
from surrogate.train import split

OUTPUTS = (("centre", "center_amplitude_um"), ("edge", "edge_amplitude_um"))


def harmonic_scene(sweep_scene: dict[str, Any], frequency_hz: float) -> dict[str, Any]:
    """The scene dict of a sweep row solved at one frequency: its analysis made harmonic at
    ``frequency_hz``, the sweep's tolerance dropped, everything else as stored."""
    scene = json.loads(json.dumps(sweep_scene))
    analysis = {k: v for k, v in scene["analysis"].items() if k != "tolerance"}
    scene["analysis"] = {**analysis, "kind": "harmonic", "frequency_hz": float(frequency_hz)}
    return scene


@dataclass
class Scored:
    """A model's answers at every (design, band frequency) pair of a test set, once: the
    data, its pairs' FE centre and profile [um], the answers (:func:`predict_pairs`) and the
    pairs' named inputs."""

    test: SweepData
    centre: np.ndarray
    profile: np.ndarray
    pred: dict[str, np.ndarray]
    inputs: dict[str, np.ndarray]

    @classmethod
    def of(cls, predictor: Predictor, test: SweepData) -> Scored:
        codes, centre, profile, _ = pair_rows(test, np.arange(len(test.codes)))
        return cls(test, centre, profile, predict_pairs(predictor, test, codes),
                   named_inputs(codes, test.all_specs))

    def subset(self, rows: np.ndarray) -> dict[str, np.ndarray]:
        """The answers at the pairs ``rows`` (the profile grid kept whole)."""
        n = len(self.centre)
        return {k: (v[rows] if np.ndim(v) and len(v) == n else v) for k, v in self.pred.items()}


def worst_pairs(s: Scored, k: int) -> list[dict[str, Any]]:
    """The ``k`` designs with the largest error on the field's scale, each at its worst
    pair: design index, output, frequency [Hz], model and FE [um], the model's 95 % interval
    [um] (from its calibrated log-std)."""
    field = np.maximum(s.centre, s.profile[:, 0])
    truth = {"centre": s.centre, "edge": s.profile[:, 0]}
    err = np.stack([np.abs(s.pred[key] - truth[name]) / field for name, key in OUTPUTS])
    n_f = s.test.band_hz.size
    per_design = err.reshape(len(OUTPUTS), len(s.test.codes), n_f)
    rows = []
    for d in np.argsort(per_design.max(axis=(0, 2)))[::-1][:k]:
        o, f = np.unravel_index(per_design[:, d].argmax(), (len(OUTPUTS), n_f))
        name, key = OUTPUTS[o]
        pair = d * n_f + f
        value, log_std = s.pred[key][pair], s.pred[f"{key}_log_std"][pair]
        rows.append({"design": int(d), "output": name, "frequency_hz": float(s.test.band_hz[f]),
                     "error_over_field": float(per_design[o, d, f]), "model_um": float(value),
                     "sweep_um": float(truth[name][pair]),
                     "interval_um": (float(value * np.exp(-Z95 * log_std)),
                                     float(value * np.exp(Z95 * log_std)))})
    return rows


#: The groups of test designs scored apart (name, rule on the named inputs of the pairs): the
#: two attachments, and the pogo units with lightly damped rings (loss factor below 0.06 of its
#: log-uniform 0.02-0.30: about 40 % of the ringed units) where the worst designs sit, on any
#: skin and on soft skin.
GROUPS = (
    ("all", lambda x: np.ones(len(x["attachment"]), bool)),
    ("glued", lambda x: x["attachment"] == "glued"),
    ("pogo", lambda x: x["attachment"] == "pogo"),
    ("pogo, rings with loss factor < 0.06", lambda x: (x["attachment"] == "pogo")
     & (x["n_rings"] > 0) & (x["ring_loss_factor"] < 0.06)),
    ("the same on skin < 40 kPa", lambda x: (x["attachment"] == "pogo") & (x["n_rings"] > 0)
     & (x["ring_loss_factor"] < 0.06) & (x["skin_E_kPa"] < 40.0)),
)


def by_group(s: Scored) -> list[str]:
    """Per :data:`GROUPS`: designs, and per output the p95 relative error and the 95 %
    interval's coverage of the FE values over the group's pairs, as the cards score them
    (:func:`surrogate.sweep.scoring.score_pairs`)."""
    lines = []
    for group, rule in GROUPS:
        rows = rule(s.inputs)
        got = score_pairs(s.subset(rows), s.centre[rows], s.profile[rows], s.test.grid_mm)
        lines.append(f"  {group} ({rows.sum() // s.test.band_hz.size} designs): " + "; ".join(
            f"{name} p95 {100 * got[name][1]:.1f} %, coverage "
            f"{100 * got[f'{name}_coverage95']:.1f} %" for name, _ in OUTPUTS))
    return lines


def by_attachment_calibration(model: str, train_dir: str, test: SweepData) -> list[str]:
    """What intervals calibrated per attachment (a Mondrian split of the conformal scores)
    would cover, against the card's one calibration over all designs: both calibrated here the
    same way (:func:`surrogate.intervals.calibrate`, hierarchical by design) on every design
    the model's training held out of ``train_dir`` (the card's seed and test fraction), the
    model's raw log-std, then scored on ``test`` by group (centre / edge coverage)."""
    raw = load_predictor(model, calibrated=False)
    extra = list(raw.extra_outputs)
    train = load_sweep_datasets([train_dir])
    _, held = split(len(train.codes), float(raw.card["training"]["test_fraction"]),
                    int(raw.card["training"]["seed"]))

    def scores(data: SweepData, designs: np.ndarray) -> tuple[np.ndarray, dict[str, np.ndarray]]:
        codes, centre, profile, ext = pair_rows(data, designs, "profile_normal_um" in extra)
        return (residuals(raw.predict(codes), centre, profile, ext),
                named_inputs(codes, data.all_specs))

    r_cal, x_cal = scores(train, held)
    r_test, x_test = scores(test, np.arange(len(test.codes)))
    design = np.repeat(held, train.band_hz.size)
    pooled = np.asarray(calibrate(r_cal, extra=extra, group=design)["log_std_scale"])
    scale = np.empty_like(r_test)
    lines = []
    for choice in np.unique(x_cal["attachment"]):
        rows = x_cal["attachment"] == choice
        factor = np.asarray(calibrate(r_cal[rows], extra=extra, group=design[rows])
                            ["log_std_scale"])
        scale[x_test["attachment"] == choice] = factor
        lines.append(f"  {choice}: factors centre {factor[0]:.3g}, edge {factor[1]:.3g} "
                     f"(all designs: {pooled[0]:.3g}, {pooled[1]:.3g})")
    for group, rule in GROUPS:
        rows = rule(x_test)
        one = (r_test[rows, :2] <= Z95 * pooled[None, :2]).mean(axis=0)
        split_ = (r_test[rows, :2] <= Z95 * scale[rows, :2]).mean(axis=0)
        lines.append(f"  {group}: coverage centre / edge {100 * one[0]:.1f} / {100 * one[1]:.1f} % "
                     f"calibrated over all designs, {100 * split_[0]:.1f} / {100 * split_[1]:.1f} "
                     "% per attachment")
    return lines


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--model", default="models/nn-sweep", help="a sweep model directory")
    ap.add_argument("--test-data", default="datasets/default-sweep-test")
    ap.add_argument("--worst", type=int, default=6, help="designs listed (default 6)")
    ap.add_argument("--no-resolve", action="store_true", help="skip the direct FE re-solves")
    ap.add_argument("--by-attachment", metavar="TRAIN_DIR", default=None,
                    help="also: the coverage if the intervals were calibrated per attachment on "
                    "the designs the model's training held out of TRAIN_DIR (its dataset)")
    args = ap.parse_args()
    predictor = load_predictor(args.model)
    test = load_sweep_datasets([args.test_data])
    if args.by_attachment:
        print(f"{args.model}: intervals calibrated per attachment, on {args.test_data}:")
        print("\n".join(by_attachment_calibration(args.model, args.by_attachment, test)))
    scored = Scored.of(predictor, test)
    print(f"{args.model} on {args.test_data}, by group of designs (every band frequency):")
    print("\n".join(by_group(scored)))
    rows = worst_pairs(scored, args.worst)
    table = Store.open(args.test_data).read()
    table = table[table["status"] == "ok"].sort_values("sample_index", kind="stable")
    table = table.reset_index(drop=True)
    inputs = [spec.name for spec in test.specs]
    print(f"{args.model} on {args.test_data}: the {len(rows)} designs with the largest error on "
          "the field's scale, each at its worst pair")
    for r in rows:
        direct = ""
        if not args.no_resolve:
            scene = harmonic_scene(json.loads(table.loc[r["design"], "scene_json"]),
                                   r["frequency_hz"])
            t0 = time.perf_counter()
            res = fem.simulate(scene_from_dict(scene))
            value = (res.center_amplitude_um if r["output"] == "centre"
                     else res.edge_amplitude_um)
            direct = (f" / direct {value:.4g} ({100 * (value / r['sweep_um'] - 1):+.2f} % from "
                      f"the sweep, {time.perf_counter() - t0:.1f} s)")
        design = ", ".join(f"{n} {_text(table.loc[r['design'], n])}" for n in inputs)
        low, high = r["interval_um"]
        held = "holds" if low <= r["sweep_um"] <= high else "misses"
        print(f"  design {r['design']}: {100 * r['error_over_field']:.1f} % of the field, "
              f"{r['output']} at {r['frequency_hz']:g} Hz: model {r['model_um']:.4g} / sweep "
              f"{r['sweep_um']:.4g} um{direct}; the 95 % interval {low:.3g}-{high:.3g} um "
              f"{held} the FE value\n      {design}")


def _text(value: Any) -> str:
    return f"{value:.3g}" if isinstance(value, float | np.floating) else str(value)


if __name__ == "__main__":
    main()
