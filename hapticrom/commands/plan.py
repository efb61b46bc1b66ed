"""``hapticrom plan LAYOUT.toml``: lay out an array on the shipped surrogate.

    hapticrom plan examples/forearm-layout.toml --out out/plan.json --plot out/plan.png
    hapticrom plan examples/forearm-layout.toml --verify     # re-solve the winner with FE

``--verify`` builds the winning design's scene exactly as the model's training data did (the
dataset's own parameter space maps model inputs to a scene, ``Space.resolve``; inputs the
model does not take keep the space's centre values, as the fixed ones do), solves it with the
FE solver (``surrogate.data.worker.run_sample``, the dataset's mesh settings) and compares
centre and edge amplitude, and the pitch each profile implies under the same criterion. Its
verdict uses the plan's own criterion: the FE criterion load at the planned pitch above 1 is a
failure, printed with the pitch the FE needs.

Exit codes: 0 a plan (and, with ``--verify``, the FE confirms it); 1 no design meets the
criterion (or none is playable); 2 bad input, nothing written; 3 ``--verify``: the FE
refutes the plan (criterion load above 1 at the planned pitch, or the unit not felt); the plan
is still written, with the verdict under ``verify``.

``--out`` stores the model paths relative to the plan file (:mod:`planner.paths`), so the plan
plays from any directory.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

import numpy as np

from hapticrom.outputs import atomic_path, check_output_file

__all__ = ["EXIT_VERIFY_FAILED", "register"]

EXIT_VERIFY_FAILED = 3  # --verify: the FE solve refutes the plan


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
    from planner import load_layout, plan_as_record, plan_layout, write_plan_plot
    from planner.paths import relative_plan_models
    from planner.plan_record import PlanRecord

    for opt in ("out", "plot"):
        if getattr(args, opt):
            check_output_file(f"--{opt}", getattr(args, opt), args.overwrite)
    req, tissue = load_layout(args.layout), None
    if args.tissue:
        from planner.tissue import apply_tissue, load_tissue

        tissue = load_tissue(args.tissue)
        req = apply_tissue(req, tissue)
    plan = plan_layout(req)
    try:
        verify = _verify(plan) if args.verify and plan.best is not None else None
    except RuntimeError as err:  # the FE solve itself failed: said, no traceback, nothing written
        print(f"hapticrom plan: failed: {err}", file=sys.stderr)
        return 1
    _print_plan(plan)
    spread = _print_tissue(plan, tissue) if tissue is not None else None
    if verify is not None:
        _print_verify(verify)
    if args.out:
        doc = relative_plan_models(plan_as_record(plan).to_dict(), args.out)
        record = PlanRecord(**doc, verify=verify if args.verify else None,
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
    return EXIT_VERIFY_FAILED if verify is not None and not verify["holds"] else 0


def _dataset_path(model: str) -> Path:
    """The model's training dataset (the card's path, relative to the working directory or
    to the repository holding ``models/NAME``)."""
    from surrogate.runtime.card import read_card

    card = read_card(model)
    rel = Path(card["training_data"][0]["path"])
    for base in (Path.cwd(), Path(model).resolve().parents[1]):
        if (base / rel).is_dir():
            return base / rel
    raise FileNotFoundError(f"--verify: the model's training dataset {str(rel)!r} was not found "
                            "(its parameter space builds the FE scene)")


def _verify(plan: Any) -> dict[str, Any]:
    """FE re-solve of the chosen design; surrogate vs FE amplitudes and implied pitches, and
    the verdict on the plan's own criterion at the planned pitch."""
    from planner.crosstalk import UnitField
    from planner.optimise import is_felt, smallest_pitch, worst_load
    from surrogate.data.store import Store
    from surrogate.data.worker import run_sample

    req, best = plan.request, plan.best
    space = Store.open(_dataset_path(req.model)).space
    row = {**space.center(), **req.site, **best.inputs, "frequency_hz": best.frequency_hz}
    out = run_sample(space.resolve(row))
    if out["status"] != "ok":
        raise RuntimeError(f"--verify: the FE solve failed: {out['error']}")
    fe = UnitField(float(out["center_amplitude_um"]), float(out["edge_radius_mm"]),
                   np.asarray(out["profile_distance_mm"], dtype=float),
                   np.maximum(np.asarray(out["profile_magnitude_um"], dtype=float), 1e-12))
    felt = is_felt(fe.center_um, req, best.frequency_hz)
    fe_pitch = smallest_pitch(fe, req, best.frequency_hz) if felt else None
    load = worst_load(fe, req, best.pitch_mm, best.frequency_hz)
    holds = felt and load <= 1.0
    return {
        "design": best.name, "frequency_hz": best.frequency_hz,
        "edge_radius_mm": round(best.edge_radius_mm, 4), "holds": holds,
        "criterion": req.criterion.kind,
        "surrogate": {"center_um": round(best.center_um, 4),
                      "edge_um": round(best.edge_um, 4),
                      "pitch_mm": round(best.pitch_mm, 3),
                      "pitch_nominal_mm": None if best.pitch_nominal_mm is None else
                      round(best.pitch_nominal_mm, 3), "holds_at": best.holds_at},
        "fe": {"center_um": round(fe.center_um, 4),
               "edge_um": round(float(out["edge_amplitude_um"]), 4),
               "pitch_mm": None if fe_pitch is None else round(fe_pitch, 3),
               "criterion_load_at_plan_pitch": round(load, 4), "felt": felt,
               "profile_end_from_edge_mm": float(fe.distance_mm[-1]),
               "dofs": int(out["dofs"]), "wall_s": round(float(out["wall_s"]), 2)},
        "scene_inputs": {k: row[k] for k in sorted(row)},
    }


