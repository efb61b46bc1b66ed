"""Dataset tools over a store: summary (``dataset_info``), checks (``validate_dataset``) and
``merge_datasets``. The command line's ``hapticrom dataset info|validate|merge`` call these."""

from __future__ import annotations

import json
import warnings
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa

from fem.scene import SceneError, scene_from_dict, scene_hash
from surrogate.data.codec import ARRAY_COLUMNS, CodecError, SweepCodec, worst_errors
from surrogate.data.digests import check_parts, part_entry, stray_files
from surrogate.data.errors import DatasetError
from surrogate.data.integrity import manifest_problems, part_problems
from surrogate.data.output_checks import check_outputs, outputs_summary
from surrogate.data.provenance import solver_key
from surrogate.data.space import Space
from surrogate.data.store import FEM_SOURCE, STATUSES, DatasetWarning, Store

__all__ = ["dataset_info", "merge_datasets", "seal_dataset", "validate_dataset"]

def dataset_info(path: str | Path) -> dict[str, Any]:
    """Summary of a dataset: manifest essentials plus counts computed from the parts."""
    with warnings.catch_warnings():  # reported below, in the summary
        warnings.simplefilter("ignore", DatasetWarning)
        store = Store.open(path, deep=True)
    problems = part_problems(store)
    if problems:  # counts over such parts would be wrong
        raise DatasetError(str(store.path), f"{store.path}: {'; '.join(problems)}")
    m = store.manifest
    space = m["space"]["space"]
    counts = store.counts()
    runs = m.get("runs", [])
    return {
        "path": str(store.path), "space": space.get("name"), "space_hash": m.get("space_hash"),
        "parameters": [p["name"] for p in m["space"].get("parameter", [])],
        "sampling": m.get("sampling"), "solver": m.get("solver"),
        "solver_versions": sorted({s.get("version", "?") + "+" + s.get("hash", "?")
                                   for s in m.get("solver_history", [])}),
        "analysis_kind": m.get("analysis_kind"), "mesh": m.get("mesh"),
        "outputs": outputs_summary(m, store.schema.names), "band": m.get("band"),
        "profile_grid_mm": m.get("profile_grid_mm"), **counts,
        "bytes": sum(p.stat().st_size for p in store.parts()),
        "temp_files": len(store.temp_files()),
        "stray_files": stray_files(store.path, m.get("parts") or {}),
        "runs": len(runs), "interrupted_runs": sum(1 for r in runs if r.get("finished") is None),
        "merged_from": m.get("merged_from"),
        "codec": _codec_summary(m.get("codec")),
    }


def _codec_summary(record: Any) -> dict[str, Any] | None:
    """A compact dataset's codec parameters and its largest error over every column."""
    if not isinstance(record, dict):
        return None
    keep = {k: record.get(k) for k in ("name", "version", "tolerance", "bound", "order")}
    return {**keep, "max_error": max((record.get("max_error") or {}).values(), default=None)}


def validate_dataset(path: str | Path, rehash: bool = False,
                     notes: list[str] | None = None) -> list[str]:
    """Check a dataset; return a list of problems (empty when valid); stray files (ignored,
    not a problem) are appended to ``notes``.

    Checks: the manifest's part records (every recorded part present, its rows hashing to the
    recorded digest, no unrecorded ``part-N.parquet``); every part readable with exactly the
    dataset schema; no (source, sample_id)
    twice; generated rows have unique sample indices (unless merged); statuses are "ok" or
    "failed"; failed rows carry error text; generated ok rows have finite amplitudes and a
    profile on the manifest grid; parameter values lie in the space; each part's solver is
    in the manifest history. A compact sweep dataset (:mod:`surrogate.data.codec`): every
    part's codes decode, its codec is the manifest's, and its codec error per column -- the
    one recorded when it was written and the one its stored steps prove -- is within the
    codec's bound. ``rehash`` recomputes every sample_id from scene_json."""
    store = Store.open(path, check=False)
    problems = [f"_manifest.json: {p}" for p in manifest_problems(store)]
    if any("section(s) are missing" in p or "not a valid space" in p for p in problems):
        return problems  # nothing below can be checked against a broken manifest
    check = check_parts(store, deep=True)
    problems += check.problems
    if notes is not None and check.strays:
        notes.append(f"ignored (not part of the dataset): {', '.join(check.strays)}")
    problems += part_problems(store)
    schema = store.stored_schema
    tables = []
    for part in store.parts():
        if not part.exists():
            continue  # a missing recorded part: reported above
        try:
            t = store.read_part(part)
        except DatasetError as err:
            problems.append(str(err))
            continue
        if not t.schema.remove_metadata().equals(schema):
            problems.append(f"{part.name}: schema differs from the dataset schema")
            continue
        problems += _check_part_solver(store, part)
        if store.codec is not None:
            problems += _check_codec(store, part, t)
            try:
                t = store.decode_part(part, t)
            except DatasetError as err:
                problems.append(str(err))
                continue
        tables.append(t.replace_schema_metadata(None))
    if not tables:
        return problems
    df = pa.concat_tables(tables).to_pandas()
    problems += _check_rows(store, df)
    if rehash:
        problems += _check_hashes(df)
    return problems


