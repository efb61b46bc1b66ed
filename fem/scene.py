"""Scene schema: a TOML file describing one FE problem, validated into frozen dataclasses.

Layout (the public contract; ``examples/forearm.toml`` and ``examples/unit-*.toml`` are
commented files)::

    [tissue]            radius_mm, side, base, and [[tissue.layer]] (top to bottom):
                        name, material, thickness_mm, E_kPa, density_kg_m3, nu, loss_factor
    [load]              kind, direction, radius_mm, amplitude_Pa, force_N
    [unit]              orientation, attachment, encapsulation, ring_thickness_mm
      [unit.motor]      diameter_mm, height_mm, mass_g, unbalance_g_mm (or force_N and
                        force_at_hz), rotor_height_mm, E_kPa, nu, rated_voltage_V,
                        rated_frequency_hz, start_voltage_V, tau_spinup_ms, tau_spindown_ms
      [unit.board]      thickness_mm, diameter_mm, material, E_kPa, density_kg_m3, nu
      [unit.pogo]       count, radius_mm, stiffness_N_m, length_mm, travel_mm, tip_diameter_mm
      [unit.actuator]   force_N
    [analysis]          kind, frequency_hz, time_step_ms, duration_ms, rho_inf, voltage_schedule
    [mesh]              near_size_mm, near_radius_mm, far_size_mm, order
    [output]            radii_mm, profile_step_mm, profile_length_mm, history_every
    [effects]           inertia, hysteretic_damping, encapsulation, pogo, unit_mass, rocking,
                        spin_up, preload (booleans; a missing key means "auto")

Values are stored in the user units named in each field (mm, kPa, g, ms); SI properties
(``E_Pa``, ``thickness_m``, ``unbalance_kg_m``, ...) convert at the edge. Every table is
described by a small spec (key -> :class:`Spec`: type, default, interval or choices), so adding
a table or an analysis kind is a matter of adding a spec entry and a dataclass.

The haptic unit. ``load.kind = "unit"`` is a coin ERM motor (an unbalance force rotating
parallel to the skin, Fourier mode 1) and ``"normal_actuator"`` an LRA or voice coil (a vertical
force on the housing, mode 0, amplitude ``[unit.actuator] force_N``). Both need a ``[unit]``
table, and a ``[unit]`` table needs one of them; ``load.direction``, ``radius_mm``,
``amplitude_Pa`` and ``force_N`` are then not used. ``encapsulation`` lists the silicone rings
inner to outer, each a library material name (aliases "A".."D" allowed) or an inline table with
the keys of a tissue layer except ``thickness_mm`` (every ring is ``ring_thickness_mm`` wide).
``[unit.pogo]`` is validated even when ``attachment = "glued"`` leaves it unused.
``[unit.actuator]`` is only allowed with ``"normal_actuator"``.

Resolution (what :func:`scene_to_dict` writes back, so that round trips are exact): a motor
given by ``force_N`` at ``force_at_hz`` is stored as ``unbalance_g_mm = force_N / (2 pi
force_at_hz)^2`` (converted to g mm); the force keys are input only and are not written back.
A ring equal to its library material is written as the canonical name, any other ring as a
full inline table. ``[effects]`` keeps only the keys set to true or false (None = auto) and is
left out when all are auto; ``[unit]`` is left out when the scene has no unit, and
``[unit.actuator]`` unless the load is a normal actuator (or the actuator is not the default).

Every error is a :class:`SceneError` whose ``.field`` is the dotted path of the offending
value (``tissue.layer[1].nu``, ``unit.encapsulation[2].E_kPa``) and whose message names the
allowed range or choices.
"""

from __future__ import annotations

import dataclasses
import difflib
import hashlib
import json
import math
import numbers
import re
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from fem.materials import UnknownMaterialError, get_material

__all__ = [
    "DEFAULT_FOREARM_LAYERS",
    "EFFECT_NAMES",
    "UNIT_LOAD_KINDS",
    "Actuator",
    "Analysis",
    "Board",
    "Effects",
    "Layer",
    "Load",
    "MeshSettings",
    "Motor",
    "Output",
    "Pogo",
    "Ring",
    "Scene",
    "SceneError",
    "Tissue",
    "Unit",
    "dump_scene_toml",
    "load_scene",
    "scene_from_dict",
    "scene_hash",
    "scene_to_dict",
]

MAX_LAYERS = 50
MAX_RINGS = 5
UNIT_LOAD_KINDS = ("unit", "normal_actuator")
"""Load kinds that are a haptic unit sitting on the skin (they need a ``[unit]`` table)."""


class SceneError(ValueError):
    """Invalid scene input. ``field`` is the dotted path of the bad value, e.g.
    ``tissue.layer[1].nu``, or ``"<file>"`` for a TOML syntax error."""

    def __init__(self, field: str, message: str) -> None:
        super().__init__(message)
        self.field = field



def _si(name: str, factor: float, doc: str = "") -> property:
    """A read-only SI view of a field kept in the units of the file (``thickness_mm`` ->
    ``thickness_m``): the field's value times ``factor``."""

    def value(self: Any) -> float:
        return getattr(self, name) * factor

    return property(value, doc=doc or f"``{name}`` in SI units (x {factor:g}).")


# --------------------------------------------------------------------------- dataclasses


@dataclass(frozen=True)
class Layer:
    """One tissue or encapsulation layer: thickness [mm], Young's modulus [kPa], density
    [kg/m3], Poisson's ratio [-], hysteretic loss factor eta [-] (E* = E (1 + i eta)).
    ``material`` is the canonical library name the values started from, if any."""

    name: str
    thickness_mm: float
    E_kPa: float
    density_kg_m3: float
    nu: float
    loss_factor: float = 0.0
    material: str | None = None

    thickness_m = _si("thickness_mm", 1e-3)
    E_Pa = _si("E_kPa", 1e3)


@dataclass(frozen=True)
class Tissue:
    """Layered cylinder of radius ``radius_mm`` [mm]; ``layers`` top (skin) to bottom."""

    layers: tuple[Layer, ...]
    radius_mm: float = 50.0
    side: str = "absorbing"
    base: str = "fixed"

    def __post_init__(self) -> None:
        object.__setattr__(self, "layers", tuple(self.layers))  # a list would be unhashable

    radius_m = _si("radius_mm", 1e-3)

    @property
    def depth_mm(self) -> float:
        """Total thickness of all layers [mm]."""
        return sum(layer.thickness_mm for layer in self.layers)


