"""Content digests of dataset parts, and the check of a directory's parts against its manifest.

Every part a hapticrom writer flushes is recorded in the manifest's ``parts`` table::

    "parts": {"part-000001.parquet": {"rows": 256, "rows_sha256": "...",
                                      "file_sha256": "...", "bytes": 48213}, ...}

* ``rows_sha256``: sha256 over the part's rows as decoded (:func:`rows_digest`): column
  names, the null mask and the values of every column, list lengths and list values, in
  schema order. It does not depend on how the Parquet file encodes them (compression, page
  layout, key-value metadata), so it says "these are the rows that were written".
* ``file_sha256`` and ``bytes``: the file as written. A matching file hash proves the rows
  without decoding them (the fast path every reader takes); a file that differs is decoded
  and accepted only if its rows hash to ``rows_sha256``.

The manifest is the commit point of a write: a part is written to ``.part-N.parquet.tmp``,
fsynced, recorded in the manifest (saved atomically), then renamed to ``part-N.parquet``. A
process killed between the manifest save and the rename leaves a recorded part under its
temporary name: readers read it there and the next writer (under the lock) finishes the
rename. An unrecorded ``part-N.parquet`` (a copied or foreign part) makes the dataset
refused; any other file in the directory is a stray: reported, never read.
"""

from __future__ import annotations

import hashlib
import re
from collections.abc import Mapping
from pathlib import Path
from typing import Any, Protocol

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.parquet as pq

__all__ = ["PART_RE", "TMP_RE", "PartCheck", "check_parts", "file_sha256", "part_entry",
           "rows_digest", "stray_files"]

PART_RE = re.compile(r"^part-(\d{6,})\.parquet$")
TMP_RE = re.compile(r"^\.part-(\d{6,})\.parquet\.tmp$")
_OWN = {"_manifest.json", "_lock", "._manifest.json.tmp"}
_CHUNK = 1 << 20