def _check_part_solver(store: Store, part: Path) -> list[str]:
    solver = store.part_metadata(part).get("solver")
    known = {solver_key(s) for s in store.manifest.get("solver_history", [])}
    if solver and solver_key(solver) not in known:
        return [f"{part.name}: written by solver {solver.get('version')} "
                f"({solver.get('hash')}), which the manifest does not list"]
    return []


def _check_codec(store: Store, part: Path, stored: pa.Table) -> list[str]:
    """A compact part's codec against the manifest's, and its errors against the bound."""
    codec = store.codec
    assert codec is not None
    name = part.name.removeprefix(".").removesuffix(".tmp")
    own = store.part_metadata(part).get("codec")
    if own != codec.part_record():
        return [f"{name}: written with codec {own!r}, not the dataset's {codec.part_record()}"]
    problems = []
    recorded = (store.manifest.get("parts") or {}).get(name, {}).get("codec_error")
    if not isinstance(recorded, dict) or set(recorded) != set(ARRAY_COLUMNS):
        problems.append(f"{name}: the manifest records no codec error for every column")
        recorded = {}
    try:
        proven = codec.proven(stored)
    except CodecError as err:
        return [*problems, f"{name}: its codes do not decode: {err}"]
    for col in ARRAY_COLUMNS:
        err = recorded.get(col)
        if err is not None and not (isinstance(err, float | int) and 0 <= err <= codec.bound):
            problems.append(f"{name}: {col}: codec error {err!r} recorded when it was written "
                            f"is above the bound {codec.bound:g} (of the band maximum at the "
                            "location)")
        if proven[col] > codec.bound:
            problems.append(f"{name}: {col}: its stored steps allow a codec error of "
                            f"{proven[col]:.3g}, above the bound {codec.bound:g} (of the band "
                            "maximum at the location)")
        elif isinstance(err, float | int) and err > proven[col] * (1 + 1e-9):
            problems.append(f"{name}: {col}: codec error {err:.3g} recorded, more than its "
                            f"codes allow ({proven[col]:.3g}): the record or the part was "
                            "edited")
    return problems


def _check_rows(store: Store, df: Any) -> list[str]:
    problems = []
    dup = df.duplicated(["source", "sample_id"])
    if dup.any():
        problems.append(f"{int(dup.sum())} rows repeat a (source, sample_id): "
                        f"{df.loc[dup, 'sample_id'].head(3).tolist()}")
    fem = df["source"] == FEM_SOURCE
    if not store.manifest.get("merged_from") and df.loc[fem, "sample_index"].duplicated().any():
        problems.append("generated rows repeat a sample_index")
    bad_status = ~df["status"].isin(STATUSES)
    if bad_status.any():
        problems.append(f"{int(bad_status.sum())} rows have a status other than ok/failed")
    no_error = (df["status"] == "failed") & (df["error"].isna() | (df["error"] == ""))
    if no_error.any():
        problems.append(f"{int(no_error.sum())} failed rows have no error text")
    ok_fem = fem & (df["status"] == "ok")
    if not store.manifest.get("band"):  # single-frequency magnitudes
        for col in ("edge_amplitude_um", "center_amplitude_um"):
            vals = df.loc[ok_fem, col].to_numpy(dtype=float)
            if vals.size and not np.all(np.isfinite(vals)):
                problems.append(f"generated ok rows with non-finite {col}")
        problems += _check_profiles(store, df.loc[ok_fem])
    problems += check_outputs(store.manifest, df.loc[ok_fem])
    problems += _check_ranges(store.space, df)
    return problems


