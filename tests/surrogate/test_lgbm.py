"""The LightGBM peer registered as a kind (issue 20, item 5): it learns, exports to one ONNX
graph that splits where LightGBM does, trains from the CLI, and the accuracy study fits it
through the registry. Skipped when the lightgbm package (the bench extra) is not installed."""

from __future__ import annotations

import json

import numpy as np
import pytest

from hapticrom.cli import main
from surrogate import kinds
from surrogate.estimators.lgbm import LightGBMRegressor, export_lgbm
from surrogate.runtime.models import load_model
from surrogate.runtime.predictor import Predictor, make_session

pytest.importorskip("lightgbm", reason="the lgbm kind needs lightgbm (pip install "
                    "'hapticrom[bench]')")

SMALL = {"n_estimators": 200, "learning_rate": 0.05}


def _smooth(n: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    X = np.random.default_rng(seed).uniform(0, 1, (n, 3))
    T = np.column_stack([np.sin(3 * X[:, 0]) + X[:, 1], X[:, 2] ** 2 - X[:, 0]])
    return X, T


def test_lgbm_learns_a_smooth_function_and_its_std_is_a_held_out_rms():
    X, T = _smooth(400)
    est = LightGBMRegressor(**SMALL).fit(X, T)
    Xt, Tt = _smooth(200, seed=1)
    mean, std = est.predict(Xt, return_std=True)
    rms = np.sqrt(np.mean((mean - Tt) ** 2, axis=0))
    assert np.all(rms < 0.1) and len(est.boosters_) == 2
    assert np.allclose(std, est.residual_std_) and np.all(est.residual_std_ > 0)
    # held out, so of the order of the test error, not the (much smaller) training error
    assert np.all(est.residual_std_ > 0.3 * rms)


@pytest.mark.parametrize(("param", "value"), [("n_estimators", 0), ("learning_rate", 0.0),
                                              ("num_leaves", 1), ("subsample", 1.5)])
def test_lgbm_refuses_bad_parameters_naming_them(param, value):
    X, T = _smooth(30)
    with pytest.raises(ValueError, match=f"{param} = "):
        LightGBMRegressor(**{param: value}).fit(X, T)


def test_lgbm_graph_matches_the_estimator():
    X, T = _smooth(200)
    est = LightGBMRegressor(**SMALL).fit(X, T)
    B = np.array([[1.0, 0.5, 0.0], [0.0, 2.0, -1.0]])
    b = np.array([0.1, -0.2, 0.3])
    sess = make_session(export_lgbm(est, B, b, {"kind": "lgbm"}))
    Xq = np.vstack([X, _smooth(300, seed=2)[0]])
    got_mean, got_std = sess.run(["log_mean", "log_std"], {"x": Xq})
    mean, std = est.predict(Xq, return_std=True)
    assert np.abs(got_mean - (mean @ B + b)).max() <= kinds.KINDS["lgbm"].parity_tol
    assert np.allclose(got_std, np.sqrt(std**2 @ B**2), rtol=1e-12)


def test_train_lgbm_from_the_cli_and_load_it_at_run_time(synthetic_dataset, tmp_path, capsys):
    out = tmp_path / "lgbm"
    assert main(["train", "--data", str(synthetic_dataset), "--kind", "lgbm", "--out", str(out),
                 "--modes", "3", "--options", json.dumps(SMALL)]) == 0
    assert "trained lgbm" in capsys.readouterr().out
    card = json.loads((out / "card.json").read_text())
    assert card["kind"] == "lgbm" and card["graph"]["dtype"] == "float64"
    assert card["export_parity_max_abs_dln"] <= kinds.KINDS["lgbm"].parity_tol
    assert card["training"]["lgbm_trees_per_target"] == 200
    assert isinstance(load_model(out), Predictor)


def test_accuracy_study_fits_lgbm_through_the_registry(synthetic_dataset):
    from studies.accuracy.designs import StudyData
    from studies.accuracy.learning_curves import curve, curves
    from surrogate.runtime.encoding import encode
    from surrogate.train import load_datasets, split

    assert "lgbm" in curves(quick=True) and "lgbm" in curves(quick=False)
    data = load_datasets([synthetic_dataset])
    tr, te = split(len(data.codes), 0.2, 0)
    n = len(data.codes)
    sd = StudyData(data, encode(data.codes, data.specs), tr, te, np.ones(n), [""] * n,
                   [str(i) for i in range(n)])
    rows, last = curve("lgbm", sd, (32, 64), SMALL)
    assert [r["n"] for r in rows] == [32, 64] and last.kind == "lgbm"
    assert all(np.isfinite(r["worst_median"]) for r in rows)
