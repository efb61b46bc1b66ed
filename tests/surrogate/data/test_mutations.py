"""Datasets checked to the row: every alteration of a part or the manifest is refused by every
reader, naming the altered file, and nothing is written (issue 21 item 3).

The mutation catalogue is the one of ``bench/datasets/mutations.py``; hypothesis draws
the mutation, the part, the row, the column and the damaged bytes."""

from __future__ import annotations

import importlib.util
import json
import os
import shutil
import warnings
from pathlib import Path

import pandas as pd
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from surrogate.data.errors import DatasetError
from surrogate.data.generate import generate
from surrogate.data.inspect import dataset_info, merge_datasets, validate_dataset
from surrogate.data.store import DatasetWarning, Store
from surrogate.train import load_datasets

_BENCH = Path(__file__).resolve().parents[3] / "bench" / "datasets" / "mutations.py"
_spec = importlib.util.spec_from_file_location("mutations", _BENCH)
mut = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(mut)


@pytest.fixture(scope="module")
def pristine(tmp_path_factory):
    root = tmp_path_factory.mktemp("mut")
    space = root / "space.toml"
    space.write_text(mut.SPACE_TOML)
    return mut.build_dataset(root / "pristine", space), space


def _fresh(pristine, tmp_path, name="work"):
    work = tmp_path / name
    shutil.rmtree(work, ignore_errors=True)
    shutil.copytree(pristine, work)
    return work


def _readers(work, space, out):
    """Every library reader, each as a call that must raise DatasetError."""
    return {
        "open": lambda: Store.open(work).read(),
        "info": lambda: dataset_info(work),
        "generate": lambda: generate(space, 26, work, workers=1, progress=False),
        "train": lambda: load_datasets([work]),
        "merge": lambda: merge_datasets(out / "merged", [work]),
    }


