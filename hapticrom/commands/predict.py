"""``hapticrom predict``: evaluate a registered model (the run-time predictor).

    hapticrom predict models/nn-default --set orientation=forward --set n_rings=2 ...
    hapticrom predict --csv designs.csv --json out.json [--extrapolate]   # the default model

A CSV has a header naming every input; ``--set`` gives one design point. Only numpy and
onnxruntime are loaded.
"""

from __future__ import annotations

import argparse
import csv
import json
from typing import Any

import numpy as np

from hapticrom.documents import predict_document
from hapticrom.outputs import atomic_path, check_output_file

__all__ = ["register"]


def _points(args: argparse.Namespace, names: tuple[str, ...]) -> dict[str, np.ndarray]:
    if bool(args.set) == bool(args.csv):
        raise ValueError("give either --set NAME=VALUE ... or --csv FILE")
    if args.csv:
        with open(args.csv, newline="") as f:
            rows = list(csv.DictReader(f))
        if not rows:
            raise ValueError(f"--csv {args.csv}: no rows")
        return {k: np.array([_value(r[k]) for r in rows]) for k in rows[0]}
    point: dict[str, Any] = {}
    for item in args.set:
        name, sep, value = item.partition("=")
        if not sep:
            raise ValueError(f"--set {item!r}: expected NAME=VALUE (inputs: {', '.join(names)})")
        point[name.strip()] = np.array([_value(value.strip())])
    return point


def _value(text: str) -> Any:
    try:
        return float(text)
    except ValueError:
        return text


def _run(args: argparse.Namespace) -> int:
    # lazy: a command's own library loads when it runs (`hapticrom --help`: 0.4 s)
    from surrogate.runtime import load_predictor
    from surrogate.runtime.defaults import default_model

    if args.json:
        check_output_file("--json", args.json, args.overwrite)
    if args.model is None:
        args.model = default_model("harmonic")
        print(f"model {args.model} (the default harmonic model)")
    p = load_predictor(args.model)
    points = _points(args, p.input_names)
    out = p.predict(points, extrapolate=args.extrapolate)
    n = len(out["center_amplitude_um"])
    for i in range(n):
        flag = " (extrapolated)" if args.extrapolate and out["extrapolated"][i] else ""
        print(f"[{i}] centre (unit face) magn. {out['center_amplitude_um'][i]:.4g} um, edge magn. "
              f"{out['edge_amplitude_um'][i]:.4g} um at r = {out['edge_radius_mm'][i]:g} mm, "
              f"normalized edge {out['normalized_edge'][i]:.4g} "
              f"(log std {out['center_amplitude_um_log_std'][i]:.2g}){flag}")
    if args.json:
        doc = predict_document(args.model, p.card, points, out, p.profile_distance_mm)
        with atomic_path(args.json) as tmp:
            tmp.write_text(json.dumps(doc, indent=1) + "\n")
        print(f"wrote {args.json}")
    return 0


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``predict`` subcommand."""
    p = subparsers.add_parser("predict", help="predict amplitudes with a registered model")
    p.add_argument("model", nargs="?", default=None,
                   help="model directory (models/NAME; default: the default harmonic model, "
                   "nn-sweep when installed, else nn-default)")
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                   help="one input value (repeat for every input)")
    p.add_argument("--csv", metavar="FILE", help="design points, one per row, header = inputs")
    p.add_argument("--extrapolate", action="store_true",
                   help="allow inputs outside the trained range (flagged in the output)")
    p.add_argument("--json", metavar="OUT", help="write every output as JSON (schema: "
                   "docs/output-schema.md)")
    p.add_argument("--overwrite", action="store_true",
                   help="replace existing output files even if hapticrom did not write them")
    p.set_defaults(func=_run)
