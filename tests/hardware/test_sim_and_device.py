"""The simulated array's envelopes and field, and the device base class's safety wiring."""

from __future__ import annotations

import inspect
import time

import numpy as np
import pytest
from hw_cases import real_plan

from fieldspec import FieldError
from hardware import SafetyLimits, build_schedule, pattern_from_dict, plan_from_dict
from hardware.backends import DEVICE_KINDS, DEVICES, DeviceRequest, device_kind
from hardware.log_device import LogDevice
from hardware.protocol import Segment
from hardware.sim import SimDevice, envelopes, field_maps, unit_field

T = {"rise_ms": 20.0, "decay_ms": 40.0, "overdrive_ms": 0.0, "overdrive_level": 1.0,
     "brake_ms": 0.0, "min_isi_ms": 0.0}


def crossing(t, y, level):
    i = int(np.argmax(y >= level))
    return t[i - 1] + (level - y[i - 1]) / (y[i] - y[i - 1]) * (t[i] - t[i - 1])


def test_envelope_rise_and_decay_times_are_the_plans():
    t, e = envelopes([Segment(0, 500, 0, 1.0)], 1, T, 500)
    rise = crossing(t, e[0], 0.9) - crossing(t, e[0], 0.1)
    assert rise == pytest.approx(20.0, abs=1.0)  # the 1 ms grid
    after = t >= 500
    fall = crossing(t[after], -e[0][after], -0.1) - crossing(t[after], -e[0][after], -0.9)
    assert fall == pytest.approx(40.0, abs=1.0)
    assert e[0][t == 499] == pytest.approx(1.0, abs=1e-6)


def test_the_kick_speeds_the_rise_without_overshoot_and_the_brake_stops_at_zero():
    kick = {**T, "overdrive_ms": 15.0, "overdrive_level": 1.5, "brake_ms": 10.0}
    segs = [Segment(0, 15, 0, 0.75), Segment(15, 185, 0, 0.5), Segment(200, 10, 0, -0.75)]
    t, e = envelopes(segs, 1, kick, 210)
    _, plain = envelopes([Segment(0, 200, 0, 0.5)], 1, T, 210)
    assert e[0].max() <= 0.5 + 1e-12  # never above the nominal (steady) level
    assert crossing(t, e[0], 0.45) < crossing(t, plain[0], 0.45)
    assert e[0].min() >= 0.0 and e[0][t >= 215].max() < plain[0][t == 215].item()


def test_sim_site_amplitudes_at_steady_state_are_the_rendered_ones(tmp_path):
    plan = plan_from_dict(real_plan())
    unit = unit_field(plan)
    assert unit.center_um == pytest.approx(plan.crosstalk_um[0, 0], rel=1e-4)
    x, y, a = field_maps(unit, plan.positions_mm, n=41)
    assert a.shape == (4, 41, 41) and np.all(a > 0)
    for j, (px, py) in enumerate(plan.positions_mm):  # inside the unit: its centre amplitude
        assert a[j, np.abs(y - py).argmin(), np.abs(x - px).argmin()] == unit.center_um
        far = np.hypot(x[0] - px, y[0] - py)
        assert a[j, 0, 0] == pytest.approx(float(unit.amplitude(far)))
    sched = build_schedule(pattern_from_dict(
        {"step": [{"intensities": [1.0, 0.5, 0.0, 0.25], "duration_ms": 600.0}]}), plan)
    dev = SimDevice(tmp_path, unit, plan.positions_mm,
                    SafetyLimits(max_level=plan.timing["overdrive_level"]))
    with dev:
        dev.play(sched)
    assert dev.peak_um == pytest.approx(sched.steps[0].rendered_um.max(), rel=1e-3)
    assert sorted(p.name for p in dev.written) == ["field-peak.png", "field.gif"]


def test_a_changed_model_is_caught(tmp_path):
    d = real_plan()
    d["crosstalk_um"] = (np.array(d["crosstalk_um"]) * 1.01).tolist()
    with pytest.raises(ValueError, match="re-plan"):
        unit_field(plan_from_dict(d))


def test_heartbeat_stops_channels_set_directly_past_the_on_time_limit(tmp_path):
    with LogDevice(tmp_path / "c.jsonl", 3, SafetyLimits(max_on_s=0.05)) as dev:
        dev.set_levels(np.array([0.5, 0.0, 0.25]))
        dev.heartbeat()
        assert dev.levels.tolist() == [0.5, 0.0, 0.25]
        time.sleep(0.06)
        dev.heartbeat()
        assert dev.levels.tolist() == [0.0, 0.0, 0.0]


def test_levels_of_the_wrong_size_are_refused(tmp_path):
    with LogDevice(tmp_path / "c.jsonl", 3) as dev, pytest.raises(ValueError, match="3 chan"):
        dev.set_levels(np.ones(2))


def test_device_registry_one_signature_and_capabilities_not_names():
    """Issue 22: every device opens with one signature; play asks a kind what it does."""
    assert DEVICE_KINDS == ("sim", "log", "serial:PORT")
    for kind in DEVICES.values():
        [param] = inspect.signature(kind.open).parameters.values()
        assert param.annotation in (DeviceRequest, "DeviceRequest")
    assert [k.name for k in DEVICES.values() if k.live] == ["serial"]
    assert [k.name for k in DEVICES.values() if k.keeps_refusal] == ["log"]
    assert device_kind("serial:/dev/x") == (DEVICES["serial"], "/dev/x")
    for bad in ("serial", "sim:/dev/x", "usb"):
        with pytest.raises(FieldError, match="choose one of sim, log, serial:PORT") as err:
            device_kind(bad)
        assert err.value.field == "--device"
