"""Who owns each drive limit, and the check of a plan and its schedule against them.

The limits (``max_level``, ``max_on_s``, ``max_duty``, ``watchdog_s``, ``exposure_limit``:
:class:`hardware.safety.SafetyLimits`) come from three owners, in this order, each only able to
lower what the one before allows:

1. **the device**: the limits it reports in STATUS (``max_level``, ``max_on_ms``,
   ``watchdog_ms``; docs/protocol.md). ``sim`` and ``log`` report none.
2. **the actuator**: its rated values (:class:`ActuatorRating`: the defaults of the drive law
   of the plan's ``timing.actuator``, :func:`rating_of`; never parameters read from the plan).
   The level limit is the actuator's maximum voltage over the nominal drive voltage at the
   plan's frequency (levels are fractions of that nominal voltage; for the ERM at the rated
   frequency the nominal voltage is the rated voltage, so the limit is max / rated voltage).
   The nominal voltage is recomputed from the actuator's drive law. On-time, duty cycle,
   watchdog and the exposure action value have no rated value for an ERM; the project's
   defaults stand in for them (:class:`hardware.safety.SafetyLimits`, stated as such).
3. **the user**: ``--max-level``, ``--max-on-ms``, ``--max-duty``, ``--watchdog-ms``,
   ``--exposure-action`` or a limits file (:func:`load_user_limits`); a value above the limit it
   would replace is refused (exit 2), not silently ignored.

A plan only *asks*: its ``timing.overdrive_level`` and every level of the schedule built from
it and a pattern are checked against the resolved limits by :func:`preflight` before anything
is sent; a refusal names the plan field or the pattern step, the value and the limit with its
owner.
"""

from __future__ import annotations

from dataclasses import dataclass, fields, replace
from pathlib import Path
from typing import Any

import numpy as np

from fieldspec import Context, Spec, read_table, require_table
from fieldspec.toml import read_toml_file
from hardware.safety import LEVEL_TOLERANCE, SafetyError, SafetyLimits, check_schedule
from hardware.schedule import PlanFile, Schedule
from motorlaw import DriveLaw, SpeedLaw, drive_law

__all__ = ["ERM_RATING", "USER_KEYS", "ActuatorRating", "DeviceLimits", "Resolved",
           "load_user_limits", "preflight", "rating_of", "resolve_limits"]

MAX_WIRE_LEVEL = 8.0  # the protocol's int16 level range, about +-8 nominal
NOMINAL_TOLERANCE = 0.01  # relative: the plan's nominal voltage against the actuator's law


@dataclass(frozen=True)
class ActuatorRating:
    """An actuator's rated values: its drive law (:mod:`motorlaw`: the nominal voltage at a
    frequency, the largest voltage it may be driven with, ``max_voltage_V`` [V], and the law's
    parameters as attributes, e.g. the ERM's ``rated_frequency_hz``); ``source`` says where
    the numbers come from."""

    name: str
    law: DriveLaw
    source: str

    def __getattr__(self, name: str) -> float:  # the law's parameters
        if name == "law" or name.startswith("__"):
            raise AttributeError(name)
        return getattr(self.law, name)

    @property
    def max_voltage_V(self) -> float:
        return self.law.max_voltage_V

    def nominal_voltage_V(self, frequency_hz: float) -> float:
        """The steady voltage of the nominal vibration at ``frequency_hz`` [V] (the ERM's:
        spinning the motor at it)."""
        return self.law.nominal_voltage_V(frequency_hz)

    def level_limit(self, frequency_hz: float) -> float:
        """The largest level (a multiple of the nominal voltage at ``frequency_hz``)."""
        return self.max_voltage_V / self.nominal_voltage_V(frequency_hz)

    @property
    def max_frequency_hz(self) -> float:
        """The highest frequency reached within the voltage limit [Hz]."""
        return self.law.band_hz()[1]