@dataclass(frozen=True)
class Load:
    """Surface load at the axis: a pressure patch of ``radius_mm`` [mm] and ``amplitude_Pa``
    [Pa], or a point force ``force_N`` [N]; "normal" is Fourier mode 0, "tangential" mode 1.
    For the unit kinds (:data:`UNIT_LOAD_KINDS`) the force comes from ``Scene.unit`` and
    ``direction``, ``radius_mm``, ``amplitude_Pa``, ``force_N`` are not used."""

    kind: str = "pressure_patch"
    direction: str = "normal"
    radius_mm: float = 2.0
    amplitude_Pa: float = 1000.0
    force_N: float = 1.0

    radius_m = _si("radius_mm", 1e-3)

    @property
    def fourier_mode(self) -> int:
        """The Fourier mode the load excites: 1 for an ERM unit (force parallel to the skin),
        0 for a normal actuator, else 0 / 1 for a normal / tangential direction."""
        if self.kind in UNIT_LOAD_KINDS:
            return 1 if self.kind == "unit" else 0
        return 0 if self.direction == "normal" else 1


@dataclass(frozen=True)
class Ring:
    """One silicone encapsulation ring (a hollow cylinder around the motor; its width is
    ``Unit.ring_thickness_mm``): Young's modulus [kPa], density [kg/m3], Poisson's ratio [-],
    hysteretic loss factor [-]; ``material`` is the canonical library name, if any."""

    name: str
    E_kPa: float
    density_kg_m3: float
    nu: float
    loss_factor: float = 0.0
    material: str | None = None

    E_Pa = _si("E_kPa", 1e3)


@dataclass(frozen=True)
class Motor:
    """The motor housing (a solid cylinder, effectively rigid) and, for an ERM, its rotor.

    Attributes:
        diameter_mm, height_mm: housing size [mm] (paper: 7 x 2 mm coin ERM).
        mass_g: motor mass [g], spread over the housing volume (estimate, not in the paper).
        unbalance_g_mm: eccentric mass x eccentricity m e [g mm]; the default 0.006 g mm over
            0.6 g gives m e / M = 10 um free displacement (DESIGN.md sec. 5). A file may give
            ``force_N`` at ``force_at_hz`` instead; it is stored resolved here.
        rotor_height_mm: rotor (eccentric mass) plane above the housing's base face [mm].
        E_kPa, nu: effective housing modulus [kPa] and Poisson's ratio [-].
        rated_voltage_V, rated_frequency_hz: spin speed [rev/s] at the rated voltage [V].
        start_voltage_V: voltage below which the rotor does not turn [V].
        tau_spinup_ms, tau_spindown_ms: first-order speed time constants [ms].
    """

    diameter_mm: float = 7.0
    height_mm: float = 2.0
    mass_g: float = 0.6
    unbalance_g_mm: float = 0.006
    rotor_height_mm: float = 1.4
    E_kPa: float = 5.0e6
    nu: float = 0.3
    rated_voltage_V: float = 3.3
    rated_frequency_hz: float = 120.0
    start_voltage_V: float = 0.4
    tau_spinup_ms: float = 20.0
    tau_spindown_ms: float = 35.0

    radius_m = _si("diameter_mm", 0.5e-3)
    height_m = _si("height_mm", 1e-3)
    mass_kg = _si("mass_g", 1e-3)
    unbalance_kg_m = _si("unbalance_g_mm", 1e-6, "m e [kg m] (1 g mm = 1e-6 kg m).")
    rotor_height_m = _si("rotor_height_mm", 1e-3)
    E_Pa = _si("E_kPa", 1e3)

    @property
    def volume_m3(self) -> float:
        return math.pi * self.radius_m**2 * self.height_m

    @property
    def density_kg_m3(self) -> float:
        """Effective housing density [kg/m3]: the mass spread over the cylinder."""
        return self.mass_kg / self.volume_m3

    @property
    def free_displacement_m(self) -> float:
        """Amplitude m e / M [m] of the free (unsupported) motor's circular vibration."""
        return self.unbalance_kg_m / self.mass_kg

    tau_spinup_s = _si("tau_spinup_ms", 1e-3)
    tau_spindown_s = _si("tau_spindown_ms", 1e-3)

    def force_N_at(self, frequency_hz: float) -> float:
        """Unbalance force amplitude m e (2 pi f)^2 [N] at spin frequency ``frequency_hz``."""
        return self.unbalance_kg_m * (2.0 * math.pi * frequency_hz) ** 2


@dataclass(frozen=True)
class Board:
    """Flexible PCB disc under the motor: thickness and diameter [mm] (thickness 0 = no
    board), library ``material`` (canonical name) and its possibly overridden E [kPa], density
    [kg/m3], Poisson's ratio [-]."""

    thickness_mm: float = 0.1
    diameter_mm: float = 7.0
    material: str = "pcb"
    E_kPa: float = 2.5e6
    density_kg_m3: float = 1420.0
    nu: float = 0.34

    @property
    def present(self) -> bool:
        """False for ``thickness_mm = 0`` (motor taped straight to the skin)."""
        return self.thickness_mm > 0

    thickness_m = _si("thickness_mm", 1e-3)
    radius_m = _si("diameter_mm", 0.5e-3)
    E_Pa = _si("E_kPa", 1e3)


@dataclass(frozen=True)
class Pogo:
    """Spring pins under the board (``attachment = "pogo"``): ``count`` pins at ``radius_mm``
    [mm] from the motor axis, axial stiffness ``stiffness_N_m`` [N/m] each, ``length_mm`` and
    ``travel_mm`` [mm], tip contact footprint ``tip_diameter_mm`` [mm] (paper: PZ8116)."""

    count: int = 3
    radius_mm: float = 2.25
    stiffness_N_m: float = 2942.0
    length_mm: float = 2.4
    travel_mm: float = 0.3
    tip_diameter_mm: float = 0.5

    radius_m = _si("radius_mm", 1e-3)
    length_m = _si("length_mm", 1e-3)
    travel_m = _si("travel_mm", 1e-3)
    tip_diameter_m = _si("tip_diameter_mm", 1e-3)

    @property
    def total_stiffness_N_m(self) -> float:
        """count x stiffness [N/m]: the pins act in parallel."""
        return self.count * self.stiffness_N_m

    @property
    def preload_N(self) -> float:
        """Spring force of one pin pressed through its full travel, k x travel [N]."""
        return self.stiffness_N_m * self.travel_m


@dataclass(frozen=True)
class Actuator:
    """Normal actuator (LRA / voice coil): vertical force amplitude on the housing [N]."""

    force_N: float = 0.1


