"""Generate a dataset: sample a space, solve every scene, store rows; resumable.

``generate(space, n, out)`` makes ``out`` hold the first ``n`` distinct feasible design points
of the space (sample indices in sequence order; points rejected by a constraint or resolving
to a scene already planned are skipped and counted in the manifest). Work runs on a local
process pool (default: one process per core) or on a Dask distributed cluster
(``scheduler="tcp://HOST:PORT"`` or a ``distributed.Client``).

Resumability: completed samples are buffered and flushed as small Parquet parts (every
``flush_every`` samples or ``flush_seconds``), each written atomically (``surrogate.data.store``).
Killed at any moment, even by SIGKILL, the same call again reads the ids already stored,
skips them and runs the rest: nothing completed is lost, nothing is stored twice. Raising
``n`` extends the dataset along the same design sequence.

Start-up: the first chunk of every worker is planned and submitted before the rest of the
plan (each scene is validated and hashed, about 4 ms: 16 s for 4096 samples), so the workers
start within seconds while the main process finishes the plan; nothing is written until the
whole plan is validated (a failing plan cancels those chunks and drops their results).

Determinism: the worker (:func:`surrogate.data.worker.run_chunk`) computes each sample from
its scene alone (JSON in, JSON out), BLAS threads are pinned to one per worker process, and
rows are sorted by sample index before each flush, so results do not depend on scheduling or
chunking.

Dispatch order: samples sharing a mesh topology are sent to a worker back to back
(:mod:`surrogate.data.topology`, in windows of 4096 samples; a key costs ~7 ms in the main
process, computed while the workers run the head start or the previous window), so the
solver's per-topology caches (scatter map, symbolic analysis) hit; chunks go longest first to
keep the workers evenly loaded.

Dask: every worker needs the same hapticrom installation (each task reports the fingerprint
of the solver it ran; a mismatch aborts the run and its rows are discarded). Start workers
with one thread each (``dask worker tcp://HOST:PORT --nworkers N --nthreads 1``): part of
every sample runs in Python under the GIL.

Failures: if the solver raises for a sample, the sample is stored with status "failed" and
the error text (exception type, message, raising location); non-finite outputs are stored as
failed too. A broken worker process or a lost Dask worker aborts the run with
:class:`RunnerError` after saving everything completed; rerunning resumes.
"""

from __future__ import annotations

import collections
import contextlib
import json
import platform
import re
import sys
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from fieldspec import WorkError
from surrogate.data.backends import DaskBackend, PoolBackend
from surrogate.data.errors import DatasetError, SpaceError
from surrogate.data.plan import Planned, PlanStats, plan_samples
from surrogate.data.pool import cpu_count, one_blas_thread
from surrogate.data.provenance import same_solver, solver_info
from surrogate.data.space import Space, check_space, load_space
from surrogate.data.store import FEM_SOURCE, Store, new_manifest, utc_now
from surrogate.data.topology import default_cap, topology_chunks, topology_key

__all__ = ["GenerateReport", "RunnerError", "generate"]

#: Dispatch samples of one mesh topology back to back (:mod:`surrogate.data.topology`), so the
#: solver's per-topology caches hit; False keeps plan order (benchmarks compare the two).
GROUP_BY_TOPOLOGY = True

_SCHEDULER_RE = re.compile(r"^(tcp|tls)://[^\s:/]+:\d{1,5}$")


class RunnerError(WorkError):
    """The execution backend failed (a worker process died, a Dask worker was lost).
    Completed samples were saved; rerun the same command to resume."""


