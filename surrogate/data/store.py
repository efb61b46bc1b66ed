"""Dataset store: a directory of Parquet parts plus a JSON manifest.

Layout::

    DIR/_manifest.json          schema version, space, sampling, solver, mesh, runs
    DIR/_lock                   advisory lock held by the one process writing DIR (deleted
                                when it finishes, also after a failure)
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
outputs: center/edge amplitudes [um], normalized edge amplitude [-], the surface profile
(list columns ``profile_distance_mm``, ``profile_uz_um``, ``profile_magnitude_um``) and, for
transient scenes, time histories (``history_t_s``, ``history_r_mm`` and per-point lists
``history_uz_um``, ``history_magnitude_um``; for a unit also ``history_center_um`` and
``history_edge_um``, each [u_r, u_z, u_theta]). ``edge_radius_mm`` is the unit's outer radius
(the solver's definition; null for datasets written before it was stored). The key of a row is
(source, sample_id).
"""

from __future__ import annotations

import contextlib
import copy
import datetime as _dt
import json
import os
import re
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

from surrogate.data.errors import DatasetError
from surrogate.data.integrity import manifest_digest, manifest_problems, part_problems
from surrogate.data.lockfile import exclusive
from surrogate.data.space import Space, space_from_dict

__all__ = [
    "FEM_SOURCE",
    "MANIFEST_NAME",
    "SCHEMA_VERSION",
    "DatasetError",
    "Store",
    "arrow_schema",
    "new_manifest",
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
    pa.field("edge_radius_mm", pa.float64()),
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
        data["digest"] = manifest_digest(data)
        path.mkdir(parents=True, exist_ok=True)
        write_json_atomic(path / MANIFEST_NAME, data)
        store = cls(path, data)
        store._space = space
        return store

    @classmethod
    def open(cls, path: str | Path, check: bool = True) -> Store:
        """Open an existing dataset; :class:`DatasetError` if ``path`` is not one, or (with
        ``check``) if its manifest was edited (:mod:`surrogate.data.integrity`)."""
        path = Path(path)
        mpath = path / MANIFEST_NAME
        if not mpath.is_file():
            raise DatasetError(str(path), f"{path} is not a hapticrom dataset "
                               f"(no {MANIFEST_NAME})")
        from fieldspec.documents import read_json_file

        data = read_json_file(mpath, DatasetError, "dataset manifest")
        if not isinstance(data, dict) or data.get("format") != FORMAT:
            raise DatasetError(str(mpath), f"{mpath}: format "
                               f"{data.get('format') if isinstance(data, dict) else data!r} is not "
                               f"{FORMAT!r}")
        if data.get("schema_version") != SCHEMA_VERSION:
            raise DatasetError(str(mpath), f"{mpath}: schema_version "
                               f"{data.get('schema_version')!r} is not supported (this "
                               f"version reads {SCHEMA_VERSION})")
        store = cls(path, data)
        problems = manifest_problems(store) if check else []
        if problems:
            raise DatasetError(str(mpath), f"{mpath}: {'; '.join(problems)}. Restore the "
                               "manifest, or regenerate the dataset")
        return store

    @classmethod
    def exists(cls, path: str | Path) -> bool:
        """True when ``path`` holds a dataset manifest."""
        return (Path(path) / MANIFEST_NAME).is_file()

    @property
    def space(self) -> Space:
        """The space recorded in the manifest (scene checks skipped: it was checked when
        the dataset was created)."""
        if self._space is None:
            recorded = copy.deepcopy(self.manifest["space"])
            # Datasets made before sampled values were rounded: their points are not rounded.
            recorded.setdefault("space", {}).setdefault("significant_digits", 0)
            self._space = space_from_dict(recorded, check_scenes=False)
        return self._space

    @property
    def schema(self) -> pa.Schema:
        """The Arrow schema every part must have."""
        return arrow_schema(self.space)

    def save_manifest(self) -> None:
        """Write the (modified) manifest atomically."""
        self.manifest["updated"] = utc_now()
        self.manifest["digest"] = manifest_digest(self.manifest)
        write_json_atomic(self.path / MANIFEST_NAME, self.manifest)

    # ---- locking

    def lock(self) -> contextlib.AbstractContextManager[None]:
        """Hold the dataset's advisory write lock (released by the OS even on kill -9; the
        lock file is deleted on release: :func:`surrogate.data.lockfile.exclusive`)."""
        return exclusive(self.path / LOCK_NAME, self.path)

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
        meta = {**(metadata or {}), "space_hash": self.manifest.get("space_hash")}
        table = table.replace_schema_metadata({"hapticrom": json.dumps(meta, sort_keys=True)})
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
        problems = part_problems(self)
        if problems:
            raise DatasetError(str(self.path), f"{self.path}: {'; '.join(problems)}; remove "
                               "the offending part(s) (hapticrom dataset validate lists them)")
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
        try:
            meta = pq.read_schema(part).metadata or {}
        except (OSError, pa.ArrowException) as err:
            raise DatasetError(str(part), f"cannot read part {part}: {err}") from None
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


def new_manifest(space: Space, solver: Mapping[str, Any]) -> dict[str, Any]:
    """The manifest entries of a new dataset over ``space`` computed by ``solver`` (a
    :func:`surrogate.data.provenance.solver_info` dict); pass them to :meth:`Store.create`."""
    defaults = space.defaults
    varied = {path for p in space.free for path in p.paths}
    return {
        "sampling": {"sampler": space.sampler, "seed": space.seed, "lhs_batch": space.lhs_batch,
                     "target_n": 0, "scanned": 0, "rejected": 0, "duplicates": 0},
        "solver": dict(solver),
        "solver_history": [dict(solver, first_used=utc_now())],
        "mesh": {**defaults.get("mesh", {}),
                 "varied_by_space": any(v.startswith("mesh.") for v in varied)},
        "analysis_kind": ("varied" if "analysis.kind" in varied
                          else defaults.get("analysis", {}).get("kind")),
        "profile_grid_mm": None,
    }
