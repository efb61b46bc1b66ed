"""NN models trained on sweep datasets: the complex band in, the one graph contract out."""

from __future__ import annotations

import json

import numpy as np
import pytest
from synthetic import make_dataset
from synthetic_sweep import BAND_HZ, GRID_MM, make_sweep_dataset

from fieldspec import FieldError
from surrogate.runtime.encoding import PredictorInputError, encode
from surrogate.runtime.predictor import Predictor, load_predictor, make_session
from surrogate.sweep.export import export_sweep_nn, member_targets, reference_log_outputs
from surrogate.sweep.nn import fit_sweep
from surrogate.sweep.targets import (
    BandTargets,
    check_not_mixed,
    load_sweep_datasets,
    log_magnitudes,
)
from surrogate.sweep.train import train_sweep
from surrogate.train import split

OPTIONS = {"hidden": (16, 16), "n_members": 3, "max_epochs": 60, "centre_modes": 6,
           "refit_epochs": 4, "refit_patience": 2}
OUTPUTS = ("profile_um", "profile_normal_um")


@pytest.fixture(scope="module")
def sweep_data(tmp_path_factory):
    return make_sweep_dataset(tmp_path_factory.mktemp("sweep") / "d", 48)


@pytest.fixture(scope="module")
def sweep_model(sweep_data, tmp_path_factory):
    out = tmp_path_factory.mktemp("models") / "nn-sweep"
    card = train_sweep([sweep_data], "nn", out, n_modes=8, options=dict(OPTIONS),
                       outputs=OUTPUTS)
    return out, card


@pytest.fixture(scope="module")
def refitted(sweep_data, sweep_model):
    """The same fit again in memory, exported, behind the trained model's card: (predictor,
    estimator, targets, data)."""
    data = load_sweep_datasets([sweep_data])
    tr, _ = split(len(data.codes), 0.2, 0)
    est, targets = fit_sweep(data, tr, n_modes=8, normal=True, options=dict(OPTIONS))
    onnx = export_sweep_nn(est, targets, True, BAND_HZ[0], BAND_HZ[-1], data.band_hz, {})
    card = json.loads((sweep_model[0] / "card.json").read_text())
    return Predictor(card, make_session(onnx)), est, targets, data


def _inputs(data, designs, f_hz):
    return {"orientation": data.codes[designs, 0], "skin_E_kPa": data.codes[designs, 1],
            "fat_thickness_mm": data.codes[designs, 2], "frequency_hz": np.full(designs.size, f_hz)}


def test_band_targets_rebuild_the_band_exactly_with_every_mode(sweep_data):
    data = load_sweep_datasets([sweep_data])
    t = BandTargets(centre_modes=1000, profile_modes=1000, spatial_tol=0.0)
    T = t.fit_transform(data.response)
    ln_s, z = t.components(T)
    got = log_magnitudes(z, ln_s[:, None])
    np.testing.assert_allclose(got, log_magnitudes(data.response), atol=1e-9)
    assert t.to_dict()["pod_modes"] == {"centre_edge": 47, "profile": 47}


def test_a_sweep_model_loads_through_the_runtime_predictor(sweep_model, sweep_data):
    path, card = sweep_model
    p = load_predictor(path)
    assert p.input_names == ("orientation", "skin_E_kPa", "fat_thickness_mm", "frequency_hz")
    assert p.input_ranges["frequency_hz"] == (100.0, 250.0)
    np.testing.assert_array_equal(p.profile_distance_mm, GRID_MM)
    out = p.predict({"orientation": ["forward", "reverse"], "skin_E_kPa": [40.0, 90.0],
                     "fat_thickness_mm": [5.0, 12.0], "frequency_hz": [123.4, 200.0]})
    assert out["profile_um"].shape == (2, GRID_MM.size)
    assert out["profile_normal_um"].shape == (2, GRID_MM.size)
    np.testing.assert_allclose(out["edge_amplitude_um"], out["profile_um"][:, 0], rtol=1e-6)
    np.testing.assert_array_equal(out["edge_radius_mm"], [5.5, 6.0])
    assert card["representation"]["name"] == "complex-band-pod"
    assert card["representation"]["spatial_rel_error"]["profile"] <= 1e-3
    assert card["training"]["split"] == "by design"
    assert card["training"]["held_out_pairs"] == card["training"]["held_out"] * BAND_HZ.size
    assert card["training_data"][0]["manifest_sha256"]
    assert card["export_parity_max_abs_dln"] <= 1e-4
    m = card["metrics"]["center_amplitude_um"]
    assert {"median_rel_err", "p95_rel_err", "p99_rel_err", "max_rel_err",
            "max_abs_err_over_field", "coverage95"} <= set(m)


