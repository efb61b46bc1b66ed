"""Dataset store: a directory of Parquet parts plus a JSON manifest.

Layout::

    DIR/_manifest.json          schema version, space, sampling, solver, mesh, runs
    DIR/_lock                   advisory lock held by the one process writing DIR (deleted
                                when it finishes, also after a failure)
    DIR/part-000001.parquet     immutable data parts (zstd), written atomically
    DIR/.part-000002.parquet.tmp   a part being written (or left by a killed run)

A sweep dataset written by this version is compact (the manifest's ``codec``,
:mod:`surrogate.data.codec`): its parts store the sweep lists as integer codes, and every
reader here gets back the float32 lists (:meth:`Store.read_table`); the manifest records, per
part (``parts[NAME].codec_error``) and for the dataset (``codec.max_error``), the largest codec
error per column measured when the part was written. A dataset without ``codec`` (every one
written before) stores the lists as written, and stays so when extended.

The dataset is the parts the manifest records (``parts``: rows, a digest of the rows and of
the file, :mod:`surrogate.data.digests`); every reader (:meth:`Store.open`) checks them and
refuses a dataset whose parts, rows or manifest do not match, naming the part. Any other file
in the directory is a stray: reported and never read. Read it with pandas from the manifest's
list (what :meth:`Store.read` returns, for a dataset without a codec; a compact one's codes
are decoded as ``docs/datasets.md`` shows)::

    m = json.load(open(f"{DIR}/_manifest.json"))
    df = pd.concat([pd.read_parquet(f"{DIR}/{name}") for name in sorted(m["parts"])])

A part is written to its temporary name, flushed to disk (fsync), recorded in the manifest
(the commit point, saved atomically) and renamed with ``os.replace``: a reader sees either no
part or a complete one, even after ``kill -9``.

Every row carries its provenance: ``sample_id`` (sha256 of the resolved scene,
``fem.scene.scene_hash``), ``sample_index`` (position in the design sequence for generated
rows, row number in the source file for ingested rows), ``status`` ("ok" or "failed"),
``error`` (text for failed rows), ``source`` ("hapticrom-fem" or "ingest:FILENAME"),
``wall_s`` [s], ``dofs``, ``elements``, ``solver_version``, ``solver_hash``, the resolved
scene as canonical JSON (``scene_json``) and the solver's warnings (``warnings``, e.g. an
under-resolved mesh; "; "-joined, null if none). Then one column per space parameter, then the
outputs (:mod:`surrogate.data.columns`: magnitudes, complex amplitudes, profiles, transient
histories, or complex sweeps over a band). The key of a row is
(source, sample_id).
"""

from __future__ import annotations

import contextlib
import copy
import datetime as _dt
import json
import os
import re
import warnings
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import pyarrow as pa
import pyarrow.parquet as pq

from fieldspec import HapticromWarning
from fieldspec.documents import read_json_file
from surrogate.data.codec import CodecError, SweepCodec, worst_errors
from surrogate.data.columns import (
    COMPLEX_FIELDS,
    OUTPUT_FIELDS,
    PROVENANCE_FIELDS,
    arrow_schema,
    profile_matrix,
    recorded_schema,
    rows_to_table,
)
from surrogate.data.digests import (
    PART_RE,
    TMP_RE,
    check_parts,
    file_sha256,
    part_entry,
    rows_digest,
)
from surrogate.data.errors import DatasetError
from surrogate.data.integrity import manifest_digest, manifest_problems, part_problems
from surrogate.data.lockfile import exclusive
from surrogate.data.space import Space, space_from_dict

