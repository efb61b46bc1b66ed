"""``hapticrom bench accuracy``: measure what accuracy costs in time and write the report."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from hapticrom.outputs import atomic_path, check_output_file

DEFAULT_OUT = "docs/accuracy-vs-time.md"


def register(subparsers: Any) -> None:
    """Add the ``bench`` sub-parser (one study for now: ``accuracy``)."""
    p = subparsers.add_parser("bench", help="measure speed against accuracy on this machine")
    sub = p.add_subparsers(dest="bench", required=True, metavar="STUDY")
    a = sub.add_parser("accuracy", help="error against time per answer for every way to get "
                       "an answer (FE levels and orders, transient, effects, GP, NN, ONNX), "
                       "learning curves and the effects audit; the shipped sweep models, "
                       "nn-default and an MLP peer over the whole band on the sweep test set "
                       "against the FE sweep; writes a Markdown report and a log-log Pareto "
                       "plot beside it (same name, .png)")
    a.add_argument("--quick", action="store_true",
                   help="3 designs, 2 mesh levels, tiny learning curves, 32 sweep test "
                   "designs and an MLP peer on 256 designs (about a minute)")
    a.add_argument("--out", default=DEFAULT_OUT, metavar="FILE.md",
                   help=f"report file (default: {DEFAULT_OUT}); the plot goes to FILE.png")
    a.add_argument("--overwrite", action="store_true",
                   help="replace existing output files even if hapticrom did not write them")
    a.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Run the study, then write the report and the plot (each atomically)."""
    out = Path(args.out)
    if out.suffix != ".md":
        raise ValueError(f"--out {args.out}: must name a .md file (the plot goes beside it)")
    png = out.with_suffix(".png")
    check_output_file("--out", out, args.overwrite)
    check_output_file("--out", png, args.overwrite)

    # lazy: a command's own library loads when it runs (`hapticrom --help`: 0.4 s)
    from studies.accuracy import run_study
    from studies.accuracy.report import render, write_plot

    res = run_study(quick=args.quick, log=lambda m: print(m, file=sys.stderr, flush=True))
    command = "hapticrom bench accuracy" + (" --quick" if args.quick else "") + \
        (f" --out {args.out}" if args.out != DEFAULT_OUT else "")
    text = render(res, png.name, command)
    image = write_plot(res)
    with atomic_path(png) as tmp:
        tmp.write_bytes(image)
    with atomic_path(out) as tmp:
        tmp.write_text(text)
    print(f"wrote {out} and {png}")
    return 0