@dataclass
class GenerateReport:
    """Outcome of one :func:`generate` call. Times in seconds, rates in samples per minute."""

    path: Path
    requested: int
    already_done: int
    new_ok: int = 0
    new_failed: int = 0
    wall_s: float = 0.0
    backend: str = "processes"
    workers: int = 0
    parts_written: int = 0
    plan: PlanStats = field(default_factory=PlanStats)
    frequencies: int = 1  # answers per sample: the band's frequencies for a sweep space

    @property
    def new(self) -> int:
        """Samples computed in this call."""
        return self.new_ok + self.new_failed

    @property
    def rate_per_min(self) -> float:
        """Samples per minute of wall time in this call (0 when nothing ran)."""
        return 60.0 * self.new / self.wall_s if self.wall_s > 0 and self.new else 0.0

    @property
    def answers_per_min(self) -> float:
        """Design-frequency answers per minute (a sweep sample answers every frequency of its
        band, a single-frequency sample one)."""
        return self.rate_per_min * self.frequencies


# --------------------------------------------------------------------------- the runner


def _check_args(n: Any, workers: Any, chunk: Any, flush_every: Any, flush_seconds: Any,
                scheduler: Any) -> None:
    def positive_int(name: str, value: Any) -> None:
        if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 1:
            raise SpaceError(name, f"{name} = {value!r}: need an integer >= 1")

    positive_int("n", n)
    for name, value in (("workers", workers), ("chunk", chunk)):
        if value is not None:
            positive_int(name, value)
    positive_int("flush_every", flush_every)
    if not isinstance(flush_seconds, int | float) or not 0 < flush_seconds <= 3600:
        raise SpaceError("flush_seconds", f"flush_seconds = {flush_seconds!r}: need "
                         "0 < flush_seconds <= 3600")
    if isinstance(scheduler, str) and not _SCHEDULER_RE.match(scheduler):
        raise SpaceError("scheduler", f"scheduler = {scheduler!r}: expected tcp://HOST:PORT "
                         "(or tls://HOST:PORT)")
    if scheduler is not None and workers is not None:
        raise SpaceError("workers", "workers applies to the local process pool; with a "
                         "scheduler the cluster's workers are used")


def _check_compatible(store: Store, space: Space, solver: Mapping[str, Any],
                      allow_solver_change: bool) -> None:
    m = store.manifest
    if m.get("space_hash") != space.space_hash():
        raise DatasetError("space", f"{store.path} was generated from a different space "
                           f"({m['space']['space'].get('name')!r}, hash "
                           f"{str(m.get('space_hash'))[:12]}) than the one given "
                           f"({space.name!r}, hash {space.space_hash()[:12]}); write to "
                           "another dataset directory")
    old = m.get("solver", {})
    if not same_solver(old, solver) and not allow_solver_change:
        raise DatasetError("allow_solver_change",
                           f"{store.path} holds results of solver {old.get('version')} "
                           f"({old.get('hash')}, git {old.get('git_revision')}); the installed "
                           f"solver is {solver['version']} ({solver['hash']}, git "
                           f"{solver['git_revision']}) and gives other numbers. Mixing them "
                           "needs allow_solver_change (--allow-solver-change; recorded in the "
                           "manifest and per row)")


