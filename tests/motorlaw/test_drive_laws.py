"""The drive-law registry (motorlaw/drive.py) and the LRA's resonant drive (motorlaw/lra.py):
registered by actuator kind, the ERM's law answering as before, the LRA's resonator, band,
ring-up, ring-down and reverse-phase brake against their closed forms, and bad parameters
named."""

from __future__ import annotations

import math

import numpy as np
import pytest

import motorlaw
from motorlaw import DRIVES, ResonantDrive, SpeedLaw, drive_law
from motorlaw.lra import DEFAULTS, RANGES

LRA = ResonantDrive()
F0, Q = DEFAULTS["resonance_hz"], DEFAULTS["quality_factor"]
V_R, V_MAX = DEFAULTS["rated_voltage_V"], DEFAULTS["max_voltage_V"]
TAU = Q / (math.pi * F0)


def test_registry_is_keyed_by_the_actuator_kind():
    assert DRIVES == {"unit": SpeedLaw, "lra": ResonantDrive}
    assert drive_law("unit") == SpeedLaw() and drive_law("lra") == LRA
    assert drive_law("lra", {"quality_factor": 5.0}).quality_factor == 5.0
    with pytest.raises(ValueError, match=r"'voice_coil' has no drive law.*\['lra', 'unit'\]"):
        drive_law("voice_coil")
    with pytest.raises(ValueError, match=r"lra\.mass: unknown drive-law parameter"):
        drive_law("lra", {"mass": 1.0})
    assert SpeedLaw().overdrive and SpeedLaw().brake and not SpeedLaw().carrier
    assert LRA.overdrive and LRA.brake and LRA.carrier


def test_the_erm_answers_with_its_one_speed_law():
    law = SpeedLaw()
    assert law.nominal_voltage_V(150.0) == motorlaw.voltage_for_frequency(law, 150.0)
    assert law.band_hz() == (0.0, motorlaw.max_frequency_hz(law))
    assert law.reach_text() == "at most 169.65 Hz"
    t = np.linspace(0.0, 0.2, 81)
    v = np.where(t < 0.1, 3.3, -4.5)
    omega, _ = motorlaw.held_speed_and_phase(law, t, v)
    assert np.array_equal(law.drive_state(t, v, 120.0), omega / (2 * math.pi))
    assert law.force_ratio(np.array([60.0, 120.0]), 120.0) == pytest.approx([0.25, 1.0])


def test_lra_resonator_and_band():
    assert LRA.response(F0) == pytest.approx(1.0)
    assert LRA.response(100 * F0) == pytest.approx(1 / Q, rel=1e-3)  # a free mass
    r = 0.9
    assert LRA.response(r * F0) == pytest.approx(r**2 / abs(1 - r**2 + 1j * r / Q) / Q)
    assert LRA.nominal_voltage_V(F0) == pytest.approx(V_R)
    lo, hi = LRA.band_hz()
    assert lo < F0 < hi and LRA.response([lo, hi]) == pytest.approx([V_R / V_MAX] * 2)
    assert LRA.nominal_voltage_V(lo) == pytest.approx(V_MAX)
    assert LRA.tau_s == pytest.approx(TAU)
    low_q = ResonantDrive(quality_factor=1.0)  # the free-mass force is reached: no top
    assert low_q.band_hz()[1] == math.inf
    assert low_q.response(low_q.band_hz()[0]) == pytest.approx(V_R / V_MAX)


def test_lra_rings_up_and_down_with_q_over_pi_f0_and_brakes_to_rest():
    t = np.arange(0.0, 0.3, 1e-4)
    on = LRA.drive_state(t, np.full(t.size, V_R), F0)
    assert on == pytest.approx(1 - np.exp(-t / TAU), abs=1e-12)  # ring-up to the rated force
    off_at = 0.2
    v = np.where(t < off_at, V_R, 0.0)
    a0 = 1 - math.exp(-off_at / TAU)
    after = t >= off_at
    free = LRA.drive_state(t, v, F0)[after]
    assert free == pytest.approx(a0 * np.exp(-(t[after] - off_at) / TAU), abs=1e-12)
    braked = LRA.drive_state(t, np.where(t < off_at, V_R, -V_MAX), F0)[after]
    stop = TAU * math.log((a0 + V_MAX / V_R) / (V_MAX / V_R))  # reversed phase: reaches 0
    s = t[after] - off_at
    assert np.all(braked[s < stop - 1e-4] > 0) and np.all(braked[s > stop + 1e-4] == 0.0)
    assert np.array_equal(LRA.force_ratio(on, F0), on)  # the state is the force envelope


def test_lra_off_resonance_reaches_the_rated_force_at_its_nominal_voltage():
    f = 0.5 * (F0 + LRA.band_hz()[1])
    t = np.arange(0.0, 0.4, 1e-3)
    state = LRA.drive_state(t, np.full(t.size, LRA.nominal_voltage_V(f)), f)
    assert state[-1] == pytest.approx(1.0, rel=1e-6)
    with pytest.raises(ValueError, match=r"frequency_hz = 200: the LRA reaches 166\.33 to "
                       r"186\.22 Hz within its 3 V limit"):
        LRA.drive_state(t, np.full(t.size, V_R), 200.0)


@pytest.mark.parametrize("name", sorted(RANGES))
def test_lra_parameters_out_of_range_are_named(name):
    lo, hi = RANGES[name]
    with pytest.raises(ValueError, match=rf"lra\.{name} = .*allowed \[{lo:g}, {hi:g}\]"):
        ResonantDrive(**{name: 2 * hi})
    with pytest.raises(ValueError, match=rf"lra\.{name}: 'x' is not a number"):
        ResonantDrive(**{name: "x"})


def test_lra_max_voltage_below_rated_is_refused():
    with pytest.raises(ValueError, match=r"lra\.max_voltage_V = 1\.5: allowed \[rated_voltage_V"):
        ResonantDrive(rated_voltage_V=2.0, max_voltage_V=1.5)