def test_at_a_band_frequency_the_graph_equals_the_numpy_rebuild(refitted):
    predictor, est, targets, data = refitted
    designs = np.arange(0, 48, 5)
    X = encode(data.codes[designs], data.specs)
    for i in (0, 7, 15):
        out = predictor.predict(_inputs(data, designs, BAND_HZ[i]))
        mean, std = reference_log_outputs(targets, member_targets(est, X),
                                          np.full(designs.size, i), normal=True)
        m = GRID_MM.size
        for name, cols in (("center_amplitude_um", 0), ("edge_amplitude_um", 1),
                           ("normalized_edge", 2), ("profile_um", slice(3, 3 + m)),
                           ("profile_normal_um", slice(3 + m, 3 + 2 * m))):
            np.testing.assert_allclose(np.log(out[name]), mean[:, cols], atol=2e-5)
            np.testing.assert_allclose(out[f"{name}_log_std"], std[:, cols], atol=2e-5)


def test_between_grid_points_a_response_linear_in_frequency_is_exact(refitted):
    predictor, est, targets, data = refitted
    designs = np.arange(1, 48, 7)
    y = member_targets(est, encode(data.codes[designs], data.specs))
    ln_s, z = targets.components(y)                  # (M, n), (M, n, n_f, P, 6)
    for f in (101.0, 137.3, 249.9):
        s = (f - BAND_HZ[0]) / (BAND_HZ[-1] - BAND_HZ[0])
        zf = z[:, :, 0] + s * (z[:, :, -1] - z[:, :, 0])  # the line through the band's ends
        want = log_magnitudes(zf, ln_s).mean(axis=0)
        out = predictor.predict(_inputs(data, designs, f))
        np.testing.assert_allclose(np.log(out["center_amplitude_um"]), want[:, 0], atol=5e-5)
        np.testing.assert_allclose(np.log(out["profile_um"]), want[:, 1:], atol=5e-5)


def test_a_frequency_outside_the_band_is_refused_naming_it(sweep_model):
    p = load_predictor(sweep_model[0])
    point = {"orientation": ["forward"], "skin_E_kPa": [50.0], "fat_thickness_mm": [8.0]}
    with pytest.raises(PredictorInputError) as err:
        p.predict({**point, "frequency_hz": [260.0]})
    assert err.value.field == "frequency_hz" and "100 <= frequency_hz <= 250 Hz" in str(err.value)
    clamped = p.predict({**point, "frequency_hz": [260.0]}, extrapolate=True)
    edge = p.predict({**point, "frequency_hz": [250.0]})
    assert clamped["extrapolated"][0]
    np.testing.assert_allclose(clamped["profile_um"], edge["profile_um"], rtol=1e-6)


def test_sweep_and_single_frequency_data_mixed_are_refused(sweep_data, tmp_path):
    single = make_dataset(tmp_path / "single", 8)
    out = tmp_path / "m"
    with pytest.raises(FieldError, match="mixes sweep and single-frequency") as err:
        check_not_mixed([sweep_data, single])
    assert err.value.field == "--data"
    assert check_not_mixed([sweep_data]) and not check_not_mixed([single])
    from hapticrom.cli import main
    assert main(["train", "--data", str(single), str(sweep_data), "--kind", "nn",
                 "--out", str(out)]) == 2
    assert not out.exists()


