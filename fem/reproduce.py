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
definition, motor parameters, the pogo-pin smearing, steady vs transient, mesh refinement, and
how the inner ring meets the motor (``unit.ring_contact``: the default "frictionless", the
paper's ties taken literally, "none", and "bonded"), for the single layers, A-C-D, a few fixed
triples and the default's own most restraining and most enhancing triples (found in the run).

Units: amplitudes in um, distances in mm, normalized values as fractions (printed in %).
"""

from __future__ import annotations

import functools
import itertools
import json
import math
import multiprocessing
import os
import shutil
import tempfile
import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from . import SOLVER_VERSION
from .parallel import one_blas_thread

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
TRANSIENT_STEP_MS = 0.2  # 42 steps per revolution (the paper: 0.05 ms); keeps the run < 60 s
TRANSIENT_CONTACT = "frictionless"  # never "none" on pins: the solver refuses it (drift)
LDV_BAND_HZ = (40.0, 200.0)  # the paper's Butterworth band-pass of the vibrometer signals
#: How the inner ring meets the motor and board: every choice of ``unit.ring_contact``.
RING_CONTACTS = ("frictionless", "none", "bonded")
#: Triples solved under every contact besides the default's own extremes (added in the run):
#: A-C-D, its mirror, and A-A-A, A-D-D, D-D-D, the extremes under each contact of a one-off scan
#: of all 64 (fem 0.1.0), so that the subset spans each contact's range.
CONTACT_TRIPLES = ("AAA", "ACD", "ADD", "DCA", "DDD")


# --------------------------------------------------------------------------- cases and scenes


@dataclass(frozen=True)
class Case:
    """One scene: an example file plus edits (dotted path -> value); ``transient`` runs the
    time-domain solver instead (constant speed from rest, ``TRANSIENT_STEP_MS``)."""

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
                             time_step_ms=TRANSIENT_STEP_MS,
                             voltage_schedule=[[0.0, d["unit"]["motor"]["rated_voltage_V"]]])
        _set(d, "effects.spin_up", False)  # the paper turns the mass at 120 rev/s from t = 0
    return d


@functools.lru_cache(maxsize=8)
def _example(name: str, examples_dir: Path = EXAMPLES_DIR):
    """The example scene ``name`` as loaded (its defaults are what every study starts from)."""
    from .scene import load_scene

    return load_scene(Path(examples_dir) / name)


def default_contact(examples_dir: Path = EXAMPLES_DIR) -> str:
    """The ring contact the triple example uses (the schema's default unless it sets one)."""
    return _example(TRIPLE, Path(examples_dir)).unit.ring_contact


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


def contact_edit(contact: str) -> tuple[tuple[str, Any], ...]:
    return (("unit.ring_contact", contact),)


def contact_name(base: str, contact: str) -> str:
    """Name of case ``base`` with ``unit.ring_contact = contact`` (the default's is the same
    scene as ``base`` and shares its solve)."""
    return f"{base}/contact-{contact}"


def contact_cases(base: str, make: Callable[..., Case], *args: Any) -> dict[str, Case]:
    """``make(*args, extra)`` under every ring contact, named by :func:`contact_name`."""
    return {contact_name(base, c): make(*args, contact_edit(c)) for c in RING_CONTACTS}


def _acd_glued(extra=()) -> Case:
    return Case(TRIPLE, (("unit.attachment", "glued"), *extra))


@dataclass(frozen=True)
class FollowUp:
    """Cases that depend on results: once every case in ``needs`` is solved, ``make`` gets
    their results and returns the new named cases (solved in the same pool)."""

    needs: tuple[str, ...]
    make: Callable[[Mapping[str, Solved]], Mapping[str, Case]]


@dataclass(frozen=True)
class Plan:
    """Named cases (several names may be one scene), the triples studied, and the follow-up
    that adds the default's extreme triples to the ring-contact study."""

    cases: dict[str, Case]
    triples: tuple[str, ...]
    sweeps: dict[str, tuple[float, ...]]
    quick: bool
    follow: FollowUp | None = None


def plan(quick: bool = False) -> Plan:
    """Every case of the reproduction; ``quick`` keeps a reduced set (4 triples, sweep end
    points, A-C-D and the extremes only in the contact study, no motor/pogo/mesh
    sensitivities, no transient) for tests."""
    c: dict[str, Case] = {}
    for o, a in itertools.product(("forward", "reverse"), ("glued", "pogo")):
        c[f"bare/{o}/{a}"] = bare_case(o, a)
    for letter in LETTERS:
        c[f"single/{letter}"] = single_case(letter)
        c.update(contact_cases(f"single/{letter}", single_case, letter))
    triples = (("AAA", "ACD", "DCA", "DDD") if quick
               else tuple("".join(t) for t in itertools.product(LETTERS, repeat=3)))
    for t in triples:
        c[f"triple/{t}"] = triple_case(t)
    for t in ("ACD",) if quick else CONTACT_TRIPLES:
        c.update(contact_cases(f"triple/{t}", triple_case, t))
    c["acd/glued"] = _acd_glued()
    c.update(contact_cases("acd/glued", _acd_glued))
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
    follow = FollowUp(tuple(f"triple/{t}" for t in triples),
                      lambda r: extreme_contact_cases(r, triples))
    return Plan(c, triples, sweeps, quick, follow)


def extreme_contact_cases(r: Mapping[str, Solved], triples: Sequence[str]) -> dict[str, Case]:
    """The most restraining and most enhancing triples under the default (by the magnitude and
    by |U_z|), under every ring contact."""
    picks: dict[str, None] = {}
    for vertical in (False, True):
        order = _ranked(r, triples, vertical)
        picks.update(dict.fromkeys((order[0], order[-1])))
    out: dict[str, Case] = {}
    for t in picks:
        out.update(contact_cases(f"triple/{t}", triple_case, t))
    return out


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
    c["transient/ACD"] = transient_case()


def transient_case() -> Case:
    """The A-C-D unit from rest, with the inner ring in ``TRANSIENT_CONTACT`` (the literal
    "none" on pins is refused by the solver: nothing would hold the unit sideways)."""
    return Case(TRIPLE, contact_edit(TRANSIENT_CONTACT), transient=True)


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
        skin_axis: the skin surface on the axis; top_axis: the motor's top face on the axis
            (NaN for a transient).
        profile_mm: distance from the edge (mm); profile: (n, 3) skin amplitudes there.
        surface_r_mm, surface: every skin-surface node (mm; (n, 3)).
        wall_s: solve time (s); dofs; warnings; contact: pogo preload check or None.
        transient: for a time-domain case, peak amplitudes (um) and sampled histories.
    """

    edge_mm: float
    centre: NDArray
    edge: NDArray
    skin_axis: NDArray
    top_axis: NDArray
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
        """Four readings of "centre" (um): ours (the unit's skin-side face on the axis), the
        skin surface on the axis, the largest skin amplitude under the unit, and the motor's
        top face on the axis (where a vibrometer looking down at the unit would aim)."""
        under = self.surface_r_mm <= self.edge_mm * (1 + 1e-9)
        return {"unit face": self.centre_um, "skin on axis": _mag(self.skin_axis) * 1e6,
                "skin peak under unit": float(_mag(self.surface[under]).max() * 1e6),
                "motor top": float(_mag(self.top_axis) * 1e6)}

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
    top = np.full(3, np.nan) if res.nodal is None else res.nodal[_top_of_axis(res.domain)]
    return Solved(float(res.edge_mm), centre, edge, axis, top, res.profile_mm, profile, r_mm, surf,
                  float(res.meta["wall_s"]), int(res.meta["dofs"]),
                  tuple(res.meta.get("warnings", ())), res.extras.get("preload"), transient)


def _top_of_axis(domain) -> int:
    """The highest mesh node on the axis: the motor's top face (nothing else reaches r = 0
    above the skin)."""
    nodes = domain.mesh.nodes
    on_axis = np.flatnonzero(np.abs(nodes[:, 0]) < 1e-12)
    return int(on_axis[np.argmin(nodes[on_axis, 1])])


def _late_peaks(res) -> dict[str, NDArray]:
    """Per-component peaks over the last two revolutions at each sampled point (m)."""
    h = res.histories
    a = h.amplitude(start=h.t[-1] - 2.0 / res.scene.unit.motor.rated_frequency_hz)
    n = res.r_mm.size
    axis = a[list(res.r_mm).index(0.0)] if 0.0 in res.r_mm else a[n] * np.nan
    return {"centre": a[n], "edge": a[n + 1], "axis": axis, "profile": a[n + 2:]}


def _transient_summary(res) -> dict:
    """Peaks over the whole run, over the last two revolutions, and over the last two
    revolutions after the paper's 40-200 Hz band-pass (um); the centre's mean displacement over
    the last revolution (a rigid drift); the centre and edge histories (um, every step)."""
    from scipy import signal

    h = res.histories
    n = res.r_mm.size
    whole = h.amplitude()
    late = _late_peaks(res)
    revolution = 1.0 / res.scene.unit.motor.rated_frequency_hz
    sos = signal.butter(2, LDV_BAND_HZ, btype="bandpass", fs=1.0 / (h.t[1] - h.t[0]),
                        output="sos")
    band = signal.sosfiltfilt(sos, h.u[:, n:n + 2], axis=0)  # centre, edge
    in_late = h.t >= h.t[-1] - 2 * revolution
    band_peak = np.abs(band[in_late]).max(axis=0)
    drift = h.u[h.t >= h.t[-1] - revolution, n].mean(axis=0)
    return {
        "time_step_ms": float((h.t[1] - h.t[0]) * 1e3),
        "centre_band_um": float(_mag(band_peak[0]) * 1e6),
        "edge_band_um": float(_mag(band_peak[1]) * 1e6),
        "edge_z_band_um": float(band_peak[1, 1] * 1e6),
        "centre_drift_um": float(np.linalg.norm(drift) * 1e6),
        "centre_band_hist_um": (np.linalg.norm(band[:, 0], axis=-1) * 1e6).tolist(),
        "edge_band_hist_um": (np.linalg.norm(band[:, 1], axis=-1) * 1e6).tolist(),
        "duration_ms": float(h.t[-1] * 1e3),
        "centre_peak_um": float(_mag(whole[n]) * 1e6),
        "edge_peak_um": float(_mag(whole[n + 1]) * 1e6),
        "edge_z_peak_um": float(whole[n + 1, 1] * 1e6),
        "centre_late_um": float(_mag(late["centre"]) * 1e6),
        "edge_late_um": float(_mag(late["edge"]) * 1e6),
        "edge_z_late_um": float(late["edge"][1] * 1e6),
        "t_ms": (h.t * 1e3).tolist(),
        "centre_um": (np.linalg.norm(h.u[:, n], axis=-1) * 1e6).tolist(),
        "edge_um": (np.linalg.norm(h.u[:, n + 1], axis=-1) * 1e6).tolist(),
    }


def run_cases(cases: Mapping[str, Case], workers: int, examples_dir: Path = EXAMPLES_DIR,
              log: Callable[[str], None] = print,
              follow: FollowUp | None = None) -> dict[str, Solved]:
    """Solve every case once (names that are the same scene share one solve), in a pool of
    ``workers`` spawned processes with one BLAS thread each; transients (the longest) are
    submitted first, then what ``follow`` needs. Once those are solved, ``follow.make`` adds its
    cases to the same pool. Returns every named case, the follow-up's included. Scripts must
    call this under ``if __name__ == "__main__":``."""
    from .scene import scene_from_dict, scene_hash

    if follow is not None and not set(follow.needs) <= set(cases):
        raise ValueError("follow-up needs cases that are not in the plan: "
                         + ", ".join(sorted(set(follow.needs) - set(cases))))
    key: dict[str, str] = {}  # name -> scene hash
    todo: dict[str, dict] = {}  # hash -> scene dict, in submission order
    known: set[str] = set()
    solved: dict[str, Solved] = {}
    needs = set(follow.needs) if follow is not None else set()

    def add(new: Mapping[str, Case]) -> None:
        for name in sorted(new, key=lambda n: (not new[n].transient, n not in needs)):
            if name in key:
                continue
            d = scene_dict(new[name], examples_dir)
            key[name] = h = scene_hash(scene_from_dict(d))  # validates
            if h not in known:
                known.add(h)
                todo[h] = d

    def follow_up() -> bool:
        """Add the follow-up's cases once its needs are solved; True if it added any."""
        nonlocal follow
        if follow is None or any(key[n] not in solved for n in follow.needs):
            return False
        f, follow = follow, None
        before = len(todo)
        add(f.make({n: solved[key[n]] for n in f.needs}))
        return len(todo) > before

    add(cases)
    if workers == 1:
        while todo:
            h = next(iter(todo))
            solved[h] = solve_scene(todo.pop(h))
            follow_up()
    else:
        spawn = multiprocessing.get_context("spawn")  # fresh interpreters read the env below
        try:
            with one_blas_thread(), ProcessPoolExecutor(workers, mp_context=spawn) as pool:
                pending: dict = {}

                def submit() -> None:
                    for h in list(todo):
                        pending[pool.submit(solve_scene, todo.pop(h))] = h

                submit()
                while pending:
                    done, _ = wait(pending, return_when=FIRST_COMPLETED)
                    for fut in done:
                        solved[pending.pop(fut)] = fut.result()
                    if follow_up():
                        submit()
        except BrokenProcessPool as err:
            raise RuntimeError("a worker process died; from a script, call reproduce() under "
                               "`if __name__ == '__main__':` (workers are spawned and import "
                               "the main module), or use workers=1") from err
    log(f"  {len(known)} distinct solves for {len(key)} named cases")
    return {name: solved[key[name]] for name in key}


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
    claims: list[list[str]] = field(default_factory=list)  # for the summary: item, paper, ours,
    # verdict


# --------------------------------------------------------------------------- studies


def _rotor_mm(ctx: Context) -> tuple[float, float]:
    """Rotor plane above the base face (mm): the example's and the sensitivity's."""
    return (ctx.example(BARE).unit.motor.rotor_height_mm,
            dict(MOTOR_VARIANTS["rotor0.6"])["unit.motor.rotor_height_mm"])


def study_orientation(r: Mapping[str, Solved], ctx: Context) -> Section:
    rows, data = [], {}
    rotor, alt = _rotor_mm(ctx)
    for a in ("glued", "pogo"):
        for tag, label in (("", f"default (rotor {rotor:g} mm above base)"),
                           ("/rotor0.6", f"sensitivity: rotor {alt:g} mm above base")):
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
    claims = [[f"reverse gives a larger centre amplitude ({a}, bare)", "reverse > forward",
               f"reverse / forward = {data[a]['ratio']:.3f}", _verdict(data[a]["ratio"] > 1)]
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
        v = _verdict(_near(ratio, PAPER_POGO_RATIO), ratio < 1)
        vz = _verdict(_near(ratio_z, PAPER_POGO_RATIO), ratio_z < 1)
        if main:
            claims = [["pogo pins halve the edge amplitude (bare, reverse)", "x0.5",
                       f"x{ratio:.3f} (abs U_z: x{ratio_z:.3f})", f"{v} / {vz}"]]
        rows.append([label, _um(g.edge_um), _um(p.edge_um), f"{ratio:.3f}", f"{ratio_z:.3f}",
                     _um(g.centre_um), _um(p.centre_um), f"{PAPER_POGO_RATIO:g}",
                     f"{v} / {vz}" if main else f"({v} / {vz})"])
    text = ("Edge amplitude (skin at the unit's outer radius, um) glued vs on pogo pins. Verdict "
            f"rule: agrees if within {REL_TOL:.0%} of 0.5, partly if pogo still lowers the edge, "
            "else disagrees; given for the magnitude / the vertical component.\n\n" + _table(
                ["design", "glued edge (um)", "pogo edge (um)", "pogo / glued (magnitude)",
                 "pogo / glued (abs U_z)", "glued centre (um)", "pogo centre (um)",
                 "paper (Fig. 8b)", "verdict"], rows)
            + "\n\nThe bare unit has no rings, so on frictionless pins only its inertia holds "
              "it sideways. The harmonic solve is well defined"
            + (f", but the solver refuses {_refused(posed['bare'])} solves of it"
               if not _posed(posed["bare"]) else "")
            + ". Section (g) gives the A-C-D ratio under every ring contact.")
    return Section("2. Pogo pins (Fig. 8b)", text, data, claims)


def _material_row(letter: str) -> tuple[float, float, float]:
    from .materials import get_material

    m = get_material(LETTERS[letter])
    return m.E_Pa / 1e3, m.density_kg_m3, m.nu


def _range_verdict(values: Sequence[float], lo: float, hi: float) -> str:
    inside = [lo * (1 - REL_TOL) <= v <= hi * (1 + REL_TOL) for v in values]
    return _verdict(all(inside), any(inside))


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
    text = (f"Forward motor, glued, one {_ring_mm(ctx):g} mm ring (library small-strain moduli, "
            f"see Model), ring contact '{default}' (the default; (g) gives the others). "
            "Normalized edge = amplitude at the edge / centre magnitude.\n\n"
            + _table(["layer", "material", "E (kPa)", "density (kg/m3)", "nu", "centre (um)",
                      "edge (um)", "normalized (magnitude)", "normalized (abs U_z)"], rows)
            + "\n\n" + _table(["claim", "paper (Fig. 9a)", "ours (magnitude)",
                               "ours (abs U_z)", "verdict (magnitude / U_z)"], claim)
            + f"\n\nVerdict rule: agrees if every material lies in the paper's range widened by "
              f"{REL_TOL:.0%}, partly if some do.\n\n![single layers](single_layers.png)")
    c = claim[0]
    return Section("3. Single layers A-D (Fig. 9a)", text, data,
                   [[c[0], c[1], f"{c[2]} (abs U_z: {c[3]})", c[4]]])


def _ranked(r: Mapping[str, Solved], triples: Sequence[str], vertical: bool) -> list[str]:
    def value(t: str) -> float:
        s = r[f"triple/{t}"]
        return s.norm_z if vertical else s.norm
    return sorted(triples, key=value)


def study_triples(r: Mapping[str, Solved], triples: Sequence[str], ctx: Context) -> Section:
    default = ctx.default
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
    text = (f"Reverse motor on pogo pins, three {_ring_mm(ctx):g} mm rings, ring contact "
            f"'{default}' (the default; (g) gives the others for a subset), every ordered "
            f"triple of A-D ({n} designs; layer 1 is the innermost). Verdict rules: a number "
            f"agrees within {REL_TOL:.0%} of the paper's; the minimum is 'partly' if it still "
            "restrains below every single layer, the maximum if it still enhances above them; "
            "A-C-D is 'partly' the most restraining if it ranks in the lowest quarter.\n\n"
            + _table(["claim", "paper (Fig. 9b/c)", "ours (magnitude)", "ours (abs U_z)",
                      "verdict (magnitude / U_z)"], claims)
            + "\n\n![triples](triples.png)\n\n<details><summary>All triples, ranked by the "
              "normalized edge (magnitude)</summary>\n\n"
            + _table(["rank", "layers 1-2-3", "centre (um)", "edge (um)",
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
        "edge_um": edge.tolist(), "normalized": norm.tolist(), "x": [float(x) for x in values],
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
    widest = _sweep_label(max(sweeps, key=lambda n: data[n]["x_ratio"]))[0]
    text = ("\n\n".join(parts) + "\n\n![sweeps](sweeps.png)\n\n"
            + "**Which parameter matters most.**\n\n"
            + _table(["parameter", "table range x_max/x_min", *[m[1] for m in measures],
                      "end-to-end slope ln(edge ratio)/ln(x ratio)"], rows)
            + "\n\n" + _table(["measure", "paper", "ours (ranking)", "verdict"], verdicts)
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
    k_ratio = (1 - 2 * lo) / (1 - 2 * hi)
    return ("show. Poisson's ratio acts through the bulk modulus K = E / (3 (1 - 2 nu)), which "
            f"changes x{k_ratio:.3g} between nu = {lo:g} and {hi:g} although nu itself changes "
            f"only x{hi / lo:.3g}.")


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
        rows.append([label, _um(s.centre_um), _um(s.edge_um), _pct(s.norm),
                     _fmt_mm(d50, length), _fmt_mm(d25, length), _pct(at)])
    claims = [["FE vs laser Doppler vibrometer on a phantom", f"R^2 = {PAPER_R2}",
               "not reproducible: a measurement on their phantom; we have no data"],
              ["two-point discrimination, optimized unit, successive stimuli",
               f"{PAPER_TPD_MM} mm (vs 13 mm earlier), p < 0.01",
               "not reproducible: a perception experiment with 10 people"]]
    text = (_table(["paper item", "paper", "ours"], claims)
            + "\n\n**Crosstalk proxy (ours, not in the paper).** For the three prototype designs:"
              " the distance from the unit's edge beyond which the skin amplitude (magnitude) "
              f"stays below 50 % / 25 % of the unit's centre amplitude (within the {length:g} mm "
              f"profile), and the amplitude at {PAPER_TPD_MM:g} mm from the edge (the paper's "
              "threshold) over the centre; rings in ring contact "
              f"'{default}'. A proxy for how far a neighbour must sit, not a perception model.\n\n"
            + _table(["design", "centre (um)", "edge (um)", "normalized edge", "below 50 % from",
                      "below 25 % from", f"at {PAPER_TPD_MM:g} mm"], rows))
    summary = [[c[0], c[1], c[2], "not reproducible"] for c in claims]
    return Section("6. Context the paper has no FE number for", text, data, summary)


def _fmt_mm(x: float, length: float) -> str:
    if x == 0:
        return "0 (below at the edge)"
    return f"> {length:g} mm" if math.isinf(x) else f"{x:.1f} mm"


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
        rows.append([n, *(f"{_um(c[k])} um: {_pct(rd[k + ' / magnitude'])} / "
                          f"{_pct(rd[k + ' / abs U_z'])}" for k in variants)])
    matrix, data = [], {}
    lo, hi = PAPER_SINGLE_RANGE
    for key in readings(r[names[0]]):
        singles = [readings(r[f"single/{c}"])[key] for c in LETTERS]
        vals = {t: readings(r[f"triple/{t}"])[key] for t in triples}
        o = sorted(triples, key=vals.get)
        d = {"single": [min(singles), max(singles)], "min": [o[0], vals[o[0]]],
             "max": [o[-1], vals[o[-1]]], "acd_rank": o.index("ACD") + 1 if "ACD" in o else None,
             "single_verdict": _range_verdict(singles, lo, hi),
             "min_near": _near(vals[o[0]], PAPER_TRIPLE_MIN),
             "max_near": _near(vals[o[-1]], PAPER_TRIPLE_MAX)}
        data[key] = d
        matrix.append([key, f"{_pct(min(singles))} - {_pct(max(singles))}",
                       d["single_verdict"], f"{_pct(vals[o[0]])} ({_design(o[0])})",
                       f"{_pct(vals[o[-1]])} ({_design(o[-1])})",
                       f"{d['acd_rank']} of {len(o)}"])
    text = ("Ours is the unit's own skin-side face on the axis (the skin under a glued unit, the "
            "board's underside on pogo pins, fem/unit.py). Alternatives: the skin surface on the "
            "axis (on pins it is not touched by the unit), the largest skin amplitude under the "
            "unit's footprint, and the motor's top face on the axis (where a vibrometer looking "
            "down on the unit would aim). On the axis the vertical amplitude of a rotating load "
            "vanishes, so every centre is a horizontal motion; the edge is read as magnitude or "
            "as |U_z|. Each cell: centre amplitude: normalized edge, magnitude / abs U_z.\n\n"
            + _table(["case", *variants], rows)
            + "\n\nThe paper's headline numbers under each reading (centre / edge component):"
              "\n\n"
            + _table(["reading", "single layers",
                      f"vs {_pct(PAPER_SINGLE_RANGE[0])} - {_pct(PAPER_SINGLE_RANGE[1])}",
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
        rows.append([n, *(f"{_pct(v.norm)} ({_pct(v.norm_z)})" for v in vals.values())])
    motor = ctx.example(BARE).unit.motor
    rotor, alt = _rotor_mm(ctx)
    heads = [f"{'rotor' if 'rotor' in path else 'mass'} {v:g} {'mm' if 'rotor' in path else 'g'}"
             for (path, v), in MOTOR_VARIANTS.values()]
    swap = math.isclose(alt, motor.height_mm - rotor)
    text = ("Normalized edge, magnitude (abs U_z in brackets), with the motor's defaults "
            f"({motor.mass_g:g} g, rotor plane {rotor:g} mm above the base face) and with one of "
            "them changed; ring contact as in the studies. The paper gives neither; the "
            "unbalance m e only scales every amplitude.\n\n"
            + _table(["case", "default", *heads], rows)
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
        rows.append([label, f"{bare.edge_um / g.edge_um:.3f}", _pct(acd.norm), _pct(acd.norm_z),
                     "n/a" if contact is None else ("yes" if contact else "no")])
    n_pins, r_p, edge = pogo.count, pogo.radius_mm, r["triple/ACD"].edge_mm
    first = n_pins - 1  # the lowest harmonic 1 +- k N besides n = 1
    text = (f"The {n_pins} pins are smeared into a ring (fem/unit.py): the vertical (n = 0) and "
            f"rocking (n = 1) stiffnesses are exact, the harmonics n = 1 +- {n_pins}k of the "
            "discrete pins are left out. Those decay away from the pin circle roughly like "
            f"(R_p / r)^|n|; at the edge of the A-C-D unit ({edge:g} mm, R_p = {r_p:g} mm) the "
            f"first, n = {first}, is about ({r_p:g} / {edge:g})^{first} = "
            f"{_pct((r_p / edge) ** first)} of its value at the pins. Below: how much the "
            "answers depend on the parts of the pin model that the smearing makes uncertain "
            "(A-C-D with the default ring contact).\n\n"
            + _table(["pin model", "bare reverse: pogo / glued edge", "A-C-D normalized",
                      "A-C-D normalized (abs U_z)", "A-C-D pins keep contact"], rows))
    return Section("(d) Three pins smeared into a ring", text, data)


def rejection(case: Case, kind: str, examples_dir: Path = EXAMPLES_DIR) -> str | None:
    """The solver's reason for refusing ``case`` as a ``kind`` ("static" or "transient")
    analysis, or None if it accepts it. It refuses a unit on frictionless pins that nothing
    holds sideways: a static solve is singular, a spin-up from rest drifts away."""
    from .problem import resolve_effects
    from .scene import SceneError, scene_from_dict

    d = scene_dict(replace(case, transient=kind == "transient"), examples_dir)
    if kind == "static":
        d["analysis"]["kind"] = "static"
    try:
        resolve_effects(scene_from_dict(d))
    except SceneError as err:
        return f"{err.field}: {err}"
    return None


def posedness(examples_dir: Path = EXAMPLES_DIR) -> dict[str, dict[str, str | None]]:
    """For the A-C-D unit on pins under every ring contact, and for the bare unit on pins
    ("bare"): the solver's refusal of a static and of a transient solve (None: accepted)."""
    units = {c: triple_case("ACD", contact_edit(c)) for c in RING_CONTACTS}
    units["bare"] = bare_case("reverse", "pogo")
    return {name: {k: rejection(case, k, examples_dir) for k in ("static", "transient")}
            for name, case in units.items()}


@dataclass(frozen=True)
class Context:
    """What the report text needs besides the results: the example scenes the cases start
    from, the default ring contact, and what the solver refuses (:func:`posedness`)."""

    examples_dir: Path
    default: str
    posed: Mapping[str, Mapping[str, str | None]]

    @classmethod
    def build(cls, examples_dir: str | os.PathLike = EXAMPLES_DIR) -> Context:
        path = Path(examples_dir)
        return cls(path, default_contact(path), posedness(path))

    def example(self, name: str):
        return _example(name, self.examples_dir)


def _posed(p: Mapping[str, str | None]) -> bool:
    return p["static"] is None and p["transient"] is None


def _refused(p: Mapping[str, str | None]) -> str:
    """"static and transient" (the kinds of solve the solver refuses), or ""."""
    return " and ".join(k for k in ("static", "transient") if p[k] is not None)


def _posed_text(p: Mapping[str, str | None]) -> str:
    return "yes" if _posed(p) else f"no, the solver refuses its {_refused(p)} solves"


def check_transient(r: Mapping[str, Solved], ctx: Context) -> Section | None:
    """(e) steady harmonic vs a transient from rest (their analysis kind)."""
    if "transient/ACD" not in r:
        return None
    h = r[contact_name("triple/ACD", TRANSIENT_CONTACT)]
    t = r["transient/ACD"].transient

    def row(label: str, centre: float, edge: float, edge_z: float) -> list[str]:
        return [label, _um(centre), _um(edge), _pct(edge / centre), _pct(edge_z / centre)]

    rows = [row("harmonic steady state", h.centre_um, h.edge_um, h.edge_z_um),
            row(f"transient, peak over 0-{t['duration_ms']:.0f} ms", t["centre_peak_um"],
                t["edge_peak_um"], t["edge_z_peak_um"]),
            row("transient, peak over the last two revolutions", t["centre_late_um"],
                t["edge_late_um"], t["edge_z_late_um"]),
            row(f"the same after a {LDV_BAND_HZ[0]:g}-{LDV_BAND_HZ[1]:g} Hz band-pass",
                t["centre_band_um"], t["edge_band_um"], t["edge_z_band_um"])]
    drift = t["centre_drift_um"] / h.centre_um
    literal = ctx.posed["none"]["transient"]
    scene = ctx.example(TRIPLE)
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
            + _table(["analysis", "centre (um)", "edge (um)", "normalized (magnitude)",
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


def _contact_label(contact: str, default: str) -> str:
    tags = {"none": "the paper's ties, literally", "bonded": "cast on the motor"}
    tag = "our default" if contact == default else tags.get(contact, "")
    return f"'{contact}'" + (f" ({tag})" if tag else "")


def _in_range(v: float) -> bool:
    lo, hi = PAPER_SINGLE_RANGE
    return lo * (1 - REL_TOL) <= v <= hi * (1 + REL_TOL)


def contact_verdicts(d: Mapping[str, dict], k: int) -> dict[str, str]:
    """Verdicts of one contact's headline numbers (``d`` from :func:`contact_readings`, over
    ``k`` triples), by the rules of sections 3 and 4; "min", "max", "acd" as
    magnitude / abs U_z."""
    m, z = d["unit face / magnitude"], d["unit face / abs U_z"]

    def v_min(x: dict) -> str:
        return _verdict(_near(x["min"][1], PAPER_TRIPLE_MIN), x["min"][1] < x["single"][0])

    def v_max(x: dict) -> str:
        return _verdict(_near(x["max"][1], PAPER_TRIPLE_MAX), x["max"][1] > x["single"][1])

    def v_acd(x: dict) -> str:
        return _verdict(x["acd_rank"] == 1, x["acd_rank"] is not None and x["acd_rank"] <= k / 4)

    return {"single": _verdict(all(map(_in_range, m["single"])), any(map(_in_range, m["single"]))),
            "min": f"{v_min(m)} / {v_min(z)}", "max": f"{v_max(m)} / {v_max(z)}",
            "acd": f"{v_acd(m)} / {v_acd(z)}"}


_CONTACT_DEFS = {
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
    from .scene import RING_GAP_MM

    order = [default, *(c for c in RING_CONTACTS if c != default)]
    names = [*(f"single/{c}" for c in LETTERS), *(f"triple/{t}" for t in study), "acd/glued"]
    rows, cases = [], {}
    for n in names:
        sols = {c: r[contact_name(n, c)] for c in order}
        cases[n] = {c: {"centre_um": s.centre_um, "edge_um": s.edge_um, "normalized": s.norm,
                        "normalized_uz": s.norm_z, "edge_mm": s.edge_mm}
                    for c, s in sols.items()}
        rows.append([n, *(f"{_um(s.centre_um)} um: {_pct(s.norm)} / {_pct(s.norm_z)}"
                          for s in sols.values())])
    table = {c: contact_readings(r, study, c) for c in order}
    k = len(study)
    claim_rows, verdicts, summary = [], {}, []
    for c in order:
        m, z = table[c]["unit face / magnitude"], table[c]["unit face / abs U_z"]
        ratio = (r[contact_name("triple/ACD", c)].edge_um
                 / r[contact_name("acd/glued", c)].edge_um)
        v = {**contact_verdicts(table[c], k), "posed": _posed_text(posed[c]),
             "pogo": _verdict(_near(ratio, PAPER_POGO_RATIO), ratio < 1)}
        verdicts[c] = {**v, "pogo_ratio": ratio}
        claim_rows.append([
            _contact_label(c, default), v["posed"],
            f"{_pct(m['single'][0])} - {_pct(m['single'][1])}: {v['single']}",
            f"{_pct(m['min'][1])} ({_design(m['min'][0])}) / {_pct(z['min'][1])}: {v['min']}",
            f"{_pct(m['max'][1])} ({_design(m['max'][0])}) / {_pct(z['max'][1])}: {v['max']}",
            f"{m['acd_rank']} of {k} ({_pct(m['acd'])}): {v['acd']}",
            f"{ratio:.3f}: {v['pogo']}"])
        summary.append([f"triples, ring contact {_contact_label(c, default)}"
                        + ("" if _posed(posed[c]) else ", not physically posed on pins")
                        + " (g)",
                        f"{_pct(PAPER_TRIPLE_MIN)} (A-C-D) - {_pct(PAPER_TRIPLE_MAX)}",
                        f"{_pct(m['min'][1])} ({_design(m['min'][0])}) - {_pct(m['max'][1])} "
                        f"({_design(m['max'][0])}) over {k} triples; A-C-D {_pct(m['acd'])}",
                        f"{v['min']} (min); {v['max']} (max)"])
    best = closest_readings(table)
    matrix = [[f"'{c}'", key, f"{_pct(d['single'][0])} - {_pct(d['single'][1])}",
               f"{_pct(d['min'][1])} ({_design(d['min'][0])})",
               f"{_pct(d['max'][1])} ({_design(d['max'][0])})", _pct(d["acd"]),
               f"x{d['f_min']:.2f}", f"x{d['f_max']:.2f}"]
              for c in order for key, d in table[c].items()]
    edges = {c: r[contact_name("triple/ACD", c)].edge_mm for c in order}
    refused = posed["none"]
    text = ("How the inner silicone ring meets the motor and board (`unit.ring_contact`); the "
            "rings are always tied to each other and to the skin.\n\n"
            + "\n".join(f"- **{_contact_label(c, default)}**: "
                        f"{_CONTACT_DEFS[c].format(gap=RING_GAP_MM)}." for c in order)
            + "\n\nThe slit moves the unit's edge out (A-C-D edge: "
            + ", ".join(f"{edges[c]:g} mm {c}" for c in order) + ").\n\n"
            "**Why the default.** Pin tips are frictionless, so sideways a unit on pins is held "
            "only by what its rings pass. With 'none' nothing holds it: the harmonic solve "
            "exists (the unit's inertia balances the rotating force), but a free-floating unit "
            "is not a physically posed model of a worn device. 'frictionless' is the weakest "
            "contact that holds it; 'bonded' needs silicone cast on the motor, while the paper "
            "describes hollow cylinders placed around it. A bare unit on pins (sections 1 and 2) "
            f"has no rings at all; physically posed: {_posed_text(posed['bare'])}."
            + ("" if _posed(refused) else
               " What the solver says of A-C-D on pins with 'none':\n\n"
               + "\n".join(f"  - {kind}: `{msg}`" for kind, msg in refused.items()
                           if msg is not None))
            + "\n\n"
            + f"The triples studied here ({k}: " + ", ".join(_design(t) for t in study)
            + ") are A-C-D, a fixed set, and the most restraining and most enhancing under the "
              f"default (section 4); minima, maxima and ranks below are over these {k} under "
              "every contact (all 64 are solved under the default only). Each cell: centre "
              "amplitude: normalized edge, magnitude / abs U_z.\n\n"
            + _table(["case", *(_contact_label(c, default) for c in order)], rows)
            + "\n\n" + _table(
                ["ring contact", "physically posed on pins",
                 f"single layers (paper {_pct(PAPER_SINGLE_RANGE[0])} - "
                 f"{_pct(PAPER_SINGLE_RANGE[1])})",
                 f"most restraining, magnitude / abs U_z (paper {_pct(PAPER_TRIPLE_MIN)})",
                 f"most enhancing, magnitude / abs U_z (paper {_pct(PAPER_TRIPLE_MAX)})",
                 "A-C-D rank (paper: 1)",
                 f"A-C-D pogo / glued edge (paper {PAPER_POGO_RATIO:g})"], claim_rows)
            + "\n\nVerdicts by the rules of sections 2-4 (where two: magnitude / abs U_z).\n\n"
            + f"**Every reading.** Each contact with each reading of (b) (centre / edge "
              f"component); the factors are the triples' min over {_pct(PAPER_TRIPLE_MIN)} "
              f"and max over {_pct(PAPER_TRIPLE_MAX)} (x1 = the paper).\n\n"
            + f"<details><summary>{len(matrix)} readings</summary>\n\n"
            + _table(["contact", "reading", "single layers", "triples: min", "triples: max",
                      "A-C-D", f"min / {_pct(PAPER_TRIPLE_MIN)}",
                      f"max / {_pct(PAPER_TRIPLE_MAX)}"], matrix)
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
        posed_note = ("physically posed." if _posed(posed[c]) else
                      "**not physically posed**: the unit floats sideways on its pins, and the "
                      f"solver refuses its {_refused(posed[c])} solves.")
        return (f"*ring contact '{c}'{' (our default)' if c == default else ''}, "
                f"{d['reading']}*: {what}; {posed_note}")

    lo, hi, both = best["min"], best["max"], best["both"]
    return "\n".join([
        f"- Closest to the paper's {_pct(PAPER_TRIPLE_MIN)}: "
        + one(lo, f"most restraining {_pct(lo['min'][1])} ({_design(lo['min'][0])}), A-C-D "
                  f"{_pct(lo['acd'])}"),
        f"- Closest to its {_pct(PAPER_TRIPLE_MAX)}: "
        + one(hi, f"most enhancing {_pct(hi['max'][1])} ({_design(hi['max'][0])})"),
        "- Closest to both at once: "
        + one(both, f"{_pct(both['min'][1])} ({_design(both['min'][0])}) - "
                    f"{_pct(both['max'][1])} ({_design(both['max'][0])})")])


def check_mesh(r: Mapping[str, Solved], ctx: Context) -> Section | None:
    """Discretisation: halve the near-field element size."""
    if "triple/ACD/mesh0.25" not in r:
        return None
    h0, h1 = ctx.example(TRIPLE).mesh.near_size_mm, dict(MESH_VARIANT)["mesh.near_size_mm"]
    rows, data = [], {}
    for n in ("single/A", "triple/ACD"):
        a, b = r[n], r[f"{n}/mesh0.25"]
        data[n] = [a.norm, b.norm]
        rows.append([n, _pct(a.norm), _pct(b.norm), f"{b.norm / a.norm - 1:+.1%}",
                     _um(a.edge_um), _um(b.edge_um)])
    text = _table(["case", f"normalized, {h0:g} mm", f"normalized, {h1:g} mm", "change",
                   f"edge um, {h0:g} mm", f"edge um, {h1:g} mm"], rows)
    return Section(f"(f) Mesh refinement (near-field element size {h0:g} -> {h1:g} mm)", text,
                   {"sizes_mm": [h0, h1], "normalized": data})


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


def fig_ring_contact(r: Mapping[str, Solved], triples: Sequence[str], default: str,
                     path: Path) -> None:
    plt = _plt()
    names = [*(f"single/{c}" for c in LETTERS),
             *(f"triple/{t}" for t in study_contact_triples(r, triples))]
    order = [default, *(c for c in RING_CONTACTS if c != default)]
    fig, ax = plt.subplots(figsize=(10, 5.0))
    x = np.arange(len(names))
    w = 0.8 / len(order)
    for i, c in enumerate(order):
        sols = [r[contact_name(n, c)] for n in names]
        ax.bar(x + (i - (len(order) - 1) / 2) * w, [s.norm for s in sols], w,
               color=f"C{i}", label=_contact_label(c, default) + ", magnitude")
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
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def fig_transient(r: Mapping[str, Solved], path: Path) -> None:
    plt = _plt()
    t = r["transient/ACD"].transient
    h = r[contact_name("triple/ACD", TRANSIENT_CONTACT)]
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(11, 3.8))
    ax.semilogy(t["t_ms"], t["centre_um"], lw=0.8, label="centre")
    ax.semilogy(t["t_ms"], t["edge_um"], lw=0.8, label="edge")
    ax.set_title("raw |u(t)| on the theta = 0 meridian", fontsize=10)
    bx.plot(t["t_ms"], t["centre_band_hist_um"], lw=0.8, label="centre, band-passed")
    bx.plot(t["t_ms"], t["edge_band_hist_um"], lw=0.8, label="edge, band-passed")
    bx.axhline(h.centre_um, color="C0", ls="--", label="centre, harmonic magnitude")
    bx.axhline(h.edge_um, color="C1", ls="--", label="edge, harmonic magnitude")
    bx.set_title(f"|u(t)| band-passed {LDV_BAND_HZ[0]:g}-{LDV_BAND_HZ[1]:g} Hz", fontsize=10)
    for a in (ax, bx):
        a.set_xlabel("time (ms)")
        a.set_ylabel("displacement magnitude (um)")
        a.legend(fontsize=7)
        a.grid(alpha=0.3)
    fig.suptitle(f"A-C-D, reverse, pogo, ring contact '{TRANSIENT_CONTACT}': transient from "
                 "rest vs steady state", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


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


@dataclass(frozen=True)
class Reproduction:
    """What ``reproduce`` produced: the report directory, the sections, timings (s)."""

    out_dir: Path
    sections: tuple[Section, ...]
    checks: tuple[Section, ...]
    wall_s: float
    solve_s: float
    n_cases: int
    n_solves: int
    workers: int
    quick: bool


def _model_text(r: Mapping[str, Solved], ctx: Context) -> str:
    from .materials import get_material
    from .scene import RING_GAP_MM

    scene, default = ctx.example(TRIPLE), ctx.default
    t, u, mesh = scene.tissue, scene.unit, scene.mesh
    m, pg, b = u.motor, u.pogo, u.board
    layers = t.layers
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
            f"{scene.analysis.frequency_hz:g} Hz. All defaults as in `examples/unit-*.toml`; "
            "nothing was tuned to the paper.\n"
            f"- Forearm (Table 1 as read in PAPER.md, {damping}): {forearm}.\n"
            f"- Silicones (library small-strain moduli, neo-Hookean from the Smooth-On 100 % "
            f"modulus, DESIGN.md sec. 4): {sil}.\n"
            f"- Motor (estimates, the paper gives none): {m.diameter_mm:g} x {m.height_mm:g} mm, "
            f"{m.mass_g:g} g, unbalance {m.unbalance_g_mm:g} g mm, rotor plane "
            f"{m.rotor_height_mm:g} mm above the base face (forward: base towards the skin), "
            f"{b.thickness_mm:g} mm flexible board (library material '{b.material}'). Pogo: "
            f"{pg.count} pins at {pg.radius_mm:g} mm, {pg.stiffness_N_m:g} N/m each, "
            f"{pg.length_mm:g} mm long, frictionless tips, smeared into a ring.\n"
            f"- Rings: {u.ring_thickness_mm:g} mm each, tied to each other and to the skin. "
            f"The inner ring meets the motor and board in ring contact **'{default}'** (our "
            "default): "
            + _CONTACT_DEFS[default].format(gap=RING_GAP_MM)
            + ". On frictionless pins something must hold the unit sideways; with the paper's "
              "ties taken literally ('none') only its inertia does"
            + (f", and the solver refuses {_refused(ctx.posed['none'])} solves of it"
               if not _posed(ctx.posed["none"]) else "")
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
            f"face, edge magnitude): the triples span {_pct(tri['min'][1])} "
            f"({_design(tri['min'][0])}) - {_pct(tri['max'][1])} ({_design(tri['max'][0])}) over "
            f"all {n}, A-C-D {_pct(tri['acd'])} (rank {tri['acd_rank']} of {n}); the paper: "
            f"{_pct(PAPER_TRIPLE_MIN)} (A-C-D) - {_pct(PAPER_TRIPLE_MAX)}.")
    if "g" not in checks:
        return text
    g = checks["g"].data
    k = len(g["triples"])
    posed_both = [(c, key) for c, per in g["readings"].items() for key, d in per.items()
                  if _posed(posed[c]) and _near(d["min"][1], PAPER_TRIPLE_MIN)
                  and _near(d["max"][1], PAPER_TRIPLE_MAX)]
    return (text + f"\n\n**Which model reading comes closest to the paper's triples**, among "
            f"the {len(RING_CONTACTS)} ring contacts x {len(next(iter(g['readings'].values())))}"
            f" centre / edge readings, over the {k} triples solved under every contact (g):"
            + "\n\n" + closest_text(g["closest"], ctx) + "\n\n"
            + ("No physically posed reading comes within "
               f"{REL_TOL:.0%} of both {_pct(PAPER_TRIPLE_MIN)} and {_pct(PAPER_TRIPLE_MAX)}."
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
             _table(["paper statement", "paper", "ours", "verdict"], summary), "",
             *([summary_note, ""] if summary_note else []),
             "## Model", "", model, "![orientation and pogo](structure.png)", ""]
    body = []
    for s in sections:
        body += [f"## {s.title}", "", s.text, ""]
    body += ["## Where we disagree, and why we think so", "", discussion, ""]
    for s in checks:
        body += [f"### {s.title}", "", s.text, ""]
    return "\n".join(head + body).rstrip() + "\n"


def _list(keys: Sequence[str]) -> str:
    return ", ".join(f"*{k}*" for k in keys) if keys else "no reading"


def _discuss_readout(r: Mapping[str, Solved], triples: Sequence[str],
                     checks: Mapping[str, Section]) -> str:
    b = checks["b"].data
    default = b["unit face / magnitude"]
    fits = {what: [k for k, d in b.items() if test(d)] for what, test in (
        ("single", lambda d: d["single_verdict"] == "agrees"),
        ("min", lambda d: d["min_near"]), ("max", lambda d: d["max_near"]))}
    every = [k for k in b if all(k in v for v in fits.values())]
    acd = [v for k, v in readings(r["triple/ACD"]).items()] if "ACD" in triples else []
    z_share = [r[f"single/{c}"].norm_z / r[f"single/{c}"].norm for c in LETTERS]
    lo, hi = PAPER_SINGLE_RANGE
    return ("- **What 'centre' and 'amplitude' mean (a, b).** The paper defines neither. On the "
            "axis a rotating load moves the unit only sideways, while at the edge the unit's "
            "rocking (the force acts above the skin) moves the skin up and down: for the single "
            f"layers |U_z| is {_pct(min(z_share))} - {_pct(max(z_share))} of the edge magnitude. "
            + (f"Across the {len(acd)} readings of (b) the A-C-D normalized edge ranges "
               f"{_pct(min(acd))} - {_pct(max(acd))}. " if acd else "")
            + f"Our default reading gives single layers {_pct(default['single'][0])} - "
              f"{_pct(default['single'][1])}. Of the {len(b)} readings, the single layers land "
              f"in {_pct(lo)} - {_pct(hi)} (+-{REL_TOL:.0%}) for {_list(fits['single'])}; the "
              f"triple minimum is within {REL_TOL:.0%} of {_pct(PAPER_TRIPLE_MIN)} for "
              f"{_list(fits['min'])}; the maximum within {REL_TOL:.0%} of "
              f"{_pct(PAPER_TRIPLE_MAX)} for {_list(fits['max'])}. "
            + ("No reading matches all three." if not every else
               f"All three match for {_list(every)}."))


def _discuss_contact(r: Mapping[str, Solved], checks: Mapping[str, Section], default: str
                     ) -> str | None:
    if "g" not in checks:
        return None
    g = checks["g"].data
    mag = {c: per["unit face / magnitude"] for c, per in g["readings"].items()}
    acd = {c: g["cases"]["triple/ACD"][c] for c in mag}
    span = "; ".join(f"'{c}' {_pct(d['min'][1])} - {_pct(d['max'][1])} (A-C-D "
                     f"{_pct(d['acd'])})" for c, d in mag.items())
    acd_vals = [v["normalized"] for v in acd.values()]
    by_contact = max(acd_vals) / min(acd_vals)
    by_material = max(d["max"][1] / d["min"][1] for d in mag.values())
    none = mag.get("none")
    text = ("- **How the rings meet the motor (g).** The paper ties the rings to each other and "
            "to the skin and says nothing about the motor. Over the "
            f"{len(g['triples'])} triples solved under every contact the normalized edge spans "
            f"{span}. The contact changes A-C-D by x{by_contact:.2f}, "
            + ("more" if by_contact > by_material else "less")
            + " than the choice of materials changes the triples under any one contact (at most "
              f"x{by_material:.2f}).")
    if none is not None and "none" != default:
        c_none, c_def = acd["none"]["centre_um"], acd[default]["centre_um"]
        text += (f" Taken literally ('none'), the unit on frictionless pins floats sideways: "
                 f"A-C-D's centre moves {_um(c_none)} um against {_um(c_def)} um with "
                 f"'{default}', and the edge is {_pct(acd['none']['normalized'])} of it. "
                 + (f"This comes closest to the paper's {_pct(PAPER_TRIPLE_MIN)}, "
                    if g["closest"]["min"]["contact"] == "none" else "")
                 + ("but no triple enhances: the most enhancing is "
                    f"{_pct(none['max'][1])} against the paper's {_pct(PAPER_TRIPLE_MAX)}. "
                    if none["max"][1] < none["single"][0] else "")
                 + f"We keep '{default}' as the default because it is physically posed, not "
                   "because of how it compares with the paper.")
    return text


def _discuss_pogo(r: Mapping[str, Solved], checks: Mapping[str, Section]) -> str:
    g, p = r["bare/reverse/glued"], r["bare/reverse/pogo"]
    ratio = p.edge_um / g.edge_um
    text = (f"- **Pogo pins (2, d).** On the bare reverse unit pins cut the edge amplitude to "
            f"x{ratio:.2f} (the paper: x{PAPER_POGO_RATIO:g}); the bare unit has no rings, so "
            "on frictionless pins only its inertia holds it sideways (centre "
            f"{_um(p.centre_um)} um on pins against {_um(g.centre_um)} um glued).")
    if "g" in checks:
        v = checks["g"].data["verdicts"]
        text += (" With the A-C-D rings: "
                 + ", ".join(f"x{d['pogo_ratio']:.2f} '{c}'" for c, d in v.items()) + " (g).")
    if "d" in checks:
        d = checks["d"].data
        ratios = [x["ratio"] for x in d.values()]
        near = [k for k, x in d.items() if _near(x["ratio"], PAPER_POGO_RATIO)]
        text += (f" The tip footprint, an arbitrary choice once the pins are a ring, moves "
                 f"A-C-D between {_pct(d['tip0.25']['acd'])} (0.25 mm) and "
                 f"{_pct(d['tip1']['acd'])} (1 mm); halving or doubling the spring constant "
                 f"gives {_pct(d['k0.5']['acd'])} - {_pct(d['k2']['acd'])}. The bare pogo ratio "
                 f"stays within {min(ratios):.2f} - {max(ratios):.2f}"
                 + (f", reaching x{PAPER_POGO_RATIO:g} for {_list(near)}." if near
                    else f", far from x{PAPER_POGO_RATIO:g}."))
    return text


def _discuss_motor(sections: Mapping[str, Section], checks: Mapping[str, Section],
                   ctx: Context) -> str:
    o = sections["orientation"].data
    rotor, alt = _rotor_mm(ctx)
    text = (f"- **Orientation depends on where the rotor sits in the can (1, c).** Reverse / "
            f"forward centre amplitude: {o['glued']['ratio']:.2f} glued, "
            f"{o['pogo']['ratio']:.2f} on pins with the rotor plane {rotor:g} mm above the "
            "base.")
    if "glued/rotor0.6" in o:
        text += (f" With it at {alt:g} mm: {o['glued/rotor0.6']['ratio']:.2f} and "
                 f"{o['pogo/rotor0.6']['ratio']:.2f}. The paper's Fig. 2 shows h but gives no "
                 "value, so the claim can not be checked without the motor's geometry.")
    if "c" in checks:
        acd = checks["c"].data["triple/ACD"]
        masses = {t: v for (t, ((path, v),)) in MOTOR_VARIANTS.items() if "mass" in path}
        default_mass = ctx.example(BARE).unit.motor.mass_g
        pairs = sorted([(default_mass, "default"), *((v, t) for t, v in masses.items())])
        text += (" Motor mass " + " / ".join(f"{m:g}" for m, _ in pairs) + " g gives A-C-D "
                 + " / ".join(_pct(acd[t][0]) for _, t in pairs)
                 + ": the normalized edge depends on a mass the paper does not give.")
    return text


def _discuss_transient(checks: Mapping[str, Section]) -> str | None:
    if "e" not in checks:
        return None
    e = checks["e"].data
    steady = e["harmonic"][1] / e["harmonic"][0]
    band = e["edge_band_um"] / e["centre_band_um"]
    c_dev = e["centre_band_um"] / e["harmonic"][0] - 1
    e_dev = e["edge_band_um"] / e["harmonic"][1] - 1
    settled = max(abs(c_dev), abs(e_dev)) < 0.05
    shift = band / steady - 1
    literal = ("the literal 'none' is refused by the solver" if e["none_refused"]
               else "the solver would also run 'none'")
    return (f"- **Steady vs transient (e).** The transient uses '{e['contact']}' ({literal}). "
            f"Raw peaks over the whole run give a normalized edge of "
            f"{_pct(e['edge_peak_um'] / e['centre_peak_um'])}, over the last two revolutions "
            f"{_pct(e['edge_late_um'] / e['centre_late_um'])}. Band-passed as the paper's "
            f"vibrometer data, the centre and edge peaks differ from the steady amplitudes by "
            f"{c_dev:+.0%} and {e_dev:+.0%}"
            + ("" if settled else f" (a {e['duration_ms']:.0f} ms run has not settled)")
            + f", the normalized edge is {_pct(band)} against {_pct(steady)} steady "
              f"({shift:+.0%}). "
            + ("The analysis kind does not explain the gaps to the paper."
               if abs(shift) < REL_TOL else
               "The analysis kind moves the normalized edge noticeably; see (e)."))


def _discuss_rest(sections: Mapping[str, Section], checks: Mapping[str, Section]) -> list[str]:
    from .materials import get_material

    lines = []
    if "f" in checks:
        f = checks["f"].data
        worst = max(abs(b / a - 1) for a, b in f["normalized"].values())
        h0, h1 = f["sizes_mm"]
        lines.append(f"- **Discretisation (f).** Refining the near-field elements from {h0:g} "
                     f"to {h1:g} mm changes the normalized edge by at most {worst:.1%}"
                     + (": not the cause." if worst < 0.05 else ": a possible contributor."))
    sw = sections["sweeps"].data
    if "density" in sw:
        edges = ", ".join(_um(x) for x in sw["density"]["edge_um"])
        xs = ", ".join(f"{x:g}" for x in sw["density"]["x"])
        first = _sweep_label(sw["ranking_edge_elasticity"][0])[0]
        e = sw["density"]["edge_um"]
        shape = ("monotonically" if all(np.diff(e) > 0) or all(np.diff(e) < 0)
                 else "not monotonically")
        lines.append(f"- **Density vs modulus (5).** By the local sensitivity the first is "
                     f"{first}; see section 5 for every measure. The edge amplitude changes "
                     f"{shape} with density ({edges} um at {xs} kg/m3). The paper's ranking "
                     "comes from box plots of transient histories (Figs. 10-12) that we can not "
                     "re-read.")
    moduli = [get_material(n).E_Pa / 1e3 for n in LETTERS.values()]
    lines.append("- **What we can not check.** (1) The paper makes the pogo pins the vibration "
                 "source; if it prescribed their motion rather than a force on the motor, centre "
                 "and edge respond differently. (2) Its constants for materials A-D are not "
                 f"given (we use library small-strain moduli, {min(moduli):g}-{max(moduli):g} "
                 "kPa). (3) What held its unit sideways on frictionless pins in 3D (the board "
                 "outline, the pins' lateral stiffness, a tie it does not list), tissue "
                 "damping, the run length and read-out of its transients.")
    return lines


def discussion_text(r: Mapping[str, Solved], triples: Sequence[str],
                    sections: Mapping[str, Section], checks: Mapping[str, Section],
                    ctx: Context) -> str:
    """The reading of the checks below it, driven by their numbers."""
    parts = [_discuss_readout(r, triples, checks), _discuss_contact(r, checks, ctx.default),
             _discuss_pogo(r, checks), _discuss_motor(sections, checks, ctx),
             _discuss_transient(checks), *_discuss_rest(sections, checks)]
    return "\n".join(p for p in parts if p)


def _atomic_dir(out: Path, fill: Callable[[Path], None]) -> None:
    """Build ``out`` in a temporary sibling directory, then swap it into place."""
    tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.tmp-", dir=out.parent))
    old = None
    try:
        umask = os.umask(0)
        os.umask(umask)
        tmp.chmod(0o777 & ~umask)  # mkdtemp makes it private; the report is not
        fill(tmp)
        if out.exists():
            old = Path(tempfile.mkdtemp(prefix=f".{out.name}.old-", dir=out.parent))
            os.replace(out, old / out.name)
        os.replace(tmp, out)
    except BaseException:
        if old is not None and not out.exists():
            os.replace(old / out.name, out)  # put the previous report back
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    finally:
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)


def _json_ready(r: Mapping[str, Solved]) -> dict:
    """Per-case numbers; profiles every 1 mm (the figures use the finer samples)."""
    out = {}
    every = max(1, round(1.0 / PROFILE_STEP_MM))
    for name, s in sorted(r.items()):
        out[name] = {"centre_um": s.centre_um, "edge_um": s.edge_um, "edge_uz_um": s.edge_z_um,
                     "normalized_edge": s.norm, "normalized_edge_uz": s.norm_z,
                     "edge_mm": s.edge_mm, "centre_variants_um": s.centre_variants_um(),
                     "profile": {
                         "distance_from_edge_mm": s.profile_mm[::every].tolist(),
                         "magnitude_over_centre": s.normalized_profile()[::every].tolist(),
                         "uz_over_centre": s.normalized_profile(True)[::every].tolist()},
                     "wall_s": s.wall_s, "dofs": s.dofs, "contact": s.contact}
    return out


def check_workers(workers: int | None) -> int:
    """The pool size: None = every core; else 1 <= workers <= 256."""
    if workers is None:
        return os.cpu_count() or 1
    if isinstance(workers, bool) or not isinstance(workers, int) or not 1 <= workers <= 256:
        raise ValueError(f"--workers = {workers!r} is out of range: allowed 1 <= workers <= 256 "
                         "(leave it out to use every core)")
    return workers


def check_out_dir(out_dir: str | os.PathLike) -> Path:
    out = Path(out_dir).resolve()
    if not out.parent.is_dir():
        raise ValueError(f"--out {out_dir}: the parent directory {out.parent} does not exist")
    if out.exists() and not out.is_dir():
        raise ValueError(f"--out {out_dir}: exists and is not a directory")
    return out


def reproduce(out_dir: str | os.PathLike = "reports/reproduce", workers: int | None = None,
              quick: bool = False, examples_dir: str | os.PathLike = EXAMPLES_DIR,
              log: Callable[[str], None] = print) -> Reproduction:
    """Run every study and write the report (README.md, PNGs, results.json) into ``out_dir``.

    Args:
        out_dir: report directory; replaced as a whole once everything succeeded.
        workers: process-pool size (None = every core).
        quick: the reduced case set of :func:`plan` (for tests).
        examples_dir: where ``unit-*.toml`` live.

    Workers are spawned processes: a script calling this needs the usual
    ``if __name__ == "__main__":`` guard (the ``hapticrom`` command has it).
    Raises:
        ValueError: bad ``workers`` or ``out_dir`` (nothing is written).
    """
    t0 = time.perf_counter()
    n_workers = check_workers(workers)
    out = check_out_dir(out_dir)
    p = plan(quick)
    log(f"hapticrom reproduce: {len(p.cases)} cases on {n_workers} worker(s)"
        + (" (quick)" if quick else ""))
    ctx = Context.build(examples_dir)
    r = run_cases(p.cases, n_workers, ctx.examples_dir, log, p.follow)
    sections = [study_orientation(r, ctx), study_pogo(r, ctx), study_single(r, ctx),
                study_triples(r, p.triples, ctx), study_sweeps(r, p.sweeps),
                study_context(r, ctx)]
    checks = {"a": check_amplitude_definition(r, p.triples),
              "b": check_centre_definition(r, p.triples)}
    if not quick:
        checks.update(c=check_motor(r, ctx), d=check_pogo(r, ctx))
    extra = {"e": check_transient(r, ctx), "f": check_mesh(r, ctx),
             "g": check_ring_contact(r, p.triples, ctx)}
    checks.update({k: v for k, v in extra.items() if v is not None})
    unique = {id(s): s for s in r.values()}
    solve_s = sum(s.wall_s for s in unique.values())
    keyed = dict(zip(("orientation", "pogo", "single", "triples", "sweeps", "context"),
                     sections, strict=True))
    discussion = discussion_text(r, p.triples, keyed, checks, ctx)
    note = closest_summary(keyed, checks, ctx)
    model = _model_text(r, ctx)

    def fill(tmp: Path) -> None:
        write_figures(r, p, tmp, ctx.default)
        run = {"quick": quick, "n_solves": len(unique), "n_cases": len(r),
               "workers": n_workers, "wall_s": time.perf_counter() - t0, "solve_s": solve_s}
        (tmp / "README.md").write_text(render(sections, list(checks.values()), discussion,
                                              run, r, model, note))
        doc = {"solver_version": SOLVER_VERSION, "run": run,
               "studies": {s.title: s.data for s in sections},
               "checks": {s.title: s.data for s in checks.values()}, "cases": _json_ready(r)}
        (tmp / "results.json").write_text(json.dumps(_finite(doc), indent=1, allow_nan=False)
                                          + "\n")

    _atomic_dir(out, fill)
    wall = time.perf_counter() - t0
    log(f"wrote {out} in {wall:.1f} s ({len(unique)} solves, sum of solve times {solve_s:.1f} s)")
    return Reproduction(out, tuple(sections), tuple(checks.values()), wall, solve_s,
                        len(r), len(unique), n_workers, quick)


def _finite(x: Any) -> Any:
    """``x`` with numpy scalars as Python numbers and NaN / inf as None (strict JSON)."""
    if isinstance(x, Mapping):
        return {str(k): _finite(v) for k, v in x.items()}
    if isinstance(x, list | tuple):
        return [_finite(v) for v in x]
    if isinstance(x, np.generic):
        x = x.item()
    if isinstance(x, float) and not math.isfinite(x):
        return None
    return x
