"""The scene's frozen dataclasses: one per TOML table, values in the units named by each field.

Values are kept in the file's units (mm, kPa, g, ms) so that a scene written back is the scene
read (exact round trips, stable hashes); each SI quantity the solver needs is a read-only view
defined once (``thickness_m``, ``E_Pa``, ``solid()`` ...; helpers in ``fem.scene.si``). The
haptic unit's dataclasses and its derived geometry (core and outer radius, rotor plane, pin
preload) are in ``fem.scene.unit_model``.
Constructing a :class:`Scene` validates it (see ``fem.scene.validate``).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from enum import StrEnum

from fieldspec import FieldError

from ..actuators import ACTUATORS, Actuator
from .si import Elastic, si_view
from .unit_model import Unit

__all__ = [
    "EFFECT_NAMES",
    "UNIT_LOAD_KINDS",
    "Analysis",
    "Effects",
    "Layer",
    "Load",
    "LoadKind",
    "MeshSettings",
    "Output",
    "Scene",
    "SceneError",
    "Tissue",
]


class SceneError(FieldError):
    """Invalid scene input. ``field`` is the dotted path of the bad value, e.g.
    ``tissue.layer[1].nu``, or ``"<file>"`` for a TOML syntax error."""

    __module__ = "fem.scene"  # its public home (error reports print module.name)


class _LoadKind(StrEnum):
    """What excites the tissue. The values are the strings of the scene files (``load.kind``),
    one per actuator class of ``fem.actuators`` (the members are made from its registry)."""

    @property
    def actuator(self) -> Actuator:
        """The actuator class instance that answers the solver's questions about this kind."""
        return ACTUATORS[self.value]

    @property
    def is_unit(self) -> bool:
        """A haptic unit sitting on the skin (needs a ``[unit]`` table)."""
        return self.actuator.is_unit


LoadKind = _LoadKind("LoadKind", [(a.enum_name, a.kind) for a in ACTUATORS.values()],
                     module=__name__, qualname="LoadKind")
LoadKind.__doc__ = _LoadKind.__doc__

UNIT_LOAD_KINDS = tuple(kind for kind in LoadKind if kind.is_unit)
"""Load kinds that are a haptic unit sitting on the skin (they need a ``[unit]`` table)."""

EFFECT_NAMES = ("inertia", "hysteretic_damping", "encapsulation", "pogo", "unit_mass", "rocking",
                "spin_up", "preload")
"""The physical effects a scene can force on (true) or off (false); absent = auto."""


@dataclass(frozen=True)
class Layer(Elastic):
    """One tissue layer: thickness [mm], Young's modulus [kPa], density [kg/m3], Poisson's
    ratio [-], hysteretic loss factor eta [-] (E* = E (1 + i eta)). ``material`` is the
    canonical library name the values started from, if any."""

    name: str
    thickness_mm: float
    E_kPa: float
    density_kg_m3: float
    nu: float
    loss_factor: float = 0.0
    material: str | None = None

    thickness_m = si_view("thickness_mm", 1e-3)