@dataclass(frozen=True)
class Unit:
    """The haptic unit on the skin, centred on the axis.

    Attributes:
        orientation: "forward" (motor as bought) or "reverse" (flipped; moves the rotor plane).
        attachment: "glued" (bonded over its footprint) or "pogo" (spring pins, frictionless).
        encapsulation: silicone rings, inner to outer (0..5).
        ring_thickness_mm: radial width of every ring [mm].
        ring_contact: how the inner ring meets the motor and board. "frictionless" (default):
            a snug fit that passes normal pressure but no shear (the paper ties the rings to
            each other and to the skin only); "bonded": cast around the motor; "none": no
            interaction at all. Except when bonded, a slit of ``RING_GAP_MM`` separates the
            meshes so that only what the contact passes is tied.
        motor, board, pogo, actuator: the parts (``pogo`` used only with attachment "pogo",
            ``actuator`` only with ``load.kind = "normal_actuator"``).
    """

    orientation: str = "forward"
    attachment: str = "glued"
    encapsulation: tuple[Ring, ...] = ()
    ring_thickness_mm: float = 1.0
    ring_contact: str = "frictionless"
    motor: Motor = field(default_factory=Motor)
    board: Board = field(default_factory=Board)
    pogo: Pogo = field(default_factory=Pogo)
    actuator: Actuator = field(default_factory=Actuator)

    def __post_init__(self) -> None:
        object.__setattr__(self, "encapsulation", tuple(self.encapsulation))

    @property
    def ring_gap_mm(self) -> float:
        """Slit [mm] between the core and the inner ring: 0 when bonded (or without rings)."""
        if not self.encapsulation or self.ring_contact == "bonded":
            return 0.0
        return RING_GAP_MM

    @property
    def core_radius_mm(self) -> float:
        """Radius [mm] of the motor-and-board core the rings wrap (the board counts only when
        present)."""
        return _core_radius_mm(self.motor.diameter_mm, self.board.thickness_mm,
                               self.board.diameter_mm)

    @property
    def outer_radius_mm(self) -> float:
        """The unit's edge [mm]: core radius plus the rings."""
        if not self.encapsulation:
            return self.core_radius_mm
        rings = len(self.encapsulation) * self.ring_thickness_mm
        return self.core_radius_mm + self.ring_gap_mm + rings

    core_radius_m = _si("core_radius_mm", 1e-3)
    outer_radius_m = _si("outer_radius_mm", 1e-3)

    @property
    def ring_radii_mm(self) -> tuple[tuple[float, float], ...]:
        """(inner, outer) radius [mm] of each ring, inner to outer."""
        r0, t = self.core_radius_mm + self.ring_gap_mm, self.ring_thickness_mm
        return tuple((r0 + i * t, r0 + (i + 1) * t) for i in range(len(self.encapsulation)))

    @property
    def rotor_above_base_mm(self) -> float:
        """Rotor plane above the housing face towards the skin [mm]: ``rotor_height_mm``
        forward, ``height_mm - rotor_height_mm`` reverse (flipped)."""
        m = self.motor
        if self.orientation == "forward":
            return m.rotor_height_mm
        return m.height_mm - m.rotor_height_mm

    ring_thickness_m = _si("ring_thickness_mm", 1e-3)


#: Radial slit [mm] between a unit's core and its inner ring when they are not bonded: it keeps
#: the meshes apart so that only what the contact transmits is tied. Micrometre amplitudes
#: never close it; it moves the unit's edge out by this much.
RING_GAP_MM = 0.05

EFFECT_NAMES = ("inertia", "hysteretic_damping", "encapsulation", "pogo", "unit_mass", "rocking",
                "spin_up", "preload")
"""The physical effects a scene can force on (true) or off (false); absent = auto."""


@dataclass(frozen=True)
class Effects:
    """Physical effects forced on (True) or off (False); None lets the solver decide from the
    scene ("auto")."""

    inertia: bool | None = None
    hysteretic_damping: bool | None = None
    encapsulation: bool | None = None
    pogo: bool | None = None
    unit_mass: bool | None = None
    rocking: bool | None = None
    spin_up: bool | None = None
    preload: bool | None = None

    def resolve(self, name: str, auto: bool) -> bool:
        """The setting of effect ``name``, or ``auto`` when it is left to the solver."""
        value = getattr(self, name)
        return auto if value is None else value


@dataclass(frozen=True)
class Analysis:
    """Analysis kind; ``frequency_hz`` drives harmonic analyses (and normal actuators in a
    transient). Transient: step and duration [ms], generalised-alpha spectral radius
    ``rho_inf`` [-], and the ERM drive as (t_ms, volts) steps, each held until the next."""

    kind: str = "static"
    frequency_hz: float = 120.0
    time_step_ms: float = 0.05
    duration_ms: float = 200.0
    rho_inf: float = 0.9
    voltage_schedule: tuple[tuple[float, float], ...] = ((0.0, 3.3),)

    def __post_init__(self) -> None:
        steps = self.voltage_schedule  # lists become tuples (hashable); validation does the rest
        if isinstance(steps, list | tuple):
            object.__setattr__(self, "voltage_schedule", tuple(
                tuple(pair) if isinstance(pair, list | tuple) else pair for pair in steps))

    time_step_s = _si("time_step_ms", 1e-3)
    duration_s = _si("duration_ms", 1e-3)

    @property
    def voltage_schedule_s(self) -> tuple[tuple[float, float], ...]:
        """The schedule as (t_start_s, volts) pairs (``fem.motor.VoltageSchedule`` steps)."""
        return tuple((t * 1e-3, v) for t, v in self.voltage_schedule)


@dataclass(frozen=True)
class MeshSettings:
    """Element size [mm] within ``near_radius_mm`` of the axis and beyond; element order."""

    near_size_mm: float = 0.5
    near_radius_mm: float = 8.0
    far_size_mm: float = 2.0
    order: int = 2


@dataclass(frozen=True)
class Output:
    """Surface probe radii [mm], stored in the order given; the surface profile from the unit
    edge outwards every ``profile_step_mm`` over ``profile_length_mm`` [mm]; transient
    histories are recorded every ``history_every``-th step."""

    radii_mm: tuple[float, ...] = (0.0, 2.0, 4.0, 8.0, 12.0, 16.0, 20.0)
    profile_step_mm: float = 1.0
    profile_length_mm: float = 20.0
    history_every: int = 1

    def __post_init__(self) -> None:
        object.__setattr__(self, "radii_mm", tuple(self.radii_mm))

    @property
    def radii_m(self) -> tuple[float, ...]:
        return tuple(r * 1e-3 for r in self.radii_mm)

    profile_step_m = _si("profile_step_mm", 1e-3)
    profile_length_m = _si("profile_length_mm", 1e-3)

    @property
    def profile_distances_mm(self) -> tuple[float, ...]:
        """Profile sample distances from the edge [mm]: 0, step, ... up to the length (the
        length itself included when it is a whole number of steps, to 1e-9 relative)."""
        n = math.floor(self.profile_length_mm / self.profile_step_mm * (1 + 1e-9))
        return tuple(i * self.profile_step_mm for i in range(n + 1))


@dataclass(frozen=True)
class Scene:
    """A complete, validated FE scene. Construction validates (raises :class:`SceneError`)."""

    tissue: Tissue
    load: Load = field(default_factory=Load)
    analysis: Analysis = field(default_factory=Analysis)
    mesh: MeshSettings = field(default_factory=MeshSettings)
    output: Output = field(default_factory=Output)
    unit: Unit | None = None
    effects: Effects = field(default_factory=Effects)

    def __post_init__(self) -> None:
        _validate(scene_to_dict(self))  # direct construction gets the same checks as a file


