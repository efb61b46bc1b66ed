"""The GP on sweep data (issue 20, item 3): output scaling, inducing set, std propagation.

Trains ``hapticrom train --kind gp`` models on a sweep dataset (:func:`surrogate.sweep.train.
train_sweep`, the command's defaults and split; one model per ``--variants`` entry of GP
options), reports the fit time, the graph's size, the card's held-out metrics and the scores
on ``--test-data`` (a sweep dataset at another Sobol seed), every (design, band frequency)
pair through the run-time predictor (``bench/surrogate/sweep_nn.py``'s scoring: median / p95 /
p99 / max relative error, the largest error on the field's scale, profile L2, calibrated 95 %
coverage).

``--sigma-points S`` compares, on the first variant refitted in memory, the two ways of
carrying the coefficients' std to ln |u|: the first-order propagation the graph ships
(:func:`surrogate.sweep.gp.linearised_log_std`) and S fixed Gaussian draws of the targets
decoded over the band (the std of the decoded ln |u| over the draws). Each is scaled by the
split-conformal factors of its calibration designs (:func:`surrogate.intervals.calibrate`)
and scored on the held-out designs: coverage and the median calibrated half-width (smaller
is better at equal coverage).

``--time-fit N`` times, on random inputs of the space's size (14 features, 178 targets), the
fit's two cubic steps at full scale: one evaluation of the summed log marginal likelihood and
its gradient on the hyperparameter subset (1,500 designs), and the kernel matrix and its
Cholesky on N designs (CPU time of this process; run it with OMP_NUM_THREADS=1).

``--profile MODEL_DIR`` prints where a graph spends its time: onnxruntime's node profile of
five calls at 1,024 rows (the predictor's chunk), one thread, the share of each node.

    python bench/surrogate/sweep_gp.py --data SWEEP_DIR --test-data TEST_DIR --out-dir DIR \
        --variants '[{"scale": "output"}, {"scale": "block"}]' --sigma-points 64
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path
from typing import Any

import numpy as np
from sweep_nn import baseline_predict, line, score

from surrogate.intervals import Z95, calibrate, coverage, normalised_residual
from surrogate.runtime.encoding import encode
from surrogate.sweep.gp import fit_sweep_gp, linearised_log_std
from surrogate.sweep.targets import (
    load_sweep_datasets,
    log_magnitudes,
    log_output_columns,
    pair_rows,
)
from surrogate.sweep.train import train_sweep
from surrogate.train import _calibration_rows, split


def held_out_line(card: dict[str, Any]) -> str:
    """The card's held-out metrics as one line."""
    m = card["metrics"]
    c, e, p = m["center_amplitude_um"], m["edge_amplitude_um"], m["profile_um"]
    return (f"centre {100 * c['median_rel_err']:.2f}/{100 * c['p95_rel_err']:.1f}/"
            f"{100 * c['p99_rel_err']:.1f}/{100 * c['max_rel_err']:.0f} %  edge "
            f"{100 * e['median_rel_err']:.2f}/{100 * e['p95_rel_err']:.1f}/"
            f"{100 * e['p99_rel_err']:.1f}/{100 * e['max_rel_err']:.0f} %  max/field "
            f"{100 * max(c['max_abs_err_over_field'], e['max_abs_err_over_field']):.1f} %  "
            f"profile L2 {100 * p['median_rel_l2']:.2f}/{100 * p['p95_rel_l2']:.1f} %  "
            f"coverage centre {100 * c['coverage95']:.1f} % edge {100 * e['coverage95']:.1f} %")


