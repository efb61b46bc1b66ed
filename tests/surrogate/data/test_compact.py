"""Compact sweep datasets in the store: what the manifest records, the pandas recipe of
docs/datasets.md, damaged and tampered parts, old datasets, and ``dataset compact``."""

from __future__ import annotations

import json
import re
import shutil
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from test_sweep_data import _dataset, fake_sweep

from hapticrom.cli import main
from hapticrom.commands.dataset import format_info
from surrogate.data.codec import ARRAY_COLUMNS, STEP_COLUMN, SweepCodec, code_column
from surrogate.data.columns import sweep_arrays
from surrogate.data.compact import compact_dataset
from surrogate.data.digests import part_entry
from surrogate.data.errors import DatasetError
from surrogate.data.inspect import dataset_info, validate_dataset
from surrogate.data.integrity import manifest_digest
from surrogate.data.store import MANIFEST_NAME, Store
from surrogate.data.worker import outputs_from_result

ROOT = Path(__file__).resolve().parents[3]
#: The codec's tolerance (2.5e-4 of the band maximum) plus float32 rounding of decoded values.
WITHIN = 2.5e-4 + 2.0**-23


def _manifest(path: Path) -> dict:
    return json.loads((path / MANIFEST_NAME).read_text())


def _save_manifest(path: Path, m: dict) -> None:
    """A consistent envelope (digest recomputed), as a careless tool would leave it."""
    m["digest"] = manifest_digest(m)
    (path / MANIFEST_NAME).write_text(json.dumps(m))


def _rewrite_part(path: Path, change, index: int = 0) -> str:
    """Apply ``change`` to the stored table of a part, record it consistently."""
    part = sorted(path.glob("part-*.parquet"))[index]
    t = pq.read_table(part)
    pq.write_table(change(t), part)
    m = _manifest(path)
    m["parts"][part.name] = {**m["parts"][part.name], **part_entry(part)}
    _save_manifest(path, m)
    return part.name


def _bytes(path: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(path.iterdir()) if p.is_file()}


# ------------------------------------------------------------------------ the stored form


def test_a_compact_set_records_its_codec_and_errors_and_stores_codes(tmp_path):
    path = _dataset(tmp_path / "d", n=6)
    m = _manifest(path)
    assert m["codec"]["name"] == "sweep-step-codes" and m["codec"]["bound"] == 3e-4
    errors = [e["codec_error"] for e in m["parts"].values()]
    assert len(errors) == 2 and all(set(e) == set(ARRAY_COLUMNS) for e in errors)
    assert all(0 < v <= WITHIN for e in errors for v in e.values())
    assert m["codec"]["max_error"] == {c: max(e[c] for e in errors) for c in ARRAY_COLUMNS}
    stored = pq.read_table(sorted(path.glob("part-*.parquet"))[0])
    assert not set(ARRAY_COLUMNS) & set(stored.column_names)
    assert stored.schema.field(code_column(ARRAY_COLUMNS[0])).type == pa.list_(pa.int16())
    store = Store.open(path, deep=True)
    assert store.schema.field("sweep_profile_ur_im_um").type == pa.list_(pa.float32())
    assert store.read_table(["sweep_edge_uz_re_um", "sample_index"]).column_names == \
        ["sweep_edge_uz_re_um", "sample_index"]
    meta = store.part_metadata(store.parts()[0])
    assert meta["codec"] == SweepCodec().part_record()
    assert meta["codec_error"] == m["parts"][store.parts()[0].name]["codec_error"]
    assert validate_dataset(path) == []
    info = dataset_info(path)
    assert info["codec"] == {**SweepCodec().part_record(),
                             "max_error": max(m["codec"]["max_error"].values())}
    assert "storage   compact: sweep-step-codes v1 (bound 0.0003" in format_info(info)
    assert dataset_info(_dataset(tmp_path / "old", compact=False))["codec"] is None


def _recipe(doc: str) -> str:
    text = (ROOT / doc).read_text()
    block = re.search(r"```python\n(# recipe: compact sweep dataset\n.*?)```", text, re.S)
    assert block, f"the recipe is missing from {doc}"
    return block.group(1)


