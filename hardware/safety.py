"""Host-side safety limits: level clamping, continuous on-time, duty cycle, daily exposure.

The firmware must enforce the same rules on its own (docs/protocol.md); the host refuses a
schedule that breaks them before anything is sent.

Exposure. No standard covers vibrotactile displays worn on the forearm. The nearest published
occupational guide is the hand-arm vibration standard **ISO 5349-1:2001** (measurement and
evaluation of human exposure to hand-transmitted vibration) with the limits of **EU Directive
2002/44/EC** (Art. 3: daily exposure action value 2.5 m/s^2, limit value 5 m/s^2, A(8)). It is
used here as that nearest guide, not because it was written for this exposure:

* skin displacement amplitude u [m] (peak) at drive frequency f -> r.m.s. acceleration
  a = (2 pi f)^2 u / sqrt(2) (sinusoidal vibration);
* frequency weighting Wh (ISO 5349-1 Annex A; the filter of ISO 8041): band limits
  f1 = 6.310 Hz, f2 = 1258.9 Hz (Q1 = Q2 = 1/sqrt 2), acceleration-velocity transition
  f3 = f4 = 15.915 Hz, Q4 = 0.64, gain 1; |Wh(125 Hz)| = 0.128 (the standard's table: 0.127);
* a_hw = |Wh(f)| a; daily exposure A(8) = sqrt(sum_i a_hw,i^2 T_i / T0), T0 = 8 h (ISO 5349-1
  eq. 2 and Annex A of the Directive), compared with the action value.

Continuous on-time, duty cycle and the watchdog time have no published standard for
vibrotactile arrays; their defaults below are project choices, stated as such, chosen well
beyond any stimulus of a pattern (so they only catch runaway output) and meant to be set per
device.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Callable
from dataclasses import dataclass, field
from datetime import date
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from fieldspec import FieldError
from hardware.protocol import Segment

__all__ = ["ACCRUE_S", "EXPOSURE_ACTION_VALUE", "EXPOSURE_LIMIT_VALUE", "ExposureMeter",
           "OnTimeGuard", "SafetyError", "SafetyLimits", "a8", "acceleration_rms", "check_schedule",
           "clamp_levels", "wh_weight"]

EXPOSURE_ACTION_VALUE = 2.5  # m/s^2 A(8), Directive 2002/44/EC Art. 3(1)(b), hand-arm
EXPOSURE_LIMIT_VALUE = 5.0  # m/s^2 A(8), Directive 2002/44/EC Art. 3(1)(a), hand-arm
T0_S = 8 * 3600.0  # reference duration of A(8): 8 h (ISO 5349-1, 2002/44/EC)
ACCRUE_S = 0.25  # a real-time back end adds the exposure played at least this often [s]
LEVEL_TOLERANCE = 5e-4  # levels are written with 4 decimals (a plan's overdrive_level)


class SafetyError(FieldError):
    """A command the safety limits refuse: ``field`` names the limit or the input; ``value``,
    ``limit`` and ``owner`` (who set the limit) when known."""

    def __init__(self, field: str, message: str, *, value: float | None = None,
                 limit: float | None = None, owner: str | None = None,
                 t_ms: float | None = None) -> None:
        super().__init__(field, message)
        self.value, self.limit, self.owner, self.t_ms = value, limit, owner, t_ms

    def to_dict(self) -> dict[str, object]:
        return {"field": self.field, "value": self.value, "limit": self.limit,
                "owner": self.owner, "message": str(self)}


@dataclass(frozen=True)
class SafetyLimits:
    """Host-side limits (levels are fractions of the nominal drive level).

    ``max_level``: 1.0 = nominal; the limit in force comes from the device, the actuator's
    rated voltage and the user (:func:`hardware.limits.resolve_limits`), never from a plan.
    ``max_on_s`` (10 s), ``duty_window_s`` (60 s), ``max_duty`` (0.5), ``watchdog_s``
    (0.25 s): project choices, no published source (module docstring).
    """

    max_level: float = 1.0
    max_on_s: float = 10.0
    duty_window_s: float = 60.0
    max_duty: float = 0.5
    watchdog_s: float = 0.25
    exposure_limit: float = EXPOSURE_ACTION_VALUE

    def __post_init__(self) -> None:
        checks = {"max_level": (self.max_level, 0, 8), "max_on_s": (self.max_on_s, 0, 3600),
                  "duty_window_s": (self.duty_window_s, 0, 86400),
                  "max_duty": (self.max_duty, 0, 1), "watchdog_s": (self.watchdog_s, 0, 60),
                  "exposure_limit": (self.exposure_limit, 0, EXPOSURE_LIMIT_VALUE)}
        for name, (v, lo, hi) in checks.items():
            if not lo < v <= hi:
                raise SafetyError(name, f"{name} = {v!r}: allowed {lo} < {name} <= {hi}")


def clamp_levels(levels: NDArray, limits: SafetyLimits) -> NDArray:
    """Levels clipped to [-max_level, max_level] (NaN refused)."""
    x = np.asarray(levels, dtype=float)
    if not np.all(np.isfinite(x)):
        raise SafetyError("levels", "levels must be finite numbers")
    return np.clip(x, -limits.max_level, limits.max_level)


def _on_intervals(segments: list[Segment], channel: int) -> list[tuple[int, int]]:
    """Merged [start, end) ms intervals during which ``channel`` is driven (level != 0)."""
    spans = sorted((s.t_ms, s.t_ms + s.duration_ms) for s in segments
                   if s.channel == channel and s.level != 0 and s.duration_ms > 0)
    merged: list[tuple[int, int]] = []
    for a, b in spans:
        if merged and a <= merged[-1][1]:
            merged[-1] = (merged[-1][0], max(merged[-1][1], b))
        else:
            merged.append((a, b))
    return merged


def check_schedule(segments: list[Segment], limits: SafetyLimits) -> list[Segment]:
    """The segments, checked: raises :class:`SafetyError` if a level is beyond ``max_level``
    (refused, never clipped: a clipped overdrive or brake is not the stimulus that was asked
    for), if a channel would run longer than ``max_on_s`` without a pause, or more than
    ``max_duty`` of any ``duty_window_s`` window."""
    out = list(segments)
    for s in out:
        if not math.isfinite(s.level) or abs(s.level) > limits.max_level + LEVEL_TOLERANCE:
            raise SafetyError("max_level", f"channel {s.channel} would be driven at level "
                              f"{s.level:g} from t = {s.t_ms} ms: the limit is "
                              f"{limits.max_level:.4g}", value=abs(s.level),
                              limit=limits.max_level, t_ms=s.t_ms)
    window_ms = limits.duty_window_s * 1e3
    for ch in sorted({s.channel for s in out}):
        spans = _on_intervals(out, ch)
        for a, b in spans:
            if b - a > limits.max_on_s * 1e3:
                raise SafetyError("max_on_s", f"channel {ch} would run {(b - a) / 1e3:g} s "
                                  f"without a pause from t = {a} ms: the limit is "
                                  f"{limits.max_on_s:g} s", value=(b - a) / 1e3,
                                  limit=limits.max_on_s, t_ms=a)
        for a, _ in spans:  # the busiest window starts where some interval starts
            busy = sum(max(0.0, min(e, a + window_ms) - max(s, a)) for s, e in spans)
            if busy > limits.max_duty * window_ms + 1e-9:
                raise SafetyError("max_duty", f"channel {ch} would be on {busy / window_ms:.0%} "
                                  f"of the {limits.duty_window_s:g} s from t = {a} ms: the "
                                  f"limit is {limits.max_duty:.0%}", value=busy / window_ms,
                                  limit=limits.max_duty, t_ms=a)
    return out


@dataclass
class OnTimeGuard:
    """Live on-time tracking for levels set directly (``set_levels``): ``update`` records when
    each channel went on, ``expired(now)`` lists the channels on for longer than the limit."""

    limits: SafetyLimits
    on_since: dict[int, float] = field(default_factory=dict)

    def update(self, levels: NDArray, now: float) -> None:
        for ch, v in enumerate(levels):
            if v != 0:
                self.on_since.setdefault(ch, now)
            else:
                self.on_since.pop(ch, None)

    def expired(self, now: float) -> list[int]:
        return sorted(ch for ch, t in self.on_since.items() if now - t > self.limits.max_on_s)

    def clear(self) -> None:
        self.on_since.clear()


# ---- exposure (ISO 5349-1, 2002/44/EC) -------------------------------------------------------

_W1, _W2 = 2 * math.pi * 6.310, 2 * math.pi * 1258.9  # band limits [rad/s]
_W3 = _W4 = 2 * math.pi * 15.915  # acceleration-velocity transition [rad/s]
_Q1 = _Q2 = 1 / math.sqrt(2)
_Q4 = 0.64


def wh_weight(frequency_hz: float | NDArray) -> NDArray:
    """|Wh(f)|: the hand-arm frequency weighting of ISO 5349-1 Annex A, band-limited."""
    s = 2j * np.pi * np.asarray(frequency_hz, dtype=float)
    hh = s**2 / (s**2 + _W1 * s / _Q1 + _W1**2)
    hl = _W2**2 / (s**2 + _W2 * s / _Q2 + _W2**2)
    ht = (s + _W3) / (s**2 + _W4 * s / _Q4 + _W4**2) * _W4**2 / _W3
    return np.abs(hh * hl * ht)


def acceleration_rms(amplitude_m: NDArray, frequency_hz: float) -> NDArray:
    """r.m.s. acceleration [m/s^2] of a sinusoidal displacement of peak ``amplitude_m``."""
    return (2 * np.pi * frequency_hz) ** 2 * np.asarray(amplitude_m, dtype=float) / np.sqrt(2)


def a8(a_hw: NDArray, duration_s: NDArray) -> float:
    """Daily exposure A(8) [m/s^2] of exposures ``a_hw`` [m/s^2] lasting ``duration_s``."""
    a_hw, t = np.asarray(a_hw, dtype=float), np.asarray(duration_s, dtype=float)
    return float(np.sqrt(np.sum(a_hw**2 * t) / T0_S))


@dataclass
class ExposureMeter:
    """Per-site accumulated sum of a_hw^2 T [m^2/s^3] for one day; optionally kept in a file
    (``state_path``) so that separate sessions of the same day add up.

    The day is the local calendar day (the host's time zone, ``TZ``) given by the clock
    ``today`` (:meth:`datetime.date.today` unless a caller injects another) when a dose is
    added: a play that crosses a local midnight puts what it plays before midnight on the old
    day and the rest on the new one, split within :data:`ACCRUE_S` (docs/safety.md). A
    daylight-saving change moves no dose: the date of the wall clock decides, whatever the
    offset.

    The file is append-only JSON lines, written through: every exposure added is one line
    ``{"date": "YYYY-MM-DD", "dose": [per site]}`` (an increment), flushed and fsync'd before
    the call returns, so a host killed with ``kill -9`` loses at most the exposure since the
    last line (a real-time back end adds one at least every :data:`ACCRUE_S`). Reading sums
    today's lines of the same site count; the earlier layout (one object holding the day's
    total) is one such line. A line that is not that is refused naming the file and the line
    (a line torn by a crash while it was written is ignored)."""

    n_sites: int
    limit: float = EXPOSURE_ACTION_VALUE
    state_path: Path | None = None
    today: Callable[[], date] = field(default=date.today, repr=False, compare=False)
    _by_day: dict[date, NDArray] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        self._by_day = {}
        self._dose_of(self.today())  # a malformed file is refused now, not at the first dose

    @property
    def dose(self) -> NDArray:
        """Today's dose per site so far [m^2/s^3] (today: the clock ``today``)."""
        return self._dose_of(self.today())

    def _dose_of(self, day: date) -> NDArray:
        """The dose of ``day``: what this meter added, or the file's lines of that day."""
        if day not in self._by_day:
            path = None if self.state_path is None else Path(self.state_path)
            self._by_day[day] = (self._read(path, day) if path is not None and path.exists()
                                 else np.zeros(self.n_sites))
        return self._by_day[day]

    def _read(self, path: Path, day: date) -> NDArray:
        total = np.zeros(self.n_sites)
        today = day.isoformat()
        lines = path.read_text(encoding="utf-8").split("\n")
        for i, line in enumerate(lines, 1):
            if not line.strip():
                continue
            try:
                state = json.loads(line)
            except (json.JSONDecodeError, RecursionError):
                if line.startswith('{"date"') and not line.rstrip().endswith("}"):
                    continue  # a line torn by a crash while it was written
                raise SafetyError("exposure-file", f"--exposure-file {path}: line {i} is not "
                                  "JSON; expected {\"date\": \"YYYY-MM-DD\", \"dose\": [...]} "
                                  "per line") from None
            dose = state.get("dose") if isinstance(state, dict) else None
            if not isinstance(state, dict) or not isinstance(state.get("date"), str) or \
                    not isinstance(dose, list) or not all(
                        isinstance(v, int | float) and not isinstance(v, bool) and
                        math.isfinite(v) and v >= 0 for v in dose):
                raise SafetyError("exposure-file", f"--exposure-file {path}: line {i} needs "
                                  "'date' (YYYY-MM-DD) and 'dose' (a list of numbers >= 0, "
                                  "one per site, m^2/s^3)")
            if state["date"] == today and len(dose) == self.n_sites:
                total += np.asarray(dose, dtype=float)
        return total

    def a8(self) -> NDArray:
        """A(8) per site so far today [m/s^2]."""
        return np.sqrt(self.dose / T0_S)

    def increment(self, site_amplitude_m: NDArray, frequency_hz: float,
                  duration_s: NDArray) -> NDArray:
        """The dose of exposures (rows: successive steps, columns: sites)."""
        a_hw = wh_weight(frequency_hz) * acceleration_rms(site_amplitude_m, frequency_hz)
        t = np.asarray(duration_s, dtype=float).reshape(-1, 1)
        return (np.atleast_2d(a_hw) ** 2 * t).sum(axis=0)

    def added(self, site_amplitude_m: NDArray, frequency_hz: float,
              duration_s: NDArray) -> NDArray:
        """The dose after exposures (rows: successive steps, columns: sites)."""
        return self.dose + self.increment(site_amplitude_m, frequency_hz, duration_s)

    def check(self, site_amplitude_m: NDArray, frequency_hz: float,
              duration_s: NDArray) -> NDArray:
        """A(8) per site after the exposures; raises SafetyError beyond the limit."""
        after = np.sqrt(self.added(site_amplitude_m, frequency_hz, duration_s) / T0_S)
        if after.max() > self.limit:
            k = int(after.argmax())
            raise SafetyError("exposure", f"site {k} would reach A(8) = {after[k]:.3g} m/s^2 "
                              f"today: the daily exposure action value is {self.limit:g} "
                              "m/s^2 (ISO 5349-1 weighting, Directive 2002/44/EC)",
                              value=float(after[k]), limit=self.limit)
        return after

    def record(self, site_amplitude_m: NDArray, frequency_hz: float,
               duration_s: NDArray) -> None:
        """Add exposures to the day's dose (and to the file, written through)."""
        self._add(self.increment(site_amplitude_m, frequency_hz, duration_s))

    def accrue(self, schedule: Any, t_from_ms: float, t_to_ms: float) -> None:
        """Add the exposure of ``schedule`` (its steps' rendered site amplitudes [um]) between
        ``t_from_ms`` and ``t_to_ms`` after its start."""
        amp = np.array([s.rendered_um for s in schedule.steps]) * 1e-6
        start = np.array([s.start_ms for s in schedule.steps], dtype=float)
        end = start + np.array([s.duration_ms for s in schedule.steps], dtype=float)
        overlap_s = np.clip(np.minimum(end, t_to_ms) - np.maximum(start, t_from_ms), 0, None)
        if overlap_s.any():
            self._add(self.increment(amp, schedule.frequency_hz, overlap_s * 1e-3))

    def _add(self, inc: NDArray) -> None:
        day = self.today()  # one reading: the line and the sum agree on the day
        self._by_day[day] = self._dose_of(day) + inc
        if self.state_path is not None:
            line = json.dumps({"date": day.isoformat(),
                               "dose": [float(f"{v:.9g}") for v in inc]})
            fd = os.open(self.state_path, os.O_RDWR | os.O_APPEND | os.O_CREAT, 0o644)
            try:
                size = os.fstat(fd).st_size
                torn = size and os.pread(fd, 1, size - 1) != b"\n"  # a crash cut the last line
                os.write(fd, (("\n" if torn else "") + line + "\n").encode("utf-8"))
                os.fsync(fd)
            finally:
                os.close(fd)
