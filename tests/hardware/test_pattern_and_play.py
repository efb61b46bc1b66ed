"""Pattern files, binding a pattern to a plan (levels, timing), the sim and log devices, and
``hapticrom play`` (exit 2 naming the field, nothing written)."""

from __future__ import annotations

import copy
import json

import numpy as np
import pytest
from hw_cases import TIMING, line_plan, real_plan, sealed

from hapticrom.cli import main
from hardware import (
    PatternError,
    PlanFileError,
    SafetyLimits,
    build_schedule,
    load_pattern,
    pattern_from_dict,
    plan_from_dict,
)
from hardware.log_device import LogDevice

ONE = {"step": [{"sites": [1], "duration_ms": 100.0, "gap_ms": 50.0}]}


def test_the_example_pattern_is_valid():
    p = load_pattern("examples/pattern-sweep.toml")
    assert len(p.steps) == 18 and p.steps[-1].intensities is not None


@pytest.mark.parametrize("change, field", [
    (lambda d: d.update(steps=[]), "steps"),
    (lambda d: d.pop("step"), "step"),
    (lambda d: d["step"][0].pop("duration_ms"), "step[0].duration_ms"),
    (lambda d: d["step"][0].update(duration_ms=0.0), "step[0].duration_ms"),
    (lambda d: d["step"][0].update(gap_ms=-1.0), "step[0].gap_ms"),
    (lambda d: d["step"][0].update(intensity=1.5), "step[0].intensity"),
    (lambda d: d["step"][0].update(sites=[1, 1]), "step[0].sites"),
    (lambda d: d["step"][0].update(sites=[-1]), "step[0].sites[0]"),
    (lambda d: d["step"][0].update(sites=["a"]), "step[0].sites[0]"),
    (lambda d: d["step"][0].update(intensities=[0.5]), "step[0]"),
    (lambda d: d["step"][0].pop("sites"), "step[0]"),
    (lambda d: d["step"][0].update(duration=1), "step[0].duration"),
    (lambda d: d.update(pattern={"name": 3}), "pattern.name"),
])
def test_bad_patterns_name_the_field(change, field):
    d = copy.deepcopy(ONE)
    change(d)
    with pytest.raises(PatternError) as err:
        pattern_from_dict(d)
    assert err.value.field == field, str(err.value)


@pytest.mark.parametrize("step, field, words", [
    ({"sites": [3], "duration_ms": 10.0}, "step[0].sites", "0 <= site <= 2"),
    ({"intensities": [0.5, 0.5], "duration_ms": 10.0}, "step[0].intensities", "3 sites"),
])
def test_patterns_are_checked_against_the_plan(step, field, words):
    with pytest.raises(PatternError, match=words) as err:
        build_schedule(pattern_from_dict({"step": [step]}), plan_from_dict(line_plan()))
    assert err.value.field == field


def test_a_channel_driven_twice_needs_the_inter_stimulus_interval():
    plan = plan_from_dict(line_plan())
    steps = [{"sites": [0], "duration_ms": 50.0, "gap_ms": 44.0},
             {"sites": [0, 2], "duration_ms": 50.0}]
    with pytest.raises(PatternError, match=r"channel 0 is driven in steps 0 and 1 44 ms apart;"
                       r".* min_isi_ms \(and brake_ms\) = 45 ms") as err:
        build_schedule(pattern_from_dict({"step": steps}), plan)
    assert err.value.field == "step[0].gap_ms"
    steps[0]["gap_ms"] = 45.0
    build_schedule(pattern_from_dict({"step": steps}), plan)
    steps[1]["sites"] = [2]  # another channel: no interval needed
    steps[0]["gap_ms"] = 0.0
    build_schedule(pattern_from_dict({"step": steps}), plan)
    # a step of another channel in between does not reset the interval
    steps = [{"sites": [0], "duration_ms": 50.0},
             {"sites": [2], "duration_ms": 20.0, "gap_ms": 20.0},
             {"sites": [0], "duration_ms": 50.0}]
    with pytest.raises(PatternError, match="steps 0 and 2 40 ms apart") as err:
        build_schedule(pattern_from_dict({"step": steps}), plan)
    assert err.value.field == "step[2]"
    steps[1]["gap_ms"] = 25.0
    build_schedule(pattern_from_dict({"step": steps}), plan)


