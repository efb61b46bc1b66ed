"""Generate a dataset: sample a space, solve every scene, store rows; resumable.

``generate(space, n, out)`` makes ``out`` hold the first ``n`` distinct feasible design points
of the space (sample indices in sequence order; points rejected by a constraint or resolving
to a scene already planned are skipped and counted in the manifest). Work runs on a local
process pool (default: one process per core) or on a Dask distributed cluster
(``scheduler="tcp://HOST:PORT"`` or a ``distributed.Client``).

Resumability: completed samples are buffered and flushed as small Parquet parts (every
``flush_every`` samples or ``flush_seconds``), each written atomically (``surrogate.store``).
Killed at any moment, even by SIGKILL, the same call again reads the ids already stored,
skips them and runs the rest: nothing completed is lost, nothing is stored twice. Raising
``n`` extends the dataset along the same design sequence.

Determinism: the worker function :func:`run_chunk` computes each sample from its scene alone
(JSON in, JSON out), BLAS threads are pinned to one per worker process, and rows are sorted by
sample index before each flush, so results do not depend on scheduling or chunking.

Dask: every worker needs the same hapticrom installation (each task reports the source hash
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
import concurrent.futures as cf
import contextlib
import functools
import json
import multiprocessing
import os
import platform
import re
import sys
import threading
import time
import traceback
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from fem.parallel import one_blas_thread
from surrogate.space import Space, SpaceError, load_space
from surrogate.store import FEM_SOURCE, DatasetError, Store, solver_info, utc_now

__all__ = [
    "GenerateReport",
    "Planned",
    "RunnerError",
    "generate",
    "plan_samples",
    "run_chunk",
    "run_sample",
    "unit_histories",
]

_SCHEDULER_RE = re.compile(r"^(tcp|tls)://[^\s:/]+:\d{1,5}$")

class RunnerError(RuntimeError):
    """The execution backend failed (a worker process died, a Dask worker was lost).
    Completed samples were saved; rerun the same command to resume."""


@dataclass(frozen=True)
class Planned:
    """One design point to run: sequence ``index``, ``sample_id`` (scene hash), parameter
    ``values`` (column -> python scalar) and the resolved, canonical ``scene`` dict."""

    index: int
    sample_id: str
    values: dict[str, Any]
    scene: dict[str, Any]


@dataclass
class PlanStats:
    """How many sequence indices were scanned to find the planned points, and why the others
    were skipped."""

    scanned: int = 0
    rejected: int = 0
    duplicates: int = 0


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

    @property
    def new(self) -> int:
        """Samples computed in this call."""
        return self.new_ok + self.new_failed

    @property
    def rate_per_min(self) -> float:
        """Samples per minute of wall time in this call (0 when nothing ran)."""
        return 60.0 * self.new / self.wall_s if self.wall_s > 0 and self.new else 0.0


# --------------------------------------------------------------------------- planning


def plan_samples(space: Space, n: int) -> tuple[list[Planned], PlanStats]:
    """The first ``n`` distinct feasible design points of ``space``, every scene validated.

    Raises :class:`SpaceError` naming the sample index and parameter if a scene is invalid,
    or if the space has fewer than ``n`` distinct feasible points in a long prefix."""
    from fem.scene import scene_hash, scene_to_dict

    if isinstance(n, bool) or not isinstance(n, int | np.integer) or n < 1:
        raise SpaceError("n", f"n = {n!r}: need an integer >= 1")
    planned: list[Planned] = []
    seen: set[str] = set()
    stats = PlanStats()
    limit = max(16 * n, 4096)
    block = max(64, min(n, 8192))
    while len(planned) < n:
        if stats.scanned >= limit:
            raise SpaceError("n", f"space {space.name!r} gives only {len(planned)} distinct "
                             f"feasible points in its first {stats.scanned} design points "
                             f"({stats.rejected} rejected by constraints, {stats.duplicates} "
                             f"repeat a scene); n = {n} is too many for it")
        values = space.points(stats.scanned, block)
        feasible = space.feasible(values)
        for j in range(block):
            index = stats.scanned + j
            if not feasible[j]:
                stats.rejected += 1
                continue
            row = {k: _py(v[j]) for k, v in values.items()}
            try:
                scene = space.scene(row)
            except SpaceError as err:
                raise SpaceError(err.field, f"sample {index}: {err}") from None
            sid = scene_hash(scene)
            if sid in seen:
                stats.duplicates += 1
                continue
            seen.add(sid)
            planned.append(Planned(index, sid, row, scene_to_dict(scene)))
            if len(planned) == n:
                stats.scanned = index + 1
                return planned, stats
        stats.scanned += block
    return planned, stats  # pragma: no cover - the loop returns


def _py(value: Any) -> Any:
    return value.item() if isinstance(value, np.generic) else value


# --------------------------------------------------------------------------- the worker


def run_sample(scene: Mapping[str, Any]) -> dict[str, Any]:
    """Solve one scene dict; return output columns plus status, error, wall_s [s], dofs.

    Never raises for a bad sample: the exception becomes ``status = "failed"`` with its text.
    The result depends on the scene only."""
    from fem.scene import scene_from_dict
    from fem.simulate import simulate

    t0 = time.perf_counter()
    try:
        result = simulate(scene_from_dict(scene))
        out = outputs_from_result(result.to_dict())
        out.update(unit_histories(result))
        bad = _non_finite(out)
        out["status"], out["error"] = ("failed", f"NonFiniteResult: {bad}") if bad else ("ok",
                                                                                         None)
    except Exception as err:  # a failed sample is data, not a crash
        out = {"status": "failed", "error": _error_text(err)}
    out["wall_s"] = time.perf_counter() - t0
    return out


def run_chunk(payload: str) -> str:
    """Worker entry point: JSON list of scene dicts in; JSON ``{"solver": hash, "rows":
    [output dicts]}`` out, ``solver`` being the source hash of the solver this worker runs.

    Plain strings cross the process boundary, so no solver object is ever pickled."""
    rows = [run_sample(scene) for scene in json.loads(payload)]
    return json.dumps({"solver": _worker_solver_hash(), "rows": rows})


@functools.cache
def _worker_solver_hash() -> str:
    # Computed once per worker process, when it first runs a chunk (the solver is imported).
    return str(solver_info(git=False)["source_sha256"])


def outputs_from_result(d: Mapping[str, Any]) -> dict[str, Any]:
    """Dataset output columns from ``SimulationResult.to_dict()``."""
    meta = d.get("meta", {})
    prof = d.get("profile") or {}
    out: dict[str, Any] = {
        "center_amplitude_um": d.get("center_amplitude_um"),
        "edge_amplitude_um": d.get("edge_amplitude_um"),
        "normalized_edge": d.get("normalized_edge"),
        "profile_distance_mm": prof.get("distance_from_edge_mm"),
        "profile_uz_um": prof.get("uz_um"),
        "profile_magnitude_um": prof.get("magnitude_um"),
        "dofs": meta.get("dofs"),
        "elements": meta.get("elements"),
        "warnings": "; ".join(str(w) for w in meta.get("warnings", [])) or None,
    }
    hist = d.get("histories")
    if hist:
        points = hist.get("points", [])
        out["history_t_s"] = hist.get("t_s")
        out["history_r_mm"] = [p["r_mm"] for p in points]
        out["history_uz_um"] = [p.get("uz_um") for p in points]
        out["history_magnitude_um"] = [p.get("magnitude_um") for p in points]
    return out


def unit_histories(result: Any) -> dict[str, Any]:
    """Center and edge time histories of a transient unit run (the points its
    ``center_amplitude_um`` / ``edge_amplitude_um`` are taken at), as [[u_r], [u_z], [u_theta]]
    lists in um on the theta = 0 meridian; empty for a steady run or a point load."""
    h = getattr(result, "histories", None)
    if h is None or getattr(result, "edge_mm", None) is None:
        return {}
    n = result.r_mm.size  # histories hold the probes, then the center, then the edge
    return {f"history_{name}_um": (h.u[:, n + i, :].T * 1e6).tolist()
            for i, name in enumerate(("center", "edge"))}


def _non_finite(out: Mapping[str, Any]) -> str:
    for key, value in out.items():
        if value is None or isinstance(value, str):
            continue
        flat = _flat(value)
        if flat.size and not np.all(np.isfinite(flat)):
            return f"{key} contains NaN or inf"
    return ""


def _flat(value: Any) -> np.ndarray:
    if isinstance(value, list) and value and isinstance(value[0], list):
        return np.concatenate([_flat(v) for v in value])
    return np.asarray(value, dtype=float).ravel()


def _error_text(err: BaseException) -> str:
    text = "".join(traceback.format_exception_only(type(err), err)).strip()
    tb = traceback.extract_tb(err.__traceback__)
    if tb:
        frame = tb[-1]
        text += f" (at {Path(frame.filename).name}:{frame.lineno} in {frame.name})"
    return text


# --------------------------------------------------------------------------- backends


def _init_worker(parent_pid: int) -> None:
    # A worker orphaned by kill -9 of the runner would otherwise wait on its queue forever.
    def watch() -> None:
        while os.getppid() == parent_pid:
            time.sleep(1.0)
        os._exit(1)

    threading.Thread(target=watch, daemon=True, name="parent-watch").start()
    import fem.simulate  # noqa: F401 - import the solver once per worker, not per sample


class _PoolBackend:
    name = "processes"

    def __init__(self, workers: int) -> None:
        self.workers = workers
        self.executor = cf.ProcessPoolExecutor(
            workers, mp_context=multiprocessing.get_context("spawn"),
            initializer=_init_worker, initargs=(os.getpid(),))

    def submit(self, payload: str) -> Any:
        return self.executor.submit(run_chunk, payload)

    def wait(self, pending: Sequence[Any], timeout: float) -> set[Any]:
        done, _ = cf.wait(pending, timeout=timeout, return_when=cf.FIRST_COMPLETED)
        return set(done)

    def close(self, cancel: bool) -> None:
        self.executor.shutdown(wait=not cancel, cancel_futures=cancel)


class _DaskBackend:
    name = "dask"

    def __init__(self, scheduler: Any) -> None:
        from distributed import Client

        self.own = isinstance(scheduler, str)
        try:
            self.client = Client(scheduler, timeout="15s") if self.own else scheduler
        except OSError as err:
            raise DatasetError("--scheduler", f"cannot connect to the Dask scheduler at "
                               f"{scheduler}: {err}") from None
        info = self.client.scheduler_info()
        workers = info.get("workers", {}).values()
        self.workers = sum(int(w.get("nthreads", 1)) for w in workers) or 1

    def submit(self, payload: str) -> Any:
        return self.client.submit(run_chunk, payload, pure=False)

    def wait(self, pending: Sequence[Any], timeout: float) -> set[Any]:
        from distributed import wait

        try:
            res = wait(list(pending), timeout=timeout, return_when="FIRST_COMPLETED")
        except TimeoutError:
            return set()
        return set(res.done)

    def close(self, cancel: bool) -> None:
        if self.own:
            self.client.close()





# --------------------------------------------------------------------------- the runner


def _check_args(n: Any, workers: Any, chunk: Any, flush_every: Any, flush_seconds: Any,
                scheduler: Any) -> None:
    def positive_int(name: str, value: Any) -> None:
        if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 1:
            raise SpaceError(name, f"{name} = {value!r}: need an integer >= 1")

    positive_int("--n", n)
    for name, value in (("--workers", workers), ("--chunk", chunk)):
        if value is not None:
            positive_int(name, value)
    positive_int("--flush-every", flush_every)
    if not isinstance(flush_seconds, int | float) or not 0 < flush_seconds <= 3600:
        raise SpaceError("--flush-seconds", f"--flush-seconds = {flush_seconds!r}: need "
                         "0 < seconds <= 3600")
    if isinstance(scheduler, str) and not _SCHEDULER_RE.match(scheduler):
        raise SpaceError("--scheduler", f"--scheduler = {scheduler!r}: expected "
                         "tcp://HOST:PORT (or tls://HOST:PORT)")
    if scheduler is not None and workers is not None:
        raise SpaceError("--workers", "--workers applies to the local process pool; with "
                         "--scheduler the cluster's workers are used")


def _check_compatible(store: Store, space: Space, solver: Mapping[str, Any],
                      allow_solver_change: bool) -> None:
    m = store.manifest
    if m.get("space_hash") != space.space_hash():
        raise DatasetError("--space", f"{store.path} was generated from a different space "
                           f"({m['space']['space'].get('name')!r}, hash "
                           f"{str(m.get('space_hash'))[:12]}) than the one given "
                           f"({space.name!r}, hash {space.space_hash()[:12]}); use another --out")
    old = m.get("solver", {})
    same = (old.get("version"), old.get("source_sha256")) == (solver["version"],
                                                              solver["source_sha256"])
    if not same and not allow_solver_change:
        raise DatasetError("--allow-solver-change",
                           f"{store.path} holds results of solver {old.get('version')} "
                           f"(source {str(old.get('source_sha256'))[:12]}, git "
                           f"{old.get('git_revision')}); the installed solver is "
                           f"{solver['version']} (source {solver['hash']}, git "
                           f"{solver['git_revision']}). Mixing them needs "
                           "--allow-solver-change (recorded in the manifest and per row)")


def generate(space: Space | str | Path, n: int, out: str | Path, *,
             scheduler: Any = None, workers: int | None = None, chunk: int | None = None,
             flush_every: int = 256, flush_seconds: float = 10.0, progress: bool = True,
             allow_solver_change: bool = False, command: str = "") -> GenerateReport:
    """Make dataset ``out`` hold the first ``n`` distinct feasible samples of ``space``.

    ``space`` is a :class:`Space` or a TOML path; ``scheduler`` None (local process pool of
    ``workers`` processes, default all cores), "tcp://HOST:PORT" or a ``distributed.Client``.
    ``chunk`` samples go to a worker per task (default adaptive). Everything is validated
    before anything is written: bad input raises :class:`SpaceError` or
    :class:`DatasetError` and leaves the disk untouched."""
    _check_args(n, workers, chunk, flush_every, flush_seconds, scheduler)
    if not isinstance(space, Space):
        space = load_space(space)
    out = Path(out)
    solver = solver_info()
    store = None
    if Store.exists(out):
        store = Store.open(out)
        _check_compatible(store, space, solver, allow_solver_change)
    elif out.exists() and (not out.is_dir() or any(out.iterdir())):
        raise DatasetError("--out", f"--out {out} exists and is not a hapticrom dataset "
                           "(nor an empty directory)")
    planned, stats = plan_samples(space, int(n))
    backend: Any = _DaskBackend(scheduler) if scheduler is not None else None
    try:
        if store is None:
            store = Store.create(out, space, **_new_manifest(space, solver))
        with store.lock():
            store.remove_temp_files()
            return _run(store, space, planned, stats, solver, backend, workers, chunk,
                        flush_every, flush_seconds, progress, allow_solver_change, command)
    finally:
        if backend is not None:
            backend.close(cancel=True)


def _new_manifest(space: Space, solver: Mapping[str, Any]) -> dict[str, Any]:
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


def _todo(store: Store, planned: Sequence[Planned], allow_solver_change: bool) -> list[Planned]:
    keys, by_index = store.keys()
    done_ids = {sid for src, sid in keys if src == FEM_SOURCE}
    todo = []
    for p in planned:
        if p.sample_id in done_ids:
            continue
        if p.index in by_index:
            if not allow_solver_change:
                raise DatasetError("--allow-solver-change", f"sample {p.index} is stored with "
                                   f"id {by_index[p.index][:12]} but now resolves to "
                                   f"{p.sample_id[:12]}: the scene schema or its defaults "
                                   "changed since the dataset was generated; use another "
                                   "--out, or --allow-solver-change to keep the old rows")
            continue
        todo.append(p)
    return todo


def _run(store: Store, space: Space, planned: list[Planned], stats: PlanStats,
         solver: Mapping[str, Any], backend: Any, workers: int | None, chunk: int | None,
         flush_every: int, flush_seconds: float, progress: bool, allow_solver_change: bool,
         command: str) -> GenerateReport:
    m = store.manifest
    if (m["solver"].get("version"), m["solver"].get("source_sha256")) != (
            solver["version"], solver["source_sha256"]):
        m["solver"] = dict(solver)
        m["solver_history"].append(dict(solver, first_used=utc_now()))
    todo = _todo(store, planned, allow_solver_change)
    sampling = m["sampling"]
    sampling["target_n"] = max(int(sampling.get("target_n", 0)), len(planned))
    if stats.scanned >= int(sampling.get("scanned", 0)):
        sampling.update(scanned=stats.scanned, rejected=stats.rejected,
                        duplicates=stats.duplicates)
    report = GenerateReport(store.path, len(planned), len(planned) - len(todo), plan=stats)
    run = {"started": utc_now(), "finished": None, "command": command, "host":
           platform.node(), "python": sys.version.split()[0], "solver_hash": solver["hash"],
           "target_n": len(planned), "todo": len(todo)}
    m["runs"].append(run)
    store.save_manifest()
    if not todo:
        run.update(finished=utc_now(), new_ok=0, new_failed=0)
        store.save_manifest()
        return report
    own_backend = backend is None
    with one_blas_thread() if own_backend else contextlib.nullcontext():
        if own_backend:
            backend = _PoolBackend(workers or _cpu_count())
        report.backend, report.workers = backend.name, backend.workers
        run.update(backend=backend.name, workers=backend.workers)
        t0 = time.perf_counter()
        try:
            _execute(store, todo, solver, backend, chunk, flush_every, flush_seconds, progress,
                     report)
        finally:
            report.wall_s = time.perf_counter() - t0
            if own_backend:
                backend.close(cancel=True)
            run.update(finished=utc_now(), new_ok=report.new_ok, new_failed=report.new_failed,
                       wall_s=round(report.wall_s, 3),
                       rate_per_min=round(report.rate_per_min, 1))
            store.save_manifest()
    return report


def _cpu_count() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not Linux
        return os.cpu_count() or 1


def _chunks(todo: Sequence[Planned], size: int) -> collections.deque[list[Planned]]:
    return collections.deque(list(todo[i : i + size]) for i in range(0, len(todo), size))


def _execute(store: Store, todo: list[Planned], solver: Mapping[str, Any], backend: Any,
             chunk: int | None, flush_every: int, flush_seconds: float, progress: bool,
             report: GenerateReport) -> None:
    from tqdm import tqdm

    size = chunk or max(1, min(32, len(todo) // (backend.workers * 16)))
    queue = _chunks(todo, size)
    pending: dict[Any, list[Planned]] = {}
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
               disable=not progress, file=sys.stderr, smoothing=0.05, desc=store.path.name)
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
    if reply["solver"] != solver["source_sha256"]:
        # e.g. a cluster worker with another installation, or fem edited during the run
        raise RunnerError(f"a worker runs solver source {reply['solver'][:12]}, not the "
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
