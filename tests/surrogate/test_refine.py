"""Active learning: batch selection and one refinement round on a cheap FE space."""

from __future__ import annotations

import copy

import numpy as np
import pytest

from hapticrom.cli import main
from surrogate.data.generate import generate
from surrogate.data.space import space_from_dict
from surrogate.data.store import Store
from surrogate.refine import refine, select_batch
from tests.surrogate.data.test_generate import SPACE


def test_select_batch_takes_the_most_uncertain_spread_out_points():
    X = np.array([[0.0, 0.0], [0.01, 0.0], [1.0, 1.0], [0.5, 0.5]])
    score = np.array([10.0, 9.0, 1.0, 5.0])
    assert list(select_batch(score, X, 1)) == [0]
    # [1] is as uncertain as [0] but sits on top of it: the next pick is [3]
    assert list(select_batch(score, X, 2, min_distance=0.1)) == [0, 3]
    # too few rows far enough apart: the distance shrinks until k are found
    assert sorted(select_batch(score, X, 4, min_distance=10.0)) == [0, 1, 2, 3]
    with pytest.raises(ValueError, match="k = 5"):
        select_batch(score, X, 5)


def test_refine_adds_samples_of_the_space_where_the_gp_is_least_certain(tmp_path):
    space = space_from_dict(copy.deepcopy(SPACE))
    out = tmp_path / "d"
    generate(space, 24, out, workers=1, progress=False)
    report = refine(out, 6, rounds=2, workers=1, progress=False)
    store = Store.open(out)
    df = store.read()
    assert len(df) == 36 and (df["status"] == "ok").all()
    assert df["sample_id"].is_unique
    assert [r["rows_before"] for r in report.rounds] == [24, 30]
    assert store.manifest["sampling"]["target_n"] == 24  # refinement is not the sequence
    # the picks are more uncertain than the average candidate
    assert all(r["mean_log_std_picked"] > r["mean_log_std_pool"] for r in report.rounds)
    # extending the dataset along its sequence afterwards keeps the refined rows
    generate(space, 32, out, workers=1, progress=False)
    assert len(Store.open(out).read()) >= 36 + 8 - 6


def test_refine_cli_rejects_a_bad_batch(tmp_path, capsys):
    assert main(["refine", str(tmp_path), "--batch", "0"]) == 2
    assert "--batch" in capsys.readouterr().err
