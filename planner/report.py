"""A plan as JSON (``plan_to_dict``) and as a figure (``write_plan_plot``)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

import figstyle
from planner.optimise import PITCH_TOL_MM, Z95, Plan
from planner.plan_record import KIND, SCHEMA_VERSION

__all__ = ["plan_to_dict", "write_plan_plot"]


def _r(x: float | None, digits: int = 4) -> float | None:
    return None if x is None else float(round(x, digits))


def plan_to_dict(plan: Plan) -> dict[str, Any]:
    """Everything a user or the play step needs: request, candidates, the chosen array (not
    yet sealed: ``planner.plan_record.seal_plan`` adds the digest when it is written)."""
    req = plan.request
    cands = [{"name": c.name, "frequency_hz": c.frequency_hz, "inputs": c.inputs,
              "center_um": _r(c.center_um), "edge_radius_mm": _r(c.edge_radius_mm),
              "pitch_mm": _r(c.pitch_mm, 3), "pitch_95_mm": _r(c.pitch_95_mm, 3),
              "edge_to_edge_mm": _r(c.edge_to_edge_mm, 3),
              "worst_load": _r(c.load), "shape": c.shape, "log_std_center": _r(c.log_std_center),
              "log_std_profile_max":
              _r(c.log_std_profile_max), "extrapolated": c.extrapolated}
             for c in plan.candidates]
    best = plan.best
    crit = req.criterion
    criterion: dict[str, Any] = {
        "kind": crit.kind, "max_ratio": crit.max_ratio, "superposition": crit.superposition,
        "profile": "envelope (largest amplitude at any larger distance)",
        "pitch_tolerance_mm": PITCH_TOL_MM, "drive_level": crit.drive_level}
    if crit.threshold is not None:
        t = crit.threshold
        criterion["threshold"] = {
            "source": t.source, "site": t.site, "contactor_area_cm2": t.contactor_area_cm2,
            "frequency_hz": list(t.frequency_hz),
            "threshold_um": [round(x, 6) for x in t.threshold_um],
            "at_best_frequency_um": None if best is None else
            _r(float(t(best.frequency_hz)), 6)}
    return {
        "schema_version": SCHEMA_VERSION, "kind": KIND, "model": req.model,
        "array": {"rows": req.rows, "cols": req.cols, "grid": req.grid,
                  "objective": req.objective, "region_mm": req.region_mm},
        "criterion": criterion,
        "site": req.site, "candidates": cands,
        "best": None if best is None else best.name,
        "best_inputs": None if best is None else best.inputs,
        "best_frequency_hz": None if best is None else best.frequency_hz,
        "pitch_mm": None if best is None else _r(best.pitch_mm, 3),
        "margin": _r(plan.margin),
        "positions_mm": np.round(plan.positions_mm, 4).tolist(),
        "crosstalk_um": np.round(plan.crosstalk_um, 6).tolist(),
        "leakage_ratio": np.round(plan.ratios, 6).tolist(),
        "leakage_um": np.round(plan.leakage_um, 6).tolist(),
        "criterion_load": np.round(plan.loads, 6).tolist(),
        "uncertainty": None if best is None else uncertainty(plan),
        "timing": plan.timing,
    }


def uncertainty(plan: Plan) -> dict[str, Any]:
    """The surrogate's uncertainty at the chosen design: its predictive log-std (the ensemble
    spread or GP std the run-time model exports), the 95 % interval of the own amplitude, the
    margin left when neighbours sit at their upper and the site at its lower 95 % bound, and
    whether the design lies outside the model's trained range."""
    b = plan.best
    lo, hi = b.center_um * np.exp(-Z95 * b.log_std_center), b.center_um * np.exp(
        Z95 * b.log_std_center)
    load95 = plan.load_95
    return {"center_log_std": _r(b.log_std_center), "profile_log_std_max":
            _r(b.log_std_profile_max), "center_95_um": [_r(lo), _r(hi)],
            "margin_95": None if load95 is None else (None if load95 == 0 else
                                                      _r(1.0 / load95)),
            "criterion_holds_at_95": load95 is not None and load95 <= 1.0,
            "pitch_95_mm": _r(b.pitch_95_mm, 3), "extrapolated": b.extrapolated}


_PLOTTED = {
    "ratio": "left: unit sites (mm) coloured by the leakage ratio (neighbours' amplitude / own "
             "centre amplitude); right: each candidate's predicted skin amplitude against "
             "distance from its centre, relative to its own centre amplitude (the unit's "
             "face), with the criterion",
    "perceptual": "left: unit sites (mm) coloured by the leakage over the detection threshold; "
                  "right: each candidate's predicted skin amplitude (um) against distance from "
                  "its centre at the drive level, with the detection threshold at each "
                  "frequency",
}


def write_plan_plot(plan: Plan, path: str | Path) -> None:
    """Left: the array (sites coloured by leakage ratio, unit outlines); right: each
    candidate's amplitude against distance from its centre, with the criterion."""
    from matplotlib.patches import Circle

    fig, (ax, bx) = figstyle.figure(1, 2, width_in=11, height_in=5.2)
    best = plan.best
    if best is not None:
        pos = plan.positions_mm
        sc = ax.scatter(pos[:, 0], pos[:, 1], c=plan.ratios, cmap="viridis", zorder=3,
                        vmin=0, vmax=plan.request.criterion.max_ratio)
        if plan.request.criterion.kind == "perceptual":
            sc.set_array(plan.loads)
            sc.set_clim(0, 1)
        for x, y in pos:
            ax.add_patch(Circle((x, y), best.edge_radius_mm, fill=False, color="0.4"))
        fig.colorbar(sc, ax=ax, label="leakage / own amplitude" if plan.request.criterion.kind
                     == "ratio" else "leakage / detection threshold")
        spacing = ("nearest sites" if plan.request.grid == "free" else "pitch")
        ax.set_title(f"{best.name} at {best.frequency_hz:g} Hz: {spacing} "
                     f"{best.pitch_mm:.2f} mm")
    else:
        ax.set_title("no design meets the criterion within the pitch bounds")
    ax.set_aspect("equal")
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("y [mm]")
    crit = plan.request.criterion
    perceptual = crit.kind == "perceptual"
    for c in plan.shown():
        f = c.unit
        r = np.linspace(f.edge_radius_mm, plan.request.max_pitch_mm, 300)
        y = f.amplitude(r) * crit.drive_level if perceptual else f.amplitude(r) / f.center_um
        line, = bx.semilogy(r, y, label=f"{c.name}, {c.frequency_hz:g} Hz")
        if perceptual:
            bx.axhline(float(crit.threshold(c.frequency_hz)), color=line.get_color(), ls=":",
                       lw=1)
    if perceptual:
        bx.plot([], [], "k:", lw=1, label="detection threshold (dotted, per frequency)")
        bx.set_ylabel(f"amplitude at drive level {crit.drive_level:g} [um]")
    else:
        bx.axhline(crit.max_ratio, color="k", ls="--", lw=1, label="criterion (one neighbour)")
        bx.set_ylabel("amplitude / own center amplitude")
    bx.set_xlabel("distance from unit centre [mm]")
    bx.legend(fontsize=8)
    figstyle.annotate(
        fig, "Array plan", design=("best: " + best.name) if best is not None else
        "no design meets the criterion",
        frequency=", ".join(sorted({f"{c.frequency_hz:g} Hz" for c in plan.candidates})),
        plotted=_PLOTTED["perceptual" if perceptual else "ratio"])
    figstyle.save(fig, path)
