"""Calibration on a sweep-trained model: an LDV measurement (normal component) runs on the
default normal model when that is a sweep model trained with ``profile_normal_um``."""

from __future__ import annotations

import json

import numpy as np

from calibration.forward import ForwardModel
from calibration.measurement import read_measurement
from hapticrom.cli import main
from surrogate.runtime import defaults, load_predictor
from surrogate.runtime.models import MODEL_PATH_ENV

LDV = "examples/measurement-forearm-ldv.csv"
FIT3 = "skin_E_kPa,fat_thickness_mm,tissue_loss_factor"


def test_an_ldv_measurement_calibrates_on_the_default_sweep_model(sweep_model, monkeypatch,
                                                                   tmp_path, capsys):
    monkeypatch.setenv(MODEL_PATH_ENV, str(sweep_model.parent))
    monkeypatch.setattr(defaults, "DEFAULT_MODELS", {**defaults.DEFAULT_MODELS,
                                                     "normal": (sweep_model.name, "nn-normal")})
    out = tmp_path / "cal.json"
    assert main(["calibrate", LDV, "--fit", FIT3, "--walkers", "16", "--steps", "120",
                 "--out", str(out)]) == 0
    assert f"model {sweep_model.name} " in capsys.readouterr().out
    doc = json.loads(out.read_text())
    assert doc["model"]["name"] == sweep_model.name
    assert {p["component"] for p in doc["measurement"]["points"]} == {"normal"}
    assert set(doc["likelihood"]["surrogate_error"]) == {"profile_normal_um"}


def test_normal_rows_read_the_sweep_models_normal_profile(sweep_model):
    """The forward model's prediction of each normal row is the model's |u_z| profile at the
    row's distance and frequency (log-linear on the 40 mm grid)."""
    p = load_predictor(sweep_model)
    m = read_measurement(LDV)
    tissue = {"skin_E_kPa": 60.0, "fat_thickness_mm": 10.0, "tissue_loss_factor": 0.25}
    fwd = ForwardModel(p, m, list(tissue), m.design)
    mean, _ = fwd.predict(np.array([list(tissue.values())]))
    assert {q.reference for q in m.points} == {"edge"}
    for k, q in enumerate(m.points):
        row = {**m.design, **tissue, "frequency_hz": q.frequency_hz}
        out = p.predict({n: np.array([row[n]]) for n in p.input_names})
        want = np.interp(q.distance_m * 1e3, p.profile_distance_mm,
                         np.log(out["profile_normal_um"][0] * 1e-6))
        np.testing.assert_allclose(mean[0, k], want, rtol=0, atol=1e-6)  # float32 graph
