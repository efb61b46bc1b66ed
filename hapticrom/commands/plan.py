"""``hapticrom plan LAYOUT.toml``: lay out an array on the shipped surrogate.

    hapticrom plan examples/forearm-layout.toml --out out/plan.json --plot out/plan.png
    hapticrom plan examples/forearm-layout.toml --verify     # FE re-plan of the top 5
    hapticrom plan examples/forearm-layout.toml --verify-top 3

``--verify`` re-solves the top K candidates of the surrogate's ranking with the FE solver, each
scene built exactly as the model's training data was (:mod:`hapticrom.commands.plan_verify`),
judges and re-ranks them on the FE fields with the plan's own criterion
(:mod:`planner.verify`) and reports whether the FE's winner (design and frequency) and its
pitch agree with the surrogate's.

Exit codes: 0 a plan (and, with ``--verify``, the FE confirms it); 1 no design meets the
criterion (or none is playable); 2 bad input, nothing written (``--verify-top`` outside 1-32
too); 3 ``--verify``: the FE refutes the plan (its winner among the top K differs, or the
winner's pitch is more than 2 % off the FE's, or the criterion fails at the FE field at the
planned pitch); the plan is still written, with the verdict under ``verify``.

``--out`` stores the model paths relative to the plan file (:mod:`planner.paths`), so the plan
plays from any directory.
"""

from __future__ import annotations

import argparse
import json
import sys
from typing import Any

from hapticrom.commands.plan_verify import EXIT_VERIFY_FAILED, print_verify, top_k, verify_plan
from hapticrom.outputs import atomic_path, check_output_file

__all__ = ["EXIT_VERIFY_FAILED", "register"]


def _header(plan: Any) -> str:
    req = plan.request
    crit = req.criterion
    limit = (f"leakage <= {crit.max_ratio:g} of own amplitude" if crit.kind == "ratio" else
             f"leakage below the detection threshold (the "
             f"{crit.threshold.site or crit.threshold.source} curve), drive level "
             f"{crit.drive_level:g}")
    shape = (f"{req.cols} free sites" if req.grid == "free" else
             f"{req.rows} x {req.cols} {req.grid} array")
    if req.objective == "max_sites":
        shape = (f"most {req.grid} sites in {req.region_mm[0]:g} x {req.region_mm[1]:g} mm "
                 f"(chosen: {req.rows} x {req.cols})")
    basis = ("ranked on the pitch that holds at the model's 95 % bounds"
             if crit.holds_at == "bounds_95" else "ranked on the nominal prediction")
    return f"{shape}, {limit} ({crit.superposition}), {basis}, model {req.model}"


def _candidate_line(c: Any, free: bool) -> str:
    if c.pitch_mm is None:
        pitch = "infeasible" + ("" if c.pitch_nominal_mm is None else
                                f" at the 95 % bounds (nominal {c.pitch_nominal_mm:.2f} mm)")
    elif free:
        pitch = (f"nearest sites {c.pitch_mm:6.2f} mm, worst load {c.load:.3f} (margin "
                 f"{1 / c.load if c.load else float('inf'):.3f})")
    else:
        nominal = ("n/a" if c.pitch_nominal_mm is None else f"{c.pitch_nominal_mm:6.2f}")
        pitch = (f"pitch {c.pitch_mm:6.2f} mm (edge to edge {c.edge_to_edge_mm:5.2f} mm; "
                 f"nominal {nominal} mm, at the 95 % bounds {c.pitch_95_mm or float('nan'):6.2f}"
                 " mm)")
    flags = []
    if c.extrapolations or c.extrapolated:
        flags.append("extrapolated: " + ", ".join(x.field for x in c.extrapolations)
                     if c.extrapolations else "extrapolated")
    if c.pitch_mm is not None and c.beyond_profile >= 0.01:
        flags.append(f"{c.beyond_profile:.0%} of the leakage beyond the profile")
    if not c.felt:
        flags.append("own amplitude below the detection threshold")
    if c.shape is not None and c.pitch_mm is not None:
        pitch = f"{c.shape[0]} x {c.shape[1]} sites, " + pitch
    flag = "".join(f" [{f}]" for f in flags)
    return (f"  {c.name:22s} {c.frequency_hz:6.0f} Hz  center {c.center_um:6.2f} um  "
            f"{pitch}{flag}")


