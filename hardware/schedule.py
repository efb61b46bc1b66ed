"""A pattern bound to a plan: drive levels per step and the timed schedule of channel segments.

Per step, the target amplitude of site i is its intensity times the site's own amplitude at
the nominal level (the plan's crosstalk matrix diagonal, C[i, i]); the channel levels are the
bounded least-squares drive of :func:`planner.drive_levels` (levels in [0, 1], 1 = nominal).

Timing comes from the plan's ``timing`` object (the transient model, ``planner.timing``):
each driven channel gets an overdrive kick of ``overdrive_ms`` at ``overdrive_level`` times its
level (the kick's ratio to the steady drive is kept at lower levels: an approximation for a
motor whose speed is not linear in voltage), the steady level for the rest of the step, then
a brake pulse of reverse drive at the same ratio for ``brake_ms``. Two stimuli of one channel
(in successive steps or with other steps between) need at least ``min_isi_ms`` (and
``brake_ms``) from the end of one to the start of the next (the shortest inter-stimulus
interval at which the residual vibration has died out); a shorter interval is an error naming
the step.

The actuator is asked, never assumed: the plan's ``timing.actuator`` and ``timing.drive_law``
(absent in plans made before they were recorded: the coin ERM with its default law) give its
drive law (:func:`motorlaw.drive_law`), which says whether an overdrive kick and a reverse-drive
brake exist, and whether the device drives a carrier at the plan's frequency (an LRA, driven at
its resonance when the plan's frequency is it) or a DC level whose size sets the speed (the
ERM: no carrier). Whether the law reaches the plan's frequency within its voltage limit is
checked with the other limits (:func:`hardware.limits.resolve_limits`).
"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from fieldspec import FieldError
from fieldspec.documents import read_json_file
from hardware.pattern import Pattern, PatternError
from hardware.protocol import Segment
from motorlaw import DriveLaw, SpeedLaw, drive_law
from planner.drive import drive_levels, rendered
from planner.paths import resolve_plan_models
from planner.plan_record import PlanCheck, PlanRecord, PlanRecordError

__all__ = ["ACTIVE_LEVEL", "TIMING_KEYS", "PlanFile", "PlanFileError", "Schedule", "StepDrive",
           "build_schedule", "load_plan", "plan_from_dict"]

TIMING_KEYS = ("rise_ms", "decay_ms", "overdrive_ms", "overdrive_level", "brake_ms",
               "min_isi_ms")
ACTIVE_LEVEL = 1.0 / 4096  # below one protocol level step a channel counts as off


class PlanFileError(FieldError):
    """A plan JSON that cannot be played (``.field`` names the key)."""


@dataclass(frozen=True)
class PlanFile:
    """What ``play`` needs from a plan: the array, its crosstalk and the unit's timing."""

    data: dict[str, Any]
    crosstalk_um: NDArray  # C[i, j]: amplitude at site i of unit j at the nominal level [um]
    positions_mm: NDArray
    frequency_hz: float
    timing: dict[str, float]
    record: PlanCheck | None = None  # sealed / edited / unsealed (planner.plan_record)

    @property
    def n_sites(self) -> int:
        return len(self.crosstalk_um)

    @property
    def drive(self) -> DriveLaw:
        """The actuator's drive law from ``timing.actuator`` and ``timing.drive_law`` (a plan
        without them: the coin ERM's default law); PlanFileError naming the key."""
        t = self.data.get("timing") or {}
        kind = t.get("actuator", SpeedLaw.kind)
        params = t.get("drive_law") or {}
        if not isinstance(kind, str) or not isinstance(params, dict):
            raise PlanFileError("timing.actuator", "plan.timing.actuator must be a name and "
                                "timing.drive_law an object; re-plan")
        try:
            return drive_law(kind, params)
        except (TypeError, ValueError) as err:
            raise PlanFileError("timing.drive_law" if "drive law" not in str(err)
                                else "timing.actuator", f"plan.timing: {err}; re-plan") from None