@pytest.mark.parametrize("doc", ["docs/datasets.md", "datasets/README.md"])
def test_the_documented_pandas_recipe_gives_the_stores_arrays(tmp_path, doc):
    path = _dataset(tmp_path / "d", n=5)
    code = _recipe(doc).replace('DIR = "datasets/default-sweep"', f"DIR = {str(path)!r}")
    assert code != _recipe(doc)
    env: dict = {}
    exec(compile(code, "docs/datasets.md recipe", "exec"), env)
    df = Store.open(path).read()
    assert env["df"]["sample_id"].tolist() == df["sample_id"].tolist()
    for where in ("center", "edge", "profile"):
        got = np.stack([env["sweep"](where, c) for c in "rzt"], axis=-1)   # (n, loc, n_f, 3)
        for i in range(len(df)):
            want = sweep_arrays(df.loc[i], where)                          # (n_f, [n_p,] 3)
            want = want[:, None] if where != "profile" else want
            np.testing.assert_allclose(got[i].transpose(1, 0, 2), want, rtol=1e-6,
                                       atol=1e-7 * np.abs(want).max())
    assert env["uz"].shape == (5, 6, 16)


# ------------------------------------------------------------------ damage and tampering


@pytest.fixture(scope="module")
def pristine(tmp_path_factory) -> Path:
    return _dataset(tmp_path_factory.mktemp("compact") / "d", n=6)


