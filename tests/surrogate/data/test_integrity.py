"""A dataset's manifest and parts are checked: hand edits and copied parts are refused."""

from __future__ import annotations

import json
import re
import shutil
from pathlib import Path

import pytest

from surrogate.data.errors import DatasetError
from surrogate.data.generate import generate
from surrogate.data.inspect import dataset_info, validate_dataset
from surrogate.data.integrity import manifest_digest
from surrogate.data.provenance import solver_info
from surrogate.data.space import space_from_dict
from surrogate.data.store import MANIFEST_NAME, Store, new_manifest

SHIPPED = Path(__file__).resolve().parents[3] / "datasets" / "default"


@pytest.fixture
def dataset(tmp_path):
    """A generated-style dataset (manifest from new_manifest) with two parts of rows."""
    from synthetic import SPACE, make_dataset

    src = make_dataset(tmp_path / "src", 8)
    space = space_from_dict(SPACE)
    out = tmp_path / "d"
    grid = json.loads((src / MANIFEST_NAME).read_text())["profile_grid_mm"]
    manifest = {**new_manifest(space, solver_info(git=False)), "profile_grid_mm": grid}
    store = Store.create(out, space, **manifest)
    rows = Store.open(src).read_table()
    with store.lock():
        store.write_part(rows.slice(0, 4))
        store.write_part(rows.slice(4))
    return out


def _edit(path: Path, change) -> None:
    m = json.loads((path / MANIFEST_NAME).read_text())
    change(m)
    (path / MANIFEST_NAME).write_text(json.dumps(m))


def test_a_written_manifest_carries_its_digest(dataset):
    m = json.loads((dataset / MANIFEST_NAME).read_text())
    assert m["digest"] == manifest_digest(m)
    assert validate_dataset(dataset) == []


@pytest.mark.parametrize("change, message", [
    (lambda m: m["sampling"].update(seed=8), "does not match its digest"),
    (lambda m: m["space"]["parameter"][2].update(high=150.0), "space was edited"),
    (lambda m: m["solver"].update(hash="other"), "digest"),
    (lambda m: m.pop("sampling"), "does not match its digest"),
])
def test_hand_edits_are_refused_by_open_and_listed_by_validate(dataset, change, message):
    _edit(dataset, change)
    with pytest.raises(DatasetError, match="Restore the manifest") as info:
        Store.open(dataset)
    assert message in str(info.value)
    assert any(message in p for p in validate_dataset(dataset))


@pytest.mark.parametrize("change, message", [
    (lambda m: (m["sampling"].update(seed=8), m.pop("digest")), "is not the space's seed"),
    (lambda m: (m["space"]["parameter"][2].update(high=150.0), m.pop("digest")),
     "space was edited"),
    (lambda m: (m["solver"].update(fingerprint="x", version="9"), m.pop("digest")),
     "not in solver_history"),
    (lambda m: (m["runs"].append({"command": "generate"}), m.pop("sampling"), m.pop("digest")),
     "sampling section(s) are missing"),  # a generated dataset (it records runs)
])
def test_without_a_digest_the_semantic_checks_still_catch_edits(dataset, change, message):
    _edit(dataset, change)
    with pytest.raises(DatasetError, match=re.escape(message)):
        Store.open(dataset)


def test_a_copied_part_is_found_by_generate_info_and_validate(dataset):
    from synthetic import SPACE

    parts = Store.open(dataset).parts()
    shutil.copy(parts[0], dataset / "part-000009.parquet")
    with pytest.raises(DatasetError, match=r"part-000009\.parquet is not recorded"):
        generate(space_from_dict(SPACE), 8, dataset, workers=1, progress=False)
    with pytest.raises(DatasetError, match=r"part-000009\.parquet is not recorded"):
        dataset_info(dataset)
    assert any("part-000009.parquet is not recorded in the manifest" in p
               for p in validate_dataset(dataset))


def test_a_part_of_another_space_is_foreign(dataset, tmp_path):
    from synthetic import make_dataset

    other = make_dataset(tmp_path / "other", 3, start=100)
    m = json.loads((other / MANIFEST_NAME).read_text())
    m["space"]["space"]["seed"] = 99  # another space: another hash
    m["space_hash"] = space_from_dict(m["space"]).space_hash()
    m["digest"] = manifest_digest(m)
    (other / MANIFEST_NAME).write_text(json.dumps(m))
    store = Store.open(other)
    with store.lock():
        store.write_part(store.read_table())  # records the other space's hash
    shutil.copy(store.parts()[-1], dataset / "part-000009.parquet")
    assert any("part-000009.parquet is not recorded in the manifest" in p
               for p in validate_dataset(dataset))


def test_the_shipped_dataset_is_sealed_and_opens():
    m = json.loads((SHIPPED / MANIFEST_NAME).read_text())
    assert m["digest"] == manifest_digest(m)
    assert sorted(m["parts"]) == [p.name for p in sorted(SHIPPED.glob("part-*.parquet"))]
    Store.open(SHIPPED)
