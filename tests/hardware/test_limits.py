"""Issue 26: the drive limits come from the device, the actuator and the user, never from the
plan. Each refusal comes before the first frame that drives anything, names the plan field or
pattern step, the value and the limit, exits 2, and the log device (or the serial session
record) keeps it."""

from __future__ import annotations

import json

import pytest
from hw_cases import line_plan, sealed

from hapticrom.cli import main
from hardware import ERM_RATING, DeviceLimits, SafetyError, resolve_limits
from hardware.emulator import DEFAULT_MAX_LEVEL, PtyEmulator
from hardware.protocol import Frame, Msg

PATTERN = "[[step]]\nsites = [0, 2]\nduration_ms = 80.0\ngap_ms = 20.0\n"


def play(tmp_path, plan: dict, pattern: str = PATTERN, *extra: str, device: str = "log",
         seal: bool = True) -> tuple[int, list[dict]]:
    """Play ``plan`` on the log device; (exit code, the log's lines)."""
    path = tmp_path / "plan.json"
    path.write_text(json.dumps(sealed(plan) if seal else plan))
    pat = tmp_path / "p.toml"
    pat.write_text(pattern)
    out = tmp_path / "out"
    rc = main(["play", str(path), str(pat), "--device", device, "--out", str(out),
               "--overwrite", *extra])  # each call replaces the previous play's output
    log = out / "commands.jsonl"
    return rc, [json.loads(x) for x in log.read_text().splitlines()] if log.exists() else []


def refused(lines: list[dict]) -> dict:
    """The refusal line; nothing was played or set."""
    commands = [x["command"] for x in lines]
    assert "refused" in commands and "play" not in commands and "set_levels" not in commands
    return lines[commands.index("refused")]


def test_the_actuator_limit_is_max_over_nominal_voltage_and_each_owner_only_lowers():
    at_rated = resolve_limits(ERM_RATING.rated_frequency_hz)
    assert at_rated.limits.max_level == pytest.approx(4.5 / 3.3)  # max / rated voltage
    assert at_rated.owners["max_level"].startswith("actuator: 4.5 V maximum / 3.3 V nominal")
    assert "not a datasheet value" in at_rated.owners["max_level"]  # its source, stated
    at150 = resolve_limits(150.0)
    assert at150.limits.max_level == pytest.approx(4.5 / (0.4 + 150 * 2.9 / 120))
    dev = resolve_limits(100.0, DeviceLimits(max_level=1.2, max_on_s=2.0, watchdog_s=0.1))
    assert (dev.limits.max_level, dev.limits.max_on_s, dev.limits.watchdog_s) == (1.2, 2.0, 0.1)
    assert dev.owners["max_level"] == "device (its STATUS)"
    # a device reporting more than the actuator allows does not raise it
    loose = resolve_limits(100.0, DeviceLimits(max_level=8.0, max_on_s=3600.0))
    assert loose.limits.max_level == pytest.approx(4.5 / (0.4 + 100 * 2.9 / 120))
    assert loose.limits.max_on_s == 10.0
    user = resolve_limits(100.0, user=[("max_level", 1.1, "--max-level 1.1"),
                                       ("max_on_s", 1.0, "--max-on-ms 1000")])
    assert user.limits.max_level == 1.1 and user.owners["max_on_s"] == "user: --max-on-ms 1000"
    with pytest.raises(SafetyError, match=r"--max-level 1\.5: a user setting can only lower"
                       ) as err:
        resolve_limits(100.0, DeviceLimits(max_level=1.2), user=[("max_level", 1.5,
                                                                  "--max-level 1.5")])
    assert (err.value.field, err.value.limit) == ("--max-level", 1.2)
    with pytest.raises(SafetyError, match=r"above its 4\.5 V maximum") as err:
        resolve_limits(180.0)
    assert err.value.field == "best_frequency_hz"