def sigma_point_std(est: Any, targets: Any, X: np.ndarray, n_f: int, draws: np.ndarray
                    ) -> tuple[np.ndarray, np.ndarray]:
    """(log_mean, log_std) (n * n_f, K) of designs ``X`` at every band frequency: the mean's
    decode and the std over ``draws`` (S, T) standard-normal target draws."""
    y, v = est.predict(X)
    means, stds = [], []
    for i in range(len(X)):
        ys = y[i] + np.sqrt(v[i]) * est.y_std_ * np.vstack([np.zeros(draws.shape[1]), draws])
        ln_s, z = targets.components(ys)                      # (1 + S, n_f, P, 6)
        out = log_output_columns(log_magnitudes(z, ln_s[:, None]))
        means.append(out[0])
        stds.append(out[1:].std(axis=0))
    return np.concatenate(means), np.concatenate(stds)


def compare_std(data: Any, args: argparse.Namespace, options: dict[str, Any]) -> None:
    """Linearised std against S sigma points, each conformally calibrated (see docstring)."""
    tr, te = split(len(data.codes), args.test, args.seed)
    tr, cal = _calibration_rows(tr, args.calibration_fraction, args.seed)
    if cal.size == 0:
        cal, te = te[: te.size // 2], te[te.size // 2:]
    est, targets = fit_sweep_gp(data, tr, seed=args.seed, n_modes=args.modes, options=options)
    n_f = data.band_hz.size
    draws = np.random.default_rng(args.seed).standard_normal((args.sigma_points,
                                                              est.y_mean_.size))
    results: dict[str, dict[str, np.ndarray]] = {"linearised": {}, "sigma points": {}}
    for name, rows in (("cal", cal), ("held", te)):
        X = encode(data.codes[rows], data.specs)
        truth = log_output_columns(log_magnitudes(data.response[rows])).reshape(
            rows.size * n_f, -1)
        mean, sp = sigma_point_std(est, targets, X, n_f, draws)
        y, v = est.predict(X)
        lin = linearised_log_std(targets, np.repeat(y, n_f, axis=0), np.repeat(v, n_f),
                                 np.tile(np.arange(n_f, dtype=float), rows.size), est.y_std_)
        for label, std in (("linearised", lin), ("sigma points", sp)):
            results[label][name] = normalised_residual(np.exp(truth), np.exp(mean), std)
            results[label][name + "_std"] = std
    for label, r in results.items():
        entry = calibrate(r["cal"])
        scale = np.asarray(entry["log_std_scale"])
        cov = coverage(r["held"], scale)
        width = np.median(Z95 * r["held_std"] * scale[None, :], axis=0)
        print(f"{label:13s} ({args.sigma_points} draws)" if label != "linearised" else
              f"{label:13s}", "factors", {k: round(g["factor"], 2) for k, g in
                                          entry["groups"].items()},
              "held-out coverage", {k: round(100 * c, 1) for k, c in cov.items()},
              f"median half-width ln: centre {width[0]:.3f} edge {width[1]:.3f} "
              f"profile {np.median(width[3:]):.3f}", flush=True)


def time_fit(n: int, d: int = 14, T: int = 178, n_hyper: int = 1500) -> None:
    """CPU seconds of one likelihood + gradient evaluation at ``n_hyper`` designs and of the
    kernel matrix + Cholesky at ``n`` designs (random inputs; see the docstring)."""
    from scipy.linalg import cholesky

    from surrogate.estimators.gp import ard_kernel
    from surrogate.sweep.gp import _SummedGPR

    rng = np.random.default_rng(0)
    X = rng.uniform(size=(n_hyper, d))
    gpr = _SummedGPR(ard_kernel("matern52", d, 1e-2, (1e-6, 1.0)), optimizer=None)
    gpr.fit(X, np.sin(X @ rng.normal(size=(d, T))))
    t0 = time.process_time()
    gpr.log_marginal_likelihood(gpr.kernel_.theta, eval_gradient=True)
    t1 = time.process_time()
    cholesky(gpr.kernel_(rng.uniform(size=(n, d))), lower=True)
    print(f"one likelihood + gradient at {n_hyper} designs x {T} targets: {t1 - t0:.1f} s CPU; "
          f"kernel matrix + Cholesky at {n} designs: {time.process_time() - t1:.1f} s CPU")


def profile_graph(model_dir: str, rows: int = 1024, top: int = 8) -> None:
    """Share of the graph's node time per node (onnxruntime profiling, one thread)."""
    import collections
    import tempfile

    import onnxruntime as ort

    opts = ort.SessionOptions()
    opts.enable_profiling, opts.intra_op_num_threads = True, 1
    opts.profile_file_prefix = str(Path(tempfile.mkdtemp()) / "profile")
    session = ort.InferenceSession(str(Path(model_dir) / "model.onnx"), opts,
                                   providers=["CPUExecutionProvider"])
    spec = session.get_inputs()[0]
    x = np.random.default_rng(0).uniform(size=(rows, spec.shape[1]))
    x = x.astype(np.float64 if "double" in spec.type else np.float32)
    for _ in range(5):
        session.run(None, {"x": x})
    events = json.loads(Path(session.end_profiling()).read_text())
    total: collections.Counter[tuple[str, str]] = collections.Counter()
    for e in events:
        if e.get("cat") == "Node" and e["name"].endswith("_kernel_time"):
            total[(e["args"]["op_name"], e["name"][:-len("_kernel_time")])] += e["dur"]
    whole = sum(total.values())
    for (op, name), dur in total.most_common(top):
        print(f"{100 * dur / whole:5.1f} %  {op:12s} {name}")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--data", required=True)
    ap.add_argument("--test-data", default=None)
    ap.add_argument("--out-dir", required=True, help="the models are written here")
    ap.add_argument("--variants", default='[{}]', help="JSON list of GP option dicts")
    ap.add_argument("--test", type=float, default=0.2)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--modes", type=int, default=None)
    ap.add_argument("--sigma-points", type=int, default=0)
    ap.add_argument("--calibration-fraction", type=float, default=None,
                    help="training designs kept out for the interval calibration (as "
                    "hapticrom train)")
    ap.add_argument("--json", default=None, help="write the scores here")
    ap.add_argument("--time-fit", type=int, default=0, help="time the cubic steps at N designs")
    ap.add_argument("--profile", default=None, help="profile this model directory's graph")
    args = ap.parse_args(argv)
    if args.profile:
        profile_graph(args.profile)
    if args.time_fit:
        time_fit(args.time_fit)
    variants = json.loads(args.variants)
    data = load_sweep_datasets([args.data])
    test = load_sweep_datasets([args.test_data]) if args.test_data else None
    print(f"{len(data.codes)} designs" + (f"; test set {len(test.codes)} designs"
                                          if test else ""), flush=True)
    results = {}
    Path(args.out_dir).mkdir(parents=True, exist_ok=True)
    for k, options in enumerate(variants):
        out = Path(args.out_dir) / f"gp-sweep-{k}"
        t0 = time.perf_counter()
        card = train_sweep([args.data], "gp", out, test_fraction=args.test, seed=args.seed,
                           n_modes=args.modes, options=dict(options), overwrite=True,
                           calibration_fraction=args.calibration_fraction)
        seconds = time.perf_counter() - t0
        size = (out / "model.onnx").stat().st_size
        print(f"{json.dumps(options)}: {out}, train {seconds:.0f} s (GP fit "
              f"{card['training']['gp']['fit_seconds']:.0f} s), graph {size / 1e6:.1f} MB, "
              f"{card['training']['gp']['kernel']}\n  held out "
              f"({card['training']['held_out']} designs) {held_out_line(card)}", flush=True)
        results[json.dumps(options)] = {"card_metrics": card["metrics"], "seconds": seconds,
                                        "graph_bytes": size}
        if test is not None:
            codes, centre, profile, _ = pair_rows(test, np.arange(len(test.codes)))
            s = score(baseline_predict(str(out), test, codes), centre, profile, test.grid_mm)
            print("  " + line("test set", s), flush=True)
            results[json.dumps(options)]["test"] = s
    if args.sigma_points:
        compare_std(data, args, dict(variants[0]))
    if args.json:
        Path(args.json).write_text(json.dumps({"args": vars(args), "results": results},
                                              indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
