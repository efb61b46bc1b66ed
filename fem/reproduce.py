"""Re-run the studies of Guo et al. 2025 (Biomimetics 10:597) and put our numbers beside theirs.

Every study is a set of harmonic steady-state solves at 120 Hz on the default forearm, each scene
built from one of ``examples/unit-*.toml`` by ``scene_to_dict`` + edits + ``scene_from_dict``
(the defaults are never tuned). The solves run in a process pool; the report (Markdown, PNG
figures and a JSON of every number) is built in a temporary directory and moved into place.

Studies (PAPER.md, "Results to reproduce"):
  1. orientation: forward vs reverse, bare motor, glued and pogo (Fig. 8a);
  2. pogo pins: glued vs pogo, reverse, bare (Fig. 8b: edge amplitude halved);
  3. single layers A-D, forward, glued (Fig. 9a: normalized edge 50-58 %);
  4. all 64 ordered triples of A-D, reverse + pogo (Fig. 9b/c: 19 % for A-C-D to 90 %);
  5. density / modulus / Poisson sweeps, three equal rings, reverse + pogo (Tables 2-4);
  6. context: the three prototype designs and a crosstalk proxy (ours, not the paper's).
Checks of why we might disagree: amplitude definition (magnitude vs vertical), centre
definition, motor parameters, the pogo-pin smearing, steady vs transient, mesh refinement.

Units: amplitudes in um, distances in mm, normalized values as fractions (printed in %).
"""

from __future__ import annotations

import itertools
import json
import math
import os
import shutil
import tempfile
import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from . import SOLVER_VERSION

EXAMPLES_DIR = Path(__file__).resolve().parent.parent / "examples"
BARE = "unit-bare-forward.toml"
DOUBLE = "unit-double-forward.toml"
TRIPLE = "unit-triple-reverse-pogo.toml"
COMMAND = "hapticrom reproduce --out reports/reproduce"

LETTERS: dict[str, str] = {
    "A": "ecoflex-00-10",
    "B": "ecoflex-00-50",
    "C": "dragon-skin-10-medium",
    "D": "dragon-skin-30",
}
PROFILE_STEP_MM = 0.25  # output sampling only (the mesh does not depend on it)

# The paper's statements and numbers (Sec. 3.2-3.4, Tables 2-4).
PAPER_POGO_RATIO = 0.5
PAPER_SINGLE_RANGE = (0.50, 0.58)
PAPER_TRIPLE_MIN = 0.19
PAPER_TRIPLE_MIN_DESIGN = "ACD"
PAPER_TRIPLE_MAX = 0.90
PAPER_R2 = 0.9831
PAPER_TPD_MM = 8.6
TABLE2_DENSITY = (1000.0, 2000.0, 4000.0)
TABLE3_E_KPA = (15.0, 100.0, 268.0, 355.0, 900.0, 1200.0, 3600.0)
TABLE4_NU = (0.2, 0.33, 0.47)
COMMON = (1000.0, 355.0, 0.47)  # density kg/m3, E kPa, nu: the point all three tables share
ELASTICITY_STEP = 1.05  # x * 1.05**(+-1) for the central log-log derivative
REL_TOL = 0.20  # "agrees" with a paper number: within 20 % of it (stated in the report)

# Sensitivity to what the paper does not give (edits on top of each case).
MOTOR_VARIANTS: dict[str, tuple[tuple[str, Any], ...]] = {
    "rotor0.6": (("unit.motor.rotor_height_mm", 0.6),),
    "mass0.3": (("unit.motor.mass_g", 0.3),),
    "mass1.2": (("unit.motor.mass_g", 1.2),),
}
POGO_VARIANTS: dict[str, tuple[tuple[str, Any], ...]] = {
    "tip0.25": (("unit.pogo.tip_diameter_mm", 0.25),),
    "tip1": (("unit.pogo.tip_diameter_mm", 1.0),),
    "k0.5": (("unit.pogo.stiffness_N_m", 1471.0),),
    "k2": (("unit.pogo.stiffness_N_m", 5884.0),),
}
MESH_VARIANT = (("mesh.near_size_mm", 0.25),)
TRANSIENT_MS = 50.0  # the paper's run length is not given; 6 revolutions at 120 rev/s


# --------------------------------------------------------------------------- cases and scenes


@dataclass(frozen=True)
class Case:
    """One scene: an example file plus edits (dotted path -> value); ``transient`` runs the
    time-domain solver instead (constant speed from rest, the paper's 0.05 ms step)."""

    base: str
    edits: tuple[tuple[str, Any], ...] = ()
    transient: bool = False


def _set(d: dict, path: str, value: Any) -> None:
    *head, last = path.split(".")
    for key in head:
        d = d.setdefault(key, {})
    d[last] = value


def scene_dict(case: Case, examples_dir: Path = EXAMPLES_DIR) -> dict:
    """The TOML-shaped dict of ``case``: its example, the edits, the fine profile sampling."""
    from .scene import load_scene, scene_to_dict

    d = scene_to_dict(load_scene(Path(examples_dir) / case.base))
    _set(d, "output.profile_step_mm", PROFILE_STEP_MM)
    for path, value in case.edits:
        _set(d, path, value)
    if d["unit"]["attachment"] == "pogo" and not case.transient:
        _set(d, "effects.preload", True)  # report whether the pins stay in contact
    if case.transient:
        d["analysis"].update(kind="transient", duration_ms=TRANSIENT_MS,
                             voltage_schedule=[[0.0, d["unit"]["motor"]["rated_voltage_V"]]])
        _set(d, "effects.spin_up", False)  # the paper turns the mass at 120 rev/s from t = 0
    return d


def _rings(letters: str) -> list[str]:
    return [LETTERS[c] for c in letters]


def bare_case(orientation: str, attachment: str, extra=()) -> Case:
    return Case(BARE, (("unit.orientation", orientation), ("unit.attachment", attachment),
                       ("unit.encapsulation", []), *extra))


def single_case(letter: str, extra=()) -> Case:
    return Case(BARE, (("unit.orientation", "forward"), ("unit.attachment", "glued"),
                       ("unit.encapsulation", _rings(letter)), *extra))


def triple_case(letters: str, extra=()) -> Case:
    return Case(TRIPLE, (("unit.orientation", "reverse"), ("unit.attachment", "pogo"),
                         ("unit.encapsulation", _rings(letters)), *extra))