@settings(max_examples=60, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(mutation=st.sampled_from(sorted(mut.MUTATIONS)), rnd=st.randoms(use_true_random=False),
       reader=st.sampled_from(["open", "info", "generate", "train", "merge", "validate"]))
def test_every_mutation_is_refused_naming_the_file_and_nothing_is_written(
        pristine, tmp_path, mutation, rnd, reader):
    dataset, space = pristine
    work = _fresh(dataset, tmp_path)
    out = tmp_path / "out"
    shutil.rmtree(out, ignore_errors=True)
    out.mkdir()
    named = mut.MUTATIONS[mutation](work, lambda n: rnd.randrange(n))
    before = mut.snapshot(work)
    if reader == "validate":
        try:
            problems = validate_dataset(work)
        except DatasetError as err:  # a manifest that cannot be read at all
            problems = [str(err)]
        assert any(named in p for p in problems), problems
    else:
        with pytest.raises(DatasetError) as info:
            _readers(work, space, out)[reader]()
        assert named in str(info.value)
    assert mut.snapshot(work) == before
    assert not any(out.iterdir())


@pytest.mark.parametrize("mutation", sorted(mut.MUTATIONS))
@pytest.mark.parametrize("command", ["info", "validate", "generate", "train", "refine", "merge"])
def test_every_command_exits_2_naming_the_file(pristine, tmp_path, mutation, command):
    dataset, space = pristine
    work = _fresh(dataset, tmp_path)
    scratch = tmp_path / "scratch"
    scratch.mkdir()
    named = mut.MUTATIONS[mutation](work, lambda n: n // 2)
    before = mut.snapshot(work)
    code, text = mut.run_cli(mut.commands(work, space, scratch)[command])
    assert (code, mut.classify(code, text, named, before, mut.snapshot(work),
                               any(scratch.iterdir()))) == (2, "refused"), text


def test_row_edit_x1000_was_accepted_before_and_is_refused_now(pristine, tmp_path):
    """The defect as reported: centre amplitude x1000 passed validate --rehash, info,
    generate and train."""
    dataset, _space = pristine
    work = _fresh(dataset, tmp_path)
    part = sorted(work.glob("part-*.parquet"))[1]
    df = pd.read_parquet(part)
    df.loc[3, "center_amplitude_um"] *= 1000
    df.to_parquet(part)
    for argv in (["dataset", "validate", "--rehash", str(work)], ["dataset", "info", str(work)],
                 ["train", "--data", str(work), "--kind", "gp", "--out", str(tmp_path / "m")]):
        code, text = mut.run_cli(argv)
        assert code == 2 and "part-000002.parquet" in text, text
    assert not (tmp_path / "m").exists()


def test_strays_are_ignored_by_every_reader_and_the_pandas_recipe_agrees(pristine, tmp_path):
    dataset, _ = pristine
    work = _fresh(dataset, tmp_path)
    shutil.copy(work / "part-000001.parquet", work / "old copy.parquet")
    (work / "notes.txt").write_text("mine")
    with pytest.warns(DatasetWarning, match="notes.txt"):
        ours = Store.open(work).read()
    m = json.loads((work / "_manifest.json").read_text())  # the recipe of datasets/README.md
    recipe = pd.concat([pd.read_parquet(work / name) for name in sorted(m["parts"])],
                       ignore_index=True)
    pd.testing.assert_frame_equal(ours.reset_index(drop=True), recipe)
    assert len(ours) == 24
    assert dataset_info(work)["stray_files"] == ["notes.txt", "old copy.parquet"]
    notes: list[str] = []
    assert validate_dataset(work, notes=notes) == []
    assert "notes.txt" in notes[0]
    code, text = mut.run_cli(["dataset", "validate", str(work)])
    assert code == 0 and "note: ignored" in text


def test_a_part_recorded_but_not_yet_renamed_is_read_and_finished(pristine, tmp_path):
    """kill -9 between the manifest save (commit) and the rename: readers read the part under
    its temporary name; the next writer finishes the rename."""
    dataset, _space = pristine
    work = _fresh(dataset, tmp_path)
    os.replace(work / "part-000003.parquet", work / ".part-000003.parquet.tmp")
    with warnings.catch_warnings():
        warnings.simplefilter("error", DatasetWarning)
        assert len(Store.open(work, deep=True).read()) == 24
    assert validate_dataset(work) == []
    store = Store.open(work)
    with store.lock():
        assert store.remove_temp_files() == []
    assert (work / "part-000003.parquet").is_file()
    assert not (work / ".part-000003.parquet.tmp").exists()


def test_an_unrecorded_temp_part_is_never_read(pristine, tmp_path):
    dataset, _ = pristine
    work = _fresh(dataset, tmp_path)
    shutil.copy(work / "part-000001.parquet", work / ".part-000004.parquet.tmp")
    assert len(Store.open(work).read()) == 24
    store = Store.open(work)
    with store.lock():
        assert [p.name for p in store.remove_temp_files()] == [".part-000004.parquet.tmp"]


def test_seal_records_the_digests_of_an_old_dataset_after_validating_it(pristine, tmp_path):
    dataset, _ = pristine
    work = _fresh(dataset, tmp_path)
    mut.manifest_strip(work, lambda n: 0)
    with pytest.raises(DatasetError, match="dataset seal"):
        Store.open(work)
    code, text = mut.run_cli(["dataset", "seal", str(work)])
    assert code == 0 and "sealed: 3 parts, 24 rows" in text
    assert len(Store.open(work, deep=True).read()) == 24
    code, text = mut.run_cli(["dataset", "seal", str(work)])
    assert code == 0 and "already sealed" in text


def test_seal_refuses_a_damaged_old_dataset_and_writes_nothing(pristine, tmp_path):
    dataset, _ = pristine
    work = _fresh(dataset, tmp_path)
    mut.manifest_strip(work, lambda n: 0)
    shutil.copy(work / "part-000001.parquet", work / "part-000007.parquet")
    before = mut.snapshot(work)
    code, text = mut.run_cli(["dataset", "seal", str(work)])
    assert code == 2 and "part-000007.parquet repeats 8 sample" in text
    assert mut.snapshot(work) == before
