"""The serial back end against the emulator over a pseudo-terminal (real time).

Deadlines are checked on the emulator's own timestamps: each channel's stop is at or after
the deadline (never early) and within the deadline plus ``SLACK_S``. The emulator checks
every millisecond; the slack covers a loaded test machine delaying its thread."""

from __future__ import annotations

import os
import time

import numpy as np
import pytest
import serial
from hw_cases import line_plan, sealed

from hardware import (
    DeviceError,
    DeviceRefused,
    Heartbeat,
    SafetyLimits,
    build_schedule,
    pattern_from_dict,
    plan_from_dict,
)
from hardware.emulator import PtyEmulator
from hardware.protocol import Decoder, ErrorCode, Frame, Msg, decode_nak, encode
from hardware.serial_device import SerialDevice

WATCHDOG_S = 0.25
SLACK_S = 0.1
N = 4


@pytest.fixture
def emu():
    with PtyEmulator(N, watchdog_s=WATCHDOG_S, max_on_s=5.0) as e:
        yield e


def wait_until(cond, limit_s=3.0):
    end = time.monotonic() + limit_s
    while time.monotonic() < end:
        if cond():
            return True
        time.sleep(0.005)
    return False


def channel_stops(emu, reason):
    with emu.lock:
        return {e.channel: e.t for e in emu.array.events if e.level == 0 and e.reason == reason}


def test_set_levels_heartbeat_and_status(emu):
    with SerialDevice(emu.port, N) as dev:
        sent = dev.set_levels(np.array([0.5, 1.0, 0.0, 2.0]))
        assert sent.tolist() == [0.5, 1.0, 0.0, 1.0]  # clamped to max_level = 1
        dev.heartbeat()
        s = dev.status()
        assert s.levels == (0.5, 1.0, 0.0, 1.0) and s.watchdog_ms == 250
        assert dev.watchdog_s == 0.25
    assert emu.array.levels == [0.0] * N  # stopped on the way out


def test_watchdog_stops_every_channel_within_the_stated_time(emu):
    dev = SerialDevice(emu.port, N)
    dev.heartbeat()
    dev.set_levels(np.ones(N))
    assert wait_until(lambda: len(channel_stops(emu, "watchdog")) == N)
    last_beat = emu.array.heartbeats[-1]
    for ch, t in channel_stops(emu, "watchdog").items():
        assert WATCHDOG_S <= t - last_beat <= WATCHDOG_S + SLACK_S, ch
    assert dev.status().watchdog_tripped
    dev.close()


def test_a_heartbeat_thread_keeps_the_array_on_and_its_end_trips_the_watchdog(emu):
    dev = SerialDevice(emu.port, N)
    with Heartbeat(dev) as hb:
        dev.set_levels(np.full(N, 0.5))
        time.sleep(0.4)  # longer than the watchdog time, shorter than the on-time limit
        assert emu.array.levels == [0.5] * N and hb.error is None and hb.beats >= 3
    assert wait_until(lambda: len(channel_stops(emu, "watchdog")) == N)
    dev.close()


def test_the_heartbeat_follows_the_shorter_watchdog_of_device_and_host():
    with PtyEmulator(N, watchdog_s=0.1) as emu:
        dev = SerialDevice(emu.port, N)
        assert dev.watchdog_s == 0.1 and Heartbeat(dev).period_s == 0.025
        dev.close()


def test_on_time_limit_over_the_link():
    with PtyEmulator(N, watchdog_s=WATCHDOG_S, max_on_s=0.6) as emu:
        dev = SerialDevice(emu.port, N)
        with Heartbeat(dev):
            dev.set_levels(np.array([1.0, 0, 0, 0]))
            on = next(e.t for e in emu.array.events if e.channel == 0 and e.level == 1.0)
            assert wait_until(lambda: 0 in channel_stops(emu, "on-time"))
        assert 0.6 <= channel_stops(emu, "on-time")[0] - on <= 0.6 + SLACK_S
        assert "watchdog" not in {e.reason for e in emu.array.events if e.t < on + 0.6}
        dev.close()


@pytest.mark.parametrize("way_out", ["close", "exception", "ctrl-c"])
def test_every_way_out_stops_all_channels(emu, way_out):
    error = {"close": None, "exception": RuntimeError, "ctrl-c": KeyboardInterrupt}[way_out]
    try:
        with SerialDevice(emu.port, N) as dev:
            dev.heartbeat()
            dev.set_levels(np.full(N, 0.75))
            assert emu.array.levels == [0.75] * N
            if error is not None:
                raise error("stop")
    except (RuntimeError, KeyboardInterrupt):
        pass
    assert emu.array.levels == [0.0] * N
    assert set(channel_stops(emu, "stop")) == set(range(N))
    assert dev.closed


def test_corrupted_bytes_get_a_nak_and_the_next_frame_an_ack(emu):
    port = serial.Serial(emu.port, timeout=0)
    bad = bytearray(encode(Msg.HEARTBEAT, 11))
    bad[-1] ^= 0x10  # a flipped CRC bit
    cut = encode(Msg.HEARTBEAT, 13)[:4] + b"\xff"  # cut off: the length runs into what follows
    port.write(b"\x00\x13garbage" + bytes(bad) + cut + encode(Msg.HEARTBEAT, 12))
    dec, got = Decoder(), []
    assert wait_until(lambda: got.extend(dec.feed(port.read(256))) or any(
        isinstance(f, Frame) and f.type == Msg.ACK for f in got))
    naks = [decode_nak(f.payload) for f in got if f.type == Msg.NAK]
    assert naks == [(11, ErrorCode.BAD_CRC), (13, ErrorCode.BAD_LENGTH)]
    assert [f.seq for f in got if f.type == Msg.ACK] == [12]
    port.close()


