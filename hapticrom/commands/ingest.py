"""``hapticrom ingest FILE --out D``: import external simulation results into a dataset.

A CSV table of parameters and amplitudes, or one amplitude-vs-distance export (ABAQUS .rpt,
COMSOL CSV), validated against the dataset's parameter space. Examples::

    hapticrom ingest results.csv --out datasets/default
    hapticrom ingest job1.rpt --out D --distance-unit mm --amplitude-unit m \\
        --set skin_E_kPa=49 --set fat_thickness_mm=14 ...
"""

from __future__ import annotations

import argparse
from typing import Any


def _column_pair(text: str) -> tuple[int, int]:
    parts = text.split(",")
    try:
        a, b = (int(p) for p in parts)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r}: expected two column indices I,J "
                                         "(0-based), e.g. 0,1") from None
    if a < 0 or b < 0 or a == b:
        raise argparse.ArgumentTypeError(f"{text!r}: need two different indices >= 0")
    return a, b


def register(subparsers: Any) -> None:
    """Add the ``ingest`` sub-parser."""
    p = subparsers.add_parser(
        "ingest", help="import external simulation results (CSV table or ABAQUS/COMSOL "
        "profile)", description="Import a CSV of parameters and amplitudes, or one "
        "amplitude-vs-distance export (ABAQUS/COMSOL), validated against the space.")
    p.add_argument("file", help="table CSV or profile export")
    p.add_argument("--out", required=True, help="dataset directory (created if missing)")
    p.add_argument("--space", help="space TOML (required when --out does not exist yet)")
    p.add_argument("--kind", choices=("auto", "table", "profile"), default="auto",
                   help="auto: a table when the header names amplitude/profile columns")
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                   help="parameter value for all rows (repeatable)")
    p.add_argument("--center-amplitude-um", type=float, help="center amplitude of a profile")
    p.add_argument("--distance-unit", help="unit of profile distances (mm, m, cm, um, in)")
    p.add_argument("--amplitude-unit", help="unit of profile amplitudes (um, nm, mm, m)")
    p.add_argument("--columns", type=_column_pair, default=(0, 1), metavar="I,J",
                   help="profile columns of distance and amplitude (default 0,1)")
    p.add_argument("--source", help="source label (default: the file name)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Ingest a table or a profile, then print what was added."""
    # lazy: a command's own library loads when it runs (`hapticrom --help`: 0.4 s)
    from surrogate.data.ingest import (
        ingest_profile,
        ingest_table,
        looks_like_table,
        parse_assignments,
    )

    values = parse_assignments(args.set)
    kind = args.kind
    if kind == "auto":
        kind = "table" if looks_like_table(args.file) else "profile"
    units = {"distance_unit": args.distance_unit, "amplitude_unit": args.amplitude_unit,
             "columns": args.columns, "source": args.source}
    if kind == "table":
        if args.center_amplitude_um is not None:
            raise ValueError("--center-amplitude-um applies to a profile; a table has a "
                             "center_amplitude_um column")
        rep = ingest_table(args.file, args.out, args.space, values=values, **units)
    else:
        rep = ingest_profile(args.file, args.out, values, args.space,
                             center_amplitude_um=args.center_amplitude_um, **units)
    print(f"{rep.path}: {rep.added} rows added from {rep.source} ({rep.rows_read} read, "
          f"{rep.skipped_existing} already present)")
    return 0
