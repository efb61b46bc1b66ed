"""Never destroy what hapticrom did not write (issue 21, item 1): ``train --out`` with
``--overwrite`` replaces only a model directory hapticrom wrote, never the dataset it reads
nor a directory of other files; the refusal names the path and what it holds."""

from __future__ import annotations

import json

import pytest
from model_dirs import copy_model, tree

from hapticrom.cli import main
from surrogate.registry import write_model


def train(data, out, *extra):
    return main(["train", "--data", str(data), "--kind", "gp", "--out", str(out), *extra])


def test_train_never_deletes_the_dataset_it_reads(synthetic_dataset, capsys):
    """Before: `train --data D --out D --overwrite` printed "wrote D" and deleted D."""
    before = tree(synthetic_dataset)
    assert train(synthetic_dataset, synthetic_dataset, "--overwrite") == 2
    err = capsys.readouterr().err
    assert "overlaps the input" in err and str(synthetic_dataset) in err
    assert tree(synthetic_dataset) == before
    assert train(synthetic_dataset, synthetic_dataset / "model", "--overwrite") == 2
    assert tree(synthetic_dataset) == before


def test_train_refuses_a_directory_of_user_files(synthetic_dataset, tmp_path, capsys):
    """Before: a directory with notes.txt and sub/keep.txt given as --out was deleted."""
    user = tmp_path / "mine"
    (user / "sub").mkdir(parents=True)
    (user / "notes.txt").write_text("keep me")
    (user / "sub" / "keep.txt").write_text("me too")
    before = tree(user)
    assert train(synthetic_dataset, user, "--overwrite") == 2
    err = capsys.readouterr().err
    assert str(user) in err and "notes.txt" in err and "sub/" in err
    assert "did not write" in err
    assert tree(user) == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["mine"]  # no temporary left


def test_train_refuses_another_dataset_and_a_model_holding_user_files(
        synthetic_dataset, tmp_path, capsys):
    other = tmp_path / "other-data"
    (other).mkdir()
    (other / "_manifest.json").write_text(json.dumps({"format": "hapticrom-dataset"}))
    assert train(synthetic_dataset, other, "--overwrite") == 2
    assert "a hapticrom dataset" in capsys.readouterr().err
    model = copy_model("gp", tmp_path / "model")
    (model / "notes.txt").write_text("mine")
    before = tree(model)
    assert train(synthetic_dataset, model, "--overwrite") == 2
    assert "notes.txt" in capsys.readouterr().err
    assert tree(model) == before


def test_write_model_replaces_only_its_own_directory(tmp_path):
    card = {"kind": "rom", "coefficients": "c.json"}
    out = write_model(tmp_path / "m", card, {"c.json": b"{}"})
    with pytest.raises(FileExistsError):
        write_model(out, card, {"c.json": b"{}"})
    write_model(out, card, {"c.json": b"{ }"}, overwrite=True)
    assert (out / "c.json").read_bytes() == b"{ }"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["m"]
    user = tmp_path / "user"
    user.mkdir()
    (user / "a.txt").write_text("x")
    with pytest.raises(ValueError, match=r"a\.txt"):
        write_model(user, card, {"c.json": b"{}"}, overwrite=True)
    assert (user / "a.txt").read_text() == "x"
    empty = tmp_path / "empty"
    empty.mkdir()
    write_model(empty, card, {"c.json": b"{}"})  # an empty directory is fine


def test_merge_never_writes_into_an_input(synthetic_dataset, capsys):
    before = tree(synthetic_dataset)
    assert main(["dataset", "merge", "--out", str(synthetic_dataset / "merged"),
                 str(synthetic_dataset)]) == 2
    assert "overlaps the input" in capsys.readouterr().err
    assert tree(synthetic_dataset) == before and not (synthetic_dataset / "merged").exists()


def test_the_library_refuses_before_training(synthetic_dataset, tmp_path):
    from surrogate.envelope.fit import train as train_rom
    from surrogate.train import train as train_surrogate

    user = tmp_path / "user"
    user.mkdir()
    (user / "notes.txt").write_text("x")
    with pytest.raises(ValueError, match=r"notes\.txt"):
        train_surrogate([synthetic_dataset], "gp", user, overwrite=True)
    with pytest.raises(ValueError, match=r"notes\.txt"):
        train_rom([synthetic_dataset], user, overwrite=True)
    assert (user / "notes.txt").read_text() == "x"