def uniform_case(density: float, E_kPa: float, nu: float) -> Case:
    """Three equal rings carrying one row of Tables 2-4, reverse + pogo."""
    ring = {"name": "table", "E_kPa": E_kPa, "density_kg_m3": density, "nu": nu,
            "loss_factor": 0.0}
    return Case(TRIPLE, (("unit.orientation", "reverse"), ("unit.attachment", "pogo"),
                         ("unit.encapsulation", [dict(ring) for _ in range(3)])))


def uniform_name(density: float, E_kPa: float, nu: float) -> str:
    return f"uniform/rho{density:g}/E{E_kPa:g}/nu{nu:g}"


@dataclass(frozen=True)
class Plan:
    """Named cases (several names may be one scene) and the triples studied."""

    cases: dict[str, Case]
    triples: tuple[str, ...]
    sweeps: dict[str, tuple[float, ...]]
    quick: bool


def plan(quick: bool = False) -> Plan:
    """Every case of the reproduction; ``quick`` keeps a reduced set (4 triples, sweep end
    points, no motor/pogo/mesh sensitivities, no transient) for tests."""
    c: dict[str, Case] = {}
    for o, a in itertools.product(("forward", "reverse"), ("glued", "pogo")):
        c[f"bare/{o}/{a}"] = bare_case(o, a)
    for letter in LETTERS:
        c[f"single/{letter}"] = single_case(letter)
    triples = (("AAA", "ACD", "DCA", "DDD") if quick
               else tuple("".join(t) for t in itertools.product(LETTERS, repeat=3)))
    for t in triples:
        c[f"triple/{t}"] = triple_case(t)
    c["acd/glued"] = Case(TRIPLE, (("unit.attachment", "glued"),))
    c["proto/bare"] = Case(BARE)
    c["proto/double"] = Case(DOUBLE)
    c["proto/triple"] = Case(TRIPLE)
    sweeps = {"density": TABLE2_DENSITY, "E": TABLE3_E_KPA, "nu": TABLE4_NU}
    if quick:
        sweeps = {k: (v[0], v[-1]) for k, v in sweeps.items()}
    for name, values in sweeps.items():
        for x in values:
            point = _sweep_point(name, x)
            c[uniform_name(*point)] = uniform_case(*point)
    for name in sweeps:  # the log-log derivative at the common point
        for s in (ELASTICITY_STEP, 1.0 / ELASTICITY_STEP):
            point = _sweep_point(name, _common_value(name) * s)
            c[uniform_name(*point)] = uniform_case(*point)
    if not quick:
        _add_sensitivities(c)
    return Plan(c, triples, sweeps, quick)


def _add_sensitivities(c: dict[str, Case]) -> None:
    for tag, extra in MOTOR_VARIANTS.items():
        for letter in LETTERS:
            c[f"single/{letter}/{tag}"] = single_case(letter, extra)
        c[f"triple/ACD/{tag}"] = triple_case("ACD", extra)
    for o, a in itertools.product(("forward", "reverse"), ("glued", "pogo")):
        c[f"bare/{o}/{a}/rotor0.6"] = bare_case(o, a, MOTOR_VARIANTS["rotor0.6"])
    for tag, extra in POGO_VARIANTS.items():
        c[f"bare/reverse/pogo/{tag}"] = bare_case("reverse", "pogo", extra)
        c[f"triple/ACD/{tag}"] = triple_case("ACD", extra)
    c["triple/ACD/mesh0.25"] = triple_case("ACD", MESH_VARIANT)
    c["single/A/mesh0.25"] = single_case("A", MESH_VARIANT)
    c["transient/ACD"] = Case(TRIPLE, transient=True)


_SWEEP_INDEX = {"density": 0, "E": 1, "nu": 2}


def _common_value(name: str) -> float:
    return COMMON[_SWEEP_INDEX[name]]


def _sweep_point(name: str, x: float) -> tuple[float, float, float]:
    point = list(COMMON)
    point[_SWEEP_INDEX[name]] = float(x)
    return (point[0], point[1], point[2])


# --------------------------------------------------------------------------- solving


@dataclass(frozen=True)
class Solved:
    """What the report needs from one solve. Complex (U_r, U_z, U_t) amplitudes in m.

    Attributes:
        edge_mm: the unit's outer radius (mm).
        centre: the unit's skin-side face on the axis (fem.unit); edge: skin at edge_mm.
        skin_axis: the skin surface on the axis.
        profile_mm: distance from the edge (mm); profile: (n, 3) skin amplitudes there.
        surface_r_mm, surface: every skin-surface node (mm; (n, 3)).
        wall_s: solve time (s); dofs; warnings; contact: pogo preload check or None.
        transient: for a time-domain case, peak amplitudes (um) and sampled histories.
    """

    edge_mm: float
    centre: NDArray
    edge: NDArray
    skin_axis: NDArray
    profile_mm: NDArray
    profile: NDArray
    surface_r_mm: NDArray
    surface: NDArray
    wall_s: float
    dofs: int
    warnings: tuple[str, ...] = ()
    contact: dict | None = None
    transient: dict | None = field(default=None, repr=False)

    @property
    def centre_um(self) -> float:
        return _mag(self.centre) * 1e6

    @property
    def edge_um(self) -> float:
        return _mag(self.edge) * 1e6

    @property
    def edge_z_um(self) -> float:
        return abs(self.edge[1]) * 1e6

    @property
    def norm(self) -> float:
        """Normalized edge: displacement magnitude at the edge over the centre's."""
        return self.edge_um / self.centre_um

    @property
    def norm_z(self) -> float:
        """|U_z| at the edge over the centre magnitude (U_z vanishes on the axis in mode 1)."""
        return self.edge_z_um / self.centre_um

    def centre_variants_um(self) -> dict[str, float]:
        """Three readings of "centre" (um): ours (the unit's skin-side face on the axis), the
        skin surface on the axis, and the largest skin amplitude under the unit."""
        under = self.surface_r_mm <= self.edge_mm * (1 + 1e-9)
        return {"unit face": self.centre_um, "skin on axis": _mag(self.skin_axis) * 1e6,
                "skin peak under unit": float(_mag(self.surface[under]).max() * 1e6)}

    def normalized_profile(self, vertical: bool = False) -> NDArray:
        """Profile amplitude over the centre magnitude (magnitude, or |U_z| if vertical)."""
        amp = np.abs(self.profile[:, 1]) if vertical else _mag(self.profile)
        return amp * 1e6 / self.centre_um


def _mag(U: NDArray) -> Any:
    return np.sqrt(np.sum(np.abs(U) ** 2, axis=-1))


