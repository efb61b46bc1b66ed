"""The planner's timing asks the actuator's drive law: an LRA's rise and decay from its
ring-up time constant Q / (pi f0), its overdrive kick and reverse-phase brake in closed form;
its reach refused with the band; the ERM's envelope model refuses to time an LRA."""

from __future__ import annotations

import math
from pathlib import Path
from types import SimpleNamespace as NS

import pytest

from fieldspec import FieldError
from motorlaw import ResonantDrive
from planner import plan_layout
from planner.layout import LayoutError, layout_from_dict
from planner.timing import TIMING_KEYS, envelope_timing, law_response, plan_timing

ROOT = Path(__file__).resolve().parents[2]
LRA = ResonantDrive()
F0, TAU, V_R, V_MAX = LRA.resonance_hz, LRA.tau_s, LRA.rated_voltage_V, LRA.max_voltage_V
DT = 2.5e-4
SITE = {"skin_E_kPa": 49.0, "fat_thickness_mm": 14.0, "tissue_loss_factor": 0.3}
INPUTS = {"orientation": "reverse", "attachment": "glued", "n_rings": 2,
          "ring_1_E_kPa": 150.0, "ring_2_E_kPa": 150.0, "ring_3_E_kPa": 150.0,
          "ring_density_kg_m3": 1070.0, "ring_nu": 0.47, "ring_loss_factor": 0.08}


def _request(model: str, actuator: str = "lra") -> NS:
    return NS(timing=NS(model=model, actuator=actuator, tau_spinup_ms=20.0,
                        tau_spindown_ms=35.0, isi_fraction=0.1),
              criterion=NS(kind="ratio"), allow_extrapolation=False, site=SITE)


def test_lra_timing_from_its_ring_up_time_constant():
    t = envelope_timing(law_response(LRA, F0, 5.0), V_R, V_MAX, 0.1, dt_s=DT)
    ms, k = 1e3 * TAU, V_MAX / V_R
    assert t.steady_envelope_um == pytest.approx(5.0, rel=1e-6)
    assert t.rise_ms == pytest.approx(ms * math.log(9), abs=0.3)  # 10-90 %: tau ln 9
    assert t.decay_ms == pytest.approx(ms * math.log(9), abs=0.3)
    assert t.overdrive_ms == pytest.approx(ms * math.log(k / (k - 1)), abs=0.3)  # to nominal
    assert t.brake_ms == pytest.approx(ms * math.log((1 + k) / k), abs=0.3)  # reversed phase
    assert t.min_isi_unbraked_ms == pytest.approx(ms * math.log(10), abs=0.3)
    assert t.min_isi_ms < t.min_isi_unbraked_ms and t.overdrive_level == pytest.approx(k)


def test_plan_timing_of_an_lra_without_an_envelope_model():
    out = plan_timing(_request(""), NS(inputs=INPUTS, frequency_hz=F0, center_um=5.0))
    assert out.get("unavailable") is None and out["actuator"] == "lra"
    assert out["rise_ms"] == pytest.approx(1e3 * TAU * math.log(9), abs=0.6)
    assert out["nominal_voltage_V"] == pytest.approx(V_R) and out["brake_voltage_V"] == -V_MAX
    assert out["drive_law"] == LRA.params()
    lo, hi = LRA.band_hz()
    assert (out["min_frequency_hz"], out["max_frequency_hz"]) == (round(lo, 4), round(hi, 4))
    far = plan_timing(_request(""), NS(inputs=INPUTS, frequency_hz=200.0, center_um=5.0))
    assert all(far[k] is None for k in TIMING_KEYS)
    assert "200 Hz needs" in far["unavailable"]
    assert "above the LRA's 3 V limit (166.33 to 186.22 Hz)" in far["unavailable"]


def test_the_erm_envelope_model_refuses_to_time_an_lra():
    model = str(ROOT / "models" / "rom-default")
    out = plan_timing(_request(model), NS(inputs=INPUTS, frequency_hz=F0, center_um=5.0))
    assert all(out[k] is None for k in TIMING_KEYS)
    assert out["unavailable"].startswith("actuator: 'lra': this envelope model was trained "
                                         "for the actuator 'unit' (coin ERM) only")
    erm = plan_timing(_request(model, "unit"), NS(inputs=INPUTS, frequency_hz=150.0,
                                                  center_um=5.0))
    assert erm.get("unavailable") is None and erm["actuator"] == "unit"
    assert erm["drive_law"]["rated_voltage_V"] == 3.3


def test_layout_timing_actuator_is_a_registered_drive_law():
    base = {"model": {"path": "models/nn-default"}, "array": {"rows": 2, "cols": 2},
            "site": SITE, "drive": {"frequencies_hz": [175.0]},
            "design": [{"name": "a", **INPUTS}]}
    req = layout_from_dict({**base, "timing": {"actuator": "lra", "model": ""}})
    assert (req.timing.actuator, req.timing.model) == ("lra", "")
    assert layout_from_dict(base).timing.actuator == "unit"
    with pytest.raises(LayoutError) as err:
        layout_from_dict({**base, "timing": {"actuator": "voice_coil"}})
    assert isinstance(err.value, FieldError) and err.value.field == "timing.actuator"
    assert "'lra'" in str(err.value) and "'unit'" in str(err.value)


def test_planning_an_lra_on_the_erms_harmonic_model_is_refused():
    base = {"model": {"path": str(ROOT / "models" / "nn-default")},
            "array": {"rows": 2, "cols": 2}, "site": SITE,
            "drive": {"frequencies_hz": [175.0]}, "design": [{"name": "a", **INPUTS}]}
    for timing in ({"actuator": "lra", "model": ""}, {"actuator": "lra"}):
        with pytest.raises(LayoutError) as err:
            plan_layout(layout_from_dict({**base, "timing": timing}))
        assert err.value.field == "timing.actuator"
        assert "predicts the amplitudes of the actuator 'unit' (coin ERM)" in str(err.value)


def test_the_erm_timed_by_its_law_alone_takes_the_requests_time_constants():
    req = _request("", "unit")
    req.timing.tau_spinup_ms = 10.0
    out = plan_timing(req, NS(inputs=INPUTS, frequency_hz=120.0, center_um=5.0))
    assert out["drive_law"]["tau_spinup_s"] == 0.01 and out["actuator"] == "unit"
    # quasi-static: the force m e omega^2 rises with the square of the speed (tau 10 ms)
    square = math.log(1 / (1 - math.sqrt(0.1))) - math.log(1 / (1 - math.sqrt(0.9)))
    assert out["rise_ms"] == pytest.approx(-10.0 * square, abs=0.6)
