"""The host-side heartbeat: a daemon thread calling ``device.heartbeat()`` every
``period_s`` (a quarter of the device's watchdog time by default, so that three lost
heartbeats in a row still keep the device running). When a heartbeat fails the thread stops
and keeps the error; the device's watchdog then stops every channel.

    with open_device(...) as dev, Heartbeat(dev):
        dev.play(schedule)
"""

from __future__ import annotations

import threading
from types import TracebackType
from typing import Any


class Heartbeat:
    """Runs ``device.heartbeat()`` in a thread until stopped (a context manager)."""

    def __init__(self, device: Any, period_s: float | None = None) -> None:
        self.device = device
        self.period_s = period_s if period_s is not None else device.watchdog_s / 4
        if not 0 < self.period_s < device.watchdog_s:
            raise ValueError(f"heartbeat period {self.period_s!r} s: allowed 0 < period < "
                             f"the watchdog time {device.watchdog_s} s")
        self.error: BaseException | None = None
        self.beats = 0
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="hapticrom-heartbeat",
                                        daemon=True)

    def _run(self) -> None:
        while not self._stop.wait(self.period_s):
            try:
                self.device.heartbeat()
                self.beats += 1
            except Exception as err:  # the link failed: the device watchdog takes over
                self.error = err
                return

    def start(self) -> Heartbeat:
        """Beat once now (so that commands right after this are covered), then every
        period in the thread."""
        self.device.heartbeat()
        self.beats += 1
        self._thread.start()
        return self

    def stop(self) -> None:
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join()

    def __enter__(self) -> Heartbeat:
        return self.start()

    def __exit__(self, kind: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        self.stop()