# The paper's forearm (Guo et al. 2025, Table 1, as read in PAPER.md). The paper states a
# 31.9 mm block, which fits none of the ways to split Table 1's digits; this reading
# (1.9 + 14 + 21 + 5 = 41.9 mm) keeps the plausible layer thicknesses and is a documented choice.
DEFAULT_FOREARM_LAYERS: tuple[Layer, ...] = (
    Layer("skin", 1.9, 49.0, 1116.0, 0.47, 0.0, "skin"),
    Layer("subcutaneous", 14.0, 10.0, 1116.0, 0.47, 0.0, "subcutaneous"),
    Layer("muscle", 21.0, 53.0, 1116.0, 0.47, 0.0, "muscle"),
    Layer("bone", 5.0, 2.94e6, 2000.0, 0.32, 0.0, "bone"),
)


def _core_radius_mm(motor_diameter_mm: float, board_thickness_mm: float,
                    board_diameter_mm: float) -> float:
    # One definition for Unit.core_radius_mm and the validator (which works on dicts).
    board = board_diameter_mm if board_thickness_mm > 0 else 0.0
    return 0.5 * max(motor_diameter_mm, board)


# --------------------------------------------------------------------------- table specs

REQUIRED: Any = object()  # sentinel: no default


class Schedule:
    """Spec kind marker: a non-empty list of [t_ms, volts] pairs, the first at t_ms = 0, times
    strictly increasing; ``Spec.interval`` bounds the volts."""


@dataclass(frozen=True)
class Spec:
    """One key of a table: ``kind`` (float, int, str, bool, tuple = list of floats, or
    :class:`Schedule`), default (None: optional, no value), ``interval`` in math notation
    ("(0, 1e9]"; a bound may be a dotted path of an earlier resolved value, e.g.
    "tissue.radius_mm"), enum ``choices``, ``nonzero``; ``input_only`` keys are accepted in
    files but resolved into other keys, not stored."""

    kind: type
    default: Any = REQUIRED
    interval: str = ""
    choices: tuple[Any, ...] = ()
    nonzero: bool = False
    input_only: bool = False


_LAYER = {
    "name": Spec(str, None),  # default: the material name, else "layer<i>"
    "material": Spec(str, None),  # library name; explicit fields below override it
    "thickness_mm": Spec(float, REQUIRED, "(0, 10000]"),
    "E_kPa": Spec(float, REQUIRED, "(0, 1e9]"),
    "density_kg_m3": Spec(float, REQUIRED, "(0, 1e5]"),
    "nu": Spec(float, REQUIRED, "[0, 0.5)"),
    "loss_factor": Spec(float, 0.0, "[0, 2]"),
}
_RING = {key: spec for key, spec in _LAYER.items() if key != "thickness_mm"}  # name: "ring<i>"

_MOTOR = {
    "diameter_mm": Spec(float, 7.0, "(0, 100]"),
    "height_mm": Spec(float, 2.0, "(0, 50]"),
    "mass_g": Spec(float, 0.6, "(0, 1000]"),
    "unbalance_g_mm": Spec(float, 0.006, "(0, 1000]"),
    "force_N": Spec(float, None, "(0, 1e3]", input_only=True),  # -> unbalance_g_mm
    "force_at_hz": Spec(float, None, "(0, 1e5]", input_only=True),
    "rotor_height_mm": Spec(float, 1.4, "[0, unit.motor.height_mm]"),
    "E_kPa": Spec(float, 5.0e6, "(0, 1e9]"),
    "nu": Spec(float, 0.3, "[0, 0.5)"),
    "rated_voltage_V": Spec(float, 3.3, "(0, 50]"),
    "rated_frequency_hz": Spec(float, 120.0, "(0, 1e4]"),
    "start_voltage_V": Spec(float, 0.4, "[0, unit.motor.rated_voltage_V)"),
    "tau_spinup_ms": Spec(float, 20.0, "(0, 1e4]"),
    "tau_spindown_ms": Spec(float, 35.0, "(0, 1e4]"),
}
_BOARD = {
    "thickness_mm": Spec(float, 0.1, "[0, 10]"),
    "diameter_mm": Spec(float, 7.0, "(0, 100]"),
    "material": Spec(str, "pcb"),  # library name; the three keys below default to its values
    "E_kPa": Spec(float, REQUIRED, "(0, 1e9]"),
    "density_kg_m3": Spec(float, REQUIRED, "(0, 1e5]"),
    "nu": Spec(float, REQUIRED, "[0, 0.5)"),
}
_POGO = {
    "count": Spec(int, 3, "[1, 64]"),
    "radius_mm": Spec(float, 2.25, "(0, 50]"),
    "stiffness_N_m": Spec(float, 2942.0, "(0, 1e9]"),
    "length_mm": Spec(float, 2.4, "(0, 50]"),
    "travel_mm": Spec(float, 0.3, "[0, unit.pogo.length_mm)"),
    "tip_diameter_mm": Spec(float, 0.5, "(0, 5]"),
}
_ACTUATOR = {"force_N": Spec(float, 0.1, "[-1e3, 1e3]", nonzero=True)}

# [unit]: its own keys, the rings list, then its part tables (in this order when written).
_UNIT = {
    "orientation": Spec(str, "forward", choices=("forward", "reverse")),
    "attachment": Spec(str, "glued", choices=("glued", "pogo")),
    "ring_thickness_mm": Spec(float, 1.0, "(0, 20]"),
    "ring_contact": Spec(str, "frictionless", choices=("frictionless", "bonded", "none")),
}
_UNIT_PARTS: dict[str, tuple[type, dict[str, Spec]]] = {
    "motor": (Motor, _MOTOR),
    "board": (Board, _BOARD),
    "pogo": (Pogo, _POGO),
    "actuator": (Actuator, _ACTUATOR),
}
_UNIT_KEYS = ["orientation", "attachment", "encapsulation", "ring_thickness_mm", "ring_contact",
              *_UNIT_PARTS]

