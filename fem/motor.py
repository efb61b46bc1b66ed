"""Coin eccentric-rotating-mass (ERM) motor: the unbalance force of the transient analysis.

The speed law (steady speed linear in voltage above the start voltage, first-order spin-up and
spin-down, reverse-drive braking that ends at rest, exact piecewise solution) and its defaults
are defined once in :mod:`motorlaw` and re-exported here; the run-time envelope model
(``surrogate.runtime.rom``) calls the same functions. This module adds the rotor's unbalance:

- The unbalance force ``F = m_e omega^2`` (``m_e`` = eccentric mass x eccentricity) rotates in
  the plane of the coin: ``(F_x, F_y) = m_e omega^2 (cos phi, sin phi)`` with
  ``phi = integral of omega dt``, phi(0) = 0, counter-clockwise about the coin axis. Amplitude
  and frequency therefore rise together.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from motorlaw import (
    TWO_PI,
    SpeedLaw,
    VoltageSchedule,
    phase,
    rise_time_s,
    simulate_speed,
    speed_and_phase,
    speed_per_volt,
    speed_rate,
    steady_frequency_hz,
    target_speed_rad_s,
)
from motorlaw.erm import evaluate, segments

__all__ = ["ERMMotor", "VoltageSchedule", "erm_load_history", "phase", "rise_time_s",
           "simulate_speed", "speed_rate", "steady_force_N", "steady_frequency_hz",
           "target_speed_rad_s", "unbalance_force"]


@dataclass(frozen=True)
class ERMMotor(SpeedLaw):
    """Coin ERM motor: the speed law's parameters (:class:`motorlaw.SpeedLaw`, inherited with
    its defaults :data:`motorlaw.DEFAULTS`, documented estimates) plus the unbalance.

    Attributes:
        unbalance_kg_m: eccentric mass times eccentricity m*e, kg m (> 0; keyword only).
    """

    unbalance_kg_m: float = field(kw_only=True)

    def __post_init__(self) -> None:
        _require("unbalance_kg_m", self.unbalance_kg_m)
        super().__post_init__()

    @property
    def speed_per_volt(self) -> float:
        """Slope of the steady speed above the start voltage, rad/s per V."""
        return speed_per_volt(self)


def steady_force_N(motor: ERMMotor, volts: float | np.ndarray) -> np.ndarray | float:
    """Steady unbalance force amplitude m_e omega^2 at a constant voltage, N."""
    omega = TWO_PI * np.asarray(steady_frequency_hz(motor, volts))
    out = motor.unbalance_kg_m * omega**2
    return float(out) if np.ndim(out) == 0 else out


def unbalance_force(motor: ERMMotor, schedule: VoltageSchedule,
                    t: float | np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """In-plane unbalance force components (F_x, F_y) = m_e omega^2 (cos phi, sin phi), N."""
    omega, phi = speed_and_phase(motor, schedule, t)
    amplitude = motor.unbalance_kg_m * omega**2
    return amplitude * np.cos(phi), amplitude * np.sin(phi)


def erm_load_history(motor: ERMMotor,
                     schedule: VoltageSchedule) -> Callable[[np.ndarray], np.ndarray]:
    """``load_history`` for fem.transient.solve_transient with k = 2 load columns.

    Returns a function mapping times (nt,) in s to (nt, 2) forces in N: column 0 is F_x
    (apply with the x-direction load vector), column 1 is F_y (apply with the y one).
    """
    seg = segments(motor, schedule)  # built (and validated) once, reused for every block

    def history(t: np.ndarray) -> np.ndarray:
        omega, phi = evaluate(seg, np.ravel(np.asarray(t, dtype=float)))
        amplitude = motor.unbalance_kg_m * omega**2
        return np.column_stack([amplitude * np.cos(phi), amplitude * np.sin(phi)])

    return history


def _require(name: str, value: float) -> None:
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise TypeError(f"ERMMotor.{name} must be a real number in (0, inf), got {value!r}")
    if not (math.isfinite(value) and value > 0.0):
        raise ValueError(f"ERMMotor.{name} must be in (0, inf), got {value!r}")