def file_sha256(path: Path) -> str:
    """sha256 hex of a file's bytes."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        while block := fh.read(_CHUNK):
            h.update(block)
    return h.hexdigest()


def rows_digest(table: pa.Table) -> str:
    """sha256 hex of a table's rows: names, null masks, list lengths and values of every
    column in order; independent of the Parquet encoding and of the schema metadata."""
    h = hashlib.sha256()
    h.update(f"rows={table.num_rows};cols={table.num_columns};".encode())
    for name, column in zip(table.column_names, table.columns, strict=True):
        h.update(f"column:{name};".encode())
        _hash_array(h, column.combine_chunks() if column.num_chunks != 1 else column.chunk(0))
    return h.hexdigest()


def _hash_array(h: Any, arr: pa.Array) -> None:
    t = arr.type
    h.update(f"n={len(arr)};nulls={arr.null_count};".encode())
    if arr.null_count:
        h.update(np.asarray(arr.is_valid(), dtype=np.bool_).tobytes())
    if pa.types.is_list(t) or pa.types.is_large_list(t):
        h.update(b"list;")
        lengths = pc.list_value_length(arr).fill_null(0)
        h.update(np.asarray(lengths, dtype=np.int64).tobytes())
        _hash_array(h, pc.list_flatten(arr))
    elif pa.types.is_string(t) or pa.types.is_large_string(t):
        h.update(b"string;")
        h.update(np.asarray(pc.binary_length(arr).fill_null(0), dtype=np.int64).tobytes())
        big = arr.cast(pa.large_string())
        _, offsets, data = big.buffers()
        if data is not None and len(big):  # the value bytes of the entries, in order
            off = np.frombuffer(offsets, dtype=np.int64)[big.offset: big.offset + len(big) + 1]
            h.update(memoryview(data)[int(off[0]): int(off[-1])])
    elif pa.types.is_boolean(t):
        h.update(b"bool;")
        h.update(np.asarray(arr.fill_null(False), dtype=np.bool_).tobytes())
    elif pa.types.is_integer(t) or pa.types.is_floating(t):
        dtype = np.dtype(t.to_pandas_dtype())
        h.update(f"{dtype.str};".encode())
        filled = arr.fill_null(0) if arr.null_count else arr
        h.update(np.ascontiguousarray(filled.to_numpy(zero_copy_only=False),
                                      dtype=dtype).tobytes())
    else:  # no other type is written by hapticrom; hash its Python values
        h.update(f"{t};{arr.to_pylist()!r}".encode())


def part_entry(path: Path) -> dict[str, Any]:
    """The manifest record of the part file at ``path`` (decodes it once)."""
    table = pq.read_table(path)
    return {"rows": table.num_rows, "rows_sha256": rows_digest(table),
            "file_sha256": file_sha256(path), "bytes": path.stat().st_size}


class PartCheck:
    """The outcome of :func:`check_parts`: ``problems`` (each naming a part; non-empty means
    the dataset must be refused) and ``strays`` (files ignored by every reader)."""

    def __init__(self) -> None:
        self.problems: list[str] = []
        self.strays: list[str] = []


def stray_files(path: Path, listed: Mapping[str, Any]) -> list[str]:
    """Names in ``path`` that are neither the manifest, the lock, a recorded part (under its
    own or temporary name) nor an unfinished temporary part."""
    out = []
    for p in sorted(path.iterdir(), key=lambda p: p.name):
        if p.name in _OWN or p.name in listed or TMP_RE.match(p.name) or PART_RE.match(p.name):
            continue
        out.append(p.name + ("/" if p.is_dir() else ""))
    return out


class Store(Protocol):
    """What the part checks read of a dataset (:class:`surrogate.data.store.Store` is one;
    the store runs these checks, so this module does not import it)."""

    path: Path
    manifest: dict[str, Any]

    def part_path(self, name: str) -> Path | None: ...


def check_parts(store: Store, deep: bool = False) -> PartCheck:
    """Compare the directory's parts with the manifest's ``parts`` table.

    Problems: a recorded part missing; its rows not matching ``rows_sha256`` (edited, damaged,
    replaced); an unreadable part; a ``part-N.parquet`` not recorded (a copied part). With
    ``deep`` the rows are hashed even when the file hash matches."""
    res = PartCheck()
    listed = store.manifest.get("parts")
    if not isinstance(listed, Mapping):
        res.problems.append("the manifest records no part digests (written before hapticrom "
                            "recorded them): check it with `hapticrom dataset validate` and "
                            "record them with `hapticrom dataset seal DIR`")
        return res
    for name in sorted(listed):
        entry = listed[name]
        if not PART_RE.match(str(name)) or not isinstance(entry, Mapping):
            res.problems.append(f"_manifest.json: parts entry {name!r} is not a part record")
            continue
        path = store.part_path(name)
        if path is None:
            res.problems.append(f"{name} is recorded in the manifest but missing (deleted or "
                                "moved): restore it, or regenerate the dataset")
            continue
        res.problems += _check_one(path, name, entry, deep)
    for p in sorted(store.path.iterdir(), key=lambda p: p.name):
        if PART_RE.match(p.name) and p.name not in listed:
            res.problems.append(f"{p.name} is not recorded in the manifest (a copied or "
                                "foreign part?): move it out of the dataset")
    res.strays = stray_files(store.path, listed)
    return res


def _check_one(path: Path, name: str, entry: Mapping[str, Any], deep: bool) -> list[str]:
    try:
        if not deep and path.stat().st_size == entry.get("bytes") \
                and file_sha256(path) == entry.get("file_sha256"):
            return []
        table = pq.read_table(path)
    except (OSError, pa.ArrowException) as err:
        return [f"{name} is unreadable (damaged): {err}"]
    if table.num_rows != entry.get("rows"):
        return [f"{name} holds {table.num_rows} rows, the manifest recorded "
                f"{entry.get('rows')!r} (edited or replaced after it was written)"]
    if rows_digest(table) != entry.get("rows_sha256"):
        return [f"{name}: its rows do not match the digest recorded when it was written "
                "(a value was edited, or the file was damaged or replaced)"]
    if file_sha256(path) != entry.get("file_sha256"):
        return [f"{name}: its bytes do not match the sha256 recorded when it was written, "
                "although its rows decode the same (damaged or rewritten): restore it, or "
                "record it again with `hapticrom dataset seal` if it was rewritten on purpose"]
    return []
