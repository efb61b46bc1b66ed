"""Learning curve of the NN ensemble: held-out error against the number of FE samples.

    .venv/bin/python bench/bench_learning_curve.py [--data datasets/default] [--sizes 512 1024]

The held-out rows are those of ``hapticrom train`` (seeded 20 %); each size trains the default
ensemble on the first n training rows in the space's Sobol order (what a dataset of n samples
would hold) and reports the median and 95th-percentile relative error of the center and edge
amplitudes (through the same output map as the shipped model, in float64 torch, no export).
A straight line in log-log extrapolates how many samples a target error needs.
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np
from amplitude_errors import amplitude_errors

from surrogate.nn import MLPEnsembleRegressor
from surrogate.pod import ProfileTargets
from surrogate.runtime.encoding import encode
from surrogate.train import load_datasets, split


def rel_errors(est: MLPEnsembleRegressor, targets: ProfileTargets, X: np.ndarray,
               center: np.ndarray, edge: np.ndarray) -> dict[str, float]:
    """Median and p95 relative errors of exp(predicted log) for center and edge."""
    B, b = targets.output_map()
    return amplitude_errors(est.predict(X) @ B + b, center, edge)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", default="datasets/default")
    ap.add_argument("--sizes", type=int, nargs="+", default=[256, 512, 1024, 2048, 3277])
    ap.add_argument("--json", default=None, help="write the table as JSON here")
    args = ap.parse_args()
    data = load_datasets([args.data])
    tr, te = split(len(data.codes), 0.2, 0)  # the split of `hapticrom train`
    X = encode(data.codes, data.specs)
    edge = data.profile_um[:, 0]
    rows = []
    for n in args.sizes:
        sub = tr[:n]  # load_datasets keeps the Sobol order: the first n training rows
        t0 = time.perf_counter()
        targets = ProfileTargets()
        T = targets.fit_transform(data.center_um[sub], data.profile_um[sub])
        est = MLPEnsembleRegressor(random_state=0).fit(X[sub], T)
        err = rel_errors(est, targets, X[te], data.center_um[te], edge[te])
        rows.append({"n": int(sub.size), **err, "seconds": time.perf_counter() - t0})
        print(f"n {sub.size:5d}  center {err['center_median']:.4f} / {err['center_p95']:.4f}  "
              f"edge {err['edge_median']:.4f} / {err['edge_p95']:.4f}  "
              f"({rows[-1]['seconds']:.0f} s)", flush=True)
    if len(rows) >= 2:
        n = np.log([r["n"] for r in rows])
        slope = np.polyfit(n, np.log([r["center_median"] for r in rows]), 1)[0]
        need = rows[-1]["n"] * (0.01 / rows[-1]["center_median"]) ** (1 / slope)
        print(f"center median error ~ n^{slope:.2f}: 1 % would need about {need:.3g} samples")
    if args.json:
        with open(args.json, "w") as f:
            json.dump(rows, f, indent=1)


if __name__ == "__main__":
    main()
