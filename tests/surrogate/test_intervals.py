"""Calibrated intervals (surrogate/intervals.py) and the run-time predictor's fast paths."""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest
from synthetic import make_dataset

from surrogate.calibrate_intervals import calibrate_model_dir
from surrogate.intervals import Z95, calibrate, conformal_quantile, coverage
from surrogate.runtime import ModelFileError, PredictorInputError, load_predictor
from surrogate.runtime.card import replace_card, verify_model_dir
from surrogate.runtime.predictor import CALIBRATION_KEY, CHUNK_ROWS


def test_conformal_factor_makes_new_rows_covered():
    rng = np.random.default_rng(0)
    spread = np.array([2.0, 1.5, 1.5] + [0.8] * 5)  # residuals |N(0, s)| per column: f = s
    r_cal, r_new = (np.abs(rng.standard_normal((n, 8))) * spread for n in (400, 4000))
    entry = calibrate(r_cal)
    assert entry["groups"]["center"]["columns"] == [0]
    assert entry["groups"]["edge"]["columns"] == [1, 2]
    assert entry["groups"]["profile"]["columns"] == list(range(3, 8))
    for name, s in (("center", 2.0), ("edge", 1.5), ("profile", 0.8)):
        assert entry["groups"][name]["factor"] == pytest.approx(s, rel=0.15)
    before, after = coverage(r_new), coverage(r_new, entry["log_std_scale"])
    assert before["center_amplitude_um"] < 0.7 and before["profile_um"] > 0.98
    for v in after.values():
        assert 0.93 <= v <= 0.97
    with pytest.raises(ValueError, match="at least 20"):
        calibrate(r_cal[:10])


def test_hierarchical_quantile_is_the_pooled_rank_at_level_times_one_plus_one_over_k():
    rng = np.random.default_rng(1)
    k_groups, n_each = 30, 20
    scores = rng.random((k_groups * n_each, 1))
    group = np.repeat(np.arange(k_groups), n_each)
    rank = int(np.ceil(0.95 * (k_groups + 1) * n_each))  # 589 of the 600 pooled scores
    assert conformal_quantile(scores, 0.95, group) == np.sort(scores.ravel())[rank - 1]
    # groups of one row: the ordinary split-conformal rank ceil((n + 1) level)
    single = scores[:40]
    assert conformal_quantile(single, 0.95, np.arange(40)) == conformal_quantile(single, 0.95)
    # a row's columns share its group's mass: two columns of one row count as that row
    wide = np.column_stack([scores[:, 0], scores[:, 0]])
    assert conformal_quantile(wide, 0.95, group) == conformal_quantile(scores, 0.95, group)
    # unequal groups: each group carries the same mass whatever its size
    uneven = np.r_[np.zeros(21), np.ones(1000)][:, None]  # 21 groups of 1 at 0, one of 1000 at 1
    labels = np.r_[np.arange(21), np.full(1000, 21)]
    assert conformal_quantile(uneven, 0.9, labels) == 0.0  # mass at 0: 21/23 = 0.913 >= 0.9
    assert conformal_quantile(uneven, 0.9) == 1.0  # pooled, the big group outweighs


def test_hierarchical_factor_covers_new_groups_where_the_pooled_one_falls_short():
    """Residuals shared within a group (a design's frequencies): the pooled 95 % quantile
    covers about K / (K + 1) of new groups (29/31 here), the hierarchical one at least 95 %."""
    rng = np.random.default_rng(2)
    k_groups, n_each, trials = 30, 20, 2000
    group = np.repeat(np.arange(k_groups), n_each)
    covered = {"pooled": [], "hierarchical": []}
    for _ in range(trials):
        shared = rng.standard_normal(k_groups + 1)
        r = np.abs(shared[:, None] + 0.01 * rng.standard_normal((k_groups + 1, n_each)))
        cal, new = r[:-1].reshape(-1, 1), r[-1]
        for name, g in (("pooled", None), ("hierarchical", group)):
            covered[name].append(np.mean(new <= conformal_quantile(cal, 0.95, g)))
    assert np.mean(covered["hierarchical"]) >= 0.95
    assert np.mean(covered["pooled"]) < 0.945


