"""Generation: planning, process pool, Dask LocalCluster, failures, kill -9 and resume, CLI."""

from __future__ import annotations

import contextlib
import copy
import dataclasses
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pyarrow.parquet as pq
import pytest

from fem import simulate
from fem.scene import scene_from_dict, scene_hash
from hapticrom.cli import main
from surrogate.data.errors import DatasetError
from surrogate.data.generate import generate
from surrogate.data.inspect import validate_dataset
from surrogate.data.integrity import manifest_digest
from surrogate.data.plan import plan_samples
from surrogate.data.space import SpaceError, space_from_dict
from surrogate.data.store import FEM_SOURCE, MANIFEST_NAME, Store
from surrogate.data.worker import run_sample

ROOT = Path(__file__).resolve().parents[3]
# Coarse, cheap scenes (about 20 ms each): the tests check bookkeeping, not accuracy.
SPACE: dict[str, Any] = {
    "space": {"name": "gen-test", "seed": 5},
    "base": {"analysis": {"kind": "harmonic", "frequency_hz": 120.0},
             "mesh": {"near_size_mm": 1.0, "far_size_mm": 4.0, "order": 1,
                      "follow_wavelength": False},
             "tissue": {"radius_mm": 30.0}},
    "parameter": [
        {"name": "skin_E_kPa", "type": "continuous", "path": "tissue.layer[0].E_kPa",
         "low": 20.0, "high": 120.0, "scale": "log"},
        {"name": "fat_thickness_mm", "type": "continuous",
         "path": "tissue.layer[1].thickness_mm", "low": 3.0, "high": 15.0},
        {"name": "frequency_hz", "type": "continuous", "path": "analysis.frequency_hz",
         "low": 100.0, "high": 250.0},
    ],
}


def _toml(d: dict[str, Any]) -> str:
    """Tiny TOML writer for the space dicts used here (tables of scalars, arrays of tables)."""
    def val(v: Any) -> str:
        return json.dumps(v) if not isinstance(v, bool) else str(v).lower()

    lines = ["[space]"] + [f"{k} = {val(v)}" for k, v in d["space"].items()]
    for table, body in d.get("base", {}).items():
        lines += [f"[base.{table}]"] + [f"{k} = {val(v)}" for k, v in body.items()]
    for p in d["parameter"]:
        lines += ["[[parameter]]"] + [f"{k} = {val(v)}" for k, v in p.items()]
    for c in d.get("constraint", []):
        lines += ["[[constraint]]"] + [f"{k} = {val(v)}" for k, v in c.items()]
    if "band" in d:
        lines += ["[band]"] + [f"{k} = {val(v)}" for k, v in d["band"].items()]
    return "\n".join(lines) + "\n"


@pytest.fixture
def space_file(tmp_path: Path) -> Path:
    p = tmp_path / "space.toml"
    p.write_text(_toml(SPACE))
    return p


def _frame(path: Path) -> pd.DataFrame:
    return pd.read_parquet(path).sort_values("sample_index").reset_index(drop=True)


# ----------------------------------------------------------------------------- planning


def test_plan_extends_the_same_sequence_and_honours_constraints() -> None:
    d = copy.deepcopy(SPACE)
    d["constraint"] = [{"name": "soft", "expr": "skin_E_kPa < 60"}]
    space = space_from_dict(d)
    short, _ = plan_samples(space, 10)
    long, stats = plan_samples(space, 25)
    assert [p.sample_id for p in long[:10]] == [p.sample_id for p in short]
    assert all(p.values["skin_E_kPa"] < 60 for p in long)
    assert stats.rejected > 0 and stats.scanned == long[-1].index + 1
    assert stats.scanned == 25 + stats.rejected
    # the planned scene really is the one hashed
    p = long[3]
    assert scene_hash(scene_from_dict(p.scene)) == p.sample_id


def test_plan_skips_repeated_scenes_and_refuses_too_many() -> None:
    d = copy.deepcopy(SPACE)
    d["parameter"] = [{"name": "side", "type": "categorical", "path": "tissue.side",
                       "choices": ["absorbing", "fixed", "free"]}]
    space = space_from_dict(d)
    planned, stats = plan_samples(space, 3)
    assert sorted(p.values["side"] for p in planned) == ["absorbing", "fixed", "free"]
    assert stats.duplicates == stats.scanned - 3
    with pytest.raises(SpaceError, match=r"only 3 distinct feasible points"):
        plan_samples(space, 4)


