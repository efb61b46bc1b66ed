"""Check (g): how the inner ring meets the motor (``unit.ring_contact``), under every reading of
the center and edge, and which (contact, reading) comes closest to the paper."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

from fem.scene import RING_GAP_MM

from .cases import RING_CONTACTS, Context, contact_name, is_posed, posed_text, refused_kinds
from .checks import readings
from .paper import LETTERS, PAPER_POGO_RATIO, PAPER_SINGLE_RANGE, PAPER_TRIPLE_MAX, PAPER_TRIPLE_MIN
from .solved import Solved
from .text import REL_TOL, Section, design, md_table, near, pct, um, verdict


def study_contact_triples(r: Mapping[str, Solved], triples: Sequence[str]) -> list[str]:
    """The triples solved under every ring contact, in the order of ``triples``."""
    return [t for t in triples
            if all(contact_name(f"triple/{t}", c) in r for c in RING_CONTACTS)]


def contact_readings(r: Mapping[str, Solved], triples: Sequence[str], contact: str) -> dict:
    """Per reading of :func:`readings` under one contact: the single layers' range, the
    triples' min and max ([design, value]), A-C-D's value and rank, and the factors
    min / 19 % and max / 90 % (1 = the paper's number)."""
    out = {}
    singles = [readings(r[contact_name(f"single/{c}", contact)]) for c in LETTERS]
    per = {t: readings(r[contact_name(f"triple/{t}", contact)]) for t in triples}
    for key in singles[0]:
        vals = {t: per[t][key] for t in triples}
        o = sorted(triples, key=vals.get)
        s = [x[key] for x in singles]
        out[key] = {"single": [min(s), max(s)], "min": [o[0], vals[o[0]]],
                    "max": [o[-1], vals[o[-1]]], "acd": vals.get("ACD", math.nan),
                    "acd_rank": o.index("ACD") + 1 if "ACD" in o else None,
                    "f_min": vals[o[0]] / PAPER_TRIPLE_MIN,
                    "f_max": vals[o[-1]] / PAPER_TRIPLE_MAX}
    return out


def _off(f: float) -> float:
    """How far a factor is from 1, the same for over and under (x2 and x0.5 both give 2)."""
    return max(f, 1.0 / f)


def closest_readings(table: Mapping[str, Mapping[str, dict]]) -> dict[str, dict]:
    """The (contact, reading) of ``table[contact][reading]`` (from :func:`contact_readings`)
    closest to the paper's most restraining triple (19 %: "min"), to its most enhancing
    (90 %: "max"), and to both at once ("both": product of the two distances)."""
    score = {"min": lambda d: _off(d["f_min"]), "max": lambda d: _off(d["f_max"]),
             "both": lambda d: _off(d["f_min"]) * _off(d["f_max"])}
    cells = [(c, k, d) for c, per in table.items() for k, d in per.items()]
    out = {}
    for target, f in score.items():
        c, k, d = min(cells, key=lambda x, f=f: f(x[2]))
        out[target] = {"contact": c, "reading": k, **d}
    return out


def contact_label(contact: str, default: str) -> str:
    tags = {"none": "the paper's ties, literally", "bonded": "cast on the motor"}
    tag = "our default" if contact == default else tags.get(contact, "")
    return f"'{contact}'" + (f" ({tag})" if tag else "")


def in_paper_single_range(v: float) -> bool:
    lo, hi = PAPER_SINGLE_RANGE
    return lo * (1 - REL_TOL) <= v <= hi * (1 + REL_TOL)


def contact_verdicts(d: Mapping[str, dict], k: int) -> dict[str, str]:
    """Verdicts of one contact's headline numbers (``d`` from :func:`contact_readings`, over
    ``k`` triples), by the rules of sections 3 and 4; "min", "max", "acd" as
    magnitude / abs U_z."""
    m, z = d["unit face / magnitude"], d["unit face / abs U_z"]

    def v_min(x: dict) -> str:
        return verdict(near(x["min"][1], PAPER_TRIPLE_MIN), x["min"][1] < x["single"][0])

    def v_max(x: dict) -> str:
        return verdict(near(x["max"][1], PAPER_TRIPLE_MAX), x["max"][1] > x["single"][1])

    def v_acd(x: dict) -> str:
        return verdict(x["acd_rank"] == 1, x["acd_rank"] is not None and x["acd_rank"] <= k / 4)

    inside = [in_paper_single_range(v) for v in m["single"]]
    return {"single": verdict(all(inside), any(inside)),
            "min": f"{v_min(m)} / {v_min(z)}", "max": f"{v_max(m)} / {v_max(z)}",
            "acd": f"{v_acd(m)} / {v_acd(z)}"}


CONTACT_DEFS = {
    "frictionless": "a snug fit that passes normal pressure but no shear: the radial "
                    "displacement of the ring's inner face is tied to the core's across a "
                    "{gap:g} mm slit over the core's height",
    "none": "no interaction: the paper's tie list taken literally (rings tied to each other "
            "and to the skin only), a {gap:g} mm slit between ring and core",
    "bonded": "cast around the motor and board: shared nodes, no slit"}


def check_ring_contact(r: Mapping[str, Solved], triples: Sequence[str], ctx: Context
                       ) -> Section | None:
    """(g) how the inner ring meets the motor: every ``unit.ring_contact`` for the single
    layers and the contact-study triples."""
    default, posed = ctx.default, ctx.posed
    study = study_contact_triples(r, triples)
    if not study:
        return None

    order = [default, *(c for c in RING_CONTACTS if c != default)]
    names = [*(f"single/{c}" for c in LETTERS), *(f"triple/{t}" for t in study), "acd/glued"]
    rows, cases = [], {}
    for n in names:
        sols = {c: r[contact_name(n, c)] for c in order}
        cases[n] = {c: {"centre_um": s.centre_um, "edge_um": s.edge_um, "normalized": s.norm,
                        "normalized_uz": s.norm_z, "edge_mm": s.edge_mm}
                    for c, s in sols.items()}
        rows.append([n, *(f"{um(s.centre_um)} um: {pct(s.norm)} / {pct(s.norm_z)}"
                          for s in sols.values())])
    table = {c: contact_readings(r, study, c) for c in order}
    k = len(study)
    claim_rows, verdicts, summary = [], {}, []
    for c in order:
        m, z = table[c]["unit face / magnitude"], table[c]["unit face / abs U_z"]
        ratio = (r[contact_name("triple/ACD", c)].edge_um
                 / r[contact_name("acd/glued", c)].edge_um)
        v = {**contact_verdicts(table[c], k), "posed": posed_text(posed[c]),
             "pogo": verdict(near(ratio, PAPER_POGO_RATIO), ratio < 1)}
        verdicts[c] = {**v, "pogo_ratio": ratio}
        claim_rows.append([
            contact_label(c, default), v["posed"],
            f"{pct(m['single'][0])} - {pct(m['single'][1])}: {v['single']}",
            f"{pct(m['min'][1])} ({design(m['min'][0])}) / {pct(z['min'][1])}: {v['min']}",
            f"{pct(m['max'][1])} ({design(m['max'][0])}) / {pct(z['max'][1])}: {v['max']}",
            f"{m['acd_rank']} of {k} ({pct(m['acd'])}): {v['acd']}",
            f"{ratio:.3f}: {v['pogo']}"])
        summary.append([f"triples, ring contact {contact_label(c, default)}"
                        + ("" if is_posed(posed[c]) else ", not physically posed on pins")
                        + " (g)",
                        f"{pct(PAPER_TRIPLE_MIN)} (A-C-D) - {pct(PAPER_TRIPLE_MAX)}",
                        f"{pct(m['min'][1])} ({design(m['min'][0])}) - {pct(m['max'][1])} "
                        f"({design(m['max'][0])}) over {k} triples; A-C-D {pct(m['acd'])}",
                        f"{v['min']} (min); {v['max']} (max)"])
    best = closest_readings(table)
    matrix = [[f"'{c}'", key, f"{pct(d['single'][0])} - {pct(d['single'][1])}",
               f"{pct(d['min'][1])} ({design(d['min'][0])})",
               f"{pct(d['max'][1])} ({design(d['max'][0])})", pct(d["acd"]),
               f"x{d['f_min']:.2f}", f"x{d['f_max']:.2f}"]
              for c in order for key, d in table[c].items()]
    edges = {c: r[contact_name("triple/ACD", c)].edge_mm for c in order}
    refused = posed["none"]
    text = ("How the inner silicone ring meets the motor and board (`unit.ring_contact`); the "
            "rings are always tied to each other and to the skin.\n\n"
            + "\n".join(f"- **{contact_label(c, default)}**: "
                        f"{CONTACT_DEFS[c].format(gap=RING_GAP_MM)}." for c in order)
            + "\n\nThe slit moves the unit's edge out (A-C-D edge: "
            + ", ".join(f"{edges[c]:g} mm {c}" for c in order) + ").\n\n"
            "**Why the default.** Pin tips are frictionless, so sideways a unit on pins is held "
            "only by what its rings pass. With 'none' nothing holds it: the harmonic solve "
            "exists (the unit's inertia balances the rotating force), but a free-floating unit "
            "is not a physically posed model of a worn device. 'frictionless' is the weakest "
            "contact that holds it; 'bonded' needs silicone cast on the motor, while the paper "
            "describes hollow cylinders placed around it. A bare unit on pins (sections 1 and 2) "
            f"has no rings at all; physically posed: {posed_text(posed['bare'])}."
            + ("" if is_posed(refused) else
               " What the solver says of A-C-D on pins with 'none':\n\n"
               + "\n".join(f"  - {kind}: `{msg}`" for kind, msg in refused.items()
                           if msg is not None))
            + "\n\n"
            + f"The triples studied here ({k}: " + ", ".join(design(t) for t in study)
            + ") are A-C-D, a fixed set, and the most restraining and most enhancing under the "
              f"default (section 4); minima, maxima and ranks below are over these {k} under "
              "every contact (all 64 are solved under the default only). Each cell: centre "
              "amplitude: normalized edge, magnitude / abs U_z.\n\n"
            + md_table(["case", *(contact_label(c, default) for c in order)], rows)
            + "\n\n" + md_table(
                ["ring contact", "physically posed on pins",
                 f"single layers (paper {pct(PAPER_SINGLE_RANGE[0])} - "
                 f"{pct(PAPER_SINGLE_RANGE[1])})",
                 f"most restraining, magnitude / abs U_z (paper {pct(PAPER_TRIPLE_MIN)})",
                 f"most enhancing, magnitude / abs U_z (paper {pct(PAPER_TRIPLE_MAX)})",
                 "A-C-D rank (paper: 1)",
                 f"A-C-D pogo / glued edge (paper {PAPER_POGO_RATIO:g})"], claim_rows)
            + "\n\nVerdicts by the rules of sections 2-4 (where two: magnitude / abs U_z).\n\n"
            + f"**Every reading.** Each contact with each reading of (b) (centre / edge "
              f"component); the factors are the triples' min over {pct(PAPER_TRIPLE_MIN)} "
              f"and max over {pct(PAPER_TRIPLE_MAX)} (x1 = the paper).\n\n"
            + f"<details><summary>{len(matrix)} readings</summary>\n\n"
            + md_table(["contact", "reading", "single layers", "triples: min", "triples: max",
                      "A-C-D", f"min / {pct(PAPER_TRIPLE_MIN)}",
                      f"max / {pct(PAPER_TRIPLE_MAX)}"], matrix)
            + "\n\n</details>\n\n**Closest to the paper.**\n\n" + closest_text(best, ctx)
            + "\n\n![ring contact](ring_contact.png)")
    data = {"default": default, "triples": study, "cases": cases, "readings": table,
            "verdicts": verdicts, "closest": best,
            "posed": {c: dict(p) for c, p in posed.items()}}
    return Section("(g) How the inner ring meets the motor (ring contact)", text, data, summary)


def closest_text(best: Mapping[str, dict], ctx: Context) -> str:
    """Which (contact, reading) comes closest to the paper's 19 % and 90 %, and whether its
    contact is physically posed on pins: a Markdown list."""
    default, posed = ctx.default, ctx.posed

    def one(d: dict, what: str) -> str:
        c = d["contact"]
        posed_note = ("physically posed." if is_posed(posed[c]) else
                      "**not physically posed**: the unit floats sideways on its pins, and the "
                      f"solver refuses its {refused_kinds(posed[c])} solves.")
        return (f"*ring contact '{c}'{' (our default)' if c == default else ''}, "
                f"{d['reading']}*: {what}; {posed_note}")

    lo, hi, both = best["min"], best["max"], best["both"]
    return "\n".join([
        f"- Closest to the paper's {pct(PAPER_TRIPLE_MIN)}: "
        + one(lo, f"most restraining {pct(lo['min'][1])} ({design(lo['min'][0])}), A-C-D "
                  f"{pct(lo['acd'])}"),
        f"- Closest to its {pct(PAPER_TRIPLE_MAX)}: "
        + one(hi, f"most enhancing {pct(hi['max'][1])} ({design(hi['max'][0])})"),
        "- Closest to both at once: "
        + one(both, f"{pct(both['min'][1])} ({design(both['min'][0])}) - "
                    f"{pct(both['max'][1])} ({design(both['max'][0])})")])