def test_an_edited_overdrive_level_is_refused_before_anything_is_sent(tmp_path, capsys):
    d = line_plan()  # 100 Hz: the actuator allows 4.5 / 2.817 = 1.598
    sealed_plan = sealed(d)
    sealed_plan["timing"]["overdrive_level"] = 5.0  # edited by hand, digest left as it was
    rc, lines = play(tmp_path, sealed_plan, seal=False)
    assert rc == 2
    err = capsys.readouterr().err
    assert "plan_sha256" in err and "edited" in err and "--allow-edited-plan" in err
    assert refused(lines)["field"] == "plan_sha256"
    # allowed on purpose: the limit still holds, and the log records the permission
    rc, lines = play(tmp_path, sealed_plan, PATTERN, "--allow-edited-plan", seal=False)
    assert rc == 2
    err = capsys.readouterr().err
    assert "plan timing.overdrive_level = 5 asks beyond the level limit 1.598 (actuator" in err
    r = refused(lines)
    assert (r["field"], r["value"], round(r["limit"], 3)) == ("timing.overdrive_level", 5.0,
                                                                1.598)
    plan_line = next(x for x in lines if x["command"] == "plan")
    assert plan_line["integrity"] == "edited" and plan_line["allowed_by"] == \
        "--allow-edited-plan"
    # re-sealed by whoever edited it: a valid digest does not raise the limit either
    d["timing"]["overdrive_level"] = 5.0
    rc, lines = play(tmp_path, d)
    assert rc == 2 and refused(lines)["field"] == "timing.overdrive_level"
    assert "1.598" in capsys.readouterr().err


def test_an_edited_on_time_or_duty_cannot_raise_the_limits(tmp_path, capsys):
    # limits written into the plan are not read: the project's 10 s on-time holds
    d = line_plan()
    d["limits"] = {"max_on_s": 3600.0, "max_duty": 1.0, "max_level": 8.0}
    rc, lines = play(tmp_path, d, "[[step]]\nsites = [1]\nduration_ms = 12000.0\n")
    assert rc == 2 and "pattern step[0]: channel 1 would run 12.008 s" in \
        capsys.readouterr().err
    r = refused(lines)
    assert (r["field"], r["limit"]) == ("step[0]", 10.0)
    # a brake stretched in the plan's timing drives the channel past the on-time limit
    d = line_plan()
    d["timing"]["brake_ms"] = 9000.0
    rc, lines = play(tmp_path, d, "[[step]]\nsites = [1]\nduration_ms = 2000.0\n")
    assert rc == 2 and refused(lines)["field"] == "step[0]"
    assert "would run 11 s" in capsys.readouterr().err
    # a duty cycle: the user's 10 % is kept whatever the plan says
    busy = "[[step]]\nsites = [1]\nduration_ms = 1000.0\ngap_ms = 1000.0\n" * 10
    rc, lines = play(tmp_path, line_plan(), busy, "--max-duty", "0.1")
    assert rc == 2 and refused(lines)["limit"] == 0.1
    assert "user: --max-duty 0.1" in capsys.readouterr().err


def test_a_user_value_above_a_limit_is_refused_in_its_own_units(tmp_path, capsys):
    rc, lines = play(tmp_path, line_plan(), PATTERN, "--watchdog-ms", "5000")
    err = capsys.readouterr().err
    assert rc == 2 and "--watchdog-ms 5000: a user setting can only lower a limit; " \
        "the limit is 250 ms (project default" in err and "watchdog_s" not in err
    assert refused(lines)["field"] == "--watchdog-ms"


