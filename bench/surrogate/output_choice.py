"""Which outputs should a surrogate learn from sweep data, and how do the peers do? One table.

Issue 20, items 1 and 5 (:mod:`studies.output_choice`): every learner (scikit-learn MLP,
shared-kernel GP, per-output GPs, LightGBM) on every output choice (``point``: today's
magnitude at one frequency per row; ``lnmag``: POD of ln |u(f)| over the band; ``complex``: POD
of the complex band response with its scale; ``poles``: a pole-residue form fitted per design
by vector fitting), trained on the same designs of a sweep dataset
and scored on the same test designs at every band frequency: a held-out split (``--test``) or
another dataset (``--test-data``, e.g. fresh FE solves at another Sobol seed).

    python bench/surrogate/output_choice.py --data TRAIN [--test-data TEST] [--max-train N]
        [--gp-rows N] [--learners mlp,gp,gp-each,lgbm] [--choices point,lnmag,complex,poles]
        [--json out.json]

Prints one markdown table (errors in %) and, with ``--json``, writes the records and the data
sizes. GPs are capped at ``--gp-rows`` training rows (the table says so).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

from threadpoolctl import threadpool_limits

from studies.output_choice import data, learners, poles, representations, study


def _choices(args: argparse.Namespace) -> list[representations.Choice]:
    made = {"point": lambda: representations.Point(args.freqs_per_design, args.point_modes),
            "lnmag": lambda: representations.LnMagBand(args.modes, args.profile_modes),
            "complex": lambda: representations.ComplexBand(args.modes, args.profile_modes),
            "poles": lambda: poles.PoleResidue(args.poles)}
    out = []
    for name in args.choices.split(","):
        if name not in made:
            raise ValueError(f"--choices {name!r}: allowed {', '.join(made)}")
        out.append(made[name]())
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--data", required=True, help="training sweep dataset directory")
    ap.add_argument("--test-data", help="test sweep dataset (default: hold out --test)")
    ap.add_argument("--test", type=float, default=0.25,
                    help="held-out design fraction without --test-data")
    ap.add_argument("--max-train", type=int, help="use the first N training designs")
    ap.add_argument("--max-test", type=int, help="score the first N test designs")
    ap.add_argument("--gp-rows", type=int, help="GP learners train on the first N rows")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--modes", type=int, default=24, help="POD modes of the band choices")
    ap.add_argument("--profile-modes", type=int, default=12,
                    help="POD modes of the band choices' profile block")
    ap.add_argument("--point-modes", type=int, default=8,
                    help="POD modes of magnitude@f's profile at one frequency")
    ap.add_argument("--poles", type=int, default=4,
                    help="poles per design of the pole-residue choice (poles)")
    ap.add_argument("--no-profile", action="store_true", help="centre and edge only")
    ap.add_argument("--freqs-per-design", type=int, default=1,
                    help="training frequencies per design of the magnitude@f choice")
    ap.add_argument("--learners", default="mlp,gp,gp-each,lgbm",
                    help="comma-separated, or none (only each choice's projection floor)")
    ap.add_argument("--choices", default="point,lnmag,complex")
    ap.add_argument("--restarts", type=int, default=1,
                    help="gp-each: optimiser restarts of the leading targets")
    ap.add_argument("--lead", type=int, default=4, help="gp-each: targets given restarts")
    ap.add_argument("--trees", type=int, default=3000, help="lgbm: trees per target")
    ap.add_argument("--threads", type=int, default=1,
                    help="BLAS threads and LightGBM's booster-fitting processes (default 1: on "
                    "a shared machine more threads thrash; vector fitting ran 60x slower in "
                    "CPU time with the default pool)")
    ap.add_argument("--json", type=Path, help="write the records here")
    args = ap.parse_args(argv)
    try:
        choices = _choices(args)
        made = [learners.make(n, args.seed, gp_rows=args.gp_rows, restarts=args.restarts,
                              lead=args.lead, trees=args.trees, workers=args.threads)
                for n in args.learners.split(",") if args.learners != "none"]
        full, specs = data.load(args.data, profile=not args.no_profile)
        if args.test_data:
            train = full
            test, _ = data.load(args.test_data, profile=not args.no_profile, specs=specs)
        else:
            train, test = data.split(full, args.test, args.seed)
        if args.max_train:
            train = train.take(slice(0, args.max_train))
        if args.max_test:
            test = test.take(slice(0, args.max_test))
        if test.band.shape != train.band.shape or (test.band != train.band).any():
            raise ValueError("the test designs' band differs from the training designs'")
    except ValueError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    sizes = (f"train {len(train)} designs of {train.source}; test {len(test)} designs of "
             f"{test.source}; {train.band.size} frequencies {train.band[0]:g}-"
             f"{train.band[-1]:g} Hz")
    print(sizes)
    print(study.HEADER)
    t0 = time.perf_counter()
    with threadpool_limits(args.threads):
        records = study.run(train, test, made, choices, args.seed)
    print()
    print(study.table(records))
    if args.json:
        args.json.write_text(json.dumps(
            {"command": " ".join(["python bench/surrogate/output_choice.py",
                                   *(argv or sys.argv[1:])]),
             "train": {"source": train.source, "designs": len(train)},
             "test": {"source": test.source, "designs": len(test)},
             "band_hz": [float(train.band[0]), float(train.band[-1]), int(train.band.size)],
             "wall_s": time.perf_counter() - t0, "records": records}, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
