"""The normal component an LDV sees: models/nn-normal serves it, the forward model reads
``profile_normal_um`` for normal rows and ``profile_um`` for magnitude rows, ``hapticrom
calibrate`` picks nn-normal without --model, and a model or a point without a normal output is
refused naming the row, the component and the model; the likelihood with the surrogate's spread
held fixed."""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

import numpy as np
import pytest

from calibration.fit import calibrate, surrogate_error_t
from calibration.forward import ForwardModel
from calibration.likelihood import mixture_log_likelihood
from calibration.measurement import MeasurementError, measurement_from_rows, read_measurement
from calibration.priors import PriorError
from calibration.synthetic import REFERENCE_DESIGNS
from hapticrom.cli import main
from hapticrom.documents import schema
from surrogate.runtime import load_predictor
from surrogate.runtime.card import read_card
from surrogate.runtime.defaults import default_model

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "hapticrom"))
from schema_check import problems

LDV = "examples/measurement-forearm-ldv.csv"
DESIGN = REFERENCE_DESIGNS["bare motor"]
TISSUE = {"skin_E_kPa": 60.0, "fat_thickness_mm": 10.0, "tissue_loss_factor": 0.25}
FIT3 = "skin_E_kPa,fat_thickness_mm,tissue_loss_factor"
QUICK = ["--walkers", "16", "--steps", "300"]
SUBJECTS = Path("bench/calibration/data/calibration-subjects.json")


@pytest.fixture(scope="module")
def normal():
    return load_predictor("models/nn-normal")


def _row(ref, d, f, comp):
    return {"reference": ref, "distance_mm": d, "frequency_hz": f, "quantity": "displacement",
            "unit": "um", "statistic": "peak", "component": comp, "value": 1.0,
            "uncertainty": "5%"}


def test_normal_rows_read_the_normal_profile_and_magnitude_rows_the_magnitude(normal):
    rows = [_row("edge", 5, 150, "normal"), _row("edge", 5, 150, "magnitude"),
            _row("centre", 0, 150, "magnitude"), _row("edge", 7.5, 150, "normal")]
    fit = ["skin_E_kPa", "tissue_loss_factor"]
    fwd = ForwardModel(normal, measurement_from_rows(rows, design=DESIGN), fit,
                       {**DESIGN, "fat_thickness_mm": TISSUE["fat_thickness_mm"]})
    mean, std = fwd.predict(np.array([[TISSUE[n] for n in fit]]))
    X = {k: np.array([v]) for k, v in {**DESIGN, **TISSUE, "frequency_hz": 150.0}.items()}
    o = normal.uncalibrated().predict(X)  # the likelihood widens the graph's raw spread itself
    um = np.exp(mean[0]) * 1e6
    assert um[0] == pytest.approx(o["profile_normal_um"][0][5], rel=1e-5)
    assert um[1] == pytest.approx(o["profile_um"][0][5], rel=1e-5)
    assert um[2] == pytest.approx(o["center_amplitude_um"][0], rel=1e-5)
    assert um[3] == pytest.approx(np.sqrt(o["profile_normal_um"][0][7]
                                          * o["profile_normal_um"][0][8]), rel=1e-5)
    assert std[0, 0] == pytest.approx(o["profile_normal_um_log_std"][0][5], rel=1e-5)
    assert um[0] < um[1]  # |u_z| is part of the magnitude
    # the errors of different outputs are not correlated; along one output they are
    C = fwd.error_correlation({"profile_um": 20.0, "profile_normal_um": 4.5}, 60.0)
    assert C[0, 1] == 0.0 and C[0, 2] == 0.0
    assert C[0, 3] == pytest.approx(np.exp(-2.5 / 4.5))


def test_normal_model_predicts_the_fe_normal_component():
    """On the study's FE subjects at their true tissue, nn-normal's |u_z| is within its card's
    held-out error: median |ln(FE / model)| below 0.15."""
    p = load_predictor("models/nn-normal")
    errs = []
    for s in json.loads(SUBJECTS.read_text())["subjects"][:20]:
        for i, f in enumerate(s["frequencies_hz"]):
            X = {k: np.array([v]) for k, v in {**s["design"], **s["truth"]}.items()}
            X["frequency_hz"] = np.array([f])
            errs.append(np.log(np.array(s["profile_um"]["normal"][i])
                               / p.predict(X)["profile_normal_um"][0]))
    assert np.median(np.abs(np.concatenate(errs))) < 0.15