def rating_of(plan: PlanFile) -> ActuatorRating:
    """The rating of the plan's actuator kind (``timing.actuator``): its registered drive
    law's defaults, never the parameters the plan recorded (a plan only asks; a plan computed
    with other parameters is refused by :func:`preflight`, its nominal voltage being off)."""
    kind = plan.drive.kind
    if kind == ERM_RATING.law.kind:
        return ERM_RATING
    law = drive_law(kind)
    module = type(law).__module__
    return ActuatorRating(f"{law.title} ({module} defaults)", law,
                          f"{module}.DEFAULTS (their sources and which are estimates there)")


def _erm_rating() -> ActuatorRating:
    m = SpeedLaw()
    return ActuatorRating(
        "coin ERM of the shipped models", m,
        "motorlaw.SpeedLaw (the one motor law; the defaults the models were trained with): "
        "3.3 V rated, 120 rev/s at 3.3 V (Guo et al. 2025 drive a Leader "
        "LCM0720A3463F at 3.3 V); 4.5 V maximum is the project's estimate for that motor "
        "class, not a datasheet value")


ERM_RATING = _erm_rating()


@dataclass(frozen=True)
class DeviceLimits:
    """What a device reports of its own limits (None: not reported)."""

    max_level: float | None = None
    max_on_s: float | None = None
    watchdog_s: float | None = None


#: user setting -> (SafetyLimits field, factor from the setting's unit to the field's)
USER_KEYS = {"max_level": ("max_level", 1.0), "max_on_ms": ("max_on_s", 1e-3),
             "max_duty": ("max_duty", 1.0), "watchdog_ms": ("watchdog_s", 1e-3),
             "exposure_action_m_s2": ("exposure_limit", 1.0)}


@dataclass(frozen=True)
class Resolved:
    """The limits in force and, per limit, who set it (``owners[name]``: text)."""

    limits: SafetyLimits
    owners: dict[str, str]

    def describe(self, name: str) -> str:
        """The limit and its owner, without the owner's source note."""
        return f"{getattr(self.limits, name):.4g} ({self.owners[name].split('; ')[0]})"

    def to_dict(self) -> dict[str, Any]:
        return {f.name: {"value": getattr(self.limits, f.name), "owner": self.owners[f.name]}
                for f in fields(SafetyLimits)}


def resolve_limits(frequency_hz: float, device: DeviceLimits | None = None,
                   actuator: ActuatorRating = ERM_RATING,
                   user: list[tuple[str, float, str]] | None = None) -> Resolved:
    """The limits for playing at ``frequency_hz``: device, then actuator (and the project's
    defaults where no rated value exists), then ``user`` ((SafetyLimits field, value in its
    units, where and as what it was given, e.g. ``"--watchdog-ms 300"``), applied in order);
    raises SafetyError naming the option when a user value would raise a limit."""
    base = SafetyLimits()
    values = {f.name: getattr(base, f.name) for f in fields(SafetyLimits)}
    owners = {name: "project default, no rated value: hardware.safety" for name in values}
    owners["exposure_limit"] = "ISO 5349-1 / Directive 2002/44/EC daily action value"
    nominal = actuator.nominal_voltage_V(frequency_hz)
    if nominal > actuator.max_voltage_V:
        raise SafetyError("best_frequency_hz", f"plan best_frequency_hz = {frequency_hz:g}: "
                          f"the actuator needs {nominal:.3g} V for it, above its "
                          f"{actuator.max_voltage_V:g} V maximum ({actuator.law.reach_text()}; "
                          f"{actuator.source})",
                          value=frequency_hz, limit=actuator.max_frequency_hz,
                          owner="actuator")
    values["max_level"] = min(actuator.level_limit(frequency_hz), MAX_WIRE_LEVEL)
    owners["max_level"] = (f"actuator: {actuator.max_voltage_V:g} V maximum / {nominal:.4g} V "
                           f"nominal at {frequency_hz:g} Hz; {actuator.source}")
    if device is not None:
        for name in ("max_level", "max_on_s", "watchdog_s"):
            v = getattr(device, name)
            if v is not None and v < values[name]:
                values[name], owners[name] = v, "device (its STATUS)"
    for name, v, where in user or []:
        if v > values[name] * (1 + 1e-9):
            shown = (f"{values[name] * 1e3:.4g} ms" if name.endswith("_s")
                     else f"{values[name]:.4g}")  # in the unit of the user's option
            raise SafetyError(where.split(" ")[0], f"{where}: a user setting can only lower a "
                              f"limit; the limit is {shown} "
                              f"({owners[name].split('; ')[0]})", value=v, limit=values[name],
                              owner=owners[name])
        values[name], owners[name] = v, f"user: {where}"
    return Resolved(replace(base, **{k: float(v) for k, v in values.items()}), owners)


