"""The coin eccentric-rotating-mass (ERM) motor's speed law, defined once (numpy only).

Model (SI units: s, V, rad/s, rad):

- Steady speed is linear in the drive voltage: 0 at ``start_voltage_V`` (below it stiction
  holds the rotor), ``rated_frequency_hz`` at ``rated_voltage_V``, extrapolated linearly up to
  ``max_voltage_V``. A reverse voltage (as in DRV2605 reverse-drive braking) targets the mirror
  negative speed; the motor is never driven backwards, so the speed is clamped at >= 0 and
  braking ends at rest.
- Speed follows first-order DC-motor dynamics towards that target,
  ``d omega / dt = (omega_target(V) - omega) / tau``, with ``tau = tau_spinup_s`` while
  ``|omega_target| > omega`` and ``tau_spindown_s`` otherwise (see :func:`speed_rate`).
- The rotor angle is ``phi = integral of omega dt``, phi(0) = 0.

For a piecewise-constant voltage the ODE has a closed-form solution on every interval (an
exponential, with analytic switch times where tau changes or the speed reaches zero), so
:func:`simulate_speed` and :func:`phase` evaluate it exactly, vectorised over the query
times; no ODE solver is involved. The motor starts at rest at t = 0.

Defaults (:data:`DEFAULTS`) and their sources. They are estimates, not a datasheet:

- ``rated_voltage_V`` 3.3 V and ``rated_frequency_hz`` 120 rev/s: Guo et al. 2025
  (Biomimetics 10:597) drive a Leader LCM0720A3463F coin ERM at 3.3 V and simulate 120 rev/s.
- ``start_voltage_V`` 0.4 V: coin ERMs start turning at a few tenths of a volt (estimate).
- ``tau_spinup_s`` 20 ms and ``tau_spindown_s`` 35 ms: typical coin ERMs lag 10-20 ms, rise in
  30-100 ms and stop in 50-150 ms (Precision Microdrives application notes); with first-order
  dynamics the 10-90 % rise is ``tau ln 9 = 2.2 tau`` and the 50 % lag ``tau ln 2``, so 20 ms
  gives a 44 ms rise and a 14 ms lag, 35 ms a 77 ms 90-10 % stop.
- ``max_voltage_V`` 4.5 V: the overdrive limit of a 3.3 V coin ERM (drivers such as the
  DRV2605 allow overdrive to about 1.4x rated); at the limit the motor spins at 170 rev/s.

Dead time (electrical lag before the rotor breaks away) is not modelled.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Callable, Iterable
from dataclasses import dataclass, fields
from typing import Any, Protocol

import numpy as np
from numpy.typing import NDArray

from motorlaw.drive import DriveLaw, register

TWO_PI = 2.0 * math.pi

#: The defaults of every ERM in the project (sources in the module docstring).
DEFAULTS: dict[str, float] = {
    "rated_voltage_V": 3.3,
    "rated_frequency_hz": 120.0,
    "start_voltage_V": 0.4,
    "tau_spinup_s": 0.020,
    "tau_spindown_s": 0.035,
    "max_voltage_V": 4.5,
}


class LawLike(Protocol):
    """Anything carrying the law's six parameters (:class:`SpeedLaw`, ``fem.motor.ERMMotor``)."""

    rated_voltage_V: float
    rated_frequency_hz: float
    start_voltage_V: float
    tau_spinup_s: float
    tau_spindown_s: float
    max_voltage_V: float


