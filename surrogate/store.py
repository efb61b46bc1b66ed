"""Dataset store: a directory of Parquet parts plus a JSON manifest.

Layout::

    DIR/_manifest.json          schema version, space, sampling, solver, mesh, runs
    DIR/_lock                   advisory lock held by the one process writing DIR
    DIR/part-000001.parquet     immutable data parts (zstd), written atomically
    DIR/.part-000002.parquet.tmp   a part being written (or left by a killed run)

Readers need one line: ``pandas.read_parquet(DIR)``. pyarrow's dataset discovery ignores
files whose names start with ``_`` or ``.``, so the manifest, the lock and unfinished
temporary parts are never read as data. A part is written to its temporary name, flushed to
disk (fsync) and renamed with ``os.replace``, which is atomic on POSIX: a reader sees either
no part or a complete one, even after ``kill -9``.

Every row carries its provenance: ``sample_id`` (sha256 of the resolved scene,
``fem.scene.scene_hash``), ``sample_index`` (position in the design sequence for generated
rows, row number in the source file for ingested rows), ``status`` ("ok" or "failed"),
``error`` (text for failed rows), ``source`` ("hapticrom-fem" or "ingest:FILENAME"),
``wall_s`` [s], ``dofs``, ``elements``, ``solver_version``, ``solver_hash``, the resolved
scene as canonical JSON (``scene_json``) and the solver's warnings (``warnings``, e.g. an
under-resolved mesh; "; "-joined, null if none). Then one column per space parameter, then the
outputs: centre/edge amplitudes [um], normalized edge amplitude [-], the surface profile
(list columns ``profile_distance_mm``, ``profile_uz_um``, ``profile_magnitude_um``) and, for
transient scenes, time histories (``history_t_s``, ``history_r_mm`` and per-point lists
``history_uz_um``, ``history_magnitude_um``; for a unit also ``history_center_um`` and
``history_edge_um``, each [u_r, u_z, u_theta]). The key of a row is (source, sample_id).
"""

from __future__ import annotations

import contextlib
import datetime as _dt
import errno
import fcntl
import json
import os
import re
from collections.abc import Iterator, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

from surrogate.space import Space, space_from_dict

__all__ = [
    "FEM_SOURCE",
    "MANIFEST_NAME",
    "SCHEMA_VERSION",
    "DatasetError",
    "Store",
    "arrow_schema",
    "profile_matrix",
    "utc_now",
]

SCHEMA_VERSION = 1
FORMAT = "hapticrom-dataset"
MANIFEST_NAME = "_manifest.json"
LOCK_NAME = "_lock"
FEM_SOURCE = "hapticrom-fem"
_PART_RE = re.compile(r"^part-(\d{6,})\.parquet$")
_TMP_RE = re.compile(r"^\.part-(\d{6,})\.parquet\.tmp$")
_TYPES = {"float64": pa.float64(), "int64": pa.int64(), "string": pa.string(),
          "bool": pa.bool_()}
_F64_LIST = pa.list_(pa.float64())

PROVENANCE_FIELDS = [
    pa.field("sample_id", pa.string(), nullable=False),
    pa.field("sample_index", pa.int64(), nullable=False),
    pa.field("status", pa.string(), nullable=False),
    pa.field("error", pa.string()),
    pa.field("source", pa.string(), nullable=False),
    pa.field("wall_s", pa.float64()),
    pa.field("dofs", pa.int64()),
    pa.field("elements", pa.int64()),
    pa.field("solver_version", pa.string()),
    pa.field("solver_hash", pa.string()),
    pa.field("scene_json", pa.string()),
    pa.field("warnings", pa.string()),
]
OUTPUT_FIELDS = [
    pa.field("center_amplitude_um", pa.float64()),
    pa.field("edge_amplitude_um", pa.float64()),
    pa.field("normalized_edge", pa.float64()),
    pa.field("profile_distance_mm", _F64_LIST),
    pa.field("profile_uz_um", _F64_LIST),
    pa.field("profile_magnitude_um", _F64_LIST),
    pa.field("history_t_s", _F64_LIST),
    pa.field("history_r_mm", _F64_LIST),
    pa.field("history_uz_um", pa.list_(_F64_LIST)),
    pa.field("history_magnitude_um", pa.list_(_F64_LIST)),
    # transient unit runs: [u_r, u_z, u_theta] histories (um) at the center and edge points
    pa.field("history_center_um", pa.list_(_F64_LIST)),
    pa.field("history_edge_um", pa.list_(_F64_LIST)),
]
STATUSES = ("ok", "failed")