@pytest.mark.parametrize("change, field", [
    (lambda d: d.pop("timing"), "timing"),
    (lambda d: d.update(timing=None), "timing"),
    (lambda d: d.update(timing={**dict.fromkeys(TIMING), "unavailable": "180 Hz needs 4.75 V"}),
     "timing"),
    (lambda d: d["timing"].pop("brake_ms"), "timing.brake_ms"),
    (lambda d: d["timing"].update(overdrive_level=0.5), "timing.overdrive_level"),
    (lambda d: d["timing"].update(rise_ms="fast"), "timing.rise_ms"),
    (lambda d: d.update(best=None), "best"),
    (lambda d: d.update(format="x"), "kind"),
    (lambda d: d.update(crosstalk_um=[[1.0, 2.0]]), "crosstalk_um[0]"),
    (lambda d: d.update(positions_mm=[[0.0, 0.0]]), "positions_mm"),
])
def test_bad_plans_name_the_key(change, field):
    d = line_plan()
    change(d)
    with pytest.raises(PlanFileError) as err:
        plan_from_dict(d)
    assert err.value.field == field
    if field == "timing":
        assert "re-plan" in str(err.value)
    if d.get("timing") and d["timing"].get("unavailable"):
        assert "unavailable (180 Hz needs 4.75 V)" in str(err.value)


def test_schedule_levels_timing_and_segments_by_hand():
    plan = plan_from_dict(line_plan())
    p = pattern_from_dict({"step": [{"sites": [0], "duration_ms": 100.0, "gap_ms": 20.0},
                                    {"intensities": [0.0, 0.5, 0.0], "duration_ms": 5.0}]})
    s = build_schedule(p, plan)
    a, b = s.steps
    assert (a.start_ms, a.duration_ms, b.start_ms, b.duration_ms) == (0, 100, 120, 5)
    assert np.flatnonzero(a.levels).tolist() == [0] and np.flatnonzero(b.levels).tolist() == [1]
    assert a.target_um.tolist() == [10.0, 0.0, 0.0] and b.target_um[1] == 5.0
    u0, u1 = a.levels[0], b.levels[1]
    # kick 10 ms at 1.5 u, steady to 100 ms, brake 8 ms at -1.5 u; a 5 ms step is all kick
    assert [(g.t_ms, g.duration_ms, g.channel, round(g.level / (u0 if g.channel == 0 else u1),
                                                      9)) for g in s.segments] == [
        (0, 10, 0, 1.5), (10, 90, 0, 1.0), (100, 8, 0, -1.5), (120, 5, 1, 1.5),
        (125, 8, 1, -1.5)]
    assert s.total_ms == 133
    # the drive is planner.drive_levels: the site alone, its level trading off the leakage
    assert 0.98 < u0 <= 1.0 and u1 == pytest.approx(u0 * 0.5, rel=0.02)


def test_log_device_writes_every_command(tmp_path):
    plan = plan_from_dict(line_plan())
    s = build_schedule(pattern_from_dict(ONE), plan)
    path = tmp_path / "c.jsonl"
    with LogDevice(path, 3, SafetyLimits(max_level=1.5)) as dev:
        dev.set_levels(np.array([0.2, 0.0, 3.0]))
        dev.heartbeat()
        dev.play(s)
        dev.status()
    lines = [json.loads(x) for x in path.read_text().splitlines()]
    assert [x["command"] for x in lines] == ["open", "set_levels", "heartbeat", "play", "status",
                                             "stop_all", "close"]
    assert lines[1]["levels"] == [0.2, 0.0, 1.5]  # clamped
    assert [x["t_s"] for x in lines] == sorted(x["t_s"] for x in lines)
    assert all("utc" in x for x in lines)
    play = lines[3]
    assert play["timing"] == TIMING and len(play["segments"]) == 3


def write_plan(tmp_path, d):
    path = tmp_path / "plan.json"
    path.write_text(json.dumps(sealed(d)))
    return path


def test_cli_sim_writes_png_and_gif(tmp_path, capsys):
    plan = write_plan(tmp_path, real_plan())
    pattern = tmp_path / "p.toml"
    pattern.write_text("[[step]]\nsites = [0]\nduration_ms = 60.0\ngap_ms = 10.0\n"
                       "[[step]]\nsites = [3, 1]\nintensity = 0.5\nduration_ms = 60.0\n")
    out = tmp_path / "play"
    assert main(["play", str(plan), str(pattern), "--device", "sim", "--out", str(out)]) == 0
    assert sorted(p.name for p in out.iterdir()) == [".hapticrom-output.json", "field-peak.png",
                                                     "field.gif"]
    assert (out / "field-peak.png").read_bytes()[:4] == b"\x89PNG"
    assert (out / "field.gif").read_bytes()[:6] == b"GIF89a"
    assert "A(8)" in capsys.readouterr().out
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]  # no temporary left