def solve_scene(d: Mapping[str, Any]) -> Solved:
    """Build and solve one scene dict (worker side; plain data in and out)."""
    from .scene import scene_from_dict
    from .simulate import simulate

    res = simulate(scene_from_dict(d))
    r_mm, surf = res.surface_curve()
    transient = None if res.histories is None else _transient_summary(res)
    if res.histories is not None:  # steady-looking values: the last two revolutions
        late = _late_peaks(res)
        centre, edge, axis, profile = late["centre"], late["edge"], late["axis"], late["profile"]
    else:
        centre, edge, profile = res.center, res.edge, res.profile
        axis = res.U[list(res.r_mm).index(0.0)] if 0.0 in res.r_mm else res.center * np.nan
    return Solved(float(res.edge_mm), centre, edge, axis, res.profile_mm, profile, r_mm, surf,
                  float(res.meta["wall_s"]), int(res.meta["dofs"]),
                  tuple(res.meta.get("warnings", ())), res.extras.get("preload"), transient)


def _late_peaks(res) -> dict[str, NDArray]:
    """Per-component peaks over the last two revolutions at each sampled point (m)."""
    h = res.histories
    a = h.amplitude(start=h.t[-1] - 2.0 / res.scene.unit.motor.rated_frequency_hz)
    n = res.r_mm.size
    axis = a[list(res.r_mm).index(0.0)] if 0.0 in res.r_mm else a[n] * np.nan
    return {"centre": a[n], "edge": a[n + 1], "axis": axis, "profile": a[n + 2:]}


def _transient_summary(res) -> dict:
    """Peaks over the whole run and over the last two revolutions (um), and the centre and
    edge displacement-magnitude histories every 0.25 ms."""
    h = res.histories
    n = res.r_mm.size
    whole = h.amplitude()
    late = _late_peaks(res)
    step = max(1, round(0.25e-3 / (h.t[1] - h.t[0]))) if h.t.size > 1 else 1
    return {
        "duration_ms": float(h.t[-1] * 1e3),
        "centre_peak_um": float(_mag(whole[n]) * 1e6),
        "edge_peak_um": float(_mag(whole[n + 1]) * 1e6),
        "edge_z_peak_um": float(whole[n + 1, 1] * 1e6),
        "centre_late_um": float(_mag(late["centre"]) * 1e6),
        "edge_late_um": float(_mag(late["edge"]) * 1e6),
        "edge_z_late_um": float(late["edge"][1] * 1e6),
        "t_ms": (h.t[::step] * 1e3).tolist(),
        "centre_um": (np.linalg.norm(h.u[::step, n], axis=-1) * 1e6).tolist(),
        "edge_um": (np.linalg.norm(h.u[::step, n + 1], axis=-1) * 1e6).tolist(),
        "edge_uz_um": (h.u[::step, n + 1, 1] * 1e6).tolist(),
    }


def run_cases(cases: Mapping[str, Case], workers: int, examples_dir: Path = EXAMPLES_DIR,
              log: Callable[[str], None] = print) -> dict[str, Solved]:
    """Solve every case once (names that are the same scene share one solve), in a pool of
    ``workers`` processes; transients (the longest) are submitted first."""
    from .scene import scene_from_dict, scene_hash

    dicts = {name: scene_dict(case, examples_dir) for name, case in cases.items()}
    key = {name: scene_hash(scene_from_dict(d)) for name, d in dicts.items()}  # validates
    unique = {key[name]: dicts[name] for name in sorted(cases, key=lambda n:
                                                        not cases[n].transient)}
    solved: dict[str, Solved] = {}
    if workers == 1:
        for h, d in unique.items():
            solved[h] = solve_scene(d)
    else:
        with ProcessPoolExecutor(max_workers=workers) as pool:
            futures = {pool.submit(solve_scene, d): h for h, d in unique.items()}
            for fut in as_completed(futures):
                solved[futures[fut]] = fut.result()
    log(f"  {len(unique)} distinct solves for {len(cases)} named cases")
    return {name: solved[key[name]] for name in cases}


# --------------------------------------------------------------------------- report helpers


def _pct(x: float) -> str:
    return "n/a" if not math.isfinite(x) else f"{100 * x:.1f} %"


def _um(x: float) -> str:
    return f"{x:.4g}"


def _table(columns: Sequence[str], rows: Iterable[Sequence[Any]]) -> str:
    lines = ["| " + " | ".join(columns) + " |", "|" + "---|" * len(columns)]
    lines += ["| " + " | ".join(str(v) for v in row) + " |" for row in rows]
    return "\n".join(lines)


def _near(ours: float, paper: float) -> bool:
    return abs(ours - paper) <= REL_TOL * abs(paper)


def _verdict(ok: bool, partly: bool = False) -> str:
    return "agrees" if ok else ("partly" if partly else "disagrees")


def _design(letters: str) -> str:
    return "-".join(letters)


def _gap_phrase(before: float, after: float, target: float) -> str:
    """Whether a change of definition or parameter brings a value to the paper's."""
    if _near(after, target):
        return f"reaches the paper's {_pct(target)} (within {REL_TOL:.0%})"
    if abs(after - target) < abs(before - target):
        return f"moves towards the paper's {_pct(target)} but does not reach it"
    return f"does not move it towards the paper's {_pct(target)}"


@dataclass
class Section:
    """One report section: Markdown text and the numbers behind it (for results.json)."""

    title: str
    text: str
    data: dict = field(default_factory=dict)


# --------------------------------------------------------------------------- studies


def study_orientation(r: Mapping[str, Solved]) -> Section:
    rows, data = [], {}
    for a in ("glued", "pogo"):
        for tag, label in (("", "default (rotor 1.4 mm above base)"),
                           ("/rotor0.6", "sensitivity: rotor 0.6 mm above base")):
            fwd, rev = r.get(f"bare/forward/{a}{tag}"), r.get(f"bare/reverse/{a}{tag}")
            if fwd is None or rev is None:
                continue
            ratio = rev.centre_um / fwd.centre_um
            data[f"{a}{tag}"] = {"forward_centre_um": fwd.centre_um,
                                 "reverse_centre_um": rev.centre_um, "ratio": ratio}
            rows.append([a, label, _um(fwd.centre_um), _um(rev.centre_um), f"{ratio:.3f}",
                         "reverse > forward", _verdict(ratio > 1) + ("" if not tag else
                                                                     " (sensitivity)")])
    text = ("Bare motor (no rings), centre amplitude = displacement magnitude of the unit's "
            "skin-side face on the axis (um).\n\n" + _table(
                ["attachment", "motor", "forward centre (um)", "reverse centre (um)",
                 "reverse / forward", "paper (Fig. 8a)", "verdict"], rows))
    return Section("1. Motor orientation (Fig. 8a)", text, data)


