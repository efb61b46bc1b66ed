"""The shipped dataset is valid, was made by this solver, and re-solving rows reproduces it."""

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from fem.scene import scene_from_dict
from fem.simulate import simulate
from surrogate.store import solver_info, validate_dataset

SHIPPED = Path(__file__).resolve().parents[1] / "datasets" / "default"


def test_shipped_dataset_is_valid_and_complete():
    assert validate_dataset(SHIPPED) == []
    manifest = json.loads((SHIPPED / "_manifest.json").read_text())
    df = pd.read_parquet(SHIPPED)
    assert len(df) == manifest["sampling"]["target_n"] == 2048
    assert (df["status"] == "ok").all()
    assert df["sample_id"].is_unique


def test_shipped_dataset_matches_this_solver():
    """If this fails, the solver changed: regenerate with the command in datasets/README.md."""
    manifest = json.loads((SHIPPED / "_manifest.json").read_text())
    assert manifest["solver"]["source_sha256"] == solver_info(git=False)["source_sha256"]


@pytest.mark.parametrize("row", [0, 777, 2047])
def test_resolving_a_shipped_row_reproduces_it(row):
    df = pd.read_parquet(SHIPPED)
    stored = df.sort_values("sample_index").iloc[row]
    res = simulate(scene_from_dict(json.loads(stored["scene_json"])))
    assert res.normalized_edge == pytest.approx(stored["normalized_edge"], rel=1e-9)
    assert res.center_amplitude_um == pytest.approx(stored["center_amplitude_um"], rel=1e-9)
    d = res.to_dict()["profile"]
    assert np.allclose(d["magnitude_um"], stored["profile_magnitude_um"], rtol=1e-9)
