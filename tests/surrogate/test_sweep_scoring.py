"""A sweep model's card scored on fresh designs (``hapticrom train --test-data``): the test set
entry names its datasets (digest, seed, size) and holds the held-out metrics' figures on every
test design; a test set that repeats the training designs or another band is refused. The
benches' pairs scorer gives the card's figures and is exact on analytic pairs."""

from __future__ import annotations

import json

import numpy as np
import pytest
from sweep_fixture import coarse_space_dict, make_dataset

from fieldspec import FieldError
from hapticrom.cli import main
from surrogate.registry import manifest_sha256
from surrogate.runtime.predictor import load_predictor
from surrogate.sweep.scoring import load_test_data, predict_pairs, score_pairs, score_test_set
from surrogate.sweep.targets import load_sweep_datasets, pair_rows
from surrogate.sweep.train import sweep_metrics

OTHER_SEED = 777


def _score(model, test):
    predictor = load_predictor(model)
    extra = [o["name"] for o in predictor.card["outputs"] if o["name"] == "profile_normal_um"]
    return score_test_set(test, lambda d, designs: sweep_metrics(
        predictor, d, designs, ["profile_um", *extra]))


def test_the_test_set_entry_names_its_designs_and_scores_every_one(sweep_dataset, sweep_model,
                                                                   tmp_path):
    path = make_dataset(tmp_path / "test", 8, seed=OTHER_SEED)
    train = load_sweep_datasets([sweep_dataset])
    test = load_test_data([path], train, "onehot")
    entry = _score(sweep_model, test)
    assert entry["designs"] == 8 and entry["pairs"] == 8 * train.band_hz.size
    (src,) = entry["data"]
    assert src["seed"] == OTHER_SEED != coarse_space_dict()["space"]["seed"]
    assert src["manifest_sha256"] == manifest_sha256(path) and src["rows"] == 8
    m = entry["metrics"]
    for name in ("center_amplitude_um", "edge_amplitude_um"):
        assert set(m[name]) >= {"median_rel_err", "p95_rel_err", "p99_rel_err", "max_rel_err",
                                "max_abs_err_over_field", "coverage95"}
        assert m[name]["median_rel_err"] <= m[name]["p95_rel_err"] <= m[name]["max_rel_err"]
    assert {"median_rel_l2", "p95_rel_l2", "p99_rel_l2", "max_rel_l2"} <= set(m["profile_um"])
    json.dumps(entry)  # plain JSON for the card


def test_a_test_set_of_the_training_designs_or_another_band_is_refused(sweep_dataset, tmp_path):
    train = load_sweep_datasets([sweep_dataset])
    with pytest.raises(FieldError, match="the same space at the same seed") as err:
        load_test_data([make_dataset(tmp_path / "same", 4)], train, "onehot")
    assert err.value.field == "--test-data"
    other_band = make_dataset(tmp_path / "band", 4, seed=OTHER_SEED,
                              band={"start": 100.0, "stop": 200.0})
    with pytest.raises(FieldError, match=r"band .* differ from the training data's"):
        load_test_data([other_band], train, "onehot")


def test_test_data_with_single_frequency_datasets_exits_2(tmp_path, capsys):
    code = main(["train", "--data", "datasets/default", "--kind", "nn", "--out",
                 str(tmp_path / "m"), "--test-data", "datasets/default"])
    assert code == 2 and not (tmp_path / "m").exists()
    assert "--test-data: only with sweep datasets" in capsys.readouterr().err


def test_the_pairs_scorer_of_the_benches_gives_the_cards_figures(sweep_dataset, sweep_model,
                                                                 tmp_path):
    # bench/surrogate/sweep_nn.py and `hapticrom bench accuracy` score through
    # predict_pairs + score_pairs; the card through sweep_metrics: the same figures
    path = make_dataset(tmp_path / "test", 8, seed=OTHER_SEED)
    test = load_sweep_datasets([path])
    designs = np.arange(8)
    predictor = load_predictor(sweep_model)
    codes, centre, profile, _ = pair_rows(test, designs)
    got = score_pairs(predict_pairs(predictor, test, codes), centre, profile, test.grid_mm)
    card = sweep_metrics(predictor, test, designs, ["profile_um"])
    for name, key in (("centre", "center_amplitude_um"), ("edge", "edge_amplitude_um")):
        m = card[key]
        want = [m[k] for k in ("median_rel_err", "p95_rel_err", "p99_rel_err", "max_rel_err",
                               "max_abs_err_over_field")]
        assert got[name] == pytest.approx(want, rel=1e-12)
        assert got[f"{name}_coverage95"] == pytest.approx(m["coverage95"], rel=1e-12)
    assert got["profile_all"] == pytest.approx(
        [card["profile_um"]["median_rel_l2"], card["profile_um"]["p95_rel_l2"]], rel=1e-12)


def test_score_pairs_is_exact_on_analytic_pairs():
    grid = np.array([0.0, 10.0, 20.0, 30.0])
    centre = np.array([2.0, 4.0])
    profile = np.array([[1.0, 1.0, 1.0, 1.0], [8.0, 4.0, 2.0, 1.0]])
    pred = {"center_amplitude_um": centre * [1.1, 1.0], "edge_amplitude_um": [1.0, 6.0],
            "profile_um": profile * 1.05}
    s = score_pairs(pred, centre, profile, grid)
    assert s["centre"] == pytest.approx([0.05, 0.095, 0.099, 0.1, 0.1])
    # edge errors 0 and 0.25; on the field's scale 2 / max(4, 8)
    assert s["edge"][3] == pytest.approx(0.25) and s["edge"][4] == pytest.approx(0.25)
    assert s["profile_all"] == pytest.approx([0.05, 0.05])
    assert "centre_coverage95" not in s
    # a model on its own 0-20 mm grid (every 5 mm): scored on the shared points only
    pred["profile_um"] = np.array([[1.0, 9.0, 1.0, 9.0, 1.0], [8.0, 9.0, 4.0, 9.0, 2.0]])
    pred["grid_mm"] = np.array([0.0, 5.0, 10.0, 15.0, 20.0])
    s = score_pairs(pred, centre, profile, grid)
    assert "profile_all" not in s and s["profile_0_20mm"] == pytest.approx([0.0, 0.0])