# ----------------------------------------------------------------------------- runs


def test_process_pool_run_matches_direct_solves_and_extends(tmp_path: Path) -> None:
    out = tmp_path / "ds"
    rep = generate(space_from_dict(SPACE), 6, out, workers=2, progress=False)
    assert (rep.new_ok, rep.new_failed, rep.already_done, rep.workers) == (6, 0, 0, 2)
    first_parts = {p.name: p.read_bytes() for p in Store.open(out).parts()}
    rep = generate(space_from_dict(SPACE), 14, out, workers=2, progress=False, flush_every=3)
    assert (rep.already_done, rep.new) == (6, 8) and rep.parts_written >= 3
    df = _frame(out)
    planned, _ = plan_samples(space_from_dict(SPACE), 14)
    assert df["sample_index"].tolist() == [p.index for p in planned]
    assert df["sample_id"].tolist() == [p.sample_id for p in planned]
    assert (df["status"] == "ok").all() and (df["source"] == FEM_SOURCE).all()
    # earlier parts are never rewritten
    for name, data in first_parts.items():
        assert (out / name).read_bytes() == data
    # each row holds exactly what the solver returns for its scene
    for i in (0, 9):
        direct = simulate(scene_from_dict(planned[i].scene)).to_dict()
        assert df.loc[i, "center_amplitude_um"] == direct["centre"]["magnitude_um"]
        assert df.loc[i, "edge_amplitude_um"] == direct["edge"]["magnitude_um"]
        np.testing.assert_array_equal(df.loc[i, "profile_magnitude_um"],
                                      direct["profile"]["magnitude_um"])
        assert df.loc[i, "dofs"] == direct["meta"]["dofs"]
        assert df.loc[i, "frequency_hz"] == planned[i].values["frequency_hz"]
    m = Store.open(out).manifest
    assert m["sampling"]["target_n"] == 14 and len(m["runs"]) == 2
    assert m["profile_grid_mm"] == pytest.approx(list(df.loc[0, "profile_distance_mm"]))
    assert validate_dataset(out, rehash=True) == []
    # asking again for what is there runs nothing
    assert generate(space_from_dict(SPACE), 14, out, workers=1, progress=False).new == 0


def test_dask_local_cluster_gives_identical_rows(tmp_path: Path) -> None:
    from distributed import LocalCluster

    space = space_from_dict(SPACE)
    generate(space, 8, tmp_path / "pool", workers=2, progress=False)
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=False, protocol="tcp",
                      host="127.0.0.1", dashboard_address=None) as cluster:
        address = cluster.scheduler_address
        assert address.startswith("tcp://127.0.0.1:")
        rep = generate(space, 8, tmp_path / "dask", scheduler=address, chunk=3, progress=False)
    assert (rep.backend, rep.workers, rep.new_ok) == ("dask", 2, 8)
    a, b = _frame(tmp_path / "pool"), _frame(tmp_path / "dask")
    cols = ["sample_id", "sample_index", "skin_E_kPa", "center_amplitude_um",
            "edge_amplitude_um", "normalized_edge", "dofs"]
    pd.testing.assert_frame_equal(a[cols], b[cols])
    assert all(np.array_equal(x, y) for x, y in zip(a["profile_magnitude_um"],
                                                    b["profile_magnitude_um"], strict=True))