def generate(space: Space | str | Path, n: int, out: str | Path, *,
             scheduler: Any = None, workers: int | None = None, chunk: int | None = None,
             flush_every: int = 256, flush_seconds: float = 10.0, progress: bool = True,
             allow_solver_change: bool = False, command: str = "",
             only: Sequence[int] | None = None) -> GenerateReport:
    """Make dataset ``out`` hold the first ``n`` distinct feasible samples of ``space``.

    ``only``: run just the planned samples with these sequence indices (active learning picks
    them, ``surrogate.refine``); the dataset's target size is then left as it was.

    ``space`` is a :class:`Space` or a TOML path; ``scheduler`` None (local process pool of
    ``workers`` processes, default all cores), "tcp://HOST:PORT" or a ``distributed.Client``.
    ``chunk`` samples go to a worker per task (default adaptive). Everything is validated
    before anything is written: bad input raises :class:`SpaceError` or
    :class:`DatasetError` and leaves the disk untouched."""
    _check_args(n, workers, chunk, flush_every, flush_seconds, scheduler)
    checked = isinstance(space, Space)  # a Space object was checked when it was built
    if not checked:
        space = load_space(space, check_scenes=False)  # checked below, after the head start
    out = Path(out)
    store = None
    if Store.exists(out):
        store = Store.open(out, deep=True)
    elif out.exists() and (not out.is_dir() or any(out.iterdir())):
        raise DatasetError("out", f"{out} exists and is not a hapticrom dataset (nor an empty "
                           "directory)")
    own = scheduler is None
    backend: Any = DaskBackend(scheduler) if not own else None
    t_head = time.perf_counter()  # the rate counts from the head start: it is part of the run
    try:
        with one_blas_thread() if own else contextlib.nullcontext():
            if own:
                backend = PoolBackend(workers or cpu_count())  # spawns at the first submit
            head = _head_start(space, int(n), store, backend, chunk) if only is None else {}
        # while the head start runs: the space's scene check, the solver's identity, the
        # dataset's compatibility and the whole plan; any failure cancels the head start
        if not checked:
            check_space(space)
        solver = solver_info()
        if store is not None:
            _check_compatible(store, space, solver, allow_solver_change)
        planned, stats = plan_samples(space, int(n))
        if only is not None:
            wanted = {int(i) for i in only}
            planned = [p for p in planned if p.index in wanted]
            stats = PlanStats()  # a selection says nothing about how the sequence was scanned
        if store is None:
            store = Store.create(out, space, **new_manifest(space, solver))
        with store.lock():
            store.remove_temp_files()
            return _run(store, space, planned, stats, solver, backend, own,
                        (head, t_head) if head else None, chunk, flush_every, flush_seconds,
                        progress, allow_solver_change, command)
    finally:
        if backend is not None:
            backend.close(cancel=True)


