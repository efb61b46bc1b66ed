"""``hapticrom train``: fit a surrogate on datasets and register it under ``models/NAME``.

    hapticrom train --data datasets/default --kind nn --out models/default-nn
    hapticrom train --data datasets/default datasets/lab --kind gp --out models/gp --overwrite
    hapticrom train --data datasets/transient --kind rom --out models/rom-default
"""

from __future__ import annotations

import argparse

__all__ = ["register"]


def _options(text: str | None) -> dict:
    from fieldspec import FieldError
    from fieldspec.documents import loads_json  # nesting limits

    try:
        options = loads_json(text, "--options", FieldError) if text else {}
    except FieldError as err:
        raise ValueError(f"--options {text[:80]!r}: not JSON within the limits ({err})") from None
    if not isinstance(options, dict):
        raise ValueError(f"--options {text!r}: expected a JSON object")
    return options


def _run_rom(args: argparse.Namespace, options: dict) -> int:
    from surrogate.rom import train

    unknown = sorted(set(options) - {"harmonic", "max_nfev"})
    if unknown:
        raise ValueError(f"--options: {unknown[0]!r} is not a rom option (allowed: harmonic, "
                         "max_nfev)")
    card = train(args.data, args.out, seed=args.seed, overwrite=args.overwrite, **options)
    held = card["metrics"]["held_out"]["summary"]
    print(f"identified rom on {card['split']['n_train']} runs, held out "
          f"{card['split']['n_held_out']}")
    print("  " + "  ".join(f"{k} {v:.4g}" for k, v in held.items() if v is not None))
    print(f"wrote {args.out}")
    return 0


def _run(args: argparse.Namespace) -> int:
    from hapticrom.outputs import check_dir_output

    options = _options(args.options)
    check_dir_output("--out", args.out, kind="model", overwrite=args.overwrite,
                     reads=args.data)
    if args.kind == "rom":
        return _run_rom(args, options)
    from surrogate.train import train

    card = train(args.data, args.kind, args.out, test_fraction=args.test_fraction,
                 seed=args.seed, n_modes=args.modes, overwrite=args.overwrite,
                 options=options)
    t = card["training"]
    print(f"trained {args.kind} on {t['rows']} rows, held out {t['held_out']} "
          f"(POD {t['pod_modes']} modes, {100 * t['pod_energy']:.3f} % energy)")
    for name, m in card["metrics"].items():
        print(f"  {name:22s} " + "  ".join(f"{k} {v:.4g}" for k, v in m.items()))
    print(f"export parity max |d ln| {card['export_parity_max_abs_dln']:.2g}")
    print(f"wrote {args.out}")
    return 0


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``train`` subcommand."""
    p = subparsers.add_parser("train", help="train a surrogate (gp, nn or transient rom)")
    p.add_argument("--data", nargs="+", required=True, metavar="DATASET",
                   help="one or more dataset directories (same space inputs)")
    p.add_argument("--kind", required=True, choices=("gp", "nn", "rom"),
                   help="model kind: gp, nn (harmonic amplitudes), rom (transient envelope)")
    p.add_argument("--out", required=True, metavar="DIR", help="model directory to write")
    p.add_argument("--overwrite", action="store_true",
                   help="replace an existing model directory (only one hapticrom wrote; never "
                   "a dataset or a directory of other files)")
    p.add_argument("--test-fraction", type=float, default=0.2,
                   help="share of rows held out for the metrics (default 0.2)")
    p.add_argument("--seed", type=int, default=0, help="seed of split and training")
    p.add_argument("--modes", type=int, default=None,
                   help="POD modes of the log profile (default: 99.99 %% energy; gp 4)")
    p.add_argument("--options", metavar="JSON",
                   help='estimator parameters, e.g. \'{"n_members": 8}\'')
    p.set_defaults(func=_run)
