"""One ERM speed law: the solver and the run-time model call the same functions with the same
defaults (identity, not only equal numbers)."""

from __future__ import annotations

import ast
import subprocess
from pathlib import Path

import numpy as np
import pytest

import fem.motor
import motorlaw
import surrogate.runtime.rom
from fem.scene.unit_model import Motor
from motorlaw import DEFAULTS, SpeedLaw, VoltageSchedule

ROOT = Path(__file__).resolve().parents[2]


def test_solver_reexports_the_law_itself() -> None:
    for name in ("VoltageSchedule", "simulate_speed", "phase", "speed_rate",
                 "steady_frequency_hz", "target_speed_rad_s", "rise_time_s"):
        assert getattr(fem.motor, name) is getattr(motorlaw, name), name


def test_runtime_calls_the_same_law(monkeypatch) -> None:
    """The run-time speed is computed by motorlaw's exact solution: replacing it there changes
    what the run-time model returns."""
    calls = []
    original = motorlaw.erm.speed_and_phase

    def spy(law, schedule, t):
        calls.append(law)
        return original(law, schedule, t)

    monkeypatch.setattr(motorlaw.erm, "speed_and_phase", spy)
    t = np.linspace(0.0, 0.1, 11)
    surrogate.runtime.rom.motor_speed(t, np.full(t.size, 3.3), 0.02, 0.035, SpeedLaw())
    assert calls and isinstance(calls[0], SpeedLaw)
    assert surrogate.runtime.rom.held_speed_and_phase is motorlaw.held_speed_and_phase


def test_solver_and_runtime_speeds_agree_exactly() -> None:
    """The FE load's speed (fem.motor on an ERMMotor) and the run-time speed (held samples) are
    bit-identical on a schedule whose switches lie on the sample grid."""
    steps = ((0.0, 4.5), (0.01, 3.3), (0.05, -4.5), (0.07, 0.0), (0.1, 2.0))
    t = np.round(np.arange(0.0, 0.15 + 1e-12, 2.5e-4), 10)
    erm = fem.motor.ERMMotor(unbalance_kg_m=6e-9, tau_spinup_s=0.025, tau_spindown_s=0.05)
    fe = fem.motor.simulate_speed(erm, VoltageSchedule(steps), t)
    starts = np.array([s for s, _ in steps])
    volts = np.array([v for _, v in steps])[np.searchsorted(starts, t + 1e-12, "right") - 1]
    rt = surrogate.runtime.rom.motor_speed(t, volts, 0.025, 0.05, SpeedLaw())
    np.testing.assert_allclose(rt, fe, rtol=1e-12, atol=1e-9)
    assert fe[t > 0.07].min() == 0.0 and fe.max() > 600.0


def test_defaults_are_defined_once() -> None:
    law = SpeedLaw()
    erm = fem.motor.ERMMotor(unbalance_kg_m=1e-9)
    scene_motor = Motor()
    for key, value in DEFAULTS.items():
        assert getattr(law, key) == value and getattr(erm, key) == value
    assert scene_motor.rated_voltage_V == DEFAULTS["rated_voltage_V"]
    assert scene_motor.rated_frequency_hz == DEFAULTS["rated_frequency_hz"]
    assert scene_motor.start_voltage_V == DEFAULTS["start_voltage_V"]
    assert scene_motor.tau_spinup_s == pytest.approx(DEFAULTS["tau_spinup_s"], rel=1e-15)
    assert scene_motor.tau_spindown_s == pytest.approx(DEFAULTS["tau_spindown_s"], rel=1e-15)
    assert motorlaw.max_frequency_hz(law) == pytest.approx(120.0 * (4.5 - 0.4) / (3.3 - 0.4))


def test_no_copy_of_the_law_outside_motorlaw() -> None:
    """No module but motorlaw defines the speed recurrence or its default numbers."""
    offenders = []
    tracked = subprocess.run(["git", "ls-files", "*.py"], cwd=ROOT, capture_output=True,
                             text=True, check=False).stdout.split()
    # the sources in the tree (staged wheel sources and build output are copies by design)
    paths = [ROOT / p for p in tracked] if tracked else [
        p for p in ROOT.glob("*/**/*.py") if not {"src", "build"} & set(p.parts)]
    for path in paths:
        rel = path.relative_to(ROOT)
        if rel.parts[0] in ("motorlaw", "tests", ".venv", "studies", "bench") or "site-packages" \
                in rel.parts or not path.is_file():
            continue
        tree = ast.parse(path.read_text())
        for node in ast.walk(tree):
            if isinstance(node, ast.FunctionDef) and node.name in (
                    "target_omega", "target_speed_rad_s", "_interval_pieces", "speed_rate"):
                offenders.append(f"{rel}: def {node.name}")
            if isinstance(node, ast.ClassDef) and node.name == "MotorConstants":
                offenders.append(f"{rel}: class {node.name}")
    assert not offenders, offenders


def test_voltage_for_frequency_inverts_the_steady_law() -> None:
    law = SpeedLaw()
    for f in (50.0, 120.0, 160.0):
        v = motorlaw.voltage_for_frequency(law, f)
        assert motorlaw.steady_frequency_hz(law, v) == pytest.approx(f)


def test_bad_law_names_the_field() -> None:
    with pytest.raises(ValueError, match=r"SpeedLaw.max_voltage_V must be in \[rated_voltage_V"):
        SpeedLaw(max_voltage_V=3.0)
