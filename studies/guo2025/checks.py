"""Checks of why we may disagree with the paper: (a) amplitude definition, (b) center definition,
(c) motor parameters, (d) the smeared pogo pins, (e) steady vs transient, (f) mesh refinement."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import replace

import numpy as np

from .cases import (
    BARE,
    MESH_VARIANT,
    MOTOR_VARIANTS,
    POGO_VARIANTS,
    TRANSIENT_CONTACT,
    TRIPLE,
    Context,
    case_scene,
    contact_name,
    transient_case,
)
from .paper import (
    LDV_BAND_HZ,
    LETTERS,
    PAPER_POGO_RATIO,
    PAPER_SINGLE_RANGE,
    PAPER_TRIPLE_MAX,
    PAPER_TRIPLE_MIN,
)
from .solved import Solved
from .studies import range_verdict, rotor_mm
from .text import Section, design, gap_phrase, md_table, near, pct, um


def check_amplitude_definition(r: Mapping[str, Solved], triples: Sequence[str]) -> Section:
    """(a) magnitude vs vertical component, for the headline numbers."""
    singles = [r[f"single/{c}"] for c in LETTERS]
    acd = r["triple/ACD"]
    pogo_g, pogo_p = r["bare/reverse/glued"], r["bare/reverse/pogo"]
    mid = sum(PAPER_SINGLE_RANGE) / 2
    s_m = float(np.mean([s.norm for s in singles]))
    s_z = float(np.mean([s.norm_z for s in singles]))
    ratio_m, ratio_z = pogo_p.edge_um / pogo_g.edge_um, pogo_p.edge_z_um / pogo_g.edge_z_um
    rows = [["single layers, mean normalized edge", pct(mid), pct(s_m), pct(s_z)],
            ["A-C-D normalized edge", pct(PAPER_TRIPLE_MIN), pct(acd.norm), pct(acd.norm_z)],
            ["pogo / glued edge (bare, reverse)", f"{PAPER_POGO_RATIO:g}", f"{ratio_m:.3f}",
             f"{ratio_z:.3f}"]]
    text = ("We report the displacement magnitude sqrt(|U_r|^2 + |U_t|^2 + |U_z|^2) of the "
            "rotating load; a laser Doppler vibrometer looking at the skin, and probably the "
            "paper's FE read-out, see the vertical component. The centre is the same in both "
            "columns (on the axis the vertical amplitude of a rotating load vanishes), so the "
            "right column is |U_z| at the edge over the centre magnitude.\n\n"
            + md_table(["quantity", "paper", "magnitude", "abs U_z"], rows)
            + f"\n\nUsing the vertical component {gap_phrase(s_m, s_z, mid)} for the single "
              f"layers, and {gap_phrase(acd.norm, acd.norm_z, PAPER_TRIPLE_MIN)} for A-C-D.")
    return Section("(a) Amplitude definition", text, {"single_mean": [s_m, s_z],
                                                      "acd": [acd.norm, acd.norm_z],
                                                      "pogo_ratio": [ratio_m, ratio_z]})


def readings(s: Solved) -> dict[str, float]:
    """Normalized edge under every (centre, component) reading: edge magnitude or |U_z| over
    each of :meth:`Solved.centre_variants_um`."""
    out = {}
    for key, c in s.centre_variants_um().items():
        out[f"{key} / magnitude"] = s.edge_um / c
        out[f"{key} / abs U_z"] = s.edge_z_um / c
    return out


def check_centre_definition(r: Mapping[str, Solved], triples: Sequence[str]) -> Section:
    """(b) four readings of the centre amplitude, each with the edge magnitude or |U_z|."""
    names = list(dict.fromkeys([*(f"single/{c}" for c in LETTERS), "triple/ACD"]))
    variants = list(r[names[0]].centre_variants_um())
    rows = []
    for n in names:
        s, rd = r[n], readings(r[n])
        c = s.centre_variants_um()
        rows.append([n, *(f"{um(c[k])} um: {pct(rd[k + ' / magnitude'])} / "
                          f"{pct(rd[k + ' / abs U_z'])}" for k in variants)])
    matrix, data = [], {}
    lo, hi = PAPER_SINGLE_RANGE
    for key in readings(r[names[0]]):
        singles = [readings(r[f"single/{c}"])[key] for c in LETTERS]
        vals = {t: readings(r[f"triple/{t}"])[key] for t in triples}
        o = sorted(triples, key=vals.get)
        d = {"single": [min(singles), max(singles)], "min": [o[0], vals[o[0]]],
             "max": [o[-1], vals[o[-1]]], "acd_rank": o.index("ACD") + 1 if "ACD" in o else None,
             "single_verdict": range_verdict(singles, lo, hi),
             "min_near": near(vals[o[0]], PAPER_TRIPLE_MIN),
             "max_near": near(vals[o[-1]], PAPER_TRIPLE_MAX)}
        data[key] = d
        matrix.append([key, f"{pct(min(singles))} - {pct(max(singles))}",
                       d["single_verdict"], f"{pct(vals[o[0]])} ({design(o[0])})",
                       f"{pct(vals[o[-1]])} ({design(o[-1])})",
                       f"{d['acd_rank']} of {len(o)}"])
    text = ("Ours is the unit's own skin-side face on the axis (the skin under a glued unit, the "
            "board's underside on pogo pins, the solver's haptic-unit model). Alternatives: the "
            "skin surface on the "
            "axis (on pins it is not touched by the unit), the largest skin amplitude under the "
            "unit's footprint, and the motor's top face on the axis (where a vibrometer looking "
            "down on the unit would aim). On the axis the vertical amplitude of a rotating load "
            "vanishes, so every centre is a horizontal motion; the edge is read as magnitude or "
            "as |U_z|. Each cell: centre amplitude: normalized edge, magnitude / abs U_z.\n\n"
            + md_table(["case", *variants], rows)
            + "\n\nThe paper's headline numbers under each reading (centre / edge component):"
              "\n\n"
            + md_table(["reading", "single layers",
                      f"vs {pct(PAPER_SINGLE_RANGE[0])} - {pct(PAPER_SINGLE_RANGE[1])}",
                      "triples: min", "triples: max",
                      "A-C-D rank"], matrix)
            + "\n\nThese readings were tried after seeing our default disagree; a reading that "
              "matches one claim is a hypothesis about what the paper measured, not agreement.")
    return Section("(b) Centre definition", text, data)


def check_motor(r: Mapping[str, Solved], ctx: Context) -> Section:
    """(c) motor mass and rotor height (the unbalance cancels in normalized values)."""
    cases = [*(f"single/{c}" for c in LETTERS), "triple/ACD"]
    tags = ["", *MOTOR_VARIANTS]
    rows, data, changes = [], {}, []
    for n in cases:
        base = r[n].norm
        vals = {t: r[f"{n}/{t}" if t else n] for t in tags}
        data[n] = {t or "default": [v.norm, v.norm_z] for t, v in vals.items()}
        changes += [abs(v.norm / base - 1) for v in vals.values()]
        rows.append([n, *(f"{pct(v.norm)} ({pct(v.norm_z)})" for v in vals.values())])
    motor = ctx.example(BARE).unit.motor
    rotor, alt = rotor_mm(ctx)
    heads = [f"{'rotor' if 'rotor' in path else 'mass'} {v:g} {'mm' if 'rotor' in path else 'g'}"
             for (path, v), in MOTOR_VARIANTS.values()]
    flipped = replace(ctx.example(BARE).unit, orientation="reverse")  # fem defines the flip
    swap = math.isclose(alt, flipped.rotor_above_base_mm)
    text = ("Normalized edge, magnitude (abs U_z in brackets), with the motor's defaults "
            f"({motor.mass_g:g} g, rotor plane {rotor:g} mm above the base face) and with one of "
            "them changed; ring contact as in the studies. The paper gives neither; the "
            "unbalance m e only scales every amplitude.\n\n"
            + md_table(["case", "default", *heads], rows)
            + f"\n\nLargest relative change of a normalized edge: {max(changes):.0%}. The "
              f"orientation study (section 1) also lists the rotor-{alt:g} mm case"
            + (": with it, forward and reverse swap their rotor heights." if swap else "."))
    return Section("(c) Motor parameters the paper does not give", text, data)


def check_pogo(r: Mapping[str, Solved], ctx: Context) -> Section:
    """(d) the smeared pins: footprint and stiffness."""
    g = r["bare/reverse/glued"]
    rows, data = [], {}
    pogo = ctx.example(TRIPLE).unit.pogo
    labels = {"": f"default ({pogo.tip_diameter_mm:g} mm tip, {pogo.stiffness_N_m:g} N/m)"}
    for tag, ((path, v),) in POGO_VARIANTS.items():
        labels[tag] = (f"tip {v:g} mm" if "tip" in path
                       else f"stiffness x{v / pogo.stiffness_N_m:g}")
    for tag, label in labels.items():
        bare = r[f"bare/reverse/pogo/{tag}" if tag else "bare/reverse/pogo"]
        acd = r[f"triple/ACD/{tag}" if tag else "triple/ACD"]
        contact = acd.contact.get("contact_maintained") if acd.contact else None
        data[tag or "default"] = {"ratio": bare.edge_um / g.edge_um, "acd": acd.norm,
                                  "acd_contact": contact}
        rows.append([label, f"{bare.edge_um / g.edge_um:.3f}", pct(acd.norm), pct(acd.norm_z),
                     "n/a" if contact is None else ("yes" if contact else "no")])
    n_pins, r_p, edge = pogo.count, pogo.radius_mm, r["triple/ACD"].edge_mm
    first = n_pins - 1  # the lowest harmonic 1 +- k N besides n = 1
    text = (f"The {n_pins} pins are smeared into a ring (the solver's haptic-unit model): the "
            "vertical (n = 0) and "
            f"rocking (n = 1) stiffnesses are exact, the harmonics n = 1 +- {n_pins}k of the "
            "discrete pins are left out. Those decay away from the pin circle roughly like "
            f"(R_p / r)^|n|; at the edge of the A-C-D unit ({edge:g} mm, R_p = {r_p:g} mm) the "
            f"first, n = {first}, is about ({r_p:g} / {edge:g})^{first} = "
            f"{pct((r_p / edge) ** first)} of its value at the pins. Below: how much the "
            "answers depend on the parts of the pin model that the smearing makes uncertain "
            "(A-C-D with the default ring contact).\n\n"
            + md_table(["pin model", "bare reverse: pogo / glued edge", "A-C-D normalized",
                      "A-C-D normalized (abs U_z)", "A-C-D pins keep contact"], rows))
    return Section("(d) Three pins smeared into a ring", text, data)



def check_transient(r: Mapping[str, Solved], ctx: Context) -> Section | None:
    """(e) steady harmonic vs a transient from rest (their analysis kind)."""
    if "transient/ACD" not in r:
        return None
    h = r[contact_name("triple/ACD", TRANSIENT_CONTACT)]
    t = r["transient/ACD"].transient

    def row(label: str, centre: float, edge: float, edge_z: float) -> list[str]:
        return [label, um(centre), um(edge), pct(edge / centre), pct(edge_z / centre)]

    rows = [row("harmonic steady state", h.centre_um, h.edge_um, h.edge_z_um),
            row(f"transient, peak over 0-{t['duration_ms']:.0f} ms", t["centre_peak_um"],
                t["edge_peak_um"], t["edge_z_peak_um"]),
            row("transient, peak over the last two revolutions", t["centre_late_um"],
                t["edge_late_um"], t["edge_z_late_um"]),
            row(f"the same after a {LDV_BAND_HZ[0]:g}-{LDV_BAND_HZ[1]:g} Hz band-pass",
                t["centre_band_um"], t["edge_band_um"], t["edge_z_band_um"])]
    drift = t["centre_drift_um"] / h.centre_um
    literal = ctx.posed["none"]["transient"]
    scene = case_scene(transient_case())  # the scene the transient solves
    damped = ("undamped" if all(ly.loss_factor == 0 for ly in scene.tissue.layers)
              else "hysteretically damped")
    rev_hz = scene.unit.motor.rated_frequency_hz
    text = ("The paper ran ABAQUS dynamic implicit (0.05 ms step) with the mass turning at "
            "120 rev/s from the start and read amplitudes off time histories; the run length "
            "and the tissue damping are not given. Our transient: the A-C-D unit (reverse, "
            f"pogo, ring contact '{TRANSIENT_CONTACT}'), constant speed {rev_hz:g} rev/s from "
            f"rest, {t['duration_ms']:.0f} ms at a {t['time_step_ms']:g} ms step "
            f"({1e3 / rev_hz / t['time_step_ms']:.0f} steps per revolution; generalised-alpha, "
            f"second order), the default {damped} tissue, a damping layer as the absorber. "
            "Amplitudes: per-component peaks combined as the magnitude; the band-pass is the "
            f"paper's vibrometer processing (Butterworth {LDV_BAND_HZ[0]:g}-{LDV_BAND_HZ[1]:g} "
            "Hz, zero phase).\n\n"
            + ("**The paper's ties taken literally (ring contact 'none') can not be run as a "
               "transient:** on frictionless pins nothing but its inertia holds the unit "
               "sideways, a start from rest would leave it drifting, and the solver refuses it "
               f"(`{literal}`). The transient therefore uses '{TRANSIENT_CONTACT}', compared "
               "with the harmonic solve of the same unit.\n\n"
               if literal is not None else
               "The solver accepts a transient of ring contact 'none' on pins.\n\n")
            + md_table(["analysis", "centre (um)", "edge (um)", "normalized (magnitude)",
                      "normalized (abs U_z)"], rows)
            + f"\n\nThe unit's mean displacement over the last revolution is "
              f"{t['centre_drift_um']:.3g} um, {drift:.0%} of its steady amplitude: "
            + ("small against its vibration: the rings hold the unit sideways. "
               if drift < 0.5 else "the unit drifts sideways, and a raw peak measures the "
                                   "drift. ")
            + "The raw peaks also contain the start-up transient, which the band-pass keeps "
              "(its frequencies are in the pass band).\n\n![transient](transient.png)")
    data = {"contact": TRANSIENT_CONTACT, "harmonic": [h.centre_um, h.edge_um, h.edge_z_um],
            "none_refused": literal}
    data.update({k: v for k, v in t.items() if not isinstance(v, list)})
    return Section("(e) Steady harmonic vs transient", text, data)



def check_mesh(r: Mapping[str, Solved], ctx: Context) -> Section | None:
    """Discretisation: halve the near-field element size."""
    if "triple/ACD/mesh0.25" not in r:
        return None
    h0, h1 = ctx.example(TRIPLE).mesh.near_size_mm, dict(MESH_VARIANT)["mesh.near_size_mm"]
    rows, data = [], {}
    for n in ("single/A", "triple/ACD"):
        a, b = r[n], r[f"{n}/mesh0.25"]
        data[n] = [a.norm, b.norm]
        rows.append([n, pct(a.norm), pct(b.norm), f"{b.norm / a.norm - 1:+.1%}",
                     um(a.edge_um), um(b.edge_um)])
    text = md_table(["case", f"normalized, {h0:g} mm", f"normalized, {h1:g} mm", "change",
                   f"edge um, {h0:g} mm", f"edge um, {h1:g} mm"], rows)
    return Section(f"(f) Mesh refinement (near-field element size {h0:g} -> {h1:g} mm)", text,
                   {"sizes_mm": [h0, h1], "normalized": data})


