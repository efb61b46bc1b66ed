"""Re-encode a sweep dataset into the compact stored form (``hapticrom dataset compact``).

``compact_dataset(src, out)`` writes a new dataset ``out`` holding exactly the rows of the
sweep dataset ``src`` (float32 lists, the form written before :mod:`surrogate.data.codec`), its
sweep lists stored as codes. Everything else carries over: the manifest's space, sampling,
solver history and runs (``generate`` extends ``out`` as it would ``src``), every row's
provenance; the manifest adds ``compacted_from`` (the source's path, manifest digest, rows,
parts and bytes). The rows of consecutive source parts written by one solver (version and
fingerprint; their git revisions listed in the new part's metadata) are cut into parts of
``rows_per_part`` rows (every Parquet part carries about 15 kB of footer: parts of a few rows,
as a generation flushed every few seconds writes them, would cost more than their rows).

Atomic: the new dataset is built and validated in ``.OUT.compact-PID`` beside ``out`` and
renamed to ``out`` only when complete; an existing ``out`` is replaced (``overwrite``) by
moving it aside, renaming the new one in and deleting the old one. A failure or an interrupt
deletes the temporary directory; a ``kill -9`` leaves it (removed by the next compaction to
the same ``out``), never a half-written ``out``.
"""

from __future__ import annotations

import contextlib
import os
import re
import shutil
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pyarrow as pa

from surrogate.data.codec import SweepCodec
from surrogate.data.errors import DatasetError
from surrogate.data.inspect import validate_dataset
from surrogate.data.integrity import part_problems
from surrogate.data.provenance import solver_key
from surrogate.data.store import Store, utc_now

__all__ = ["compact_dataset"]

#: Manifest entries a new dataset makes itself (or that describe the source's parts).
_OWN_KEYS = ("format", "schema_version", "created", "space", "space_hash", "parts", "digest",
             "updated", "codec")


def compact_dataset(src: str | Path, out: str | Path, *, overwrite: bool = False,
                    rows_per_part: int = 1024, codec: SweepCodec | None = None
                    ) -> dict[str, Any]:
    """Write the compact form of sweep dataset ``src`` to ``out`` (see the module). Returns
    ``{"rows", "parts_in", "parts_out", "bytes_in", "bytes_out", "max_error"}``;
    :class:`DatasetError` (naming ``src`` or ``out``) for a source that is not a valid
    float-list sweep dataset or an ``out`` that exists (without ``overwrite``), is the source
    or is not a dataset; nothing is written then."""
    if isinstance(rows_per_part, bool) or not isinstance(rows_per_part, int) \
            or rows_per_part < 1:
        raise DatasetError("rows_per_part", f"rows_per_part = {rows_per_part!r}: need an "
                           "integer >= 1")
    source = _source(Path(src))
    out = Path(out)
    _check_out(source.path, out, overwrite)
    codec = codec or SweepCodec()
    _remove_stale(out)
    tmp = out.parent / f".{out.name}.compact-{os.getpid()}"
    try:
        new = _build(source, tmp, codec, rows_per_part)
        _swap(tmp, out)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)  # gone already when the swap succeeded
    new = Store.open(out)
    return {"rows": sum(int(e["rows"]) for e in new.manifest["parts"].values()),
            "parts_in": len(source.parts()), "parts_out": len(new.parts()),
            "bytes_in": sum(p.stat().st_size for p in source.parts()),
            "bytes_out": sum(p.stat().st_size for p in new.parts()),
            "max_error": max(new.manifest["codec"].get("max_error", {}).values(), default=0.0)}


def _source(path: Path) -> Store:
    store = Store.open(path, deep=True)  # DatasetError naming the part for a damaged source
    problems = part_problems(store)
    if problems:
        raise DatasetError("src", f"{path}: {'; '.join(problems)}")
    if not store.manifest.get("band"):
        raise DatasetError("src", f"{path} is not a sweep dataset (no band): only sweep "
                           "datasets have a compact form")
    if store.codec is not None:
        raise DatasetError("src", f"{path} is compact already (codec "
                           f"{store.manifest['codec'].get('name')}): re-encoding codes would "
                           "add a second rounding error")
    return store


