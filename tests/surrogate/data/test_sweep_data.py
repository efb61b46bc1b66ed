"""Data made of sweeps: a space's [band], the sweep columns, their storage and their checks.

The storage is tested on synthetic SweepResult-like objects (the fields of
``fem.sweep.SweepResult``); the generation of real sweeps is in test_sweep_generate.py."""

from __future__ import annotations

import copy
import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from surrogate.data.columns import COMPONENTS, SWEEP_FIELDS, sweep_arrays
from surrogate.data.digests import part_entry
from surrogate.data.errors import DatasetError, SpaceError
from surrogate.data.inspect import dataset_info, validate_dataset
from surrogate.data.integrity import manifest_digest
from surrogate.data.provenance import solver_info
from surrogate.data.space import load_space, space_from_dict
from surrogate.data.store import MANIFEST_NAME, Store, new_manifest
from surrogate.data.worker import outputs_from_result

ROOT = Path(__file__).resolve().parents[3]
SPACE: dict[str, Any] = {
    "space": {"name": "sweep-test", "seed": 3},
    "base": {"mesh": {"near_size_mm": 1.0, "far_size_mm": 4.0, "order": 1,
                      "follow_wavelength": False},
             "output": {"profile_length_mm": 10.0, "profile_step_mm": 2.0}},
    "parameter": [
        {"name": "skin_E_kPa", "type": "continuous", "path": "tissue.layer[0].E_kPa",
         "low": 20.0, "high": 120.0, "scale": "log"},
        {"name": "fat_thickness_mm", "type": "continuous",
         "path": "tissue.layer[1].thickness_mm", "low": 3.0, "high": 15.0},
    ],
    "band": {"start": 100.0, "stop": 250.0, "step": 10.0},
}
F = np.round(100.0 + 10.0 * np.arange(16), 9)
GRID = np.arange(0.0, 10.0 + 1e-9, 2.0)


@dataclass
class FakeSweep:
    """The fields of fem.sweep.SweepResult (shared interface 2)."""

    frequency_hz: np.ndarray
    center: np.ndarray
    edge: np.ndarray
    profile_mm: np.ndarray
    profile: np.ndarray
    edge_mm: float | None = 5.5
    error_estimate: float = 2e-4
    full_solves: int = 3
    meta: dict = field(default_factory=lambda: {"dofs": 1234, "elements": 321,
                                                "warnings": []})


def fake_sweep(seed: int, n_f: int = F.size, n_p: int = GRID.size) -> FakeSweep:
    """A resonance-like complex response [m]."""
    rng = np.random.default_rng(seed)
    f = F[:n_f]
    h = 1.0 / (1.0 - (f / (150 + 50 * rng.random())) ** 2 + 0.05j)
    comp = rng.normal(size=3) + 1j * rng.normal(size=3)
    center = 1e-6 * h[:, None] * comp[None, :]
    edge = 0.5 * center
    decay = np.exp(-GRID[None, :n_p, None] / 6.0)
    profile = 0.4 * center[:, None, :] * decay
    return FakeSweep(f, center, edge, GRID[:n_p], profile)


def _space():
    return space_from_dict(SPACE, check_scenes=False)