def study_pogo(r: Mapping[str, Solved]) -> Section:
    pairs = [("bare, reverse (the study)", "bare/reverse/glued", "bare/reverse/pogo", True),
             ("bare, forward (context)", "bare/forward/glued", "bare/forward/pogo", False),
             ("A-C-D, reverse (context)", "acd/glued", "triple/ACD", False)]
    rows, data = [], {}
    for label, g_name, p_name, main in pairs:
        g, p = r[g_name], r[p_name]
        ratio, ratio_z = p.edge_um / g.edge_um, p.edge_z_um / g.edge_z_um
        data[label] = {"glued_edge_um": g.edge_um, "pogo_edge_um": p.edge_um, "ratio": ratio,
                       "ratio_uz": ratio_z, "glued_centre_um": g.centre_um,
                       "pogo_centre_um": p.centre_um}
        v = _verdict(_near(ratio, PAPER_POGO_RATIO), ratio < 1)
        vz = _verdict(_near(ratio_z, PAPER_POGO_RATIO), ratio_z < 1)
        rows.append([label, _um(g.edge_um), _um(p.edge_um), f"{ratio:.3f}", f"{ratio_z:.3f}",
                     _um(g.centre_um), _um(p.centre_um), f"{PAPER_POGO_RATIO:g}",
                     f"{v} / {vz}" if main else f"({v} / {vz})"])
    text = ("Edge amplitude (skin at the unit's outer radius, um) glued vs on pogo pins. Verdict "
            f"rule: agrees if within {REL_TOL:.0%} of 0.5, partly if pogo still lowers the edge, "
            "else disagrees; given for the magnitude / the vertical component.\n\n" + _table(
                ["design", "glued edge (um)", "pogo edge (um)", "pogo / glued (magnitude)",
                 "pogo / glued (abs U_z)", "glued centre (um)", "pogo centre (um)",
                 "paper (Fig. 8b)", "verdict"], rows))
    return Section("2. Pogo pins (Fig. 8b)", text, data)


def _material_row(letter: str) -> tuple[float, float, float]:
    from .materials import get_material

    m = get_material(LETTERS[letter])
    return m.E_Pa / 1e3, m.density_kg_m3, m.nu


def _range_verdict(values: Sequence[float], lo: float, hi: float) -> str:
    inside = [lo * (1 - REL_TOL) <= v <= hi * (1 + REL_TOL) for v in values]
    return _verdict(all(inside), any(inside))


def study_single(r: Mapping[str, Solved]) -> Section:
    rows, data = [], {}
    for letter in LETTERS:
        s = r[f"single/{letter}"]
        E, rho, nu = _material_row(letter)
        data[letter] = {"material": LETTERS[letter], "centre_um": s.centre_um,
                        "edge_um": s.edge_um, "normalized": s.norm, "normalized_uz": s.norm_z}
        rows.append([letter, LETTERS[letter], f"{E:g}", f"{rho:g}", f"{nu:g}", _um(s.centre_um),
                     _um(s.edge_um), _pct(s.norm), _pct(s.norm_z)])
    mags = [data[c]["normalized"] for c in LETTERS]
    verts = [data[c]["normalized_uz"] for c in LETTERS]
    lo, hi = PAPER_SINGLE_RANGE
    claim = [["normalized edge, single layers", f"{_pct(lo)} - {_pct(hi)}",
              f"{_pct(min(mags))} - {_pct(max(mags))}", f"{_pct(min(verts))} - {_pct(max(verts))}",
              f"{_range_verdict(mags, lo, hi)} / {_range_verdict(verts, lo, hi)}"],
             ["spread across materials", f"{_pct(hi - lo)} points",
              f"{_pct(max(mags) - min(mags))} points", f"{_pct(max(verts) - min(verts))} points",
              "(context)"]]
    text = ("Forward motor, glued, one 1 mm ring (library small-strain moduli, see Model). "
            "Normalized edge = amplitude at the edge / centre magnitude.\n\n"
            + _table(["layer", "material", "E (kPa)", "density (kg/m3)", "nu", "centre (um)",
                      "edge (um)", "normalized (magnitude)", "normalized (abs U_z)"], rows)
            + "\n\n" + _table(["claim", "paper (Fig. 9a)", "ours (magnitude)",
                               "ours (abs U_z)", "verdict (magnitude / U_z)"], claim)
            + f"\n\nVerdict rule: agrees if every material lies in the paper's range widened by "
              f"{REL_TOL:.0%}, partly if some do.\n\n![single layers](single_layers.png)")
    return Section("3. Single layers A-D (Fig. 9a)", text, data)


def _ranked(r: Mapping[str, Solved], triples: Sequence[str], vertical: bool) -> list[str]:
    def value(t: str) -> float:
        s = r[f"triple/{t}"]
        return s.norm_z if vertical else s.norm
    return sorted(triples, key=value)


