"""The forward model reads the right model output for every measured point, interpolates the
profile, refuses points the model cannot predict (naming the row), and takes a model with a
normal-component output when one is given."""

from __future__ import annotations

import numpy as np
import pytest

from calibration.forward import ForwardModel
from calibration.measurement import MeasurementError, measurement_from_rows
from calibration.synthetic import REFERENCE_DESIGNS
from surrogate.runtime import load_predictor

DESIGN = REFERENCE_DESIGNS["bare motor"]
TISSUE = {"skin_E_kPa": 60.0, "fat_thickness_mm": 10.0, "tissue_loss_factor": 0.25}
FIT = ["skin_E_kPa", "tissue_loss_factor"]


@pytest.fixture(scope="module")
def predictor():
    return load_predictor("models/nn-default")


def _row(ref, d, f, comp="magnitude"):
    return {"reference": ref, "distance_mm": d, "frequency_hz": f, "quantity": "displacement",
            "unit": "um", "statistic": "peak", "component": comp, "value": 1.0,
            "uncertainty": "5%"}


def _truth(predictor, f):
    X = {k: np.array([v]) for k, v in {**DESIGN, **TISSUE}.items()}
    X["frequency_hz"] = np.array([f])
    return predictor.predict(X)


def test_points_read_centre_profile_and_interpolate(predictor):
    rows = [_row("centre", 0, 150), _row("edge", 4, 150), _row("edge", 4.5, 150),
            _row("centre", 3.5 + 6, 200), _row("edge", 20, 200)]
    m = measurement_from_rows(rows, design=DESIGN)
    fixed = {**DESIGN, "fat_thickness_mm": TISSUE["fat_thickness_mm"]}
    fwd = ForwardModel(predictor, m, FIT, fixed)
    mean, std = fwd.predict(np.array([[TISSUE[n] for n in FIT]]))
    a, b = _truth(predictor, 150.0), _truth(predictor, 200.0)
    um = np.exp(mean[0]) * 1e6
    assert um[0] == pytest.approx(a["center_amplitude_um"][0], rel=1e-4)
    assert um[1] == pytest.approx(a["profile_um"][0][4], rel=1e-4)
    assert um[2] == pytest.approx(np.sqrt(a["profile_um"][0][4] * a["profile_um"][0][5]),
                                  rel=1e-4)  # log-linear halfway
    assert um[3] == pytest.approx(b["profile_um"][0][6], rel=1e-4)  # 9.5 mm from the centre
    assert um[4] == pytest.approx(b["profile_um"][0][20], rel=1e-4)
    raw = _truth(predictor.uncalibrated(), 150.0)  # the likelihood widens the raw spread
    assert std[0, 0] == pytest.approx(raw["center_amplitude_um_log_std"][0], rel=1e-4)
    # many parameter vectors at once give the same as one by one
    theta = np.array([[40.0, 0.2], [90.0, 0.4]])
    both, _ = fwd.predict(theta)
    assert np.allclose(both[1], fwd.predict(theta[1:])[0][0])


def test_error_correlation_structure(predictor):
    m = measurement_from_rows([_row("centre", 0, 150), _row("edge", 0, 150),
                               _row("edge", 10, 150), _row("edge", 10, 210)], design=DESIGN)
    fwd = ForwardModel(predictor, m, FIT, {**DESIGN, "fat_thickness_mm": 10.0})
    C = fwd.error_correlation(20.0, 60.0)
    assert np.allclose(np.diag(C), 1.0) and np.allclose(C, C.T)
    assert C[0, 1] == 0.0  # face and profile independent
    assert C[1, 2] == pytest.approx(np.exp(-0.5))
    assert C[2, 3] == pytest.approx(np.exp(-1.0))
    assert np.all(np.linalg.eigvalsh(C) > 0)


def test_points_the_model_cannot_predict_are_named(predictor):
    rows = [_row("centre", 2.0, 150), _row("edge", 25, 150), _row("edge", 3, 300),
            _row("edge", 3, 150, comp="normal"), _row("edge", 3, 150)]
    m = measurement_from_rows(rows, design=DESIGN)
    with pytest.raises(MeasurementError) as err:
        ForwardModel(predictor, m, FIT, {**DESIGN, "fat_thickness_mm": 10.0})
    text = str(err.value)
    assert "4 row(s)" in text
    assert "row 1, column distance_mm: 2 mm is outside" in text and "edge radius 3.5" in text
    assert "row 2, column distance_mm" in text and "[0, 20] mm from the edge" in text
    assert "row 3, column frequency_hz: 300 Hz is outside the model's range [100, 250]" in text
    assert "row 4, column component" in text and "predicts no normal component" in text


class _NormalModel:
    """The shipped predictor plus normal-component outputs (half the magnitude), as a model
    trained on |U_z| would return them."""

    def __init__(self, inner):
        self.inner = inner
        self.card, self.input_names = inner.card, inner.input_names
        self.input_ranges, self.specs = inner.input_ranges, inner.specs
        self.profile_distance_mm = inner.profile_distance_mm

    def features(self, X, **kw):
        return self.inner.features(X, **kw)

    def predict(self, X, **kw):
        out = self.inner.predict(X, **kw)
        out["center_normal_um"] = 0.5 * out["center_amplitude_um"]
        out["center_normal_um_log_std"] = out["center_amplitude_um_log_std"]
        out["profile_normal_um"] = 0.5 * out["profile_um"]
        out["profile_normal_um_log_std"] = out["profile_um_log_std"]
        return out


def test_a_model_with_a_normal_output_serves_normal_points(predictor):
    rows = [_row("edge", 5, 150, comp="normal"), _row("edge", 5, 150),
            _row("centre", 0, 150, comp="normal")]
    m = measurement_from_rows(rows, design=DESIGN)
    fwd = ForwardModel(_NormalModel(predictor), m, FIT, {**DESIGN, "fat_thickness_mm": 10.0})
    mean, _ = fwd.predict(np.array([[TISSUE[n] for n in FIT]]))
    assert mean[0, 0] == pytest.approx(mean[0, 1] + np.log(0.5))
    a = _truth(predictor, 150.0)
    assert np.exp(mean[0, 2]) * 1e6 == pytest.approx(0.5 * a["center_amplitude_um"][0])