def test_other_kinds_and_bad_sweep_options_are_refused(sweep_data, tmp_path):
    with pytest.raises(FieldError, match="sweep datasets train the gp and nn kinds") as err:
        train_sweep([sweep_data], "mlp", tmp_path / "g")
    assert err.value.field == "--kind"
    with pytest.raises(ValueError, match="loss = 'l1': allowed 'magnitude', 'coefficients'"):
        train_sweep([sweep_data], "nn", tmp_path / "n", options={"loss": "l1"})
    with pytest.raises(ValueError, match="spatial_tol = 2: allowed"):
        train_sweep([sweep_data], "nn", tmp_path / "n", options={"spatial_tol": 2})
    assert not (tmp_path / "g").exists() and not (tmp_path / "n").exists()


def test_intervals_of_a_sweep_model_calibrate_on_its_held_out_designs(sweep_data, sweep_model,
                                                                     tmp_path):
    from surrogate.calibrate_intervals import calibrate_model_dir

    # the designs are the exchangeable units: 5 calibration designs cannot give a 95 % factor
    with pytest.raises(ValueError, match="5 calibration groups: a 95% factor needs more than 19"):
        calibrate_model_dir(sweep_model[0], write=False)
    half = tmp_path / "nn-sweep-half"  # 24 designs held out: 22 calibrate, 2 check
    card = train_sweep([sweep_data], "nn", half, n_modes=8, options=dict(OPTIONS),
                       outputs=OUTPUTS, test_fraction=0.5)
    entry = calibrate_model_dir(half, write=False, check_fraction=0.1)
    assert entry["method"] == "hierarchical split-conformal"
    assert entry["groups"]["center"]["groups"] == 22
    rows = entry["rows"]
    assert rows["calibration"] + rows["check"] == card["training"]["held_out"]
    assert rows["pairs_per_design"] == BAND_HZ.size
    assert set(entry["groups"]) == {"center", "edge", "profile", "profile_normal_um"}
    assert 0.0 <= entry["coverage95_check"]["after"]["center_amplitude_um"] <= 1.0


def test_a_design_subset_trains_on_those_designs_only_and_the_card_names_them(sweep_data,
                                                                             tmp_path):
    designs = np.r_[0:20, 30:40]
    card = train_sweep([sweep_data], "nn", tmp_path / "sub", n_modes=8, options=dict(OPTIONS),
                       designs=designs)
    training = card["training"]
    assert training["rows"] + training["held_out"] == designs.size
    assert training["design_subset"]["ranges"] == [[0, 20], [30, 40]]
    assert training["design_subset"]["of"] == 48
    for bad in ([0, 0, 1], [47, 48], []):
        with pytest.raises(FieldError, match="designs: need distinct integer row positions"
                           ) as err:
            train_sweep([sweep_data], "nn", tmp_path / "bad", options=dict(OPTIONS),
                        designs=bad)
        assert err.value.field == "designs"
    assert not (tmp_path / "bad").exists()


def test_band_disagreement_is_the_raw_log_std_of_centre_and_edge_over_the_band(sweep_data,
                                                                              sweep_model):
    from surrogate.refine import band_disagreement

    data = load_sweep_datasets([sweep_data])
    p = load_predictor(sweep_model[0], calibrated=False)
    got = band_disagreement(p, data.codes[:5], data.band_hz, chunk=2)
    pred = p.predict(np.column_stack([np.repeat(data.codes[:5], BAND_HZ.size, axis=0),
                                      np.tile(data.band_hz, 5)]))
    want = 0.5 * (pred["center_amplitude_um_log_std"] + pred["edge_amplitude_um_log_std"])
    np.testing.assert_allclose(got, want.reshape(5, -1).mean(axis=1), rtol=1e-12)
    assert np.all(got > 0)
