"""Ingest of external results: tables, ABAQUS/COMSOL profiles, validation, provenance."""

from __future__ import annotations

import copy
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest

from fem.scene import scene_from_dict, scene_hash
from hapticrom.cli import main
from surrogate.data.errors import DatasetError
from surrogate.data.ingest import ingest_profile, ingest_table, read_profile_csv
from surrogate.data.inspect import validate_dataset
from surrogate.data.space import SpaceError, space_from_dict
from surrogate.data.store import FEM_SOURCE, Store

BASE = {"analysis": {"kind": "harmonic", "frequency_hz": 120.0},
        "mesh": {"near_size_mm": 1.0, "far_size_mm": 4.0, "order": 1},
        "tissue": {"radius_mm": 30.0}}
SPACE: dict[str, Any] = {
    "space": {"name": "ingest-test", "seed": 2},
    "base": BASE,
    "parameter": [
        {"name": "skin_E_kPa", "type": "continuous", "path": "tissue.layer[0].E_kPa",
         "low": 20.0, "high": 120.0},
        {"name": "frequency_hz", "type": "continuous", "path": "analysis.frequency_hz",
         "low": 100.0, "high": 250.0},
        {"name": "side", "type": "categorical", "path": "tissue.side",
         "choices": ["absorbing", "fixed"]},
        {"name": "order", "type": "fixed", "path": "mesh.order", "value": 1},
    ],
    "constraint": [{"name": "stiff_fast", "expr": "skin_E_kPa > 30 or frequency_hz < 240"}],
}
SPACE_TOML = """
[space]
name = "ingest-test"
seed = 2
[base.analysis]
kind = "harmonic"
frequency_hz = 120.0
[base.mesh]
near_size_mm = 1.0
far_size_mm = 4.0
order = 1
[base.tissue]
radius_mm = 30.0
[[parameter]]
name = "skin_E_kPa"
type = "continuous"
path = "tissue.layer[0].E_kPa"
low = 20.0
high = 120.0
[[parameter]]
name = "frequency_hz"
type = "continuous"
path = "analysis.frequency_hz"
low = 100.0
high = 250.0
[[parameter]]
name = "side"
type = "categorical"
path = "tissue.side"
choices = ["absorbing", "fixed"]
[[parameter]]
name = "order"
type = "fixed"
path = "mesh.order"
value = 1
[[constraint]]
name = "stiff_fast"
expr = "skin_E_kPa > 30 or frequency_hz < 240"
"""
COMSOL = """% Model:              forearm_unit.mph
% Version:            COMSOL 6.2.0.290
% Date:               Mar 3 2025, 10:12
% Table:              Line Graph 1 - Displacement magnitude (um)
% Arc length (mm),Displacement magnitude (µm)
0,12.5
4,6.25
8,3.0
12,1.5
16,0.75
20,0.5
"""
ABAQUS = """
            X               U:Magnitude PI: PART-1-1 N: 412

            0.0004        2.0E-06
              0.            4.0E-06
            0.002          1.0E-06
"""


def _space() -> Any:
    return space_from_dict(SPACE)


def _hash_by_hand(skin: float, freq: float, side: str) -> str:
    """Scene hash of a design point written directly in the scene schema (no space code)."""
    d = copy.deepcopy(BASE)
    d["analysis"]["frequency_hz"] = freq
    d["tissue"]["side"] = side
    d["tissue"]["layer"] = [{"material": "skin", "thickness_mm": 1.9, "E_kPa": skin},
                            {"material": "subcutaneous", "thickness_mm": 14.0},
                            {"material": "muscle", "thickness_mm": 21.0},
                            {"material": "bone", "thickness_mm": 5.0}]
    return scene_hash(scene_from_dict(d))