# Table name -> (dataclass, specs). Order matters: intervals may refer to earlier values, and
# the [unit] checks need tissue.radius_mm and load.kind.
_TABLES: dict[str, tuple[type, dict[str, Spec]]] = {
    "tissue": (Tissue, {
        "radius_mm": Spec(float, 50.0, "(0, 1e5]"),
        "side": Spec(str, "absorbing", choices=("absorbing", "fixed", "free")),
        "base": Spec(str, "fixed", choices=("fixed", "absorbing")),
    }),
    "load": (Load, {
        "kind": Spec(str, "pressure_patch",
                     choices=("pressure_patch", "point_force", *UNIT_LOAD_KINDS)),
        "direction": Spec(str, "normal", choices=("normal", "tangential")),
        "radius_mm": Spec(float, 2.0, "(0, tissue.radius_mm)"),
        "amplitude_Pa": Spec(float, 1000.0, "[-1e9, 1e9]", nonzero=True),
        "force_N": Spec(float, 1.0, "[-1e9, 1e9]", nonzero=True),
    }),
    "unit": (Unit, _UNIT),
    "analysis": (Analysis, {
        "kind": Spec(str, "static", choices=("static", "harmonic", "transient")),
        "frequency_hz": Spec(float, 120.0, "(0, 1e5]"),
        "time_step_ms": Spec(float, 0.05, "(0, 100]"),
        "duration_ms": Spec(float, 200.0, "[analysis.time_step_ms, 1e5]"),
        "rho_inf": Spec(float, 0.9, "[0, 1]"),
        "voltage_schedule": Spec(Schedule, ((0.0, 3.3),), "[-50, 50]"),
    }),
    "mesh": (MeshSettings, {
        "near_size_mm": Spec(float, 0.5, "(0, 100]"),
        "near_radius_mm": Spec(float, 8.0, "(0, tissue.radius_mm]"),
        "far_size_mm": Spec(float, 2.0, "[mesh.near_size_mm, 1000]"),
        "order": Spec(int, 2, choices=(1, 2)),
    }),
    "output": (Output, {
        "radii_mm": Spec(tuple, (0.0, 2.0, 4.0, 8.0, 12.0, 16.0, 20.0), "[0, tissue.radius_mm]"),
        "profile_step_mm": Spec(float, 1.0, "(0, 100]"),
        "profile_length_mm": Spec(float, 20.0, "(0, 1000]"),
        "history_every": Spec(int, 1, "[1, 1e6]"),
    }),
    "effects": (Effects, {name: Spec(bool, None) for name in EFFECT_NAMES}),
}
_SUBARRAYS = {"tissue": "layer"}  # array-of-tables keys inside a table
_SCHEDULE_T = Spec(float, REQUIRED, "[0, 1e5]")  # the t_ms of a schedule step

# --------------------------------------------------------------------------- validation


def _fail_unknown(path: str, key: str, allowed: list[str]) -> None:
    where = f"{path}.{key}" if path else key
    close = difflib.get_close_matches(key, allowed, n=1)
    hint = f"did you mean {close[0]!r}? " if close else ""
    raise SceneError(where, f"unknown key {where!r}: {hint}allowed keys: {', '.join(allowed)}")


def _as_table(raw: Any, path: str, allowed: list[str]) -> Mapping[str, Any]:
    if not isinstance(raw, Mapping):
        raise SceneError(path, f"{path or 'the scene'} must be a table, got {type(raw).__name__}")
    for key in raw:
        if key not in allowed:
            _fail_unknown(path, str(key), allowed)
    return raw


def _bound(token: str, ctx: Mapping[str, Any]) -> tuple[float, str]:
    try:
        return float(token), token
    except ValueError:  # a dotted path to an earlier value
        return ctx[token], f"{token} (= {ctx[token]:g})"


def _interval(spec: Spec, key: str, ctx: Mapping[str, Any]) -> tuple[float, float, str]:
    """Bounds of ``spec.interval`` and its readable form, e.g. ``0 <= nu < 0.5``."""
    lo_tok, hi_tok = (t.strip() for t in spec.interval[1:-1].split(","))
    (lo, lo_txt), (hi, hi_txt) = _bound(lo_tok, ctx), _bound(hi_tok, ctx)
    lo_op = "<" if spec.interval[0] == "(" else "<="
    hi_op = "<" if spec.interval[-1] == ")" else "<="
    text = f"{lo_txt} {lo_op} {key} {hi_op} {hi_txt}" + (", non-zero" if spec.nonzero else "")
    return lo, hi, text


def _check_interval(value: float, spec: Spec, key: str, path: str, ctx: Mapping[str, Any]):
    lo, hi, allowed = _interval(spec, key, ctx)
    lo_ok = lo < value if spec.interval[0] == "(" else lo <= value  # both False for NaN
    hi_ok = value < hi if spec.interval[-1] == ")" else value <= hi
    if not (lo_ok and hi_ok) or (spec.nonzero and value == 0):
        raise SceneError(path, f"{path} = {value!r} is out of range: allowed {allowed}")


def _number(value: Any, kind: type, path: str) -> float | int:
    # numbers.Real/Integral also admit numpy scalars from parameter sweeps; bool is excluded.
    abc = numbers.Integral if kind is int else numbers.Real
    if isinstance(value, bool | np.bool_) or not isinstance(value, abc):
        what = "an integer" if kind is int else "a number (float or int)"
        extra = " (true/false is not a number)" if isinstance(value, bool | np.bool_) else ""
        raise SceneError(path, f"{path} = {value!r} has the wrong type: expected {what}, "
                         f"got {type(value).__name__}{extra}")
    try:
        return kind(value)
    except OverflowError:  # an integer too large for a float
        raise SceneError(path, f"{path} = {value!r} is out of range: not a finite float") from None


def _read_schedule(value: Any, spec: Spec, path: str,
                   ctx: Mapping[str, Any]) -> tuple[tuple[float, float], ...]:
    """A list of [t_ms, volts] steps: t_ms starts at 0 and increases strictly."""
    if not isinstance(value, list | tuple) or not value:
        raise SceneError(path, f"{path} = {value!r} has the wrong type: expected a non-empty "
                         "list of [t_ms, volts] pairs, e.g. [[0.0, 3.3], [100.0, 0.0]]")
    steps: list[tuple[float, float]] = []
    for i, pair in enumerate(value):
        where = f"{path}[{i}]"
        if not isinstance(pair, list | tuple) or len(pair) != 2:
            raise SceneError(where, f"{where} = {pair!r} has the wrong type: expected a "
                             "[t_ms, volts] pair")
        t = _number(pair[0], float, f"{where}[0]")
        _check_interval(t, _SCHEDULE_T, "t_ms", f"{where}[0]", ctx)
        if i == 0 and t != 0:
            raise SceneError(f"{where}[0]", f"{where}[0] = {t!r} is out of range: the "
                             "schedule must start at t_ms = 0")
        if i > 0 and not t > steps[-1][0]:
            raise SceneError(f"{where}[0]", f"{where}[0] = {t!r} is out of range: times must "
                             f"increase strictly, allowed t_ms > {path}[{i - 1}][0] "
                             f"(= {steps[-1][0]:g})")
        volts = _number(pair[1], float, f"{where}[1]")
        _check_interval(volts, spec, "volts", f"{where}[1]", ctx)
        steps.append((t, volts))
    return tuple(steps)


