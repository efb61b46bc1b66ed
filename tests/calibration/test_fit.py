"""The Bayesian fit: it recovers known tissue from measurements made by the surrogate itself
and by the FE solver (cached subjects of bench/calibration/subjects.py), says what the data do
not determine, is reproducible, and its document conforms to its schema and reads back."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest

from calibration import calibrate, calibration_document, read_calibration
from calibration.document import CalibrationFileError
from calibration.priors import PriorError, priors_for
from calibration.synthetic import (
    REFERENCE_DESIGNS,
    subject_from_predictor,
    synthetic_measurement,
)
from hapticrom.documents import schema
from surrogate.runtime import load_predictor

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "hapticrom"))
from schema_check import problems

FIT = ["skin_E_kPa", "fat_thickness_mm", "tissue_loss_factor"]
FAST = {"walkers": 24, "steps": 400, "burn": 150, "n_init": 1024}
CACHE = Path("bench/calibration/data/calibration-subjects.json")


@pytest.fixture(scope="module")
def predictor():
    return load_predictor("models/nn-default")


def _z(cal, truth):
    s = cal.summary()
    return {n: abs(s[n]["mean"] - truth[n]) / s[n]["sd"] for n in s}, s


@pytest.mark.parametrize("case", [
    ({"skin_E_kPa": 35.0, "fat_thickness_mm": 6.0, "tissue_loss_factor": 0.2}, "bare motor"),
    ({"skin_E_kPa": 90.0, "fat_thickness_mm": 15.0, "tissue_loss_factor": 0.4}, "A-D double"),
])
def test_recovers_tissue_measured_by_the_surrogate(predictor, case):
    truth, design = case
    subject = subject_from_predictor(predictor, truth, REFERENCE_DESIGNS[design],
                                     [110.0, 170.0, 230.0])
    m = synthetic_measurement(subject, rel_noise=0.05, n_points=10,
                              rng=np.random.default_rng(3), sensor="ldv")
    cal = calibrate(predictor, m, FIT, seed=1, std_factor=1.0, **FAST)
    z, s = _z(cal, truth)
    assert all(v < 3.0 for v in z.values()), (z, s)
    assert s["skin_E_kPa"]["identifiable"] and s["tissue_loss_factor"]["identifiable"]
    assert s["skin_E_kPa"]["ci95"][1] - s["skin_E_kPa"]["ci95"][0] < 50.0


def test_recovers_tissue_measured_by_fe(predictor):
    subjects = json.loads(CACHE.read_text())["subjects"]
    for subject in (subjects[7], subjects[13]):  # three frequencies each
        m = synthetic_measurement(subject, rel_noise=0.05, n_points=10,
                                  rng=np.random.default_rng(subject["id"]))
        cal = calibrate(predictor, m, FIT, seed=0, **FAST)
        z, s = _z(cal, subject["truth"])
        assert all(v < 3.0 for v in z.values()), (subject["id"], z, s)


def test_one_point_determines_little_and_says_so(predictor):
    subject = subject_from_predictor(predictor, {"skin_E_kPa": 50.0, "fat_thickness_mm": 12.0,
                                                 "tissue_loss_factor": 0.3},
                                     REFERENCE_DESIGNS["bare motor"], [150.0])
    m = synthetic_measurement(subject, rel_noise=0.10, n_points=1,
                              rng=np.random.default_rng(0))
    cal = calibrate(predictor, m, FIT, seed=0, **FAST)
    doc = calibration_document(cal, model_path="models/nn-default", tissue_names=FIT)
    assert "fat_thickness_mm" in doc["unidentifiable"]
    assert "not determined" in doc["statement"]
    assert doc["posterior"]["fat_thickness_mm"]["width_ratio"] > 0.8


def test_reproducible_document_schema_and_read_back(predictor, tmp_path):
    subject = subject_from_predictor(predictor, {"skin_E_kPa": 70.0, "fat_thickness_mm": 9.0,
                                                 "tissue_loss_factor": 0.25},
                                     REFERENCE_DESIGNS["bare motor"], [120.0, 200.0])
    m = synthetic_measurement(subject, rel_noise=0.05, n_points=6,
                              rng=np.random.default_rng(1))
    a = calibrate(predictor, m, FIT[::2], fixed={"fat_thickness_mm": 9.0}, seed=5, **FAST)
    b = calibrate(predictor, m, FIT[::2], fixed={"fat_thickness_mm": 9.0}, seed=5, **FAST)
    assert np.array_equal(a.samples, b.samples)
    doc = calibration_document(a, model_path="models/nn-default",
                               tissue_names=[*FIT[::2], "fat_thickness_mm"])
    doc = json.loads(json.dumps(doc))
    assert problems(doc, schema("calibration")) == []
    assert doc["kind"] == "hapticrom.calibration" and doc["schema_version"] == 1
    assert doc["tissue"]["fat_thickness_mm"] == 9.0
    assert set(doc["tissue"]) == set(FIT)
    assert np.array(doc["correlation"]["matrix"]).shape == (2, 2)
    path = tmp_path / "cal.json"
    path.write_text(json.dumps(doc))
    t = read_calibration(path)
    assert t.model_name == "nn-default" and t.n_samples == 400
    assert t.point["skin_E_kPa"] == pytest.approx(doc["posterior"]["skin_E_kPa"]["mean"])
    broken = dict(doc, samples={"skin_E_kPa": [1.0]})
    path.write_text(json.dumps(broken))
    with pytest.raises(CalibrationFileError, match=r"samples\.skin_E_kPa"):
        read_calibration(path)
    path.write_text(json.dumps(dict(doc, kind="hapticrom.plan")))
    with pytest.raises(CalibrationFileError, match="not a calibration document"):
        read_calibration(path)


def test_priors_and_inputs_are_checked(predictor):
    specs = predictor.specs
    p = priors_for(FIT, specs)
    assert [x.kind for x in p] == ["loguniform", "uniform", "uniform"]
    assert (p[0].low, p[0].high) == (20.0, 120.0)
    given = priors_for(FIT, specs, ["skin_E_kPa=normal:49,10", "fat_thickness_mm=uniform:5,15"])
    assert given[0].kind == "normal" and (given[1].low, given[1].high) == (5.0, 15.0)
    for bad, match in [("skin_E_kPa=uniform:5,300", "inside the model's range"),
                       ("skin_E_kPa=beta:1,2", "KIND one of"),
                       ("ring_nu=uniform:0.46,0.48", "not a fitted input"),
                       ("nothing=uniform:1,2", "continuous input of the model")]:
        with pytest.raises(PriorError, match=match):
            priors_for(FIT, specs, [bad])
    with pytest.raises(PriorError, match="not a continuous input"):
        priors_for(["n_rings"], specs)
    subject = subject_from_predictor(predictor, {"skin_E_kPa": 50.0, "fat_thickness_mm": 12.0,
                                                 "tissue_loss_factor": 0.3},
                                     REFERENCE_DESIGNS["bare motor"], [150.0])
    m = synthetic_measurement(subject, rel_noise=0.05, n_points=5,
                              rng=np.random.default_rng(0))
    with pytest.raises(PriorError, match="fat_thickness_mm: no value for this model input"):
        calibrate(predictor, m, ["skin_E_kPa", "tissue_loss_factor"], **FAST)