@register
@dataclass(frozen=True)
class SpeedLaw(DriveLaw):
    """Parameters of the ERM speed law (defaults: :data:`DEFAULTS`); the drive law of the coin
    ERM (actuator kind ``"unit"``): the voltage sets the speed, an overdrive kick shortens the
    spin-up, a reverse-voltage brake stops the rotor.

    Attributes:
        rated_voltage_V: drive voltage at which the motor spins at ``rated_frequency_hz``, V.
        rated_frequency_hz: steady spin frequency at the rated voltage, rev/s.
        start_voltage_V: voltage below which the rotor does not turn (stiction), V.
        tau_spinup_s: mechanical time constant while driven towards a faster target, s.
        tau_spindown_s: time constant while slowing towards a slower target, s.
        max_voltage_V: largest |voltage| a schedule may apply, V.
    """

    rated_voltage_V: float = DEFAULTS["rated_voltage_V"]
    rated_frequency_hz: float = DEFAULTS["rated_frequency_hz"]
    start_voltage_V: float = DEFAULTS["start_voltage_V"]
    tau_spinup_s: float = DEFAULTS["tau_spinup_s"]
    tau_spindown_s: float = DEFAULTS["tau_spindown_s"]
    max_voltage_V: float = DEFAULTS["max_voltage_V"]

    kind = "unit"
    title = "coin ERM"
    noun = "motor"
    overdrive = True
    brake = True
    carrier = False
    state_unit = "rev/s"

    def __post_init__(self) -> None:
        check_law(self)

    def nominal_voltage_V(self, frequency_hz: float) -> float:
        """The voltage spinning the motor at ``frequency_hz``: :func:`voltage_for_frequency`."""
        return voltage_for_frequency(self, frequency_hz)

    def band_hz(self) -> tuple[float, float]:
        """(0, the steady speed at ``max_voltage_V``) [Hz]: :func:`max_frequency_hz`."""
        return 0.0, max_frequency_hz(self)

    def describe(self) -> str:
        per_hz = (self.rated_voltage_V - self.start_voltage_V) / self.rated_frequency_hz
        return (f"speed law {self.start_voltage_V:g} V + {per_hz * 1e3:.3f} mV/Hz: "
                f"{self.rated_frequency_hz:g} Hz at {self.rated_voltage_V:g} V")

    def drive_state(self, t_s: NDArray, volts: NDArray, frequency_hz: float) -> NDArray:
        """The spin speed [rev/s] (the frequency is set by the voltage, not by
        ``frequency_hz``): :func:`held_speed_and_phase`."""
        return held_speed_and_phase(self, t_s, volts)[0] / TWO_PI

    def force_ratio(self, state: NDArray, frequency_hz: float) -> NDArray:
        """The unbalance force m e omega^2 at the speed ``state`` [rev/s] over its value at
        ``frequency_hz``."""
        return (np.asarray(state, dtype=float) / float(frequency_hz)) ** 2

    @classmethod
    def of(cls, law: LawLike) -> SpeedLaw:
        """The law's parameters of any :class:`LawLike` object."""
        return cls(**{f.name: getattr(law, f.name) for f in fields(cls)})

    @property
    def rated_omega(self) -> float:
        """Rated speed, rad/s."""
        return TWO_PI * self.rated_frequency_hz

    @property
    def speed_per_volt(self) -> float:
        """Slope of the steady speed above the start voltage, rad/s per V."""
        return speed_per_volt(self)


def check_law(law: Any) -> None:
    """Raise ValueError (TypeError for a non-number) naming the field and its allowed range."""
    owner = type(law).__name__
    for name in ("rated_frequency_hz", "tau_spinup_s", "tau_spindown_s"):
        _require(owner, name, getattr(law, name), "(0, inf)", lambda x: x > 0.0)
    _require(owner, "start_voltage_V", law.start_voltage_V, "[0, inf)", lambda x: x >= 0.0)
    _require(owner, "rated_voltage_V", law.rated_voltage_V,
             f"(start_voltage_V = {law.start_voltage_V}, inf)",
             lambda x: x > law.start_voltage_V)
    _require(owner, "max_voltage_V", law.max_voltage_V,
             f"[rated_voltage_V = {law.rated_voltage_V}, inf)",
             lambda x: x >= law.rated_voltage_V)