class DatasetError(ValueError):
    """Bad dataset input or state (not a dataset, locked, incompatible space or solver).
    ``field`` names what is wrong (a path, a manifest key or a CLI option)."""

    def __init__(self, field: str, message: str) -> None:
        super().__init__(message)
        self.field = field


def utc_now() -> str:
    """Current UTC time, ISO 8601 with seconds."""
    return _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds")


def arrow_schema(space: Space) -> pa.Schema:
    """The fixed Arrow schema of a dataset over ``space``: provenance, parameters, outputs."""
    params = [pa.field(p.name, _TYPES[p.column_type]) for p in space.parameters]
    return pa.schema(PROVENANCE_FIELDS + params + OUTPUT_FIELDS)


def _fsync_dir(path: Path) -> None:
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def write_json_atomic(path: Path, data: Mapping[str, Any]) -> None:
    """Write JSON to ``path`` via a temporary file and ``os.replace`` (atomic)."""
    tmp = path.with_name(f".{path.name}.tmp")
    with open(tmp, "w", encoding="utf-8") as fh:
        json.dump(data, fh, indent=1, sort_keys=False, allow_nan=False)
        fh.write("\n")
        fh.flush()
        os.fsync(fh.fileno())
    os.replace(tmp, path)
    _fsync_dir(path.parent)