class Lossy:
    """A port that damages the first ``n`` frames written (one bit flipped)."""

    def __init__(self, port, n):
        self.port, self.n = port, n

    def write(self, data):
        if self.n:
            self.n -= 1
            data = bytearray(data)
            data[-1] ^= 0x01
        return self.port.write(bytes(data))

    def __getattr__(self, name):
        return getattr(self.port, name)


def test_a_damaged_command_is_sent_again_after_its_nak(emu):
    dev = SerialDevice(Lossy(serial.Serial(emu.port, timeout=0), 0), N)
    dev.port.n = 2
    dev.set_levels(np.array([0.25, 0, 0, 0]))
    assert dev.retransmissions == dev.transient_naks == 2  # sent again on each NAK
    assert emu.array.levels[0] == 0.25
    dev.close()


def test_no_answer_is_an_error_after_the_retries():
    master, slave = os.openpty()
    try:
        with pytest.raises(DeviceError, match="no acknowledgement of QUERY_STATUS after 3"):
            SerialDevice(os.ttyname(slave), N, timeout_s=0.02, retries=2)
    finally:
        os.close(master)
        os.close(slave)


class Unplugged(Lossy):
    def write(self, data):
        raise serial.SerialException("device reports readiness to read but returned no data")


def test_a_lost_link_is_a_device_error_and_the_watchdog_stops_the_array(emu):
    dev = SerialDevice(emu.port, N)
    dev.heartbeat()
    dev.set_levels(np.ones(N))
    dev.port = Unplugged(dev.port, 0)
    with pytest.raises(DeviceError, match="serial link lost"):
        with dev:
            dev.heartbeat()
    assert dev.disconnected
    assert wait_until(lambda: len(channel_stops(emu, "watchdog")) == N)


def test_a_schedule_plays_on_the_emulator_with_overdrive_and_brake():
    plan = plan_from_dict(line_plan())
    pattern = pattern_from_dict({"step": [{"sites": [1], "duration_ms": 60, "gap_ms": 50}]})
    sched = build_schedule(pattern, plan)
    # the emulator's default is the ERM's rated 4.5 / 3.3 V: it refuses the 1.5 kick itself
    with PtyEmulator(N, watchdog_s=WATCHDOG_S) as emu, \
            SerialDevice(emu.port, N, SafetyLimits(max_level=1.5)) as dev, Heartbeat(dev):
        with pytest.raises(DeviceRefused, match="LEVEL_RANGE") as err:
            dev.play(sched)
        assert err.value.field == "device" and emu.array.events == []
    with PtyEmulator(N, watchdog_s=WATCHDOG_S, max_level=1.6) as emu, \
            SerialDevice(emu.port, N, SafetyLimits(max_level=1.5)) as dev, Heartbeat(dev):
        dev.play(sched)
        assert wait_until(lambda: emu.array.t0 is None)
    levels = [round(e.level, 3) for e in emu.array.events if e.channel == 1]
    u = round(float(sched.steps[0].levels[1]), 3)
    assert levels[:4] == [round(1.5 * u, 3), u, round(-1.5 * u, 3), 0.0]


def test_cli_plays_on_a_serial_port_and_records_the_exposure(tmp_path, capsys):
    import json

    from hapticrom.cli import main

    plan = tmp_path / "plan.json"
    plan.write_text(json.dumps(sealed(line_plan())))
    pattern = tmp_path / "p.toml"
    pattern.write_text("[[step]]\nsites = [0, 2]\nduration_ms = 80.0\ngap_ms = 20.0\n"
                       "[[step]]\nsites = [1]\nduration_ms = 80.0\n")
    exposure = tmp_path / "exposure.jsonl"
    with PtyEmulator(3, watchdog_s=WATCHDOG_S, max_level=1.6) as emu:
        assert main(["play", str(plan), str(pattern), "--device", f"serial:{emu.port}",
                     "--exposure-file", str(exposure)]) == 0
        reasons = {(e.channel, e.reason) for e in emu.array.events}
    assert {(0, "schedule"), (1, "schedule"), (2, "schedule")} <= reasons
    assert "watchdog" not in {r for _, r in reasons}
    assert emu.array.levels == [0.0] * 3
    dose = np.sum([json.loads(x)["dose"] for x in exposure.read_text().splitlines()], axis=0)
    assert len(dose) == 3 and min(dose) > 0
    assert "played on serial:" in capsys.readouterr().out


def test_cli_a_missing_serial_port_exits_2(tmp_path, capsys):
    import json

    from hapticrom.cli import main

    plan = tmp_path / "plan.json"
    plan.write_text(json.dumps(sealed(line_plan())))
    pattern = tmp_path / "p.toml"
    pattern.write_text("[[step]]\nsites = [0]\nduration_ms = 10.0\n")
    port = tmp_path / "ttyNONE"
    assert main(["play", str(plan), str(pattern), "--device", f"serial:{port}"]) == 2
    assert f"cannot open serial port '{port}'" in capsys.readouterr().err