def test_profile_exports_are_read_with_their_units(tmp_path: Path) -> None:
    comsol = tmp_path / "comsol.csv"
    comsol.write_text(COMSOL, encoding="utf-8")
    d, a = read_profile_csv(comsol)
    np.testing.assert_array_equal(d, [0, 4, 8, 12, 16, 20])
    np.testing.assert_array_equal(a, [12.5, 6.25, 3.0, 1.5, 0.75, 0.5])
    rpt = tmp_path / "abaqus.rpt"
    rpt.write_text(ABAQUS)
    with pytest.raises(DatasetError, match="unit of the distance column is not in the header"):
        read_profile_csv(rpt)
    d, a = read_profile_csv(rpt, distance_unit="m", amplitude_unit="m")
    np.testing.assert_allclose(d, [0.0, 0.4, 2.0])  # sorted, m -> mm
    np.testing.assert_allclose(a, [4.0, 2.0, 1.0])  # m -> um
    semi = tmp_path / "semi.txt"
    semi.write_text("d [cm];skip;amp [nm]\n0;9;1000\n1;9;500\n")
    d, a = read_profile_csv(semi, columns=(0, 2))
    np.testing.assert_allclose(d, [0.0, 10.0])
    np.testing.assert_allclose(a, [1.0, 0.5])


@pytest.mark.parametrize("text, message", [
    ("d (mm),a (um)\n0,1\n", "at least 2 data lines"),
    ("d (mm),a (um)\n0,1\n1,x\n", r":3: non-numeric value"),
    ("d (mm),a (um)\n0,1\n1,2,3\n", "different numbers of columns"),
    ("d (mm),a (um)\n0,1\n1,-2\n", "negative amplitude"),
    ("d (mm),a (um)\n0,1\n0,2\n", "repeated distance"),
    ("d (mm),a (um)\n0,1\n1,nan\n", "NaN or inf"),
    ("d (furlong),a (um)\n0,1\n1,2\n", "distance_unit"),
])
def test_bad_profiles_are_rejected(tmp_path: Path, text: str, message: str) -> None:
    p = tmp_path / "p.csv"
    p.write_text(text)
    with pytest.raises(DatasetError, match=message):
        read_profile_csv(p)


def test_table_ingest_round_trip_and_idempotence(tmp_path: Path) -> None:
    (tmp_path / "prof.csv").write_text(COMSOL, encoding="utf-8")
    table = tmp_path / "abaqus_runs.csv"
    table.write_text("# exported 2025-03-03\n"
                     "skin_E_kPa,frequency_hz,side,center_amplitude_um,edge_amplitude_um,"
                     "profile_file,wall_s\n"
                     "49,120,absorbing,20.0,10.0,,3600\n"
                     "60,150,fixed,25.0,,prof.csv,\n")
    out = tmp_path / "ds"
    rep = ingest_table(table, out, _space())
    assert (rep.rows_read, rep.added, rep.skipped_existing) == (2, 2, 0)
    df = pd.read_parquet(out).sort_values("sample_index").reset_index(drop=True)
    assert df["source"].tolist() == ["ingest:abaqus_runs.csv"] * 2
    assert df["sample_id"].tolist() == [_hash_by_hand(49.0, 120.0, "absorbing"),
                                        _hash_by_hand(60.0, 150.0, "fixed")]
    assert df["normalized_edge"].tolist() == [0.5, 12.5 / 25.0]  # edge from the profile at 0
    assert df["edge_amplitude_um"].tolist() == [10.0, 12.5]
    assert df["order"].tolist() == [1, 1] and df["wall_s"].iloc[0] == 3600.0
    assert df["profile_distance_mm"].iloc[0] is None
    np.testing.assert_array_equal(df["profile_magnitude_um"].iloc[1],
                                  [12.5, 6.25, 3.0, 1.5, 0.75, 0.5])
    assert validate_dataset(out, rehash=True) == []
    again = ingest_table(table, out)  # the dataset's own space
    assert (again.added, again.skipped_existing) == (0, 2)
    assert len(pd.read_parquet(out)) == 2


