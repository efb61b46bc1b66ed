"""``hapticrom plan LAYOUT.toml``: lay out an array on the shipped surrogate.

    hapticrom plan examples/forearm-layout.toml --out out/plan.json --plot out/plan.png
    hapticrom plan examples/forearm-layout.toml --verify     # re-solve the winner with FE

``--verify`` builds the winning design's scene exactly as the model's training data did (the
dataset's own parameter space maps model inputs to a scene, ``Space.resolve``; inputs the
model does not take keep the space's centre values, as the fixed ones do), solves it with the
FE solver (``surrogate.data.worker.run_sample``, the dataset's mesh settings) and compares
centre and edge amplitude, and the pitch each profile implies under the same criterion.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

from hapticrom.outputs import atomic_path, check_output_file

__all__ = ["register"]


def _run(args: argparse.Namespace) -> int:
    from planner import load_layout, plan_layout, plan_to_dict, write_plan_plot
    from planner.plan_record import seal_plan

    for opt in ("out", "plot"):
        if getattr(args, opt):
            check_output_file(f"--{opt}", getattr(args, opt))
    plan = plan_layout(load_layout(args.layout))
    verify = _verify(plan) if args.verify and plan.best is not None else None
    req = plan.request
    crit = req.criterion
    limit = (f"leakage <= {crit.max_ratio:g} of own amplitude" if crit.kind == "ratio" else
             f"leakage below the detection threshold ({crit.threshold.source}), drive level "
             f"{crit.drive_level:g}")
    shape = (f"{req.cols} free sites" if req.grid == "free" else
             f"{req.rows} x {req.cols} {req.grid} array")
    if req.objective == "max_sites":
        shape = (f"most {req.grid} sites in {req.region_mm[0]:g} x {req.region_mm[1]:g} mm "
                 f"(chosen: {req.rows} x {req.cols})")
    print(f"{shape}, {limit} ({crit.superposition}), model "
          f"{req.model}")
    for family in sorted({c.family for c in plan.candidates if c.family != c.name}):
        drawn = [c for c in plan.candidates if c.family == family]
        n_ok = sum(c.pitch_mm is not None for c in drawn)
        print(f"  {family}: {len(drawn)} candidates drawn from the model's range (designs x "
              f"frequencies), {n_ok} feasible; its best is listed")
    for c in plan.shown():
        pitch = "infeasible" if c.pitch_mm is None else (
            f"nearest sites {c.pitch_mm:6.2f} mm, worst load {c.load:.3f} (margin "
            f"{1 / c.load if c.load else float('inf'):.3f})" if req.grid == "free" else
            f"pitch {c.pitch_mm:6.2f} mm (edge to edge {c.edge_to_edge_mm:5.2f} mm; with the "
            f"model's 95 % bounds {c.pitch_95_mm or float('nan'):6.2f} mm)")
        flag = (" [extrapolated]" if c.extrapolated else "") + (
            "" if c.felt else " [own amplitude below the detection threshold]")
        if c.shape is not None and c.pitch_mm is not None:
            pitch = f"{c.shape[0]} x {c.shape[1]} sites, " + pitch
        print(f"  {c.name:22s} {c.frequency_hz:6.0f} Hz  center {c.center_um:6.2f} um  "
              f"{pitch}{flag}")
    if plan.best is None:
        print("no design meets the criterion within the pitch bounds")
    else:
        print(f"best: {plan.best.name} at {plan.best.frequency_hz:g} Hz, pitch "
              f"{plan.best.pitch_mm:.2f} mm, margin {plan.margin:.3f}")
        if plan.best.family != plan.best.name:
            print("  inputs: " + ", ".join(f"{k} = {v:.4g}" if isinstance(v, float) else
                                           f"{k} = {v}" for k, v in plan.best.inputs.items()))
        _print_uncertainty(plan)
        _print_timing(plan.timing)
    if verify is not None:
        _print_verify(verify)
    if args.out:
        doc = plan_to_dict(plan)
        if args.verify:
            doc["verify"] = verify
        with atomic_path(args.out) as tmp:
            tmp.write_text(json.dumps(seal_plan(doc), indent=1) + "\n")
        print(f"wrote {args.out}")
    if args.plot:
        with atomic_path(args.plot) as tmp:
            write_plan_plot(plan, tmp)
        print(f"wrote {args.plot}")
    return 0 if plan.best is not None else 1


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
    """FE re-solve of the chosen design; surrogate vs FE amplitudes and implied pitches."""
    import numpy as np

    from planner.crosstalk import UnitField
    from planner.optimise import smallest_pitch, worst_load
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
    fe_pitch = smallest_pitch(fe, req, best.frequency_hz)
    return {
        "design": best.name, "frequency_hz": best.frequency_hz,
        "surrogate": {"center_um": round(best.center_um, 4),
                      "edge_um": round(best.edge_um, 4),
                      "pitch_mm": round(best.pitch_mm, 3)},
        "fe": {"center_um": round(fe.center_um, 4),
               "edge_um": round(float(out["edge_amplitude_um"]), 4),
               "pitch_mm": None if fe_pitch is None else round(fe_pitch, 3),
               "criterion_load_at_plan_pitch": round(
                   worst_load(fe, req, best.pitch_mm, best.frequency_hz), 4),
               "dofs": int(out["dofs"]), "wall_s": round(float(out["wall_s"]), 2)},
        "scene_inputs": {k: row[k] for k in sorted(row)},
    }


def _print_verify(v: dict[str, Any]) -> None:
    s, f = v["surrogate"], v["fe"]
    fe_pitch = "infeasible" if f["pitch_mm"] is None else f"{f['pitch_mm']:.2f} mm"
    print(f"verify ({v['design']} at {v['frequency_hz']:g} Hz, FE {f['dofs']} dofs, "
          f"{f['wall_s']:.1f} s):")
    print(f"  center  surrogate {s['center_um']:7.3f} um   FE {f['center_um']:7.3f} um "
          f"({s['center_um'] / f['center_um'] - 1:+.1%})")
    print(f"  edge    surrogate {s['edge_um']:7.3f} um   FE {f['edge_um']:7.3f} um "
          f"({s['edge_um'] / f['edge_um'] - 1:+.1%})")
    print(f"  pitch   surrogate {s['pitch_mm']:7.2f} mm   FE {fe_pitch} (FE criterion load at "
          f"the planned pitch {f['criterion_load_at_plan_pitch']:.3f}; <= 1: it holds)")


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
    p.add_argument("--verify", action="store_true",
                   help="re-solve the winning design with the FE solver (about a second) and "
                   "compare it with the surrogate (written into the plan under 'verify')")
    p.set_defaults(func=_run)