def _read_value(value: Any, spec: Spec, key: str, path: str, ctx: Mapping[str, Any]) -> Any:
    """Type-check, convert (int -> float) and range-check one value."""
    if spec.kind is str:
        if not isinstance(value, str):
            raise SceneError(path, f"{path} = {value!r} has the wrong type: expected a string, "
                             f"got {type(value).__name__}")
        value = str(value)
    elif spec.kind is bool:
        if not isinstance(value, bool | np.bool_):
            raise SceneError(path, f"{path} = {value!r} has the wrong type: expected true or "
                             f"false (leave the key out for auto), got {type(value).__name__}")
        return bool(value)
    elif spec.kind is Schedule:
        return _read_schedule(value, spec, path, ctx)
    elif spec.kind is tuple:
        if not isinstance(value, list | tuple) or not value:
            raise SceneError(path, f"{path} = {value!r} has the wrong type: expected a "
                             f"non-empty list of numbers ({_interval(spec, key, ctx)[2]})")
        items = tuple(_number(item, float, f"{path}[{i}]") for i, item in enumerate(value))
        for i, item in enumerate(items):
            _check_interval(item, spec, key, f"{path}[{i}]", ctx)
        return items
    else:
        value = _number(value, spec.kind, path)
    if spec.choices and value not in spec.choices:
        choices = ", ".join(repr(c) for c in spec.choices)
        raise SceneError(path, f"{path} = {value!r} is not allowed: choose one of {choices}")
    if spec.interval:
        _check_interval(value, spec, key, path, ctx)
    return value


_FROM_MATERIAL = ("E_kPa", "density_kg_m3", "nu", "loss_factor")


def _read_fields(raw: Mapping[str, Any], specs: Mapping[str, Spec], path: str,
                 ctx: dict[str, Any], defaults: Mapping[str, Any] | None = None) -> dict[str, Any]:
    """Resolve every key of ``specs`` from ``raw`` (else its default); record it in ``ctx``."""
    out: dict[str, Any] = {}
    for key, spec in specs.items():
        where = f"{path}.{key}"
        default = (defaults or {}).get(key, spec.default)
        if key in raw:
            out[key] = _read_value(raw[key], spec, key, where, ctx)
        elif default is REQUIRED:
            alt = " or a library material (material = ...)" if key in _FROM_MATERIAL else ""
            raise SceneError(where, f"{where} is missing: give {key} "
                             f"({_interval(spec, key, ctx)[2]}){alt}")
        else:
            out[key] = default
            if default is not None and _relative(spec):  # e.g. a default above a given bound
                try:
                    _read_value(default, spec, key, where, ctx)
                except SceneError as err:
                    raise SceneError(err.field, str(err).replace(
                        " is out of range", " (the default) is out of range")) from None
        ctx[where] = out[key]
    return out


def _relative(spec: Spec) -> bool:
    """Whether a bound of ``spec.interval`` is a dotted path (so a default can violate it)."""
    return bool(spec.interval) and any(
        re.fullmatch(r"[-+0-9.e]+", token.strip()) is None
        for token in spec.interval[1:-1].split(","))


def _material(name: str, path: str) -> Any:
    try:
        return get_material(name)
    except UnknownMaterialError as err:
        raise SceneError(path, f"{path}: {err}") from None


def _read_solid(raw: Any, path: str, specs: Mapping[str, Spec], ctx: dict[str, Any],
                default_name: str | None = None) -> dict[str, Any]:
    """A table of solid properties whose E, density, nu (and loss factor, name) default to
    those of its library ``material``; the canonical material name is stored."""
    raw = _as_table(raw, path, list(specs))
    defaults: dict[str, Any] = {"name": default_name}
    material = raw.get("material", specs["material"].default)
    if material is not None:
        name = _read_value(material, specs["material"], "material", f"{path}.material", ctx)
        mat = _material(name, f"{path}.material")
        defaults = {"name": mat.name, "material": mat.name, "E_kPa": mat.E_Pa / 1e3,
                    "density_kg_m3": mat.density_kg_m3, "nu": mat.nu,
                    "loss_factor": mat.loss_factor}
        raw = {**raw, "material": mat.name}  # store the canonical name, not the alias
    return _read_fields(raw, specs, path, ctx, {k: v for k, v in defaults.items() if k in specs})


def _read_layers(raw: Any, ctx: dict[str, Any]) -> list[dict[str, Any]]:
    if raw is None:
        return [_solid_to_dict(layer, _LAYER) for layer in DEFAULT_FOREARM_LAYERS]
    if not isinstance(raw, list | tuple):
        raise SceneError("tissue.layer", "tissue.layer must be an array of tables "
                         f"([[tissue.layer]]), got {type(raw).__name__}")
    if not 1 <= len(raw) <= MAX_LAYERS:
        raise SceneError("tissue.layer", f"tissue.layer has {len(raw)} layers: "
                         f"allowed 1 <= number of layers <= {MAX_LAYERS}")
    return [_read_solid(item, f"tissue.layer[{i}]", _LAYER, ctx, f"layer{i}")
            for i, item in enumerate(raw)]


def _read_rings(raw: Any, ctx: dict[str, Any]) -> list[dict[str, Any]]:
    """``unit.encapsulation``: library names (aliases allowed) or inline layer-like tables."""
    path = "unit.encapsulation"
    if not isinstance(raw, list | tuple):
        raise SceneError(path, f"{path} = {raw!r} has the wrong type: expected a list of ring "
                         "materials (library names or inline tables), inner to outer")
    if len(raw) > MAX_RINGS:
        raise SceneError(path, f"{path} has {len(raw)} rings: allowed 0 <= number of rings "
                         f"<= {MAX_RINGS}")
    rings = []
    for i, item in enumerate(raw):
        where = f"{path}[{i}]"
        if isinstance(item, str):  # a bare name: exactly the library material
            item = {"material": _material(item, where).name}
        elif not isinstance(item, Mapping):
            raise SceneError(where, f"{where} = {item!r} has the wrong type: expected a "
                             "material name or an inline table {material = ..., E_kPa = ...}")
        rings.append(_read_solid(item, where, _RING, ctx, f"ring{i}"))
    return rings


def _read_motor(raw: Any, ctx: dict[str, Any]) -> dict[str, Any]:
    """[unit.motor]; an unbalance given as force_N at force_at_hz is resolved to g mm."""
    path = "unit.motor"
    raw = _as_table(raw, path, list(_MOTOR))
    out = _read_fields(raw, _MOTOR, path, ctx)
    force, hz = out.pop("force_N"), out.pop("force_at_hz")
    if force is not None and "unbalance_g_mm" in raw:
        raise SceneError(f"{path}.force_N", f"{path}: give either unbalance_g_mm or force_N "
                         "(with force_at_hz), not both")
    if (force is None) != (hz is None):
        key = "force_at_hz" if force is not None else "force_N"
        other = "force_N" if force is not None else "force_at_hz"
        raise SceneError(f"{path}.{key}", f"{path}.{key} is missing: {other} needs it "
                         f"({_interval(_MOTOR[key], key, ctx)[2]})")
    if force is not None:
        unbalance = force / (2.0 * math.pi * hz) ** 2 * 1e6  # kg m -> g mm
        spec = _MOTOR["unbalance_g_mm"]
        if not 0 < unbalance <= 1000:
            raise SceneError(f"{path}.force_N", f"{path}.force_N = {force!r} at force_at_hz = "
                             f"{hz!r} gives unbalance_g_mm = {unbalance:g}, out of range: "
                             f"allowed {_interval(spec, 'unbalance_g_mm', ctx)[2]}")
        out["unbalance_g_mm"] = unbalance
    return out