@pytest.mark.parametrize("row, message", [
    ("200,120,absorbing,1,1", r"skin_E_kPa = '200' is outside the space: allowed 20.0 <= "
                              r"skin_E_kPa <= 120.0"),
    ("49,120,wobbly,1,1", r"side = 'wobbly' is outside the space: allowed one of "),
    ("25,245,fixed,1,1", r"violates constraint 'stiff_fast'"),
    ("49,abc,fixed,1,1", r"frequency_hz = 'abc': expected a float64"),
    ("49,120,fixed,,", r"no result: give center_amplitude_um"),
    ("49,120,fixed,-1,1", r"center_amplitude_um = '-1': need a finite value > 0"),
    ("49,120,fixed,0,1", r"center_amplitude_um = '0': need a finite value > 0"),
    ("49,120,fixed,1,0", r"edge_amplitude_um = '0': need a finite value > 0"),
])
def test_table_values_are_validated_and_nothing_written(tmp_path: Path, row: str,
                                                        message: str) -> None:
    table = tmp_path / "t.csv"
    table.write_text("skin_E_kPa,frequency_hz,side,center_amplitude_um,edge_amplitude_um\n"
                     f"49,120,absorbing,2,1\n{row}\n")
    with pytest.raises((SpaceError, DatasetError), match=message) as err:
        ingest_table(table, tmp_path / "ds", _space())
    assert "t.csv:3" in str(err.value)
    assert not (tmp_path / "ds").exists()


def test_table_columns_and_assignments(tmp_path: Path) -> None:
    table = tmp_path / "t.csv"
    table.write_text("skin_E_kPa,side,stiffness,edge_amplitude_um\n49,fixed,1,1\n")
    with pytest.raises(DatasetError, match="unknown column 'stiffness'"):
        ingest_table(table, tmp_path / "ds", _space())
    table.write_text("skin_E_kPa,side,edge_amplitude_um\n49,fixed,1\n")
    with pytest.raises(SpaceError, match="give --set frequency_hz=VALUE"):
        ingest_table(table, tmp_path / "ds", _space())
    with pytest.raises(SpaceError, match="unknown parameter"):
        ingest_table(table, tmp_path / "ds", _space(), values={"freq": "120"})
    table.write_text("skin_E_kPa,side,edge_amplitude_um,order\n49,fixed,1,2\n")
    with pytest.raises(SpaceError, match="order = '2' is outside the space: allowed exactly 1"):
        ingest_table(table, tmp_path / "ds", _space(), values={"frequency_hz": "120"})
    table.write_text("skin_E_kPa,side,center_amplitude_um,edge_amplitude_um,normalized_edge\n"
                     "49,fixed,4,1,0.5\n")
    with pytest.raises(DatasetError, match=r"normalized_edge = 0.5 but edge/center = 0.25"):
        ingest_table(table, tmp_path / "ds", _space(), values={"frequency_hz": "120"})
    with pytest.raises(DatasetError, match="give a space to create it"):
        ingest_table(table, tmp_path / "ds")
    assert not (tmp_path / "ds").exists()


def test_profile_ingest_into_a_generated_dataset(tmp_path: Path) -> None:
    from surrogate.data.generate import generate, plan_samples

    space = _space()
    out = tmp_path / "ds"
    generate(space, 2, out, workers=1, progress=False)
    point = plan_samples(space, 1)[0][0]
    rpt = tmp_path / "job7.rpt"
    rpt.write_text(ABAQUS)
    values = {k: str(v) for k, v in point.values.items() if k != "order"}
    rep = ingest_profile(rpt, out, values, distance_unit="m", amplitude_unit="m",
                         center_amplitude_um=8.0)
    assert rep.added == 1
    df = pd.read_parquet(out)
    assert sorted(df["source"]) == [FEM_SOURCE, FEM_SOURCE, "ingest:job7.rpt"]
    ext = df[df["source"] == "ingest:job7.rpt"].iloc[0]
    fem_row = df[(df["source"] == FEM_SOURCE) & (df["sample_index"] == point.index)].iloc[0]
    assert ext["sample_id"] == fem_row["sample_id"] == point.sample_id  # same design point
    assert ext["edge_amplitude_um"] == pytest.approx(4.0)
    assert ext["normalized_edge"] == pytest.approx(0.5)
    assert validate_dataset(out) == []
    # generation still resumes cleanly next to ingested rows
    assert generate(space, 3, out, workers=1, progress=False).new == 1
    with pytest.raises(DatasetError, match="differs from the space"):
        ingest_profile(rpt, out, values, space_from_dict({**SPACE, "space": {"name": "z"}}),
                       distance_unit="m", amplitude_unit="m")
    assert Store.open(out).counts()["rows"] == 4