def _check_profiles(store: Store, ok: Any) -> list[str]:
    grid = store.manifest.get("profile_grid_mm")
    problems = []
    for sid, d, a in zip(ok["sample_id"], ok["profile_distance_mm"],
                         ok["profile_magnitude_um"], strict=True):
        if d is None or a is None or len(d) != len(a):
            problems.append(f"sample {sid[:12]}: missing or ragged profile")
        elif grid is not None and (len(d) != len(grid) or not np.allclose(d, grid, atol=1e-9)):
            problems.append(f"sample {sid[:12]}: profile grid differs from the manifest's")
        if len(problems) >= 5:
            break
    return problems


def _check_ranges(space: Space, df: Any) -> list[str]:
    problems = []
    for p in space.parameters:
        col = df[p.name]
        if p.type in ("continuous", "integer"):
            bad = col.isna() | (col < p.low) | (col > p.high)
        elif p.type == "categorical":
            bad = ~col.isin(list(p.choices))
        else:
            bad = col != p.value
        if bad.any():
            problems.append(f"{int(bad.sum())} rows have {p.name} outside the space "
                            f"({p.allowed()}), e.g. {col[bad].iloc[0]!r}")
    return problems


def _check_hashes(df: Any) -> list[str]:
    problems = []
    for sid, text in zip(df["sample_id"], df["scene_json"], strict=True):
        try:
            actual = scene_hash(scene_from_dict(json.loads(text)))
        except (TypeError, ValueError, SceneError) as err:
            problems.append(f"sample {sid[:12]}: scene_json unreadable: {err}")
            continue
        if actual != sid:
            problems.append(f"sample {sid[:12]}: scene_json hashes to {actual[:12]}")
    return problems


def merge_datasets(out: str | Path, inputs: Sequence[str | Path],
                   allow_mixed_solvers: bool = False,
                   rows_per_part: int = 50_000) -> dict[str, Any]:
    """Write the union of ``inputs`` to a new dataset ``out`` (compacted into few parts).

    Inputs must have the same parameter columns; a row present in several inputs (same
    source and sample_id) is kept once, an "ok" copy before a "failed" one. Different solver
    versions need ``allow_mixed_solvers``. Only a merge of datasets from one space can be
    extended by ``generate``. When an input is compact (:mod:`surrogate.data.codec`) the
    union is: compact inputs' codes pass through unchanged (never rounded twice), float-list
    inputs are encoded, and every part records, per column, the largest error of all inputs.
    Returns counts; validates everything before writing."""
    if not inputs:
        raise DatasetError("inputs", "merge needs at least one input dataset")
    out = Path(out)
    if out.exists() and (not out.is_dir() or any(out.iterdir())):
        raise DatasetError("out", f"{out} exists and is not empty; merge writes a new dataset")
    stores = [Store.open(p) for p in inputs]
    first = stores[0]
    for s in stores[1:]:
        if s.schema.remove_metadata() != first.schema.remove_metadata():
            raise DatasetError(str(s.path), f"{s.path} has other columns than {first.path}; "
                               "only datasets over the same parameters can be merged")
    solvers = {solver_key(h): h
               for s in stores for h in s.manifest.get("solver_history", [])}
    if len(solvers) > 1 and not allow_mixed_solvers:
        listed = ", ".join(f"{v} ({str(h)[:12]})" for v, h in solvers)
        raise DatasetError("allow_mixed_solvers", f"the inputs were computed by different "
                           f"solvers ({listed}); allow_mixed_solvers (--allow-mixed-solvers) "
                           "merges anyway")
    codec = _merge_codec(stores)
    errors = None
    if codec is None:
        table = pa.concat_tables([s.read_table() for s in stores])
    else:
        table, errors = _stored_union(stores, codec)
    df = table.select(["source", "sample_id", "status"]).to_pandas()
    # lexsort: the last key is the primary one -> ok rows first, then input order
    order = np.lexsort((np.arange(len(df)), df["status"].ne("ok").to_numpy()))
    keep = ~df.iloc[order].duplicated(["source", "sample_id"]).to_numpy()
    rows = np.sort(order[keep])
    merged = table.take(pa.array(rows))
    hashes = {s.manifest.get("space_hash") for s in stores}
    manifest = {k: v for k, v in first.manifest.items()
                if k not in ("format", "schema_version", "created", "space", "space_hash",
                             "columns", "runs", "updated", "codec", "compacted_from")}
    if codec is not None:
        manifest["codec"] = codec.to_dict()
    manifest.update(solver_history=list(solvers.values()), merged_from=[
        {"path": str(s.path), "space_hash": s.manifest.get("space_hash"),
         "rows": s.counts()["rows"]} for s in stores])
    new = Store.create(out, first.space, **manifest)
    if len(hashes) > 1:
        new.manifest["space_hash"] = None  # not extendable: the inputs sampled other spaces
        new.manifest["spaces"] = sorted(h for h in hashes if h)
        new.save_manifest()
    with new.lock():
        for start in range(0, max(merged.num_rows, 1), rows_per_part):
            chunk = merged.slice(start, rows_per_part)
            if chunk.num_rows:
                new.write_part(chunk, {"source": "merge"}, encoded=errors)
    return {"rows_in": table.num_rows, "rows_out": merged.num_rows,
            "duplicates_dropped": table.num_rows - merged.num_rows, "parts": len(new.parts())}


