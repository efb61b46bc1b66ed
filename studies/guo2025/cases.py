"""The case language of the reproduction: named scenes built from the shipped prototype scenes
(``scenes/unit-*.toml``) by dotted-path edits, the plan of every case, and what the solver
refuses (posedness).

A case never tunes a default: it starts from a shipped scene (``scene_to_dict``), applies its
edits and is validated by ``scene_from_dict``. Units in names: mm, g, N/m, kPa, kg/m3.
"""

from __future__ import annotations

import functools
import itertools
import os
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from fem.problem import resolve_effects
from fem.scene import SceneError, load_scene, scene_from_dict, scene_to_dict

from .paper import COMMON, LETTERS, TABLE2_DENSITY, TABLE3_E_KPA, TABLE4_NU
from .solved import Solved

#: The prototype scenes the cases start from, shipped as package data.
SCENES_DIR = Path(__file__).resolve().parent / "scenes"
BARE = "unit-bare-forward.toml"
DOUBLE = "unit-double-forward.toml"
TRIPLE = "unit-triple-reverse-pogo.toml"
PROFILE_STEP_MM = 0.25  # output sampling only (the mesh does not depend on it)
ELASTICITY_STEP = 1.05  # x * 1.05**(+-1) for the central log-log derivative

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
#: How the inner ring meets the motor and board: every choice of ``unit.ring_contact``.
RING_CONTACTS = ("frictionless", "none", "bonded")
#: Triples solved under every contact besides the default's own extremes (added in the run):
#: A-C-D, its mirror, and A-A-A, A-D-D, D-D-D, the extremes under each contact of a one-off scan
#: of all 64 (fem 0.1.0), so that the subset spans each contact's range.
CONTACT_TRIPLES = ("AAA", "ACD", "ADD", "DCA", "DDD")


@dataclass(frozen=True)
class Case:
    """One scene: an example file plus edits (dotted path -> value); ``transient`` runs the
    time-domain solver instead (constant speed from rest, ``TRANSIENT_STEP_MS``).

    The paper's model is undamped, so every case sets the loss factor of each tissue layer
    and ring to 0 (the paper's reading), except a ``damped`` case, which keeps the library's
    sourced loss factors (``fem.materials``): the damping sensitivity."""

    base: str
    edits: tuple[tuple[str, Any], ...] = ()
    transient: bool = False
    damped: bool = False


def _set(d: dict, path: str, value: Any) -> None:
    *head, last = path.split(".")
    for key in head:
        d = d.setdefault(key, {})
    d[last] = value


def scene_dict(case: Case, scenes_dir: Path = SCENES_DIR) -> dict:
    """The TOML-shaped dict of ``case``: its example, the edits, the fine profile sampling."""
    d = scene_to_dict(load_scene(Path(scenes_dir) / case.base))
    _set(d, "output.profile_step_mm", PROFILE_STEP_MM)
    for path, value in case.edits:
        _set(d, path, value)
    if not case.damped:
        _undamped(d)
    if d["unit"]["attachment"] == "pogo" and not case.transient:
        _set(d, "effects.preload", True)  # report whether the pins stay in contact
    if case.transient:
        d["analysis"].update(kind="transient", duration_ms=TRANSIENT_MS,
                             time_step_ms=TRANSIENT_STEP_MS,
                             voltage_schedule=[[0.0, d["unit"]["motor"]["rated_voltage_V"]]])
        _set(d, "effects.spin_up", False)  # the paper turns the mass at 120 rev/s from t = 0
    return d


def case_scene(case: Case, scenes_dir: Path = SCENES_DIR):
    """The validated scene ``case`` solves (what the report describes)."""
    return scene_from_dict(scene_dict(case, scenes_dir))


def _undamped(d: dict) -> None:
    """Loss factor 0 on every tissue layer and ring of the scene dict ``d`` (in place)."""
    for layer in d["tissue"]["layer"]:
        layer["loss_factor"] = 0.0
    rings = d["unit"].get("encapsulation", [])
    d["unit"]["encapsulation"] = [
        {"material": ring, "loss_factor": 0.0} if isinstance(ring, str)
        else {**ring, "loss_factor": 0.0} for ring in rings]


