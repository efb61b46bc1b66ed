"""Learning curves of the GP and the NN: held-out error against the number of FE samples and
against total compute (generation + training). Thin front end of
:mod:`studies.accuracy.learning_curves` (also part of ``hapticrom bench accuracy``).

    .venv/bin/python bench/surrogate/learning_curve.py [--kind nn] [--sizes 256 512 1024]

Each size trains ``hapticrom train``'s default model on the first n training rows in the
space's Sobol order and reports the study's error metric (:mod:`studies.accuracy.metric`:
max of center, edge and profile-L2 relative errors) on every held-out row.
"""

from __future__ import annotations

import argparse
import json

from studies.accuracy.designs import DATASET, load_study_data
from studies.accuracy.learning_curves import curve, samples_for, sizes
from surrogate import kinds


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", default=str(DATASET))
    ap.add_argument("--kind", choices=["gp", "nn"], default="nn")
    ap.add_argument("--sizes", type=int, nargs="+", default=None)
    ap.add_argument("--json", default=None, help="write the table as JSON here")
    args = ap.parse_args()
    sd = load_study_data(args.data)
    rows, _ = curve(args.kind, sd, args.sizes or sizes(kinds.get(args.kind)))
    for r in rows:
        print(f"n {r['n']:5d}  error median {r['worst_median']:.4f} p95 {r['worst_p95']:.4f}  "
              f"center {r['center_median']:.4f}  edge {r['edge_median']:.4f}  "
              f"generation {r['generation_s']:.0f} s + training {r['train_s']:.0f} s")
    need = samples_for(rows)
    if need["n"] is not None:
        how = "extrapolated" if need["extrapolated"] else "measured"
        print(f"1 % median error: about {need['n']:.3g} samples ({how})")
    if args.json:
        with open(args.json, "w") as f:
            json.dump(rows, f, indent=1)


if __name__ == "__main__":
    main()