@settings(max_examples=25, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(which=st.integers(0, 1), at=st.floats(0.0, 1.0), length=st.integers(1, 64),
       mask=st.integers(1, 255))
def test_a_damaged_compressed_part_is_refused_by_name(pristine, tmp_path, which, at, length,
                                                      mask):
    path = tmp_path / "work"
    shutil.rmtree(path, ignore_errors=True)
    shutil.copytree(pristine, path)
    part = sorted(path.glob("part-*.parquet"))[which]
    data = bytearray(part.read_bytes())
    start = int(at * (len(data) - length))
    data[start:start + length] = bytes(b ^ mask for b in data[start:start + length])
    part.write_bytes(bytes(data))
    before = _bytes(path)
    with pytest.raises(DatasetError, match=part.name):
        Store.open(path)
    problems = validate_dataset(path)
    assert problems and all(part.name in p for p in problems), problems
    with pytest.raises(DatasetError, match=part.name):
        compact_dataset(path, tmp_path / "out")
    assert _bytes(path) == before and not (tmp_path / "out").exists()


def test_validate_and_info_exit_2_naming_a_damaged_part(tmp_path, capsys):
    path = _dataset(tmp_path / "d", n=6)
    part = sorted(path.glob("part-*.parquet"))[1]
    data = bytearray(part.read_bytes())
    mid = len(data) // 2
    data[mid:mid + 64] = bytes(b ^ 0xA5 for b in data[mid:mid + 64])
    part.write_bytes(bytes(data))
    assert main(["dataset", "validate", str(path)]) == 2
    assert part.name in capsys.readouterr().out
    assert main(["dataset", "info", str(path)]) == 2
    assert part.name in capsys.readouterr().err


def test_steps_coarser_than_the_bound_fail_validate_by_part_and_column(tmp_path, capsys):
    path = _dataset(tmp_path / "d")

    def coarser(t: pa.Table) -> pa.Table:  # re-encoded on steps 4x as large, same record
        logical = SweepCodec().decode(t)
        stored, _ = SweepCodec(tolerance=1e-3, bound=3e-3).encode(logical)
        return stored.replace_schema_metadata(t.schema.metadata)

    name = _rewrite_part(path, coarser)
    Store.open(path, deep=True)  # a consistent envelope: only the codec check sees it
    problems = validate_dataset(path)
    hits = [p for p in problems if p.startswith(f"{name}: sweep_") and "above the bound" in p]
    assert len(hits) == len(ARRAY_COLUMNS), problems
    assert "sweep_profile_uz_re_um: its stored steps allow a codec error of 0.001" in \
        "".join(hits)
    assert main(["dataset", "validate", str(path)]) == 2
    assert f"problem: {name}: sweep_center_ur_re_um" in capsys.readouterr().out


def test_a_recorded_codec_error_above_the_bound_fails_validate(tmp_path):
    path = _dataset(tmp_path / "d")
    m = _manifest(path)
    name = sorted(m["parts"])[1]
    m["parts"][name]["codec_error"]["sweep_edge_ut_im_um"] = 4e-4
    _save_manifest(path, m)
    problems = validate_dataset(path)
    assert any(p.startswith(f"{name}: sweep_edge_ut_im_um: codec error 0.0004 recorded") and
               "above the bound 0.0003" in p for p in problems), problems


def test_a_recorded_error_below_what_the_codes_allow_is_consistent_not_above(tmp_path):
    path = _dataset(tmp_path / "d")
    m = _manifest(path)
    name = sorted(m["parts"])[0]
    m["parts"][name]["codec_error"]["sweep_center_ur_re_um"] = 2.9e-4  # > provable 2.5e-4
    _save_manifest(path, m)
    assert any("more than its codes allow" in p and name in p for p in validate_dataset(path))


def test_a_part_written_with_another_codec_is_named(tmp_path):
    path = _dataset(tmp_path / "d")

    def other(t: pa.Table) -> pa.Table:
        meta = json.loads(t.schema.metadata[b"hapticrom"])
        meta["codec"]["order"] = 2
        return t.replace_schema_metadata({"hapticrom": json.dumps(meta)})

    name = _rewrite_part(path, other)
    assert any(p.startswith(f"{name}: written with codec") for p in validate_dataset(path))


def test_codes_that_do_not_decode_are_refused_by_name(tmp_path):
    path = _dataset(tmp_path / "d")

    def shorter(t: pa.Table) -> pa.Table:
        i = t.schema.get_field_index("sweep_edge_uz_re_q")
        return t.set_column(i, t.schema.field(i), pa.array(
            [row[:-1] for row in t.column(i).to_pylist()], t.schema.field(i).type))

    name = _rewrite_part(path, shorter)
    with pytest.raises(DatasetError, match=f"{name}: its codes do not decode"):
        Store.open(path).read()
    assert any(name in p and "do not decode" in p for p in validate_dataset(path))


# ------------------------------------------------------------------------ old datasets


def test_an_old_float_list_set_is_read_exactly_and_extended_in_its_own_form(tmp_path):
    path = _dataset(tmp_path / "d", n=4, compact=False)
    store = Store.open(path)
    assert store.codec is None and "codec" not in store.manifest
    row = {**outputs_from_result(fake_sweep(9)), "skin_E_kPa": 50.0, "fat_thickness_mm": 9.0,
           "status": "ok", "sample_id": "e" * 64, "sample_index": 99,
           "source": "hapticrom-fem"}
    with store.lock():
        store.write_part([row])
    for part in Store.open(path).parts():
        t = pq.read_table(part)
        assert t.schema.field("sweep_profile_uz_re_um").type == pa.list_(pa.float32())
        assert STEP_COLUMN not in t.column_names
    df = Store.open(path).read().sort_values("sample_index").reset_index(drop=True)
    want = fake_sweep(1).profile * 1e6
    np.testing.assert_array_equal(sweep_arrays(df.loc[1], "profile"),
                                  want.real.astype(np.float32) + 1j * want.imag.astype(
                                      np.float32))
    assert len(df) == 5 and validate_dataset(path) == []


# ------------------------------------------------------------------ dataset compact


def test_compact_reencodes_every_row_and_keeps_the_provenance(tmp_path):
    src = _dataset(tmp_path / "old", n=7, compact=False)
    before = _bytes(src)
    res = compact_dataset(src, tmp_path / "new", rows_per_part=3)
    assert _bytes(src) == before  # the source is only read
    assert (res["rows"], res["parts_in"], res["parts_out"]) == (7, 2, 3)
    assert 0 < res["max_error"] <= WITHIN
    new, old = Store.open(tmp_path / "new", deep=True), Store.open(src)
    assert new.codec == SweepCodec() and new.manifest["space_hash"] == old.manifest["space_hash"]
    cf = new.manifest["compacted_from"]
    assert cf["manifest_digest"] == old.manifest["digest"] and cf["rows"] == 7
    for key in ("sampling", "solver", "solver_history", "runs", "band", "profile_grid_mm"):
        assert new.manifest[key] == old.manifest[key]
    a, b = old.read(), new.read()
    assert a.drop(columns=list(ARRAY_COLUMNS)).equals(b.drop(columns=list(ARRAY_COLUMNS)))
    for col in ARRAY_COLUMNS:
        x, y = np.stack(a[col]), np.stack(b[col])
        assert np.abs(x - y).max() <= 2.5e-4 * np.abs(x).max() * np.sqrt(6)
    assert validate_dataset(tmp_path / "new") == []


def test_compacting_the_same_parts_again_gives_the_same_bytes(tmp_path):
    """A set re-compacted as its source grows keeps its full parts byte for byte (git then
    stores only the new ones): no clock in a part."""
    src = _dataset(tmp_path / "old", n=7, compact=False)
    compact_dataset(src, tmp_path / "a", rows_per_part=3)
    compact_dataset(src, tmp_path / "b", rows_per_part=3)
    a, b = _bytes(tmp_path / "a"), _bytes(tmp_path / "b")
    parts = sorted(k for k in a if k.startswith("part-"))
    assert len(parts) == 3 and all(a[k] == b[k] for k in parts)


def test_compact_cli_refuses_an_existing_out_unless_overwrite(tmp_path, capsys):
    src = _dataset(tmp_path / "old", n=4, compact=False)
    out = _dataset(tmp_path / "out", n=2)
    kept = _bytes(out)
    assert main(["dataset", "compact", str(src), "--out", str(out)]) == 2
    assert "exists; --overwrite replaces it" in capsys.readouterr().err
    assert _bytes(out) == kept
    assert main(["dataset", "compact", str(src), "--out", str(out), "--overwrite"]) == 0
    assert Store.open(out).counts()["rows"] == 4
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]


