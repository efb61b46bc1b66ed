"""The surrogate-kind registry and the MLP baseline added through it (issue 22)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from fieldspec import FieldError
from hapticrom.cli import main
from surrogate import kinds
from surrogate.estimators.mlp import MLPBaselineRegressor, export_mlp
from surrogate.runtime.models import load_model
from surrogate.runtime.predictor import Predictor, make_session


def test_registry_lists_every_kind_once_with_what_training_needs():
    assert list(kinds.KINDS) == ["gp", "nn", "mlp", "lgbm", "rom"]
    assert kinds.STEADY_KINDS == ("gp", "nn", "mlp", "lgbm")
    for name in kinds.STEADY_KINDS:
        k = kinds.KINDS[name]
        assert k.name == name and k.export is not None and k.trainer is None
        assert k.dtype in ("float32", "float64") and 0 < k.parity_tol < 1e-2
    assert kinds.KINDS["rom"].trainer is not None and kinds.KINDS["rom"].estimator is None


def test_unknown_kind_names_the_field_and_the_choices():
    with pytest.raises(FieldError, match=r"--kind 'svm': allowed gp, nn, mlp, lgbm, rom") as err:
        kinds.get("svm")
    assert err.value.field == "--kind"
    with pytest.raises(FieldError, match=r"allowed gp, nn, mlp, lgbm$"):
        kinds.get("rom", steady=True)


def _smooth(n: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    X = np.random.default_rng(seed).uniform(0, 1, (n, 3))
    T = np.column_stack([np.sin(3 * X[:, 0]) + X[:, 1], X[:, 2] ** 2 - X[:, 0]])
    return X, T


def test_mlp_learns_a_smooth_function_and_its_std_is_the_residual_rms():
    X, T = _smooth(300)
    est = MLPBaselineRegressor(hidden=(32, 32), max_iter=3000).fit(X, T)
    Xt, Tt = _smooth(100, seed=1)
    mean, std = est.predict(Xt, return_std=True)
    assert np.sqrt(np.mean((mean - Tt) ** 2)) < 0.05
    assert np.allclose(std, est.residual_std_) and np.all(est.residual_std_ > 0)
    assert est.predict(Xt[:, :1].repeat(3, axis=1)).shape == (100, 2)


@pytest.mark.parametrize(("param", "value", "match"), [
    ("hidden", (), "hidden = ()"), ("activation", "gelu", "activation = 'gelu'"),
    ("alpha", -1.0, "alpha = -1.0"), ("max_iter", 0, "max_iter = 0")])
def test_mlp_refuses_bad_parameters_naming_them(param, value, match):
    X, T = _smooth(20)
    with pytest.raises(ValueError, match=match):
        MLPBaselineRegressor(**{param: value}).fit(X, T)


def test_mlp_graph_matches_the_estimator_within_float32_tolerance():
    X, T = _smooth(200)
    est = MLPBaselineRegressor(hidden=(16,), max_iter=500).fit(X, T)
    B = np.array([[1.0, 0.5, 0.0], [0.0, 2.0, -1.0]])
    b = np.array([0.1, -0.2, 0.3])
    sess = make_session(export_mlp(est, B, b, {"kind": "mlp"}))
    got_mean, got_std = sess.run(["log_mean", "log_std"], {"x": X.astype(np.float32)})
    mean, std = est.predict(X, return_std=True)
    assert np.abs(got_mean - (mean @ B + b)).max() <= kinds.KINDS["mlp"].parity_tol
    assert np.allclose(got_std, np.sqrt(std**2 @ B**2), rtol=1e-5)


def test_train_mlp_from_the_cli_and_load_it_at_run_time(synthetic_dataset, tmp_path, capsys):
    out = tmp_path / "mlp"
    assert main(["train", "--data", str(synthetic_dataset), "--kind", "mlp", "--out", str(out),
                 "--modes", "3", "--options", '{"hidden": [32, 32], "max_iter": 800}']) == 0
    text = capsys.readouterr().out
    assert "trained mlp" in text and "export parity" in text
    card = json.loads((out / "card.json").read_text())
    assert card["kind"] == "mlp" and card["graph"]["dtype"] == "float32"
    assert card["export_parity_max_abs_dln"] <= kinds.KINDS["mlp"].parity_tol
    assert card["metrics"]["center_amplitude_um"]["median_rel_err"] < 0.5
    model = load_model(out)
    assert isinstance(model, Predictor)
    assert main(["train", "--data", str(synthetic_dataset), "--kind", "mlp", "--out",
                 str(tmp_path / "bad"), "--options", '{"activation": "gelu"}']) == 2
    assert "activation = 'gelu'" in capsys.readouterr().err
    assert not (tmp_path / "bad").exists()


def test_accuracy_study_fits_the_mlp_baseline_through_the_registry(synthetic_dataset):
    from studies.accuracy.designs import StudyData
    from studies.accuracy.learning_curves import curve
    from surrogate.runtime.encoding import encode
    from surrogate.train import load_datasets, split

    data = load_datasets([synthetic_dataset])
    tr, te = split(len(data.codes), 0.2, 0)
    n = len(data.codes)
    sd = StudyData(data, encode(data.codes, data.specs), tr, te, np.ones(n), [""] * n,
                   [str(i) for i in range(n)])
    rows, last = curve("mlp", sd, (32, 64), {"hidden": [16], "max_iter": 300})
    assert [r["n"] for r in rows] == [32, 64] and last.kind == "mlp"
    assert all(np.isfinite(r["worst_median"]) and r["generation_s"] == r["n"] for r in rows)
    with pytest.raises(FieldError, match="kind 'rom': allowed gp, nn, mlp, lgbm"):
        curve("rom", sd, (32,))