class Store:
    """An existing dataset directory. Open with :meth:`open`, create with :meth:`create`."""

    def __init__(self, path: Path, manifest: dict[str, Any]) -> None:
        self.path = Path(path)
        self.manifest = manifest
        self._space: Space | None = None

    # ---- creating and opening

    @classmethod
    def create(cls, path: str | Path, space: Space, **manifest: Any) -> Store:
        """Create ``path`` (must not exist, or be an empty directory) with a manifest for
        ``space``; extra keyword arguments are stored in the manifest."""
        path = Path(path)
        if path.exists() and (not path.is_dir() or any(path.iterdir())):
            raise DatasetError(str(path), f"{path} exists and is not an empty directory")
        head = {"format": FORMAT, "schema_version": SCHEMA_VERSION, "created": utc_now(),
                "space": space.to_dict(), "space_hash": space.space_hash(),
                "columns": [{"name": f.name, "type": str(f.type)} for f in arrow_schema(space)]}
        data = {**head, **manifest}
        data.setdefault("runs", [])
        path.mkdir(parents=True, exist_ok=True)
        write_json_atomic(path / MANIFEST_NAME, data)
        store = cls(path, data)
        store._space = space
        return store

    @classmethod
    def open(cls, path: str | Path) -> Store:
        """Open an existing dataset; :class:`DatasetError` if ``path`` is not one."""
        path = Path(path)
        mpath = path / MANIFEST_NAME
        if not mpath.is_file():
            raise DatasetError(str(path), f"{path} is not a hapticrom dataset "
                               f"(no {MANIFEST_NAME})")
        try:
            data = json.loads(mpath.read_text(encoding="utf-8"))
        except (OSError, json.JSONDecodeError) as err:
            raise DatasetError(str(mpath), f"cannot read {mpath}: {err}") from None
        if data.get("format") != FORMAT:
            raise DatasetError(str(mpath), f"{mpath}: format {data.get('format')!r} is not "
                               f"{FORMAT!r}")
        if data.get("schema_version") != SCHEMA_VERSION:
            raise DatasetError(str(mpath), f"{mpath}: schema_version "
                               f"{data.get('schema_version')!r} is not supported (this "
                               f"version reads {SCHEMA_VERSION})")
        return cls(path, data)

    @classmethod
    def exists(cls, path: str | Path) -> bool:
        """True when ``path`` holds a dataset manifest."""
        return (Path(path) / MANIFEST_NAME).is_file()

    @property
    def space(self) -> Space:
        """The space recorded in the manifest (scene checks skipped: it was checked when
        the dataset was created)."""
        if self._space is None:
            self._space = space_from_dict(self.manifest["space"], check_scenes=False)
        return self._space

    @property
    def schema(self) -> pa.Schema:
        """The Arrow schema every part must have."""
        return arrow_schema(self.space)

    def save_manifest(self) -> None:
        """Write the (modified) manifest atomically."""
        self.manifest["updated"] = utc_now()
        write_json_atomic(self.path / MANIFEST_NAME, self.manifest)

    # ---- locking

    @contextlib.contextmanager
    def lock(self) -> Iterator[None]:
        """Hold the dataset's advisory write lock (released by the OS even on kill -9)."""
        fh = open(self.path / LOCK_NAME, "a+")
        try:
            try:
                fcntl.flock(fh.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError as err:
                if err.errno in (errno.EAGAIN, errno.EACCES):
                    raise DatasetError(str(self.path), f"{self.path} is being written by "
                                       "another process (lock held); wait for it to finish"
                                       ) from None
                raise
            yield
        finally:
            fh.close()

    # ---- parts

    def parts(self) -> list[Path]:
        """Complete part files, in write order."""
        found = [(int(m.group(1)), p) for p in self.path.iterdir()
                 if (m := _PART_RE.match(p.name))]
        return [p for _, p in sorted(found)]

    def temp_files(self) -> list[Path]:
        """Unfinished parts (ignored by readers)."""
        return sorted(p for p in self.path.iterdir() if _TMP_RE.match(p.name))

    def remove_temp_files(self) -> list[Path]:
        """Delete unfinished parts left by an interrupted writer (call under :meth:`lock`)."""
        removed = self.temp_files()
        for p in removed:
            p.unlink(missing_ok=True)
        return removed

    def _next_seq(self) -> int:
        seqs = [int(m.group(1)) for p in self.path.iterdir()
                if (m := _PART_RE.match(p.name) or _TMP_RE.match(p.name))]
        return max(seqs, default=0) + 1

    def write_part(self, rows: Sequence[Mapping[str, Any]] | pa.Table,
                   metadata: Mapping[str, Any] | None = None) -> Path:
        """Write ``rows`` (dicts keyed by column, missing columns are null; or an Arrow table
        with the dataset schema) as a new part, atomically. ``metadata`` goes into the
        Parquet key-value metadata under ``hapticrom``. Call under :meth:`lock`."""
        if isinstance(rows, pa.Table):
            table = rows.replace_schema_metadata(None).cast(self.schema)
        else:
            table = rows_to_table(rows, self.schema)
        if metadata:
            table = table.replace_schema_metadata(
                {"hapticrom": json.dumps(dict(metadata), sort_keys=True)})
        seq = self._next_seq()
        final = self.path / f"part-{seq:06d}.parquet"
        tmp = self.path / f".{final.name}.tmp"
        pq.write_table(table, tmp, compression="zstd")
        with open(tmp, "rb") as fh:
            os.fsync(fh.fileno())
        os.replace(tmp, final)
        _fsync_dir(self.path)
        return final

    # ---- reading

    def read_part(self, part: Path, columns: Sequence[str] | None = None) -> pa.Table:
        """One part as an Arrow table; :class:`DatasetError` naming the file if unreadable."""
        try:
            return pq.read_table(part, columns=list(columns) if columns else None)
        except (OSError, pa.ArrowException) as err:
            raise DatasetError(str(part), f"cannot read part {part}: {err}") from None

    def read_table(self, columns: Sequence[str] | None = None) -> pa.Table:
        """All rows as one Arrow table with the dataset schema."""
        tables = [self.read_part(p, columns) for p in self.parts()]
        if not tables:
            schema = self.schema
            if columns:
                schema = pa.schema([schema.field(c) for c in columns])
            return schema.empty_table()
        return pa.concat_tables([t.replace_schema_metadata(None) for t in tables])

    def read(self, columns: Sequence[str] | None = None) -> Any:
        """All rows as a pandas DataFrame (same as ``pandas.read_parquet(DIR)``)."""
        return self.read_table(columns).to_pandas()

    def keys(self) -> tuple[set[tuple[str, str]], dict[int, str]]:
        """(set of (source, sample_id), {sample_index: sample_id} of generated rows)."""
        keys: set[tuple[str, str]] = set()
        index: dict[int, str] = {}
        for part in self.parts():
            t = self.read_part(part, ["source", "sample_id", "sample_index"]).to_pydict()
            for src, sid, idx in zip(t["source"], t["sample_id"], t["sample_index"],
                                     strict=True):
                keys.add((src, sid))
                if src == FEM_SOURCE:
                    index[idx] = sid
        return keys, index

    def part_metadata(self, part: Path) -> dict[str, Any]:
        """The ``hapticrom`` key-value metadata of a part ({} if none)."""
        meta = pq.read_schema(part).metadata or {}
        raw = meta.get(b"hapticrom")
        return json.loads(raw) if raw else {}

    def counts(self) -> dict[str, Any]:
        """Row counts by status and by source, computed from the parts."""
        t = self.read_table(["status", "source"]).to_pydict()
        by_source: dict[str, int] = {}
        for src in t["source"]:
            by_source[src] = by_source.get(src, 0) + 1
        return {"rows": len(t["status"]), "ok": t["status"].count("ok"),
                "failed": t["status"].count("failed"), "parts": len(self.parts()),
                "by_source": by_source}


def rows_to_table(rows: Sequence[Mapping[str, Any]], schema: pa.Schema) -> pa.Table:
    """Arrow table from row dicts, with exactly ``schema`` (unknown keys are an error)."""
    names = set(schema.names)
    for i, row in enumerate(rows):
        extra = set(row) - names
        if extra:
            raise DatasetError("row", f"row {i} has unknown columns {sorted(extra)}")
    cols = {name: [_py(row.get(name)) for row in rows] for name in schema.names}
    return pa.table(cols, schema=schema)


def _py(value: Any) -> Any:
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    return value


def profile_matrix(df: Any, grid_mm: Sequence[float],
                   column: str = "profile_magnitude_um") -> np.ndarray:
    """Profiles of every row linearly interpolated onto ``grid_mm`` [mm]: an array of shape
    (rows, len(grid)) in the column's unit, NaN where a row has no profile or the grid point
    lies outside that row's distance range (no extrapolation)."""
    grid = np.asarray(grid_mm, dtype=float)
    out = np.full((len(df), grid.size), np.nan)
    for i, (d, a) in enumerate(zip(df["profile_distance_mm"], df[column], strict=True)):
        if d is None or a is None or len(d) == 0:
            continue
        d, a = np.asarray(d, dtype=float), np.asarray(a, dtype=float)
        inside = (grid >= d.min()) & (grid <= d.max())
        out[i, inside] = np.interp(grid[inside], d, a)
    return out


# --------------------------------------------------------------------------- solver identity


#: fem modules that cannot change a solution (reports, closed-form references): editing them
#: must not mark a dataset as coming from another solver.
NOT_SOLVER_SOURCES = frozenset({"reproduce.py", "analytic.py", "parallel.py"})


def solver_info(git: bool = True) -> dict[str, Any]:
    """Identity of the installed solver: ``version`` (fem.SOLVER_VERSION), ``source_sha256``
    (hash of every .py file of the fem package but ``NOT_SOLVER_SOURCES``: changes with any
    solver code edit, git or not),
    ``hash`` (its first 12 hex digits, stored per row) and ``git_revision`` (HEAD of the
    repository holding fem, "+dirty" when fem/ has uncommitted changes; "unknown" outside
    git or with ``git=False``)."""
    import hashlib

    import fem

    root = Path(fem.__file__).resolve().parent
    digest = hashlib.sha256()
    for f in sorted(root.rglob("*.py")):
        if f.name in NOT_SOLVER_SOURCES:
            continue
        digest.update(f.relative_to(root).as_posix().encode() + b"\0")
        digest.update(f.read_bytes() + b"\0")
    source = digest.hexdigest()
    return {"version": str(getattr(fem, "SOLVER_VERSION", "unknown")), "source_sha256": source,
            "hash": source[:12], "git_revision": _git_revision(root) if git else "unknown"}


def _git_revision(fem_dir: Path) -> str:
    import subprocess

    # GIT_OPTIONAL_LOCKS=0: `git status` must not write to the index of the user's repository.
    env = {**os.environ, "GIT_OPTIONAL_LOCKS": "0"}
    try:
        rev = subprocess.run(["git", "-C", str(fem_dir), "rev-parse", "HEAD"], env=env,
                             capture_output=True, text=True, timeout=10)
        if rev.returncode != 0:
            return "unknown"
        dirty = subprocess.run(["git", "-C", str(fem_dir), "status", "--porcelain",
                                "--untracked-files=normal", "--", "."], env=env,
                               capture_output=True, text=True, timeout=10)
    except (OSError, subprocess.SubprocessError):
        return "unknown"
    return rev.stdout.strip() + ("+dirty" if dirty.stdout.strip() else "")


# --------------------------------------------------------------------------- dataset tools


def dataset_info(path: str | Path) -> dict[str, Any]:
    """Summary of a dataset: manifest essentials plus counts computed from the parts."""
    store = Store.open(path)
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
        "profile_grid_mm": m.get("profile_grid_mm"), **counts,
        "bytes": sum(p.stat().st_size for p in store.parts()),
        "temp_files": len(store.temp_files()),
        "runs": len(runs), "interrupted_runs": sum(1 for r in runs if r.get("finished") is None),
        "merged_from": m.get("merged_from"),
    }