def _check_out(src: Path, out: Path, overwrite: bool) -> None:
    if out.resolve() == src.resolve() or src.resolve() in out.resolve().parents:
        raise DatasetError("out", f"--out {out} is the source dataset or inside it: write the "
                           "compact form to another directory")
    if not out.parent.is_dir():
        raise DatasetError("out", f"--out {out}: its directory {out.parent} does not exist")
    if not out.exists():
        return
    if not overwrite:
        raise DatasetError("out", f"--out {out} exists; --overwrite replaces it (a dataset "
                           "only)")
    if not (Store.exists(out) or (out.is_dir() and not any(out.iterdir()))):
        raise DatasetError("out", f"--out {out} exists and is not a hapticrom dataset (nor an "
                           "empty directory): not replaced")


def _remove_stale(out: Path) -> None:
    """Delete temporary directories of compactions to ``out`` whose process is gone."""
    pattern = re.compile(rf"^\.{re.escape(out.name)}\.(compact|old)-(\d+)$")
    for p in out.parent.iterdir():
        m = pattern.match(p.name)
        if m and p.is_dir() and not _alive(int(m.group(2))):
            shutil.rmtree(p, ignore_errors=True)


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def _build(source: Store, tmp: Path, codec: SweepCodec, rows_per_part: int) -> Store:
    m = source.manifest
    manifest = {k: v for k, v in m.items() if k not in _OWN_KEYS}
    manifest["codec"] = codec.to_dict()
    manifest["compacted_from"] = {
        "path": str(source.path), "manifest_digest": m.get("digest"),
        "rows": sum(int(e["rows"]) for e in (m.get("parts") or {}).values()),
        "parts": len(source.parts()),
        "bytes": sum(p.stat().st_size for p in source.parts()), "at": utc_now()}
    new = Store.create(tmp, source.space, **manifest)
    with new.lock():
        for meta, table in _groups(source, rows_per_part):
            new.write_part(table, meta)
    problems = validate_dataset(tmp)
    if problems:  # the source was valid: a codec fault, never stored
        raise DatasetError("out", f"the compact form failed validation, nothing written: "
                           f"{'; '.join(problems[:5])}")
    return new


def _groups(source: Store, rows_per_part: int) -> Iterator[tuple[dict[str, Any], pa.Table]]:
    """(part metadata, rows) of the new parts: the rows of consecutive source parts with the
    same source and solver (:func:`surrogate.data.provenance.solver_key`: version and
    fingerprint; the git revisions the source parts record are kept in the metadata), in
    order, cut into parts of ``rows_per_part`` rows (the last of each run of parts shorter)."""
    key: Any = None
    solver: dict[str, Any] | None = None
    revisions: list[str] = []
    buffer: list[pa.Table] = []
    # the newest source part's time, not the clock's: compacting the same parts again gives
    # the same bytes, so a set re-compacted as it grows adds only its new parts to git
    latest = ""

    def emit(everything: bool) -> Iterator[tuple[dict[str, Any], pa.Table]]:
        rows = pa.concat_tables(buffer) if buffer else None
        buffer.clear()
        if rows is None:
            return
        start = 0
        while rows.num_rows - start >= (1 if everything else rows_per_part):
            yield ({"source": key[0], "solver": solver, "git_revisions": list(revisions),
                    **({"written": latest} if latest else {})}, rows.slice(start, rows_per_part))
            start += rows_per_part
        if start < rows.num_rows:
            buffer.append(rows.slice(start))

    for part in source.parts():
        meta = source.part_metadata(part)
        own = meta.get("solver") if isinstance(meta.get("solver"), dict) else None
        this = (meta.get("source"), None if own is None else solver_key(own))
        if this != key:
            yield from emit(everything=True)
            key, solver, revisions = this, own, []
        written = meta.get("written")
        if isinstance(written, str) and written > latest:
            latest = written
        revision = (own or {}).get("git_revision")
        if revision and revision not in revisions:
            revisions.append(revision)
        buffer.append(source.read_part(part).replace_schema_metadata(None))
        yield from emit(everything=False)
    yield from emit(everything=True)


def _swap(tmp: Path, out: Path) -> None:
    """Rename the complete ``tmp`` to ``out``, replacing an existing ``out``."""
    old = out.parent / f".{out.name}.old-{os.getpid()}"
    if out.exists():
        os.replace(out, old)
    try:
        os.replace(tmp, out)
    except OSError:
        if old.exists():
            os.replace(old, out)
        raise
    with contextlib.suppress(OSError):
        fd = os.open(out.parent, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)
    shutil.rmtree(old, ignore_errors=True)