def test_hierarchical_calibration_names_its_method_and_refuses_too_few_groups():
    rng = np.random.default_rng(3)
    r = np.abs(rng.standard_normal((30 * 4, 8)))
    entry = calibrate(r, group=np.repeat(np.arange(30), 4))
    assert entry["method"] == "hierarchical split-conformal"
    assert entry["groups"]["center"]["groups"] == 30
    with pytest.raises(ValueError, match="19 calibration groups: a 95% factor needs more than 19"):
        calibrate(r[:19 * 4], group=np.repeat(np.arange(19), 4))


@pytest.fixture()
def model_copy(trained_models, tmp_path):
    dest = tmp_path / "nn"
    shutil.copytree(trained_models["nn"][0], dest)
    return dest


X4 = np.array([[1.0, 2.0, 40.0, 200.0], [0.0, 0.0, 90.0, 110.0], [1.0, 1.0, 60.0, 150.0]])


def test_predictor_applies_the_cards_scale(model_copy):
    raw = load_predictor(model_copy).predict(X4)
    card = verify_model_dir(model_copy)
    k = 3 + len(card["profile_distance_mm"])
    scale = np.linspace(1.5, 2.5, k)
    replace_card(model_copy, {**card, CALIBRATION_KEY: {"log_std_scale": scale.tolist()}})
    p = load_predictor(model_copy)
    for X in (X4, X4[:1]):  # batch path and the one-design path
        got, ref = p.predict(X), load_predictor(model_copy, calibrated=False).predict(X)
        np.testing.assert_array_equal(got["center_amplitude_um"], ref["center_amplitude_um"])
        np.testing.assert_allclose(got["center_amplitude_um_log_std"],
                                   ref["center_amplitude_um_log_std"] * scale[0], rtol=1e-12)
        np.testing.assert_allclose(got["normalized_edge_log_std"],
                                   ref["normalized_edge_log_std"] * scale[2], rtol=1e-12)
        np.testing.assert_allclose(got["profile_um_log_std"],
                                   ref["profile_um_log_std"] * scale[3:], rtol=1e-12)
    np.testing.assert_array_equal(raw["profile_um_log_std"],
                                  load_predictor(model_copy, calibrated=False)
                                  .predict(X4)["profile_um_log_std"])
    replace_card(model_copy, {**card, CALIBRATION_KEY: {"log_std_scale": [1.0, -1.0]}})
    with pytest.raises(ModelFileError, match="log_std_scale") as err:
        load_predictor(model_copy)
    assert err.value.field == CALIBRATION_KEY


def test_train_and_command_calibrate_on_rows_the_fit_never_saw(tmp_path):
    from surrogate.train import train

    data = make_dataset(tmp_path / "data", 300)
    card = train([data], "gp", tmp_path / "gp", n_modes=3, calibration_fraction=0.1)
    entry = card[CALIBRATION_KEY]
    assert card["training"]["calibration_rows"] == 24 and card["training"]["rows"] == 216
    assert entry["groups"]["center"]["rows"] == 24
    assert len(entry["log_std_scale"]) == len(card["log_output_columns"])
    assert verify_model_dir(tmp_path / "gp")[CALIBRATION_KEY] == entry
    with pytest.raises(ValueError, match="at least 20"):
        train([data], "gp", tmp_path / "gp2", n_modes=3, calibration_fraction=0.05)

    train([data], "gp", tmp_path / "plain", n_modes=3)
    out = calibrate_model_dir(tmp_path / "plain", [data], check_fraction=0.5, seed=3)
    assert out["rows"]["calibration"] + out["rows"]["check"] == 60
    stored = json.loads((tmp_path / "plain" / "card.json").read_text())
    assert stored[CALIBRATION_KEY] == out and verify_model_dir(tmp_path / "plain")
    assert sorted(p.name for p in (tmp_path / "plain").iterdir()) == ["card.json", "model.onnx"]
    assert set(out["coverage95_check"]["after"]) == {"center_amplitude_um",
                                                     "edge_amplitude_um", "normalized_edge",
                                                     "profile_um"}
    s = np.asarray(out["log_std_scale"])
    assert np.all(s > 0) and s[0] == out["groups"]["center"]["factor"]
    assert Z95 == pytest.approx(1.959964)


def _one(row):
    return {k: [v] for k, v in row.items()}


ROW = {"orientation": "reverse", "n_rings": 2, "skin_E_kPa": 40.0, "frequency_hz": 200.0}