def _print_verify(v: dict[str, Any]) -> None:
    s, f = v["surrogate"], v["fe"]
    fe_pitch = "none within the pitch bounds" if f["pitch_mm"] is None else \
        f"{f['pitch_mm']:.2f} mm"
    print(f"verify ({v['design']} at {v['frequency_hz']:g} Hz, FE {f['dofs']} dofs, "
          f"{f['wall_s']:.1f} s):")
    print(f"  center  surrogate {s['center_um']:7.3f} um   FE {f['center_um']:7.3f} um "
          f"({s['center_um'] / f['center_um'] - 1:+.1%})")
    print(f"  edge    surrogate {s['edge_um']:7.3f} um   FE {f['edge_um']:7.3f} um "
          f"({s['edge_um'] / f['edge_um'] - 1:+.1%})")
    print(f"  pitch   planned {s['pitch_mm']:7.2f} mm   FE needs {fe_pitch}")
    load = f["criterion_load_at_plan_pitch"]
    end = f.get("profile_end_from_edge_mm")
    if end is not None and s["pitch_mm"] - v["edge_radius_mm"] > end:
        print(f"  (the FE profile ends {end:g} mm from the unit's edge too: beyond it the FE "
              "side also uses the log-slope extension)")
    if v["holds"]:
        print(f"  verdict: HOLDS on the FE: criterion load {load:.3f} <= 1 at the planned "
              f"pitch {s['pitch_mm']:.2f} mm")
    elif not f["felt"]:
        print("  verdict: FAILS on the FE: the unit's own FE amplitude is below the detection "
              "threshold (it would not be felt)")
    else:
        print(f"  verdict: FAILS on the FE: criterion load {load:.3f} > 1 at the planned pitch "
              f"{s['pitch_mm']:.2f} mm; the FE needs {fe_pitch} (exit {EXIT_VERIFY_FAILED})")


def _print_uncertainty(plan: object) -> None:
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
                   help="re-solve the winning design with the FE solver (about a second) and "
                   "judge the plan on it with the same criterion (written into the plan under "
                   f"'verify'; exit {EXIT_VERIFY_FAILED} when the FE refutes it)")
    p.add_argument("--tissue", metavar="CALIBRATION",
                   help="plan for a person: the tissue of a `hapticrom calibrate` document, its "
                   "posterior uncertainty carried into the pitch (planner.tissue)")
    p.add_argument("--overwrite", action="store_true",
                   help="replace existing output files even if hapticrom did not write them")
    p.set_defaults(func=_run)
