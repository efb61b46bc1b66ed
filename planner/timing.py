"""Timing of one unit's vibration envelope from the transient reduced-order model.

Everything is measured on a simulated response, through the run-time ROM
(:mod:`surrogate.runtime.rom`, numpy only) or any other ``respond(t_s, volts) -> (envelope,
speed)`` of the same shape (the tests use a first-order system with a known time constant):

- ``rise_ms``: 10-90 % rise of the envelope at the nominal drive voltage, from rest (first
  crossings of 10 % and 90 % of the steady envelope; an ERM envelope can overshoot while the
  rotor passes a resonance, so ``settle_ms`` also gives when it stays within 10 % of steady).
- ``decay_ms``: 90-10 % fall of the envelope after the drive is switched off (no brake).
- ``overdrive_ms`` at ``overdrive_level`` (the drive limit over the nominal voltage): the
  longest kick at the limit that does not drive the motor past its nominal speed (the kick
  ends when the speed reaches it, as in ERM overdrive practice); ``rise_overdrive_ms`` is the
  time to 90 % of the steady envelope with the kick, against ``t90_ms`` without.
- ``brake_ms``: reverse drive at the limit until the motor is at rest (the speed reaches 0).
- ``min_isi_ms``: time from the end of a stimulus (with the brake pulse) until the residual
  envelope stays below ``isi_level_fraction`` of the steady envelope, the shortest interval
  before the next stimulus at that site; ``min_isi_unbraked_ms`` without the brake. The level
  is the detection threshold (perceptual criterion: threshold / own amplitude) or a stated
  fraction (ratio criterion, default 0.1).

Times are found on a uniform grid of ``dt_s`` (linear interpolation between samples).
The actuator's drive law (:mod:`motorlaw`, looked up by the layout's ``timing.actuator``)
gives the nominal voltage at the plan's frequency (the coin ERM's: the inverse of its
steady-speed law, 120 rev/s at 3.3 V, stiction below 0.4 V, at most 4.5 V; the LRA's: the
voltage of its rated force there), its voltage limit and its drive state (the ERM's speed,
the LRA's force envelope); a frequency that needs more than the limit has no timing
(:class:`TimingError`). With the envelope model (``timing.model``) the envelope is the
model's, which refuses an actuator it was not trained for; with ``timing.model = ""`` it is
the drive law's own envelope times the plan's steady amplitude (:func:`law_response`: the
tissue taken as quasi-static, its own mode not modelled), which is how an LRA is timed: rise
and decay from its ring-up time constant Q / (pi f0), the brake from reverse-phase drive.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

import motorlaw
from fieldspec import FieldError
from surrogate.runtime.rom import RomBlowUpError, RomInputError, load_envelope_model

__all__ = ["TIMING_KEYS", "Timing", "TimingError", "envelope_timing", "law_response",
           "plan_timing", "rom_response", "voltage_for_frequency"]

TIMING_KEYS = ("rise_ms", "decay_ms", "overdrive_ms", "overdrive_level", "brake_ms",
               "min_isi_ms")

Response = Callable[[NDArray, NDArray], tuple[NDArray, NDArray]]
SETTLE_BAND = 0.1  # settle_ms: the envelope stays within 10 % of steady


class TimingError(FieldError):
    """The timing cannot be computed (``field`` names the input)."""

    def __init__(self, field: str, message: str) -> None:
        super().__init__(field, f"{field}: {message}")


@dataclass(frozen=True)
class Timing:
    """Envelope timing (ms; voltages in V; fractions of the steady envelope)."""

    rise_ms: float
    decay_ms: float
    overdrive_ms: float
    overdrive_level: float
    brake_ms: float
    min_isi_ms: float
    nominal_voltage_V: float
    overdrive_voltage_V: float
    brake_voltage_V: float
    steady_envelope_um: float
    t90_ms: float
    rise_overdrive_ms: float
    settle_ms: float
    min_isi_unbraked_ms: float
    isi_level_fraction: float

    def to_dict(self) -> dict[str, float]:
        return {k: round(float(v), 4) for k, v in asdict(self).items()}


def voltage_for_frequency(law: motorlaw.DriveLaw, frequency_hz: float) -> float:
    """Nominal drive voltage [V] of the actuator's drive law at ``frequency_hz`` (the ERM's
    :class:`motorlaw.SpeedLaw`: the inverse of the one speed law), refused outside the
    frequencies the law reaches within its voltage limit."""
    v = law.nominal_voltage_V(frequency_hz)
    if v > law.max_voltage_V:
        raise TimingError("frequency_hz", f"{frequency_hz:g} Hz needs {v:.3f} V, above the "
                          f"{law.noun}'s {law.max_voltage_V:g} V limit ({law.reach_text()})")
    return v


def _first_up(t: NDArray, y: NDArray, level: float) -> float:
    """First time ``y`` reaches ``level`` (interpolated); nan if never."""
    i = np.flatnonzero(y >= level)
    if not i.size:
        return float("nan")
    k = int(i[0])
    if k == 0:
        return float(t[0])
    return float(np.interp(level, [y[k - 1], y[k]], [t[k - 1], t[k]]))


def _last_above(t: NDArray, y: NDArray, level: float) -> float:
    """Time after which ``y`` stays below ``level`` (interpolated); t[0] if always below."""
    i = np.flatnonzero(y > level)
    if not i.size:
        return float(t[0])
    k = int(i[-1])
    if k == t.size - 1:
        return float("nan")
    return float(np.interp(level, [y[k + 1], y[k]], [t[k + 1], t[k]]))


def _first_down(t: NDArray, y: NDArray, level: float) -> float:
    i = np.flatnonzero(y <= level)
    if not i.size:
        return float("nan")
    k = int(i[0])
    if k == 0:
        return float(t[0])
    return float(np.interp(level, [y[k], y[k - 1]], [t[k], t[k - 1]]))


def envelope_timing(respond: Response, nominal_V: float, limit_V: float,
                    isi_level_fraction: float, *, dt_s: float = 2.5e-4,
                    horizon_s: float = 0.3) -> Timing:
    """Timing of the response ``respond`` driven at ``nominal_V`` with the drive limit
    ``limit_V`` (>= nominal), ISI level a fraction of the steady envelope (0..1)."""
    if not 0 < nominal_V <= limit_V:
        raise TimingError("nominal_V", f"need 0 < nominal ({nominal_V:g} V) <= limit "
                          f"({limit_V:g} V)")
    if not 0 < isi_level_fraction < 1:
        raise TimingError("isi_level_fraction", f"{isi_level_fraction!r}: allowed (0, 1)")
    t = np.arange(0.0, horizon_s + dt_s / 2, dt_s)
    n = t.size
    on = np.full(n, nominal_V)
    env_on, speed_on = respond(t, on)
    steady, speed_nom = float(env_on[-1]), float(speed_on[-1])
    tail = env_on[int(0.8 * n):]
    if not steady > 0 or np.ptp(tail) > 0.05 * steady:
        raise TimingError("horizon_s", f"the envelope has not settled within {horizon_s:g} s "
                          "(more than 5 % change over the last fifth)")
    t10, t90 = _first_up(t, env_on, 0.1 * steady), _first_up(t, env_on, 0.9 * steady)
    settle = _last_above(t, np.abs(env_on - steady), SETTLE_BAND * steady)

    # overdrive: the kick at the limit ends when the speed reaches the nominal speed
    _, kick_speed = respond(t, np.full(n, limit_V))
    t_kick = _first_up(t, kick_speed, speed_nom)
    t_kick = 0.0 if not np.isfinite(t_kick) or limit_V == nominal_V else t_kick
    env_od, _ = respond(t, np.where(t < t_kick - 1e-12, limit_V, nominal_V))
    t90_od = _first_up(t, env_od, 0.9 * steady)

    # switch-off from steady: held on for the horizon, then off (or braked) for another
    t2 = np.arange(0.0, 2 * horizon_s + dt_s / 2, dt_s)
    off = t2 >= horizon_s - 1e-12
    after = t2[off] - horizon_s
    env_off, _ = respond(t2, np.where(off, 0.0, nominal_V))
    fall = env_off[off]
    decay = _last_above(after, fall, 0.1 * steady) - _first_down(after, fall, 0.9 * steady)
    level = isi_level_fraction * steady
    isi_unbraked = _last_above(after, fall, level)
    _, speed_brake = respond(t2, np.where(off, -limit_V, nominal_V))
    t_brake = _first_down(after, speed_brake[off], 0.0)
    if not np.isfinite(t_brake):
        raise TimingError("brake", "the reverse drive does not bring the motor to rest within "
                          f"{horizon_s:g} s")
    env_br, _ = respond(t2, np.where(off & (t2 < horizon_s + t_brake), -limit_V,
                                     np.where(off, 0.0, nominal_V)))
    isi = _last_above(after, env_br[off], level)
    return Timing(rise_ms=1e3 * (t90 - t10), decay_ms=1e3 * decay, overdrive_ms=1e3 * t_kick,
                  overdrive_level=limit_V / nominal_V, brake_ms=1e3 * t_brake,
                  min_isi_ms=1e3 * isi, nominal_voltage_V=nominal_V,
                  overdrive_voltage_V=limit_V, brake_voltage_V=-limit_V,
                  steady_envelope_um=steady, t90_ms=1e3 * t90, rise_overdrive_ms=1e3 * t90_od,
                  settle_ms=1e3 * settle, min_isi_unbraked_ms=1e3 * isi_unbraked,
                  isi_level_fraction=isi_level_fraction)


def rom_response(model: Any, design: Mapping[str, Any], *, extrapolate: bool = False,
                 point: str = "center") -> Response:
    """``respond`` of the run-time envelope ROM (``EnvelopeModel``) for one ``design``:
    the ``point`` envelope [um] and the motor speed [rev/s]."""
    key = f"{point}_envelope_um"

    def respond(t_s: NDArray, volts: NDArray) -> tuple[NDArray, NDArray]:
        out = model.simulate(t_s, volts, design, extrapolate=extrapolate)
        return out[key], out["speed_hz"]

    return respond


def law_response(law: motorlaw.DriveLaw, frequency_hz: float, steady_um: float) -> Response:
    """``respond`` of the drive law alone at ``frequency_hz``: the envelope [um] is the
    steady amplitude ``steady_um`` times the law's force relative to its nominal force (the
    tissue quasi-static, the response's frequency dependence left out), the drive state as
    the "speed"."""
    def respond(t_s: NDArray, volts: NDArray) -> tuple[NDArray, NDArray]:
        state = law.drive_state(t_s, volts, frequency_hz)
        return steady_um * law.force_ratio(state, frequency_hz), state

    return respond


def plan_timing(request: Any, best: Any, *, dt_s: float = 5e-4,
                model: Any = None) -> dict[str, Any]:
    """The ``timing`` object of a plan: :class:`Timing` of the chosen unit (``best``, a
    :class:`planner.optimise.DesignResult`) on the request's ROM, at the voltage that spins
    the motor at the plan's frequency. The model's inputs are taken from the site and design
    (every input of the harmonic model) and the request's motor time constants. The model's
    inputs (``design``) and the motor's reach at its voltage limit
    (``max_frequency_hz``) are recorded. When the timing cannot be computed (a frequency
    above that reach, a design outside the model), every key is null and ``unavailable``
    says why, with the number. ``model``: the loaded model (else loaded from the
    request). ``extrapolated`` lists the model's inputs outside its trained range
    (``model.allow_extrapolation``). ``timing.actuator`` names the actuator; its drive law is
    the envelope model's (which refuses another actuator), or with ``timing.model = ""`` the
    registered law's defaults (:func:`law_response`); ``actuator`` and ``drive_law`` (its
    parameters) are recorded for the schedule."""
    spec = request.timing
    actuator = getattr(spec, "actuator", motorlaw.SpeedLaw.kind)  # a spec without: the ERM
    crit = request.criterion
    if crit.kind == "perceptual":
        fraction = float(crit.threshold(best.frequency_hz)) / (best.center_um * crit.drive_level)
        basis = "detection threshold / own amplitude"
    else:
        fraction, basis = spec.isi_fraction, "timing.isi_fraction"
    extra = {"model": spec.model, "isi_level_basis": basis,
             "tau_spinup_ms": spec.tau_spinup_ms, "tau_spindown_ms": spec.tau_spindown_ms,
             "actuator": actuator}
    try:
        if not spec.model and model is None:
            taus = {"tau_spinup_s": 1e-3 * spec.tau_spinup_ms,
                    "tau_spindown_s": 1e-3 * spec.tau_spindown_ms}
            return {**_law_timing(actuator, taus, best, fraction, dt_s), **extra}
        model = model if model is not None else load_envelope_model(spec.model)
        model.check_actuator(actuator)
        inputs = {**request.site, **best.inputs, "tau_spinup_ms": spec.tau_spinup_ms,
                  "tau_spindown_ms": spec.tau_spindown_ms}
        design = {k: inputs[k] for k in model.input_names if k in inputs}
        missing = [k for k in model.input_names if k not in design]
        if missing:
            raise TimingError(missing[0], f"the ROM needs {missing[0]!r} (site or design)")
        ranges = model.input_ranges
        outside = sorted(k for k, v in design.items() if not isinstance(ranges[k][0], str)
                         and not ranges[k][0] <= float(v) <= ranges[k][1])
        extra["extrapolated"] = outside
        extra["design"] = design
        extra["max_frequency_hz"] = round(model.motor.band_hz()[1], 4)
        extra["drive_law"] = model.motor.params()
        nominal = voltage_for_frequency(model.motor, best.frequency_hz)
        timing = envelope_timing(rom_response(model, design,
                                              extrapolate=request.allow_extrapolation),
                                 nominal, model.motor.max_voltage_V, min(fraction, 0.99),
                                 dt_s=dt_s)
    except (TimingError, RomInputError, RomBlowUpError, OSError, ValueError) as err:
        return {**dict.fromkeys(TIMING_KEYS), **extra, "unavailable": str(err)}
    return {**timing.to_dict(), **extra}


def _law_timing(kind: str, taus: dict[str, float], best: Any, fraction: float,
                dt_s: float) -> dict[str, Any]:
    """The timing of the actuator ``kind``'s drive law alone (its defaults, and the request's
    time constants ``taus`` where the law has such parameters: the ERM's), at the plan's
    frequency and steady amplitude (:func:`law_response`)."""
    try:
        cls = motorlaw.drive_law_class(kind)
        law = cls.from_params({k: v for k, v in taus.items() if k in cls().params()})
    except ValueError as err:
        raise TimingError("actuator", str(err)) from None
    lo, hi = law.band_hz()
    nominal = voltage_for_frequency(law, best.frequency_hz)
    timing = envelope_timing(law_response(law, best.frequency_hz, best.center_um), nominal,
                             law.max_voltage_V, min(fraction, 0.99), dt_s=dt_s)
    return {**timing.to_dict(), "drive_law": law.params(), "min_frequency_hz": round(lo, 4),
            "max_frequency_hz": round(hi, 4) if np.isfinite(hi) else None}