def load_user_limits(path: str | Path) -> dict[str, float]:
    """A limits file: TOML with a ``[limits]`` table of ``max_level``, ``max_on_ms``,
    ``max_duty``, ``watchdog_ms``, ``exposure_action_m_s2`` (each optional)."""

    specs = {"max_level": Spec(float, None, "(0, 8]"),
             "max_on_ms": Spec(float, None, "(0, 3.6e6]"),
             "max_duty": Spec(float, None, "(0, 1]"),
             "watchdog_ms": Spec(float, None, "(0, 60000]"),
             "exposure_action_m_s2": Spec(float, None, "(0, 5]")}
    ctx = Context(SafetyError)
    d = read_toml_file(path, SafetyError, "limits file")
    require_table(d, "", ("limits",), ctx, what="the limits file")
    got = read_table(d.get("limits", {}), specs, "limits", ctx)
    return {k: v for k, v in got.items() if v is not None}


def _step_of(schedule: Schedule, t_ms: int) -> int:
    """The pattern step a segment starting at ``t_ms`` belongs to (its brake included)."""
    starts = [s.start_ms for s in schedule.steps]
    return max(0, int(np.searchsorted(starts, t_ms, side="right")) - 1)


def preflight(plan: PlanFile, schedule: Schedule, resolved: Resolved,
              actuator: ActuatorRating | None = None) -> None:
    """Refuse (SafetyError naming the plan field or pattern step, the value and the limit)
    anything the plan or the schedule asks beyond the limits, and a plan whose timing was
    computed for another actuator (its nominal voltage off the actuator's speed law); nothing
    has been sent."""
    actuator = actuator if actuator is not None else rating_of(plan)
    nominal = plan.data.get("timing", {}).get("nominal_voltage_V")
    want = actuator.nominal_voltage_V(plan.frequency_hz)
    if nominal is not None and abs(nominal / want - 1) > NOMINAL_TOLERANCE:
        raise SafetyError("timing.nominal_voltage_V", f"plan timing.nominal_voltage_V = "
                          f"{nominal:g} V: the actuator spins at {plan.frequency_hz:g} Hz with "
                          f"{want:.4g} V; the plan's timing was computed for another motor or "
                          "model: re-plan", value=nominal, limit=want, owner="actuator")
    lim = resolved.limits
    od = plan.timing["overdrive_level"]
    kicks = plan.timing["overdrive_ms"] > 0 or plan.timing["brake_ms"] > 0
    if kicks and od > lim.max_level + LEVEL_TOLERANCE:
        raise SafetyError("timing.overdrive_level", f"plan timing.overdrive_level = {od:g} "
                          f"asks beyond the level limit {resolved.describe('max_level')}: "
                          "refused before anything was sent", value=od, limit=lim.max_level,
                          owner=resolved.owners["max_level"])
    for s in schedule.segments:
        if abs(s.level) > lim.max_level + LEVEL_TOLERANCE:
            k = _step_of(schedule, s.t_ms)
            raise SafetyError(f"step[{k}]", f"pattern step[{k}] needs level {abs(s.level):.4g} "
                              f"on channel {s.channel} at t = {s.t_ms} ms, beyond the level "
                              f"limit {resolved.describe('max_level')}: refused before "
                              "anything was sent", value=abs(s.level), limit=lim.max_level,
                              owner=resolved.owners["max_level"])
    try:
        check_schedule(list(schedule.segments), lim)
    except SafetyError as err:
        owner = resolved.owners.get(err.field, "")
        k = _step_of(schedule, err.t_ms or 0)
        raise SafetyError(f"step[{k}]", f"pattern step[{k}]: {err} ({owner.split('; ')[0]}): "
                          "refused before anything was sent", value=err.value,
                          limit=err.limit, owner=owner, t_ms=err.t_ms) from None