def _merge_codec(stores: Sequence[Store]) -> SweepCodec | None:
    """The codec of a merge: the inputs' (one), None when no input is compact."""
    codecs = {s.codec for s in stores if s.codec is not None}
    if len(codecs) > 1:
        raise DatasetError("inputs", f"the inputs are compact with different codec parameters "
                           f"({', '.join(sorted(str(c) for c in codecs))}): not merged (their "
                           "codes would be rounded a second time)")
    return codecs.pop() if codecs else None


def _stored_union(stores: Sequence[Store], codec: SweepCodec
                  ) -> tuple[pa.Table, dict[str, float]]:
    """Every input's rows in ``codec``'s stored form, and the largest error per column."""
    tables, errors = [], [dict.fromkeys(ARRAY_COLUMNS, 0.0)]
    for s in stores:
        if s.codec is None:
            table, own = codec.encode(s.read_table())
        else:
            table = s.read_stored()
            own = s.manifest["codec"].get("max_error") or {}
        tables.append(table.cast(codec.stored_schema(stores[0].schema)))
        errors.append(own)
    return pa.concat_tables(tables), worst_errors(*errors)


def seal_dataset(path: str | Path) -> dict[str, Any]:
    """Record the part digests of a dataset written before hapticrom recorded them (see
    :mod:`surrogate.data.digests`), after a full :func:`validate_dataset` finds nothing
    wrong but their absence; a dataset already sealed is verified and left as it is.
    Returns ``{"parts", "rows", "sealed"}``; :class:`DatasetError` lists the problems and
    writes nothing."""
    store = Store.open(path, check=False)
    if isinstance(store.manifest.get("parts"), dict):
        store.verify(deep=True)
        rows = sum(int(e["rows"]) for e in store.manifest["parts"].values())
        return {"parts": len(store.manifest["parts"]), "rows": rows, "sealed": False}
    with store.lock():
        problems = [p for p in validate_dataset(path)
                    if "records no part digests" not in p]
        if problems:
            raise DatasetError(str(store.path), f"{store.path}: not sealed, fix first: "
                               f"{'; '.join(problems)}")
        entries = {p.name: part_entry(p) for p in store.parts()}
        store.manifest["parts"] = entries
        store.save_manifest()
    return {"parts": len(entries), "rows": sum(e["rows"] for e in entries.values()),
            "sealed": True}
