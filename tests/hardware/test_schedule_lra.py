"""The schedule and the limits ask the plan's actuator (its drive law, ``timing.actuator`` and
``timing.drive_law``): an LRA plan is driven with a carrier at its resonance, with its kick and
reverse-phase brake, within the LRA's own voltage limit; an ERM plan (or one made before the
actuator was recorded) is the coin ERM as before."""

from __future__ import annotations

import json

import pytest
from hw_cases import line_plan, sealed

from hapticrom.cli import main
from hardware import ERM_RATING, SafetyError, resolve_limits
from hardware.limits import preflight, rating_of
from hardware.pattern import pattern_from_dict
from hardware.schedule import PlanFileError, build_schedule, plan_from_dict
from motorlaw import ResonantDrive

LRA = ResonantDrive()
PATTERN = {"step": [{"sites": [0, 2], "duration_ms": 80.0, "gap_ms": 20.0}]}


def lra_plan(frequency_hz: float = LRA.resonance_hz) -> dict:
    d = line_plan()
    d["best_frequency_hz"] = frequency_hz
    d["timing"].update(actuator="lra", drive_law=LRA.params(), overdrive_level=1.5,
                       nominal_voltage_V=LRA.nominal_voltage_V(frequency_hz))
    return d


def test_an_lra_plan_drives_a_carrier_at_resonance_with_kick_and_brake():
    plan = plan_from_dict(lra_plan())
    assert plan.drive == LRA
    sched = build_schedule(pattern_from_dict(PATTERN), plan)
    assert sched.carrier_hz == LRA.resonance_hz
    levels = sorted({s.level for s in sched.segments if s.channel == 0})
    assert levels[0] < 0 < levels[1] < levels[2]  # brake (reversed phase), steady, kick
    assert levels[2] / levels[1] == pytest.approx(1.5) == -levels[0] / levels[1]
    erm = build_schedule(pattern_from_dict(PATTERN), plan_from_dict(line_plan()))
    assert erm.carrier_hz is None  # a DC level: the ERM's voltage sets its speed
    assert [(s.t_ms, s.level) for s in erm.segments] == [(s.t_ms, s.level)
                                                         for s in sched.segments]


def test_the_lra_limits_are_its_own():
    plan = plan_from_dict(lra_plan())
    rating = rating_of(plan)
    assert rating.law == LRA and rating_of(plan_from_dict(line_plan())) is ERM_RATING
    resolved = resolve_limits(plan.frequency_hz, actuator=rating)
    assert resolved.limits.max_level == pytest.approx(LRA.max_voltage_V / LRA.rated_voltage_V)
    preflight(plan, build_schedule(pattern_from_dict(PATTERN), plan), resolved)  # passes
    with pytest.raises(SafetyError, match=r"166\.33 to 186\.22 Hz") as err:
        resolve_limits(200.0, actuator=rating)
    assert err.value.field == "best_frequency_hz"


def test_a_malformed_actuator_is_refused_naming_it():
    d = lra_plan()
    d["timing"]["actuator"] = "voice_coil"
    with pytest.raises(PlanFileError) as err:
        build_schedule(pattern_from_dict(PATTERN), plan_from_dict(d))
    assert err.value.field == "timing.actuator" and "'voice_coil'" in str(err.value)
    d = lra_plan()
    d["timing"]["drive_law"] = {"quality_factor": -1.0}
    with pytest.raises(PlanFileError) as err:
        build_schedule(pattern_from_dict(PATTERN), plan_from_dict(d))
    assert err.value.field == "timing.drive_law" and "lra.quality_factor" in str(err.value)


def test_play_an_lra_plan_on_the_log_device(tmp_path):
    path = tmp_path / "plan.json"
    path.write_text(json.dumps(sealed(lra_plan())))
    pat = tmp_path / "p.toml"
    pat.write_text("[[step]]\nsites = [0, 2]\nduration_ms = 80.0\ngap_ms = 20.0\n")
    out = tmp_path / "out"
    assert main(["play", str(path), str(pat), "--device", "log", "--out", str(out)]) == 0
    lines = [json.loads(x) for x in (out / "commands.jsonl").read_text().splitlines()]
    played = next(x for x in lines if x["command"] == "play")
    assert played["carrier_hz"] == LRA.resonance_hz == played["frequency_hz"]
    limits = next(x for x in lines if x["command"] == "limits")
    assert limits["max_level"]["value"] == pytest.approx(1.5)
    assert limits["max_level"]["owner"].startswith("actuator: 3 V maximum / 2 V nominal at "
                                                   "175 Hz; motorlaw.lra.DEFAULTS")


def test_a_plan_cannot_raise_its_actuators_limit():
    d = lra_plan()
    d["timing"]["drive_law"] = {**LRA.params(), "max_voltage_V": 10.0}
    plan = plan_from_dict(d)
    assert plan.drive.max_voltage_V == 10.0 and rating_of(plan).law == LRA  # the defaults
    assert resolve_limits(plan.frequency_hz, actuator=rating_of(plan)).limits.max_level == \
        pytest.approx(1.5)
