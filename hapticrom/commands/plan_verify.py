"""``hapticrom plan --verify [--verify-top K]``: the surrogate's top K candidates re-solved with
the FE solver, re-ranked on the FE fields with the plan's own criterion (:mod:`planner.verify`),
and the verdict.

Each candidate's scene is built exactly as the model's training data was: the dataset's own
parameter space maps model inputs to a scene (``Space.resolve_at``: a sweep-trained model's
band becomes one harmonic solve at the candidate's frequency; inputs the model does not take
keep the space's centre values, as the fixed ones do), and
``surrogate.data.worker.run_sample`` solves it with the dataset's mesh settings.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["EXIT_VERIFY_FAILED", "fe_solver", "print_verify", "top_k", "verify_plan"]

EXIT_VERIFY_FAILED = 3  # --verify: the FE solve refutes the plan


def top_k(text: str) -> int:
    """argparse type of ``--verify-top``: an integer in [1, MAX_TOP]."""
    # lazy: a command's own library loads when it runs (`hapticrom --help`: 0.4 s)
    from planner.verify import MAX_TOP

    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not an integer; allowed 1 to "
                                         f"{MAX_TOP}") from None
    if not 1 <= value <= MAX_TOP:
        raise argparse.ArgumentTypeError(f"{value} is outside the allowed range 1 to {MAX_TOP} "
                                         "(candidates re-solved with the FE)")
    return value


def _dataset_path(model: str) -> Path:
    """The model's training dataset (the card's path, relative to the working directory or
    to the repository holding ``models/NAME``)."""
    # lazy: a command's own library loads when it runs (`hapticrom --help`: 0.4 s)
    from surrogate.runtime.card import read_card

    card = read_card(model)
    rel = Path(card["training_data"][0]["path"])
    for base in (Path.cwd(), Path(model).resolve().parents[1]):
        if (base / rel).is_dir():
            return base / rel
    raise FileNotFoundError(f"--verify: the model's training dataset {str(rel)!r} was not found "
                            "(its parameter space builds the FE scene)")


def fe_solver(plan: Any) -> Any:
    """A function solving one candidate of ``plan`` with the FE (:class:`planner.verify.FeSolve`
    out); raises RuntimeError when a solve fails."""
    # lazy: a command's own library loads when it runs (`hapticrom --help`: 0.4 s)
    from planner.crosstalk import UnitField
    from planner.verify import FeSolve
    from surrogate.data.store import Store
    from surrogate.data.worker import run_sample

    req = plan.request
    space = Store.open(_dataset_path(req.model)).space

    def solve(r: Any) -> FeSolve:
        row = {**space.center(), **req.site, **r.inputs, "frequency_hz": r.frequency_hz}
        out = run_sample(space.resolve_at(row, r.frequency_hz))
        if out["status"] != "ok":
            raise RuntimeError(f"--verify: the FE solve of {r.name} at {r.frequency_hz:g} Hz "
                               f"failed: {out['error']}")
        field = UnitField(float(out["center_amplitude_um"]), float(out["edge_radius_mm"]),
                          np.asarray(out["profile_distance_mm"], dtype=float),
                          np.maximum(np.asarray(out["profile_magnitude_um"], dtype=float),
                                     1e-12))
        return FeSolve(field, float(out["edge_amplitude_um"]), int(out["dofs"]),
                       float(out["wall_s"]), {k: row[k] for k in sorted(row)})

    return solve


def verify_plan(plan: Any, k: int) -> dict[str, Any]:
    """The ``verify`` block of ``plan`` with its top ``k`` candidates solved by the FE."""
    # lazy: a command's own library loads when it runs (`hapticrom --help`: 0.4 s)
    from planner.verify import rerank

    return rerank(plan, k, fe_solver(plan))


def print_verify(v: dict[str, Any]) -> None:
    """The verify block as a short table and the verdict."""
    s, f = v["surrogate"], v["fe"]
    free = v.get("compared") == "worst_load"
    print(f"verify: the surrogate's top {v['top_k']} re-solved with the FE ({f['dofs']} dofs, "
          f"{v['fe_wall_s']:.1f} s), ranked on the FE fields with the same criterion:")
    what = "worst load at the sites (nominal field)" if free else "pitch [mm] (nominal)"
    print(f"  ranks by the surrogate (S) and the FE; {what}, surrogate / FE; planned pitch at "
          "the plan's basis; FE load at the planned pitch")
    print(f"  {'S':>2s} {'FE':>2s}  {'design':22s} {'freq':>6s}  {'surrogate':>9s} {'FE':>9s} "
          f"{'diff':>7s} {'planned':>8s} {'FE load':>7s}")
    for c in v["candidates"]:
        cs, cf = c["surrogate"], c["fe"]
        rank = "-" if c["fe_rank"] is None else str(c["fe_rank"])
        diff = "n/a" if c["rel_diff"] is None else f"{c['rel_diff']:+.1%}"
        a, b = (("none" if x is None else f"{x:.3f}" if free else f"{x:.2f}")
                for x in (cs["value"], cf["value"]))
        print(f"  {c['surrogate_rank']:>2d} {rank:>2s}  {c['design'][:22]:22s} "
              f"{c['frequency_hz']:3.0f} Hz  {a:>9s} {b:>9s} {diff:>7s} "
              f"{cs['pitch_mm']:8.2f} {cf['load_at_plan_pitch']:7.3f}")
    print(f"  winner {v['design']} at {v['frequency_hz']:g} Hz: center surrogate "
          f"{s['center_um']:.3f} um, FE {f['center_um']:.3f} um "
          f"({s['center_um'] / f['center_um'] - 1:+.1%}); edge surrogate {s['edge_um']:.3f} um, "
          f"FE {f['edge_um']:.3f} um ({s['edge_um'] / f['edge_um'] - 1:+.1%})")
    w = v["fe_winner"]
    print("  FE winner: " + ("none (no re-solved candidate meets the criterion on the FE)"
                             if w is None else f"{w['design']} at {w['frequency_hz']:g} Hz ("
                             f"{'the same' if v['winner_agrees'] else 'DIFFERENT'})"))
    end = f.get("profile_end_from_edge_mm")
    if not free and end is not None and s["pitch_mm"] - v["edge_radius_mm"] > end:
        print(f"  (the FE profile ends {end:g} mm from the unit's edge too: beyond it the FE "
              "side also uses the log-slope extension)")
    load = f["criterion_load_at_plan_pitch"]
    fe_pitch = "none within the pitch bounds" if f["pitch_mm"] is None else \
        f"{f['pitch_mm']:.2f} mm"
    if v["holds"]:
        print(f"  criterion: HOLDS on the FE: criterion load {load:.3f} <= 1 at the planned "
              f"pitch {s['pitch_mm']:.2f} mm")
    elif not f["felt"]:
        print("  criterion: FAILS on the FE: the unit's own FE amplitude is below the "
              "detection threshold (it would not be felt)")
    else:
        print(f"  criterion: FAILS on the FE: criterion load {load:.3f} > 1 at the planned "
              f"pitch {s['pitch_mm']:.2f} mm; the FE needs {fe_pitch}")
    if v["confirmed"]:
        print(f"verdict: CONFIRMED by the FE (same winner, {'worst load' if free else 'pitch'} "
              f"within {v['tolerance']:.0%}: {v['rel_diff']:+.1%}, criterion holds)")
    else:
        print(f"verdict: REFUTED by the FE (exit {EXIT_VERIFY_FAILED}): "
              + "; ".join(v["refuted_because"]))
