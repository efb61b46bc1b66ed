"""``hapticrom design REQUEST.toml``: find the unit that lets the densest array on a site.

    hapticrom design examples/design-forearm.toml --out-dir out/design --seed 0
    hapticrom design examples/design-forearm.toml --out-dir out/design --no-verify
    hapticrom design REQUEST.toml --tissue out/cal.json --out-dir out/person

The search runs on the run-time predictor (:mod:`planner.design`); the best few designs and
the reference units are then re-solved with the FE sweep solver over the drive band
(:mod:`hapticrom.commands.design_verify`, the solve passed to
:func:`planner.design.verify.verify_search`) unless ``--no-verify``.

Outputs in ``--out-dir`` (each written whole or not at all): ``design.json`` (the sealed
record with the search history), ``unit.toml`` (the found unit's scene at its drive frequency,
for ``hapticrom simulate``), ``layout.toml`` (for ``hapticrom plan``) and ``design.png``
(the figure).

Exit codes: 0 a design (confirmed by the FE unless ``--no-verify``); 1 no design in the space
is feasible and perceptible; 2 bad input, nothing written; 3 the FE refutes the winner (the
outputs are still written, with the verdict under ``verify``).
"""

from __future__ import annotations

import argparse
import json
import sys
from dataclasses import replace
from pathlib import Path
from typing import Any

from hapticrom.commands.design_verify import band_solver, unit_scene, unit_space
from hapticrom.commands.plan_verify import EXIT_VERIFY_FAILED
from hapticrom.outputs import atomic_path, check_output_file

__all__ = ["register"]

OUTPUTS = {"record": "design.json", "scene": "unit.toml", "layout": "layout.toml",
           "plot": "design.png"}