def test_failed_samples_are_stored_with_their_error(tmp_path: Path,
                                                    monkeypatch: pytest.MonkeyPatch) -> None:
    from distributed import LocalCluster

    import fem.simulation

    real = fem.simulation.simulate

    def nan_result(res: Any) -> Any:
        return dataclasses.replace(res, center=res.center * np.nan)

    def flaky(scene: Any) -> Any:
        f = scene.analysis.frequency_hz
        if f > 200.0:
            raise ValueError(f"synthetic failure at {f:.3f} Hz")
        return nan_result(real(scene)) if f < 120.0 else real(scene)

    monkeypatch.setattr(fem.simulation, "simulate", flaky)
    space = space_from_dict(SPACE)
    planned, _ = plan_samples(space, 12)
    freqs = np.array([p.values["frequency_hz"] for p in planned])
    # threads in this process see the patched solver
    with LocalCluster(n_workers=1, threads_per_worker=2, processes=False, protocol="tcp",
                      host="127.0.0.1", dashboard_address=None) as cluster:
        rep = generate(space, 12, tmp_path / "d", scheduler=cluster.scheduler_address,
                       progress=False)
        assert rep.new_failed == int(np.sum((freqs > 200) | (freqs < 120))) > 0
        again = generate(space, 12, tmp_path / "d", scheduler=cluster.scheduler_address,
                         progress=False)
    assert again.new == 0  # failures are results: not retried, not duplicated
    df = _frame(tmp_path / "d")
    assert len(df) == 12
    for f, status, err in zip(df["frequency_hz"], df["status"], df["error"], strict=True):
        if f > 200:
            assert status == "failed"
            assert err.startswith(f"ValueError: synthetic failure at {f:.3f} Hz (at ")
        elif f < 120:
            assert status == "failed" and err == "NonFiniteResult: center_amplitude_um " \
                "contains NaN or inf"
        else:
            assert status == "ok" and pd.isna(err)
    assert validate_dataset(tmp_path / "d") == []


def test_run_sample_turns_invalid_scenes_into_failed_rows() -> None:
    out = run_sample({"analysis": {"kind": "harmonic", "frequency_hz": -1.0}})
    assert out["status"] == "failed" and out["error"].startswith("fem.scene.SceneError: ")
    assert "analysis.frequency_hz" in out["error"] and out["wall_s"] >= 0


def test_resume_refuses_other_space_or_solver(tmp_path: Path) -> None:
    out = tmp_path / "d"
    generate(space_from_dict(SPACE), 3, out, workers=1, progress=False)
    before = sorted(p.name for p in out.iterdir())
    other = copy.deepcopy(SPACE)
    other["space"]["seed"] = 6
    with pytest.raises(DatasetError, match="different space"):
        generate(space_from_dict(other), 5, out, workers=1, progress=False)
    m = json.loads((out / MANIFEST_NAME).read_text())
    m["solver"]["fingerprint"] = "0" * 64
    m["solver_history"] = [m["solver"]]
    m["digest"] = manifest_digest(m)  # as an older solver version would have written it
    (out / MANIFEST_NAME).write_text(json.dumps(m))
    with pytest.raises(DatasetError, match="allow_solver_change"):
        generate(space_from_dict(SPACE), 5, out, workers=1, progress=False)
    assert sorted(p.name for p in out.iterdir()) == before
    rep = generate(space_from_dict(SPACE), 5, out, workers=1, progress=False,
                   allow_solver_change=True)
    assert rep.new == 2
    assert len(Store.open(out).manifest["solver_history"]) == 2


# ----------------------------------------------------------------------------- kill -9


#: A sweep space (compact storage) for the kill test: coarse sweeps of about 0.7 s each.
SWEEP_SPACE: dict[str, Any] = {
    "space": {"name": "gen-sweep-test", "seed": 11},
    "base": {"mesh": SPACE["base"]["mesh"], "tissue": {"radius_mm": 30.0},
             "output": {"profile_length_mm": 10.0, "profile_step_mm": 2.0}},
    "parameter": SPACE["parameter"][:2],
    "band": {"start": 100.0, "stop": 250.0, "step": 10.0},
}


@pytest.mark.parametrize("space, n", [(SPACE, 150), (SWEEP_SPACE, 14)],
                         ids=["single-frequency", "sweep-compact"])