def study_triples(r: Mapping[str, Solved], triples: Sequence[str]) -> Section:
    singles = [r[f"single/{c}"] for c in LETTERS]
    out, claims = {}, []
    for vertical in (False, True):
        order = _ranked(r, triples, vertical)

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
        return _verdict(_near(d["min"][1], PAPER_TRIPLE_MIN), d["min"][1] < d["single_min"])

    def v_max(d: dict) -> str:
        return _verdict(_near(d["max"][1], PAPER_TRIPLE_MAX), d["max"][1] > d["single_max"])

    def v_acd(d: dict) -> str:
        return _verdict(d["acd_rank"] == 1, d["acd_rank"] is not None and d["acd_rank"] <= n / 4)

    def v_span(d: dict) -> str:
        lo, hi = d["min"][1] < d["single_min"], d["max"][1] > d["single_max"]
        return _verdict(lo and hi, lo or hi)

    claims = [
        ["most restraining triple, normalized edge", _pct(PAPER_TRIPLE_MIN),
         f"{_pct(m['min'][1])} ({_design(m['min'][0])})",
         f"{_pct(z['min'][1])} ({_design(z['min'][0])})", f"{v_min(m)} / {v_min(z)}"],
        ["the most restraining triple is A-C-D", "A-C-D (layers 1-2-3)",
         f"A-C-D ranks {m['acd_rank']} of {n} ({_pct(m['acd'])})",
         f"A-C-D ranks {z['acd_rank']} of {n} ({_pct(z['acd'])})", f"{v_acd(m)} / {v_acd(z)}"],
        ["most enhancing triple, normalized edge", _pct(PAPER_TRIPLE_MAX),
         f"{_pct(m['max'][1])} ({_design(m['max'][0])})",
         f"{_pct(z['max'][1])} ({_design(z['max'][0])})", f"{v_max(m)} / {v_max(z)}"],
        ["triples both restrain and enhance beyond single layers",
         f"{_pct(PAPER_TRIPLE_MIN)} - {_pct(PAPER_TRIPLE_MAX)} vs single "
         f"{_pct(PAPER_SINGLE_RANGE[0])} - {_pct(PAPER_SINGLE_RANGE[1])}",
         f"{_pct(m['min'][1])} - {_pct(m['max'][1])} vs single {_pct(m['single_min'])} - "
         f"{_pct(m['single_max'])}",
         f"{_pct(z['min'][1])} - {_pct(z['max'][1])} vs single {_pct(z['single_min'])} - "
         f"{_pct(z['single_max'])}", f"{v_span(m)} / {v_span(z)}"],
    ]
    order = _ranked(r, triples, False)
    order_z = _ranked(r, triples, True)
    rows = []
    for i, t in enumerate(order, 1):
        s = r[f"triple/{t}"]
        rows.append([i, _design(t), _um(s.centre_um), _um(s.edge_um), _pct(s.norm),
                     _pct(s.norm_z), order_z.index(t) + 1])
    out["all"] = {t: {"centre_um": r[f"triple/{t}"].centre_um,
                      "edge_um": r[f"triple/{t}"].edge_um, "normalized": r[f"triple/{t}"].norm,
                      "normalized_uz": r[f"triple/{t}"].norm_z} for t in triples}
    text = (f"Reverse motor on pogo pins, three 1 mm rings, every ordered triple of A-D "
            f"({n} designs; layer 1 is the innermost). Verdict rules: a number agrees within "
            f"{REL_TOL:.0%} of the paper's; the minimum is 'partly' if it still restrains below "
            "every single layer, the maximum if it still enhances above them; A-C-D is 'partly' "
            "the most restraining if it ranks in the lowest quarter.\n\n"
            + _table(["claim", "paper (Fig. 9b/c)", "ours (magnitude)", "ours (abs U_z)",
                      "verdict (magnitude / U_z)"], claims)
            + "\n\n![triples](triples.png)\n\n<details><summary>All triples, ranked by the "
              "normalized edge (magnitude)</summary>\n\n"
            + _table(["rank", "layers 1-2-3", "centre (um)", "edge (um)",
                      "normalized (magnitude)", "normalized (abs U_z)", "rank by U_z"], rows)
            + "\n\n</details>")
    return Section("4. All ordered triples (Fig. 9b/c)", text, out)


_SWEEP_LABEL = {"density": ("density", "kg/m3", "Table 2"), "E": ("Young's modulus", "kPa",
                                                                  "Table 3"),
                "nu": ("Poisson's ratio", "-", "Table 4")}


def _sweep_rows(r: Mapping[str, Solved], name: str, values: Sequence[float]) -> list[list]:
    rows = []
    for i, x in enumerate(values):
        point = _sweep_point(name, x)
        s = r[uniform_name(*point)]
        rows.append([chr(ord("A") + i), f"{point[0]:g}", f"{point[1]:g}", f"{point[2]:g}",
                     _um(s.centre_um), _um(s.edge_um), _pct(s.norm), _pct(s.norm_z)])
    return rows


def sweep_measures(r: Mapping[str, Solved], name: str, values: Sequence[float]) -> dict:
    """Fair-comparison measures of one table: spreads (max/min over its rows) of the edge
    amplitude and of the normalized edge, the end-to-end log slope over the table's range, and
    the local log-log sensitivity d ln y / d ln x at the common point (central difference)."""
    sols = [r[uniform_name(*_sweep_point(name, x))] for x in values]
    edge = np.array([s.edge_um for s in sols])
    norm = np.array([s.norm for s in sols])
    x_ratio = max(values) / min(values)
    c = _common_value(name)
    up = r[uniform_name(*_sweep_point(name, c * ELASTICITY_STEP))]
    dn = r[uniform_name(*_sweep_point(name, c / ELASTICITY_STEP))]
    h = 2 * math.log(ELASTICITY_STEP)
    i_lo, i_hi = int(np.argmin(values)), int(np.argmax(values))
    return {
        "x_ratio": x_ratio,
        "edge_spread": float(edge.max() / edge.min()),
        "norm_spread": float(norm.max() / norm.min()),
        "edge_slope_over_range": float(math.log(edge[i_hi] / edge[i_lo]) / math.log(x_ratio)),
        "edge_elasticity": math.log(up.edge_um / dn.edge_um) / h,
        "norm_elasticity": math.log(up.norm / dn.norm) / h,
        "edge_um": edge.tolist(), "normalized": norm.tolist(),
    }


