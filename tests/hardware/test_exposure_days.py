"""Which day a dose lands on (docs/safety.md): the local calendar day when it is written. A play
that crosses a local midnight splits its dose there (within ACCRUE_S); a daylight-saving change
moves none. The wall clock and the time zone are set by time-machine, so these run the same at
any hour in any zone."""

from __future__ import annotations

import json
from datetime import date, datetime, timedelta
from pathlib import Path
from zoneinfo import ZoneInfo

import numpy as np
import pytest
import time_machine
from hw_cases import line_plan

from hardware import ExposureMeter, build_schedule, plan_from_dict
from hardware.pattern import pattern_from_dict
from hardware.safety import ACCRUE_S

PATTERN = {"step": [{"sites": [0, 2], "duration_ms": 250.0, "gap_ms": 60.0},
                    {"sites": [1], "duration_ms": 250.0, "gap_ms": 60.0}] * 8}  # 4.9 s


def play_from(start: datetime, state: Path) -> tuple[object, list[tuple[float, date]]]:
    """Accrue the pattern as a real-time back end does (a line every ACCRUE_S of played time)
    with the wall clock starting at ``start``; returns the schedule and (ms, day) per line."""
    sched = build_schedule(pattern_from_dict(PATTERN), plan_from_dict(line_plan()))
    written = []
    with time_machine.travel(start, tick=False) as clock:
        meter = ExposureMeter(3, state_path=state)
        t_ms = 0.0
        while t_ms < sched.total_ms:
            nxt = min(t_ms + ACCRUE_S * 1e3, sched.total_ms)
            clock.shift(timedelta(milliseconds=nxt - t_ms))
            meter.accrue(sched, t_ms, nxt)
            written.append((nxt, date.today()))
            t_ms = nxt
    return sched, written


def dose_between(sched, t_from_ms: float, t_to_ms: float) -> np.ndarray:
    meter = ExposureMeter(3, today=lambda: date(2000, 1, 1))
    meter.accrue(sched, t_from_ms, t_to_ms)
    return meter.dose


def lines_by_day(state: Path) -> dict[str, np.ndarray]:
    days: dict[str, np.ndarray] = {}
    for line in state.read_text().splitlines():
        x = json.loads(line)
        days[x["date"]] = days.get(x["date"], 0) + np.asarray(x["dose"])
    return days


@pytest.mark.parametrize("zone, start, old_day, new_day", [
    # two seconds before midnight at the far ends of the time zones
    ("America/Adak", "2026-11-28T23:59:58", "2026-11-28", "2026-11-29"),
    ("Pacific/Kiritimati", "2026-11-28T23:59:58", "2026-11-28", "2026-11-29"),
    # Chile springs forward at midnight: 24:00 is 01:00 of the next day
    ("America/Santiago", "2026-09-05T23:59:58", "2026-09-05", "2026-09-06"),
])
def test_a_play_across_local_midnight_puts_each_dose_on_the_day_it_was_played(
        tmp_path, zone, start, old_day, new_day):
    state = tmp_path / "exposure.jsonl"
    sched, written = play_from(datetime.fromisoformat(start).replace(tzinfo=ZoneInfo(zone)),
                               state)
    split_ms = max(ms for ms, day in written if day.isoformat() == old_day)
    assert 2000 - ACCRUE_S * 1e3 <= split_ms < 2000  # midnight is 2 s into the play
    days = lines_by_day(state)
    assert sorted(days) == [old_day, new_day]
    np.testing.assert_allclose(days[old_day], dose_between(sched, 0, split_ms), rtol=1e-8)
    np.testing.assert_allclose(days[new_day], dose_between(sched, split_ms, sched.total_ms),
                               rtol=1e-8)
    # a meter opened on either day counts that day's part only
    for day in (old_day, new_day):
        opened = ExposureMeter(3, state_path=state, today=lambda d=day: date.fromisoformat(d))
        np.testing.assert_allclose(opened.dose, days[day], rtol=1e-12)


@pytest.mark.parametrize("zone, start, day", [
    # Adak falls back at 02:00: 01:00-02:00 is played twice on the same date
    ("America/Adak", "2026-11-01T01:59:58", "2026-11-01"),
    # Chile falls back at midnight: 23:00-24:00 of the 4th comes twice, the date goes back
    ("America/Santiago", "2026-04-04T23:59:58", "2026-04-04"),
])
def test_a_daylight_saving_change_moves_no_dose(tmp_path, zone, start, day):
    state = tmp_path / "exposure.jsonl"
    sched, written = play_from(datetime.fromisoformat(start).replace(tzinfo=ZoneInfo(zone)),
                               state)
    assert {d.isoformat() for _, d in written} == {day}
    days = lines_by_day(state)
    assert list(days) == [day]
    np.testing.assert_allclose(days[day], dose_between(sched, 0, sched.total_ms), rtol=1e-8)


def test_a_meter_kept_open_across_midnight_starts_the_new_day_afresh(tmp_path):
    state = tmp_path / "exposure.jsonl"
    clock = [date(2026, 11, 28)]
    meter = ExposureMeter(2, state_path=state, today=lambda: clock[0])
    meter.record(np.array([[1e-6, 2e-6]]), 125.0, [60.0])
    before = meter.dose.copy()
    assert before.min() > 0
    clock[0] = date(2026, 11, 29)
    assert meter.dose.tolist() == [0.0, 0.0]
    meter.record(np.array([[1e-6, 0.0]]), 125.0, [60.0])
    assert meter.dose[1] == 0.0 and meter.dose[0] == pytest.approx(before[0], rel=1e-12)
    clock[0] = date(2026, 11, 28)  # a clock set back finds that day's dose again
    np.testing.assert_allclose(meter.dose, before, rtol=1e-12)