def _seed(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not an integer") from None
    if not 0 <= value <= 4294967295:
        raise argparse.ArgumentTypeError(f"{value} is outside 0 to 4294967295")
    return value


def _print_outcome(outcome: Any) -> None:
    lay, s = outcome.layout, outcome.search
    crit = lay.criterion
    print(f"{lay.rows} x {lay.cols} {lay.grid} array, {crit.kind} criterion at "
          f"{crit.holds_at}, frequencies {', '.join(f'{f:g}' for f in lay.frequencies_hz)} Hz, "
          f"model {lay.model}")
    for d in outcome.evaluator.dropped:
        print(f"  dropped {d['frequency_hz']:g} Hz: {d['reason']}")
    print(f"search: {s['optimiser']} (seed {s['seed']}), {s['designs_evaluated']} designs "
          f"evaluated in {s['batches']} batches, {s['wall_s']:.1f} s "
          f"({s['evaluation_wall_s']:.1f} s predicting and judging); "
          f"{len(outcome.ranking)} feasible and felt")
    for r in outcome.references:
        pitch = "infeasible or not felt" if not r.feasible else \
            f"pitch {r.pitch_mm:6.2f} mm at {r.frequency_hz:g} Hz"
        print(f"  reference {r.name:28s} {pitch}, centre {r.center_um:6.2f} um")
    w = outcome.winner
    if w is None:
        print("no design in the space meets the criterion and is felt")
        return
    print(f"best: {w.name} at {w.frequency_hz:g} Hz, pitch {w.pitch_mm:.2f} mm (nominal "
          f"{w.pitch_nominal_mm:.2f} mm), centre {w.center_um:.2f} um (95 % low "
          f"{w.center_low_um:.2f} um, threshold {w.threshold_um:.2f} um)")
    print(f"  extrapolation: {w.beyond_profile:.0%} of the worst site's leakage power comes "
          f"from beyond the model's profile ({outcome.evaluator.profile_end_mm:g} mm from the "
          "edge; log-slope extension)")
    for p in outcome.posterior:
        print(f"  posterior: {p['design']}: pitch at the posterior's 95 % bound "
              f"{p.get('pitch_95_for_plan_mm')} mm (point estimate "
              f"{p['pitch_mm_at_point_estimate']:.2f} mm)")


def _print_verify(v: dict[str, Any]) -> None:
    print(f"FE check ({v['fe_check_wall_s']:.1f} s of sweeps):")
    for d in v["designs"] + v["references"]:
        fe = "none" if d["fe_pitch_mm"] is None else f"{d['fe_pitch_mm']:.2f} mm at " \
            f"{d['fe_frequency_hz']:g} Hz"
        print(f"  {d['design'][:40]:40s} FE pitch {fe}")
    t = v["target"]
    if t["best_reference"] is not None:
        rel = "" if t["rel_diff"] is None else f" ({t['rel_diff']:+.1%})"
        print(f"  winner on the FE {t['winner_fe_pitch_mm']} mm against the best reference "
              f"{t['best_reference']} {t['best_reference_fe_pitch_mm']} mm{rel}: "
              + ("smaller" if t["met"] else "NOT smaller"))
    if v["confirmed"]:
        print(f"verdict: CONFIRMED by the FE (same winner, pitch within {v['tolerance']:.0%}: "
              f"{v['rel_diff']:+.1%}, criterion holds)")
    else:
        print(f"verdict: REFUTED by the FE (exit {EXIT_VERIFY_FAILED}): "
              + "; ".join(v["refuted_because"]))


def _scene_text(outcome: Any) -> str:
    # lazy: a command's own library loads when it runs (`hapticrom --help`: 0.4 s)
    from fem.scene import dump_scene_toml, scene_from_dict

    w = outcome.winner
    scene = unit_scene(unit_space(outcome.layout.model), outcome.layout.site, w.inputs, w.materials,
                       {"kind": "harmonic", "frequency_hz": float(w.frequency_hz)})
    return dump_scene_toml(scene_from_dict(scene))


def _check_out_dir(out: Path, overwrite: bool) -> None:
    """``--out-dir``: a directory to be made in an existing one, or one whose output files
    may be written (checked before any work starts)."""
    if out.exists() and not out.is_dir():
        raise ValueError(f"--out-dir {out}: exists and is not a directory")
    if not out.exists():
        if not out.resolve().parent.is_dir():
            raise ValueError(f"--out-dir {out}: the directory {out.parent} does not exist")
        return
    for key, name in OUTPUTS.items():
        check_output_file(f"--out-dir ({key})", str(out / name), overwrite)


def _write(path: Path, text: str) -> None:
    with atomic_path(path) as tmp:
        tmp.write_text(text)
    print(f"wrote {path}")


def _run(args: argparse.Namespace) -> int:
    # lazy: a command's own library loads when it runs (`hapticrom --help`: 0.4 s)
    from planner.design import design, load_design_request

    out = Path(args.out_dir) if args.out_dir else None
    if out is not None:
        _check_out_dir(out, args.overwrite)
    request = load_design_request(args.request)
    tissue = None
    if args.tissue:
        # lazy: a command's own library loads when it runs (`hapticrom --help`: 0.4 s)
        from planner.tissue import load_tissue

        tissue = load_tissue(args.tissue)
    if args.verify_top is not None:
        request = replace(request, verify_top=args.verify_top)
    outcome = design(request, seed=args.seed, tissue=tissue)
    _print_outcome(outcome)
    verify = None
    if outcome.winner is not None and not args.no_verify:
        # lazy: a command's own library loads when it runs (`hapticrom --help`: 0.4 s)
        from planner.design.verify import verify_search

        try:
            verify = verify_search(outcome.evaluator, outcome.finalists, request.references,
                                   band_solver(outcome.layout.model, outcome.layout.site))
        except RuntimeError as err:
            print(f"hapticrom design: failed: {err}", file=sys.stderr)
            return 1
        _print_verify(verify)
    if out is not None:
        _write_outputs(out, outcome, verify)
    if outcome.winner is None:
        return 1
    return EXIT_VERIFY_FAILED if verify is not None and not verify["confirmed"] else 0


def _write_outputs(out: Path, outcome: Any, verify: dict[str, Any] | None) -> None:
    # lazy: a command's own library loads when it runs (`hapticrom --help`: 0.4 s)
    from planner.design.figure import write_design_plot
    from planner.design.layout_file import layout_toml
    from planner.design.record import design_record

    out.mkdir(parents=True, exist_ok=True)
    written = {k: str(out / v) for k, v in OUTPUTS.items()} if outcome.winner is not None else \
        {"record": str(out / OUTPUTS["record"]), "plot": str(out / OUTPUTS["plot"])}
    texts = {}
    if outcome.winner is not None:  # made before anything is written
        texts["scene"], texts["layout"] = _scene_text(outcome), layout_toml(outcome)
    record = design_record(outcome, verify, {k: Path(v).name for k, v in written.items()})
    texts["record"] = json.dumps(record, indent=1) + "\n"
    for key, text in texts.items():
        _write(Path(written[key]), text)
    with atomic_path(written["plot"]) as tmp:
        write_design_plot(outcome, tmp)
    print(f"wrote {written['plot']}")


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``design`` subcommand."""
    p = subparsers.add_parser(
        "design", help="find the unit that lets the densest array on a site",
        epilog=f"exit codes: 0 ok; 1 no design is feasible and felt; 2 bad input (nothing "
        f"written); {EXIT_VERIFY_FAILED} the FE refutes the winner (outputs written, with the "
        "verdict)")
    p.add_argument("request", help="design request TOML (see examples/design-forearm.toml)")
    p.add_argument("--out-dir", metavar="DIR", help="write design.json, unit.toml, layout.toml "
                   "and design.png there")
    p.add_argument("--seed", type=_seed, default=None,
                   help="the optimiser's seed (default: the request's search.seed)")
    p.add_argument("--tissue", metavar="CALIBRATION",
                   help="design for a person: the tissue of a `hapticrom calibrate` document; "
                   "the finalists re-ranked over its posterior draws")
    p.add_argument("--no-verify", action="store_true",
                   help="skip the FE check of the best designs and the references")
    p.add_argument("--verify-top", metavar="K", type=int, choices=range(1, 9), default=None,
                   help="designs re-solved with the FE (1-8; default: the request's "
                   "verify.top, 3)")
    p.add_argument("--overwrite", action="store_true",
                   help="replace existing output files even if hapticrom did not write them")
    p.set_defaults(func=_run)
