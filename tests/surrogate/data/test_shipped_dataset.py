"""The shipped dataset is valid, was made by this solver, and re-solving rows reproduces it."""

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from fem import simulate
from fem.scene import scene_from_dict
from surrogate.data.inspect import validate_dataset
from surrogate.data.provenance import solver_info

SHIPPED = Path(__file__).resolve().parents[3] / "datasets" / "default"


def test_shipped_dataset_is_valid_and_complete():
    assert validate_dataset(SHIPPED) == []
    manifest = json.loads((SHIPPED / "_manifest.json").read_text())
    df = pd.read_parquet(SHIPPED)
    assert len(df) == manifest["sampling"]["target_n"] == 4096
    assert (df["status"] == "ok").all()
    assert df["sample_id"].is_unique


def test_shipped_dataset_records_its_solver():
    manifest = json.loads((SHIPPED / "_manifest.json").read_text())
    assert manifest["solver"]["version"] == solver_info(git=False)["version"]


@pytest.mark.parametrize("row", [0, 1777, 4095])
def test_resolving_a_shipped_row_reproduces_it(row):
    """The real guarantee that the shipped data comes from this solver: stored rows re-solve
    to the same numbers. If this fails, the solver's answers changed: regenerate with the
    command in datasets/README.md."""
    df = pd.read_parquet(SHIPPED)
    stored = df.sort_values("sample_index").iloc[row]
    res = simulate(scene_from_dict(json.loads(stored["scene_json"])))
    assert res.normalized_edge == pytest.approx(stored["normalized_edge"], rel=1e-7)
    assert res.center_amplitude_um == pytest.approx(stored["center_amplitude_um"], rel=1e-7)
    profile_um = np.linalg.norm(np.abs(res.profile), axis=1) * 1e6
    assert np.allclose(profile_um, stored["profile_magnitude_um"], rtol=1e-7)
