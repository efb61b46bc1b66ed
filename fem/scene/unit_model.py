"""The haptic unit's dataclasses (``[unit]`` and its part tables), in the file's units.

Derived unit geometry (core and outer radius, ring radii, rotor plane, pin preload) is defined
here once; the haptic-unit builder (``fem.haptic_unit``) and the validator both use it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from motorlaw import DEFAULTS as MOTOR_LAW
from motorlaw.lra import DEFAULTS as LRA_LAW

from ..materials import Material
from .si import Elastic, si_view

__all__ = ["RING_GAP_MM", "Actuator", "Board", "Motor", "Pogo", "Ring", "Unit"]

#: Radial slit [mm] between a unit's core and its inner ring when they are not bonded: it keeps
#: the meshes apart so that only what the contact transmits is tied. Micrometre amplitudes
#: never close it; it moves the unit's edge out by this much.
RING_GAP_MM = 0.05


@dataclass(frozen=True)
class Ring(Elastic):
    """One silicone encapsulation ring (a hollow cylinder around the motor; its width is
    ``Unit.ring_thickness_mm``): Young's modulus [kPa], density [kg/m3], Poisson's ratio [-],
    hysteretic loss factor [-]; ``material`` is the canonical library name, if any."""

    name: str
    E_kPa: float
    density_kg_m3: float
    nu: float
    loss_factor: float = 0.0
    material: str | None = None


@dataclass(frozen=True)
class Motor:
    """The motor housing (a solid cylinder, effectively rigid) and, for an ERM, its rotor.

    Attributes:
        diameter_mm, height_mm: housing size [mm] (Guo et al. 2025: a 7 x 2 mm coin ERM).
        mass_g: motor mass [g], spread over the housing volume (estimate; the paper gives none).
        unbalance_g_mm: eccentric mass x eccentricity m e [g mm]; the default 0.006 g mm over
            0.6 g gives m e / M = 10 um free displacement, the order of the free vibration
            amplitude of 7-10 mm coin ERMs in manufacturer datasheets (Precision Microdrives).
            A file may give ``force_N`` at ``force_at_hz`` instead; it is stored resolved here.
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
    rated_voltage_V: float = MOTOR_LAW["rated_voltage_V"]  # the speed law's defaults: motorlaw
    rated_frequency_hz: float = MOTOR_LAW["rated_frequency_hz"]
    start_voltage_V: float = MOTOR_LAW["start_voltage_V"]
    tau_spinup_ms: float = 1e3 * MOTOR_LAW["tau_spinup_s"]
    tau_spindown_ms: float = 1e3 * MOTOR_LAW["tau_spindown_s"]

    radius_m = si_view("diameter_mm", 0.5e-3)
    height_m = si_view("height_mm", 1e-3)
    mass_kg = si_view("mass_g", 1e-3)
    unbalance_kg_m = si_view("unbalance_g_mm", 1e-6, "m e [kg m] (1 g mm = 1e-6 kg m).")
    rotor_height_m = si_view("rotor_height_mm", 1e-3)
    E_Pa = si_view("E_kPa", 1e3)
    tau_spinup_s = si_view("tau_spinup_ms", 1e-3)
    tau_spindown_s = si_view("tau_spindown_ms", 1e-3)

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

    def force_N_at(self, frequency_hz: float) -> float:
        """Unbalance force amplitude m e (2 pi f)^2 [N] at spin frequency ``frequency_hz``."""
        return self.unbalance_kg_m * (2.0 * math.pi * frequency_hz) ** 2

    def solid(self, with_mass: bool = True) -> Material:
        """The housing as an SI material (massless when ``with_mass`` is False)."""
        return Material("motor", self.E_Pa, self.density_kg_m3 if with_mass else 0.0, self.nu)


@dataclass(frozen=True)
class Board(Elastic):
    """Flexible PCB disc under the motor: thickness and diameter [mm] (thickness 0 = no
    board), library ``material`` (canonical name) and its possibly overridden E [kPa], density
    [kg/m3], Poisson's ratio [-]."""

    thickness_mm: float = 0.1
    diameter_mm: float = 7.0
    material: str = "pcb"
    E_kPa: float = 2.5e6
    density_kg_m3: float = 1420.0
    nu: float = 0.34

    name = "pcb"
    loss_factor = 0.0

    @property
    def present(self) -> bool:
        """False for ``thickness_mm = 0`` (motor taped straight to the skin)."""
        return self.thickness_mm > 0

    thickness_m = si_view("thickness_mm", 1e-3)
    radius_m = si_view("diameter_mm", 0.5e-3)

    def board_solid(self, with_mass: bool = True) -> Material:
        """The board as an SI material (massless when ``with_mass`` is False)."""
        if with_mass:
            return self.solid()
        return Material(self.name, self.E_Pa, 0.0, self.nu)


