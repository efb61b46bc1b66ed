"""Generating sweep datasets: real sweeps (fem.sweep) through the process pool and Dask,
resumable, each row what the solver returns for its scene."""

from __future__ import annotations

import copy
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow.parquet as pq
import pytest

import fem
from fem.scene import scene_from_dict
from surrogate.data.columns import sweep_arrays, sweep_columns
from surrogate.data.generate import generate
from surrogate.data.inspect import dataset_info, validate_dataset
from surrogate.data.plan import plan_samples
from surrogate.data.space import space_from_dict
from surrogate.data.store import Store

# Coarse, cheap sweeps: the tests check the bookkeeping, not the accuracy.
SPACE: dict[str, Any] = {
    "space": {"name": "sweep-gen-test", "seed": 11},
    "base": {"mesh": {"near_size_mm": 1.0, "far_size_mm": 4.0, "order": 1,
                      "follow_wavelength": False},
             "tissue": {"radius_mm": 30.0},
             "output": {"profile_length_mm": 10.0, "profile_step_mm": 2.0}},
    "parameter": [
        {"name": "skin_E_kPa", "type": "continuous", "path": "tissue.layer[0].E_kPa",
         "low": 20.0, "high": 120.0, "scale": "log"},
        {"name": "fat_thickness_mm", "type": "continuous",
         "path": "tissue.layer[1].thickness_mm", "low": 3.0, "high": 15.0},
    ],
    "band": {"start": 100.0, "stop": 250.0, "step": 10.0},
}


def _frame(path: Path):
    return Store.open(path).read().sort_values("sample_index").reset_index(drop=True)


def test_process_pool_sweeps_match_direct_sweeps_and_resume(tmp_path):
    space = space_from_dict(copy.deepcopy(SPACE))
    out = tmp_path / "ds"
    rep = generate(space, 2, out, workers=2, progress=False)
    assert (rep.new_ok, rep.new_failed) == (2, 0)
    first = {p.name: p.read_bytes() for p in Store.open(out).parts()}
    rep = generate(space, 3, out, workers=2, progress=False)
    assert (rep.already_done, rep.new_ok) == (2, 1)
    for name, data in first.items():  # earlier parts are never rewritten
        assert (out / name).read_bytes() == data
    df = _frame(out)
    planned, _ = plan_samples(space, 3)
    assert df["sample_id"].tolist() == [p.sample_id for p in planned]
    direct = fem.simulate(scene_from_dict(planned[1].scene))
    want = sweep_columns(direct)
    row = df.loc[1]
    for where in ("center", "edge", "profile"):  # within the codec's tolerance
        got, ref = sweep_arrays(row, where), sweep_arrays(want, where)
        scale = np.sqrt(np.max(np.sum(np.abs(ref) ** 2, axis=-1), axis=0))  # per location
        err = np.maximum(np.abs((got - ref).real), np.abs((got - ref).imag)).max(axis=(0, -1))
        assert np.all(err <= 2.51e-4 * scale)
    assert Store.open(out).codec is not None
    assert row["sweep_full_solves"] == direct.full_solves >= 1
    m = Store.open(out).manifest
    assert m["analysis_kind"] == "sweep" and len(m["band"]["frequency_hz"]) == 16
    assert m["profile_grid_mm"] == pytest.approx(list(row["profile_distance_mm"]))
    assert validate_dataset(out, rehash=True) == []
    assert dataset_info(out)["outputs"].startswith("complex sweeps: 16 frequencies")
    assert generate(space, 3, out, workers=1, progress=False).new == 0


def test_dask_local_cluster_gives_identical_sweep_rows(tmp_path):
    from distributed import Client, LocalCluster

    space = space_from_dict(copy.deepcopy(SPACE))
    generate(space, 2, tmp_path / "pool", workers=1, progress=False)
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=True,
                      dashboard_address=None) as cluster, Client(cluster) as client:
        generate(space, 2, tmp_path / "dask", scheduler=client, progress=False)
    a, b = _frame(tmp_path / "pool"), _frame(tmp_path / "dask")
    for name in ("sweep_center_uz_re_um", "sweep_profile_ur_im_um"):
        for x, y in zip(a[name], b[name], strict=True):
            np.testing.assert_array_equal(x, y)


def test_an_old_float_list_set_is_extended_in_its_form_then_compacted_and_extended(tmp_path):
    from surrogate.data.compact import compact_dataset
    from surrogate.data.provenance import solver_info
    from surrogate.data.store import new_manifest

    space = space_from_dict(copy.deepcopy(SPACE))
    old = tmp_path / "old"
    manifest = new_manifest(space, solver_info())
    del manifest["codec"]  # as every sweep dataset was written before the codec
    Store.create(old, space, **manifest)
    assert generate(space, 2, old, workers=1, progress=False).new_ok == 2
    store = Store.open(old)
    assert store.codec is None
    assert "sweep_center_uz_re_um" in pq.read_table(store.parts()[0]).column_names
    new = tmp_path / "new"
    compact_dataset(old, new)
    rep = generate(space, 3, new, workers=1, progress=False)
    assert (rep.already_done, rep.new_ok) == (2, 1)
    store = Store.open(new)
    assert len(store.parts()) == 2 and store.codec is not None
    assert all("codec_error" in e for e in store.manifest["parts"].values())
    planned, _ = plan_samples(space, 3)
    assert _frame(new)["sample_id"].tolist() == [p.sample_id for p in planned]
    assert validate_dataset(new, rehash=True) == []