@dataclass(frozen=True)
class VoltageSchedule:
    """Piecewise-constant drive: ``steps[i] = (t_start_s, volts)`` holds until the next start.

    The first step starts at t = 0 and start times increase strictly; the last step holds
    forever. Volts may be negative (reverse-drive braking); the motor-specific bound
    |volts| <= ``max_voltage_V`` is checked when the schedule is simulated.
    """

    steps: tuple[tuple[float, float], ...]

    def __post_init__(self) -> None:
        steps = tuple((float(t), float(v)) for t, v in _as_pairs(self.steps))
        if not steps:
            raise ValueError("VoltageSchedule.steps must hold at least one (t_start_s, volts)")
        times = np.array([t for t, _ in steps])
        volts = np.array([v for _, v in steps])
        if not np.all(np.isfinite(times)):
            raise ValueError(f"VoltageSchedule.steps t_start_s must be finite, got {times}")
        if not np.all(np.isfinite(volts)):
            raise ValueError(f"VoltageSchedule.steps volts must be finite, got {volts}")
        if times[0] != 0.0:
            raise ValueError(f"VoltageSchedule.steps[0] t_start_s must be 0 s, got {times[0]}")
        bad = np.flatnonzero(np.diff(times) <= 0.0)
        if bad.size:
            i = int(bad[0]) + 1
            raise ValueError(
                f"VoltageSchedule.steps t_start_s must increase strictly: steps[{i}] = "
                f"{times[i]} s is not > steps[{i - 1}] = {times[i - 1]} s"
            )
        object.__setattr__(self, "steps", steps)

    @classmethod
    def constant(cls, volts: float) -> VoltageSchedule:
        """A single voltage applied from t = 0 on."""
        return cls(((0.0, volts),))

    @classmethod
    def held(cls, t_s: np.ndarray, volts: np.ndarray) -> VoltageSchedule:
        """The schedule holding ``volts[k]`` from ``t_s[k] - t_s[0]`` to the next time (equal
        neighbours merged): a sampled drive as a step schedule starting at 0."""
        t = np.asarray(t_s, dtype=float) - float(t_s[0])
        v = np.asarray(volts, dtype=float)
        keep = np.concatenate([[True], v[1:] != v[:-1]])
        return cls(tuple(zip(t[keep].tolist(), v[keep].tolist(), strict=True)))

    @property
    def start_times_s(self) -> np.ndarray:
        return np.array([t for t, _ in self.steps])

    @property
    def volts(self) -> np.ndarray:
        return np.array([v for _, v in self.steps])


def speed_per_volt(law: LawLike) -> float:
    """Slope of the steady speed above the start voltage, rad/s per V."""
    return TWO_PI * law.rated_frequency_hz / (law.rated_voltage_V - law.start_voltage_V)


def target_speed_rad_s(law: LawLike, volts: float | np.ndarray) -> np.ndarray:
    """Signed steady speed the motor is driven towards at ``volts``, rad/s.

    Zero for |V| <= start voltage; negative for reverse voltage (a braking target).
    """
    v = _check_volts(law, volts)
    return np.sign(v) * speed_per_volt(law) * np.maximum(np.abs(v) - law.start_voltage_V, 0.0)


def steady_frequency_hz(law: LawLike, volts: float | np.ndarray) -> np.ndarray | float:
    """Steady spin frequency at a constant voltage, rev/s (0 for reverse or sub-start voltage)."""
    out = np.maximum(target_speed_rad_s(law, volts), 0.0) / TWO_PI
    return float(out) if np.ndim(out) == 0 else out


def voltage_for_frequency(law: LawLike, frequency_hz: float) -> float:
    """Steady drive voltage spinning the motor at ``frequency_hz`` (> 0), V: the inverse of the
    steady-speed law (may exceed ``max_voltage_V``; compare with :func:`max_frequency_hz`)."""
    per_hz = (law.rated_voltage_V - law.start_voltage_V) / law.rated_frequency_hz
    return law.start_voltage_V + float(frequency_hz) * per_hz


def max_frequency_hz(law: LawLike) -> float:
    """Steady spin frequency at the voltage limit ``max_voltage_V``, rev/s."""
    return speed_per_volt(law) * (law.max_voltage_V - law.start_voltage_V) / TWO_PI


