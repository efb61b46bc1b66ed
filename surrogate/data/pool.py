"""Process pools for many independent solves: one BLAS thread per worker, orphan-safe.

:func:`process_map` runs ``fn`` over items on spawned worker processes and returns the results
in input order (the paper study and benchmarks use it); :func:`make_executor` is the pool the
dataset generator's local back end runs on. Workers use one BLAS thread each: the pool already
fills the cores, oversubscribed BLAS threads slowed a 2-core run by about 15 %, and
floating-point reductions stay independent of the thread count.
"""

from __future__ import annotations

import concurrent.futures as cf
import contextlib
import multiprocessing
import os
import sys
import threading
import time
from collections.abc import Callable, Iterable, Iterator
from typing import Any, TypeVar

__all__ = ["THREAD_VARS", "check_workers", "cpu_count", "make_executor", "one_blas_thread",
           "process_map"]

#: Largest worker count accepted (far above any machine this runs on; catches typos).
MAX_WORKERS = 256

T = TypeVar("T")
R = TypeVar("R")

#: Environment variables that set the thread count of the BLAS/OpenMP libraries numpy uses.
THREAD_VARS = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS",
               "BLIS_NUM_THREADS", "VECLIB_MAXIMUM_THREADS", "NUMEXPR_NUM_THREADS")


@contextlib.contextmanager
def one_blas_thread() -> Iterator[None]:
    """Let worker processes started inside this block use one BLAS thread each (unless the
    user set a count). Spawned workers inherit the environment; the parent's is restored on
    exit."""
    saved = {k: os.environ.get(k) for k in THREAD_VARS}
    for k in THREAD_VARS:
        os.environ.setdefault(k, "1")
    try:
        yield
    finally:
        for k, v in saved.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v


def cpu_count() -> int:
    """Cores this process may use."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not Linux
        return os.cpu_count() or 1


def check_workers(workers: int | None) -> int:
    """The pool size: None = every core; else an int with 1 <= workers <= 256."""
    if workers is None:
        return cpu_count()
    if isinstance(workers, bool) or not isinstance(workers, int) or not 1 <= workers <= MAX_WORKERS:
        raise ValueError(f"workers = {workers!r} is out of range: allowed 1 <= workers <= "
                         f"{MAX_WORKERS} (None uses every core)")
    return workers


def _init_worker(parent_pid: int) -> None:
    # A worker orphaned by kill -9 of its parent would otherwise wait on its queue forever.
    def watch() -> None:
        while os.getppid() == parent_pid:
            time.sleep(1.0)
        os._exit(1)

    threading.Thread(target=watch, daemon=True, name="parent-watch").start()
    import fem.simulation  # noqa: F401 - import the solver once per worker, not per task

    # Each solve also holds its BLAS to one thread itself (fem.linalg.one_blas_thread), so a
    # user's thread count in the environment cannot oversubscribe the pool.


def make_executor(workers: int) -> cf.ProcessPoolExecutor:
    """A spawned process pool of ``workers`` solver processes; create it inside
    :func:`one_blas_thread` so that each worker uses one BLAS thread."""
    return cf.ProcessPoolExecutor(workers, mp_context=multiprocessing.get_context("spawn"),
                                  initializer=_init_worker, initargs=(os.getpid(),))


def process_map(fn: Callable[[T], R], items: Iterable[T], *, workers: int | None = None,
                desc: str | None = None) -> list[R]:
    """``[fn(item) for item in items]`` on a process pool, results in input order.

    ``fn`` must be importable by name (a module-level function). ``workers`` defaults to every
    core; ``workers=1`` runs in this process. With ``desc`` a tqdm progress bar (rate, ETA)
    goes to stderr when it is a terminal. Ctrl-C cancels the queued work and shuts the pool down."""
    n_workers = check_workers(workers)
    todo = list(items)
    n = min(n_workers, max(len(todo), 1))
    bar = _progress(len(todo), desc)
    try:
        if n == 1:
            out = []
            for item in todo:
                out.append(fn(item))
                bar.update(1)
            return out
        results: list[Any] = [None] * len(todo)
        # Workers spawn at the first submit: keep the one-thread environment until then.
        with one_blas_thread():
            executor = make_executor(n)
            try:
                futures = {executor.submit(fn, item): i for i, item in enumerate(todo)}
                for fut in cf.as_completed(futures):
                    results[futures[fut]] = fut.result()
                    bar.update(1)
            finally:
                executor.shutdown(wait=True, cancel_futures=True)
        return results
    finally:
        bar.close()


def _progress(total: int, desc: str | None) -> Any:
    # lazy: a progress bar, drawn only on a terminal
    from tqdm import tqdm

    # disable=None: tqdm draws only on a terminal (no bar in logs and pipes)
    return tqdm(total=total, desc=desc, unit="run", disable=True if desc is None else None,
                file=sys.stderr,
                dynamic_ncols=True, smoothing=0.05)
