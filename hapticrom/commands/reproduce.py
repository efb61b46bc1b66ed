"""``hapticrom reproduce``: re-run the studies of Guo et al. 2025 and write the report."""

from __future__ import annotations

import argparse
from typing import Any


def register(subparsers: Any) -> None:
    """Add the ``reproduce`` sub-parser."""
    p = subparsers.add_parser("reproduce", help="re-run the paper's studies and write a report")
    p.add_argument("--out", default="reports/reproduce", metavar="DIR",
                   help="report directory (created; a directory written by an earlier "
                   "reproduce is replaced as a whole, any other non-empty one is refused; "
                   "default: reports/reproduce)")
    p.add_argument("--workers", type=int, metavar="N",
                   help="worker processes (default: every core)")
    p.add_argument("--quick", action="store_true", help="a reduced set of cases (for tests)")
    p.add_argument("--quiet", action="store_true", help="no progress bar on stderr (it is "
                   "shown only on a terminal anyway)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Run the study into ``--out``."""
    # lazy: a command's own library loads when it runs (`hapticrom --help`: 0.4 s)
    from studies.guo2025 import reproduce

    reproduce(args.out, workers=args.workers, quick=args.quick, progress=not args.quiet)
    return 0
