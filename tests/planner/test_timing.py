"""Envelope timing: analytic answers on a first-order system, and the shipped ROM."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import motorlaw
from motorlaw import SpeedLaw
from planner.timing import (
    TIMING_KEYS,
    TimingError,
    envelope_timing,
    rom_response,
    voltage_for_frequency,
)
from surrogate.runtime.rom import load_envelope_model

ROOT = Path(__file__).resolve().parents[2]
TAU, GAIN, V_NOM, V_MAX, DT = 0.02, 2.0, 3.0, 4.5, 2.5e-4  # s, um/V, V, V, s


def first_order(t: np.ndarray, volts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """x' = (GAIN V - x) / TAU, exact per step, held at >= 0 (a motor that brakes to rest
    and never reverses); envelope = speed = x."""
    out = [0.0]
    x = 0.0
    for k in range(t.size - 1):
        target = GAIN * volts[k]
        x = max(target + (x - target) * math.exp(-(t[k + 1] - t[k]) / TAU), 0.0)
        out.append(x)
    x = np.array(out)
    return x, x


@pytest.fixture(scope="module")
def timing():
    return envelope_timing(first_order, V_NOM, V_MAX, 0.1, dt_s=DT)


def test_rise_and_decay_are_tau_ln9(timing):
    assert timing.rise_ms == pytest.approx(1e3 * TAU * math.log(9), abs=1e-3)
    assert timing.decay_ms == pytest.approx(1e3 * TAU * math.log(9), abs=1e-3)
    assert timing.steady_envelope_um == pytest.approx(GAIN * V_NOM, rel=1e-6)


def test_overdrive_ends_at_the_nominal_speed_and_shortens_the_rise(timing):
    # V_MAX kick until GAIN V_MAX (1 - e^{-t/TAU}) = GAIN V_NOM
    assert timing.overdrive_ms == pytest.approx(-1e3 * TAU * math.log(1 - V_NOM / V_MAX),
                                                abs=1e3 * DT)
    assert timing.overdrive_level == pytest.approx(V_MAX / V_NOM)
    assert timing.rise_overdrive_ms == pytest.approx(
        -1e3 * TAU * math.log(1 - 0.9 * V_NOM / V_MAX), abs=1e3 * DT)
    assert timing.rise_overdrive_ms < timing.t90_ms == pytest.approx(1e3 * TAU * math.log(10),
                                                                     abs=1e-3)


def test_brake_and_inter_stimulus_interval(timing):
    s, r = GAIN * V_NOM, GAIN * V_MAX
    # reverse drive: x = -r + (s + r) e^{-t/TAU} reaches 0 at TAU ln(1 + s / r)
    assert timing.brake_ms == pytest.approx(1e3 * TAU * math.log(1 + s / r), abs=1e3 * DT)
    # residual below 10 % of steady: TAU ln 10 coasting; TAU ln((s + r) / (0.1 s + r)) braked
    assert timing.min_isi_unbraked_ms == pytest.approx(1e3 * TAU * math.log(10), abs=1e-3)
    assert timing.min_isi_ms == pytest.approx(1e3 * TAU * math.log((s + r) / (0.1 * s + r)),
                                              abs=1e-3)
    assert set(TIMING_KEYS) <= set(timing.to_dict())


def test_without_headroom_there_is_no_overdrive():
    t = envelope_timing(first_order, V_MAX, V_MAX, 0.1, dt_s=DT)
    assert t.overdrive_ms == 0.0 and t.overdrive_level == 1.0
    assert t.rise_overdrive_ms == pytest.approx(t.t90_ms)


def test_voltage_for_frequency_inverts_the_motor_law_and_refuses_beyond_the_limit():
    m = SpeedLaw()
    v = voltage_for_frequency(m, 100.0)
    assert motorlaw.target_speed_rad_s(m, v) == pytest.approx(2 * math.pi * 100.0)
    assert voltage_for_frequency(m, 120.0) == pytest.approx(3.3)
    with pytest.raises(TimingError, match=r"above the motor's 4\.5 V limit \(at most 169\.65 Hz\)"):
        voltage_for_frequency(m, 180.0)


def test_the_shipped_rom_overdrive_and_brake_shorten_its_timing():
    model = load_envelope_model(ROOT / "models" / "rom-default")
    design = {"orientation": "reverse", "attachment": "pogo", "n_rings": 3,
              "ring_1_E_kPa": 150.0, "ring_2_E_kPa": 150.0, "ring_3_E_kPa": 150.0,
              "ring_density_kg_m3": 1070.0, "ring_nu": 0.47, "ring_loss_factor": 0.08,
              "skin_E_kPa": 49.0, "fat_thickness_mm": 14.0, "tissue_loss_factor": 0.3,
              "tau_spinup_ms": 20.0, "tau_spindown_ms": 35.0}
    t = envelope_timing(rom_response(model, design), 3.3, 4.5, 0.1, dt_s=5e-4)
    assert t.rise_overdrive_ms < t.t90_ms
    assert t.min_isi_ms < t.min_isi_unbraked_ms
    assert 0 < t.brake_ms < t.min_isi_ms
    # the motor part is exact: the kick at 4.5 V reaches 120 rev/s at tau_up ln(w_max / (w_max -
    # w_nom)), the brake at -4.5 V stops it at tau ln(1 + w_nom / w_max), tau = tau_up as the
    # reverse target is faster than the running speed (fem.motor's law)
    w_nom, w_max = 2.9, 4.1
    assert t.overdrive_ms == pytest.approx(20.0 * math.log(w_max / (w_max - w_nom)), abs=0.5)
    assert t.brake_ms == pytest.approx(20.0 * math.log(1 + w_nom / w_max), abs=0.5)


def test_plan_timing_above_the_motors_reach_says_so_with_the_number():
    from types import SimpleNamespace as NS

    from planner.timing import plan_timing

    req = NS(timing=NS(model=str(ROOT / "models" / "rom-default"), tau_spinup_ms=20.0,
                       tau_spindown_ms=35.0, isi_fraction=0.1),
             criterion=NS(kind="ratio"), allow_extrapolation=False,
             site={"skin_E_kPa": 49.0, "fat_thickness_mm": 14.0, "tissue_loss_factor": 0.3})
    inputs = {"orientation": "reverse", "attachment": "glued", "n_rings": 2,
              "ring_1_E_kPa": 150.0, "ring_2_E_kPa": 150.0, "ring_3_E_kPa": 150.0,
              "ring_density_kg_m3": 1070.0, "ring_nu": 0.47, "ring_loss_factor": 0.08}
    out = plan_timing(req, NS(inputs=inputs, frequency_hz=200.0, center_um=5.0))
    assert all(out[k] is None for k in TIMING_KEYS)
    why = out["unavailable"]
    assert "200 Hz needs 5.233 V" in why and "at most 169.65 Hz" in why
    assert out["max_frequency_hz"] == pytest.approx(120.0 * 4.1 / 2.9, abs=1e-3)
    ok = plan_timing(req, NS(inputs=inputs, frequency_hz=160.0, center_um=5.0))
    assert ok.get("unavailable") is None and ok["rise_ms"] > 0 and ok["brake_ms"] > 0
    assert ok["design"]["n_rings"] == 2 and ok["design"]["tau_spinup_ms"] == 20.0