def _print_plan(plan: Any) -> None:
    # lazy: a command's own library loads when it runs (`hapticrom --help`: 0.4 s)
    from planner.summary import summary_lines, validity

    print(_header(plan))
    for w in plan.request.criterion.warnings():
        print(f"warning: {w}")
    for d in plan.dropped:
        print(f"  dropped {d['frequency_hz']:g} Hz: {d['reason']}")
    for family in sorted({c.family for c in plan.candidates if c.family != c.name}):
        drawn = [c for c in plan.candidates if c.family == family]
        n_ok = sum(c.pitch_mm is not None for c in drawn)
        print(f"  {family}: {len(drawn)} candidates drawn from the plan's domain (designs x "
              f"frequencies), {n_ok} feasible; its best is listed")
    free = plan.request.grid == "free"
    for c in plan.shown():
        print(_candidate_line(c, free))
    for u in plan.unplayable:
        print(f"  not playable: {u['name']} at {u['frequency_hz']:g} Hz ({u['reason']})")
    if plan.best is None:
        print("no playable design meets the criterion within the pitch bounds")
        return
    best = plan.best
    print(f"best: {best.name} at {best.frequency_hz:g} Hz, pitch {best.pitch_mm:.2f} mm, "
          f"margin {plan.margin:.3f}")
    if best.family != best.name:
        print("  inputs: " + ", ".join(f"{k} = {v:.4g}" if isinstance(v, float) else
                                       f"{k} = {v}" for k, v in best.inputs.items()))
    _print_uncertainty(plan)
    _print_timing(plan.timing)
    if not plan.request.timing.enabled:
        print("  timing: not computed ([timing] enabled = false); `hapticrom play` needs it")
    lines = summary_lines(validity(plan))
    print("  extrapolation: " + ("none (every value inside the plan's domain, the leakage "
                                 "inside the model's profile)" if not lines else
                                 f"{len(lines)} flag(s)"))
    for line in lines:
        print(f"    - {line}")


def _run(args: argparse.Namespace) -> int:
    # lazy: a command's own library loads when it runs (`hapticrom --help`: 0.4 s)
    from planner import load_layout, plan_as_record, plan_layout, write_plan_plot
    from planner.paths import relative_plan_models
    from planner.plan_record import PlanRecord
    from planner.verify import DEFAULT_TOP

    for opt in ("out", "plot"):
        if getattr(args, opt):
            check_output_file(f"--{opt}", getattr(args, opt), args.overwrite)
    req, tissue = load_layout(args.layout), None
    if args.tissue:
        # lazy: a command's own library loads when it runs (`hapticrom --help`: 0.4 s)
        from planner.tissue import apply_tissue, load_tissue

        tissue = load_tissue(args.tissue)
        req = apply_tissue(req, tissue)
    plan = plan_layout(req)
    check = args.verify or args.verify_top is not None
    try:
        verify = (verify_plan(plan, args.verify_top or DEFAULT_TOP)
                  if check and plan.best is not None else None)
    except RuntimeError as err:  # the FE solve itself failed: said, no traceback, nothing written
        print(f"hapticrom plan: failed: {err}", file=sys.stderr)
        return 1
    _print_plan(plan)
    spread = _print_tissue(plan, tissue) if tissue is not None else None
    if verify is not None:
        print_verify(verify)
    if args.out:
        doc = relative_plan_models(plan_as_record(plan).to_dict(), args.out)
        record = PlanRecord(**doc, verify=verify,
                            tissue=spread if tissue is not None else None)
        with atomic_path(args.out) as tmp:
            tmp.write_text(json.dumps(record.to_json(), indent=1) + "\n")
        print(f"wrote {args.out}")
    if args.plot:
        with atomic_path(args.plot) as tmp:
            write_plan_plot(plan, tmp)
        print(f"wrote {args.plot}")
    if plan.best is None:
        return 1
    return EXIT_VERIFY_FAILED if verify is not None and not verify["confirmed"] else 0