@pytest.mark.parametrize("case, words", [
    ("same", "is the source dataset or inside it"),
    ("inside", "is the source dataset or inside it"),
    ("compact", "is compact already"),
    ("no parent", "does not exist"),
    ("not a dataset", "is not a hapticrom dataset"),
    ("rows", "rows_per_part = 0"),
])
def test_compact_refuses_bad_arguments_and_writes_nothing(tmp_path, case, words):
    src = _dataset(tmp_path / "old", n=2, compact=case == "compact")
    out = {"same": src, "inside": src / "sub", "no parent": tmp_path / "x" / "y",
           "not a dataset": tmp_path / "notes"}.get(case, tmp_path / "new")
    if case == "not a dataset":
        out.mkdir()
        (out / "keep.txt").write_text("mine")
    listing = sorted(p.name for p in tmp_path.rglob("*"))
    with pytest.raises(DatasetError, match=words):
        compact_dataset(src, out, overwrite=True, rows_per_part=0 if case == "rows" else 8)
    assert sorted(p.name for p in tmp_path.rglob("*")) == listing


def test_compact_refuses_a_single_frequency_dataset(tmp_path):
    from synthetic import make_dataset

    src = make_dataset(tmp_path / "single", n=4)
    with pytest.raises(DatasetError, match="not a sweep dataset"):
        compact_dataset(src, tmp_path / "new")
    assert not (tmp_path / "new").exists()


@pytest.mark.parametrize("existing", [False, True])
def test_a_failing_compaction_leaves_no_half_written_out(tmp_path, monkeypatch, existing):
    src = _dataset(tmp_path / "old", n=6, compact=False)
    out = tmp_path / "new"
    if existing:
        compact_dataset(src, out, rows_per_part=2)
    kept = _bytes(out) if existing else None
    real = Store.write_part
    calls = []

    def failing(self, rows, metadata=None):
        calls.append(1)
        if len(calls) == 2:
            raise KeyboardInterrupt  # as Ctrl-C in the middle of the work
        return real(self, rows, metadata)

    monkeypatch.setattr(Store, "write_part", failing)
    with pytest.raises(KeyboardInterrupt):
        compact_dataset(src, out, overwrite=True, rows_per_part=2)
    assert len(calls) == 2
    assert (_bytes(out) == kept) if existing else not out.exists()
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]


