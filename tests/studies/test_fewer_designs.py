"""Learning from fewer, better designs (studies.fewer_designs, bench/surrogate/refine_sweep.py)
on a synthetic sweep dataset (no FE): the active arm adds the pool designs the start model is
least sure of, the Sobol arm the next designs of the sequence, every model is scored on the
test designs and reused on a rerun; stacking appends a model's predictions as features."""

from __future__ import annotations

import json

import numpy as np
import pytest
from sweep_fixture import OPTIONS, make_dataset

from studies.fewer_designs import active, multifidelity
from studies.output_choice import data as sweeps
from surrogate.refine import band_disagreement
from surrogate.runtime.encoding import encode
from surrogate.runtime.predictor import load_predictor, make_session
from surrogate.sweep.export import export_sweep_nn
from surrogate.sweep.nn import fit_sweep
from surrogate.sweep.targets import load_sweep_datasets


@pytest.fixture(scope="module")
def test_set(tmp_path_factory):
    return make_dataset(tmp_path_factory.mktemp("sweep-test") / "t", 12, seed=7)


@pytest.fixture(scope="module")
def study(sweep_dataset, test_set, tmp_path_factory):
    out = tmp_path_factory.mktemp("refine-sweep")
    record = active.run(sweep_dataset, [test_set], out, start=24, add=12,
                        options=dict(OPTIONS), seeds=(0,), active_seeds=(0,),
                        test_fraction=0.2, log=lambda s: None)
    return out, record


def test_the_active_arm_adds_the_pool_designs_the_start_model_is_least_sure_of(sweep_dataset,
                                                                              study):
    out, record = study
    assert set(record["models"]) == {"start", "sobol-seed0", "active-seed0"}
    picked = np.asarray(json.loads((out / "active_picks.json").read_text())["picked"])
    assert picked.size == 12 and np.unique(picked).size == 12
    assert picked.min() >= 24 and picked.max() < 48  # from the pool only
    data = load_sweep_datasets([sweep_dataset])
    score = band_disagreement(load_predictor(out / "start", calibrated=False),
                              data.codes[24:], data.band_hz)
    # the picks are more uncertain than the pool on average, and the least uncertain design
    # of the pool is never picked
    assert score[picked - 24].mean() > score.mean()
    assert np.argmin(score) + 24 not in picked
    sel = record["selection"]
    assert sel["score_mean"]["picked"] == pytest.approx(score[picked - 24].mean())
    assert set(sel["composition"]["picked"]) >= {"pogo", "rings_0", "rings_3"}
    for name, m in record["models"].items():
        assert m["designs"] == (24 if name == "start" else 36)
        assert all(np.isfinite(v) and v >= 0 for v in m["test"].values())
    table = active.table(record)
    assert table.count("\n") == 1 + len(record["models"])
    assert "| active-seed0 | 36 |" in table
    by = record["models"]["sobol-seed0"]["by_attachment"]
    assert set(by) == {"glued", "pogo"}
    assert by["glued"]["designs"] + by["pogo"]["designs"] == 12
    assert active.attachment_table(record).count("\n") == 1 + len(record["models"])


def test_each_arm_trains_on_its_designs_only_and_a_rerun_reuses_the_models(sweep_dataset,
                                                                         test_set, study):
    out, record = study
    sobol = json.loads((out / "sobol-seed0" / "card.json").read_text())
    assert sobol["training"]["design_subset"]["ranges"] == [[0, 36]]
    assert sobol["test_set"]["designs"] == 12
    act = json.loads((out / "active-seed0" / "card.json").read_text())
    picked = json.loads((out / "active_picks.json").read_text())["picked"]
    kept = [i for a, b in act["training"]["design_subset"]["ranges"] for i in range(a, b)]
    assert kept == sorted([*range(24), *picked])
    said = []
    again = active.run(sweep_dataset, [test_set], out, start=24, add=12, options=dict(OPTIONS),
                       seeds=(0,), active_seeds=(0,), test_fraction=0.2, log=said.append)
    assert again["models"] == record["models"]
    assert all("reusing" in s for s in said)
    with pytest.raises(ValueError, match="start = 40, add = 12"):
        active.run(sweep_dataset, [test_set], out, start=40, add=12)


def test_spread_rows_show_the_range_over_seeds():
    m = {k: 0.1 for k, *_ in active.METRICS}
    record = {"models": {"sobol-seed0": {"designs": 3, "test": m},
                         "sobol-seed1": {"designs": 3, "test": {**m, "centre p95": 0.25}}}}
    spread = active.table(record).splitlines()[-1]
    assert spread.startswith("| sobol: spread over 2 seeds |")
    assert "| 15.0 |" in spread and spread.count("| 0.00 ") == len(active.METRICS) - 1


