"""Learning from fewer, better sweep designs: active learning against Sobol order, and
multi-fidelity stacking, both retrospective on solved sweep datasets (no new FE solve).

Issue 36, item 2 (:mod:`studies.fewer_designs`; docs/sweep-models.md, "Learning from fewer,
better designs").

    # (a) active learning: start 1,024 designs, add 512 by disagreement or by Sobol order
    python bench/surrogate/refine_sweep.py active --data datasets/default-sweep \
        --test-data datasets/default-sweep-test --out-dir out/refine-sweep
    # (b) multi-fidelity: nn-default's predictions as extra features of the MLP peer (and of
    # the sweep NN with --learners mlp-peer,sweep-nn)
    python bench/surrogate/refine_sweep.py stacked --data datasets/default-sweep \
        --test-data datasets/default-sweep-test --low models/nn-default --sizes 1024,2460

Each command prints a markdown table (errors in %) and writes its record as JSON.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from threadpoolctl import threadpool_limits

from studies.fewer_designs import active, multifidelity


def _active(args: argparse.Namespace) -> int:
    record = active.run(args.data, args.test_data, args.out_dir, start=args.start,
                        add=args.add, kind=args.learner, seeds=args.seeds,
                        active_seeds=args.active_seeds, options=json.loads(args.options),
                        test_fraction=args.test_fraction,
                        log=lambda s: print(s, flush=True))
    sel = record["selection"]
    print(f"mean disagreement (ln): pool {sel['score_mean']['pool']:.4f}, picked "
          f"{sel['score_mean']['picked']:.4f}, next Sobol {sel['score_mean']['next_sobol']:.4f}")
    print("composition:", json.dumps(sel["composition"]))
    print(active.table(record))
    print(active.attachment_table(record))
    return 0


def _stacked(args: argparse.Namespace) -> int:
    with threadpool_limits(args.threads):
        record = multifidelity.run(args.data, args.test_data, args.low,
                                   sizes=[int(s) for s in args.sizes.split(",")],
                                   freqs_hz=[float(f) for f in args.freqs.split(",")],
                                   modes=args.modes, profile_modes=args.profile_modes,
                                   seed=args.seed, learner_names=args.learners.split(","),
                                   nn_options=json.loads(args.nn_options),
                                   test_fraction=args.test_fraction,
                                   log=lambda s: print(s, flush=True))
    print(multifidelity.table(record))
    if args.json:
        Path(args.json).write_text(json.dumps(record, indent=1))
    return 0


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    sub = ap.add_subparsers(dest="study", required=True)
    a = sub.add_parser("active", help="active learning against Sobol order")
    a.add_argument("--data", required=True, help="the sweep dataset (arms and pool)")
    a.add_argument("--test-data", required=True, nargs="+", help="test sweep datasets")
    a.add_argument("--out-dir", required=True, type=Path,
                   help="models and record.json (existing models are reused)")
    a.add_argument("--start", type=int, default=1024)
    a.add_argument("--add", type=int, default=512)
    a.add_argument("--learner", default="nn", choices=("nn", "gp"))
    a.add_argument("--seeds", type=int, nargs="+", default=[0, 1],
                   help="seeds of the Sobol arm (the first also trains the start model)")
    a.add_argument("--active-seeds", type=int, nargs="+", default=[0])
    a.add_argument("--options", default="{}", help="the kind's options (JSON), every model")
    a.add_argument("--test-fraction", type=float, default=0.1)
    a.set_defaults(run=_active)
    s = sub.add_parser("stacked", help="multi-fidelity: a low-fidelity model's predictions as "
                       "extra features")
    s.add_argument("--data", required=True)
    s.add_argument("--test-data", required=True)
    s.add_argument("--low", default="models/nn-default",
                   help="the single-frequency model whose predictions are stacked")
    s.add_argument("--sizes", default="1024,2460", help="first N designs of --data")
    s.add_argument("--freqs", default="100,150,200,250", help="band frequencies [Hz]")
    s.add_argument("--modes", type=int, default=48)
    s.add_argument("--profile-modes", type=int, default=24)
    s.add_argument("--seed", type=int, default=0)
    s.add_argument("--learners", default="mlp-peer",
                   help="mlp-peer (the output-choice MLP peer, complex band) and/or sweep-nn (the "
                   "network of hapticrom train --kind nn), comma-separated")
    s.add_argument("--nn-options", default="{}", help="sweep-nn: its options (JSON)")
    s.add_argument("--test-fraction", type=float, default=0.1,
                   help="sweep-nn: the designs held out of the fit, as hapticrom train's")
    s.add_argument("--threads", type=int, default=1, help="BLAS threads")
    s.add_argument("--json", default=None)
    s.set_defaults(run=_stacked)
    args = ap.parse_args(argv)
    return args.run(args)


if __name__ == "__main__":
    raise SystemExit(main())
