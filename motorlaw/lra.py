"""The linear resonant actuator's (LRA's) drive law, defined once (numpy only).

An LRA is a magnet mass on a spring, driven by a voice coil with an AC voltage near its
resonance; the mass's reaction pushes the housing along the skin normal. Model (SI units):

- **Force at a frequency** (steady): a damped mass-spring resonator; the same coil drive at
  frequency f gives the force F(f) = force_N (V / rated_voltage_V) |G(f)| / Q with
  G = r^2 / (1 - r^2 + i r / Q), r = f / resonance_hz, so F = force_N at resonance and the
  rated voltage, and F -> force_N / Q far above it (the mass driven as a free mass):
  :meth:`ResonantDrive.response`.
- **Nominal voltage**: the voltage that gives the rated force at f,
  rated_voltage_V / response(f); the frequencies where that is within ``max_voltage_V`` are
  the band the LRA reaches (:meth:`ResonantDrive.band_hz`).
- **Envelope** (drive state): the force envelope a(t), relative to the rated force, of a
  resonator driven at its resonance rings up and down as a first-order system,
  da/dt = (a_target(V) - a) / tau, tau = Q / (pi f0) (the decay time of a free resonator's
  amplitude, 2 Q / omega0), with a_target = V / nominal_voltage_V(f). An overdrive kick at
  the voltage limit shortens the ring-up; driving with reversed phase brakes it (as LRA
  drivers such as the DRV2605 do), the driver stopping when the amplitude reaches zero. Driven
  off resonance, the free decay keeps the rate 1 / tau, while the ring-up beats at the
  detuning: within the band (detuning below about 1.1 / tau here) the beat is not modelled.

Defaults (:data:`DEFAULTS`) for a common 10 mm coin LRA, from the headline figures of the
datasheet families Precision Microdrives C10-100 (10 mm, 175 Hz rated frequency, 2.0 V rms
rated voltage, about 1.4 g normalised amplitude on a 100 g test mass) and Vybronics
VG1040003D (10 mm coin, resonance in the 170-175 Hz band). These figures were not re-read
from the datasheets in this tree: check them against the current datasheet before relying on
them.

- ``resonance_hz`` 175 Hz: the families' rated frequency.
- ``force_N`` 1.4 N: 1.4 g x 9.81 m/s2 on a 0.1 kg test mass (about 1.37 N), the force-class
  of the family.
- ``moving_mass_kg`` 1.5e-3 kg: an estimate (1-2 g for a 10 mm coin LRA's magnet mass).
- ``quality_factor`` 10: an estimate from the narrow (about +-10 Hz) band around resonance in
  which these LRAs are specified to be driven; with it tau = 18 ms.
- ``rated_voltage_V`` 2.0 V (rms): the C10-100 family's rated drive.
- ``max_voltage_V`` 3.0 V: an estimate of the overdrive limit (1.5x rated, as LRA drivers'
  overdrive clamps allow); with Q = 10 the band is about 165-185 Hz.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from motorlaw.drive import DriveLaw, register
from motorlaw.erm import SpeedLaw, held_speed_and_phase

__all__ = ["DEFAULTS", "RANGES", "ResonantDrive"]

#: The defaults of the project's LRA (sources in the module docstring).
DEFAULTS: dict[str, float] = {
    "resonance_hz": 175.0,
    "quality_factor": 10.0,
    "force_N": 1.4,
    "moving_mass_kg": 1.5e-3,
    "rated_voltage_V": 2.0,
    "max_voltage_V": 3.0,
}

#: Allowed ranges (low, high), both exclusive of nonsense: every parameter is > 0 and finite;
#: these bounds are those of any coin or cylindrical LRA (a scene's ``[unit.lra]`` uses them).
RANGES: dict[str, tuple[float, float]] = {
    "resonance_hz": (20.0, 1000.0),
    "quality_factor": (0.5, 200.0),
    "force_N": (1e-3, 20.0),
    "moving_mass_kg": (1e-5, 0.1),
    "rated_voltage_V": (0.1, 50.0),
    "max_voltage_V": (0.1, 50.0),
}


@register
@dataclass(frozen=True)
class ResonantDrive(DriveLaw):
    """Parameters of an LRA's drive law (defaults: :data:`DEFAULTS`; see the module docstring).

    Attributes:
        resonance_hz: the resonance f0, Hz.
        quality_factor: Q of the moving mass on its spring, -.
        force_N: force amplitude on the housing at resonance and the rated voltage, N.
        moving_mass_kg: the moving (magnet) mass, kg.
        rated_voltage_V: the drive voltage amplitude of the rated force at resonance, V.
        max_voltage_V: the largest |voltage| a schedule may apply, V (>= rated).
    """

    resonance_hz: float = DEFAULTS["resonance_hz"]
    quality_factor: float = DEFAULTS["quality_factor"]
    force_N: float = DEFAULTS["force_N"]
    moving_mass_kg: float = DEFAULTS["moving_mass_kg"]
    rated_voltage_V: float = DEFAULTS["rated_voltage_V"]
    max_voltage_V: float = DEFAULTS["max_voltage_V"]

    kind = "lra"
    title = "coin LRA"
    noun = "LRA"
    overdrive = True
    brake = True
    carrier = True
    state_unit = "x rated force"

    def __post_init__(self) -> None:
        for name, (lo, hi) in RANGES.items():
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, numbers.Real):
                raise ValueError(f"lra.{name}: {value!r} is not a number; allowed [{lo:g}, "
                                 f"{hi:g}]")
            if not (math.isfinite(value) and lo <= value <= hi):
                raise ValueError(f"lra.{name} = {value!r}: allowed [{lo:g}, {hi:g}]")
        if self.max_voltage_V < self.rated_voltage_V:
            raise ValueError(f"lra.max_voltage_V = {self.max_voltage_V!r}: allowed "
                             f"[rated_voltage_V = {self.rated_voltage_V:g}, 50]")

    @property
    def tau_s(self) -> float:
        """The envelope's ring-up and ring-down time constant Q / (pi f0), s."""
        return self.quality_factor / (math.pi * self.resonance_hz)

    def response(self, frequency_hz: NDArray | float) -> NDArray:
        """Force at ``frequency_hz`` [Hz] relative to the force at resonance [-] (1 there),
        at the same drive voltage."""
        r = np.asarray(frequency_hz, dtype=float) / self.resonance_hz
        q = self.quality_factor
        return np.abs(r**2 / (1 - r**2 + 1j * r / q)) / q

    def force_at(self, frequency_hz: NDArray | float) -> NDArray:
        """Force amplitude [N] on the housing at ``frequency_hz`` and the rated voltage."""
        return self.force_N * self.response(frequency_hz)

    def nominal_voltage_V(self, frequency_hz: float) -> float:
        """The voltage giving the rated force at ``frequency_hz``: rated / response(f), V."""
        return float(self.rated_voltage_V / self.response(float(frequency_hz)))

    def band_hz(self) -> tuple[float, float]:
        """(low, high) [Hz] where response(f) >= rated / max voltage (high may be inf when
        the free-mass force force_N / Q is reached within the limit)."""
        rho2 = (self.rated_voltage_V / self.max_voltage_V) ** 2
        q2 = self.quality_factor ** 2
        # response(r)^2 = rho2 as a quadratic in x = r^2: a x^2 + b x + c = 0
        a, b, c = 1.0 - rho2 * q2, 2.0 * rho2 * q2 - rho2, -rho2 * q2
        if abs(a) < 1e-12:
            return self.resonance_hz * math.sqrt(-c / b), math.inf
        roots = sorted(x.real for x in np.roots([a, b, c])
                       if abs(x.imag) < 1e-12 and x.real > 0)
        f = [self.resonance_hz * math.sqrt(x) for x in roots]
        return (f[0], f[1]) if a < 0 else (f[-1], math.inf)

    def describe(self) -> str:
        return (f"resonance {self.resonance_hz:g} Hz, Q {self.quality_factor:g}: rated force "
                f"at {self.rated_voltage_V:g} V there")

    def drive_state(self, t_s: NDArray, volts: NDArray, frequency_hz: float) -> NDArray:
        """The force envelope relative to the rated force [-] (the module docstring's a(t),
        exact for the voltage amplitude held between samples; reversed phase is a negative
        voltage, and the brake ends at rest). ValueError when ``frequency_hz`` is outside
        :meth:`band_hz`."""
        lo, hi = self.band_hz()
        f = float(frequency_hz)
        if not lo <= f <= hi:
            raise ValueError(f"frequency_hz = {f:g}: the LRA reaches {self.reach_text()} "
                             f"within its {self.max_voltage_V:g} V limit")
        # The same first-order law with stiction at 0 V and a brake ending at rest as the
        # ERM's speed, in units where the nominal target is 1: one exact solver for both.
        unit = SpeedLaw(rated_voltage_V=min(self.nominal_voltage_V(f), self.max_voltage_V),
                        rated_frequency_hz=1 / (2 * math.pi), start_voltage_V=0.0,
                        tau_spinup_s=self.tau_s, tau_spindown_s=self.tau_s,
                        max_voltage_V=self.max_voltage_V)
        return held_speed_and_phase(unit, t_s, volts)[0]

    def force_ratio(self, state: NDArray, frequency_hz: float) -> NDArray:
        """The force envelope is the state (relative to the rated force, the nominal)."""
        return np.asarray(state, dtype=float)
