"""The plan figure (``hapticrom plan --plot``): the array, every candidate's profile, a legend.

Three panels: the chosen array (sites numbered as pattern files address them, 0-based row by
row, coloured by their criterion load, unit outlines); each listed candidate's amplitude
against distance from its centre, the chosen one drawn thick in black with its pitch marked,
the criterion (ratio) or the detection threshold at each frequency (perceptual) as labelled
lines, and where the model's profile ends (beyond it, the log-slope extension); and the
legend in a panel of its own, so it never covers the curves. Up to 8 curves take the
project's colour-blind-safe palette, up to 20 matplotlib's ``tab20``, more an evenly spaced
``turbo`` with line styles cycled (:func:`curve_styles`: every curve a distinct pair).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

import figstyle

__all__ = ["curve_styles", "write_plan_plot"]

_LINESTYLES = ("-", "--", "-.", ":")

_PLOTTED = {
    "ratio": "left: unit sites (mm), numbered, coloured by the leakage ratio over the criterion; "
             "middle: each candidate's predicted skin amplitude against distance from its "
             "centre, relative to its own centre amplitude, with the criterion",
    "perceptual": "left: unit sites (mm), numbered, coloured by the leakage over the detection "
                  "threshold; middle: each candidate's predicted skin amplitude (um) against "
                  "distance from its centre at the drive level, with the detection threshold "
                  "at each frequency",
}


def curve_styles(n: int) -> list[tuple[str, str]]:
    """``n`` distinct (colour, line style) pairs (module docstring)."""
    # lazy: matplotlib takes 1.9 s to import, and only a figure needs it
    from matplotlib import colormaps
    from matplotlib.colors import to_hex

    if n <= len(figstyle.OKABE_ITO):
        return [(figstyle.color(i), "-") for i in range(n)]
    if n <= 20:
        tab = colormaps["tab20"]
        order = list(range(0, 20, 2)) + list(range(1, 20, 2))  # strong shades first
        return [(to_hex(tab(order[i])), "-") for i in range(n)]
    n_colours = int(np.ceil(n / len(_LINESTYLES)))
    turbo = colormaps["turbo"]
    colours = [to_hex(turbo(0.05 + 0.9 * k / max(n_colours - 1, 1))) for k in range(n_colours)]
    return [(colours[i % n_colours], _LINESTYLES[i // n_colours]) for i in range(n)]


def _array_panel(ax: Any, plan: Any) -> None:
    # lazy: matplotlib takes 1.9 s to import, and only a figure needs it
    from matplotlib.patches import Circle

    best, crit = plan.best, plan.request.criterion
    if best is None:
        ax.set_title("no design meets the criterion within the pitch bounds")
        return
    pos = plan.positions_mm
    sc = ax.scatter(pos[:, 0], pos[:, 1], c=plan.loads, cmap="viridis", zorder=3, vmin=0,
                    vmax=1)
    for i, (x, y) in enumerate(pos):
        ax.add_patch(Circle((x, y), best.edge_radius_mm, fill=False, color="0.4"))
        ax.annotate(str(i), (x, y), xytext=(0, best.edge_radius_mm * 0.6 + 4),
                    textcoords="offset points", ha="center", va="bottom",
                    fontsize=7 if len(pos) <= 64 else 5, zorder=4)
    label = ("leakage / (max_ratio x own amplitude)" if crit.kind == "ratio" else
             "leakage / detection threshold")
    ax.figure.colorbar(sc, ax=ax, label=label + " (load)", shrink=0.8)
    spacing = "nearest sites" if plan.request.grid == "free" else "pitch"
    ax.set_title(f"chosen: {best.name} at {best.frequency_hz:g} Hz\n{spacing} "
                 f"{best.pitch_mm:.2f} mm (sites numbered as in pattern files)")
    pad = best.edge_radius_mm * 2
    ax.set_xlim(pos[:, 0].min() - pad, pos[:, 0].max() + pad)
    ax.set_ylim(pos[:, 1].min() - pad, pos[:, 1].max() + 2.5 * pad)


def _label_line(ax: Any, x: float, y: float, text: str) -> None:
    ax.annotate(text, (x, y), xytext=(-2, 2), textcoords="offset points", ha="right",
                va="bottom", fontsize=7, color="0.15")


def _profiles_panel(bx: Any, plan: Any) -> None:
    req, best = plan.request, plan.best
    crit = req.criterion
    perceptual = crit.kind == "perceptual"
    shown = plan.shown()
    r_max = req.max_pitch_mm if best is None else min(req.max_pitch_mm, 2.0 * best.pitch_mm)
    for c, (colour, ls) in zip(shown, curve_styles(len(shown)), strict=True):
        f = c.unit
        r = np.linspace(f.edge_radius_mm, r_max, 300)
        y = f.amplitude(r) * crit.drive_level if perceptual else f.amplitude(r) / f.center_um
        chosen = best is not None and c is best
        bx.semilogy(r, y, color="k" if chosen else colour, ls="-" if chosen else ls,
                    lw=2.8 if chosen else 1.2, zorder=5 if chosen else 2,
                    label=("CHOSEN: " if chosen else "") + f"{c.name}, {c.frequency_hz:g} Hz"
                    + ("" if c.pitch_mm is not None else " (infeasible)"))
    if perceptual:
        for i, f_hz in enumerate(sorted({c.frequency_hz for c in shown})):
            level = float(crit.threshold(f_hz))
            bx.axhline(level, color="0.3", ls=":", lw=1)
            # labels staggered along the line so that close thresholds stay readable
            _label_line(bx, r_max - (i % 3) * 0.3 * (r_max - bx.get_xlim()[0]), level,
                        f"threshold {f_hz:g} Hz: {level:.2g} um")
        bx.set_ylabel(f"amplitude at drive level {crit.drive_level:g} [um]")
    else:
        bx.axhline(crit.max_ratio, color="0.3", ls="--", lw=1)
        _label_line(bx, r_max, crit.max_ratio,
                    f"criterion: max_ratio {crit.max_ratio:g} (one neighbour)")
        bx.set_ylabel("amplitude / own centre amplitude")
    if best is not None:
        bx.axvline(best.pitch_mm, color="k", ls="--", lw=1)
        lo = bx.get_ylim()[0]
        bx.annotate(f"chosen pitch {best.pitch_mm:.2f} mm", (best.pitch_mm, lo),
                    xytext=(3, 3), textcoords="offset points", rotation=90, fontsize=7,
                    va="bottom")
        end = best.edge_radius_mm + plan.profile_end_mm
        if end < r_max:
            bx.axvspan(end, r_max, color="0.85", alpha=0.5, zorder=0, lw=0)
            bx.annotate("beyond the model's profile: log-slope extension", (end, 1.0),
                        xycoords=("data", "axes fraction"), xytext=(3, -3),
                        textcoords="offset points", va="top", fontsize=7, color="0.3")
    bx.set_xlim(0, r_max)
    bx.set_xlabel("distance from unit centre [mm]")


def write_plan_plot(plan: Any, path: str | Path) -> None:
    """The plan figure (module docstring)."""
    fig, (ax, bx, lx) = figstyle.figure(1, 3, width_in=15, height_in=5.6,
                                        gridspec_kw={"width_ratios": [1.0, 1.25, 0.62]})
    _array_panel(ax, plan)
    ax.set_aspect("equal")
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("y [mm]")
    _profiles_panel(bx, plan)
    handles, labels = bx.get_legend_handles_labels()
    lx.axis("off")
    lx.legend(handles, labels, loc="upper left", fontsize=7.5, title="candidates",
              borderaxespad=0.0)
    best = plan.best
    crit = plan.request.criterion
    notes = list(crit.warnings())
    figstyle.annotate(
        fig, "Array plan", design=("chosen: " + best.name) if best is not None else
        "no design meets the criterion",
        frequency=", ".join(f"{f:g} Hz" for f in sorted({c.frequency_hz
                                                         for c in plan.candidates})),
        plotted=_PLOTTED[crit.kind], note="; ".join(notes) if notes else None)
    figstyle.save(fig, path)