def _read_unit(raw: Any, ctx: dict[str, Any]) -> dict[str, Any]:
    kind = ctx["load.kind"]
    if kind not in UNIT_LOAD_KINDS:
        raise SceneError("unit", f'the [unit] table needs load.kind = "unit" or '
                         f'"normal_actuator" (load.kind is {kind!r}); remove [unit] otherwise')
    raw = _as_table(raw, "unit", _UNIT_KEYS)
    out = _read_fields(raw, _UNIT, "unit", ctx)
    out["encapsulation"] = _read_rings(raw.get("encapsulation", []), ctx)
    out["motor"] = _read_motor(raw.get("motor", {}), ctx)
    out["board"] = _read_solid(raw.get("board", {}), "unit.board", _BOARD, ctx)
    out["pogo"] = _read_fields(_as_table(raw.get("pogo", {}), "unit.pogo", list(_POGO)), _POGO,
                               "unit.pogo", ctx)
    if kind == "normal_actuator":
        table = _as_table(raw.get("actuator", {}), "unit.actuator", list(_ACTUATOR))
        out["actuator"] = _read_fields(table, _ACTUATOR, "unit.actuator", ctx)
    elif "actuator" in raw:
        raise SceneError("unit.actuator", 'unit.actuator is only used with load.kind = '
                         f'"normal_actuator" (load.kind is {kind!r}); remove it')
    _check_unit_geometry(out, ctx)
    return {key: out[key] for key in _UNIT_KEYS if key in out}


def _check_unit_geometry(u: Mapping[str, Any], ctx: Mapping[str, Any]) -> None:
    """Cross-field checks: pins under the board, and the unit inside the tissue cylinder."""
    board, pogo = u["board"], u["pogo"]
    if u["attachment"] == "pogo":
        if board["thickness_mm"] == 0:
            raise SceneError("unit.board.thickness_mm", 'unit.board.thickness_mm = 0.0 is out '
                             'of range for unit.attachment = "pogo": allowed 0 < thickness_mm '
                             "<= 10 (the pins are soldered under the board)")
        r_board = 0.5 * board["diameter_mm"]
        reach = pogo["radius_mm"] + 0.5 * pogo["tip_diameter_mm"]
        if reach > r_board:
            raise SceneError("unit.pogo.radius_mm", f"unit.pogo.radius_mm = "
                             f"{pogo['radius_mm']!r} is out of range: the pin tips must sit under "
                             "the board, allowed radius_mm + tip_diameter_mm / 2 <= "
                             f"unit.board.diameter_mm / 2 (= {r_board:g}), i.e. radius_mm <= "
                             f"{r_board - 0.5 * pogo['tip_diameter_mm']:g}")
    motor_d = u["motor"]["diameter_mm"]
    core = _core_radius_mm(motor_d, board["thickness_mm"], board["diameter_mm"])
    n = len(u["encapsulation"])
    gap_mm = RING_GAP_MM if n and u["ring_contact"] != "bonded" else 0.0
    outer = core + (gap_mm + n * u["ring_thickness_mm"] if n else 0.0)
    tissue = ctx["tissue.radius_mm"]
    if not outer < tissue:
        # blame the part that sets the size: the rings, else the motor or the board
        if n:
            where = "unit.encapsulation"
        elif core == 0.5 * motor_d:
            where = "unit.motor.diameter_mm"
        else:
            where = "unit.board.diameter_mm"
        gap = f" + {gap_mm:g} mm slit" if gap_mm else ""
        raise SceneError(where, f"the unit's outer radius {outer:g} mm (core {core:g} mm{gap} + "
                         f"{n} ring(s) x {u['ring_thickness_mm']:g} mm), set by {where}, is out "
                         f"of range: allowed outer radius < tissue.radius_mm (= {tissue:g})")


def _read_table(name: str, raw: Any, ctx: dict[str, Any]) -> dict[str, Any]:
    specs = _TABLES[name][1]
    sub = _SUBARRAYS.get(name)
    raw = _as_table(raw, name, list(specs) + ([sub] if sub else []))
    out = _read_fields(raw, specs, name, ctx)
    if name == "tissue":
        out["layer"] = _read_layers(raw.get("layer"), ctx)
    if name == "effects":  # auto (None) is the absence of a key
        out = {key: value for key, value in out.items() if value is not None}
    return out


def _validate(d: Mapping[str, Any]) -> dict[str, dict[str, Any]]:
    """Check ``d`` against the specs; return it fully resolved (defaults filled, ints -> float,
    material names canonical, rings as full tables), TOML-shaped. ``unit`` is present only for
    the unit load kinds, ``effects`` only when some effect is set."""
    _as_table(d, "", list(_TABLES))
    ctx: dict[str, Any] = {}
    out: dict[str, dict[str, Any]] = {}
    for name in _TABLES:
        if name == "unit":
            if "unit" in d:
                out[name] = _read_unit(d["unit"], ctx)
            elif ctx["load.kind"] in UNIT_LOAD_KINDS:
                raise SceneError("unit", f"load.kind = {ctx['load.kind']!r} needs a [unit] "
                                 "table (an empty one takes every default)")
            continue
        table = _read_table(name, d.get(name, {}), ctx)
        if table or name != "effects":
            out[name] = table
    return out


def _make(cls: type, table: Mapping[str, Any]) -> Any:
    """``cls`` from the keys of ``table`` that are its fields."""
    names = {f.name for f in dataclasses.fields(cls)}
    return cls(**{key: value for key, value in table.items() if key in names})


def _build_unit(u: Mapping[str, Any]) -> Unit:
    parts = {name: _make(cls, u[name]) for name, (cls, _) in _UNIT_PARTS.items() if name in u}
    return Unit(u["orientation"], u["attachment"],
                tuple(_make(Ring, ring) for ring in u["encapsulation"]), u["ring_thickness_mm"],
                u["ring_contact"], **parts)


def _build(resolved: Mapping[str, Mapping[str, Any]]) -> Scene:
    parts: dict[str, Any] = {}
    for name, (cls, _) in _TABLES.items():
        if name == "unit":
            if name in resolved:
                parts[name] = _build_unit(resolved[name])
        elif name == "tissue":
            layers = tuple(_make(Layer, layer) for layer in resolved[name]["layer"])
            parts[name] = _make(Tissue, {**resolved[name], "layers": layers})
        else:
            parts[name] = _make(cls, resolved.get(name, {}))
    return Scene(**parts)