def speed_rate(law: LawLike, volts: float, omega: float) -> float:
    """Right-hand side of the speed ODE, d omega / dt in rad/s^2, at speed ``omega`` >= 0.

    This is the model that :func:`simulate_speed` solves in closed form; it is exposed for
    documentation and for checking with a general-purpose ODE solver.
    """
    target = float(target_speed_rad_s(law, volts))
    if omega <= 0.0 and target <= 0.0:
        return 0.0  # at rest and not driven forwards: stiction / braking ends at zero
    tau = law.tau_spinup_s if abs(target) > omega else law.tau_spindown_s
    return (target - omega) / tau


def rise_time_s(law: LawLike) -> float:
    """10-90 % rise time of the speed from rest after a constant voltage step, s."""
    return law.tau_spinup_s * math.log(9.0)


def simulate_speed(law: LawLike, schedule: VoltageSchedule,
                   t: float | np.ndarray) -> np.ndarray:
    """Exact spin speed omega(t), rad/s, for the schedule (motor at rest at t = 0)."""
    omega, _ = speed_and_phase(law, schedule, t)
    return omega


def phase(law: LawLike, schedule: VoltageSchedule, t: float | np.ndarray) -> np.ndarray:
    """Exact rotor angle phi(t) = integral of omega from 0 to t, rad."""
    _, phi = speed_and_phase(law, schedule, t)
    return phi


