"""``hapticrom refine``: active learning, FE samples where the GP is least certain.

    hapticrom refine datasets/default --batch 64 --rounds 2
    hapticrom train --data datasets/default --kind nn --out models/nn-default --overwrite
"""

from __future__ import annotations

import argparse

from hapticrom.commands._args import positive_int

__all__ = ["register"]


def _run(args: argparse.Namespace) -> int:
    # lazy: a command's own library loads when it runs (`hapticrom --help`: 0.4 s)
    from surrogate.refine import refine

    def show(info: dict) -> None:
        print(f"round: {info['rows_before']} rows; picked {info['added_ok']} ok, "
              f"{info['added_failed']} failed of a pool of {info['pool']}; predictive log std "
              f"picked {info['mean_log_std_picked']:.3g} vs pool {info['mean_log_std_pool']:.3g}")

    refine(args.dataset, args.batch, rounds=args.rounds, seed=args.seed, workers=args.workers,
           progress=not args.quiet, command="hapticrom refine", on_round=show)
    print(f"refined {args.dataset}; retrain with: hapticrom train --data {args.dataset} ...")
    return 0


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``refine`` subcommand."""
    p = subparsers.add_parser("refine", help="add FE samples where the surrogate is least "
                              "certain (active learning)")
    p.add_argument("dataset", help="a generated dataset directory (its space is used)")
    p.add_argument("--batch", type=positive_int, default=64,
                   help="samples per round (default 64)")
    p.add_argument("--rounds", type=positive_int, default=1, help="rounds (default 1)")
    p.add_argument("--workers", type=positive_int, default=None,
                   help="worker processes (default: one per core)")
    p.add_argument("--seed", type=int, default=0, help="seed of the GP fit")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=_run)