@functools.lru_cache(maxsize=8)
def example_scene(name: str, scenes_dir: Path = SCENES_DIR):
    """The example scene ``name`` as loaded (its defaults are what every study starts from)."""
    return load_scene(Path(scenes_dir) / name)


def default_contact(scenes_dir: Path = SCENES_DIR) -> str:
    """The ring contact the triple example uses (the schema's default unless it sets one)."""
    return example_scene(TRIPLE, Path(scenes_dir)).unit.ring_contact


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
    for name, base in (("bare", BARE), ("double", DOUBLE), ("triple", TRIPLE)):
        c[f"proto/{name}/damped"] = Case(base, damped=True)
    sweeps = {"density": TABLE2_DENSITY, "E": TABLE3_E_KPA, "nu": TABLE4_NU}
    if quick:
        sweeps = {k: (v[0], v[-1]) for k, v in sweeps.items()}
    for name, values in sweeps.items():
        for x in values:
            point = sweep_point(name, x)
            c[uniform_name(*point)] = uniform_case(*point)
    for name in sweeps:  # the log-log derivative at the common point
        for s in (ELASTICITY_STEP, 1.0 / ELASTICITY_STEP):
            point = sweep_point(name, common_value(name) * s)
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
        order = ranked(r, triples, vertical)
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


def common_value(name: str) -> float:
    return COMMON[_SWEEP_INDEX[name]]


def sweep_point(name: str, x: float) -> tuple[float, float, float]:
    point = list(COMMON)
    point[_SWEEP_INDEX[name]] = float(x)
    return (point[0], point[1], point[2])


# --------------------------------------------------------------------------- solving




def rejection(case: Case, kind: str, scenes_dir: Path = SCENES_DIR) -> str | None:
    """The solver's reason for refusing ``case`` as a ``kind`` ("static" or "transient")
    analysis, or None if it accepts it. It refuses a unit on frictionless pins that nothing
    holds sideways: a static solve is singular, a spin-up from rest drifts away."""
    d = scene_dict(replace(case, transient=kind == "transient"), scenes_dir)
    if kind == "static":
        d["analysis"]["kind"] = "static"
    try:
        resolve_effects(scene_from_dict(d))
    except SceneError as err:
        return f"{err.field}: {err}"
    return None


def posedness(scenes_dir: Path = SCENES_DIR) -> dict[str, dict[str, str | None]]:
    """For the A-C-D unit on pins under every ring contact, and for the bare unit on pins
    ("bare"): the solver's refusal of a static and of a transient solve (None: accepted)."""
    units = {c: triple_case("ACD", contact_edit(c)) for c in RING_CONTACTS}
    units["bare"] = bare_case("reverse", "pogo")
    return {name: {k: rejection(case, k, scenes_dir) for k in ("static", "transient")}
            for name, case in units.items()}


@dataclass(frozen=True)
class Context:
    """What the report text needs besides the results: the example scenes the cases start
    from, the default ring contact, and what the solver refuses (:func:`posedness`)."""

    scenes_dir: Path
    default: str
    posed: Mapping[str, Mapping[str, str | None]]

    @classmethod
    def build(cls, scenes_dir: str | os.PathLike = SCENES_DIR) -> Context:
        path = Path(scenes_dir)
        return cls(path, default_contact(path), posedness(path))

    def example(self, name: str):
        return example_scene(name, self.scenes_dir)


def is_posed(p: Mapping[str, str | None]) -> bool:
    return p["static"] is None and p["transient"] is None


def refused_kinds(p: Mapping[str, str | None]) -> str:
    """"static and transient" (the kinds of solve the solver refuses), or ""."""
    return " and ".join(k for k in ("static", "transient") if p[k] is not None)


def posed_text(p: Mapping[str, str | None]) -> str:
    return "yes" if is_posed(p) else f"no, the solver refuses its {refused_kinds(p)} solves"

def ranked(r: Mapping[str, Solved], triples: Sequence[str], vertical: bool) -> list[str]:
    def value(t: str) -> float:
        s = r[f"triple/{t}"]
        return s.norm_z if vertical else s.norm
    return sorted(triples, key=value)
