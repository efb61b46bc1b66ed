"""The head start of `generate`: the first chunks run while the rest is planned, each sample
runs once, and a plan that fails after the head start writes nothing."""

from __future__ import annotations

import copy
from pathlib import Path

import pandas as pd
import pytest
from test_generate import SPACE

import surrogate.data.generate as gen
from surrogate.data.backends import PoolBackend
from surrogate.data.errors import SpaceError
from surrogate.data.plan import plan_samples
from surrogate.data.space import load_space, space_from_dict


def test_every_sample_is_submitted_once_and_the_head_goes_first(tmp_path: Path, monkeypatch):
    submitted: list[list[float]] = []
    real_submit, real_plan = PoolBackend.submit, gen.plan_samples
    events: list[str] = []

    def submit(self, payload):
        import json

        submitted.append([s["analysis"]["frequency_hz"] for s in json.loads(payload)])
        events.append("submit")
        return real_submit(self, payload)

    def plan(space, n):
        events.append(f"plan {n}")
        return real_plan(space, n)

    monkeypatch.setattr(PoolBackend, "submit", submit)
    monkeypatch.setattr(gen, "plan_samples", plan)
    rep = gen.generate(space_from_dict(SPACE), 6, tmp_path / "d", workers=1, chunk=2,
                       progress=False)
    assert rep.new_ok == 6
    assert events[:3] == ["plan 2", "submit", "plan 6"]  # head: one chunk per worker
    assert sum(len(c) for c in submitted) == 6 and len(submitted) == 3
    df = pd.read_parquet(tmp_path / "d")
    planned, _ = plan_samples(space_from_dict(SPACE), 6)
    assert sorted(df["sample_id"]) == sorted(p.sample_id for p in planned)
    assert not (tmp_path / "d" / "_lock").exists()


def test_a_plan_failing_after_the_head_start_writes_nothing(tmp_path: Path, monkeypatch):
    real_plan = gen.plan_samples

    def plan(space, n):
        if n > 2:
            raise SpaceError("parameter x.path", "sample 5: invalid (test)")
        return real_plan(space, n)

    monkeypatch.setattr(gen, "plan_samples", plan)
    with pytest.raises(SpaceError, match="sample 5"):
        gen.generate(space_from_dict(SPACE), 6, tmp_path / "d", workers=1, chunk=2,
                     progress=False)
    assert not (tmp_path / "d").exists()


def test_resume_does_not_resubmit_stored_samples(tmp_path: Path, monkeypatch):
    space = space_from_dict(SPACE)
    gen.generate(space, 4, tmp_path / "d", workers=1, chunk=2, progress=False)
    count = []
    real_submit = PoolBackend.submit

    def submit(self, payload):
        import json

        count.append(len(json.loads(payload)))
        return real_submit(self, payload)

    monkeypatch.setattr(PoolBackend, "submit", submit)
    rep = gen.generate(space, 6, tmp_path / "d", workers=1, chunk=2, progress=False)
    assert (rep.already_done, rep.new) == (4, 2) and sum(count) == 2


def test_a_space_failing_its_scene_check_after_the_head_start_writes_nothing(tmp_path: Path):
    """A space file is checked after the head start is submitted (to start sooner); its error
    is the checker's and the disk is untouched."""
    from test_generate import _toml

    d = copy.deepcopy(SPACE)
    d["parameter"].append({"name": "probe_9", "type": "continuous",
                           "path": "output.radii_mm[9]", "low": 1.0, "high": 2.0})
    path = tmp_path / "bad.toml"
    path.write_text(_toml(d))
    with pytest.raises(SpaceError) as checked:
        load_space(path)  # the check a space file always gets
    with pytest.raises(SpaceError) as err:
        gen.generate(path, 4, tmp_path / "d", workers=1, chunk=2, progress=False)
    assert str(err.value) == str(checked.value) and "radii_mm" in str(err.value)
    assert not (tmp_path / "d").exists()