@dataclass(frozen=True)
class Tissue:
    """Layered cylinder of radius ``radius_mm`` [mm]; ``layers`` top (skin) to bottom."""

    layers: tuple[Layer, ...]
    radius_mm: float = 50.0
    side: str = "absorbing"
    base: str = "fixed"

    def __post_init__(self) -> None:
        object.__setattr__(self, "layers", tuple(self.layers))  # a list would be unhashable

    radius_m = si_view("radius_mm", 1e-3)

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

    kind: LoadKind = LoadKind.PRESSURE_PATCH
    direction: str = "normal"
    radius_mm: float = 2.0
    amplitude_Pa: float = 1000.0
    force_N: float = 1.0

    def __post_init__(self) -> None:
        try:
            object.__setattr__(self, "kind", LoadKind(self.kind))
        except (ValueError, TypeError):  # an unknown kind is left to validation to report
            pass

    radius_m = si_view("radius_mm", 1e-3)

    @property
    def fourier_mode(self) -> int:
        """The Fourier mode the load excites (its actuator's answer): 1 for an ERM unit (force
        parallel to the skin), 0 for a normal actuator or an LRA, else 0 / 1 for a normal /
        tangential direction."""
        return ACTUATORS[str(self.kind)].fourier_mode(self.direction)


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
    ``rho_inf`` [-], and the ERM drive as (t_ms, volts) steps, each held until the next.

    ``damping`` chooses how a transient stands in for the hysteretic loss factors, which have
    no causal time-domain form (``fem.transient_analysis``): ``"viscous_at_drive"`` (default,
    viscous damping with the loss eta at the rated speed, eta f / f_rated elsewhere) or
    ``"hysteretic_band"`` (a Prony series following 1 + i eta over 20-300 Hz,
    ``fem.viscoelastic``). Harmonic analyses and sweeps use the loss factors themselves.

    A sweep (``kind = "sweep"``) answers at every frequency of ``frequencies_hz`` (Hz,
    strictly increasing); given ``frequency_hz`` as a list or tuple, that is the band, and
    ``frequency_hz`` becomes its highest frequency, the one the mesh is sized for; its reduced
    model is refined until the estimated relative error of centre, edge and profile is below
    ``tolerance`` (``fem.sweep_rom``; default 1e-3, well inside the 1 % phase error of the
    default mesh)."""

    kind: str = "static"
    frequency_hz: float = 120.0
    time_step_ms: float = 0.05
    duration_ms: float = 200.0
    rho_inf: float = 0.9
    voltage_schedule: tuple[tuple[float, float], ...] = ((0.0, 3.3),)
    frequencies_hz: tuple[float, ...] = ()
    damping: str = "viscous_at_drive"
    tolerance: float = 1e-3

    def __post_init__(self) -> None:
        band = self.frequency_hz
        if isinstance(band, list | tuple):  # a sweep's band given as its frequencies
            object.__setattr__(self, "frequencies_hz", tuple(band))
            object.__setattr__(self, "frequency_hz", max(band) if band else band)
        elif isinstance(self.frequencies_hz, list):
            object.__setattr__(self, "frequencies_hz", tuple(self.frequencies_hz))
        steps = self.voltage_schedule  # lists become tuples (hashable); validation does the rest
        if isinstance(steps, list | tuple):
            object.__setattr__(self, "voltage_schedule", tuple(
                tuple(pair) if isinstance(pair, list | tuple) else pair for pair in steps))

    time_step_s = si_view("time_step_ms", 1e-3)
    duration_s = si_view("duration_ms", 1e-3)

    @property
    def voltage_schedule_s(self) -> tuple[tuple[float, float], ...]:
        """The schedule as (t_start_s, volts) pairs (``fem.motor.VoltageSchedule`` steps)."""
        return tuple((t * 1e-3, v) for t, v in self.voltage_schedule)


@dataclass(frozen=True)
class MeshSettings:
    """Element size [mm] within ``near_radius_mm`` of the axis and beyond; element order.

    With ``follow_wavelength`` (default) both sizes are upper bounds: a wave analysis uses
    smaller elements where the shortest shear wavelength of the scene at the drive frequency
    needs them (10 linear or 5 quadratic elements per wavelength, about 1 % phase error), so
    no sample of a frequency or stiffness sweep is under-resolved. Turn it off to study the
    mesh itself (convergence runs).

    ``cells_r`` / ``cells_z`` (optional) fix the number of cells in every segment of the grid
    along r and z (``fem.domain.Domain.cells_needed`` lists the segments), each at least what
    the sizes need: scenes that differ only in continuous values (a layer thickness, a modulus,
    the frequency) then share one mesh topology whose nodes move with those values, so their
    answers vary smoothly with them. A dataset's mesh plan writes them
    (``surrogate.data.mesh_plan``)."""

    near_size_mm: float = 0.5
    near_radius_mm: float = 8.0
    far_size_mm: float = 2.0
    order: int = 2
    follow_wavelength: bool = True
    cells_r: tuple[int, ...] | None = None
    cells_z: tuple[int, ...] | None = None

    def __post_init__(self) -> None:
        for name in ("cells_r", "cells_z"):
            if getattr(self, name) is not None:
                object.__setattr__(self, name, tuple(int(n) for n in getattr(self, name)))


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

    profile_step_m = si_view("profile_step_mm", 1e-3)
    profile_length_m = si_view("profile_length_mm", 1e-3)

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
        if not SCENE_CHECKS:
            raise RuntimeError("fem.scene.io registers the scene checks on import")
        for check in SCENE_CHECKS:  # direct construction gets the same checks as a file
            check(self)


SCENE_CHECKS: list[Callable[[Scene], None]] = []
"""What a constructed :class:`Scene` is checked with: ``fem.scene.io`` (imported by the
package before anything can build a scene) adds "validate its TOML-shaped dict", so this
module imports neither the reader nor the validation (no import circle in ``fem/scene``)."""