def test_cli_ingest(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    space = tmp_path / "space.toml"
    space.write_text(SPACE_TOML)
    table = tmp_path / "t.csv"
    table.write_text("skin_E_kPa,frequency_hz,side,edge_amplitude_um\n49,120,fixed,1\n")
    out = tmp_path / "ds"
    assert main(["ingest", str(table), "--out", str(out), "--space", str(space)]) == 0
    assert "1 rows added from ingest:t.csv" in capsys.readouterr().out
    prof = tmp_path / "p.csv"
    prof.write_text(COMSOL, encoding="utf-8")
    args = ["ingest", str(prof), "--out", str(out), "--set", "skin_E_kPa=50", "--set",
            "frequency_hz=130", "--set", "side=absorbing", "--source", "lab-A"]
    assert main(args) == 0
    assert "ingest:lab-A" in capsys.readouterr().out
    assert sorted(pd.read_parquet(out)["source"]) == ["ingest:lab-A", "ingest:t.csv"]
    # bad input: exit 2, message names the field, nothing written
    bad = ["ingest", str(prof), "--out", str(tmp_path / "new"), "--space", str(space)]
    assert main([*bad, "--set", "skin_E_kPa=5", "--set", "frequency_hz=130", "--set",
                 "side=fixed"]) == 2
    assert "allowed 20.0 <= skin_E_kPa <= 120.0" in capsys.readouterr().err
    assert main([*bad, "--set", "skin_E_kPa"]) == 2
    assert "expected NAME=VALUE" in capsys.readouterr().err
    assert main([*bad, "--distance-unit", "parsec", "--set", "skin_E_kPa=50", "--set",
                 "frequency_hz=130", "--set", "side=fixed"]) == 2
    assert "distance_unit = 'parsec'" in capsys.readouterr().err
    assert not (tmp_path / "new").exists()


def test_abaqus_csv_with_quoted_header(tmp_path: Path) -> None:
    p = tmp_path / "xy.csv"
    p.write_text('X,"U:Magnitude, PI: PART-1-1 N: 412"\n0.,4.E-06\n2.E-03,1.E-06\n')
    d, a = read_profile_csv(p, distance_unit="m", amplitude_unit="m")
    np.testing.assert_allclose(d, [0.0, 2.0])
    np.testing.assert_allclose(a, [4.0, 1.0])


def test_material_aliases_are_accepted_as_scene_files_accept_them(tmp_path: Path) -> None:
    """"A" is Ecoflex 00-10 in a scene; an ingested table may say so too (stored canonical)."""
    from surrogate.data.space import space_from_dict

    space = space_from_dict({
        "space": {"name": "rings", "seed": 1},
        "base": {"load": {"kind": "unit"}, "analysis": {"kind": "harmonic"},
                 "mesh": {"order": 1, "near_size_mm": 1.0, "far_size_mm": 4.0}},
        "parameter": [
            {"name": "ring", "type": "categorical", "path": "unit.encapsulation[0]",
             "choices": ["ecoflex-00-10", "dragon-skin-30"]},
            {"name": "frequency_hz", "type": "continuous", "path": "analysis.frequency_hz",
             "low": 100.0, "high": 200.0}]})
    table = tmp_path / "t.csv"
    table.write_text("ring,frequency_hz,center_amplitude_um,edge_amplitude_um\n"
                     "A,150,2,1\nDragon Skin 30,120,3,1\n")
    ingest_table(table, tmp_path / "ds", space)
    df = pd.read_parquet(tmp_path / "ds")
    assert sorted(df["ring"]) == ["dragon-skin-30", "ecoflex-00-10"]
    table.write_text("ring,frequency_hz,center_amplitude_um\nB,150,2\n")  # B is Ecoflex 00-50
    with pytest.raises(SpaceError, match="ring = 'B' is outside the space"):
        ingest_table(table, tmp_path / "ds2", space)
