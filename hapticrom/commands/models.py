"""``hapticrom models list|show``: the model registry.

    hapticrom models list [--root models]
    hapticrom models show models/default-nn
"""

from __future__ import annotations

import argparse
import json

__all__ = ["register"]


def _list(args: argparse.Namespace) -> int:
    from surrogate.registry import list_models

    rows = list_models(args.root)
    if not rows:
        print(f"no models under {args.root}")
    for r in rows:
        status = f"ok  {r['headline']}" if r["status"] == "ok" else r["status"]
        print(f"{r['name']:24s} {r.get('kind') or '-':4s} {r.get('created') or '-':26s} "
              f"{status}")
    return 0 if all(r["status"] == "ok" for r in rows) else 2  # a broken model: bad input


def _show(args: argparse.Namespace) -> int:
    from surrogate.registry import show_model

    card = show_model(args.model)
    print(json.dumps(card, indent=1))
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