def test_merge_of_compact_and_old_sets_is_compact_like_the_first(tmp_path):
    from surrogate.data.inspect import merge_datasets

    a = _dataset(tmp_path / "a", n=4)
    b = _dataset(tmp_path / "b", n=6, compact=False)  # rows 0-3 repeat a's
    res = merge_datasets(tmp_path / "m", [a, b])
    assert (res["rows_in"], res["rows_out"]) == (10, 6)
    merged = Store.open(tmp_path / "m")
    assert merged.codec == SweepCodec() and "max_error" in merged.manifest["codec"]
    assert validate_dataset(tmp_path / "m") == []
    got = merged.read().sort_values("sample_index").reset_index(drop=True)
    first = Store.open(a).read().sort_values("sample_index").reset_index(drop=True)
    for col in ARRAY_COLUMNS:  # a's codes passed through: its rows decode identically
        np.testing.assert_array_equal(np.stack(got[col][:4]), np.stack(first[col]))
    errors = [e["codec_error"] for e in merged.manifest["parts"].values()]
    of_a = _manifest(a)["codec"]["max_error"]
    assert all(of_a[c] <= e[c] <= WITHIN for e in errors for c in ARRAY_COLUMNS)


def test_merge_refuses_compact_inputs_of_other_codec_parameters(tmp_path):
    from surrogate.data.inspect import merge_datasets

    a = _dataset(tmp_path / "a", n=2)
    b = _dataset(tmp_path / "b", n=2)
    m = _manifest(b)
    m["codec"]["tolerance"] = 2e-4
    _save_manifest(b, m)
    with pytest.raises(DatasetError, match="different codec parameters"):
        merge_datasets(tmp_path / "m", [a, b])
    assert not (tmp_path / "m").exists()


def test_a_codec_for_a_single_frequency_space_is_refused(tmp_path):
    from synthetic import SPACE as SINGLE

    from surrogate.data.space import space_from_dict

    with pytest.raises(DatasetError, match="only sweep datasets"):
        Store.create(tmp_path / "d", space_from_dict(SINGLE), codec=SweepCodec().to_dict())
    assert not (tmp_path / "d").exists()


@pytest.mark.parametrize("other_solver", [False, True])
def test_compact_joins_the_parts_of_one_solver_and_keeps_their_revisions(tmp_path,
                                                                        other_solver):
    src = _dataset(tmp_path / "old", n=6, compact=False)
    m = _manifest(src)
    solvers = [{**m["solver"], "git_revision": "a" * 40},
               {**m["solver"], "git_revision": "b" * 40,
                **({"fingerprint": "f" * 64} if other_solver else {})}]
    if other_solver:  # a second solver the manifest records, as --allow-solver-change does
        m["solver_history"].append(solvers[1])
        _save_manifest(src, m)
    for i, solver in enumerate(solvers):
        def with_solver(t: pa.Table, solver=solver) -> pa.Table:
            meta = {"source": "hapticrom-fem", "solver": solver, "space_hash": m["space_hash"]}
            return t.replace_schema_metadata({"hapticrom": json.dumps(meta)})

        _rewrite_part(src, with_solver, index=i)
    res = compact_dataset(src, tmp_path / "new")
    new = Store.open(tmp_path / "new")
    metas = [new.part_metadata(p) for p in new.parts()]
    if other_solver:
        assert res["parts_out"] == 2
        assert [x["git_revisions"] for x in metas] == [["a" * 40], ["b" * 40]]
        assert metas[1]["solver"]["fingerprint"] == "f" * 64
    else:
        assert res["parts_out"] == 1 and metas[0]["git_revisions"] == ["a" * 40, "b" * 40]
    assert validate_dataset(tmp_path / "new") == []