def test_kill_minus_9_and_resume(tmp_path: Path, space: dict[str, Any], n: int) -> None:
    space_file = tmp_path / "space.toml"
    space_file.write_text(_toml(space))
    out = tmp_path / "ds"
    cmd = [sys.executable, "-c", "import sys; from hapticrom.cli import main; "
           "sys.exit(main(sys.argv[1:]))", "generate", "--space", str(space_file), "--n",
           str(n), "--out", str(out), "--workers", "2", "--chunk", "1", "--flush-every", "2",
           "--no-progress"]
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    proc = subprocess.Popen(cmd, cwd=ROOT, env=env, start_new_session=True,
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline and proc.poll() is None:
            if out.is_dir() and len(list(out.glob("part-*.parquet"))) >= 3:
                break
            time.sleep(0.02)
        assert proc.poll() is None, "the run ended before it could be killed"
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait(10)
    finally:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(proc.pid, signal.SIGKILL)  # the workers of the killed run, if any
    before = {p.name: p.read_bytes() for p in out.glob("part-*.parquet")}
    rows_before = len(pd.read_parquet(out))
    assert 0 < rows_before < n
    (out / ".part-000500.parquet.tmp").write_bytes(b"half a part")  # as if killed mid-write
    res = subprocess.run(cmd, cwd=ROOT, env=env, capture_output=True, text=True, timeout=120)
    assert res.returncode == 0, res.stderr
    df = _frame(out)
    planned, _ = plan_samples(space_from_dict(copy.deepcopy(space)), n)
    assert len(df) == n and df["sample_id"].is_unique
    assert df["sample_index"].tolist() == [p.index for p in planned]
    assert not list(out.glob(".*.tmp"))
    for part in out.glob("part-*.parquet"):
        assert pq.read_table(part).num_rows > 0
    for name, data in before.items():
        assert (out / name).read_bytes() == data
    store = Store.open(out)
    runs = store.manifest["runs"]
    assert runs[0]["finished"] is None and runs[1]["todo"] == n - rows_before
    if "band" in space:  # every part, before and after the kill, compact and its error known
        assert store.codec is not None
        assert all(max(e["codec_error"].values()) <= 2.5e-4 + 2.0**-23
                   for e in store.manifest["parts"].values())
    assert validate_dataset(out) == []


# ----------------------------------------------------------------------------- CLI


def _bad_space(tmp_path: Path, change: dict[str, Any]) -> Path:
    d = copy.deepcopy(SPACE)
    d["parameter"][1].update(change)
    p = tmp_path / "bad.toml"
    p.write_text(_toml(d))
    return p


@pytest.mark.parametrize("change, message", [
    ({"low": 5.0, "high": 5.0}, "(fat_thickness_mm).high = 5.0 is out of range"),
    ({"path": "tissue.layer[1].thick_mm"}, "'fat_thickness_mm' = 9.0 (path "
                                           "'tissue.layer[1].thick_mm')"),
    ({"low": -3.0}, "tissue.layer[1].thickness_mm"),
    ({"type": "cont"}, "type = 'cont' is not allowed: choose one of 'continuous'"),
])
def test_cli_bad_space_exit_2_and_nothing_written(tmp_path: Path, change: dict[str, Any],
                                                  message: str,
                                                  capsys: pytest.CaptureFixture) -> None:
    out = tmp_path / "out"
    rc = main(["generate", "--space", str(_bad_space(tmp_path, change)), "--n", "4", "--out",
               str(out), "--no-progress"])
    assert rc == 2
    err = capsys.readouterr().err
    assert err.startswith("hapticrom generate: error:") and message in err
    assert not out.exists()


def test_cli_bad_arguments(tmp_path: Path, space_file: Path,
                           capsys: pytest.CaptureFixture) -> None:
    out = tmp_path / "out"
    base = ["generate", "--space", str(space_file), "--out", str(out), "--no-progress"]
    for args in (["--n", "0"], ["--n", "many"], ["--n", "3", "--flush-seconds", "0"]):
        assert main(base + args) == 2
        assert args[-2] in capsys.readouterr().err
    assert main([*base, "--n", "3", "--scheduler", "localhost"]) == 2
    assert "expected tcp://HOST:PORT" in capsys.readouterr().err
    (tmp_path / "space.broken.toml").write_text("[space\n")
    assert main(["generate", "--space", str(tmp_path / "space.broken.toml"), "--n", "3",
                 "--out", str(out)]) == 2
    assert "invalid TOML" in capsys.readouterr().err
    assert not out.exists()
    busy = tmp_path / "busy"
    busy.mkdir()
    (busy / "notes.txt").write_text("mine")
    assert main([*base[:-3], "--out", str(busy), "--n", "3"]) == 2
    assert "not a hapticrom dataset" in capsys.readouterr().err
    assert [p.name for p in busy.iterdir()] == ["notes.txt"]


def test_cli_generate_info_validate(tmp_path: Path, space_file: Path,
                                    capsys: pytest.CaptureFixture) -> None:
    out = tmp_path / "ds"
    assert main(["generate", "--space", str(space_file), "--n", "4", "--out", str(out),
                 "--workers", "1", "--no-progress"]) == 0
    assert "4 new samples (4 ok, 0 failed)" in capsys.readouterr().out
    assert main(["dataset", "info", str(out), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert (info["rows"], info["ok"], info["space"]) == (4, 4, "gen-test")
    assert info["parameters"] == ["skin_E_kPa", "fat_thickness_mm", "frequency_hz"]
    assert main(["dataset", "info", str(out)]) == 0
    assert "4 (4 ok, 0 failed)" in capsys.readouterr().out
    assert main(["dataset", "validate", str(out), "--rehash"]) == 0
    assert main(["dataset", "merge", "--out", str(tmp_path / "m"), str(out), str(out)]) == 0
    assert "4 rows from 8 (4 duplicates dropped)" in capsys.readouterr().out
    assert main(["dataset", "validate", str(tmp_path / "nothing")]) == 2


def test_workers_running_another_solver_are_refused(tmp_path: Path,
                                                    monkeypatch: pytest.MonkeyPatch) -> None:
    from distributed import LocalCluster

    import surrogate.data.generate as gen
    import surrogate.data.worker as worker

    monkeypatch.setattr(worker, "worker_solver_hash", lambda: "f" * 64)
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=False, protocol="tcp",
                      host="127.0.0.1", dashboard_address=None) as cluster, \
            pytest.raises(gen.RunnerError, match="a worker runs solver ffffffffffff"):
        generate(space_from_dict(SPACE), 3, tmp_path / "d", scheduler=cluster.scheduler_address,
                 progress=False)
    assert Store.open(tmp_path / "d").parts() == []  # nothing from the foreign solver


def test_transient_rows_store_time_histories(tmp_path: Path) -> None:
    d = copy.deepcopy(SPACE)
    d["base"] = {"load": {"kind": "unit"}, "unit": {"orientation": "reverse"},
                 "analysis": {"kind": "transient", "time_step_ms": 0.5, "duration_ms": 6.0,
                              "voltage_schedule": [[0.0, 3.3]]},
                 "mesh": SPACE["base"]["mesh"], "tissue": {"radius_mm": 30.0},
                 "output": {"radii_mm": [0.0, 5.0], "history_every": 2}}
    d["parameter"] = [SPACE["parameter"][0],
                      {"name": "drive_voltage_V", "type": "continuous",
                       "path": "analysis.voltage_schedule[0][1]", "low": 2.0, "high": 4.0}]
    space = space_from_dict(d)
    generate(space, 2, tmp_path / "t", workers=1, progress=False)
    df = _frame(tmp_path / "t")
    assert Store.open(tmp_path / "t").manifest["analysis_kind"] == "transient"
    planned, _ = plan_samples(space, 2)
    assert json.loads(df.loc[1, "scene_json"])["analysis"]["voltage_schedule"][0][1] == \
        planned[1].values["drive_voltage_V"]
    res = simulate(scene_from_dict(planned[1].scene))
    direct = res.to_dict()["histories"]
    np.testing.assert_array_equal(df.loc[1, "history_t_s"], res.histories.t)
    np.testing.assert_array_equal(df.loc[1, "history_r_mm"], [0.0, 5.0])
    probes = [point for point in direct["points"] if point["label"] == "probe"]
    assert len(probes) == 2
    for k, point in enumerate(probes):
        np.testing.assert_array_equal(df.loc[1, "history_uz_um"][k], point["uz_um"])
        np.testing.assert_array_equal(df.loc[1, "history_magnitude_um"][k],
                                      point["magnitude_um"])
    assert validate_dataset(tmp_path / "t") == []


def test_an_absurd_sample_count_is_refused_at_once(tmp_path: Path, space_file: Path,
                                                   capsys: pytest.CaptureFixture) -> None:
    from surrogate.data.plan import MAX_SAMPLES

    out = tmp_path / "out"
    assert main(["generate", "--space", str(space_file), "--out", str(out), "--n",
                 "2000000000", "--no-progress"]) == 2  # refused before planning a point
    assert f"allowed 1 <= n <= {MAX_SAMPLES}" in capsys.readouterr().err
    assert not out.exists()