def study_sweeps(r: Mapping[str, Solved], sweeps: Mapping[str, Sequence[float]]) -> Section:
    parts, data = [], {}
    for name, values in sweeps.items():
        label, unit, table = _sweep_label(name)
        parts.append(f"**{table}: {label} ({unit})**, all three rings carry each row.\n\n"
                     + _table(["row", "density (kg/m3)", "E (kPa)", "nu", "centre (um)",
                               "edge (um)", "normalized (magnitude)", "normalized (abs U_z)"],
                              _sweep_rows(r, name, values)))
        data[name] = sweep_measures(r, name, values)
    measures = [("edge_spread", "edge amplitude max/min over the table"),
                ("norm_spread", "normalized edge max/min over the table"),
                ("edge_elasticity", "d ln(edge) / d ln(x) at 1000 kg/m3, 355 kPa, 0.47"),
                ("norm_elasticity", "d ln(normalized) / d ln(x) at the same point")]
    rows = [[_sweep_label(n)[0], f"{data[n]['x_ratio']:.3g}"]
            + [f"{data[n][k]:.3g}" for k, _ in measures]
            + [f"{data[n]['edge_slope_over_range']:.3g}"] for n in sweeps]
    verdicts = []
    for key, label in measures:
        order = sorted(sweeps, key=lambda n, k=key: -abs(math.log(data[n][k]))
                       if "spread" in k else -abs(data[n][k]))
        ranking = " > ".join(_sweep_label(n)[0] for n in order)
        verdicts.append([label, "density matters most", ranking,
                         _verdict(order[0] == "density")])
        data[f"ranking_{key}"] = order
    width = ", ".join(f"{_sweep_label(n)[0]} x{data[n]['x_ratio']:.3g}" for n in sweeps)
    text = ("\n\n".join(parts) + "\n\n![sweeps](sweeps.png)\n\n**Which parameter matters most.** "
            + _table(["parameter", "table range x_max/x_min", *[m[1] for m in measures],
                      "end-to-end slope ln(edge ratio)/ln(x ratio)"], rows)
            + "\n\n" + _table(["measure", "paper", "ours (ranking)", "verdict"], verdicts)
            + f"\n\nThe tables span very different ranges ({width}). The spread over a table "
              "rewards a wide range: the modulus table covers more than two decades, the "
              "density table a factor of 4, so spreads favour the modulus before any physics. "
              "The log-log sensitivity compares the parameters per relative change at one "
              "common point and is blind to the ranges; it is the fairer measure of "
              "'influence', the spread the fairer measure of what the paper's own tables can "
              "show. Poisson's ratio acts through the bulk modulus K = E / (3 (1 - 2 nu)), which "
              "changes x10 between nu = 0.2 and 0.47 although nu itself changes only x2.35.")
    return Section("5. Density, modulus and Poisson's ratio (Tables 2-4, Figs. 10-12)", text, data)


def _sweep_label(name: str) -> tuple[str, str, str]:
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


def study_context(r: Mapping[str, Solved]) -> Section:
    protos = [("1: bare, forward, glued", "proto/bare"),
              ("2: A-D double, forward, glued", "proto/double"),
              ("3: A-C-D triple, reverse, pogo", "proto/triple")]
    rows, data = [], {}
    for label, name in protos:
        s = r[name]
        d50, d25 = crosstalk_distance(s, 0.5), crosstalk_distance(s, 0.25)
        at = _at_distance(s, PAPER_TPD_MM)
        data[label] = {"centre_um": s.centre_um, "edge_um": s.edge_um, "normalized": s.norm,
                       "d50_mm": d50, "d25_mm": d25, "at_tpd": at}
        rows.append([label, _um(s.centre_um), _um(s.edge_um), _pct(s.norm), _fmt_mm(d50),
                     _fmt_mm(d25), _pct(at)])
    claims = [["FE vs laser Doppler vibrometer on a phantom", f"R^2 = {PAPER_R2}",
               "not reproducible: a measurement on their phantom; we have no data"],
              ["two-point discrimination, optimized unit, successive stimuli",
               f"{PAPER_TPD_MM} mm (vs 13 mm earlier), p < 0.01",
               "not reproducible: a perception experiment with 10 people"]]
    text = (_table(["paper item", "paper", "ours"], claims)
            + "\n\n**Crosstalk proxy (ours, not in the paper).** For the three prototype designs:"
              " the distance from the unit's edge beyond which the skin amplitude (magnitude) "
              "stays below 50 % / 25 % of the unit's centre amplitude (within the 20 mm "
              "profile), and the amplitude at 8.6 mm from the edge (the paper's threshold) over "
              "the centre. A proxy for how far a neighbour must sit, not a perception model.\n\n"
            + _table(["design", "centre (um)", "edge (um)", "normalized edge", "below 50 % from",
                      "below 25 % from", "at 8.6 mm"], rows))
    return Section("6. Context the paper has no FE number for", text, data)


def _fmt_mm(x: float) -> str:
    if x == 0:
        return "0 (below at the edge)"
    return "> 20 mm" if math.isinf(x) else f"{x:.1f} mm"


# --------------------------------------------------------------------------- disagreement checks


def check_amplitude_definition(r: Mapping[str, Solved], triples: Sequence[str]) -> Section:
    """(a) magnitude vs vertical component, for the headline numbers."""
    singles = [r[f"single/{c}"] for c in LETTERS]
    acd = r["triple/ACD"]
    pogo_g, pogo_p = r["bare/reverse/glued"], r["bare/reverse/pogo"]
    mid = sum(PAPER_SINGLE_RANGE) / 2
    s_m = float(np.mean([s.norm for s in singles]))
    s_z = float(np.mean([s.norm_z for s in singles]))
    ratio_m, ratio_z = pogo_p.edge_um / pogo_g.edge_um, pogo_p.edge_z_um / pogo_g.edge_z_um
    rows = [["single layers, mean normalized edge", _pct(mid), _pct(s_m), _pct(s_z)],
            ["A-C-D normalized edge", _pct(PAPER_TRIPLE_MIN), _pct(acd.norm), _pct(acd.norm_z)],
            ["pogo / glued edge (bare, reverse)", f"{PAPER_POGO_RATIO:g}", f"{ratio_m:.3f}",
             f"{ratio_z:.3f}"]]
    text = ("We report the displacement magnitude sqrt(|U_r|^2 + |U_t|^2 + |U_z|^2) of the "
            "rotating load; a laser Doppler vibrometer looking at the skin, and probably the "
            "paper's FE read-out, see the vertical component. The centre is the same in both "
            "columns (on the axis the vertical amplitude of a rotating load vanishes), so the "
            "right column is |U_z| at the edge over the centre magnitude.\n\n"
            + _table(["quantity", "paper", "magnitude", "abs U_z"], rows)
            + f"\n\nUsing the vertical component {_gap_phrase(s_m, s_z, mid)} for the single "
              f"layers, and {_gap_phrase(acd.norm, acd.norm_z, PAPER_TRIPLE_MIN)} for A-C-D.")
    return Section("(a) Amplitude definition", text, {"single_mean": [s_m, s_z],
                                                      "acd": [acd.norm, acd.norm_z],
                                                      "pogo_ratio": [ratio_m, ratio_z]})


