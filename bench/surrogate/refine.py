"""Active learning against plain Sobol order, retrospectively on a generated dataset.

Both arms draw from the same pool of already-solved samples, so the comparison isolates the
choice of samples from the cost of solving them: a fixed, seeded quarter of the rows is held
out; the Sobol arm takes the pool's rows in design-sequence order (the first n of the space's
sequence, what ``hapticrom generate --n`` would run); the active arm starts from the same
first ``--start`` rows and adds ``--batch`` rows per round where the GP of the round is least
certain (:func:`surrogate.refine.select_batch`, what ``hapticrom refine`` runs on new FE
samples). After each step both arms fit the same GP and report the held-out median and 95th
percentile relative error of the center and edge amplitudes.

    .venv/bin/python bench/surrogate/refine.py --data datasets/default
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from surrogate.refine import fit_log_amplitudes, select_batch, uncertainty
from surrogate.runtime.encoding import encode
from surrogate.train import load_datasets


def errors(model, X: np.ndarray, center: np.ndarray, edge: np.ndarray) -> dict[str, float]:
    """Held-out median and 95th-percentile relative errors of the GP's median prediction
    exp(mean log) of the center and the edge amplitudes (any unit, the same in both)."""
    log_pred = model.predict(X)
    out = {}
    for j, (name, y) in enumerate((("center", center), ("edge", edge))):
        rel = np.abs(np.exp(log_pred[:, j]) / y - 1.0)
        out[f"{name}_median"] = float(np.median(rel))
        out[f"{name}_p95"] = float(np.percentile(rel, 95))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--data", default="datasets/default")
    ap.add_argument("--start", type=int, default=128)
    ap.add_argument("--batch", type=int, default=128)
    ap.add_argument("--until", type=int, default=1024)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--json", default=None, help="write the table as JSON here")
    args = ap.parse_args()

    data = load_datasets([args.data])
    X = encode(data.codes, data.specs)
    center, edge = data.center_um, data.profile_um[:, 0]
    n = len(X)
    perm = np.random.default_rng(args.seed).permutation(n)
    test = perm[: n // 4]
    pool = np.sort(perm[n // 4:])  # rows are stored in sample-index (Sobol) order
    rows = []
    active = list(pool[: args.start])
    sizes = list(range(args.start, min(args.until, len(pool)) + 1, args.batch))
    for size in sizes:
        t0 = time.perf_counter()
        sobol = pool[:size]
        m_sobol = fit_log_amplitudes(X[sobol], center[sobol], edge[sobol], args.seed, size)
        m_active = fit_log_amplitudes(X[active], center[active], edge[active], args.seed, size)
        row = {"n": size,
               "sobol": errors(m_sobol, X[test], center[test], edge[test]),
               "active": errors(m_active, X[test], center[test], edge[test])}
        rows.append(row)
        print(f"n {size:5d}  sobol center {row['sobol']['center_median']:.4f} / "
              f"{row['sobol']['center_p95']:.4f} edge {row['sobol']['edge_median']:.4f} / "
              f"{row['sobol']['edge_p95']:.4f}   active center "
              f"{row['active']['center_median']:.4f} / {row['active']['center_p95']:.4f} edge "
              f"{row['active']['edge_median']:.4f} / {row['active']['edge_p95']:.4f}   "
              f"({time.perf_counter() - t0:.0f} s)", flush=True)
        rest = np.setdiff1d(pool, active)
        if size + args.batch <= sizes[-1] and rest.size >= args.batch:
            pick = select_batch(uncertainty(m_active, X[rest]), X[rest], args.batch)
            active += list(rest[pick])
    print("(median / 95th percentile relative error on", test.size, "held-out rows)")
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=1))


if __name__ == "__main__":
    main()
