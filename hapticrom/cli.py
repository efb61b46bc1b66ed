"""The ``hapticrom`` command line: parses, calls the library, prints.

Exit codes: 0 success, 2 bad input (the message names the field and the allowed range), 1 an
unexpected failure. Outputs are written only after the work succeeded, each through a temporary
file renamed into place, so an error never leaves a half-written file.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence
from pathlib import Path

from .outputs import atomic_path


def _simulate(args: argparse.Namespace) -> int:
    from fem.scene import load_scene
    from fem.simulate import simulate

    for opt in ("json", "vtk", "plot"):
        out = getattr(args, opt)
        if out is not None and not Path(out).resolve().parent.is_dir():
            raise ValueError(f"--{opt} {out}: the directory {Path(out).parent} does not exist")
    scene = load_scene(args.scene)
    result = simulate(scene)
    print(result.summary())
    if args.json:
        with atomic_path(args.json) as tmp:
            tmp.write_text(json.dumps(result.to_dict(), indent=1) + "\n")
    if args.vtk:
        from fem.results import write_vtk

        with atomic_path(args.vtk) as tmp:
            write_vtk(str(tmp), result.domain, result.nodal)
    if args.plot:
        from fem.results import write_plot

        r_mm, U = result.surface_curve()
        with atomic_path(args.plot) as tmp:
            write_plot(str(tmp), r_mm, U, Path(args.scene).name, result.edge_mm)
    for opt in ("json", "vtk", "plot"):
        if getattr(args, opt):
            print(f"wrote {getattr(args, opt)}")
    return 0


def _reproduce(args: argparse.Namespace) -> int:
    from studies.guo2025 import reproduce

    reproduce(args.out, workers=args.workers, quick=args.quick)
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="hapticrom",
        description="Reduced-order surrogate modelling of wearable vibrotactile arrays.")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    sim = sub.add_parser("simulate", help="solve a scene with the reference FE solver")
    sim.add_argument("scene", help="scene TOML file (see examples/)")
    sim.add_argument("--json", metavar="OUT", help="write surface amplitudes and meta as JSON")
    sim.add_argument("--vtk", metavar="OUT", help="write the field for ParaView (.vtu)")
    sim.add_argument("--plot", metavar="OUT", help="write a PNG of amplitude against radius")
    sim.set_defaults(func=_simulate)

    rep = sub.add_parser("reproduce", help="re-run the paper's studies and write a report")
    rep.add_argument("--out", default="reports/reproduce", metavar="DIR",
                     help="report directory, replaced as a whole (default: reports/reproduce)")
    rep.add_argument("--workers", type=int, metavar="N",
                     help="worker processes (default: every core)")
    rep.add_argument("--quick", action="store_true", help="a reduced set of cases (for tests)")
    rep.set_defaults(func=_reproduce)

    try:
        from surrogate import cli as surrogate_cli
    except ImportError:  # the datasets extra is optional
        surrogate_cli = None
    if surrogate_cli is not None:
        surrogate_cli.register(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; returns the exit code."""
    args = build_parser().parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except (ValueError, FloatingPointError) as exc:  # bad input, or an ill-posed model from it
        print(f"hapticrom: error: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:  # unreadable input file, unwritable output
        print(f"hapticrom: error: {exc.filename}: {exc.strerror}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
