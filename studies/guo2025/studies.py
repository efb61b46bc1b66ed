"""The paper's studies, one report section each: 1 orientation (Fig. 8a), 2 pogo pins (Fig. 8b),
3 single layers (Fig. 9a), 4 all ordered triples (Fig. 9b/c), 5 the encapsulation sweeps
(Tables 2-4), 6 context the paper has no FE number for. Amplitudes in um, fractions printed in %.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import numpy as np

from fem.materials import Material, get_material

from .cases import (
    BARE,
    ELASTICITY_STEP,
    MOTOR_VARIANTS,
    TRIPLE,
    Context,
    common_value,
    is_posed,
    ranked,
    refused_kinds,
    sweep_point,
    uniform_name,
)
from .paper import (
    COMMON,
    LETTERS,
    PAPER_POGO_RATIO,
    PAPER_R2,
    PAPER_SINGLE_RANGE,
    PAPER_TPD_MM,
    PAPER_TRIPLE_MAX,
    PAPER_TRIPLE_MIN,
)
from .solved import Solved
from .text import REL_TOL, Section, design, md_table, near, pct, um, verdict

# --------------------------------------------------------------------------- studies


def rotor_mm(ctx: Context) -> tuple[float, float]:
    """Rotor plane above the base face (mm): the example's and the sensitivity's."""
    return (ctx.example(BARE).unit.motor.rotor_height_mm,
            dict(MOTOR_VARIANTS["rotor0.6"])["unit.motor.rotor_height_mm"])


def study_orientation(r: Mapping[str, Solved], ctx: Context) -> Section:
    rows, data = [], {}
    rotor, alt = rotor_mm(ctx)
    for a in ("glued", "pogo"):
        for tag, label in (("", f"default (rotor {rotor:g} mm above base)"),
                           ("/rotor0.6", f"sensitivity: rotor {alt:g} mm above base")):
            fwd, rev = r.get(f"bare/forward/{a}{tag}"), r.get(f"bare/reverse/{a}{tag}")
            if fwd is None or rev is None:
                continue
            ratio = rev.centre_um / fwd.centre_um
            data[f"{a}{tag}"] = {"forward_centre_um": fwd.centre_um,
                                 "reverse_centre_um": rev.centre_um, "ratio": ratio}
            rows.append([a, label, um(fwd.centre_um), um(rev.centre_um), f"{ratio:.3f}",
                         "reverse > forward", verdict(ratio > 1) + ("" if not tag else
                                                                     " (sensitivity)")])
    text = ("Bare motor (no rings), centre amplitude = displacement magnitude of the unit's "
            "skin-side face on the axis (um).\n\n" + md_table(
                ["attachment", "motor", "forward centre (um)", "reverse centre (um)",
                 "reverse / forward", "paper (Fig. 8a)", "verdict"], rows))
    claims = [[f"reverse gives a larger centre amplitude ({a}, bare)", "reverse > forward",
               f"reverse / forward = {data[a]['ratio']:.3f}", verdict(data[a]["ratio"] > 1)]
              for a in ("glued", "pogo")]
    return Section("1. Motor orientation (Fig. 8a)", text, data, claims)


def study_pogo(r: Mapping[str, Solved], ctx: Context) -> Section:
    default, posed = ctx.default, ctx.posed
    pairs = [("bare, reverse (the study)", "bare/reverse/glued", "bare/reverse/pogo", True),
             ("bare, forward (context)", "bare/forward/glued", "bare/forward/pogo", False),
             (f"A-C-D, reverse, ring contact '{default}' (context)", "acd/glued", "triple/ACD",
              False)]
    rows, data, claims = [], {}, []
    for label, g_name, p_name, main in pairs:
        g, p = r[g_name], r[p_name]
        ratio, ratio_z = p.edge_um / g.edge_um, p.edge_z_um / g.edge_z_um
        data[label] = {"glued_edge_um": g.edge_um, "pogo_edge_um": p.edge_um, "ratio": ratio,
                       "ratio_uz": ratio_z, "glued_centre_um": g.centre_um,
                       "pogo_centre_um": p.centre_um}
        v = verdict(near(ratio, PAPER_POGO_RATIO), ratio < 1)
        vz = verdict(near(ratio_z, PAPER_POGO_RATIO), ratio_z < 1)
        if main:
            claims = [["pogo pins halve the edge amplitude (bare, reverse)", "x0.5",
                       f"x{ratio:.3f} (abs U_z: x{ratio_z:.3f})", f"{v} / {vz}"]]
        rows.append([label, um(g.edge_um), um(p.edge_um), f"{ratio:.3f}", f"{ratio_z:.3f}",
                     um(g.centre_um), um(p.centre_um), f"{PAPER_POGO_RATIO:g}",
                     f"{v} / {vz}" if main else f"({v} / {vz})"])
    text = ("Edge amplitude (skin at the unit's outer radius, um) glued vs on pogo pins. Verdict "
            f"rule: agrees if within {REL_TOL:.0%} of 0.5, partly if pogo still lowers the edge, "
            "else disagrees; given for the magnitude / the vertical component.\n\n" + md_table(
                ["design", "glued edge (um)", "pogo edge (um)", "pogo / glued (magnitude)",
                 "pogo / glued (abs U_z)", "glued centre (um)", "pogo centre (um)",
                 "paper (Fig. 8b)", "verdict"], rows)
            + "\n\nThe bare unit has no rings, so on frictionless pins only its inertia holds "
              "it sideways. The harmonic solve is well defined"
            + (f", but the solver refuses {refused_kinds(posed['bare'])} solves of it"
               if not is_posed(posed["bare"]) else "")
            + ". Section (g) gives the A-C-D ratio under every ring contact.")
    return Section("2. Pogo pins (Fig. 8b)", text, data, claims)


def _material_row(letter: str) -> tuple[float, float, float]:
    m = get_material(LETTERS[letter])
    return m.E_Pa / 1e3, m.density_kg_m3, m.nu


def range_verdict(values: Sequence[float], lo: float, hi: float) -> str:
    inside = [lo * (1 - REL_TOL) <= v <= hi * (1 + REL_TOL) for v in values]
    return verdict(all(inside), any(inside))


def _ring_mm(ctx: Context) -> float:
    return ctx.example(TRIPLE).unit.ring_thickness_mm


def study_single(r: Mapping[str, Solved], ctx: Context) -> Section:
    default = ctx.default
    rows, data = [], {}
    for letter in LETTERS:
        s = r[f"single/{letter}"]
        E, rho, nu = _material_row(letter)
        data[letter] = {"material": LETTERS[letter], "centre_um": s.centre_um,
                        "edge_um": s.edge_um, "normalized": s.norm, "normalized_uz": s.norm_z}
        rows.append([letter, LETTERS[letter], f"{E:g}", f"{rho:g}", f"{nu:g}", um(s.centre_um),
                     um(s.edge_um), pct(s.norm), pct(s.norm_z)])
    mags = [data[c]["normalized"] for c in LETTERS]
    verts = [data[c]["normalized_uz"] for c in LETTERS]
    lo, hi = PAPER_SINGLE_RANGE
    claim = [["normalized edge, single layers", f"{pct(lo)} - {pct(hi)}",
              f"{pct(min(mags))} - {pct(max(mags))}", f"{pct(min(verts))} - {pct(max(verts))}",
              f"{range_verdict(mags, lo, hi)} / {range_verdict(verts, lo, hi)}"],
             ["spread across materials", f"{pct(hi - lo)} points",
              f"{pct(max(mags) - min(mags))} points", f"{pct(max(verts) - min(verts))} points",
              "(context)"]]
    text = (f"Forward motor, glued, one {_ring_mm(ctx):g} mm ring (library small-strain moduli, "
            f"see Model), ring contact '{default}' (the default; (g) gives the others). "
            "Normalized edge = amplitude at the edge / centre magnitude.\n\n"
            + md_table(["layer", "material", "E (kPa)", "density (kg/m3)", "nu", "centre (um)",
                      "edge (um)", "normalized (magnitude)", "normalized (abs U_z)"], rows)
            + "\n\n" + md_table(["claim", "paper (Fig. 9a)", "ours (magnitude)",
                               "ours (abs U_z)", "verdict (magnitude / U_z)"], claim)
            + f"\n\nVerdict rule: agrees if every material lies in the paper's range widened by "
              f"{REL_TOL:.0%}, partly if some do.\n\n![single layers](single_layers.png)")
    c = claim[0]
    return Section("3. Single layers A-D (Fig. 9a)", text, data,
                   [[c[0], c[1], f"{c[2]} (abs U_z: {c[3]})", c[4]]])



def study_triples(r: Mapping[str, Solved], triples: Sequence[str], ctx: Context) -> Section:
    default = ctx.default
    singles = [r[f"single/{c}"] for c in LETTERS]
    out, claims = {}, []
    for vertical in (False, True):
        order = ranked(r, triples, vertical)

        def val(t: str, v: bool = vertical) -> float:
            s = r[f"triple/{t}"]
            return s.norm_z if v else s.norm
        s_vals = [s.norm_z if vertical else s.norm for s in singles]
        out["uz" if vertical else "magnitude"] = {
            "min": [order[0], val(order[0])], "max": [order[-1], val(order[-1])],
            "acd_rank": order.index("ACD") + 1 if "ACD" in order else None,
            "acd": val("ACD") if "ACD" in order else None, "single_min": min(s_vals),
            "single_max": max(s_vals)}
    m, z = out["magnitude"], out["uz"]
    n = len(triples)

    def v_min(d: dict) -> str:
        return verdict(near(d["min"][1], PAPER_TRIPLE_MIN), d["min"][1] < d["single_min"])

    def v_max(d: dict) -> str:
        return verdict(near(d["max"][1], PAPER_TRIPLE_MAX), d["max"][1] > d["single_max"])

    def v_acd(d: dict) -> str:
        return verdict(d["acd_rank"] == 1, d["acd_rank"] is not None and d["acd_rank"] <= n / 4)

    def v_span(d: dict) -> str:
        lo, hi = d["min"][1] < d["single_min"], d["max"][1] > d["single_max"]
        return verdict(lo and hi, lo or hi)

    claims = [
        ["most restraining triple, normalized edge", pct(PAPER_TRIPLE_MIN),
         f"{pct(m['min'][1])} ({design(m['min'][0])})",
         f"{pct(z['min'][1])} ({design(z['min'][0])})", f"{v_min(m)} / {v_min(z)}"],
        ["the most restraining triple is A-C-D", "A-C-D (layers 1-2-3)",
         f"A-C-D ranks {m['acd_rank']} of {n} ({pct(m['acd'])})",
         f"A-C-D ranks {z['acd_rank']} of {n} ({pct(z['acd'])})", f"{v_acd(m)} / {v_acd(z)}"],
        ["most enhancing triple, normalized edge", pct(PAPER_TRIPLE_MAX),
         f"{pct(m['max'][1])} ({design(m['max'][0])})",
         f"{pct(z['max'][1])} ({design(z['max'][0])})", f"{v_max(m)} / {v_max(z)}"],
        ["triples both restrain and enhance beyond single layers",
         f"{pct(PAPER_TRIPLE_MIN)} - {pct(PAPER_TRIPLE_MAX)} vs single "
         f"{pct(PAPER_SINGLE_RANGE[0])} - {pct(PAPER_SINGLE_RANGE[1])}",
         f"{pct(m['min'][1])} - {pct(m['max'][1])} vs single {pct(m['single_min'])} - "
         f"{pct(m['single_max'])}",
         f"{pct(z['min'][1])} - {pct(z['max'][1])} vs single {pct(z['single_min'])} - "
         f"{pct(z['single_max'])}", f"{v_span(m)} / {v_span(z)}"],
    ]
    order = ranked(r, triples, False)
    order_z = ranked(r, triples, True)
    rows = []
    for i, t in enumerate(order, 1):
        s = r[f"triple/{t}"]
        rows.append([i, design(t), um(s.centre_um), um(s.edge_um), pct(s.norm),
                     pct(s.norm_z), order_z.index(t) + 1])
    out["all"] = {t: {"centre_um": r[f"triple/{t}"].centre_um,
                      "edge_um": r[f"triple/{t}"].edge_um, "normalized": r[f"triple/{t}"].norm,
                      "normalized_uz": r[f"triple/{t}"].norm_z} for t in triples}
    text = (f"Reverse motor on pogo pins, three {_ring_mm(ctx):g} mm rings, ring contact "
            f"'{default}' (the default; (g) gives the others for a subset), every ordered "
            f"triple of A-D ({n} designs; layer 1 is the innermost). Verdict rules: a number "
            f"agrees within {REL_TOL:.0%} of the paper's; the minimum is 'partly' if it still "
            "restrains below every single layer, the maximum if it still enhances above them; "
            "A-C-D is 'partly' the most restraining if it ranks in the lowest quarter.\n\n"
            + md_table(["claim", "paper (Fig. 9b/c)", "ours (magnitude)", "ours (abs U_z)",
                      "verdict (magnitude / U_z)"], claims)
            + "\n\n![triples](triples.png)\n\n<details><summary>All triples, ranked by the "
              "normalized edge (magnitude)</summary>\n\n"
            + md_table(["rank", "layers 1-2-3", "centre (um)", "edge (um)",
                      "normalized (magnitude)", "normalized (abs U_z)", "rank by U_z"], rows)
            + "\n\n</details>")
    summary = [[c[0], c[1], f"{c[2]} (abs U_z: {c[3]})", c[4]] for c in claims]
    return Section("4. All ordered triples (Fig. 9b/c)", text, out, summary)


_SWEEP_LABEL = {"density": ("density", "kg/m3", "Table 2"), "E": ("Young's modulus", "kPa",
                                                                  "Table 3"),
                "nu": ("Poisson's ratio", "-", "Table 4")}


def _sweep_rows(r: Mapping[str, Solved], name: str, values: Sequence[float]) -> list[list]:
    rows = []
    for i, x in enumerate(values):
        point = sweep_point(name, x)
        s = r[uniform_name(*point)]
        rows.append([chr(ord("A") + i), f"{point[0]:g}", f"{point[1]:g}", f"{point[2]:g}",
                     um(s.centre_um), um(s.edge_um), pct(s.norm), pct(s.norm_z)])
    return rows


def sweep_measures(r: Mapping[str, Solved], name: str, values: Sequence[float]) -> dict:
    """Fair-comparison measures of one table: spreads (max/min over its rows) of the edge
    amplitude and of the normalized edge, the end-to-end log slope over the table's range, and
    the local log-log sensitivity d ln y / d ln x at the common point (central difference)."""
    sols = [r[uniform_name(*sweep_point(name, x))] for x in values]
    edge = np.array([s.edge_um for s in sols])
    norm = np.array([s.norm for s in sols])
    x_ratio = max(values) / min(values)
    c = common_value(name)
    up = r[uniform_name(*sweep_point(name, c * ELASTICITY_STEP))]
    dn = r[uniform_name(*sweep_point(name, c / ELASTICITY_STEP))]
    h = 2 * math.log(ELASTICITY_STEP)
    i_lo, i_hi = int(np.argmin(values)), int(np.argmax(values))
    return {
        "x_ratio": x_ratio,
        "edge_spread": float(edge.max() / edge.min()),
        "norm_spread": float(norm.max() / norm.min()),
        "edge_slope_over_range": float(math.log(edge[i_hi] / edge[i_lo]) / math.log(x_ratio)),
        "edge_elasticity": math.log(up.edge_um / dn.edge_um) / h,
        "norm_elasticity": math.log(up.norm / dn.norm) / h,
        "edge_um": edge.tolist(), "normalized": norm.tolist(), "x": [float(x) for x in values],
    }


def study_sweeps(r: Mapping[str, Solved], sweeps: Mapping[str, Sequence[float]]) -> Section:
    parts, data = [], {}
    for name, values in sweeps.items():
        label, unit, table = sweep_label(name)
        parts.append(f"**{table}: {label} ({unit})**, all three rings carry each row.\n\n"
                     + md_table(["row", "density (kg/m3)", "E (kPa)", "nu", "centre (um)",
                               "edge (um)", "normalized (magnitude)", "normalized (abs U_z)"],
                              _sweep_rows(r, name, values)))
        data[name] = sweep_measures(r, name, values)
    measures = [("edge_spread", "edge amplitude max/min over the table"),
                ("norm_spread", "normalized edge max/min over the table"),
                ("edge_elasticity", "d ln(edge) / d ln(x) at 1000 kg/m3, 355 kPa, 0.47"),
                ("norm_elasticity", "d ln(normalized) / d ln(x) at the same point")]
    rows = [[sweep_label(n)[0], f"{data[n]['x_ratio']:.3g}"]
            + [f"{data[n][k]:.3g}" for k, _ in measures]
            + [f"{data[n]['edge_slope_over_range']:.3g}"] for n in sweeps]
    verdicts = []
    for key, label in measures:
        order = sorted(sweeps, key=lambda n, k=key: -abs(math.log(data[n][k]))
                       if "spread" in k else -abs(data[n][k]))
        ranking = " > ".join(sweep_label(n)[0] for n in order)
        verdicts.append([label, "density matters most", ranking,
                         verdict(order[0] == "density")])
        data[f"ranking_{key}"] = order
    width = ", ".join(f"{sweep_label(n)[0]} x{data[n]['x_ratio']:.3g}" for n in sweeps)
    widest = sweep_label(max(sweeps, key=lambda n: data[n]["x_ratio"]))[0]
    text = ("\n\n".join(parts) + "\n\n![sweeps](sweeps.png)\n\n"
            + "**Which parameter matters most.**\n\n"
            + md_table(["parameter", "table range x_max/x_min", *[m[1] for m in measures],
                      "end-to-end slope ln(edge ratio)/ln(x ratio)"], rows)
            + "\n\n" + md_table(["measure", "paper", "ours (ranking)", "verdict"], verdicts)
            + f"\n\nThe tables span very different ranges ({width}). The spread over a table "
              "rewards a wide range, so spreads favour the parameter with the widest table "
              f"({widest}) before any physics. "
              "The log-log sensitivity compares the parameters per relative change at one "
              "common point and is blind to the ranges; it is the fairer measure of "
              "'influence', the spread the fairer measure of what the paper's own tables can "
              + _bulk_text(sweeps))
    claims = [[f"density matters most, by {v[0]}", v[1], v[2], v[3]] for v in verdicts]
    return Section("5. Density, modulus and Poisson's ratio (Tables 2-4, Figs. 10-12)", text,
                   data, claims)


def _bulk_text(sweeps: Mapping[str, Sequence[float]]) -> str:
    """The end of the sweep discussion: how far the Poisson table moves the bulk modulus."""
    if "nu" not in sweeps:
        return "show."

    lo, hi = min(sweeps["nu"]), max(sweeps["nu"])
    E_Pa, rho = COMMON[1] * 1e3, COMMON[0]
    k_ratio = (Material("hi", E_Pa, rho, hi).bulk_Pa / Material("lo", E_Pa, rho, lo).bulk_Pa)
    return ("show. Poisson's ratio acts through the bulk modulus K = E / (3 (1 - 2 nu)), which "
            f"changes x{k_ratio:.3g} between nu = {lo:g} and {hi:g} although nu itself changes "
            f"only x{hi / lo:.3g}.")


def sweep_label(name: str) -> tuple[str, str, str]:
    return _SWEEP_LABEL[name]


def crosstalk_distance(s: Solved, fraction: float) -> float:
    """Distance from the edge (mm) beyond which the skin magnitude stays below ``fraction`` of
    the centre amplitude, linearly interpolated; 0 if already below at the edge, inf if not
    below by the end of the profile."""
    y, d = s.normalized_profile(), s.profile_mm
    above = np.flatnonzero(y >= fraction)
    if above.size == 0:
        return 0.0
    i = above[-1]
    if i == y.size - 1:
        return math.inf
    return float(d[i] + (y[i] - fraction) / (y[i] - y[i + 1]) * (d[i + 1] - d[i]))


def _at_distance(s: Solved, mm: float) -> float:
    return float(np.interp(mm, s.profile_mm, s.normalized_profile()))


def study_context(r: Mapping[str, Solved], ctx: Context) -> Section:
    default = ctx.default
    protos = [("1: bare, forward, glued", "proto/bare"),
              ("2: A-D double, forward, glued", "proto/double"),
              ("3: A-C-D triple, reverse, pogo", "proto/triple")]
    rows, data = [], {}
    length = float(r["proto/triple"].profile_mm[-1])
    for label, name in protos:
        s = r[name]
        d50, d25 = crosstalk_distance(s, 0.5), crosstalk_distance(s, 0.25)
        at = _at_distance(s, PAPER_TPD_MM)
        data[label] = {"centre_um": s.centre_um, "edge_um": s.edge_um, "normalized": s.norm,
                       "d50_mm": d50, "d25_mm": d25, "at_tpd": at}
        rows.append([label, um(s.centre_um), um(s.edge_um), pct(s.norm),
                     _fmt_mm(d50, length), _fmt_mm(d25, length), pct(at)])
    claims = [["FE vs laser Doppler vibrometer on a phantom", f"R^2 = {PAPER_R2}",
               "not reproducible: a measurement on their phantom; we have no data"],
              ["two-point discrimination, optimized unit, successive stimuli",
               f"{PAPER_TPD_MM} mm (vs 13 mm earlier), p < 0.01",
               "not reproducible: a perception experiment with 10 people"]]
    text = (md_table(["paper item", "paper", "ours"], claims)
            + "\n\n**Crosstalk proxy (ours, not in the paper).** For the three prototype designs:"
              " the distance from the unit's edge beyond which the skin amplitude (magnitude) "
              f"stays below 50 % / 25 % of the unit's centre amplitude (within the {length:g} mm "
              f"profile), and the amplitude at {PAPER_TPD_MM:g} mm from the edge (the paper's "
              "threshold) over the centre; rings in ring contact "
              f"'{default}'. A proxy for how far a neighbour must sit, not a perception model.\n\n"
            + md_table(["design", "centre (um)", "edge (um)", "normalized edge", "below 50 % from",
                      "below 25 % from", f"at {PAPER_TPD_MM:g} mm"], rows))
    text += "\n\n" + _damping_text(r, protos)
    summary = [[c[0], c[1], c[2], "not reproducible"] for c in claims]
    return Section("6. Context the paper has no FE number for", text, data, summary)


def _damping_text(r: Mapping[str, Solved], protos: Sequence[tuple[str, str]]) -> str:
    """The damping sensitivity: each prototype undamped (the paper's reading) against the
    library's sourced tissue and silicone loss factors."""
    rows = []
    for label, name in protos:
        s, d = r[name], r[f"{name}/damped"]
        rows.append([label, um(s.centre_um), um(d.centre_um), um(s.edge_um), um(d.edge_um),
                     pct(s.norm), pct(d.norm)])
    return ("**Damping sensitivity (ours, not in the paper).** The paper's model is undamped, "
            "and so is every case above. Living tissue is lossy at these frequencies; with the "
            "library's loss factors (soft tissue 0.3, bone 0.02, silicone 0.1; sources in "
            "`fem.materials` and docs/materials.md):\n\n"
            + md_table(["design", "centre undamped (um)", "centre damped (um)",
                        "edge undamped (um)", "edge damped (um)", "normalized undamped",
                        "normalized damped"], rows))


def _fmt_mm(x: float, length: float) -> str:
    if x == 0:
        return "0 (below at the edge)"
    return f"> {length:g} mm" if math.isinf(x) else f"{x:.1f} mm"


# --------------------------------------------------------------------------- disagreement checks

