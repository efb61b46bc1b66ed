"""Where samples run: a local process pool (default) or a Dask distributed cluster.

Both back ends take JSON payloads (a chunk of scene dicts) for :func:`run_chunk` and hand back
futures; the runner (:mod:`surrogate.data.generate`) only submits, waits and closes.
"""

from __future__ import annotations

import concurrent.futures as cf
from collections.abc import Sequence
from typing import Any

from surrogate.data.errors import DatasetError
from surrogate.data.pool import make_executor
from surrogate.data.worker import run_chunk

__all__ = ["DaskBackend", "PoolBackend"]


class PoolBackend:
    """A local process pool (spawned workers, each watching its parent)."""

    name = "processes"

    def __init__(self, workers: int) -> None:
        self.workers = workers
        self.executor = make_executor(workers)

    def submit(self, payload: str) -> Any:
        return self.executor.submit(run_chunk, payload)

    def wait(self, pending: Sequence[Any], timeout: float) -> set[Any]:
        done, _ = cf.wait(pending, timeout=timeout, return_when=cf.FIRST_COMPLETED)
        return set(done)

    def close(self, cancel: bool) -> None:
        self.executor.shutdown(wait=not cancel, cancel_futures=cancel)


class DaskBackend:
    """A Dask distributed client (owned when built from an address)."""

    name = "dask"

    def __init__(self, scheduler: Any) -> None:
        # optional (the `datasets` extra): only the Dask backend needs it
        from distributed import Client

        self.own = isinstance(scheduler, str)
        try:
            self.client = Client(scheduler, timeout="15s") if self.own else scheduler
        except OSError as err:
            raise DatasetError("scheduler", f"cannot connect to the Dask scheduler at "
                               f"{scheduler}: {err}") from None
        info = self.client.scheduler_info()
        workers = info.get("workers", {}).values()
        self.workers = sum(int(w.get("nthreads", 1)) for w in workers) or 1

    def submit(self, payload: str) -> Any:
        return self.client.submit(run_chunk, payload, pure=False)

    def wait(self, pending: Sequence[Any], timeout: float) -> set[Any]:
        # optional (the `datasets` extra): only the Dask backend needs it
        from distributed import wait

        try:
            res = wait(list(pending), timeout=timeout, return_when="FIRST_COMPLETED")
        except TimeoutError:
            return set()
        return set(res.done)

    def close(self, cancel: bool) -> None:
        if self.own:
            self.client.close()