def test_rows_without_a_normal_output_are_refused_by_name(normal):
    m = read_measurement(LDV)
    with pytest.raises(MeasurementError) as err:
        ForwardModel(load_predictor("models/nn-default"), m, ["skin_E_kPa"],
                     {**m.design, "fat_thickness_mm": 10.0, "tissue_loss_factor": 0.2})
    text = str(err.value)
    assert "12 row(s) the model cannot predict" in text
    assert ("row 14, column component: 'normal': the model 'nn-default' predicts no normal "
            "component") in text
    assert err.value.field == "row 14: component"
    face = measurement_from_rows([_row("centre", 0, 150, "normal"),
                                  _row("edge", 2, 150, "normal")], design=DESIGN)
    with pytest.raises(MeasurementError) as err:
        ForwardModel(normal, face, ["skin_E_kPa"], {**DESIGN, "fat_thickness_mm": 10.0,
                                                     "tissue_loss_factor": 0.2})
    assert ("row 1, column component: 'normal' at the unit's face (centre, 0 mm): the model "
            "'nn-normal' predicts the normal component only on the skin around the unit") \
        in str(err.value)
    assert "1 row(s)" in str(err.value)


def test_calibrate_picks_the_default_normal_model_for_an_ldv_measurement(tmp_path, capsys):
    """nn-normal, or nn-sweep once trained with the normal component (the defaults)."""
    card = read_card(default_model("normal"))
    name = card["name"]
    out = tmp_path / "cal.json"
    assert main(["calibrate", LDV, "--fit", FIT3, *QUICK, "--out", str(out),
                 "--plot", str(tmp_path / "cal.png"), "--verify"]) == 0
    assert f"model {name}" in capsys.readouterr().out
    doc = json.loads(out.read_text())
    assert problems(doc, schema("calibration")) == []
    assert doc["model"]["name"] == name
    assert doc["likelihood"]["error_length_mm"] == {
        "profile_normal_um": surrogate_error_t("profile_normal_um", card)["length_mm"]}
    err = doc["likelihood"]["surrogate_error"]["profile_normal_um"]
    # the example measures at 120 and 170 Hz: one mixing variable each, its scale per frequency
    assert err["profile_kernel"] == "matern32" and err["shared_within_hz"] < 50.0
    assert set(err["scale_by_frequency_hz"]) == {"120", "170"}
    assert doc["likelihood"]["surrogate_spread"] == "posterior"
    assert {p["component"] for p in doc["measurement"]["points"]} == {"normal"}
    lo, hi = doc["posterior"]["skin_E_kPa"]["ci95"]  # the example was made with 75 kPa
    assert lo < 75.0 < hi
    # --verify compares |u_z| of the FE solve at the posterior mean, point by point
    v = doc["verify"]
    assert len(v["points"]) == 12 and v["median_abs_log_surrogate_vs_fe"] < 0.15
    for q in v["points"]:
        assert abs(q["fe_um"] / q["measured_um"] - 1) < 0.3


def test_calibrate_with_a_magnitude_model_exits_2_naming_component_and_model(tmp_path,
                                                                               capsys):
    out = tmp_path / "cal.json"
    code = main(["calibrate", LDV, "--model", "models/nn-default", "--fit", FIT3,
                 "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 2 and not out.exists()
    assert "'normal': the model 'nn-default' predicts no normal component" in err
    assert "models/nn-normal" in err


def test_fixed_likelihood_equals_the_batched_one_at_the_same_spread():
    rng = np.random.default_rng(0)
    m = 6
    y, rel = rng.normal(size=m), rng.uniform(0.03, 0.1, m)
    corr = np.exp(-np.abs(np.subtract.outer(np.arange(m), np.arange(m))) / 3.0)
    mean, s = rng.normal(size=(5, m)), 1.4 * rng.uniform(0.02, 0.1, m)
    blocks = [(np.arange(4), 2.0), (np.arange(4, m), math.inf)]
    fixed = s[:, None] * corr * s[None, :]
    batched = np.tile(fixed, (5, 1, 1))
    np.testing.assert_allclose(mixture_log_likelihood(y - mean, rel ** 2, fixed, blocks),
                               mixture_log_likelihood(y - mean, rel ** 2, batched, blocks),
                               rtol=1e-12)


def test_spread_choice_is_checked(normal):
    m = read_measurement(LDV)
    with pytest.raises(PriorError, match="spread 'median': allowed posterior, local"):
        calibrate(normal, m, ["skin_E_kPa"], spread="median", steps=20, burn=5,
                  fixed={"fat_thickness_mm": 8.0, "tissue_loss_factor": 0.2})
