"""``hapticrom simulate SCENE``: solve one scene with the reference FE solver."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

from hapticrom.outputs import atomic_path, check_output_file
from hapticrom.progress import progress_bar

_OUTPUTS = ("json", "vtk", "plot")


def register(subparsers: Any) -> None:
    """Add the ``simulate`` sub-parser."""
    p = subparsers.add_parser("simulate", help="solve a scene with the reference FE solver")
    p.add_argument("scene", help="scene TOML file (see examples/)")
    p.add_argument("--json", metavar="OUT", help="write surface amplitudes and meta as JSON")
    p.add_argument("--vtk", metavar="OUT", help="write the field for ParaView (.vtu)")
    p.add_argument("--plot", metavar="OUT", help="write a PNG of amplitude against radius")
    p.add_argument("--max-unknowns", type=_unknowns, default=None, metavar="N",
                   help="refuse scenes estimated above N unknowns before solving (default "
                   "1e6, sized for 24 GB; 'inf' to disable)")
    p.add_argument("--quiet", action="store_true", help="no progress bar on stderr")
    p.add_argument("--overwrite", action="store_true",
                   help="replace existing output files even if hapticrom did not write them")
    p.set_defaults(func=run)


def _unknowns(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not value >= 1000:
        raise argparse.ArgumentTypeError(f"{value:g} is out of range: allowed >= 1000 or inf")
    return value


def run(args: argparse.Namespace) -> int:
    """Solve, print the summary, write the requested outputs (each atomically)."""
    # lazy: a command's own library loads when it runs (`hapticrom --help`: 0.4 s)
    from fem import simulate
    from fem.scene import load_scene

    for opt in _OUTPUTS:
        if getattr(args, opt) is not None:
            check_output_file(f"--{opt}", getattr(args, opt), args.overwrite)
    # lazy: a command's own library loads when it runs (`hapticrom --help`: 0.4 s)
    from fem.cost import DEFAULT_MAX_UNKNOWNS, check_cost

    limit = DEFAULT_MAX_UNKNOWNS if args.max_unknowns is None else args.max_unknowns
    scene = load_scene(args.scene)
    if scene.analysis.kind == "sweep" and args.vtk is not None:
        raise ValueError("--vtk writes one solution field; a sweep has one per "
                         "frequency: use --json (complex values at every frequency) or "
                         "--plot, or a harmonic scene at the frequency of interest")
    est = check_cost(scene, limit)
    if est.seconds > 30 and not args.quiet:  # say so before a long run starts
        print(f"hapticrom simulate: about {est.unknowns:.3g} unknowns, ~{est.memory_gb:.2g} GB, "
              f"~{est.seconds / 60:.1f} min (estimate)", file=sys.stderr, flush=True)
    name = Path(args.scene).name
    with progress_bar(scene.analysis.kind == "transient" and not args.quiet,
                      "time steps", name) as report:
        result = simulate(scene, max_unknowns=limit, progress=report)
    print(result.summary(name))
    if args.json:
        with atomic_path(args.json) as tmp:
            tmp.write_text(json.dumps(result.to_dict(name), indent=1) + "\n")
    if args.vtk:
        # lazy: a command's own library loads when it runs (`hapticrom --help`: 0.4 s)
        from fem.results import write_vtk

        with atomic_path(args.vtk) as tmp:
            write_vtk(str(tmp), result.domain, result.nodal)
    if args.plot:
        # lazy: a command's own library loads when it runs (`hapticrom --help`: 0.4 s)
        from fem.plots import plot_result
        from fem.sweep_output import plot_sweep

        plot = plot_sweep if scene.analysis.kind == "sweep" else plot_result
        with atomic_path(args.plot) as tmp:
            plot(str(tmp), result, name)
    for opt in _OUTPUTS:
        if getattr(args, opt):
            print(f"wrote {getattr(args, opt)}")
    return 0