def plan_from_dict(d: Any, schema: dict[str, Any] | None = None) -> PlanFile:
    """Validate a plan mapping (``hapticrom plan --out``) as untrusted input: its record
    (:func:`planner.plan_record.check_plan`: header, every number in its physical range,
    ``schema`` when given, the digest; read as :class:`planner.plan_record.PlanRecord`) and
    what playing needs."""
    try:
        plan = PlanRecord.from_json(d, schema)
    except PlanRecordError as err:
        raise PlanFileError(err.field, str(err)) from None
    record = plan.check
    if plan.best is None:
        raise PlanFileError("best", "the plan has no feasible design (best = null): nothing "
                            "to play; re-plan with wider pitch bounds or another criterion")
    missing = [k for k in ("crosstalk_um", "positions_mm", "best_frequency_hz") if k not in d]
    if missing:
        raise PlanFileError(missing[0], f"plan: missing or malformed {missing[0]!r}")
    try:
        C = np.asarray(plan.crosstalk_um, dtype=float)
        pos = np.asarray(plan.positions_mm, dtype=float)
        freq = float(plan.best_frequency_hz)
    except (KeyError, TypeError, ValueError) as err:
        raise PlanFileError(str(err).strip("'"), f"plan: missing or malformed {err}") from None
    if C.ndim != 2 or C.shape[0] != C.shape[1] or not C.size or not np.all(np.isfinite(C)) \
            or np.any(C < 0) or np.any(np.diag(C) <= 0):
        raise PlanFileError("crosstalk_um", "plan.crosstalk_um: expected a square matrix of "
                            "amplitudes >= 0 um with a positive diagonal")
    if pos.shape != (len(C), 2):
        raise PlanFileError("positions_mm", f"plan.positions_mm: expected {len(C)} x 2 "
                            "site positions")
    if "timing" not in d:  # absent (an older plan), not null (timing unavailable)
        raise PlanFileError("timing", "the plan has no 'timing' (rise, decay, overdrive, "
                            "brake, inter-stimulus interval from the transient model): re-plan "
                            "it with the current `hapticrom plan` so that it carries the timing")
    t = plan.timing
    if t is None or (isinstance(t, dict) and t.get("unavailable")):
        why = f" ({t['unavailable']})" if t else ""
        raise PlanFileError("timing", f"the plan's timing is unavailable{why}: play needs the "
                            "unit's rise, decay, overdrive, brake and inter-stimulus interval; "
                            "re-plan with a drive frequency and model the timing can be "
                            "computed for")
    if not isinstance(t, dict):
        raise PlanFileError("timing", "plan.timing must be an object; re-plan")
    timing = {}
    for key in TIMING_KEYS:
        v = t.get(key)
        hi = 8.0 if key == "overdrive_level" else 60_000.0
        lo_ok = v is not None and not isinstance(v, bool) and isinstance(v, int | float) and (
            v >= 1.0 if key == "overdrive_level" else v >= 0)
        if not lo_ok or not v <= hi:
            allowed = "1 <= overdrive_level <= 8" if key == "overdrive_level" else \
                f"0 <= {key} <= 60000"
            raise PlanFileError(f"timing.{key}", f"plan.timing.{key} = {v!r}: expected a "
                                f"number, allowed {allowed}; re-plan to refresh the timing")
        timing[key] = float(v)
    return PlanFile(d, C, pos, freq, timing, record)


def load_plan(path: str | Path, schema: dict[str, Any] | None = None) -> PlanFile:
    data = read_json_file(path, PlanFileError, "plan")
    plan = plan_from_dict(data, schema)  # checked as written; then its model paths made usable
    return replace(plan, data=resolve_plan_models(copy.deepcopy(plan.data), path))


@dataclass(frozen=True)
class StepDrive:
    """One step bound to the plan: when, the channel levels, target and rendered site
    amplitudes [um]."""

    start_ms: int
    duration_ms: int
    levels: NDArray
    target_um: NDArray
    rendered_um: NDArray