# --------------------------------------------------------------------------- public API


def scene_from_dict(d: Mapping[str, Any]) -> Scene:
    """Validate a TOML-shaped mapping (as from ``tomllib``) and build a :class:`Scene`.
    Missing tables and keys take their documented defaults; no ``[[tissue.layer]]`` means the
    paper's forearm (:data:`DEFAULT_FOREARM_LAYERS`)."""
    return _build(_validate(d))


def load_scene(path: str | Path) -> Scene:
    """Read and validate a scene TOML file. Syntax errors raise :class:`SceneError` with
    ``field == "<file>"`` and the line in the message."""
    path = Path(path)
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except tomllib.TOMLDecodeError as err:
        raise SceneError("<file>", f"{path}: invalid TOML: {err}") from None
    return scene_from_dict(data)


def _plain(value: Any, kind: type) -> Any:
    # ints given directly to the dataclasses become floats, so equal scenes hash equally.
    # numpy scalars become Python ones (JSON and TOML know only those).
    if kind is float and isinstance(value, numbers.Real) and not isinstance(value, bool):
        return float(value)
    if kind is int and isinstance(value, numbers.Integral) and not isinstance(value, bool):
        return int(value)
    if kind is bool and isinstance(value, np.bool_):
        return bool(value)
    if kind is tuple and isinstance(value, list | tuple):
        return [_plain(v, float) for v in value]
    if kind is Schedule and isinstance(value, list | tuple):
        return [[_plain(v, float) for v in pair] if isinstance(pair, list | tuple) else pair
                for pair in value]
    return value


def _table_to_dict(obj: Any, specs: Mapping[str, Spec]) -> dict[str, Any]:
    return {key: _plain(getattr(obj, key), spec.kind) for key, spec in specs.items()
            if not spec.input_only}


def _solid_to_dict(solid: Layer | Ring, specs: Mapping[str, Spec]) -> dict[str, Any]:
    """A layer or ring as a TOML-shaped dict (``material`` omitted when None: TOML has no
    null)."""
    out = _table_to_dict(solid, specs)
    if out["material"] is None:
        del out["material"]
    return out


def _ring_to_toml(ring: Ring) -> str | dict[str, Any]:
    """A ring equal to its library material as the canonical name, else a full inline table."""
    if isinstance(ring.material, str):
        try:
            library = _make(Ring, _read_solid({"material": ring.material}, "", _RING, {}))
        except SceneError:  # not a library material: written inline, validation reports it
            library = None
        if ring == library:
            return library.material
    return _solid_to_dict(ring, _RING)


def _unit_to_dict(unit: Unit, load_kind: str) -> dict[str, Any]:
    out = {**_table_to_dict(unit, _UNIT),
           "encapsulation": [_ring_to_toml(ring) for ring in unit.encapsulation]}
    for name, (cls, specs) in _UNIT_PARTS.items():
        part = getattr(unit, name)
        # the actuator only matters for a normal actuator (elsewhere a non-default one is
        # written so that validation rejects it instead of dropping it)
        if name != "actuator" or load_kind == "normal_actuator" or part != cls():
            out[name] = _table_to_dict(part, specs)
    return {key: out[key] for key in _UNIT_KEYS if key in out}


def scene_to_dict(scene: Scene) -> dict[str, dict[str, Any]]:
    """Fully resolved TOML-shaped dict; ``scene_from_dict(scene_to_dict(s)) == s``.
    ``unit`` appears only when the scene has one, ``effects`` only with some effect set (see
    the module docstring for how motors and rings are written)."""
    out: dict[str, dict[str, Any]] = {}
    for name, (_, specs) in _TABLES.items():
        obj = getattr(scene, name)
        if name == "unit":
            if obj is not None:
                out[name] = _unit_to_dict(obj, scene.load.kind)
            continue
        table = _table_to_dict(obj, specs)
        if name == "effects":
            table = {key: value for key, value in table.items() if value is not None}
            if not table:
                continue
        out[name] = table
    out["tissue"]["layer"] = [_solid_to_dict(layer, _LAYER) for layer in scene.tissue.layers]
    return out


def scene_hash(scene: Scene) -> str:
    """sha256 hex digest of the canonical JSON of :func:`scene_to_dict` (sorted keys, floats
    written with ``repr`` so they round-trip exactly)."""
    text = json.dumps(scene_to_dict(scene), sort_keys=True, separators=(",", ":"),
                      allow_nan=False, ensure_ascii=True)
    return hashlib.sha256(text.encode("ascii")).hexdigest()


_TOML_ESCAPES = {'"': '\\"', "\\": "\\\\", "\b": "\\b", "\t": "\\t", "\n": "\\n",
                 "\f": "\\f", "\r": "\\r"}
_BARE_KEY = re.compile(r"[A-Za-z0-9_-]+")


def _toml_value(value: Any) -> str:
    if isinstance(value, str):
        # TOML basic strings forbid raw control characters (U+0000-U+001F, U+007F).
        return '"' + re.sub(
            r'["\\\x00-\x1f\x7f]',
            lambda m: _TOML_ESCAPES.get(m.group(), f"\\u{ord(m.group()):04X}"), value) + '"'
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        if not math.isfinite(value):
            raise ValueError(f"cannot write non-finite float {value!r}")
        return repr(value)  # shortest exact repr, always a valid TOML float ("1e-05", "2.0")
    if isinstance(value, int):
        return str(value)
    if isinstance(value, list | tuple):  # nested lists and inline tables recurse
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    if isinstance(value, Mapping):
        return "{" + ", ".join(f"{_toml_key(k)} = {_toml_value(v)}"
                               for k, v in value.items()) + "}"
    raise TypeError(f"cannot write {type(value).__name__} to TOML")


def _toml_key(key: str) -> str:
    return key if _BARE_KEY.fullmatch(key) else _toml_value(key)


def _toml_table(path: str, table: Mapping[str, Any]) -> list[str]:
    """``[path]`` with its plain keys, then its sub-tables ``[path.key]`` and arrays of tables
    ``[[path.key]]`` (TOML needs the plain keys first)."""
    lines, after = [f"[{path}]"], []
    for key, value in table.items():
        if isinstance(value, Mapping):
            after += ["", *_toml_table(f"{path}.{key}", value)]
        elif key == _SUBARRAYS.get(path):
            for item in value:
                after += ["", f"[[{path}.{key}]]"]
                after += [f"{k} = {_toml_value(v)}" for k, v in item.items()]
        else:
            lines.append(f"{key} = {_toml_value(value)}")
    return lines + after


def dump_scene_toml(scene: Scene) -> str:
    """Write ``scene`` as TOML text in the schema layout (all values explicit)."""
    lines = ["# hapticrom scene (written by fem.scene.dump_scene_toml); units in key names", ""]
    for name, table in scene_to_dict(scene).items():
        lines += [*_toml_table(name, table), ""]
    return "\n".join(lines)