def _dataset(path: Path, n: int = 4, compact: bool = True) -> Path:
    """A sweep dataset of n rows written the way generate writes them (``compact``: as
    generate writes them now; else float32 lists, as before the codec)."""
    space = _space()
    manifest = {**new_manifest(space, solver_info(git=False)), "profile_grid_mm": GRID.tolist()}
    if not compact:
        del manifest["codec"]
    store = Store.create(path, space, **manifest)
    pts = space.points(0, n)
    rows = []
    for i in range(n):
        values = {k: v[i].item() for k, v in pts.items()}
        rows.append({**outputs_from_result(fake_sweep(i)), **values, "status": "ok",
                     "sample_id": f"{i:064x}", "sample_index": i, "source": "hapticrom-fem",
                     "scene_json": json.dumps(space.resolve(values))})
    with store.lock():
        store.write_part(rows[: n // 2])
        store.write_part(rows[n // 2:])
    return path


# ------------------------------------------------------------------------------ the band


def test_a_band_makes_every_scene_a_sweep_and_enters_the_hash():
    space = _space()
    assert space.band.frequencies_hz == tuple(F)
    analysis = space.resolve(space.center())["analysis"]
    assert analysis == {"kind": "sweep", "frequency_hz": {"start": 100.0, "stop": 250.0,
                                                          "step": 10.0}}
    other = copy.deepcopy(SPACE)
    other["band"]["step"] = 5.0
    assert space_from_dict(other, check_scenes=False).space_hash() != space.space_hash()
    no_band = {k: v for k, v in SPACE.items() if k != "band"}
    assert "band" not in space_from_dict(no_band, check_scenes=False).to_dict()
    assert space_from_dict(space.to_dict(), check_scenes=False).band == space.band


@pytest.mark.parametrize("band, fld, words", [
    ({"start": 100.0, "stop": 90.0, "step": 1.0}, "band.stop", "allowed stop > start"),
    ({"start": 100.0, "stop": 250.0, "step": 0.01}, "band.step", "allowed step >= "),
    ({"start": 100.0, "stop": 250.0}, "band.step", "missing"),
    ({"start": 100.0, "stop": 250.0, "step": 1.0, "points": 5}, "band.points", ""),
    ({"start": -5.0, "stop": 250.0, "step": 1.0}, "band.start", "allowed 0 < start <= 1e5"),
    ("100-250", "band", "a table"),
])
def test_bad_bands_are_refused_naming_the_field(band, fld, words):
    d = {**copy.deepcopy(SPACE), "band": band}
    with pytest.raises(SpaceError) as err:
        space_from_dict(d, check_scenes=False)
    assert err.value.field == fld and words in str(err.value)


def test_a_frequency_parameter_and_a_band_exclude_each_other():
    d = copy.deepcopy(SPACE)
    d["parameter"].append({"name": "frequency_hz", "type": "continuous",
                           "path": "analysis.frequency_hz", "low": 100.0, "high": 250.0})
    with pytest.raises(SpaceError, match="which the space's \\[band\\] sets") as err:
        space_from_dict(d, check_scenes=False)
    assert err.value.field == "parameter frequency_hz.path"


def test_the_shipped_sweep_space():
    space = load_space(ROOT / "datasets" / "spaces" / "default-sweep.toml", check_scenes=False)
    default = load_space(ROOT / "datasets" / "spaces" / "default.toml", check_scenes=False)
    assert len(space.band.frequencies_hz) == 76
    assert space.band.frequencies_hz[0] == 100.0 and space.band.frequencies_hz[-1] == 250.0
    assert set(space.names) == set(default.names) - {"frequency_hz"}
    scene = space.resolve(space.center())
    assert scene["output"]["profile_length_mm"] == 40.0
    assert scene["tissue"]["radius_mm"] == 70.0


# ------------------------------------------------------------------------------ storage


def _location_error(got: np.ndarray, ref: np.ndarray) -> float:
    """Largest error of a real or imaginary part relative to the band maximum magnitude at
    its location, of (n_f, 3) or (n_f, n_p, 3) arrays."""
    scale = np.sqrt(np.max(np.sum(np.abs(ref) ** 2, axis=-1), axis=0))  # per location
    err = np.max(np.maximum(np.abs((got - ref).real), np.abs((got - ref).imag)), axis=(0, -1))
    return float(np.max(err / scale))


@pytest.mark.parametrize("compact, bound", [(False, 1e-7), (True, 2.51e-4)])
def test_a_sweep_round_trips_through_the_store(tmp_path, compact, bound):
    """Float32 lists to 6e-8 relative, the compact form within its tolerance (2.5e-4 of the
    band maximum at the location)."""
    path = _dataset(tmp_path / "d", compact=compact)
    store = Store.open(path, deep=True)
    schema = store.schema
    assert "center_amplitude_um" not in schema.names and "frequency_hz" not in schema.names
    assert schema.field("sweep_profile_uz_re_um").type == pa.list_(pa.float32())
    df = store.read().sort_values("sample_index").reset_index(drop=True)
    for i in (0, 3):
        want = fake_sweep(i)
        row = df.loc[i]
        np.testing.assert_array_equal(row["sweep_frequency_hz"], F)
        np.testing.assert_array_equal(row["profile_distance_mm"], GRID)
        for where, ref in (("center", want.center), ("edge", want.edge),
                           ("profile", want.profile)):
            got = sweep_arrays(row, where)
            assert got.shape == ref.shape
            assert _location_error(got, ref * 1e6) <= bound
        assert row["sweep_full_solves"] == 3 and row["sweep_error_estimate"] == 2e-4
        assert row["dofs"] == 1234 and row["edge_radius_mm"] == 5.5
    m = store.manifest
    assert m["analysis_kind"] == "sweep" and m["band"]["frequency_hz"] == F.tolist()
    assert validate_dataset(path) == []
    info = dataset_info(path)
    assert info["outputs"].startswith("complex sweeps: 16 frequencies 100-250 Hz, profile 6")
    assert info["rows"] == 4


def test_rows_are_compact(tmp_path):
    path = _dataset(tmp_path / "d", n=8)
    per_row = sum(p.stat().st_size for p in Store.open(path).parts()) / 8
    raw = 4 * 6 * F.size * (2 + GRID.size)  # float32 values of the sweep lists
    assert per_row < 2 * raw + 3000  # the lists dominate, no float64 blow-up


def test_columns_of_a_result_with_wrong_shapes_are_refused():
    bad = fake_sweep(0)
    bad.profile = bad.profile[:, :-1]
    with pytest.raises(ValueError, match="do not fit 16 frequencies x 6 profile points"):
        outputs_from_result(bad)


def _edit_row(path: Path, column: str, change) -> None:
    part = sorted(path.glob("part-*.parquet"))[0]
    t = pq.read_table(part)
    i = t.schema.get_field_index(column)
    values = t.column(i).to_pylist()
    values[0] = change(values[0])
    pq.write_table(t.set_column(i, t.schema.field(i), pa.array(values, t.schema.field(i).type)),
                   part)
    m = json.loads((path / MANIFEST_NAME).read_text())  # a consistent envelope, bad physics
    m["parts"][part.name] = part_entry(part)
    m["digest"] = manifest_digest(m)
    (path / MANIFEST_NAME).write_text(json.dumps(m))


@pytest.mark.parametrize("column, change, words", [
    ("sweep_profile_uz_im_um", lambda v: v[:-1], "sweep_profile_uz_im_um holds 95 values, "
     "expected 96"),
    ("sweep_center_ur_re_um", lambda v: [float("nan"), *v[1:]], "sweep_center_ur_re_um has "
     "non-finite"),
    ("sweep_frequency_hz", lambda v: [v[0] + 1.0, *v[1:]], "differs from the manifest's band"),
    ("profile_distance_mm", lambda v: [x * 2 for x in v], "differs from the manifest's grid"),
    ("sweep_full_solves", lambda v: 0, "at least one solve"),
])
def test_validate_checks_the_sweep_columns(tmp_path, column, change, words):
    path = _dataset(tmp_path / "d", compact=False)
    _edit_row(path, column, change)
    problems = validate_dataset(path)
    assert any(words in p for p in problems), problems


def test_a_non_finite_sweep_is_a_failed_row(monkeypatch):
    import fem
    from surrogate.data.worker import run_sample

    bad = fake_sweep(1)
    bad.center[3, 1] = np.nan
    monkeypatch.setattr(fem, "simulate", lambda scene: bad)
    out = run_sample(_space().resolve(_space().center()))
    assert out["status"] == "failed" and "sweep_center_uz_re_um contains NaN" in out["error"]


def test_sweep_columns_cover_every_component():
    names = {f.name for f in SWEEP_FIELDS}
    for where in ("center", "edge", "profile"):
        for c in COMPONENTS:
            assert {f"sweep_{where}_u{c}_re_um", f"sweep_{where}_u{c}_im_um"} <= names


def test_ingest_refuses_a_sweep_dataset_and_writes_nothing(tmp_path):
    from surrogate.data.ingest import ingest_table

    path = _dataset(tmp_path / "d")
    table = tmp_path / "t.csv"
    table.write_text("skin_E_kPa,fat_thickness_mm,center_amplitude_um\n50,10,3.0\n")
    before = {p.name: p.read_bytes() for p in path.iterdir()}
    with pytest.raises(DatasetError, match="is a sweep dataset"):
        ingest_table(table, path)
    assert {p.name: p.read_bytes() for p in path.iterdir()} == before


def test_training_on_a_sweep_dataset_is_refused_by_name(tmp_path):
    from hapticrom.cli import main

    path = _dataset(tmp_path / "d")
    assert main(["train", "--data", str(path), "--kind", "gp", "--out",
                 str(tmp_path / "m")]) == 2
    assert not (tmp_path / "m").exists()
