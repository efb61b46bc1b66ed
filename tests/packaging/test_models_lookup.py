"""surrogate.runtime.models: a model by path, by name on HAPTICROM_MODEL_PATH or in the source
checkout, the right loaded type per card kind, and a clear error naming where it looked."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from surrogate.runtime import EnvelopeModel, ModelFileError, Predictor, load_model
from surrogate.runtime.models import MODEL_PATH_ENV, find_model, list_models

REPO = Path(__file__).resolve().parents[2]


def test_by_path_and_by_name_in_the_checkout(monkeypatch):
    monkeypatch.delenv(MODEL_PATH_ENV, raising=False)
    assert find_model(REPO / "models/nn-default") == REPO / "models/nn-default"
    assert find_model("nn-default").resolve() == (REPO / "models/nn-default").resolve()
    assert isinstance(load_model("nn-default"), Predictor)
    assert isinstance(load_model(str(REPO / "models/rom-default")), EnvelopeModel)
    assert {"nn-default", "gp-default", "rom-default"} <= set(list_models())


def test_model_path_env_comes_first(monkeypatch, tmp_path):
    shutil.copytree(REPO / "models/nn-default", tmp_path / "nn-default")
    monkeypatch.setenv(MODEL_PATH_ENV, str(tmp_path))
    assert find_model("nn-default") == tmp_path / "nn-default"
    (tmp_path / "nn-default" / "stray.txt").write_text("x")
    with pytest.raises(ModelFileError, match=r"stray\.txt"):  # verified when loaded
        load_model("nn-default")


def test_unknown_name_says_where_it_looked(monkeypatch, tmp_path):
    monkeypatch.setenv(MODEL_PATH_ENV, str(tmp_path))
    with pytest.raises(ModelFileError, match=r"nn-defualt.*not found") as err:
        find_model("nn-defualt")
    assert err.value.field == "model"
    assert str(tmp_path) in str(err.value) and "nn-default" in str(err.value)
    with pytest.raises(ModelFileError, match="not found"):
        find_model(tmp_path / "nothing-here")