__all__ = [
    "FEM_SOURCE",
    "MANIFEST_NAME",
    "OUTPUT_FIELDS",
    "PROVENANCE_FIELDS",
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
_PART_RE, _TMP_RE = PART_RE, TMP_RE
STATUSES = ("ok", "failed")
#: Output columns added after datasets were first written: rows for a dataset that predates
#: them are stored without them.
_LATER_COLUMNS = frozenset(f.name for f in COMPLEX_FIELDS)


class DatasetWarning(HapticromWarning):
    """A dataset directory holds files that are not part of the dataset (ignored)."""


def utc_now() -> str:
    """Current UTC time, ISO 8601 with seconds."""
    return _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds")


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
        if manifest.get("codec") is not None and space.band is None:
            raise DatasetError("codec", "only sweep datasets (a space with a band) have a "
                               "compact form")
        head = {"format": FORMAT, "schema_version": SCHEMA_VERSION, "created": utc_now(),
                "space": space.to_dict(), "space_hash": space.space_hash(),
                "columns": [{"name": f.name, "type": str(f.type)} for f in arrow_schema(space)]}
        data = {**head, **manifest}
        if data.get("codec") is not None:  # the codec's parameters; errors come with parts
            data["codec"] = SweepCodec.from_record(data["codec"], path).to_dict()
        data.setdefault("runs", [])
        data["parts"] = {}
        data["digest"] = manifest_digest(data)
        path.mkdir(parents=True, exist_ok=True)
        write_json_atomic(path / MANIFEST_NAME, data)
        store = cls(path, data)
        store._space = space
        return store

    @classmethod
    def open(cls, path: str | Path, check: bool = True, deep: bool = False) -> Store:
        """Open an existing dataset; :class:`DatasetError` if ``path`` is not one, or (with
        ``check``) if its manifest was edited (:mod:`surrogate.data.integrity`) or its parts
        do not match the manifest's record (:meth:`verify`; ``deep``: every part's rows are
        decoded and hashed, not only the file hashes compared; :meth:`read_table` of all
        columns checks the rows it reads in any case)."""
        path = Path(path)
        mpath = path / MANIFEST_NAME
        if not mpath.is_file():
            raise DatasetError(str(path), f"{path} is not a hapticrom dataset "
                               f"(no {MANIFEST_NAME})")

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
        if check:
            store.verify(deep=deep)
        return store

    def verify(self, deep: bool = False) -> list[str]:
        """Refuse (:class:`DatasetError`, naming the manifest or the part) a dataset whose
        manifest was edited or whose parts do not match the manifest's record; returns the
        stray files (ignored, also reported as a :class:`DatasetWarning`)."""
        mpath = self.path / MANIFEST_NAME
        problems = manifest_problems(self)
        if problems:
            raise DatasetError(str(mpath), f"{mpath}: {'; '.join(problems)}. Restore the "
                               "manifest, or regenerate the dataset")
        check = check_parts(self, deep=deep)
        if check.problems:
            raise DatasetError(str(self.path), f"{self.path}: refused: "
                               f"{'; '.join(check.problems)}")
        if check.strays:
            warnings.warn_explicit(f"{self.path}: ignoring files that are not part of the "
                                   f"dataset: {', '.join(check.strays)}", DatasetWarning,
                                   filename="hapticrom", lineno=0)  # no source line shown
        return check.strays

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
        """The Arrow schema of the rows (what :meth:`read_table` returns): the columns the
        manifest records (a dataset written before a column existed does not have it)."""
        return recorded_schema(self.space, self.manifest)

    @property
    def codec(self) -> SweepCodec | None:
        """The codec of a compact sweep dataset (:mod:`surrogate.data.codec`), None for a
        dataset stored as written (float lists)."""
        recorded = self.manifest.get("codec")
        return None if recorded is None else SweepCodec.from_record(recorded,
                                                                    self.path / MANIFEST_NAME)

    @property
    def stored_schema(self) -> pa.Schema:
        """The Arrow schema every part must have: :attr:`schema`, or its stored form when
        the dataset has a codec."""
        codec = self.codec
        return self.schema if codec is None else codec.stored_schema(self.schema)

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
        """The dataset's part files in write order: those the manifest records (a recorded
        part whose rename a killed writer did not finish is read under its temporary name),
        or, in a dataset written before parts were recorded, every ``part-N.parquet``."""
        listed = self.manifest.get("parts")
        if isinstance(listed, Mapping):
            names = [str(n) for n in listed]
            paths = [self.part_path(n) or self.path / n for n in names]
        else:
            paths = [p for p in self.path.iterdir() if _PART_RE.match(p.name)]
        return sorted(paths, key=lambda p: int(re.sub(r"\D", "", p.name) or 0))

    def part_path(self, name: str) -> Path | None:
        """Where the recorded part ``name`` is: its own name, or its temporary name when the
        writer was killed between recording it and renaming it; None if neither exists."""
        for p in (self.path / name, self.path / f".{name}.tmp"):
            if p.is_file():
                return p
        return None

    def temp_files(self) -> list[Path]:
        """Unfinished parts (ignored by readers)."""
        return sorted(p for p in self.path.iterdir() if _TMP_RE.match(p.name))

    def remove_temp_files(self) -> list[Path]:
        """Finish the rename of recorded parts a killed writer left under their temporary
        name, delete the unrecorded ones (never committed); call under :meth:`lock`.
        Returns the deleted files."""
        listed = self.manifest.get("parts") or {}
        removed = []
        for p in self.temp_files():
            name = p.name[1:-len(".tmp")]
            entry = listed.get(name)
            if entry is not None and not (self.path / name).exists() \
                    and file_sha256(p) == entry.get("file_sha256"):
                os.replace(p, self.path / name)
                continue
            p.unlink(missing_ok=True)
            removed.append(p)
        _fsync_dir(self.path)
        return removed

    def _next_seq(self) -> int:
        seqs = [int(m.group(1)) for p in self.path.iterdir()
                if (m := _PART_RE.match(p.name) or _TMP_RE.match(p.name))]
        return max(seqs, default=0) + 1

    def write_part(self, rows: Sequence[Mapping[str, Any]] | pa.Table,
                   metadata: Mapping[str, Any] | None = None, *,
                   encoded: Mapping[str, float] | None = None) -> Path:
        """Write ``rows`` (dicts keyed by column, missing columns are null; or an Arrow table
        with the dataset schema) as a new part, atomically. ``metadata`` goes into the
        Parquet key-value metadata under ``hapticrom``. ``encoded``: ``rows`` is a table
        already in the stored form of this dataset's codec (codes passed through, not rounded
        again), with these largest errors per column. Call under :meth:`lock`."""
        if encoded is not None:
            return self._write_encoded(rows, metadata, encoded)
        if isinstance(rows, pa.Table):
            table = rows.replace_schema_metadata(None).cast(self.schema)
        else:
            later = _LATER_COLUMNS - set(self.schema.names)  # an older dataset: not stored
            if later:
                rows = [{k: v for k, v in r.items() if k not in later} for r in rows]
            table = rows_to_table(rows, self.schema)
        codec = self.codec
        if codec is None:
            meta = {**(metadata or {}), "space_hash": self.manifest.get("space_hash")}
            return self._write(table, meta, {"compression": "zstd"}, None)
        try:
            stored, errors = codec.encode(table)
        except CodecError as err:
            raise DatasetError("rows", f"{self.path}: rows not stored: {err}") from None
        return self._write_encoded(stored, metadata, errors)

    def _write_encoded(self, table: pa.Table, metadata: Mapping[str, Any] | None,
                       errors: Mapping[str, float]) -> Path:
        codec = self.codec
        if codec is None or not isinstance(table, pa.Table):
            raise DatasetError("rows", f"{self.path}: encoded rows for a dataset without a "
                               "codec, or not a table")
        worst = max(errors.values(), default=0.0)
        if worst > codec.bound:  # cannot happen with tolerance < bound; never store it
            raise DatasetError("codec", f"{self.path}: codec error {worst:.3g} above its bound "
                               f"{codec.bound:g}: rows not stored")
        table = table.replace_schema_metadata(None).cast(self.stored_schema)
        meta = {**(metadata or {}), "space_hash": self.manifest.get("space_hash"),
                "codec": codec.part_record(), "codec_error": dict(errors)}
        return self._write(table, meta, codec.parquet_options(table.schema), errors)

    def _write(self, table: pa.Table, meta: Mapping[str, Any], options: Mapping[str, Any],
               errors: Mapping[str, float] | None) -> Path:
        table = table.replace_schema_metadata({"hapticrom": json.dumps(meta, sort_keys=True)})
        seq = self._next_seq()
        final = self.path / f"part-{seq:06d}.parquet"
        tmp = self.path / f".{final.name}.tmp"
        pq.write_table(table, tmp, **options)
        with open(tmp, "rb") as fh:
            os.fsync(fh.fileno())
        entry = part_entry(tmp)
        if errors is not None:
            entry["codec_error"] = dict(errors)
            record = self.manifest["codec"]
            record["max_error"] = worst_errors(record.get("max_error") or {}, errors)
        self.manifest.setdefault("parts", {})[final.name] = entry
        self.save_manifest()  # the commit point: the part belongs to the dataset from here on
        os.replace(tmp, final)
        _fsync_dir(self.path)
        return final

    # ---- reading

    def read_part(self, part: Path, columns: Sequence[str] | None = None) -> pa.Table:
        """One part as an Arrow table; :class:`DatasetError` naming the file if unreadable,
        including data that reads but is not valid (a damaged page of strings that are not
        UTF-8 would otherwise fail later, in whichever reader converts them; the full check
        costs about 2 % of the read)."""
        try:
            table = pq.read_table(part, columns=list(columns) if columns else None)
            table.validate(full=True)
            return table
        except (OSError, pa.ArrowException) as err:
            raise DatasetError(str(part), f"cannot read part {part}: {err}") from None

    def read_table(self, columns: Sequence[str] | None = None) -> pa.Table:
        """All rows as one Arrow table with the dataset schema (a compact dataset's parts
        decoded: :meth:`decode_part`). Reading every column checks each part's rows against
        the digest the manifest recorded (:class:`DatasetError` naming the part)."""
        codec = self.codec
        stored = codec.stored_columns(columns) if codec is not None and columns else columns
        tables = self._read_parts(stored)
        if not tables:
            schema = self.schema
            if columns:
                schema = pa.schema([schema.field(c) for c in columns])
            return schema.empty_table()
        if codec is not None:
            tables = [self.decode_part(p, t) for p, t in zip(self.parts(), tables, strict=True)]
            if columns:
                tables = [t.select(list(columns)) for t in tables]
        return pa.concat_tables([t.replace_schema_metadata(None) for t in tables])

    def read_stored(self) -> pa.Table:
        """All rows as the parts store them (a compact dataset's codes, not decoded), each
        part checked against its recorded digest."""
        tables = self._read_parts(None)
        if not tables:
            return self.stored_schema.empty_table()
        return pa.concat_tables([t.replace_schema_metadata(None) for t in tables])

    def _read_parts(self, columns: Sequence[str] | None) -> list[pa.Table]:
        """Every part's stored columns; all of them checked against the recorded digests."""
        tables = [self.read_part(p, columns) for p in self.parts()]
        listed = self.manifest.get("parts")
        if columns is None and isinstance(listed, Mapping):
            for part, table in zip(self.parts(), tables, strict=True):
                name = part.name.removeprefix(".").removesuffix(".tmp")
                entry = listed.get(name) or {}
                if rows_digest(table) != entry.get("rows_sha256"):
                    raise DatasetError(str(part), f"{self.path}: refused: {name}: its rows "
                                       "do not match the digest recorded when it was written")
                if "file_sha256" in entry and file_sha256(part) != entry["file_sha256"]:
                    raise DatasetError(str(part), f"{self.path}: refused: {name}: its bytes "
                                       "do not match the sha256 recorded when it was written "
                                       "(damaged or rewritten)")
        return tables

    def decode_part(self, part: Path, stored: pa.Table) -> pa.Table:
        """The rows of a compact part as the dataset schema types them; :class:`DatasetError`
        naming the part when its codes do not decode (a damaged or edited part)."""
        codec = self.codec
        if codec is None:
            return stored
        try:
            return codec.decode(stored, self.schema)
        except CodecError as err:
            raise DatasetError(str(part), f"{self.path}: refused: {part.name}: its codes do "
                               f"not decode: {err}") from None

    def read(self, columns: Sequence[str] | None = None) -> Any:
        """All rows as a pandas DataFrame (:meth:`read_table`: for a dataset without a codec
        the same as ``pandas.read_parquet`` of its parts; a compact one's lists decoded)."""
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
        "analysis_kind": ("sweep" if space.band is not None else "varied"
                          if "analysis.kind" in varied
                          else defaults.get("analysis", {}).get("kind")),
        "profile_grid_mm": None,
        **({"band": {**space.band.to_dict(), "frequency_hz": list(space.band.frequencies_hz)},
            "codec": SweepCodec().to_dict()}  # sweeps are stored compact
           if space.band is not None else {}),
    }
