"""The designs a sweep model misses worst on a test set: each design's worst (frequency,
output) pair on the field's scale (|error| / max(FE centre, FE edge), as the cards' largest
error), the design's inputs, and the test set's FE answer re-checked by a direct harmonic
solve of the same scene at that frequency (so that a large error is known to be the model's,
not the reduced-order sweep's).

    .venv/bin/python bench/surrogate/worst_designs.py --model models/nn-sweep \
        --test-data datasets/default-sweep-test [--worst 6] [--no-resolve]

One line per design, worst first: the error on the field's scale, the output and frequency,
model / sweep / direct values [um], then the design's inputs (moduli in kPa, thickness in mm).
"""

from __future__ import annotations

import argparse
import json
import time
from typing import Any

import numpy as np

import fem
from fem.scene import scene_from_dict
from surrogate.data.store import Store
from surrogate.runtime.predictor import load_predictor
from surrogate.sweep.scoring import predict_pairs
from surrogate.sweep.targets import load_sweep_datasets, pair_rows

OUTPUTS = (("centre", "center_amplitude_um"), ("edge", "edge_amplitude_um"))


def harmonic_scene(sweep_scene: dict[str, Any], frequency_hz: float) -> dict[str, Any]:
    """The scene dict of a sweep row solved at one frequency: its analysis made harmonic at
    ``frequency_hz``, the sweep's tolerance dropped, everything else as stored."""
    scene = json.loads(json.dumps(sweep_scene))
    analysis = {k: v for k, v in scene["analysis"].items() if k != "tolerance"}
    scene["analysis"] = {**analysis, "kind": "harmonic", "frequency_hz": float(frequency_hz)}
    return scene


def worst_pairs(model: str, test_dir: str, k: int) -> list[dict[str, Any]]:
    """The ``k`` designs of ``test_dir`` with the largest error of ``model`` on the field's
    scale, each at its worst pair: design index, output, frequency [Hz], model and FE [um]."""
    test = load_sweep_datasets([test_dir])
    codes, centre, profile, _ = pair_rows(test, np.arange(len(test.codes)))
    pred = predict_pairs(load_predictor(model), test, codes)
    field = np.maximum(centre, profile[:, 0])
    truth = {"centre": centre, "edge": profile[:, 0]}
    err = np.stack([np.abs(pred[key] - truth[name]) / field for name, key in OUTPUTS])
    n_f = test.band_hz.size
    per_design = err.reshape(len(OUTPUTS), len(test.codes), n_f)
    worst_of = per_design.max(axis=(0, 2))
    rows = []
    for d in np.argsort(worst_of)[::-1][:k]:
        o, f = np.unravel_index(per_design[:, d].argmax(), (len(OUTPUTS), n_f))
        name, key = OUTPUTS[o]
        pair = d * n_f + f
        rows.append({"design": int(d), "output": name, "frequency_hz": float(test.band_hz[f]),
                     "error_over_field": float(per_design[o, d, f]),
                     "model_um": float(pred[key][pair]), "sweep_um": float(truth[name][pair])})
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--model", default="models/nn-sweep", help="a sweep model directory")
    ap.add_argument("--test-data", default="datasets/default-sweep-test")
    ap.add_argument("--worst", type=int, default=6, help="designs listed (default 6)")
    ap.add_argument("--no-resolve", action="store_true", help="skip the direct FE re-solves")
    args = ap.parse_args()
    rows = worst_pairs(args.model, args.test_data, args.worst)
    table = Store.open(args.test_data).read()
    table = table[table["status"] == "ok"].sort_values("sample_index", kind="stable")
    table = table.reset_index(drop=True)
    inputs = [s.name for s in load_predictor(args.model).specs if s.name != "frequency_hz"]
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
        print(f"  design {r['design']}: {100 * r['error_over_field']:.1f} % of the field, "
              f"{r['output']} at {r['frequency_hz']:g} Hz: model {r['model_um']:.4g} / sweep "
              f"{r['sweep_um']:.4g} um{direct}\n      {design}")


def _text(value: Any) -> str:
    return f"{value:.3g}" if isinstance(value, float | np.floating) else str(value)


if __name__ == "__main__":
    main()
