"""Issue 21 item 5: after a watchdog or on-time stop, a lost link or a refusal, ``play`` says
what was and was not played (up to which step, which channels, why), exits 1 and records it;
a device refusing a schedule before it starts is bad input (exit 2, no traceback); and
``hapticrom emulate`` runs the emulator for the serial path."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest
from hw_cases import line_plan, sealed

from hapticrom.cli import main
from hardware import (
    Heartbeat,
    PlaybackInterrupted,
    SafetyLimits,
    build_schedule,
    pattern_from_dict,
    plan_from_dict,
)
from hardware.emulator import PtyEmulator
from hardware.playback import playback_report
from hardware.protocol import Frame, Msg
from hardware.serial_device import SerialDevice

ROOT = Path(__file__).resolve().parents[2]
# twelve 100 ms steps, each on one site in turn, 60 ms apart: 1.9 s in all
SWEEP = [{"sites": [k % 3], "duration_ms": 100.0, "gap_ms": 60.0} for k in range(12)]


def sweep_toml(steps=SWEEP) -> str:
    return "".join(f"[[step]]\nsites = {s['sites']}\nduration_ms = {s['duration_ms']}\n"
                   f"gap_ms = {s['gap_ms']}\n" for s in steps)


def files(tmp_path, steps=SWEEP) -> tuple[Path, Path]:
    plan = tmp_path / "plan.json"
    plan.write_text(json.dumps(sealed(line_plan())))
    pattern = tmp_path / "p.toml"
    pattern.write_text(sweep_toml(steps))
    return plan, pattern


def record_lines(out: Path) -> list[dict]:
    (path,) = out.glob("session-*.jsonl")
    return [json.loads(x) for x in path.read_text().splitlines()]


def test_the_report_splits_the_steps_at_the_last_good_moment():
    sched = build_schedule(pattern_from_dict({"step": SWEEP[:4]}), plan_from_dict(line_plan()))
    r = playback_report(sched, 200.0, "watchdog")  # steps at 0, 160, 320, 480 ms
    assert (r["steps_played"], r["step_cut"], r["steps_not_played"]) == ([0], 1, [2, 3])
    assert r["step_cut_channels"] == [1] and r["channels_not_played"] == [0, 2]
    assert "watchdog" in r["summary"] and "not played in full: steps 2-3" in r["summary"]
    assert "cut short: step 1 (channels 1)" in r["summary"]
    whole = playback_report(sched, 0.0, "link")
    assert whole["steps_played"] == [] and whole["steps_not_played"] == [0, 1, 2, 3]


def test_a_frozen_heartbeat_is_reported_as_a_cut_short_pattern():
    sched = build_schedule(pattern_from_dict({"step": SWEEP}), plan_from_dict(line_plan()))
    with PtyEmulator(3, max_level=1.6) as emu, \
            SerialDevice(emu.port, 3, SafetyLimits(max_level=1.5)) as dev:
        hb = Heartbeat(dev).start()
        threading.Timer(0.4, hb.stop).start()  # the host stops beating (as if frozen)
        with pytest.raises(PlaybackInterrupted) as err:
            dev.play(sched)
        hb.stop()
    r = err.value.report
    assert r["reason"] == "watchdog"
    assert r["steps_played"] and r["steps_not_played"]  # some of it, not all
    assert r["steps_played"][-1] < r["steps_not_played"][0]
    assert r["played_ms"] < sched.total_ms


def test_cli_reports_a_watchdog_stop_exits_1_and_records_it(tmp_path, capsys, monkeypatch):
    import hardware

    class Freezing(Heartbeat):
        """Beats for 0.4 s, then stops (the host frozen, the heartbeat thread stalled)."""

        def start(self):
            super().start()
            threading.Timer(0.4, self._stop.set).start()
            return self

    monkeypatch.setattr(hardware, "Heartbeat", Freezing)
    plan, pattern = files(tmp_path)
    out = tmp_path / "session"
    with PtyEmulator(3, max_level=1.6) as emu:
        rc = main(["play", str(plan), str(pattern), "--device", f"serial:{emu.port}",
                   "--out", str(out)])
    err = capsys.readouterr().err
    assert rc == 1 and "Traceback" not in err
    assert "play interrupted after" in err and "watchdog" in err
    assert "played in full: steps 0-" in err and "not played in full: steps" in err
    lines = record_lines(out)
    commands = [x["command"] for x in lines]
    assert commands[:2] == ["plan", "limits"] and "interrupted" in commands
    rec = lines[commands.index("interrupted")]
    assert rec["reason"] == "watchdog" and rec["steps_not_played"]
    assert rec["steps_played"] == list(range(len(rec["steps_played"])))


def test_cli_reports_an_on_time_stop(tmp_path, capsys):
    # a device that does not report its on-time limit stops a 500 ms stimulus (a 250 ms kick
    # and 250 ms steady: each segment within its 300 ms) at 300 ms
    steps = [{"sites": [0], "duration_ms": 500.0, "gap_ms": 60.0},
             {"sites": [1], "duration_ms": 100.0, "gap_ms": 0.0}]
    plan, pattern = files(tmp_path, steps)
    d = line_plan()
    d["timing"]["overdrive_ms"] = 250.0
    plan.write_text(json.dumps(sealed(d)))
    with PtyEmulator(3, max_level=1.6, max_on_s=0.3, report_limits=False) as emu:
        rc = main(["play", str(plan), str(pattern), "--device", f"serial:{emu.port}"])
        reasons = {e.reason for e in emu.array.events}
    err = capsys.readouterr().err
    assert rc == 1 and "on-time limit stopped a channel" in err and "on-time" in reasons
    assert "not played in full: steps 1 (1 steps; channels 1)" in err or "cut short: step" in err


def after_start(emu, delay_s, action):
    """Run ``action`` ``delay_s`` after the emulator accepted a schedule (in a thread)."""
    def run():
        end = time.monotonic() + 60
        while emu.array.t0 is None and time.monotonic() < end:
            time.sleep(0.005)
        time.sleep(delay_s)
        action()

    threading.Thread(target=run, daemon=True).start()


def test_cli_reports_a_lost_link(tmp_path, capsys):
    plan, pattern = files(tmp_path)
    with PtyEmulator(3, max_level=1.6) as emu:
        after_start(emu, 0.3, emu.stop)  # the device goes away mid-pattern
        rc = main(["play", str(plan), str(pattern), "--device", f"serial:{emu.port}"])
    err = capsys.readouterr().err
    assert rc == 1 and "the link to the device was lost" in err and "Traceback" not in err


def test_a_device_refusing_an_over_long_segment_is_exit_2_without_traceback(tmp_path, capsys):
    steps = [{"sites": [0], "duration_ms": 500.0, "gap_ms": 0.0}]
    plan, pattern = files(tmp_path, steps)
    out = tmp_path / "session"
    with PtyEmulator(3, max_level=1.6, max_on_s=0.2, report_limits=False) as emu:
        rc = main(["play", str(plan), str(pattern), "--device", f"serial:{emu.port}",
                   "--out", str(out)])
        assert emu.array.events == []
    err = capsys.readouterr().err
    assert rc == 2 and "Traceback" not in err
    assert "the device refused the schedule (ON_TIME" in err and "nothing was played" in err
    refusal = next(x for x in record_lines(out) if x["command"] == "refused")
    assert refusal["field"] == "device"


def _python(*args: str, **kw) -> subprocess.Popen:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.Popen([sys.executable, "-m", "hapticrom.cli", *args], cwd=ROOT, env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, **kw)


def test_a_host_frozen_by_sigstop_is_told_the_pattern_was_cut_short(tmp_path):
    plan, pattern = files(tmp_path)
    with PtyEmulator(3, max_level=1.6) as emu:
        proc = _python("play", str(plan), str(pattern), "--device", f"serial:{emu.port}")
        end = time.monotonic() + 60
        while not any(isinstance(f, Frame) and f.type == Msg.PLAY_SCHEDULE
                      for _, f in list(emu.array.received)) and time.monotonic() < end:
            time.sleep(0.01)
        time.sleep(0.2)
        proc.send_signal(signal.SIGSTOP)
        time.sleep(0.6)
        proc.send_signal(signal.SIGCONT)
        _, err = proc.communicate(timeout=60)
    assert proc.returncode == 1, err
    assert "watchdog" in err and "not played in full: steps" in err and "Traceback" not in err


def test_emulate_stops_on_ctrl_c_even_when_started_with_sigint_ignored():
    """A background job of a script inherits SIGINT ignored; the command line restores it."""
    proc = _python("emulate", "--channels", "1",
                   preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_IGN))
    try:
        assert proc.stdout.readline().strip().startswith("/dev/")
    finally:
        proc.send_signal(signal.SIGINT)
        try:
            proc.communicate(timeout=30)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.communicate()
            pytest.fail("the emulator ignored SIGINT")
    assert proc.returncode == 130


def test_emulate_prints_its_port_serves_play_and_stops_on_ctrl_c(tmp_path, capsys):
    proc = _python("emulate", "--channels", "3", "--max-level", "1.6")
    try:
        port = proc.stdout.readline().strip()
        assert port.startswith("/dev/")
        plan, pattern = files(tmp_path, SWEEP[:2])
        assert main(["play", str(plan), str(pattern), "--device", f"serial:{port}"]) == 0
        assert "played on serial:" in capsys.readouterr().out
    finally:
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=30)
    assert proc.returncode == 130
    assert "emulating 3 channels" in err and "schedule received" in err