def test_stacking_appends_the_low_fidelity_predictions_as_features(sweep_dataset, sweep_model,
                                                                   test_set):
    sw, specs = sweeps.load(str(sweep_dataset))
    codes = multifidelity.design_codes(sweep_dataset, specs)
    feats, outside = multifidelity.low_features(sweep_model, codes, specs, (100.0, 250.0))
    assert feats.shape == (len(sw), 4) and outside == 0.0
    p = load_predictor(sweep_model)
    names = {s.name: j for j, s in enumerate(specs)}
    one = p.predict({n: ([specs[names[n]].choices[int(codes[3, names[n]])]]
                         if specs[names[n]].type == "categorical" else [codes[3, names[n]]])
                     if n != "frequency_hz" else [250.0] for n in p.input_names})
    assert feats[3, 1] == pytest.approx(np.log(one["center_amplitude_um"][0]), rel=1e-6)
    assert feats[3, 3] == pytest.approx(np.log(one["edge_amplitude_um"][0]), rel=1e-6)
    more = multifidelity.stacked(sw, feats)
    assert more.x.shape == (len(sw), sw.x.shape[1] + 4)
    np.testing.assert_array_equal(more.x[:, :sw.x.shape[1]], sw.x)
    with pytest.raises(ValueError, match="feature rows"):
        multifidelity.stacked(sw, feats[:3])
    # the model was trained on the sweep dataset: its own designs overlap, the test set's not
    test_codes = multifidelity.design_codes(test_set, specs)
    assert multifidelity.overlap(sweep_model, codes, specs)["identical"] == len(codes)
    assert multifidelity.overlap(sweep_model, test_codes, specs)["identical"] == 0


def test_the_stacked_study_scores_the_same_learner_with_and_without(sweep_dataset, sweep_model,
                                                                    test_set):
    record = multifidelity.run(sweep_dataset, test_set, sweep_model, sizes=(24,),
                               freqs_hz=(100.0, 200.0), modes=6, profile_modes=4,
                               log=lambda s: None)
    rows = record["records"]
    assert [(r["learner"], r["size"], r["inputs"]) for r in rows] == [
        ("nn-sweep-fixture", None, "alone"), ("mlp", 24, "design"),
        ("mlp", 24, "design + low-fidelity")]
    assert record["overlap"]["identical"] == 0
    assert all(np.isfinite(r["centre_median"]) for r in rows)
    assert rows[0]["profile_l2_median"] is None
    assert multifidelity.table(record).count("\n") == 1 + len(rows)


def test_the_sweep_nn_learns_with_the_stacked_features_and_answers_as_its_graph(
        sweep_dataset, sweep_model, test_set):
    data = load_sweep_datasets([sweep_dataset])
    designs = np.arange(30)
    est, targets = fit_sweep(data, designs, options=dict(OPTIONS))
    X = encode(data.codes[30:], data.specs)
    got = multifidelity.sweep_nn_answers(est, targets, X, chunk=5)
    session = make_session(export_sweep_nn(est, targets, False, data.band_hz[0],
                                           data.band_hz[-1], data.band_hz, {}))
    n_f = data.band_hz.size
    f = (data.band_hz - data.band_hz[0]) / (data.band_hz[-1] - data.band_hz[0])
    x = np.column_stack([np.repeat(X, n_f, axis=0), np.tile(f, len(X))]).astype(np.float32)
    log_mean = session.run(["log_mean"], {"x": x})[0].reshape(len(X), n_f, -1)
    np.testing.assert_allclose(np.log(got.center), log_mean[..., 0], atol=1e-4)
    np.testing.assert_allclose(np.log(got.edge), log_mean[..., 1], atol=1e-4)
    np.testing.assert_allclose(np.log(got.profile), log_mean[..., 3:], atol=1e-4)
    with pytest.raises(ValueError, match="features: 3 rows for 48 designs"):
        fit_sweep(data, designs, options=dict(OPTIONS), features=np.ones((3, 2)))
    record = multifidelity.run(sweep_dataset, test_set, sweep_model, sizes=(30,),
                               freqs_hz=(150.0,), learner_names=("sweep-nn",),
                               nn_options=dict(OPTIONS), log=lambda s: None)
    rows = record["records"][1:]
    assert [(r["learner"], r["inputs"], r["train_rows"]) for r in rows] == [
        ("sweep NN", "design", 27), ("sweep NN", "design + low-fidelity", 27)]
    assert all(np.isfinite(r["centre_p95"]) and r["profile_l2_median"] > 0 for r in rows)
    with pytest.raises(ValueError, match="allowed mlp-peer, sweep-nn"):
        multifidelity.run(sweep_dataset, test_set, sweep_model, learner_names=("gp",))
