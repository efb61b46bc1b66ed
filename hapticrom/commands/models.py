"""``hapticrom models list|show|calibrate-intervals``: the model registry.

    hapticrom models list [--root models]
    hapticrom models show models/default-nn
    hapticrom models calibrate-intervals models/nn-default [--data datasets/default] [--dry-run]
"""

from __future__ import annotations

import argparse
import json

__all__ = ["register"]


def _list(args: argparse.Namespace) -> int:
    # lazy: a command's own library loads when it runs (`hapticrom --help`: 0.4 s)
    from surrogate.registry import list_models

    rows = list_models(args.root)
    if not rows:
        print(f"no models under {args.root}")
    for r in rows:
        status = f"ok  {r['headline']}" if r["status"] == "ok" else r["status"]
        print(f"{r['name']:24s} {r.get('kind') or '-':4s} {r.get('created') or '-':26s} "
              f"{status}")
        for w in r.get("warnings", []):
            print(f"  warning: {w}")
    return 0 if all(r["status"] == "ok" for r in rows) else 2  # a broken model: bad input


def _show(args: argparse.Namespace) -> int:
    # lazy: a command's own library loads when it runs (`hapticrom --help`: 0.4 s)
    from surrogate.registry import show_model

    card = show_model(args.model)
    print(json.dumps(card, indent=1))
    return 0


def _calibrate(args: argparse.Namespace) -> int:
    # lazy: a command's own library loads when it runs (`hapticrom --help`: 0.4 s)
    from surrogate.calibrate_intervals import calibrate_model_dir

    entry = calibrate_model_dir(args.model, args.data, check_fraction=args.check_fraction,
                                seed=args.seed, write=not args.dry_run)
    rows = entry["rows"]
    print(f"{args.model}: split-conformal 95 % factors from {rows['calibration']} held-out "
          f"rows: " + ", ".join(f"{g} {v['factor']:.3f}" for g, v in entry["groups"].items()))
    cov = entry["coverage95_check"]
    print(f"coverage of the 95 % interval on {rows['check']} other held-out rows "
          "(before -> after):")
    for name in cov["before"]:
        print(f"  {name:22s} {cov['before'][name]:6.1%} -> {cov['after'][name]:6.1%}")
    print("dry run: card unchanged" if args.dry_run else f"re-sealed {args.model}/card.json")
    return 0


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``models`` subcommand group."""
    p = subparsers.add_parser("models", help="list or show registered models")
    sub = p.add_subparsers(dest="models_command", required=True, metavar="ACTION")
    ls = sub.add_parser("list", help="every model under a directory, verified: ok, or "
                        "refused and why (exit 2 when any is refused)")
    ls.add_argument("--root", default="models", help="models directory (default: models)")
    ls.set_defaults(func=_list)
    show = sub.add_parser("show", help="print a model's verified card")
    show.add_argument("model", help="model directory")
    show.set_defaults(func=_show)
    cal = sub.add_parser("calibrate-intervals", help="scale a model's log-std so its 95 %% "
                         "intervals cover 95 %% of the rows its training held out "
                         "(split conformal; re-seals the card)")
    cal.add_argument("model", help="model directory")
    cal.add_argument("--data", nargs="+", metavar="DATASET",
                     help="the datasets it was trained on (default: the card's paths; their "
                     "manifests must match the card's)")
    cal.add_argument("--check-fraction", type=float, default=0.5,
                     help="share of the held-out rows kept apart to measure the coverage "
                     "(default 0.5; the rest compute the factors)")
    cal.add_argument("--seed", type=int, default=0,
                     help="seed of the calibration / check split (default 0)")
    cal.add_argument("--dry-run", action="store_true", help="report, do not write the card")
    cal.set_defaults(func=_calibrate)
