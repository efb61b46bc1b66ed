"""Extra profile outputs (``hapticrom train --outputs profile_um,profile_normal_um``): one more
POD block among the targets and the outputs, exported in the one graph, decoded by name at run
time, and refused by name when unknown or not stored."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from synthetic import GRID_MM, make_dataset, synthetic_amplitudes, synthetic_normal

from fieldspec import FieldError
from surrogate.pod import ProfileTargets, output_columns
from surrogate.runtime import load_predictor
from surrogate.runtime.predictor import output_layout

NORMAL = "profile_normal_um"
OPTIONS = {"max_epochs": 300, "n_members": 3, "hidden": (32, 32)}


@pytest.fixture(scope="module")
def normal_dataset(tmp_path_factory):
    return make_dataset(tmp_path_factory.mktemp("data") / "normal", 96, normal=True)


@pytest.fixture(scope="module")
def normal_model(normal_dataset, tmp_path_factory):
    from surrogate.train import train

    out = tmp_path_factory.mktemp("models") / "nn-normal"
    card = train([normal_dataset], "nn", out, options=OPTIONS, n_modes=3,
                 outputs=["profile_um", NORMAL])
    return out, card


def test_output_map_of_an_extra_block_is_exact():
    rng = np.random.default_rng(4)
    center = rng.uniform(1, 10, 40)
    rate = rng.uniform(0.5, 1, 40)[:, None]
    x = np.linspace(0, 3, 7)[None, :]
    profile = 0.8 * center[:, None] * np.exp(-x * rate)
    normal = profile * (0.6 + 0.3 * np.cos(2 * x + rate))
    t = ProfileTargets(n_modes=7, extra=[NORMAL])
    T = t.fit_transform(center, profile, [normal])
    B, b = t.output_map()
    out = T @ B + b
    assert B.shape == (1 + 7 + 7, 3 + 2 * 7)
    tol = {"rtol": 0, "atol": 1e-12}
    np.testing.assert_allclose(out[:, 3:10], np.log(profile), **tol)
    np.testing.assert_allclose(out[:, 10:], np.log(normal), **tol)
    np.testing.assert_allclose(out[:, 1], np.log(profile[:, 0]), **tol)  # edge: the magnitude
    assert not B[1:8, 10:].any() and not B[8:, :10].any()  # each block maps only its own
    assert output_columns(7, [NORMAL])[10:] == [f"{NORMAL}[{j}]" for j in range(7)]


def test_trained_normal_model_predicts_both_profiles(normal_model):
    path, card = normal_model
    assert [o["name"] for o in card["outputs"]][3:5] == ["profile_um", NORMAL]
    assert card["log_output_columns"] == output_columns(GRID_MM.size, [NORMAL])
    assert card["training"]["profile_outputs"][NORMAL]["column"] == "profile_uz_um"
    assert set(card["metrics"][NORMAL]) == {"median_rel_err", "p95_rel_err", "p99_rel_err",
                                            "max_rel_err", "median_rel_l2", "p95_rel_l2",
                                            "coverage95"}
    assert card["metrics"][NORMAL]["median_rel_err"] < 0.05
    p = load_predictor(path)
    assert NORMAL in p.output_names
    X = {"orientation": np.array(["forward", "reverse"]), "n_rings": np.array([0, 2]),
         "skin_E_kPa": np.array([30.0, 90.0]), "frequency_hz": np.array([120.0, 200.0])}
    out = p.predict(X)
    _, profile = synthetic_amplitudes(X["orientation"], X["n_rings"].astype(float),
                                      X["skin_E_kPa"], X["frequency_hz"])
    np.testing.assert_allclose(out[NORMAL], synthetic_normal(profile, X["skin_E_kPa"]),
                               rtol=0.15)
    np.testing.assert_allclose(out["profile_um"], profile, rtol=0.15)
    assert out[NORMAL].shape == out[f"{NORMAL}_log_std"].shape == (2, GRID_MM.size)


def test_normal_block_round_trip_onnx_equals_the_estimator(normal_dataset):
    """The run-time predictor's profile_normal_um is the in-memory ensemble's through the
    output map, to float32 precision (what training's export parity asserts)."""
    from surrogate.estimators.nn import MLPEnsembleRegressor, export_nn
    from surrogate.runtime.encoding import encode
    from surrogate.runtime.predictor import Predictor, make_session
    from surrogate.train import load_datasets

    data = load_datasets([normal_dataset], outputs=[NORMAL])
    targets = ProfileTargets(n_modes=3, extra=[NORMAL])
    T = targets.fit_transform(data.center_um, data.profile_um, [data.extra_um[NORMAL]])
    X = encode(data.codes, data.specs)
    est = MLPEnsembleRegressor(max_epochs=40, n_members=3, hidden=(16, 16)).fit(X, T)
    B, b = targets.output_map()
    card = {"kind": "nn", "inputs": [s.to_dict() for s in data.specs],
            "profile_distance_mm": data.grid_mm.tolist(),
            "log_output_columns": output_columns(data.grid_mm.size, [NORMAL]),
            "edge_radius": {"method": "table", "inputs": ["n_rings"],
                            "keys": [[0.0], [1.0], [2.0], [3.0]],
                            "values_mm": [3.5, 4.55, 5.55, 6.55]},
            "graph": {"file": "model.onnx", "dtype": "float32"}}
    predictor = Predictor(card, make_session(export_nn(est, B, b, {"kind": "nn"})))
    got = predictor.predict(data.codes[:20])
    mean, _ = est.predict(X[:20], return_std=True)
    want = mean @ B + b
    m = data.grid_mm.size
    np.testing.assert_allclose(np.log(got[NORMAL]), want[:, 3 + m:], atol=1e-4)
    np.testing.assert_allclose(np.log(got["profile_um"]), want[:, 3:3 + m], atol=1e-4)


def test_unknown_output_and_missing_column_are_refused(synthetic_dataset, tmp_path):
    from surrogate.train import train

    with pytest.raises(FieldError, match="--outputs profile_um,profile_x: 'profile_x' is not a "
                       "profile output \\(allowed: profile_um, profile_normal_um\\)"):
        train([synthetic_dataset], "nn", tmp_path / "a", outputs=["profile_um", "profile_x"])
    with pytest.raises(FieldError, match="does not store profile_uz_um") as err:
        train([synthetic_dataset], "nn", tmp_path / "b", outputs=[NORMAL])
    assert err.value.field == "--outputs"
    assert not (tmp_path / "a").exists() and not (tmp_path / "b").exists()


def test_cli_train_outputs_refusal_exits_2(synthetic_dataset, tmp_path, capsys):
    from hapticrom.cli import main

    rc = main(["train", "--data", str(synthetic_dataset), "--kind", "nn", "--outputs",
               "profile_um,profile_um", "--out", str(tmp_path / "m")])
    assert rc == 2
    assert "a name is given twice" in capsys.readouterr().err
    assert not (tmp_path / "m").exists()


@pytest.mark.parametrize(("columns", "message"), [
    (["center_amplitude_um", "edge_amplitude_um", "normalized_edge", "profile_um[0]",
      "profile_um[2]", "profile_um[1]"], "in order"),
    (["center_amplitude_um", "edge_amplitude_um", "normalized_edge", "profile_um[0]",
      "profile_um[1]", "profile_um[2]", "profile_um[0]", "profile_um[1]", "profile_um[2]"],
     "appears twice"),
    (["edge_amplitude_um", "center_amplitude_um", "normalized_edge", "profile_um[0]",
      "profile_um[1]", "profile_um[2]"], "must start with"),
])
def test_bad_output_layouts_are_refused(columns, message):
    with pytest.raises(ValueError, match=message):
        output_layout(columns, 3)


def test_shipped_normal_model_card():
    """models/nn-normal: the magnitude outputs of nn-default plus profile_normal_um, with its
    held-out metrics, loadable by name."""
    from surrogate.runtime.models import load_model

    root = Path(__file__).resolve().parents[2]
    card = json.loads((root / "models/nn-normal/card.json").read_text())
    assert card["training"]["profile_outputs"][NORMAL]["column"] == "profile_uz_um"
    assert card["metrics"][NORMAL]["coverage95"] > 0.5
    p = load_model("nn-normal")
    assert p.output_names == ("center_amplitude_um", "edge_amplitude_um", "normalized_edge",
                              "profile_um", NORMAL, "edge_radius_mm")
