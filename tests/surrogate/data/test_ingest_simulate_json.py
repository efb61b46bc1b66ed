"""`hapticrom simulate --json` results ingest as profiles, in the version-1 layout and in the
unversioned layout before it (readable for one release)."""

from __future__ import annotations

import json
from pathlib import Path

import pandas as pd
import pytest
from test_ingest import BASE, SPACE

from fem import simulate
from fem.scene import scene_from_dict
from surrogate.data.errors import DatasetError
from surrogate.data.ingest import ingest_profile
from surrogate.data.space import space_from_dict

VALUES = {"skin_E_kPa": "49", "frequency_hz": "120", "side": "absorbing"}


@pytest.fixture(scope="module")
def result():
    return simulate(scene_from_dict(BASE))


@pytest.mark.parametrize("layout", ["v1", "v0"])
def test_simulate_json_ingests_in_both_layouts(tmp_path: Path, result, layout) -> None:
    doc = result.to_dict("b.toml") if layout == "v1" else result.to_dict_v0()
    path = tmp_path / f"run-{layout}.json"
    path.write_text(json.dumps(doc))
    rep = ingest_profile(path, tmp_path / "ds", VALUES, space_from_dict(SPACE))
    assert rep.added == 1
    row = pd.read_parquet(tmp_path / "ds").iloc[0]
    assert row["center_amplitude_um"] == pytest.approx(result.center_amplitude_um)
    assert row["edge_amplitude_um"] == pytest.approx(result.edge_amplitude_um, rel=1e-9)
    assert list(row["profile_distance_mm"]) == pytest.approx(list(result.profile_mm))


def test_a_result_of_another_kind_or_version_is_refused(tmp_path: Path, result) -> None:
    doc = result.to_dict()
    doc["schema_version"] = 9
    path = tmp_path / "future.json"
    path.write_text(json.dumps(doc))
    with pytest.raises(DatasetError, match="schema_version = 9"):
        ingest_profile(path, tmp_path / "ds", VALUES, space_from_dict(SPACE))
    assert not (tmp_path / "ds").exists()