def check_centre_definition(r: Mapping[str, Solved], triples: Sequence[str]) -> Section:
    """(b) three readings of the centre amplitude."""
    names = [*(f"single/{c}" for c in LETTERS), "triple/ACD"]
    order = _ranked(r, triples, False)
    names += [f"triple/{order[0]}", f"triple/{order[-1]}"]
    names = list(dict.fromkeys(names))
    variants = list(r[names[0]].centre_variants_um())
    rows, data = [], {}
    for n in names:
        s = r[n]
        c = s.centre_variants_um()
        data[n] = {k: s.edge_um / v for k, v in c.items()}
        rows.append([n.replace("triple/", "triple ").replace("single/", "single "),
                     *(f"{_um(c[k])} um -> {_pct(s.edge_um / c[k])}" for k in variants)])
    rank_rows = []
    for k in variants:
        vals = {t: r[f"triple/{t}"].edge_um / r[f"triple/{t}"].centre_variants_um()[k]
                for t in triples}
        o = sorted(triples, key=vals.get)
        rank_rows.append([k, f"{_pct(vals[o[0]])} ({_design(o[0])})",
                          f"{_pct(vals[o[-1]])} ({_design(o[-1])})",
                          f"{o.index('ACD') + 1} of {len(o)}" if "ACD" in o else "n/a"])
        data[f"triples/{k}"] = {"min": [o[0], vals[o[0]]], "max": [o[-1], vals[o[-1]]]}
    text = ("Ours is the unit's own skin-side face on the axis (the skin under a glued unit, the "
            "board's underside on pogo pins, fem/unit.py). Alternatives: the skin surface on the "
            "axis (on pins it is not touched by the unit), and the largest skin amplitude under "
            "the unit's footprint. Each cell: centre amplitude -> normalized edge (magnitude)."
            "\n\n" + _table(["case", *variants], rows)
            + "\n\n" + _table(["centre definition", "triples: min", "triples: max",
                               "A-C-D rank"], rank_rows))
    return Section("(b) Centre definition", text, data)


def check_motor(r: Mapping[str, Solved]) -> Section:
    """(c) motor mass and rotor height (the unbalance cancels in normalized values)."""
    cases = [*(f"single/{c}" for c in LETTERS), "triple/ACD"]
    tags = ["", *MOTOR_VARIANTS]
    rows, data, changes = [], {}, []
    for n in cases:
        base = r[n].norm
        vals = {t: r[f"{n}/{t}" if t else n] for t in tags}
        data[n] = {t or "default": [v.norm, v.norm_z] for t, v in vals.items()}
        changes += [abs(v.norm / base - 1) for v in vals.values()]
        rows.append([n, *(f"{_pct(v.norm)} ({_pct(v.norm_z)})" for v in vals.values())])
    text = ("Normalized edge, magnitude (abs U_z in brackets), with the motor's defaults (0.6 g, "
            "rotor plane 1.4 mm above the base face) and with one of them changed. The paper "
            "gives neither; the unbalance m e only scales every amplitude.\n\n"
            + _table(["case", "default", "rotor 0.6 mm", "mass 0.3 g", "mass 1.2 g"], rows)
            + f"\n\nLargest relative change of a normalized edge: {max(changes):.0%}. The "
              "orientation study (section 1) also lists the rotor-0.6 mm case: with it, forward "
              "and reverse swap their rotor heights.")
    return Section("(c) Motor parameters the paper does not give", text, data)


def check_pogo(r: Mapping[str, Solved]) -> Section:
    """(d) the smeared pins: footprint and stiffness."""
    g = r["bare/reverse/glued"]
    rows, data = [], {}
    labels = {"": "default (0.5 mm tip, 2942 N/m)", "tip0.25": "tip 0.25 mm",
              "tip1": "tip 1.0 mm", "k0.5": "stiffness x0.5", "k2": "stiffness x2"}
    for tag, label in labels.items():
        bare = r[f"bare/reverse/pogo/{tag}" if tag else "bare/reverse/pogo"]
        acd = r[f"triple/ACD/{tag}" if tag else "triple/ACD"]
        contact = acd.contact.get("contact_maintained") if acd.contact else None
        data[tag or "default"] = {"ratio": bare.edge_um / g.edge_um, "acd": acd.norm,
                                  "acd_contact": contact}
        rows.append([label, f"{bare.edge_um / g.edge_um:.3f}", _pct(acd.norm), _pct(acd.norm_z),
                     "n/a" if contact is None else ("yes" if contact else "no")])
    text = ("The three pins are smeared into a ring (fem/unit.py): the vertical (n = 0) and "
            "rocking (n = 1) stiffnesses are exact, the harmonics n = 3k +- 1 of three discrete "
            "pins are left out. Those decay away from the pin circle roughly like "
            "(R_p / r)^|n|; at the edge of a triple unit (6.5 mm, R_p = 2.25 mm) the first, "
            "n = 2, is about (2.25 / 6.5)^2 = 12 % of its value at the pins. Below: how much the "
            "answers depend on the parts of the pin model that the smearing makes uncertain.\n\n"
            + _table(["pin model", "bare reverse: pogo / glued edge", "A-C-D normalized",
                      "A-C-D normalized (abs U_z)", "A-C-D pins keep contact"], rows))
    return Section("(d) Three pins smeared into a ring", text, data)


def check_transient(r: Mapping[str, Solved]) -> Section | None:
    """(e) steady harmonic vs a transient from rest (their analysis kind)."""
    if "transient/ACD" not in r:
        return None
    h, t = r["proto/triple"], r["transient/ACD"].transient
    rows = [["harmonic steady state", _um(h.centre_um), _um(h.edge_um), _pct(h.norm),
             _pct(h.norm_z)],
            [f"transient, peak over 0-{t['duration_ms']:.0f} ms", _um(t["centre_peak_um"]),
             _um(t["edge_peak_um"]), _pct(t["edge_peak_um"] / t["centre_peak_um"]),
             _pct(t["edge_z_peak_um"] / t["centre_peak_um"])],
            ["transient, peak over the last two revolutions", _um(t["centre_late_um"]),
             _um(t["edge_late_um"]), _pct(t["edge_late_um"] / t["centre_late_um"]),
             _pct(t["edge_z_late_um"] / t["centre_late_um"])]]
    text = ("The paper ran ABAQUS dynamic implicit (0.05 ms step) with the mass turning at "
            "120 rev/s from the start and read amplitudes off time histories; the run length "
            "and the tissue damping are not given. Our transient: the A-C-D unit, same step, "
            f"constant speed from rest, {t['duration_ms']:.0f} ms, default (undamped) tissue, "
            "a damping layer as the absorber. Amplitudes per component peak, combined as "
            "the magnitude.\n\n" + _table(["analysis", "centre (um)", "edge (um)",
                                           "normalized (magnitude)", "normalized (abs U_z)"],
                                          rows)
            + "\n\n![transient](transient.png)")
    return Section("(e) Steady harmonic vs transient", text, {"harmonic": [h.centre_um,
                                                                          h.edge_um],
                                                             **{k: v for k, v in t.items()
                                                                if not isinstance(v, list)}})


