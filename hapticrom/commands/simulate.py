"""``hapticrom simulate SCENE``: solve one scene with the reference FE solver."""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

from hapticrom.outputs import atomic_path, check_output_file

_OUTPUTS = ("json", "vtk", "plot")


def register(subparsers: Any) -> None:
    """Add the ``simulate`` sub-parser."""
    p = subparsers.add_parser("simulate", help="solve a scene with the reference FE solver")
    p.add_argument("scene", help="scene TOML file (see examples/)")
    p.add_argument("--json", metavar="OUT", help="write surface amplitudes and meta as JSON")
    p.add_argument("--vtk", metavar="OUT", help="write the field for ParaView (.vtu)")
    p.add_argument("--plot", metavar="OUT", help="write a PNG of amplitude against radius")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Solve, print the summary, write the requested outputs (each atomically)."""
    from fem import simulate
    from fem.scene import load_scene

    for opt in _OUTPUTS:
        if getattr(args, opt) is not None:
            check_output_file(f"--{opt}", getattr(args, opt))
    result = simulate(load_scene(args.scene))
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
    for opt in _OUTPUTS:
        if getattr(args, opt):
            print(f"wrote {getattr(args, opt)}")
    return 0
