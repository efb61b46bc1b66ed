"""The NN sweep model: MSE on the complex-band coefficients vs training through the decode.

Issue 20, items 1 and 3. On the same designs of a sweep dataset (held out by design with the
split of ``hapticrom train``: ``--test`` and ``--seed``), this fits the complex-band model of
:mod:`surrogate.sweep.train` once by MSE on its targets (``loss = "coefficients"``), scores it,
then keeps training the same members through the differentiable decode on ln magnitudes
(``loss = "magnitude"``, what ``hapticrom train`` ships by default) and scores it again. Every
score is of the exported ONNX graph run on the run-time encoding, at every band frequency of
the held-out designs (and of the designs of ``--test-data``, a sweep dataset at another Sobol
seed), beside a single-frequency model (``--baseline``, default models/nn-default) scored at
the same (design, frequency) pairs. Profile L2 errors over the whole profile and over 0-20 mm
(the single-frequency models' profile).

    python bench/surrogate/sweep_nn.py --data SWEEP_DIR \
        --test-data TEST_DIR --options '{"hidden": [256, 256]}'
    python bench/surrogate/sweep_nn.py --model models/NAME --test-data ... --data ...
"""

from __future__ import annotations

import argparse
import copy
import json
import time
from typing import Any

import numpy as np

from surrogate.runtime.encoding import encode
from surrogate.runtime.predictor import load_predictor, make_session
from surrogate.sweep.export import export_sweep_nn
from surrogate.sweep.nn import fit_sweep, split_nn_options
from surrogate.sweep.scoring import predict_pairs
from surrogate.sweep.scoring import score_pairs as score
from surrogate.sweep.targets import SweepData, load_sweep_datasets, pair_rows
from surrogate.train import _calibration_rows, split


def graph_predict(onnx: bytes, data: SweepData, codes: np.ndarray) -> dict[str, np.ndarray]:
    """Centre, edge and profile [um] from the exported graph at (design, frequency) codes
    (encoded with the inputs of the training data ``data``)."""
    session = make_session(onnx)
    x = encode(codes, data.all_specs).astype(np.float32)
    log_mean = np.concatenate([session.run(["log_mean"], {"x": x[i:i + 4096]})[0]
                               for i in range(0, len(x), 4096)])
    amp = np.exp(log_mean.astype(float))
    return {"center_amplitude_um": amp[:, 0], "edge_amplitude_um": amp[:, 1],
            "profile_um": amp[:, 3:3 + data.grid_mm.size]}


def baseline_predict(path: str, data: SweepData, codes: np.ndarray) -> dict[str, np.ndarray]:
    """A model directory's outputs at the pairs (through the run-time predictor), its profile
    on its own grid."""
    return predict_pairs(load_predictor(path), data, codes)


def line(name: str, s: dict[str, Any]) -> str:
    c, e = s["centre"], s["edge"]
    pa = s.get("profile_all", [np.nan, np.nan])
    pn = s["profile_0_20mm"]
    return (f"{name:34} centre {100 * c[0]:.2f}/{100 * c[1]:.1f}/{100 * c[2]:.1f}/"
            f"{100 * c[3]:.0f} %  edge {100 * e[0]:.2f}/{100 * e[1]:.1f}/{100 * e[2]:.1f}/"
            f"{100 * e[3]:.0f} %  max/field {100 * max(c[4], e[4]):.1f} %  profile L2 "
            f"{100 * pa[0]:.2f}/{100 * pa[1]:.1f} % (0-20 mm {100 * pn[0]:.2f}/"
            f"{100 * pn[1]:.1f} %)" + "".join(f"  coverage {k[:-11]} {100 * v:.1f} %"
                                               for k, v in s.items() if k.endswith("coverage95")))


