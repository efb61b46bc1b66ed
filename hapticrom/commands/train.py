"""``hapticrom train``: fit a surrogate on datasets and register it under ``models/NAME``.

    hapticrom train --data datasets/default --kind nn --out models/default-nn
    hapticrom train --data datasets/default datasets/lab --kind gp --out models/gp --overwrite
    hapticrom train --data datasets/default --kind mlp --out models/mlp-baseline
    hapticrom train --data datasets/transient --kind rom --out models/rom-default \
        --options '{"quasi_static_share": true}'
    hapticrom train --data datasets/default --kind nn --outputs profile_um,profile_normal_um \
        --out models/nn-normal
    hapticrom train --data datasets/default-sweep --kind nn --out models/nn-sweep   # sweeps

The kinds are those of the registry :mod:`surrogate.kinds`; this command knows none by name.
"""

from __future__ import annotations

import argparse

from fieldspec import FieldError
from fieldspec.documents import loads_json
from hapticrom.outputs import check_dir_output

__all__ = ["register"]


def _options(text: str | None) -> dict:
    try:
        options = loads_json(text, "--options", FieldError) if text else {}
    except FieldError as err:
        raise ValueError(f"--options {text[:80]!r}: not JSON within the limits ({err})") from None
    if not isinstance(options, dict):
        raise ValueError(f"--options {text!r}: expected a JSON object")
    return options


def _run(args: argparse.Namespace) -> int:
    # Lazy: the registry loads scikit-learn and torch (about 5 s measured with
    # `python -X importtime -c "import surrogate.kinds"`), which every other command and
    # `hapticrom --help` would pay for.
    from surrogate import kinds
    from surrogate.card_warnings import card_warnings
    from surrogate.sweep.targets import check_not_mixed
    from surrogate.sweep.train import train_sweep
    from surrogate.train import train

    options = _options(args.options)
    kind = kinds.get(args.kind)
    check_dir_output("--out", args.out, kind="model", overwrite=args.overwrite,
                     reads=[*args.data, *(args.test_data or [])])
    sweep = check_not_mixed(args.data)
    if args.test_data and not sweep:
        raise FieldError("--test-data", "--test-data: only with sweep datasets (a sweep "
                         "model's card is scored on the test set's designs)")
    fit = train_sweep if sweep else train  # sweeps: the complex band
    more = {"test_data": args.test_data} if args.test_data else {}
    card = fit(args.data, kind.name, args.out, test_fraction=args.test_fraction,
               seed=args.seed, n_modes=args.modes, overwrite=args.overwrite,
               options=options, outputs=args.outputs.split(","),
               calibration_fraction=args.calibration_fraction, **more)
    for line in kind.report(card):
        print(line)
    if "test_set" in card:  # --test-data: the fresh designs' figures beside the held-out ones
        t = card["test_set"]
        print(f"test set: {t['designs']} designs ({t['pairs']} pairs)")
        for name, m in t["metrics"].items():
            print(f"  {name:22s} " + "  ".join(f"{k} {v:.4g}" for k, v in m.items()))
    print(f"wrote {args.out}")
    for w in card_warnings(card):  # as the card says (written when it was sealed)
        print(f"warning: {w}")
    return 0


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``train`` subcommand."""
    p = subparsers.add_parser("train", help="train a surrogate (a kind of surrogate.kinds)")
    p.add_argument("--data", nargs="+", required=True, metavar="DATASET",
                   help="one or more dataset directories (same space inputs)")
    p.add_argument("--kind", required=True, metavar="KIND",
                   help="model kind, a name of the registry surrogate.kinds: gp, nn, mlp, "
                   "lgbm (harmonic amplitudes), rom (transient envelope); docs/architecture.md")
    p.add_argument("--out", required=True, metavar="DIR", help="model directory to write")
    p.add_argument("--test-data", nargs="+", default=None, metavar="DATASET",
                   help="sweep datasets of fresh designs (the same space at another seed, "
                   "e.g. of datasets/spaces/default-sweep-test.toml) the card is also scored "
                   "on: its test_set (docs/sweep-models.md)")
    p.add_argument("--overwrite", action="store_true",
                   help="replace an existing model directory (only one hapticrom wrote; never "
                   "a dataset or a directory of other files)")
    p.add_argument("--test-fraction", type=float, default=0.2,
                   help="share of rows held out for the metrics (default 0.2)")
    p.add_argument("--calibration-fraction", type=float, default=None,
                   help="share of the training rows kept out of the fit to calibrate the 95 %% "
                   "intervals (split conformal, surrogate/intervals.py; default: 0.1 when that "
                   "is at least 100 rows, else none; 0: none -- calibrate later with hapticrom "
                   "models calibrate-intervals)")
    p.add_argument("--seed", type=int, default=0, help="seed of split and training")
    p.add_argument("--modes", type=int, default=None,
                   help="POD modes of the log profile (default: 99.99 %% energy; gp 4)")
    p.add_argument("--outputs", default="profile_um", metavar="NAMES",
                   help="comma-separated profile outputs to learn besides the centre, edge and "
                   "ratio: profile_um (the magnitude, always), profile_normal_um (the normal "
                   "component |u_z| an LDV sees, from the column profile_uz_um); default "
                   "profile_um")
    p.add_argument("--options", metavar="JSON",
                   help='estimator parameters, e.g. \'{"n_members": 8}\'')
    p.set_defaults(func=_run)
