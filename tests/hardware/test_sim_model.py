"""The simulated array renders envelopes with the plan's transient model itself."""

from __future__ import annotations

import numpy as np
import pytest

from hardware.protocol import Segment
from hardware.sim import envelopes, model_envelopes
from planner.timing import envelope_timing, rom_response, voltage_for_frequency
from surrogate.runtime.rom import load_envelope_model
from tests.surrogate.rom_cases import DESIGN, SHIPPED

MODEL = SHIPPED


@pytest.fixture(scope="module")
def timing():
    model = load_envelope_model(MODEL)
    nominal = voltage_for_frequency(model.motor, 150.0)
    t = envelope_timing(rom_response(model, DESIGN), nominal, model.motor.max_voltage_V, 0.1)
    return {**t.to_dict(), "model": str(MODEL), "design": dict(DESIGN)}


def test_sim_envelope_is_the_models_envelope_at_the_channels_voltage(timing):
    segs = [Segment(0, 400, 0, 1.0), Segment(0, 200, 1, 0.5)]
    t, e = model_envelopes(segs, 3, timing, 400)
    model = load_envelope_model(MODEL)
    for ch, (dur, level) in enumerate([(400, 1.0), (200, 0.5)]):
        volts = np.where(t < dur, level * timing["nominal_voltage_V"], 0.0)
        ref = model.simulate(1e-3 * t, volts, DESIGN)["center_envelope_um"]
        np.testing.assert_allclose(e[ch], ref / timing["steady_envelope_um"], rtol=1e-12)
    assert e[0, np.searchsorted(t, 399.0)] == pytest.approx(1.0, abs=0.02)  # nominal steady
    assert np.all(e[2] == 0.0)  # an idle channel


def test_the_brake_pulse_shortens_the_tail(timing):
    on = Segment(0, 300, 0, 1.0)
    brake = Segment(300, round(timing["brake_ms"]), 0, -timing["overdrive_level"])
    t, braked = model_envelopes([on, brake], 1, timing, 300 + round(timing["brake_ms"]))
    _, coast = model_envelopes([on], 1, timing, 300 + round(timing["brake_ms"]))
    after = (t > 300) & (t < 340)
    assert np.all(braked[0, after] <= coast[0, after] + 1e-12)
    assert braked[0, after].sum() < coast[0, after].sum()


def test_a_plan_without_the_models_design_falls_back_to_first_order(timing):
    old = {k: v for k, v in timing.items() if k != "design"}
    assert model_envelopes([Segment(0, 100, 0, 1.0)], 1, old, 100) is None
    t, e = envelopes([Segment(0, 100, 0, 1.0)], 1, old, 100)
    assert e.shape == (1, t.size)
