"""Issue 27 item 4: the daily exposure survives a crash. The dose is appended to the exposure
file as it accrues (fsync'd lines), so a host killed with kill -9 loses at most the last
second; a malformed exposure file is refused naming the file, the line and the key (exit 2).
The meters here read a fixed clock (``today=``): what day a dose lands on is
test_exposure_days.py's subject."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from datetime import date
from pathlib import Path

import numpy as np
import pytest
from hw_cases import line_plan, sealed

from hapticrom.cli import main
from hardware import ExposureMeter, SafetyError, build_schedule, load_pattern, plan_from_dict
from hardware.emulator import PtyEmulator

ROOT = Path(__file__).resolve().parents[2]
DAY = date(2026, 3, 14)  # the meters' clock: no test here reads the wall clock's date
TODAY = DAY.isoformat()


def on_day(n_sites: int, state: Path | None) -> ExposureMeter:
    """A meter of ``state`` whose clock says DAY."""
    return ExposureMeter(n_sites, state_path=state, today=lambda: DAY)


def files(tmp_path: Path, n_steps: int) -> tuple[Path, Path]:
    plan = tmp_path / "plan.json"
    plan.write_text(json.dumps(sealed(line_plan())))
    pattern = tmp_path / "p.toml"
    pattern.write_text("[[step]]\nsites = [0, 2]\nduration_ms = 250.0\ngap_ms = 60.0\n"
                       "[[step]]\nsites = [1]\nduration_ms = 250.0\ngap_ms = 60.0\n" * n_steps)
    return plan, pattern


def test_the_file_is_append_only_lines_that_add_up(tmp_path):
    state = tmp_path / "exposure.jsonl"
    one = on_day(2, state)
    one.record(np.array([[1e-6, 0.0]]), 125.0, [60.0])
    one.record(np.array([[1e-6, 2e-6]]), 125.0, [60.0])
    lines = [json.loads(x) for x in state.read_text().splitlines()]
    assert len(lines) == 2 and all(x["date"] == TODAY for x in lines)
    assert on_day(2, state).dose == pytest.approx(one.dose, rel=1e-8)
    # a line torn by a crash while it was written is skipped, and the next one starts afresh
    with state.open("a") as f:
        f.write('{"date": "' + TODAY + '", "dose": [1.0')
    assert on_day(2, state).dose == pytest.approx(one.dose, rel=1e-8)
    two = on_day(2, state)
    two.record(np.array([[1e-6, 0.0]]), 125.0, [60.0])
    assert on_day(2, state).dose == pytest.approx(two.dose, rel=1e-8)
    # yesterday's lines and another array's do not count today
    with state.open("a") as f:
        f.write(json.dumps({"date": "2000-01-01", "dose": [9.0, 9.0]}) + "\n")
        f.write(json.dumps({"date": TODAY, "dose": [9.0, 9.0, 9.0]}) + "\n")
    assert on_day(2, state).dose == pytest.approx(two.dose, rel=1e-8)
    # the earlier layout (one object with the day's total) is one such line
    old = tmp_path / "old.json"
    old.write_text(json.dumps({"date": TODAY, "dose": [0.5, 0.25]}))
    assert on_day(2, old).dose.tolist() == [0.5, 0.25]


@pytest.mark.parametrize("text, words", [
    ('{"date": "' + TODAY + '"}\n', "line 1 needs 'date' (YYYY-MM-DD) and 'dose'"),
    ('{"date": "' + TODAY + '", "dose": [1.0, -2.0, 0.0]}\n', "'dose' (a list of numbers >= 0"),
    ('[1, 2, 3]\n', "line 1 needs"),
    ('{"date": "' + TODAY + '", "dose": [0, 0, 0]}\nnot json\n{"date": "x", "dose": []}\n',
     "line 2 is not JSON"),
])
def test_a_malformed_exposure_file_is_refused_naming_it(tmp_path, capsys, text, words):
    state = tmp_path / "exposure.jsonl"
    state.write_text(text)
    with pytest.raises(SafetyError) as err:
        on_day(3, state)
    assert err.value.field == "exposure-file" and words in str(err.value)
    plan, pattern = files(tmp_path, 1)
    rc = main(["play", str(plan), str(pattern), "--device", "serial:/dev/null-none",
               "--exposure-file", str(state)])
    err = capsys.readouterr().err
    assert rc == 2 and f"--exposure-file {state}" in err and "Traceback" not in err


def test_kill_9_while_playing_loses_at_most_the_last_second(tmp_path):
    plan, pattern = files(tmp_path, 8)  # 16 steps of 250 ms, 310 ms apart: 4.9 s
    state = tmp_path / "exposure.jsonl"
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    with PtyEmulator(3, max_level=1.6) as emu:
        proc = subprocess.Popen([sys.executable, "-m", "hapticrom.cli", "play", str(plan),
                                 str(pattern), "--device", f"serial:{emu.port}",
                                 "--exposure-file", str(state)], cwd=ROOT, env=env,
                                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        end = time.monotonic() + 60
        while emu.array.t0 is None and time.monotonic() < end:
            time.sleep(0.005)
        t_start = emu.array.t0
        time.sleep(2.5)
        t_kill = time.monotonic()
        proc.send_signal(signal.SIGKILL)
        proc.wait(timeout=30)
    assert t_start is not None and proc.returncode == -signal.SIGKILL
    # every line the killed process wrote, whatever day its clock said (the run may cross a
    # midnight): what survives the crash is the subject here
    recorded = np.sum([json.loads(x)["dose"] for x in state.read_text().splitlines()
                       if x.endswith("}")], axis=0)
    sched = build_schedule(load_pattern(pattern), plan_from_dict(json.loads(plan.read_text())))
    played_ms = (t_kill - t_start) * 1e3
    at_least, at_most = on_day(3, None), on_day(3, None)
    at_least.accrue(sched, 0.0, played_ms - 1000.0)  # everything but the last second
    at_most.accrue(sched, 0.0, played_ms + 50.0)
    assert played_ms < sched.total_ms - 1000  # killed well before the end
    assert np.all(recorded >= at_least.dose * (1 - 1e-6)) and at_least.dose.min() > 0
    assert np.all(recorded <= at_most.dose * (1 + 1e-6))
