"""The design figure (``hapticrom design --plot``).

Left: every evaluated design's pitch (at the criterion's basis) against its own centre
amplitude at its best frequency, grey; the Pareto front (no other design both packs closer
and vibrates more) joined in blue; the reference units (the paper's prototypes) as labelled
squares and the winner as a star. Right: the winner's worst criterion load against the pitch,
nominal and at the model's 95 % bounds, with the best reference's at the bounds; the load 1
line (the criterion), the winner's pitch, and where the nearest neighbour lies beyond the
model's profile (the log-slope extension: the shaded band).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

import figstyle
from planner.design.run import DesignOutcome, pareto_front
from planner.optimise import DesignResult, worst_load

__all__ = ["write_design_plot"]


def _scatter(ax: Any, outcome: DesignOutcome) -> None:
    hist = outcome.history
    ok = [e for e in hist if e.feasible]
    ax.scatter([e.center_um for e in ok], [e.pitch_mm for e in ok], s=9, color="0.65",
               label=f"evaluated ({len(ok)} of {len(hist)} feasible and felt)", zorder=1)
    front = [hist[i] for i in pareto_front(hist)]
    ax.plot([e.center_um for e in front], [e.pitch_mm for e in front], "-o", ms=3.5,
            color=figstyle.color(1), label="Pareto front", zorder=2)
    for i, r in enumerate(outcome.references):
        if r.feasible:
            ax.scatter([r.center_um], [r.pitch_mm], marker="s", s=40, zorder=3,
                       color=figstyle.color(2 + i), label=f"{r.name} ({r.pitch_mm:.1f} mm)")
    w = outcome.winner
    if w is not None:
        ax.scatter([w.center_um], [w.pitch_mm], marker="*", s=160, color="black", zorder=4,
                   label=f"winner: {w.name} ({w.pitch_mm:.1f} mm)")
    ax.set_xlabel("own centre amplitude at the best frequency [um]")
    ax.set_ylabel(f"pitch at the criterion's basis ({outcome.layout.criterion.holds_at}) [mm]")
    ax.legend(fontsize=7, loc="upper right")


def _result(outcome: DesignOutcome, name: str, frequency_hz: float | None
            ) -> DesignResult | None:
    plan = outcome.plan
    if plan is None or frequency_hz is None:
        return None
    return next((c for c in plan.candidates if c.name == name and
                 c.frequency_hz == frequency_hz), None)


def _loads(ax: Any, outcome: DesignOutcome) -> None:
    w = outcome.winner
    r = _result(outcome, w.name, w.frequency_hz) if w is not None else None
    if r is None:
        ax.set_title("no winner")
        return
    req = outcome.layout
    refs = [x for x in outcome.references if x.feasible]
    ref = min(refs, key=lambda x: x.score) if refs else None
    top = max(w.pitch_mm * 2.0, (ref.pitch_mm * 1.3) if ref else 0.0)
    p = np.linspace(2 * r.edge_radius_mm, min(top, req.max_pitch_mm), 160)
    curves = [(r.unit, r.frequency_hz, "winner, nominal", "--", "black"),
              (r.bound, r.frequency_hz, "winner, 95 % bounds", "-", "black")]
    rr = _result(outcome, ref.name, ref.frequency_hz) if ref else None
    if rr is not None:
        curves.append((rr.bound, rr.frequency_hz, f"{rr.name}, 95 % bounds", "-",
                       figstyle.color(2)))
    for field, f, label, ls, colour in curves:
        ok = p >= 2 * field.edge_radius_mm
        ax.semilogy(p[ok], [worst_load(field, req, x, f) for x in p[ok]], ls=ls, color=colour,
                    label=label)
    ax.axhline(1.0, color=figstyle.color(5), lw=1, label="criterion (load 1)")
    ax.axvline(w.pitch_mm, color="0.4", lw=0.8, ls=":",
               label=f"winner's pitch {w.pitch_mm:.2f} mm")
    end = r.unit.profile_end_mm
    if end < p[-1]:
        ax.axvspan(max(end, p[0]), p[-1], color="0.85", alpha=0.5, lw=0, zorder=0,
                   label="neighbour beyond the model's profile")
    ax.set_xlabel("pitch [mm]")
    ax.set_ylabel("worst site load (leakage / allowed)")
    ax.legend(fontsize=7, loc="upper right")


def write_design_plot(outcome: DesignOutcome, path: str | Path) -> None:
    """The design figure (module docstring)."""
    fig, (ax, bx) = figstyle.figure(1, 2, width_in=12, height_in=5.0)
    _scatter(ax, outcome)
    _loads(bx, outcome)
    w = outcome.winner
    crit = outcome.layout.criterion
    figstyle.annotate(
        fig, "Unit design", design=("winner: " + w.name) if w is not None else "none found",
        frequency=", ".join(f"{f:g} Hz" for f in outcome.layout.frequencies_hz),
        plotted=f"left: pitch ({crit.kind} criterion, {crit.holds_at}) against own amplitude "
                f"of every evaluated design ({outcome.search['optimiser']}, seed "
                f"{outcome.search['seed']}); right: the winner's worst load against the pitch",
        note=None)
    figstyle.save(fig, path)
