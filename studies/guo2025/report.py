"""The report's Markdown: the model description, the warnings, the summary's closest-reading
statement and the page layout."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from fem import SOLVER_VERSION
from fem.materials import get_material
from fem.scene import RING_GAP_MM

from .cases import RING_CONTACTS, TRIPLE, Case, Context, case_scene, is_posed, refused_kinds
from .contact import CONTACT_DEFS, closest_text
from .paper import LETTERS, PAPER_TRIPLE_MAX, PAPER_TRIPLE_MIN
from .solved import Solved
from .text import REL_TOL, Section, design, md_table, near, pct

COMMAND = "hapticrom reproduce --out reports/reproduce"


def _model_text(r: Mapping[str, Solved], ctx: Context) -> str:
    scene, default = ctx.example(TRIPLE), ctx.default
    t, u, mesh = scene.tissue, scene.unit, scene.mesh
    m, pg, b = u.motor, u.pogo, u.board
    layers = case_scene(Case(TRIPLE)).tissue.layers  # what the cases solve, not the example
    damping = ("no damping" if all(ly.loss_factor == 0 for ly in layers)
               else "loss factors " + ", ".join(f"{ly.loss_factor:g}" for ly in layers))
    forearm = ", ".join(f"{ly.name} {ly.thickness_mm:g} mm / {ly.E_kPa:g} kPa" for ly in layers)
    sil = ", ".join(f"{c} {get_material(n).E_Pa / 1e3:g} kPa / {get_material(n).density_kg_m3:g}"
                    f" kg/m3 / nu {get_material(n).nu:g}" for c, n in LETTERS.items())
    order = {1: "linear", 2: "quadratic"}[mesh.order]
    side = ("absorbing side (PML in harmonic solves, a damping layer in transients)"
            if t.side == "absorbing" else f"{t.side} side")
    return (f"- Solver: hapticrom `fem` {SOLVER_VERSION}, axisymmetric Fourier-mode FE (mode 1 "
            f"for the rotating unbalance force), {order} elements, {mesh.near_size_mm:g} mm "
            f"within {mesh.near_radius_mm:g} mm of the axis and {mesh.far_size_mm:g} mm beyond, "
            f"{side}, bone bottom {t.base}; harmonic steady state at "
            f"{scene.analysis.frequency_hz:g} Hz. All defaults as in the shipped `unit-*.toml` "
            "scenes; "
            "nothing was tuned to the paper.\n"
            f"- Forearm (our reading of the paper's Table 1, {damping}): {forearm}.\n"
            f"- Silicones (library small-strain moduli, neo-Hookean from the Smooth-On 100 % "
            f"modulus, see `fem.materials`): {sil}.\n"
            f"- Motor (estimates, the paper gives none): {m.diameter_mm:g} x {m.height_mm:g} mm, "
            f"{m.mass_g:g} g, unbalance {m.unbalance_g_mm:g} g mm, rotor plane "
            f"{m.rotor_height_mm:g} mm above the base face (forward: base towards the skin), "
            f"{b.thickness_mm:g} mm flexible board (library material '{b.material}'). Pogo: "
            f"{pg.count} pins at {pg.radius_mm:g} mm, {pg.stiffness_N_m:g} N/m each, "
            f"{pg.length_mm:g} mm long, frictionless tips, smeared into a ring.\n"
            f"- Rings: {u.ring_thickness_mm:g} mm each, tied to each other and to the skin. "
            f"The inner ring meets the motor and board in ring contact **'{default}'** (our "
            "default): "
            + CONTACT_DEFS[default].format(gap=RING_GAP_MM)
            + ". On frictionless pins something must hold the unit sideways; with the paper's "
              "ties taken literally ('none') only its inertia does"
            + (f", and the solver refuses {refused_kinds(ctx.posed['none'])} solves of it"
               if not is_posed(ctx.posed["none"]) else "")
            + ". Section (g) compares every contact.\n"
            "- Centre amplitude: displacement magnitude of the unit's skin-side face on the axis; "
            "edge: the skin surface at the unit's outer radius; normalized edge = edge / centre. "
            "We also give the vertical component |U_z| at the edge over the same centre.\n"
            + _warnings_text(r))


def _warnings_text(r: Mapping[str, Solved]) -> str:
    lost = sorted(n for n, s in r.items() if s.contact and not s.contact["contact_maintained"])
    warned = sorted({w for s in r.values() for w in s.warnings})
    lines = []
    if lost:
        lines.append(f"- The linear pin model assumes the pins stay in contact; the dynamic pin "
                     f"force exceeds the preload in {len(lost)} case(s): "
                     + ", ".join(lost[:8]) + (" ..." if len(lost) > 8 else "") + ".")
    else:
        lines.append("- Every pogo case keeps its pins in contact (dynamic pin force below the "
                     "preload k x travel).")
    lines += [f"- Solver warning: {w}" for w in warned]
    return "\n".join(lines) + "\n"


def closest_summary(sections: Mapping[str, Section], checks: Mapping[str, Section],
                    ctx: Context) -> str:
    """The summary's plain statement: which model reading comes closest to the paper's 19 %
    and 90 %, whether it is physically posed, and what our default reading gives."""
    default, posed = ctx.default, ctx.posed
    tri = sections["triples"].data["magnitude"]
    n = len(sections["triples"].data["all"])
    text = (f"**Our default reading** (ring contact '{default}', centre = the unit's skin-side "
            f"face, edge magnitude): the triples span {pct(tri['min'][1])} "
            f"({design(tri['min'][0])}) - {pct(tri['max'][1])} ({design(tri['max'][0])}) over "
            f"all {n}, A-C-D {pct(tri['acd'])} (rank {tri['acd_rank']} of {n}); the paper: "
            f"{pct(PAPER_TRIPLE_MIN)} (A-C-D) - {pct(PAPER_TRIPLE_MAX)}.")
    if "g" not in checks:
        return text
    g = checks["g"].data
    k = len(g["triples"])
    posed_both = [(c, key) for c, per in g["readings"].items() for key, d in per.items()
                  if is_posed(posed[c]) and near(d["min"][1], PAPER_TRIPLE_MIN)
                  and near(d["max"][1], PAPER_TRIPLE_MAX)]
    return (text + f"\n\n**Which model reading comes closest to the paper's triples**, among "
            f"the {len(RING_CONTACTS)} ring contacts x {len(next(iter(g['readings'].values())))}"
            f" centre / edge readings, over the {k} triples solved under every contact (g):"
            + "\n\n" + closest_text(g["closest"], ctx) + "\n\n"
            + ("No physically posed reading comes within "
               f"{REL_TOL:.0%} of both {pct(PAPER_TRIPLE_MIN)} and {pct(PAPER_TRIPLE_MAX)}."
               if not posed_both else
               f"Physically posed readings within {REL_TOL:.0%} of both: "
               + ", ".join(f"*'{c}', {key}*" for c, key in posed_both) + ".")
            + " These readings were searched after seeing the default disagree: a match is a "
              "hypothesis about the paper's model, not agreement.")


def render(sections: Sequence[Section], checks: Sequence[Section], discussion: str,
           run: Mapping[str, Any], r: Mapping[str, Solved], model: str = "",
           summary_note: str = "") -> str:
    summary = [c for s in (*sections, *checks) for c in s.claims]
    head = ["# Reproducing Guo et al. 2025 with hapticrom", ""]
    if run["quick"]:
        head += ["> **Quick run** (`--quick`): a reduced set of cases for testing; the committed "
                 "report is the full run.", ""]
    head += [f"Generated by `{COMMAND}` (add `--workers N` to choose the pool size). Model "
             f"version `fem` {SOLVER_VERSION}. {run['n_solves']} distinct solves "
             f"({run['n_cases']} named cases) on {run['workers']} worker process(es): "
             f"**wall time {run['wall_s']:.1f} s** (sum of solve times {run['solve_s']:.1f} s).",
             "", "Paper: W. Guo et al., Optimization Design of Haptic Units for Perception Feedback"
             " Interfaces Based on Vibrotactile Amplitude Modulation, Biomimetics 10 (2025) 597, "
             "doi:10.3390/biomimetics10090597.", "",
             "Verdicts: *agrees* within the stated rule, *partly* when the direction holds but "
             "not the number, *disagrees* otherwise. Where two verdicts are given they are for "
             "the displacement magnitude / the vertical component.", "", "## Summary", "",
             md_table(["paper statement", "paper", "ours", "verdict"], summary), "",
             *([summary_note, ""] if summary_note else []),
             "## Model", "", model, "![orientation and pogo](structure.png)", ""]
    body = []
    for s in sections:
        body += [f"## {s.title}", "", s.text, ""]
    body += ["## Where we disagree, and why we think so", "", discussion, ""]
    for s in checks:
        body += [f"### {s.title}", "", s.text, ""]
    return "\n".join(head + body).rstrip() + "\n"