def test_cli_log_writes_jsonl(tmp_path):
    plan = write_plan(tmp_path, line_plan())
    out = tmp_path / "log"
    assert main(["play", str(plan), "examples/pattern-sweep.toml", "--device", "log", "--out",
                 str(out)]) == 2  # 16 sites in the example, 3 in this plan
    assert not out.exists()
    pattern = tmp_path / "p.toml"
    pattern.write_text("[[step]]\nsites = [0, 2]\nduration_ms = 60.0\n")
    assert main(["play", str(plan), str(pattern), "--device", "log", "--out", str(out)]) == 0
    commands = [json.loads(x)["command"] for x in (out / "commands.jsonl").read_text()
                .splitlines()]
    assert commands == ["open", "plan", "limits", "play", "stop_all", "close"]


@pytest.mark.parametrize("text, field", [
    ("[[step]]\nsites = [0]\n", "step[0].duration_ms"),
    ("[[step]]\nsites = [0]\nduration_ms = 10.0\nintensity = 2.0\n", "step[0].intensity"),
    ("[[step]\n", "<file>"),
])
def test_cli_bad_pattern_exits_2_naming_the_field_and_writes_nothing(tmp_path, capsys, text,
                                                                      field):
    plan = write_plan(tmp_path, line_plan())
    pattern = tmp_path / "p.toml"
    pattern.write_text(text)
    out = tmp_path / "out"
    assert main(["play", str(plan), str(pattern), "--device", "log", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert field in err or (field == "<file>" and "invalid TOML" in err)
    assert not out.exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["p.toml", "plan.json"]


def test_cli_plan_without_timing_exits_2_asking_to_replan(tmp_path, capsys):
    d = line_plan()
    del d["timing"]
    plan = write_plan(tmp_path, d)
    out = tmp_path / "out"
    pattern = tmp_path / "p.toml"
    pattern.write_text("[[step]]\nsites = [0]\nduration_ms = 10.0\n")
    assert main(["play", str(plan), str(pattern), "--device", "sim", "--out", str(out)]) == 2
    assert "re-plan" in capsys.readouterr().err and not out.exists()


def test_cli_refuses_a_pattern_beyond_the_on_time_limit(tmp_path, capsys):
    plan = write_plan(tmp_path, line_plan())
    pattern = tmp_path / "p.toml"
    pattern.write_text("[[step]]\nsites = [0]\nduration_ms = 2000.0\n")
    out = tmp_path / "out"
    assert main(["play", str(plan), str(pattern), "--device", "log", "--out", str(out),
                 "--max-on-ms", "1000"]) == 2
    assert "step[0]: channel 0 would run 2.008 s" in capsys.readouterr().err
    lines = [json.loads(x) for x in (out / "commands.jsonl").read_text().splitlines()]
    assert [x["command"] for x in lines] == ["open", "plan", "limits", "refused", "stop_all",
                                             "close"]  # the refusal recorded, nothing played
    assert lines[3]["field"] == "step[0]" and lines[3]["limit"] == 1.0


def test_cli_bad_device_exits_2(tmp_path, capsys):
    plan = write_plan(tmp_path, line_plan())
    assert main(["play", str(plan), "examples/pattern-sweep.toml", "--device", "usb"]) == 2
    assert "sim, log, serial:PORT" in capsys.readouterr().err


def test_playing_imports_neither_torch_nor_sklearn_nor_the_solver(tmp_path):
    import subprocess
    import sys

    plan = write_plan(tmp_path, real_plan())
    code = ("import sys\nfrom hardware import *\nfrom hardware.sim import unit_field\n"
            f"p = load_plan({str(plan)!r})\n"
            "build_schedule(pattern_from_dict({'step': [{'sites': [0], 'duration_ms': 9}]}), "
            "p)\nunit_field(p)\n"
            "bad = [m for m in ('torch', 'sklearn', 'fem') if m in sys.modules]\n"
            "assert not bad, bad\n")
    subprocess.run([sys.executable, "-c", code], check=True)