def test_a_plan_from_another_model_is_refused(tmp_path, capsys):
    d = line_plan()
    d["best_frequency_hz"] = 150.0
    # timing of a 6 V motor: 6 / 4.025 V = 1.49, above this ERM's 4.5 / 4.025 = 1.118
    d["timing"].update(overdrive_level=1.49, nominal_voltage_V=4.025)
    rc, lines = play(tmp_path, d)
    assert rc == 2 and refused(lines)["field"] == "timing.overdrive_level"
    assert "beyond the level limit 1.118" in capsys.readouterr().err
    # timing computed for a motor with another speed law
    d["timing"].update(overdrive_level=1.1, nominal_voltage_V=3.0)
    rc, lines = play(tmp_path, d)
    assert rc == 2 and refused(lines)["field"] == "timing.nominal_voltage_V"
    assert "computed for another motor or model" in capsys.readouterr().err
    # a frequency this motor cannot reach
    d["best_frequency_hz"] = 180.0
    d["timing"].pop("nominal_voltage_V")
    rc, lines = play(tmp_path, d)
    assert rc == 2 and refused(lines)["field"] == "best_frequency_hz"


def test_a_pattern_needing_more_than_the_limit_is_refused_and_less_plays(tmp_path, capsys):
    d = line_plan()
    d["timing"].update(overdrive_ms=0.0, brake_ms=0.0)  # no kick: the steady level counts
    rc, lines = play(tmp_path, d, PATTERN, "--max-level", "0.8")
    assert rc == 2
    r = refused(lines)
    assert r["field"] == "step[0]" and r["limit"] == 0.8 and r["value"] > 0.8
    assert "pattern step[0] needs level" in capsys.readouterr().err
    half = PATTERN + "intensity = 0.5\n"
    rc, lines = play(tmp_path, d, half, "--max-level", "0.8")
    assert rc == 0 and "play" in [x["command"] for x in lines]


def test_a_limits_file_is_a_user_setting(tmp_path, capsys):
    limits = tmp_path / "limits.toml"
    limits.write_text("[limits]\nmax_level = 1.2\n")
    rc, lines = play(tmp_path, line_plan(), PATTERN, "--limits", str(limits))
    assert rc == 2 and refused(lines)["limit"] == 1.2
    assert "limits.toml: limits.max_level" in capsys.readouterr().err
    limits.write_text("[limits]\nmax_levle = 1.2\n")
    rc, lines = play(tmp_path, line_plan(), PATTERN, "--limits", str(limits))
    assert rc == 2 and "max_levle" in capsys.readouterr().err


def test_the_device_limit_refuses_before_the_first_frame_on_serial(tmp_path, capsys):
    d = line_plan()  # overdrive 1.5: the actuator allows 1.598 at 100 Hz, the device 1.364
    assert DEFAULT_MAX_LEVEL == round(4.5 / 3.3, 4)  # the emulator's default: rated, not 8x
    path = tmp_path / "plan.json"
    path.write_text(json.dumps(sealed(d)))
    pat = tmp_path / "p.toml"
    pat.write_text(PATTERN)
    with PtyEmulator(3) as emu:
        rc = main(["play", str(path), str(pat), "--device", f"serial:{emu.port}", "--out",
                   str(tmp_path / "session")])
        sent = {item.type for _, item in emu.array.received if isinstance(item, Frame)}
        assert emu.array.events == []
    assert rc == 2 and sent <= {Msg.QUERY_STATUS, Msg.STOP_ALL}
    assert "level limit 1.364 (device (its STATUS))" in capsys.readouterr().err
    (record,) = (tmp_path / "session").iterdir()
    r = refused([json.loads(x) for x in record.read_text().splitlines()])
    assert r["field"] == "timing.overdrive_level" and r["owner"] == "device (its STATUS)"


def test_status_carries_the_device_limits_and_the_shorter_status_still_decodes():
    from hardware.protocol import Status, decode_status, encode_status

    with_limits = Status(0, 250, (0.5, 0.0), 1.3636, 10000)
    back = decode_status(encode_status(with_limits))
    assert back.max_on_ms == 10000 and back.max_level == pytest.approx(1.3636, abs=1 / 4096)
    old = Status(0, 250, (0.5, 0.0))
    assert len(encode_status(old)) == 8 and decode_status(encode_status(old)) == old
    with pytest.raises(ValueError, match="does not match"):
        decode_status(encode_status(with_limits)[:-1])