def speed_and_phase(law: LawLike, schedule: VoltageSchedule,
                    t: float | np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(omega, phi) at times ``t`` (any shape, >= 0 s), rad/s and rad, vectorised over ``t``."""
    return evaluate(segments(law, schedule), np.asarray(t, dtype=float))


def held_speed_and_phase(law: LawLike, t_s: np.ndarray,
                         volts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(omega, phi) at the sample times ``t_s`` (s, increasing) for ``volts[k]`` (V) held from
    ``t_s[k]`` to the next time, from rest at ``t_s[0]``: the exact law on
    :meth:`VoltageSchedule.held`."""
    t = np.asarray(t_s, dtype=float)
    return speed_and_phase(law, VoltageSchedule.held(t, volts), t - t[0])


# ---------------------------------------------------------------- exact piecewise solution


@dataclass(frozen=True)
class Segments:
    """Pieces on which omega(t) = T + (w0 - T) exp(-(t - t0) / tau) holds exactly."""

    t0: np.ndarray
    w0: np.ndarray
    target: np.ndarray
    tau: np.ndarray
    phi0: np.ndarray


def evaluate(seg: Segments, times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(omega, phi) of the pieces ``seg`` at ``times`` (s, >= 0)."""
    if not np.all(np.isfinite(times)) or np.any(times < 0.0):
        raise ValueError("t must be finite and >= 0 s (the schedule starts at t = 0)")
    idx = np.searchsorted(seg.t0, times, side="right") - 1
    s = times - seg.t0[idx]
    target, tau, excess = seg.target[idx], seg.tau[idx], seg.w0[idx] - seg.target[idx]
    decay = np.exp(-s / tau)
    # max(): round-off must not produce a tiny negative speed just before a stop.
    omega = np.maximum(target + excess * decay, 0.0)
    phi = seg.phi0[idx] + target * s - excess * tau * np.expm1(-s / tau)
    return omega, phi


def segments(law: LawLike, schedule: VoltageSchedule) -> Segments:
    """Split every constant-voltage interval at tau switches and at the stop."""
    if not isinstance(schedule, VoltageSchedule):
        raise TypeError(f"schedule must be a VoltageSchedule, got {type(schedule).__name__}")
    _check_schedule_volts(law, schedule)
    starts = schedule.start_times_s
    ends = np.append(starts[1:], np.inf)
    targets = target_speed_rad_s(law, schedule.volts).tolist()
    rows: list[tuple[float, float, float, float, float]] = []
    omega, phi = 0.0, 0.0
    for start, end, target in zip(starts.tolist(), ends.tolist(), targets, strict=True):
        t = start
        for piece_target, tau, duration in _interval_pieces(law, omega, target):
            rows.append((t, omega, piece_target, tau, phi))
            span = min(duration, end - t)
            if not math.isfinite(span):
                break
            omega, phi = _advance(omega, phi, piece_target, tau, span, span == duration)
            t += span
            if t >= end:
                break
    t0, w0, tgt, tau, phi0 = (np.array(col) for col in zip(*rows, strict=True))
    return Segments(t0, w0, tgt, tau, phi0)


def _interval_pieces(law: LawLike, omega: float,
                     target: float) -> list[tuple[float, float, float]]:
    """(target, tau, duration) pieces for a constant target starting at speed ``omega``.

    The last piece has infinite duration. A positive or zero target is approached
    monotonically, so tau never changes. A negative (braking) target is approached with
    tau_spindown while omega >= |target|, then tau_spinup, until omega reaches 0 at a time
    known in closed form; the speed then stays at rest.
    """
    tau_up, tau_down = law.tau_spinup_s, law.tau_spindown_s
    if target >= 0.0:
        return [(target, tau_up if target > omega else tau_down, math.inf)]
    rest = (0.0, 1.0, math.inf)  # omega = 0, phi constant (tau irrelevant)
    if omega <= 0.0:
        return [rest]
    pieces = []
    if omega >= -target:
        # omega(s) = T + (omega - T) e^{-s/tau_down} reaches |T| = -T at this s:
        pieces.append((target, tau_down, tau_down * math.log((omega - target) / (-2.0 * target))))
        omega = -target
    # ... and reaches 0 with tau_up at this s:
    pieces.append((target, tau_up, tau_up * math.log((omega - target) / (-target))))
    pieces.append(rest)
    return [p for p in pieces if p[2] > 0.0]  # drop zero-length pieces (omega == |target|)


def _advance(omega: float, phi: float, target: float, tau: float, span: float,
             completes: bool) -> tuple[float, float]:
    """Exact (omega, phi) after ``span`` s on one piece; snaps to the piece's end speed."""
    excess = omega - target
    phi_end = phi + target * span - excess * tau * math.expm1(-span / tau)
    if completes and target < 0.0:
        # Braking pieces end exactly at |target| (tau switch) or at 0 (stop).
        end = -target if omega > -target else 0.0
        return end, phi_end
    return max(target + excess * math.exp(-span / tau), 0.0), phi_end


# ---------------------------------------------------------------- validation helpers


def _require(owner: str, name: str, value: float, allowed: str,
             ok: Callable[[float], bool]) -> None:
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise TypeError(f"{owner}.{name} must be a real number in {allowed}, got {value!r}")
    if not (math.isfinite(value) and ok(float(value))):
        raise ValueError(f"{owner}.{name} must be in {allowed}, got {value!r}")


def _check_volts(law: LawLike, volts: float | np.ndarray) -> np.ndarray:
    v = np.asarray(volts, dtype=float)
    limit = law.max_voltage_V
    if not np.all(np.isfinite(v)) or np.any(np.abs(v) > limit):
        raise ValueError(
            f"voltage must be within [-{limit}, {limit}] V (max_voltage_V), got {volts!r}"
        )
    return v


def _check_schedule_volts(law: LawLike, schedule: VoltageSchedule) -> None:
    limit = law.max_voltage_V
    for i, (_, volts) in enumerate(schedule.steps):
        if abs(volts) > limit:
            raise ValueError(
                f"VoltageSchedule.steps[{i}] volts = {volts} V is outside [-{limit}, {limit}] V "
                "(max_voltage_V)"
            )


def _as_pairs(steps: Iterable[Iterable[float]]) -> list[tuple[float, float]]:
    try:
        pairs = [tuple(step) for step in steps]
    except TypeError as exc:
        raise TypeError("VoltageSchedule.steps must be a sequence of (t_start_s, volts)") from exc
    for i, pair in enumerate(pairs):
        if len(pair) != 2:
            raise ValueError(f"VoltageSchedule.steps[{i}] must be (t_start_s, volts), got {pair}")
    return pairs  # type: ignore[return-value]