def score_model(args: argparse.Namespace) -> int:
    """Score a trained model and the baseline at every pair of the test set's designs."""
    test = load_sweep_datasets([args.test_data])
    codes, centre, profile, _ = pair_rows(test, np.arange(len(test.codes)))
    print(f"test set {len(test.codes)} designs x {test.band_hz.size} frequencies")
    results = {}
    for name in (args.model, args.baseline):
        s = score(baseline_predict(name, test, codes), centre, profile, test.grid_mm)
        results[name] = s
        print(line(name, s), flush=True)
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"args": vars(args), "results": results}, f, indent=1)
    return 0


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--data", required=True)
    ap.add_argument("--test-data", default=None)
    ap.add_argument("--baseline", default="models/nn-default")
    ap.add_argument("--test", type=float, default=0.2)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--modes", type=int, default=None, help="profile POD modes (default 128)")
    ap.add_argument("--options", default="{}", help="sweep and estimator options (JSON)")
    ap.add_argument("--json", default=None, help="write the scores here")
    ap.add_argument("--centre-weights", default="1",
                    help="comma-separated centre_weight values: one refit of the same stage-1 "
                    "fit each")
    ap.add_argument("--model", default=None, help="score this trained sweep model directory "
                    "on --test-data (beside --baseline) instead of fitting")
    args = ap.parse_args(argv)
    if args.model:
        return score_model(args)
    options = json.loads(args.options)
    ours, _ = split_nn_options(dict(options))
    data = load_sweep_datasets([args.data])
    tr, te = split(len(data.codes), args.test, args.seed)
    tr, _cal = _calibration_rows(tr, None, args.seed)
    sets = {"held-out": (data, te)}
    if args.test_data:
        test = load_sweep_datasets([args.test_data])
        sets["test set"] = (test, np.arange(len(test.codes)))
    print(f"{len(data.codes)} designs: fit {tr.size}, held out {te.size}"
          + (f"; test set {len(sets['test set'][1])} designs" if args.test_data else "")
          + f"; {data.band_hz.size} frequencies; errors med/p95/p99/max over every pair")
    results: dict[str, Any] = {}
    t0 = time.perf_counter()
    est, targets = fit_sweep(data, tr, seed=args.seed, n_modes=args.modes,
                             options={**options, "loss": "coefficients"})
    stages = [("coefficients (MSE)", time.perf_counter() - t0)]
    first = est
    weights = [float(w) for w in args.centre_weights.split(",")]
    for stage in ("coefficients", *(f"magnitude w{w:g}" for w in weights)):
        if stage != "coefficients":
            from surrogate.sweep.export import BandDecoder, magnitude_error

            t0 = time.perf_counter()
            X = encode(data.codes[tr], data.specs)
            est = copy.deepcopy(first)
            est.refit(X, magnitude_error(BandDecoder(targets), data.response[tr],
                                         centre_weight=float(stage.split(" w")[1])),
                      max_epochs=ours["refit_epochs"], patience=ours["refit_patience"],
                      learning_rate=ours["refit_learning_rate"])
            stages.append((f"+ through the decode ({stage})", time.perf_counter() - t0))
            print(f"refit best epochs {est.refit_best_epoch_}", flush=True)
        onnx = export_sweep_nn(est, targets, False, data.band_hz[0], data.band_hz[-1],
                               data.band_hz, {})
        for set_name, (d, designs) in sets.items():
            codes, centre, profile, _ = pair_rows(d, designs)
            s = score(graph_predict(onnx, data, codes), centre, profile, d.grid_mm)
            results[f"{stage} {set_name}"] = s
            print(line(f"{stage} {set_name}", s), flush=True)
    for set_name, (d, designs) in sets.items():
        codes, centre, profile, _ = pair_rows(d, designs)
        s = score(baseline_predict(args.baseline, d, codes), centre, profile, d.grid_mm)
        results[f"baseline {set_name}"] = s
        print(line(f"{args.baseline} {set_name}", s), flush=True)
    print("fit time: " + ", ".join(f"{n} {t:.0f} s" for n, t in stages))
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"args": vars(args), "results": results}, f, indent=1)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
