"""Parquet store: round trip through pandas, atomic parts, locking, validate and merge."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pyarrow.parquet as pq
import pytest

from surrogate.data.errors import DatasetError
from surrogate.data.inspect import merge_datasets, validate_dataset
from surrogate.data.provenance import FINGERPRINT_SCENES, same_solver, solver_info
from surrogate.data.space import space_from_dict
from surrogate.data.store import (
    FEM_SOURCE,
    LOCK_NAME,
    MANIFEST_NAME,
    Store,
    arrow_schema,
    profile_matrix,
)

SPACE = {
    "space": {"name": "store-test", "seed": 1},
    "base": {"analysis": {"kind": "harmonic"}},
    "parameter": [
        {"name": "skin_E_kPa", "type": "continuous", "path": "tissue.layer[0].E_kPa",
         "low": 20.0, "high": 120.0},
        {"name": "n_layers", "type": "integer", "path": "output.radii_mm", "map": "list_length",
         "low": 1, "high": 3},
        {"name": "side", "type": "categorical", "path": "tissue.side",
         "choices": ["absorbing", "fixed"]},
        {"name": "pml", "type": "categorical", "path": "x.flag", "choices": [True, False]},
    ],
}
SOLVER = {"version": "9.9", "source_sha256": "ab" * 32, "hash": "ab" * 6,
          "git_revision": "deadbeef"}


def _space() -> Any:
    return space_from_dict(SPACE, check_scenes=False)


def _row(i: int, status: str = "ok", source: str = FEM_SOURCE, **kw: Any) -> dict[str, Any]:
    grid = [0.0, 1.0, 2.0]
    row = {"sample_id": f"id{i:04d}", "sample_index": i, "status": status, "source": source,
           "wall_s": 0.01 * i, "dofs": 100 + i, "elements": 50, "solver_version": "9.9",
           "solver_hash": SOLVER["hash"], "scene_json": "{}", "skin_E_kPa": 20.0 + i,
           "n_layers": 1 + i % 3, "side": "fixed" if i % 2 else "absorbing", "pml": i % 2 == 0,
           "center_amplitude_um": 10.0 + i, "edge_amplitude_um": 5.0 + i,
           "normalized_edge": (5.0 + i) / (10.0 + i), "profile_distance_mm": grid,
           "profile_uz_um": [3.0, 2.0, 1.0], "profile_magnitude_um": [5.0 + i, 4.0, 3.0]}
    if status == "failed":
        row.update(error="ValueError: boom", center_amplitude_um=None, edge_amplitude_um=None,
                   normalized_edge=None, profile_distance_mm=None, profile_magnitude_um=None,
                   profile_uz_um=None)
    row.update(kw)
    return row


def _store(path: Path, rows: list[dict[str, Any]] | None = None, solver: dict | None = None
           ) -> Store:
    solver = solver or SOLVER
    store = Store.create(path, _space(), solver=solver, solver_history=[solver],
                         sampling={"sampler": "sobol", "seed": 1}, profile_grid_mm=[0.0, 1.0, 2.0])
    if rows:
        with store.lock():
            store.write_part(rows, {"solver": solver})
    return store


def test_round_trip_through_one_line_of_pandas(tmp_path: Path) -> None:
    rows = [_row(i) for i in range(5)] + [_row(5, "failed")]
    store = _store(tmp_path / "d", rows[:3])
    with store.lock():
        store.write_part(rows[3:])
    # junk that must never be read as data: an unfinished part and the manifest/lock
    (tmp_path / "d" / ".part-000099.parquet.tmp").write_bytes(b"PAR1 not really")
    df = pd.read_parquet(tmp_path / "d").sort_values("sample_index").reset_index(drop=True)
    assert len(df) == 6
    assert list(df.columns) == arrow_schema(_space()).names
    assert df["skin_E_kPa"].tolist() == [20.0 + i for i in range(6)]
    assert df["n_layers"].dtype == np.int64 and df["pml"].dtype == bool
    assert df["side"].tolist() == ["absorbing", "fixed"] * 3
    np.testing.assert_array_equal(df.loc[2, "profile_magnitude_um"], [7.0, 4.0, 3.0])
    assert df.loc[5, "status"] == "failed" and df.loc[5, "error"] == "ValueError: boom"
    assert math.isnan(df.loc[5, "center_amplitude_um"])
    assert df["history_t_s"].isna().all()
    assert (store.path / MANIFEST_NAME).is_file()
    assert store.read().shape == df.shape


def test_reserved_names_are_exactly_the_store_columns() -> None:
    from surrogate.data.columns import COMPLEX_FIELDS, SWEEP_FIELDS
    from surrogate.data.parameters import RESERVED_COLUMNS
    from surrogate.data.store import OUTPUT_FIELDS, PROVENANCE_FIELDS

    assert {f.name for f in PROVENANCE_FIELDS + OUTPUT_FIELDS + COMPLEX_FIELDS
            + SWEEP_FIELDS} == RESERVED_COLUMNS


def test_parts_are_numbered_and_temp_files_removed(tmp_path: Path) -> None:
    store = _store(tmp_path / "d")
    tmp = tmp_path / "d" / ".part-000007.parquet.tmp"
    tmp.write_bytes(b"garbage")
    with store.lock():
        first = store.write_part([_row(0)])
        assert first.name == "part-000008.parquet"  # never reuses a temp file's number
        assert store.remove_temp_files() == [tmp]
        second = store.write_part([_row(1)])
    assert [p.name for p in store.parts()] == ["part-000008.parquet", "part-000009.parquet"]
    assert second.name == "part-000009.parquet" and not store.temp_files()
    meta = json.loads(pq.read_schema(first).metadata[b"hapticrom"])
    assert meta == {"space_hash": store.manifest["space_hash"]}  # only what every part records


def test_write_part_rejects_unknown_columns_and_bad_types(tmp_path: Path) -> None:
    store = _store(tmp_path / "d")
    with store.lock():
        with pytest.raises(DatasetError, match=r"unknown columns \['bogus'\]"):
            store.write_part([{**_row(0), "bogus": 1}])
        with pytest.raises((TypeError, ValueError)):
            store.write_part([{**_row(0), "skin_E_kPa": "soft"}])
    assert store.parts() == [] and store.temp_files() == []


def test_lock_is_exclusive(tmp_path: Path) -> None:
    store = _store(tmp_path / "d")
    other = Store.open(tmp_path / "d")
    with store.lock():
        with pytest.raises(DatasetError, match="another process"), other.lock():
            pass
    with other.lock():  # released
        pass
    assert not (tmp_path / "d" / LOCK_NAME).exists()  # no lock file left behind


def test_lock_file_is_removed_after_a_failure(tmp_path: Path) -> None:
    store = _store(tmp_path / "d")
    with pytest.raises(RuntimeError), store.lock():
        assert (tmp_path / "d" / LOCK_NAME).exists()
        raise RuntimeError("boom")
    assert not (tmp_path / "d" / LOCK_NAME).exists()
    with store.lock():  # and it can be taken again
        pass


def test_open_and_create_errors(tmp_path: Path) -> None:
    with pytest.raises(DatasetError, match="not a hapticrom dataset"):
        Store.open(tmp_path)
    (tmp_path / "file.txt").write_text("x")
    with pytest.raises(DatasetError, match="not an empty directory"):
        Store.create(tmp_path, _space())
    d = tmp_path / "d"
    _store(d)
    m = json.loads((d / MANIFEST_NAME).read_text())
    m["schema_version"] = 99
    (d / MANIFEST_NAME).write_text(json.dumps(m))
    with pytest.raises(DatasetError, match="schema_version 99 is not supported"):
        Store.open(d)


def test_keys_and_counts(tmp_path: Path) -> None:
    store = _store(tmp_path / "d", [_row(0), _row(1, "failed"), _row(2, source="ingest:x.csv")])
    keys, by_index = store.keys()
    assert keys == {(FEM_SOURCE, "id0000"), (FEM_SOURCE, "id0001"), ("ingest:x.csv", "id0002")}
    assert by_index == {0: "id0000", 1: "id0001"}
    c = store.counts()
    assert (c["rows"], c["ok"], c["failed"], c["parts"]) == (3, 2, 1, 1)
    assert c["by_source"] == {FEM_SOURCE: 2, "ingest:x.csv": 1}


def test_profile_matrix_interpolates_without_extrapolating() -> None:
    df = pd.DataFrame({"profile_distance_mm": [[0.0, 2.0, 4.0], [1.0, 3.0], None],
                       "profile_magnitude_um": [[4.0, 2.0, 0.0], [10.0, 30.0], None]})
    m = profile_matrix(df, [0.0, 1.0, 3.0, 5.0])
    np.testing.assert_allclose(m[0], [4.0, 3.0, 1.0, np.nan])
    np.testing.assert_allclose(m[1], [np.nan, 10.0, 30.0, np.nan])
    assert np.isnan(m[2]).all()


def test_validate_accepts_clean_and_reports_problems(tmp_path: Path) -> None:
    clean = _store(tmp_path / "clean", [_row(i) for i in range(4)] + [_row(4, "failed")])
    assert validate_dataset(clean.path) == []
    bad = _store(tmp_path / "bad", [_row(0), _row(1)])
    with bad.lock():
        bad.write_part([_row(0)])  # the same sample again
        bad.write_part([_row(2, "failed", error=None)])
        bad.write_part([_row(3, skin_E_kPa=500.0, side="wobbly")])
        bad.write_part([_row(4, center_amplitude_um=float("nan"))])
        bad.write_part([_row(5, profile_distance_mm=[0.0, 1.5, 2.0])])
        bad.write_part([_row(6)], {"solver": {"version": "0.0", "source_sha256": "ff" * 32}})
    (bad.path / "part-000099.parquet").write_bytes(b"not parquet")
    problems = "\n".join(validate_dataset(bad.path))
    for expected in ("repeat a (source, sample_id)", "repeat a sample_index",
                     "failed rows have no error text", "skin_E_kPa outside the space",
                     "side outside the space", "non-finite center_amplitude_um",
                     "profile grid differs", "part-000099.parquet",
                     "which the manifest does not list"):
        assert expected in problems


def test_merge_unions_and_prefers_ok_rows(tmp_path: Path) -> None:
    a = _store(tmp_path / "a", [_row(0), _row(1, "failed"), _row(2)])
    b = _store(tmp_path / "b", [_row(1), _row(2), _row(3), _row(3, source="ingest:x.csv")])
    res = merge_datasets(tmp_path / "m", [a.path, b.path])
    assert res == {"rows_in": 7, "rows_out": 5, "duplicates_dropped": 2, "parts": 1}
    df = pd.read_parquet(tmp_path / "m")
    assert sorted(zip(df["source"], df["sample_id"], strict=True)) == sorted(
        [(FEM_SOURCE, "id0000"), (FEM_SOURCE, "id0001"), (FEM_SOURCE, "id0002"),
         (FEM_SOURCE, "id0003"), ("ingest:x.csv", "id0003")])
    assert df.loc[df["sample_id"] == "id0001", "status"].tolist() == ["ok"]
    assert validate_dataset(tmp_path / "m") == []
    assert Store.open(tmp_path / "m").manifest["merged_from"][1]["rows"] == 4


def test_merge_refuses_mixed_solvers_and_other_columns(tmp_path: Path) -> None:
    a = _store(tmp_path / "a", [_row(0)])
    other = dict(SOLVER, version="1.0", source_sha256="cd" * 32)
    b = _store(tmp_path / "b", [_row(1)], solver=other)
    with pytest.raises(DatasetError, match="different solvers"):
        merge_datasets(tmp_path / "m", [a.path, b.path])
    assert not (tmp_path / "m").exists()
    merge_datasets(tmp_path / "m", [a.path, b.path], allow_mixed_solvers=True)
    assert len(Store.open(tmp_path / "m").manifest["solver_history"]) == 2
    narrow = {**SPACE, "parameter": SPACE["parameter"][:1]}
    c = Store.create(tmp_path / "c", space_from_dict(narrow, check_scenes=False),
                     solver=SOLVER, solver_history=[SOLVER])
    with pytest.raises(DatasetError, match="other columns"):
        merge_datasets(tmp_path / "m2", [a.path, c.path])
    with pytest.raises(DatasetError, match="not empty"):
        merge_datasets(tmp_path / "m", [a.path])


def test_solver_info_identifies_the_installed_solver_by_its_numbers() -> None:
    import fem

    info = solver_info()
    assert info["version"] == fem.SOLVER_VERSION
    assert len(info["fingerprint"]) == 64 and info["hash"] == info["fingerprint"][:12]
    assert info["git_revision"] == "unknown" or len(info["git_revision"].split("+")[0]) == 40
    assert solver_info(git=False)["fingerprint"] == info["fingerprint"]
    assert len(FINGERPRINT_SCENES) >= 3


def test_solver_fingerprint_changes_with_the_physics(monkeypatch: pytest.MonkeyPatch) -> None:
    """A change of what the solver computes changes the fingerprint; the cache is per process,
    so recompute it with a modified default material."""
    from fem import materials
    from surrogate.data import provenance

    before = provenance.solver_fingerprint()
    provenance.solver_fingerprint.cache_clear()
    scenes = [dict(s) for s in provenance.FINGERPRINT_SCENES]
    scenes[1] = {**scenes[1], "analysis": {"kind": "harmonic", "frequency_hz": 151.0}}
    monkeypatch.setattr(provenance, "FINGERPRINT_SCENES", tuple(scenes))
    try:
        assert provenance.solver_fingerprint() != before
    finally:
        provenance.solver_fingerprint.cache_clear()
    assert materials  # the library the fingerprint scenes resolve through


def test_old_manifests_compare_by_source_hash() -> None:
    old = {"version": "0.1.0", "source_sha256": "ab" * 32}
    assert same_solver(old, dict(old))
    assert not same_solver(old, {"version": "0.1.0", "fingerprint": "cd" * 32})
