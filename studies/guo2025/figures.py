"""The report's PNG figures (matplotlib, Agg backend): profiles over distance from the unit edge
(mm), normalized amplitudes, the sweeps, the ring contacts and the transient."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

import figstyle

from .cases import (
    RING_CONTACTS,
    TRANSIENT_CONTACT,
    Plan,
    contact_name,
    ranked,
    sweep_point,
    uniform_name,
)
from .contact import contact_label, study_contact_triples
from .paper import LDV_BAND_HZ, LETTERS, PAPER_SINGLE_RANGE, PAPER_TRIPLE_MAX, PAPER_TRIPLE_MIN
from .solved import Solved
from .studies import sweep_label
from .text import design

#: Every steady case of the study runs at the paper's rated 120 rev/s (the scenes' ERM
#: rated_frequency_hz and analysis.frequency_hz, Guo et al. 2025).
FREQUENCY = "120 Hz (ERM at the paper's 120 rev/s), harmonic steady state"
_NORMALIZED = ("normalized amplitude = skin amplitude / centre amplitude, where the centre is "
               "the unit's skin-side face at r = 0; magnitude = sqrt(|U_r|^2+|U_z|^2+|U_t|^2), "
               "abs U_z the normal component alone")


def _finish(fig, path: Path, title: str, design_text: str, plotted: str,
            frequency: str | None = FREQUENCY) -> None:
    figstyle.annotate(fig, title, design=design_text, frequency=frequency, plotted=plotted)
    figstyle.save(fig, path)


def _profile_axes(ax, title: str) -> None:
    ax.set_xlim(0, 20)
    ax.set_ylim(bottom=0)
    ax.set_xlabel("distance from the unit edge (mm)")
    ax.set_ylabel("amplitude / centre amplitude")
    ax.set_title(title, fontsize=10)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)


def fig_single_layers(r: Mapping[str, Solved], path: Path) -> None:
    fig, ax = figstyle.figure(height_in=4.8)
    for i, c in enumerate(LETTERS):
        s, col = r[f"single/{c}"], figstyle.color(i)
        ax.plot(s.profile_mm, s.normalized_profile(), color=col, label=f"{c} magnitude")
        ax.plot(s.profile_mm, s.normalized_profile(True), "--", color=col, label=f"{c} abs U_z")
    ax.axhspan(*PAPER_SINGLE_RANGE, color="grey", alpha=0.2, label="paper: edge 50-58 %")
    _profile_axes(ax, "Single layers, forward, glued (cf. Fig. 9a)")
    _finish(fig, path, "One silicone ring: skin profile outside the unit",
            "forward motor, glued, one 1 mm ring of material " + ", ".join(LETTERS),
            "skin surface amplitude against distance from the unit edge (mm); " + _NORMALIZED)


def fig_triples(r: Mapping[str, Solved], triples: Sequence[str], path: Path) -> None:
    order = ranked(r, triples, False)
    fig, (ax, bx) = figstyle.figure(1, 2, width_in=11, height_in=4.9)
    picks = list(dict.fromkeys([order[0], "ACD", order[-1]]))
    for i, t in enumerate(picks):
        s, col = r[f"triple/{t}"], figstyle.color(i)
        ax.plot(s.profile_mm, s.normalized_profile(), color=col, label=f"{design(t)} magnitude")
        ax.plot(s.profile_mm, s.normalized_profile(True), "--", color=col,
                label=f"{design(t)} abs U_z")
    ax.axhline(PAPER_TRIPLE_MIN, color="k", lw=0.8, ls=":", label="paper 19 % / 90 %")
    ax.axhline(PAPER_TRIPLE_MAX, color="k", lw=0.8, ls=":")
    _profile_axes(ax, "Most restraining, A-C-D, most enhancing (cf. Fig. 9b/c)")
    vals = [r[f"triple/{t}"].norm for t in order]
    vals_z = [r[f"triple/{t}"].norm_z for t in order]
    x = np.arange(len(order))
    bx.bar(x, vals, color=[figstyle.color(1) if t == "ACD" else figstyle.color(0)
                           for t in order], label="magnitude")
    bx.plot(x, vals_z, "k.", ms=4, label="abs U_z")
    bx.axhline(PAPER_TRIPLE_MIN, color="k", lw=0.8, ls=":")
    bx.axhline(PAPER_TRIPLE_MAX, color="k", lw=0.8, ls=":")
    bx.set_xticks(x, [t for t in order], rotation=90, fontsize=6 if len(order) > 16 else 8)
    bx.set_ylabel("normalized edge amplitude")
    bx.set_title("All triples, ranked (A-C-D in vermillion)", fontsize=10)
    bx.legend(fontsize=7)
    _finish(fig, path, "Three rings: skin profile and normalized edge amplitude",
            "reverse motor on pogo pins, three 1 mm rings (letters: materials inner to outer)",
            "left: skin amplitude against distance from the unit edge; right: normalized edge "
            "amplitude of every triple, ranked; " + _NORMALIZED)


def fig_sweeps(r: Mapping[str, Solved], sweeps: Mapping[str, Sequence[float]],
               path: Path) -> None:
    fig, axes = figstyle.figure(1, len(sweeps), width_in=4.2 * len(sweeps), height_in=4.5)
    for ax, (name, values) in zip(np.atleast_1d(axes), sweeps.items(), strict=True):
        sols = [r[uniform_name(*sweep_point(name, x))] for x in values]
        label, unit, table = sweep_label(name)
        ax.plot(values, [s.edge_um for s in sols], "o-", color=figstyle.color(0))
        ax.set_ylabel("edge amplitude (um)", color=figstyle.color(0))
        ax.set_xlabel(f"{label} ({unit})")
        if name == "E":
            ax.set_xscale("log")
        tw = ax.twinx()
        tw.plot(values, [s.norm for s in sols], "s--", color=figstyle.color(1), label="magnitude")
        tw.plot(values, [s.norm_z for s in sols], "^:", color=figstyle.color(2), label="abs U_z")
        tw.set_ylabel("normalized edge")
        tw.legend(fontsize=7)
        ax.set_title(f"{table}: three equal rings", fontsize=10)
        ax.grid(alpha=0.3)
    _finish(fig, path, "Ring property sweeps", "three equal rings, one property swept at a "
            "time (paper Tables 2-4)", "edge magnitude (um, left axis) and normalized edge "
            "amplitude (right axis) against the swept property; " + _NORMALIZED)


def fig_structure(r: Mapping[str, Solved], path: Path) -> None:
    fig, (ax, bx) = figstyle.figure(1, 2, width_in=9, height_in=4.3)
    x = np.arange(2)
    for i, o in enumerate(("forward", "reverse")):
        ax.bar(x + 0.4 * i, [r[f"bare/{o}/{a}"].centre_um for a in ("glued", "pogo")], 0.4,
               label=o)
    ax.set_xticks(x + 0.2, ["glued", "pogo"])
    ax.set_ylabel("centre amplitude (um)")
    ax.set_title("Orientation, bare motor (cf. Fig. 8a)", fontsize=10)
    ax.legend(fontsize=8)
    for i, a in enumerate(("glued", "pogo")):
        bx.bar(x + 0.4 * i, [r[f"bare/{o}/{a}"].edge_um for o in ("reverse", "forward")], 0.4,
               label=a)
    bx.set_xticks(x + 0.2, ["reverse", "forward"])
    bx.set_ylabel("edge amplitude (um)")
    bx.set_title("Pogo pins, bare motor (cf. Fig. 8b)", fontsize=10)
    bx.legend(fontsize=8)
    _finish(fig, path, "Motor orientation and attachment", "bare motor (no rings), forward "
            "or reverse, glued or on pogo pins", "centre magnitude (the unit's skin-side face "
            "at r = 0) and edge magnitude (skin at the unit's outer radius), um")


def fig_ring_contact(r: Mapping[str, Solved], triples: Sequence[str], default: str,
                     path: Path) -> None:
    names = [*(f"single/{c}" for c in LETTERS),
             *(f"triple/{t}" for t in study_contact_triples(r, triples))]
    order = [default, *(c for c in RING_CONTACTS if c != default)]
    fig, ax = figstyle.figure(width_in=10, height_in=5.6)
    x = np.arange(len(names))
    w = 0.8 / len(order)
    for i, c in enumerate(order):
        sols = [r[contact_name(n, c)] for n in names]
        ax.bar(x + (i - (len(order) - 1) / 2) * w, [s.norm for s in sols], w,
               color=figstyle.color(i), label=contact_label(c, default) + ", magnitude")
        ax.plot(x + (i - (len(order) - 1) / 2) * w, [s.norm_z for s in sols], "k.", ms=4,
                label="abs U_z" if i == 0 else None)
    ax.axhspan(*PAPER_SINGLE_RANGE, color="grey", alpha=0.25, label="paper: single 50-58 %")
    ax.axhline(PAPER_TRIPLE_MIN, color="k", lw=0.8, ls=":", label="paper: triples 19 % / 90 %")
    ax.axhline(PAPER_TRIPLE_MAX, color="k", lw=0.8, ls=":")
    ax.set_xticks(x, [n.split("/")[-1] if n.startswith("triple") else n.replace("single/", "")
                      + " (single)" for n in names], rotation=45, fontsize=8)
    ax.set_ylabel("normalized edge amplitude")
    ax.set_title("How the inner ring meets the motor (ring contact)", fontsize=10)
    ax.legend(fontsize=7, ncol=3, loc="upper center", bbox_to_anchor=(0.5, -0.2))
    ax.grid(alpha=0.3, axis="y")
    _finish(fig, path, "Ring contact", "single rings and selected triples with the inner "
            "ring bonded, frictionless or not touching the motor", "normalized edge amplitude "
            "per design and contact; " + _NORMALIZED)


def fig_transient(r: Mapping[str, Solved], path: Path) -> None:
    t = r["transient/ACD"].transient
    h = r[contact_name("triple/ACD", TRANSIENT_CONTACT)]
    fig, (ax, bx) = figstyle.figure(1, 2, width_in=11, height_in=4.6)
    ax.semilogy(t["t_ms"], t["centre_um"], lw=0.8, label="centre")
    ax.semilogy(t["t_ms"], t["edge_um"], lw=0.8, label="edge")
    ax.set_title("raw |u(t)| on the theta = 0 meridian", fontsize=10)
    bx.plot(t["t_ms"], t["centre_band_hist_um"], lw=0.8, label="centre, band-passed")
    bx.plot(t["t_ms"], t["edge_band_hist_um"], lw=0.8, label="edge, band-passed")
    bx.axhline(h.centre_um, color=figstyle.color(0), ls="--", label="centre, harmonic magnitude")
    bx.axhline(h.edge_um, color=figstyle.color(1), ls="--", label="edge, harmonic magnitude")
    bx.set_title(f"|u(t)| band-passed {LDV_BAND_HZ[0]:g}-{LDV_BAND_HZ[1]:g} Hz", fontsize=10)
    for a in (ax, bx):
        a.set_xlabel("time (ms)")
        a.set_ylabel("displacement magnitude (um)")
        a.legend(fontsize=7)
        a.grid(alpha=0.3)
    _finish(fig, path, "Transient from rest against the steady state",
            f"A-C-D, reverse, pogo, ring contact '{TRANSIENT_CONTACT}'",
            "displacement magnitude |u(t)| (um) at the centre (the unit's face at r = 0) and "
            "the edge on the theta = 0 meridian: raw (left, log scale) and band-passed like "
            "the paper's vibrometer (right), with the harmonic magnitudes dashed",
            frequency="ERM spin-up to its rated 120 rev/s")


def write_figures(r: Mapping[str, Solved], p: Plan, out: Path, default: str) -> list[str]:
    """Write the PNGs into ``out``; returns their file names."""
    figs = {"structure.png": lambda f: fig_structure(r, f),
            "single_layers.png": lambda f: fig_single_layers(r, f),
            "triples.png": lambda f: fig_triples(r, p.triples, f),
            "sweeps.png": lambda f: fig_sweeps(r, p.sweeps, f)}
    if study_contact_triples(r, p.triples):
        figs["ring_contact.png"] = lambda f: fig_ring_contact(r, p.triples, default, f)
    if "transient/ACD" in r:
        figs["transient.png"] = lambda f: fig_transient(r, f)
    for name, draw in figs.items():
        draw(out / name)
    return list(figs)


# --------------------------------------------------------------------------- the report
