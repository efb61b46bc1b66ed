"""The detection-threshold curve and the perceptual criterion, on cases checked by hand."""

from __future__ import annotations

import math

import numpy as np
import pytest

from planner.layout import LayoutError, layout_from_dict
from planner.optimise import PITCH_TOL_MM, is_felt, smallest_pitch
from planner.threshold import VERRILLO_1966_FOREARM, ThresholdCurve
from tests.planner.test_crosstalk_and_pitch import EDGE, R0, C, L, exponential_unit


def test_log_log_interpolation_is_exact_for_a_power_law():
    # T = 2 um (f / 100 Hz)^-2 is a straight line in log-log: exact between the nodes
    f = (50.0, 100.0, 400.0)
    curve = ThresholdCurve(f, tuple(2.0 * (x / 100.0) ** -2 for x in f), "power law")
    for x in (50.0, 70.0, 100.0, 141.0, 300.0, 400.0):
        assert curve(x) == pytest.approx(2.0 * (x / 100.0) ** -2, rel=1e-12)


def test_the_curve_is_not_extrapolated():
    with pytest.raises(ValueError, match="outside the threshold curve's range"):
        VERRILLO_1966_FOREARM(60.0)
    with pytest.raises(ValueError, match="strictly increasing"):
        ThresholdCurve((100.0, 100.0), (1.0, 1.0), "x")


def test_verrillo_shape_minimum_slopes_and_area_law():
    v = VERRILLO_1966_FOREARM
    # -10 dB re 1 um at the 220 Hz minimum; -12 dB per octave below, +9 dB per octave above
    assert 20 * math.log10(v(220.0)) == pytest.approx(-10.0)
    assert 20 * math.log10(v(110.0) / v(220.0)) == pytest.approx(12.0)
    assert 20 * math.log10(v(440.0) / v(220.0)) == pytest.approx(9.0)
    assert v(220.0) < min(v(150.0), v(300.0))
    # half the contact area: 3 dB higher
    half = v.at_area(1.45)
    assert 20 * math.log10(half(220.0) / v(220.0)) == pytest.approx(3.0)


def perceptual(rows: int, cols: int, superposition: str, level: float = 1.0, **extra):
    return layout_from_dict({
        "array": {"rows": rows, "cols": cols, "min_pitch_mm": 1.0, "max_pitch_mm": 200.0},
        "drive": {"frequencies_hz": [200.0]},
        "criterion": {"kind": "perceptual", "superposition": superposition,
                      "drive_level": level, "threshold_hz": [100.0, 300.0],
                      "threshold_um": [0.5, 0.5], "threshold_source": "flat test curve",
                      **extra},
        "design": [{"name": "x"}]})


def test_perceptual_pitch_by_hand():
    # one neighbour: level C R0 exp(-(p - EDGE) / L) = T  ->  p = EDGE + L ln(level C R0 / T)
    for level in (1.0, 0.5):
        req = perceptual(1, 2, "worst", level)
        p = smallest_pitch(exponential_unit(), req, 200.0)
        assert p == pytest.approx(EDGE + L * math.log(level * C * R0 / 0.5), abs=PITCH_TOL_MM)
    # a row of three, powers add at the middle site
    p = smallest_pitch(exponential_unit(), perceptual(1, 3, "incoherent"), 200.0)
    assert p == pytest.approx(EDGE + L * math.log(math.sqrt(2) * C * R0 / 0.5), abs=PITCH_TOL_MM)


def test_a_unit_below_the_threshold_is_not_felt():
    req = perceptual(1, 2, "worst", level=0.04)  # 0.04 x 10 um = 0.4 um < 0.5 um
    assert not is_felt(C, req, 200.0)
    assert is_felt(C, perceptual(1, 2, "worst", level=0.06), 200.0)


@pytest.mark.parametrize("criterion, field", [
    ({"kind": "loud"}, "criterion.kind"),
    ({"kind": "perceptual", "threshold_hz": [100.0, 200.0], "threshold_um": [1.0, 1.0]},
     "criterion.threshold_source"),
    ({"kind": "perceptual", "threshold_hz": [200.0, 100.0], "threshold_um": [1.0, 1.0],
      "threshold_source": "x"}, "criterion.threshold_hz"),
    ({"kind": "ratio", "contactor_area_cm2": 1.0}, "criterion.contactor_area_cm2"),
    ({"kind": "perceptual", "drive_level": 0.0}, "criterion.drive_level"),
    ({"kind": "perceptual", "threshold_hz": [150.0, 300.0], "threshold_um": [1.0, 1.0],
      "threshold_source": "x"}, "drive.frequencies_hz"),
])
def test_bad_criteria_name_the_field(criterion, field):
    with pytest.raises(LayoutError) as info:
        layout_from_dict({"array": {"rows": 1, "cols": 2}, "drive": {"frequencies_hz": [120.0]},
                          "criterion": criterion, "design": [{"name": "x"}]})
    assert info.value.field == field


def test_the_default_curve_and_its_area_rescaling_are_used():
    req = layout_from_dict({"array": {"rows": 1, "cols": 2}, "criterion": {
        "kind": "perceptual", "contactor_area_cm2": 0.725}, "design": [{"name": "x"}]})
    t = req.criterion.threshold
    assert t.contactor_area_cm2 == 0.725 and "Verrillo 1966" in t.source
    np.testing.assert_allclose(t(120.0) / VERRILLO_1966_FOREARM(120.0), 10 ** (6 / 20))
