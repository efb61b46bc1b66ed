"""A sweep model's card scored on fresh designs (``hapticrom train --test-data``): the test set
entry names its datasets (digest, seed, size) and holds the held-out metrics' figures on every
test design; a test set that repeats the training designs or another band is refused."""

from __future__ import annotations

import json

import pytest
from sweep_fixture import coarse_space_dict, make_dataset

from fieldspec import FieldError
from hapticrom.cli import main
from surrogate.registry import manifest_sha256
from surrogate.runtime.predictor import load_predictor
from surrogate.sweep.scoring import load_test_data, score_test_set
from surrogate.sweep.targets import load_sweep_datasets
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