def _print_uncertainty(plan: object) -> None:
    # lazy: a command's own library loads when it runs (`hapticrom --help`: 0.4 s)
    from planner.report import uncertainty

    u = uncertainty(plan)
    lo, hi = u["center_95_um"]
    m95 = "inf" if u["margin_95"] is None else f"{u['margin_95']:.3f}"
    print(f"  surrogate at the chosen design: center 95 % [{lo:.2f}, {hi:.2f}] um, profile "
          f"log-std up to {u['profile_log_std_max']:.3f}; margin at the 95 % bounds {m95}"
          f"{'' if u['criterion_holds_at_95'] else ' (criterion NOT met at the bounds)'}"
          f"{' [extrapolated]' if u['extrapolated'] else ''}")


def _print_tissue(plan: Any, tissue: Any) -> dict[str, Any] | None:
    """The calibrated tissue and the chosen design's pitch over its posterior draws."""
    # lazy: a command's own library loads when it runs (`hapticrom --help`: 0.4 s)
    from planner.tissue import posterior_pitch

    print(f"  tissue from {tissue.path}: " + ", ".join(
        f"{k} = {v:.4g}" if isinstance(v, float) else f"{k} = {v}"
        for k, v in tissue.point.items()))
    s = posterior_pitch(plan, tissue)
    if s is None:
        return None

    def mm(x: float | None) -> str:
        return "infeasible" if x is None else f"{x:.2f} mm"

    print(f"  pitch over {s['draws']} posterior draws (prediction): median "
          f"{mm(s['pitch_mm_median'])}, 95 % [{mm(s['pitch_mm_2_5'])}, "
          f"{mm(s['pitch_mm_97_5'])}], at the posterior's 95 % bound {mm(s['pitch_95_mm'])}; "
          f"with the surrogate's 95 % bounds too {mm(s['pitch_95_with_surrogate_mm'])}")
    print(f"  pitch for this person at the posterior's 95 % bound, judged as the plan is "
          f"({s['holds_at']}): {mm(s['pitch_95_for_plan_mm'])} (the plan's "
          f"{s['pitch_mm_at_point_estimate']:.2f} mm is at the posterior mean)")
    return s


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
          f"{timing['min_isi_ms']:.1f} ms"
          + (" [extrapolated: " + ", ".join(timing["extrapolated"]) + "]"
             if timing.get("extrapolated") else ""))


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``plan`` subcommand."""
    p = subparsers.add_parser(
        "plan", help="lay out a haptic array on the surrogate",
        epilog=f"exit codes: 0 ok; 1 no playable design meets the criterion; 2 bad input; "
        f"{EXIT_VERIFY_FAILED} --verify: the FE refutes the plan (written, with the verdict)")
    p.add_argument("layout", help="layout request TOML (see examples/forearm-layout.toml)")
    p.add_argument("--out", metavar="JSON", help="write the plan as JSON (model paths relative "
                   "to it)")
    p.add_argument("--plot", metavar="PNG", help="write the layout and profiles figure")
    p.add_argument("--verify", action="store_true",
                   help="re-solve the surrogate's top candidates with the FE solver (about a "
                   "second each), re-rank them on the FE fields with the same criterion and "
                   "report whether the winner and its pitch agree (written into the plan under "
                   f"'verify'; exit {EXIT_VERIFY_FAILED} when the FE refutes it)")
    p.add_argument("--verify-top", metavar="K", type=top_k, default=None,
                   help="--verify re-solves the top K candidates of the surrogate's ranking "
                   "(integer 1-32, default 5; implies --verify)")
    p.add_argument("--tissue", metavar="CALIBRATION",
                   help="plan for a person: the tissue of a `hapticrom calibrate` document, its "
                   "posterior uncertainty carried into the pitch (planner.tissue)")
    p.add_argument("--overwrite", action="store_true",
                   help="replace existing output files even if hapticrom did not write them")
    p.set_defaults(func=_run)