def check_mesh(r: Mapping[str, Solved]) -> Section | None:
    """Discretisation: halve the near-field element size."""
    if "triple/ACD/mesh0.25" not in r:
        return None
    rows, data = [], {}
    for n in ("single/A", "triple/ACD"):
        a, b = r[n], r[f"{n}/mesh0.25"]
        data[n] = [a.norm, b.norm]
        rows.append([n, _pct(a.norm), _pct(b.norm), f"{b.norm / a.norm - 1:+.1%}",
                     _um(a.edge_um), _um(b.edge_um)])
    text = _table(["case", "normalized, 0.5 mm", "normalized, 0.25 mm", "change",
                   "edge um, 0.5 mm", "edge um, 0.25 mm"], rows)
    return Section("(f) Mesh refinement (near-field element size 0.5 -> 0.25 mm)", text, data)


# --------------------------------------------------------------------------- figures


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _profile_axes(ax, title: str) -> None:
    ax.set_xlim(0, 20)
    ax.set_ylim(bottom=0)
    ax.set_xlabel("distance from the unit edge (mm)")
    ax.set_ylabel("amplitude / centre amplitude")
    ax.set_title(title, fontsize=10)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)


def fig_single_layers(r: Mapping[str, Solved], path: Path) -> None:
    plt = _plt()
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    for i, c in enumerate(LETTERS):
        s, col = r[f"single/{c}"], f"C{i}"
        ax.plot(s.profile_mm, s.normalized_profile(), color=col, label=f"{c} magnitude")
        ax.plot(s.profile_mm, s.normalized_profile(True), "--", color=col, label=f"{c} abs U_z")
    ax.axhspan(*PAPER_SINGLE_RANGE, color="grey", alpha=0.2, label="paper: edge 50-58 %")
    _profile_axes(ax, "Single layers, forward, glued (cf. Fig. 9a)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def fig_triples(r: Mapping[str, Solved], triples: Sequence[str], path: Path) -> None:
    plt = _plt()
    order = _ranked(r, triples, False)
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(11, 4.2))
    picks = list(dict.fromkeys([order[0], "ACD", order[-1]]))
    for i, t in enumerate(picks):
        s, col = r[f"triple/{t}"], f"C{i}"
        ax.plot(s.profile_mm, s.normalized_profile(), color=col, label=f"{_design(t)} magnitude")
        ax.plot(s.profile_mm, s.normalized_profile(True), "--", color=col,
                label=f"{_design(t)} abs U_z")
    ax.axhline(PAPER_TRIPLE_MIN, color="k", lw=0.8, ls=":", label="paper 19 % / 90 %")
    ax.axhline(PAPER_TRIPLE_MAX, color="k", lw=0.8, ls=":")
    _profile_axes(ax, "Most restraining, A-C-D, most enhancing (cf. Fig. 9b/c)")
    vals = [r[f"triple/{t}"].norm for t in order]
    vals_z = [r[f"triple/{t}"].norm_z for t in order]
    x = np.arange(len(order))
    bx.bar(x, vals, color=["C3" if t == "ACD" else "C0" for t in order], label="magnitude")
    bx.plot(x, vals_z, "k.", ms=4, label="abs U_z")
    bx.axhline(PAPER_TRIPLE_MIN, color="k", lw=0.8, ls=":")
    bx.axhline(PAPER_TRIPLE_MAX, color="k", lw=0.8, ls=":")
    bx.set_xticks(x, [t for t in order], rotation=90, fontsize=6 if len(order) > 16 else 8)
    bx.set_ylabel("normalized edge amplitude")
    bx.set_title("All triples, ranked (A-C-D in red)", fontsize=10)
    bx.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def fig_sweeps(r: Mapping[str, Solved], sweeps: Mapping[str, Sequence[float]],
               path: Path) -> None:
    plt = _plt()
    fig, axes = plt.subplots(1, len(sweeps), figsize=(4.2 * len(sweeps), 3.8))
    for ax, (name, values) in zip(np.atleast_1d(axes), sweeps.items(), strict=True):
        sols = [r[uniform_name(*_sweep_point(name, x))] for x in values]
        label, unit, table = _sweep_label(name)
        ax.plot(values, [s.edge_um for s in sols], "o-", color="C0")
        ax.set_ylabel("edge amplitude (um)", color="C0")
        ax.set_xlabel(f"{label} ({unit})")
        if name == "E":
            ax.set_xscale("log")
        tw = ax.twinx()
        tw.plot(values, [s.norm for s in sols], "s--", color="C1", label="magnitude")
        tw.plot(values, [s.norm_z for s in sols], "^:", color="C2", label="abs U_z")
        tw.set_ylabel("normalized edge")
        tw.legend(fontsize=7)
        ax.set_title(f"{table}: three equal rings", fontsize=10)
        ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def fig_structure(r: Mapping[str, Solved], path: Path) -> None:
    plt = _plt()
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(9, 3.6))
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
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def fig_transient(r: Mapping[str, Solved], path: Path) -> None:
    plt = _plt()
    t, h = r["transient/ACD"].transient, r["proto/triple"]
    fig, ax = plt.subplots(figsize=(7, 3.8))
    ax.plot(t["t_ms"], t["centre_um"], lw=0.8, label="centre, transient")
    ax.plot(t["t_ms"], t["edge_um"], lw=0.8, label="edge, transient")
    ax.axhline(h.centre_um, color="C0", ls="--", label="centre, harmonic amplitude")
    ax.axhline(h.edge_um, color="C1", ls="--", label="edge, harmonic amplitude")
    ax.set_xlabel("time (ms)")
    ax.set_ylabel("displacement magnitude (um)")
    ax.set_title("A-C-D, reverse, pogo: transient from rest vs steady state", fontsize=10)
    ax.legend(fontsize=7)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def write_figures(r: Mapping[str, Solved], p: Plan, out: Path) -> list[str]:
    """Write the PNGs into ``out``; returns their file names."""
    figs = {"structure.png": lambda f: fig_structure(r, f),
            "single_layers.png": lambda f: fig_single_layers(r, f),
            "triples.png": lambda f: fig_triples(r, p.triples, f),
            "sweeps.png": lambda f: fig_sweeps(r, p.sweeps, f)}
    if "transient/ACD" in r:
        figs["transient.png"] = lambda f: fig_transient(r, f)
    for name, draw in figs.items():
        draw(out / name)
    return list(figs)
