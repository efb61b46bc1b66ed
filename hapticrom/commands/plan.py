"""``hapticrom plan LAYOUT.toml``: lay out an array on the shipped surrogate.

    hapticrom plan examples/forearm-layout.toml --out out/plan.json --plot out/plan.png
"""

from __future__ import annotations

import argparse
import json

from hapticrom.outputs import atomic_path, check_output_file

__all__ = ["register"]


def _run(args: argparse.Namespace) -> int:
    from planner import load_layout, plan_layout, plan_to_dict, write_plan_plot

    for opt in ("out", "plot"):
        if getattr(args, opt):
            check_output_file(f"--{opt}", getattr(args, opt))
    plan = plan_layout(load_layout(args.layout))
    req = plan.request
    crit = req.criterion
    limit = (f"leakage <= {crit.max_ratio:g} of own amplitude" if crit.kind == "ratio" else
             f"leakage below the detection threshold ({crit.threshold.source}), drive level "
             f"{crit.drive_level:g}")
    print(f"{req.rows} x {req.cols} {req.grid} array, {limit} ({crit.superposition}), model "
          f"{req.model}")
    for c in plan.candidates:
        pitch = "infeasible" if c.pitch_mm is None else (
            f"pitch {c.pitch_mm:6.2f} mm (edge to edge {c.edge_to_edge_mm:5.2f} mm; with the "
            f"model's 95 % bounds {c.pitch_95_mm or float('nan'):6.2f} mm)")
        flag = (" [extrapolated]" if c.extrapolated else "") + (
            "" if c.felt else " [own amplitude below the detection threshold]")
        print(f"  {c.name:22s} {c.frequency_hz:6.0f} Hz  center {c.center_um:6.2f} um  "
              f"{pitch}{flag}")
    if plan.best is None:
        print("no design meets the criterion within the pitch bounds")
    else:
        print(f"best: {plan.best.name} at {plan.best.frequency_hz:g} Hz, pitch "
              f"{plan.best.pitch_mm:.2f} mm, margin {plan.margin:.3f}")
        _print_uncertainty(plan)
        _print_timing(plan.timing)
    if args.out:
        with atomic_path(args.out) as tmp:
            tmp.write_text(json.dumps(plan_to_dict(plan), indent=1) + "\n")
        print(f"wrote {args.out}")
    if args.plot:
        with atomic_path(args.plot) as tmp:
            write_plan_plot(plan, tmp)
        print(f"wrote {args.plot}")
    return 0 if plan.best is not None else 1


def _print_uncertainty(plan: object) -> None:
    from planner.report import uncertainty

    u = uncertainty(plan)
    lo, hi = u["center_95_um"]
    m95 = "inf" if u["margin_95"] is None else f"{u['margin_95']:.3f}"
    print(f"  surrogate at the chosen design: center 95 % [{lo:.2f}, {hi:.2f}] um, profile "
          f"log-std up to {u['profile_log_std_max']:.3f}; margin at the 95 % bounds {m95}"
          f"{'' if u['criterion_holds_at_95'] else ' (criterion NOT met at the bounds)'}"
          f"{' [extrapolated]' if u['extrapolated'] else ''}")


def _print_timing(timing: dict | None) -> None:
    if timing is None:
        return
    if timing.get("unavailable"):
        print(f"  timing: unavailable ({timing['unavailable']})")
        return
    print(f"  timing ({timing['model']}): rise {timing['rise_ms']:.1f} ms, decay "
          f"{timing['decay_ms']:.1f} ms, overdrive {timing['overdrive_ms']:.1f} ms at "
          f"{timing['overdrive_voltage_V']:g} V (x{timing['overdrive_level']:.2f}; 90 % in "
          f"{timing['rise_overdrive_ms']:.1f} ms instead of {timing['t90_ms']:.1f}), brake "
          f"{timing['brake_ms']:.1f} ms, shortest inter-stimulus interval "
          f"{timing['min_isi_ms']:.1f} ms")


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``plan`` subcommand."""
    p = subparsers.add_parser("plan", help="lay out a haptic array on the surrogate")
    p.add_argument("layout", help="layout request TOML (see examples/forearm-layout.toml)")
    p.add_argument("--out", metavar="JSON", help="write the plan as JSON")
    p.add_argument("--plot", metavar="PNG", help="write the layout and profiles figure")
    p.set_defaults(func=_run)