def _chunk_size(chunk: int | None, n: int, workers: int) -> int:
    return chunk or max(1, min(32, n // (workers * 16)))


def _head_start(space: Space, n: int, store: Store | None, backend: Any,
                chunk: int | None) -> dict[Any, list[Planned]]:
    """Plan the first chunk of every worker and submit it before the whole plan is made, so
    that the workers start within a second or two while the main process validates the other
    scenes (about 4 ms each: 16 s for 4096). Nothing is written before the whole plan is
    validated: a failing plan cancels these futures and their results are dropped. Samples
    the dataset already holds are not submitted."""
    size = _chunk_size(chunk, n, backend.workers)
    try:
        head, _ = plan_samples(space, min(n, size * backend.workers))
    except SpaceError:  # no head start: the checks that follow report it in their words
        return {}
    if store is not None:
        keys, by_index = store.keys()
        done = {sid for src, sid in keys if src == FEM_SOURCE}
        head = [p for p in head if p.sample_id not in done and p.index not in by_index]
    return {backend.submit(json.dumps([p.scene for p in items])): items
            for items in _chunks(head, size)}


def _todo(store: Store, planned: Sequence[Planned], allow_solver_change: bool) -> list[Planned]:
    keys, by_index = store.keys()
    done_ids = {sid for src, sid in keys if src == FEM_SOURCE}
    todo = []
    for p in planned:
        if p.sample_id in done_ids:
            continue
        if p.index in by_index:
            if not allow_solver_change:
                raise DatasetError("allow_solver_change", f"sample {p.index} is stored with "
                                   f"id {by_index[p.index][:12]} but now resolves to "
                                   f"{p.sample_id[:12]}: the scene schema or its defaults "
                                   "changed since the dataset was generated; write to another "
                                   "dataset, or allow_solver_change to keep the old rows")
            continue
        todo.append(p)
    return todo


def _run(store: Store, space: Space, planned: list[Planned], stats: PlanStats,
         solver: Mapping[str, Any], backend: Any, own_backend: bool,
         head_start: tuple[dict[Any, list[Planned]], float] | None, chunk: int | None,
         flush_every: int,
         flush_seconds: float, progress: bool, allow_solver_change: bool,
         command: str) -> GenerateReport:
    m = store.manifest
    if not same_solver(m["solver"], solver):
        m["solver"] = dict(solver)
        m["solver_history"].append(dict(solver, first_used=utc_now()))
    todo = _todo(store, planned, allow_solver_change)
    sampling = m["sampling"]
    sampling["target_n"] = max(int(sampling.get("target_n", 0)), len(planned))
    if stats.scanned >= int(sampling.get("scanned", 0)):
        sampling.update(scanned=stats.scanned, rejected=stats.rejected,
                        duplicates=stats.duplicates)
    report = GenerateReport(store.path, len(planned), len(planned) - len(todo), plan=stats,
                            frequencies=len(space.band.frequencies_hz) if space.band else 1)
    run = {"started": utc_now(), "finished": None, "command": command, "host":
           platform.node(), "python": sys.version.split()[0], "solver_hash": solver["hash"],
           "target_n": len(planned), "todo": len(todo)}
    m["runs"].append(run)
    store.save_manifest()
    if not todo:
        run.update(finished=utc_now(), new_ok=0, new_failed=0)
        store.save_manifest()
        return report
    with one_blas_thread() if own_backend else contextlib.nullcontext():
        report.backend, report.workers = backend.name, backend.workers
        run.update(backend=backend.name, workers=backend.workers)
        head, t0 = head_start or ({}, time.perf_counter())
        try:
            _execute(store, todo, solver, backend, chunk, flush_every, flush_seconds, progress,
                     report, head)
        finally:
            report.wall_s = time.perf_counter() - t0
            run.update(finished=utc_now(), new_ok=report.new_ok, new_failed=report.new_failed,
                       wall_s=round(report.wall_s, 3),
                       rate_per_min=round(report.rate_per_min, 1))
            store.save_manifest()
    return report



def _chunks(todo: Sequence[Planned], size: int) -> collections.deque[list[Planned]]:
    return collections.deque(list(todo[i : i + size]) for i in range(0, len(todo), size))


#: Samples grouped at a time: their keys cost ~30 s in the main process, computed when the
#: previous window's chunks are all submitted (the workers are busy with those meanwhile); a
#: window this large already repeats most topologies of the default space.
GROUP_WINDOW = 4096


class _DispatchQueue:
    """The chunks to submit, in order: each window of :data:`GROUP_WINDOW` samples grouped by
    mesh topology, longest chunks first (an explicit ``chunk`` is the largest chunk made), or
    plan order when :data:`GROUP_BY_TOPOLOGY` is off. A window's keys are computed when its
    first chunk is needed."""

    def __init__(self, todo: Sequence[Planned], size: int, chunk: int | None,
                 workers: int) -> None:
        self.size, self.chunk, self.workers = size, chunk, workers
        step = GROUP_WINDOW if GROUP_BY_TOPOLOGY else max(len(todo), 1)
        self.windows = collections.deque(todo[i : i + step] for i in range(0, len(todo), step))
        self.chunks: collections.deque[list[Planned]] = collections.deque()

    def __bool__(self) -> bool:
        return bool(self.chunks or self.windows)

    def popleft(self) -> list[Planned]:
        if not self.chunks:
            self.chunks = self._chunks(self.windows.popleft())
        return self.chunks.popleft()

    def _chunks(self, window: Sequence[Planned]) -> collections.deque[list[Planned]]:
        if not GROUP_BY_TOPOLOGY:
            return _chunks(window, self.size)
        keys = [topology_key(p.scene) for p in window]
        cap = self.size if self.chunk else default_cap(self.size, len(window), self.workers)
        return collections.deque(topology_chunks(window, keys, self.size, cap))


def _execute(store: Store, todo: list[Planned], solver: Mapping[str, Any], backend: Any,
             chunk: int | None, flush_every: int, flush_seconds: float, progress: bool,
             report: GenerateReport, head: dict[Any, list[Planned]] | None = None) -> None:
    # lazy: a progress bar, drawn only on a terminal
    from tqdm import tqdm

    size = _chunk_size(chunk, len(todo), backend.workers)
    wanted = {p.sample_id for p in todo}
    pending: dict[Any, list[Planned]] = {}
    for fut, items in (head or {}).items():  # submitted before the plan was complete
        if all(p.sample_id in wanted for p in items):
            pending[fut] = items
        else:  # cannot happen with a deterministic plan; never store what was not asked for
            fut.cancel()
    started = {p.sample_id for items in pending.values() for p in items}
    queue = _DispatchQueue([p for p in todo if p.sample_id not in started], size, chunk,
                           backend.workers)
    buffer: list[dict[str, Any]] = []
    last_flush = time.monotonic()
    total = report.requested

    def flush() -> None:
        nonlocal last_flush
        if buffer:
            buffer.sort(key=lambda r: r["sample_index"])
            store.write_part(buffer, {"source": FEM_SOURCE, "solver": dict(solver),
                                      "written": utc_now()})
            report.parts_written += 1
            buffer.clear()
        last_flush = time.monotonic()

    bar = tqdm(total=total, initial=report.already_done, unit="sample", dynamic_ncols=True,
               disable=None if progress else True,  # None: drawn only on a terminal
               file=sys.stderr, smoothing=0.05, desc=store.path.name)
    try:
        while queue or pending:
            while queue and len(pending) < 2 * backend.workers + 1:
                items = queue.popleft()
                pending[backend.submit(json.dumps([p.scene for p in items]))] = items
            for fut in backend.wait(list(pending), timeout=min(flush_seconds, 1.0)):
                items = pending.pop(fut)
                outs = _chunk_rows(fut, items, solver)
                for p, o in zip(items, outs, strict=True):
                    buffer.append(_row(p, o, solver))
                    _note_grid(store, o)
                    if o["status"] == "ok":
                        report.new_ok += 1
                    else:
                        report.new_failed += 1
                bar.update(len(items))
                bar.set_postfix(failed=report.new_failed, refresh=False)
            if buffer and (len(buffer) >= flush_every
                           or time.monotonic() - last_flush >= flush_seconds):
                flush()
    finally:
        for fut in pending:
            fut.cancel()
        flush()  # whatever completed is valid data, also on Ctrl-C or a backend failure
        bar.close()


def _chunk_rows(fut: Any, items: Sequence[Planned], solver: Mapping[str, Any]
                ) -> list[dict[str, Any]]:
    try:
        reply = json.loads(fut.result())
    except Exception as err:
        raise RunnerError(f"the execution backend failed while running samples "
                          f"{items[0].index}..{items[-1].index}: {type(err).__name__}: {err}. "
                          "Completed samples were saved; rerun the same command to resume"
                          ) from err
    if reply["solver"] != solver["fingerprint"]:
        # e.g. a cluster worker with another installation, or fem edited during the run
        raise RunnerError(f"a worker runs solver {reply['solver'][:12]}, not the "
                          f"{solver['hash']} this run records; its results were discarded. "
                          "Install the same hapticrom on every worker, then rerun")
    return list(reply["rows"])


def _row(p: Planned, out: Mapping[str, Any], solver: Mapping[str, Any]) -> dict[str, Any]:
    return {**out, **p.values, "sample_id": p.sample_id, "sample_index": p.index,
            "source": FEM_SOURCE, "solver_version": solver["version"],
            "solver_hash": solver["hash"],
            "scene_json": json.dumps(p.scene, sort_keys=True, separators=(",", ":"))}


def _note_grid(store: Store, out: Mapping[str, Any]) -> None:
    grid = out.get("profile_distance_mm")
    if out.get("status") == "ok" and grid and store.manifest.get("profile_grid_mm") is None:
        store.manifest["profile_grid_mm"] = [float(g) for g in grid]
