"""A plan as JSON (``plan_to_dict``) and as a figure (``write_plan_plot``)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

import figstyle
from planner.optimise import PITCH_TOL_MM, Plan

__all__ = ["plan_to_dict", "write_plan_plot"]


def _r(x: float | None, digits: int = 4) -> float | None:
    return None if x is None else float(round(x, digits))


def plan_to_dict(plan: Plan) -> dict[str, Any]:
    """Everything a user or the play step needs: request, candidates, the chosen array."""
    req = plan.request
    cands = [{"name": c.name, "frequency_hz": c.frequency_hz, "inputs": c.inputs,
              "center_um": _r(c.center_um), "edge_radius_mm": _r(c.edge_radius_mm),
              "pitch_mm": _r(c.pitch_mm, 3), "pitch_95_mm": _r(c.pitch_95_mm, 3),
              "edge_to_edge_mm": _r(c.edge_to_edge_mm, 3),
              "log_std_center": _r(c.log_std_center), "log_std_profile_max":
              _r(c.log_std_profile_max), "extrapolated": c.extrapolated}
             for c in plan.candidates]
    best = plan.best
    return {
        "format": "hapticrom-plan", "version": 1, "model": req.model,
        "array": {"rows": req.rows, "cols": req.cols, "grid": req.grid},
        "criterion": {"max_ratio": req.criterion.max_ratio,
                      "superposition": req.criterion.superposition,
                      "profile": "envelope (largest amplitude at any larger distance)",
                      "pitch_tolerance_mm": PITCH_TOL_MM},
        "site": req.site, "candidates": cands,
        "best": None if best is None else best.name,
        "best_frequency_hz": None if best is None else best.frequency_hz,
        "pitch_mm": None if best is None else _r(best.pitch_mm, 3),
        "margin": _r(plan.margin),
        "positions_mm": np.round(plan.positions_mm, 4).tolist(),
        "crosstalk_um": np.round(plan.crosstalk_um, 6).tolist(),
        "leakage_ratio": np.round(plan.ratios, 6).tolist(),
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
        for x, y in pos:
            ax.add_patch(Circle((x, y), best.edge_radius_mm, fill=False, color="0.4"))
        fig.colorbar(sc, ax=ax, label="leakage / own amplitude")
        ax.set_title(f"{best.name} at {best.frequency_hz:g} Hz: pitch {best.pitch_mm:.2f} mm")
    else:
        ax.set_title("no design meets the criterion within the pitch bounds")
    ax.set_aspect("equal")
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("y [mm]")
    for c in plan.candidates:
        f = c.unit
        r = np.linspace(f.edge_radius_mm, plan.request.max_pitch_mm, 300)
        bx.semilogy(r, f.amplitude(r) / f.center_um, label=f"{c.name}, {c.frequency_hz:g} Hz")
    bx.axhline(plan.request.criterion.max_ratio, color="k", ls="--", lw=1,
               label="criterion (one neighbour)")
    bx.set_xlabel("distance from unit centre [mm]")
    bx.set_ylabel("amplitude / own center amplitude")
    bx.legend(fontsize=8)
    figstyle.annotate(
        fig, "Array plan", design=("best: " + best.name) if best is not None else
        "no design meets the criterion",
        frequency=", ".join(sorted({f"{c.frequency_hz:g} Hz" for c in plan.candidates})),
        plotted="left: unit sites (mm) coloured by the leakage ratio (neighbours' amplitude / "
        "own centre amplitude); right: each candidate's predicted skin amplitude against "
        "distance from its centre, relative to its own centre amplitude (the unit's face), "
        "with the criterion")
    figstyle.save(fig, path)