@dataclass(frozen=True)
class Schedule:
    """The steps and the channel segments a device plays (times in ms from the start)."""

    n_channels: int
    frequency_hz: float
    timing: dict[str, float]
    steps: tuple[StepDrive, ...]
    segments: tuple[Segment, ...]
    carrier_hz: float | None = None  # the AC drive frequency (an LRA), None: a DC level (ERM)

    @property
    def total_ms(self) -> int:
        ends = [s.t_ms + s.duration_ms for s in self.segments]
        ends += [s.start_ms + s.duration_ms for s in self.steps]
        return max(ends, default=0)


def _targets(pattern: Pattern, plan: PlanFile) -> NDArray:
    n = plan.n_sites
    own = np.diag(plan.crosstalk_um)
    rows = []
    for k, step in enumerate(pattern.steps):
        if step.intensities is not None:
            if len(step.intensities) != n:
                raise PatternError(f"step[{k}].intensities", f"step[{k}].intensities has "
                                   f"{len(step.intensities)} values: the plan has {n} sites")
            x = np.asarray(step.intensities, dtype=float)
        else:
            bad = [s for s in step.sites if s >= n]
            if bad:
                raise PatternError(f"step[{k}].sites", f"step[{k}].sites: site {bad[0]} does "
                                   f"not exist; allowed 0 <= site <= {n - 1}")
            x = np.zeros(n)
            x[list(step.sites)] = step.intensity
        rows.append(x * own)
    return np.array(rows)


def build_schedule(pattern: Pattern, plan: PlanFile) -> Schedule:
    """Levels for every step and the timed segments (overdrive and brake where the actuator's
    drive law has them, steady)."""
    t = plan.timing
    law = plan.drive  # its reach at the plan's frequency: hardware.limits.resolve_limits
    od_ms = round(t["overdrive_ms"]) if law.overdrive else 0
    brake_ms = round(t["brake_ms"]) if law.brake else 0
    ratio = t["overdrive_level"]
    steps: list[StepDrive] = []
    segs: list[Segment] = []
    start = 0.0
    min_gap = max(t["min_isi_ms"], t["brake_ms"] if law.brake else 0.0)
    last_end = np.full(plan.n_sites, -np.inf)  # end of each channel's last stimulus [ms]
    last_step = np.zeros(plan.n_sites, dtype=int)
    for k, (step, target) in enumerate(zip(pattern.steps, _targets(pattern, plan), strict=True)):
        sol = drive_levels(plan.crosstalk_um, target)
        levels = np.where(sol.levels >= ACTIVE_LEVEL, sol.levels, 0.0)
        active = levels > 0
        soon = active & (start - last_end < min_gap - 1e-9)
        if np.any(soon):
            ch = int(np.flatnonzero(soon)[0])
            j = int(last_step[ch])
            field = f"step[{j}].gap_ms" if j == k - 1 else f"step[{k}]"
            raise PatternError(field, f"{field}: channel {ch} is driven in steps {j} and {k} "
                               f"{start - last_end[ch]:g} ms apart; successive stimuli of a "
                               f"channel need at least the plan's min_isi_ms (and brake_ms) = "
                               f"{min_gap:g} ms between them")
        last_end[active] = start + step.duration_ms
        last_step[active] = k
        t0, dur = round(start), round(step.duration_ms)
        steps.append(StepDrive(t0, dur, levels, target, rendered(plan.crosstalk_um, levels)))
        for ch in np.flatnonzero(active):
            u = float(levels[ch])
            kick = min(od_ms, dur)
            if kick:
                segs.append(Segment(t0, kick, int(ch), u * ratio))
            if dur > kick:
                segs.append(Segment(t0 + kick, dur - kick, int(ch), u))
            if brake_ms:
                segs.append(Segment(t0 + dur, brake_ms, int(ch), -u * ratio))
        start += step.duration_ms + step.gap_ms
    if not math.isfinite(start):
        raise PatternError("step", "the pattern's total duration is not finite")
    segs.sort(key=lambda s: (s.t_ms, s.channel))
    return Schedule(plan.n_sites, plan.frequency_hz, dict(t), tuple(steps), tuple(segs),
                    plan.frequency_hz if law.carrier else None)