def test_one_design_path_equals_the_batch_path(trained_models):
    for kind in ("nn", "gp"):
        p = load_predictor(trained_models[kind][0])
        fast = p.predict(_one(ROW))  # lists of one value: the one-design path
        slow = p.predict(ROW)  # scalars: the general parser, batch of one
        also = p.predict({k: np.array([v]) for k, v in ROW.items()}, extrapolate=True)
        assert list(fast) == list(slow)
        for k in slow:
            np.testing.assert_array_equal(fast[k], slow[k])
            np.testing.assert_array_equal(also[k], slow[k])
            assert fast[k].shape == slow[k].shape and fast[k].dtype == slow[k].dtype
        assert also["extrapolated"].tolist() == [False]


@pytest.mark.parametrize("over", [{"skin_E_kPa": 500.0}, {"orientation": "sideways"},
                                  {"n_rings": 1.5}, {"n_rings": 7}, {"skin_E_kPa": float("nan")},
                                  {"frequency_hz": "soft"}, {"orientation": 5}])
def test_refusals_read_the_same_on_every_path(trained_models, over):
    p = load_predictor(trained_models["nn"][0])
    messages = set()
    for X in (_one({**ROW, **over}), {**ROW, **over},
              {k: np.array([v]) for k, v in {**ROW, **over}.items()}):
        with pytest.raises(PredictorInputError) as err:
            p.predict(X)
        messages.add((err.value.field, str(err.value)))
    assert len(messages) == 1


def test_a_large_batch_is_chunked_without_changing_it(trained_models):
    p = load_predictor(trained_models["nn"][0])
    rng = np.random.default_rng(1)
    n = 2 * CHUNK_ROWS + 7
    X = {"orientation": np.array(["forward", "reverse"])[rng.integers(0, 2, n)],
         "n_rings": rng.integers(0, 3, n), "skin_E_kPa": rng.uniform(20, 120, n),
         "frequency_hz": rng.uniform(100, 250, n)}
    big = p.predict(X)
    part = p.predict({k: v[CHUNK_ROWS - 3:CHUNK_ROWS + 3] for k, v in X.items()})
    for k in big:
        np.testing.assert_allclose(big[k][CHUNK_ROWS - 3:CHUNK_ROWS + 3], part[k], rtol=1e-6,
                                   atol=1e-7)
        assert big[k].flags.c_contiguous


def test_the_command_refuses_bad_input_and_writes_nothing(model_copy, tmp_path, capsys):
    from hapticrom.cli import main

    before = (model_copy / "card.json").read_bytes()
    assert main(["models", "calibrate-intervals", str(tmp_path / "none")]) == 2
    assert main(["models", "calibrate-intervals", str(model_copy), "--check-fraction",
                 "1.5"]) == 2
    assert "--check-fraction" in capsys.readouterr().err
    other = make_dataset(tmp_path / "other", 40)
    assert main(["models", "calibrate-intervals", str(model_copy), "--data", str(other)]) == 2
    assert "not the data the model was trained on" in capsys.readouterr().err
    assert (model_copy / "card.json").read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["nn", "other"]


def test_training_calibrates_by_default_only_on_enough_rows():
    from surrogate.train import AUTO_CALIBRATION_ROWS, _calibration_rows

    small, big = np.arange(500), np.arange(10 * AUTO_CALIBRATION_ROWS)
    fit, cal = _calibration_rows(small, None, 0)
    assert cal.size == 0 and np.array_equal(fit, small)
    fit, cal = _calibration_rows(big, None, 0)
    assert cal.size == AUTO_CALIBRATION_ROWS and fit.size == big.size - cal.size
    assert not set(fit) & set(cal) and set(fit) | set(cal) == set(big)
    assert _calibration_rows(big, 0.0, 0)[1].size == 0
    with pytest.raises(ValueError, match="must be in"):
        _calibration_rows(big, 1.0, 0)


def test_one_design_calls_from_many_threads_do_not_mix(trained_models):
    from concurrent.futures import ThreadPoolExecutor

    p = load_predictor(trained_models["nn"][0])
    rows = [{**ROW, "skin_E_kPa": e} for e in np.linspace(25.0, 110.0, 8)]
    want = [p.predict(_one(r))["center_amplitude_um"][0] for r in rows]

    def work(k):
        return [p.predict(_one(rows[(k + i) % 8]))["center_amplitude_um"][0] for i in range(40)]

    with ThreadPoolExecutor(4) as pool:
        for k, got in enumerate(pool.map(work, range(4))):
            assert got == [want[(k + i) % 8] for i in range(40)]