def validate_dataset(path: str | Path, rehash: bool = False) -> list[str]:
    """Check a dataset; return a list of problems (empty when valid).

    Checks: every part readable with exactly the dataset schema; no (source, sample_id)
    twice; generated rows have unique sample indices (unless merged); statuses are "ok" or
    "failed"; failed rows carry error text; generated ok rows have finite amplitudes and a
    profile on the manifest grid; parameter values lie in the space; each part's solver is
    in the manifest history. ``rehash`` recomputes every sample_id from scene_json."""
    store = Store.open(path)
    problems: list[str] = []
    schema = store.schema
    tables = []
    for part in store.parts():
        try:
            t = store.read_part(part)
        except DatasetError as err:
            problems.append(str(err))
            continue
        if not t.schema.remove_metadata().equals(schema):
            problems.append(f"{part.name}: schema differs from the dataset schema")
            continue
        problems += _check_part_solver(store, part)
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
    known = {s.get("source_sha256") for s in store.manifest.get("solver_history", [])}
    if solver and solver.get("source_sha256") not in known:
        return [f"{part.name}: written by solver {solver.get('version')} "
                f"({solver.get('hash')}), which the manifest does not list"]
    return []


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
    for col in ("edge_amplitude_um", "center_amplitude_um"):
        vals = df.loc[ok_fem, col].to_numpy(dtype=float)
        if vals.size and not np.all(np.isfinite(vals)):
            problems.append(f"generated ok rows with non-finite {col}")
    problems += _check_profiles(store, df.loc[ok_fem])
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
    from fem.scene import SceneError, scene_from_dict, scene_hash

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
    extended by ``generate``. Returns counts; validates everything before writing."""
    if not inputs:
        raise DatasetError("inputs", "merge needs at least one input dataset")
    out = Path(out)
    if out.exists() and (not out.is_dir() or any(out.iterdir())):
        raise DatasetError("--out", f"{out} exists and is not empty; merge writes a new dataset")
    stores = [Store.open(p) for p in inputs]
    first = stores[0]
    for s in stores[1:]:
        if s.schema.remove_metadata() != first.schema.remove_metadata():
            raise DatasetError(str(s.path), f"{s.path} has other columns than {first.path}; "
                               "only datasets over the same parameters can be merged")
    solvers = {(h.get("version"), h.get("source_sha256")): h
               for s in stores for h in s.manifest.get("solver_history", [])}
    if len(solvers) > 1 and not allow_mixed_solvers:
        listed = ", ".join(f"{v} ({str(h)[:12]})" for v, h in solvers)
        raise DatasetError("--allow-mixed-solvers", f"the inputs were computed by different "
                           f"solvers ({listed}); pass --allow-mixed-solvers to merge anyway")
    table = pa.concat_tables([s.read_table() for s in stores])
    df = table.to_pandas()
    # lexsort: the last key is the primary one -> ok rows first, then input order
    order = np.lexsort((np.arange(len(df)), df["status"].ne("ok").to_numpy()))
    keep = ~df.iloc[order].duplicated(["source", "sample_id"]).to_numpy()
    rows = np.sort(order[keep])
    merged = table.take(pa.array(rows))
    hashes = {s.manifest.get("space_hash") for s in stores}
    manifest = {k: v for k, v in first.manifest.items()
                if k not in ("format", "schema_version", "created", "space", "space_hash",
                             "columns", "runs", "updated")}
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
                new.write_part(chunk, {"source": "merge"})
    return {"rows_in": table.num_rows, "rows_out": merged.num_rows,
            "duplicates_dropped": table.num_rows - merged.num_rows, "parts": len(new.parts())}
