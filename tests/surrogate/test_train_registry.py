"""Training on a small dataset, registry round trip, hash tampering, export parity."""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest
from synthetic import GRID_MM, synthetic_amplitudes

from surrogate.runtime import ModelFileError, load_predictor


@pytest.mark.parametrize("kind", ["nn", "gp"])
def test_trained_model_learns_the_synthetic_answer(trained_models, kind):
    path, card = trained_models[kind]
    m = card["metrics"]
    # a smooth 4-input function from ~77 rows: a few percent at most
    assert m["center_amplitude_um"]["median_rel_err"] < 0.05
    assert m["profile_um"]["median_rel_l2"] < 0.05
    p = load_predictor(path)
    X = {"orientation": np.array(["forward", "reverse"]), "n_rings": np.array([0, 2]),
         "skin_E_kPa": np.array([30.0, 90.0]), "frequency_hz": np.array([120.0, 200.0])}
    out = p.predict(X)
    center, profile = synthetic_amplitudes(X["orientation"], X["n_rings"].astype(float),
                                           X["skin_E_kPa"], X["frequency_hz"])
    np.testing.assert_allclose(out["center_amplitude_um"], center, rtol=0.1)
    np.testing.assert_allclose(out["profile_um"], profile, rtol=0.15)
    # derived outputs are defined once: edge = profile at distance 0, normalized = edge/center
    np.testing.assert_allclose(out["edge_amplitude_um"], out["profile_um"][:, 0], rtol=1e-5)
    np.testing.assert_allclose(out["normalized_edge"],
                               out["edge_amplitude_um"] / out["center_amplitude_um"], rtol=1e-5)
    assert out["profile_um"].shape == (2, GRID_MM.size)
    assert np.all(out["center_amplitude_um_log_std"] >= 0)


@pytest.mark.parametrize("kind", ["nn", "gp"])
def test_edge_radius_is_exact(trained_models, kind):
    """Edge radius comes from a table keyed by n_rings: exactly the solver's outer radius."""
    from synthetic import SPACE

    from fem.scene import scene_from_dict
    from surrogate.data.space import space_from_dict

    path, card = trained_models[kind]
    assert card["edge_radius"]["inputs"] == ["n_rings"]
    space = space_from_dict(SPACE)
    p = load_predictor(path)
    for n in (0, 1, 2):
        row = {"orientation": "forward", "n_rings": n, "skin_E_kPa": 50.0,
               "frequency_hz": 150.0}
        want = scene_from_dict(space.resolve(row)).unit.outer_radius_mm
        got = p.predict({k: np.array([v]) for k, v in row.items()})["edge_radius_mm"][0]
        assert got == want


@pytest.mark.parametrize("kind", ["nn", "gp"])
def test_card_contents(trained_models, kind):
    path, _card = trained_models[kind]
    on_disk = json.loads((path / "card.json").read_text())
    assert on_disk["kind"] == kind
    assert set(on_disk["files"]) == {"model.onnx"}
    assert len(on_disk["training_data"][0]["manifest_sha256"]) == 64
    assert {i["name"] for i in on_disk["inputs"]} == {"orientation", "n_rings", "skin_E_kPa",
                                                      "frequency_hz"}
    assert on_disk["export_parity_max_abs_dln"] <= 1e-4
    assert "onnxruntime" in on_disk["versions"]
    import onnx

    meta = {p.key: p.value for p in onnx.load(str(path / "model.onnx")).metadata_props}
    assert meta["kind"] == kind
    assert json.loads(meta["inputs"])[2]["unit"] == "kPa"


def test_tampered_file_is_rejected(trained_models, tmp_path):
    src, _ = trained_models["nn"]
    bad = tmp_path / "bad"
    shutil.copytree(src, bad)
    data = bytearray((bad / "model.onnx").read_bytes())
    data[-1] ^= 1
    (bad / "model.onnx").write_bytes(bytes(data))
    with pytest.raises(ModelFileError, match="sha256"):
        load_predictor(bad)


def test_unlisted_and_missing_files_are_rejected(trained_models, tmp_path):
    src, _ = trained_models["gp"]
    extra = tmp_path / "extra"
    shutil.copytree(src, extra)
    (extra / "evil.pkl").write_bytes(b"x")
    with pytest.raises(ModelFileError, match="not listed"):
        load_predictor(extra)
    missing = tmp_path / "missing"
    shutil.copytree(src, missing)
    (missing / "model.onnx").unlink()
    with pytest.raises(ModelFileError, match="missing"):
        load_predictor(missing)


def test_write_model_refuses_to_overwrite(trained_models, synthetic_dataset):
    from surrogate.train import train

    path, _ = trained_models["nn"]
    with pytest.raises(FileExistsError):
        train([synthetic_dataset], "nn", path)


def test_training_is_reproducible(synthetic_dataset, tmp_path):
    from surrogate.train import train

    opts = {"max_epochs": 50, "n_members": 2, "hidden": (8,)}
    a = train([synthetic_dataset], "nn", tmp_path / "a", options=opts, n_modes=2)
    b = train([synthetic_dataset], "nn", tmp_path / "b", options=opts, n_modes=2)
    assert a["metrics"] == b["metrics"]


def test_rows_are_read_in_design_order_whatever_the_part_order(tmp_path):
    from synthetic import make_dataset

    from surrogate.train import load_datasets

    ordered = load_datasets([make_dataset(tmp_path / "a", 12)])
    shuffled = load_datasets([make_dataset(tmp_path / "b", 12, reverse=True)])
    assert np.array_equal(ordered.codes, shuffled.codes)
    assert np.array_equal(ordered.center_um, shuffled.center_um)


def test_two_datasets_train_together(synthetic_dataset, tmp_path):
    from synthetic import make_dataset

    from surrogate.train import load_datasets

    other = make_dataset(tmp_path / "more", 16, start=200)
    data = load_datasets([synthetic_dataset, other])
    assert len(data.codes) == 96 + 16
    assert [s["rows"] for s in data.sources] == [96, 16]