@dataclass(frozen=True)
class Pogo:
    """Spring pins under the board (``attachment = "pogo"``): ``count`` pins at ``radius_mm``
    [mm] from the motor axis, axial stiffness ``stiffness_N_m`` [N/m] each, ``length_mm`` and
    ``travel_mm`` [mm], tip contact footprint ``tip_diameter_mm`` [mm] (Guo et al. 2025 use
    PZ8116 pins; stiffness and travel from that part's datasheet)."""

    count: int = 3
    radius_mm: float = 2.25
    stiffness_N_m: float = 2942.0
    length_mm: float = 2.4
    travel_mm: float = 0.3
    tip_diameter_mm: float = 0.5

    radius_m = si_view("radius_mm", 1e-3)
    length_m = si_view("length_mm", 1e-3)
    travel_m = si_view("travel_mm", 1e-3)
    tip_diameter_m = si_view("tip_diameter_mm", 1e-3)

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
class LraPart:
    """``[unit.lra]``: the LRA's resonator (``load.kind = "lra"`` only; optional: absent, the
    defaults of :data:`motorlaw.lra.DEFAULTS` apply, with their sources there). Its force at
    resonance is ``[unit.actuator] force_N``.

    Attributes:
        resonance_hz: resonance f0 [Hz].
        quality_factor: Q of the moving mass on its spring [-].
        moving_mass_g: the moving (magnet) mass [g].
        rated_voltage_V: drive voltage of the rated force at resonance [V].
        max_voltage_V: largest drive voltage (overdrive limit) [V].
    """

    resonance_hz: float = LRA_LAW["resonance_hz"]
    quality_factor: float = LRA_LAW["quality_factor"]
    moving_mass_g: float = 1e3 * LRA_LAW["moving_mass_kg"]
    rated_voltage_V: float = LRA_LAW["rated_voltage_V"]
    max_voltage_V: float = LRA_LAW["max_voltage_V"]

    moving_mass_kg = si_view("moving_mass_g", 1e-3)


@dataclass(frozen=True)
class Unit:
    """The haptic unit on the skin, centered on the axis.

    Attributes:
        orientation: "forward" (motor as bought) or "reverse" (flipped; moves the rotor plane).
        attachment: "glued" (bonded over its footprint) or "pogo" (spring pins, frictionless).
        encapsulation: silicone rings, inner to outer (0..5).
        ring_thickness_mm: radial width of every ring [mm].
        ring_contact: how the inner ring meets the motor and board. "frictionless" (default):
            a snug fit that passes normal pressure but no shear (Guo et al. 2025 tie the rings
            to each other and to the skin only); "bonded": cast around the motor; "none": no
            interaction at all. Except when bonded, a slit of ``RING_GAP_MM`` separates the
            meshes so that only what the contact passes is tied.
        motor, board, pogo, actuator: the parts (``pogo`` used only with attachment "pogo",
            ``actuator`` only with ``load.kind = "normal_actuator"`` or ``"lra"``).
        lra: the LRA's resonator (``load.kind = "lra"`` only); None: not given (defaults).
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
    lra: LraPart | None = None  # None is not written: scene hashes without it are unchanged

    def __post_init__(self) -> None:
        object.__setattr__(self, "encapsulation", tuple(self.encapsulation))

    # The geometry is computed in SI (the solver's units, so that the mesh lines the solver
    # places are exactly these values); the mm views are for messages and reports.
    @property
    def ring_gap_m(self) -> float:
        """Slit [m] between the core and the inner ring: 0 when bonded (or without rings)."""
        if not self.encapsulation or self.ring_contact == "bonded":
            return 0.0
        return RING_GAP_MM * 1e-3

    @property
    def core_radius_m(self) -> float:
        """Radius [m] of the motor-and-board core the rings wrap (the board counts only when
        present)."""
        return max(self.motor.radius_m, self.board.radius_m if self.board.present else 0.0)

    @property
    def ring_start_m(self) -> float:
        """Inner radius [m] of the inner ring: the core plus the slit."""
        return self.core_radius_m + self.ring_gap_m

    @property
    def ring_radii_m(self) -> tuple[tuple[float, float], ...]:
        """(inner, outer) radius [m] of each ring, inner to outer."""
        r0, t = self.ring_start_m, self.ring_thickness_m
        return tuple((r0 + i * t, r0 + i * t + t) for i in range(len(self.encapsulation)))

    @property
    def outer_radius_m(self) -> float:
        """The unit's edge [m]: core radius plus the slit and the rings."""
        if not self.encapsulation:
            return self.core_radius_m
        return self.ring_start_m + len(self.encapsulation) * self.ring_thickness_m

    @property
    def rotor_above_base_m(self) -> float:
        """Rotor plane above the housing face towards the skin [m]: ``rotor_height_mm``
        forward, ``height_mm - rotor_height_mm`` reverse (flipped)."""
        m = self.motor
        if self.orientation == "forward":
            return m.rotor_height_m
        return m.height_m - m.rotor_height_m

    ring_thickness_m = si_view("ring_thickness_mm", 1e-3)
    ring_gap_mm = si_view("ring_gap_m", 1e3)
    core_radius_mm = si_view("core_radius_m", 1e3)
    outer_radius_mm = si_view("outer_radius_m", 1e3)
    rotor_above_base_mm = si_view("rotor_above_base_m", 1e3)

    @property
    def ring_radii_mm(self) -> tuple[tuple[float, float], ...]:
        """(inner, outer) radius [mm] of each ring, inner to outer."""
        return tuple((r0 * 1e3, r1 * 1e3) for r0, r1 in self.ring_radii_m)
