"""The ``log`` back end: every command as one JSON line, with its time.

Each line holds ``t_s`` (seconds since the device was opened, monotonic clock), ``utc`` (ISO
8601 wall-clock time) and ``command`` (``open``, ``set_levels``, ``play``, ``stop_all``,
``heartbeat``, ``status``, ``close``; and the host's events: ``limits`` in force with their
owners, the plan's integrity, ``refused`` with the field, value and limit, ``interrupted``
with what was and was not played) with the command's arguments: levels per channel
(fractions of nominal), and for ``play`` the steps (start, duration [ms], levels, rendered
site amplitudes [um]) and the segments ``[t_ms, duration_ms, channel, level]`` as sent.
The file is flushed after every line, so a crash keeps everything up to it.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from hardware.device import Device
from hardware.playback import JsonLines
from hardware.protocol import Segment, Status
from hardware.safety import ExposureMeter, SafetyLimits
from hardware.schedule import Schedule

__all__ = ["LogDevice"]


def _r(x: NDArray) -> list[float]:
    return [round(float(v), 6) for v in x]


class LogDevice(Device):
    """Writes the command log to ``path`` (JSON lines); holds the levels it was told."""

    def __init__(self, path: str | Path, n_channels: int, limits: SafetyLimits | None = None,
                 exposure: ExposureMeter | None = None) -> None:
        super().__init__(n_channels, limits, exposure)
        self.path = Path(path)
        self.record = JsonLines(self.path)
        self.levels = np.zeros(n_channels)
        # limits not given: the caller sets them next (set_limits, then a ``limits`` line)
        self._write("open", n_channels=n_channels,
                    limits=None if limits is None else vars(self.limits))

    def _write(self, command: str, **args: Any) -> None:
        self.record.write(command, **args)

    def note(self, event: str, **info: Any) -> None:
        self._write(event, **info)

    def _set_levels(self, levels: NDArray) -> None:
        self.levels = levels.copy()
        self._write("set_levels", levels=_r(levels))

    def _play(self, schedule: Schedule, segments: list[Segment]) -> None:
        steps = [{"start_ms": s.start_ms, "duration_ms": s.duration_ms, "levels": _r(s.levels),
                  "rendered_um": _r(s.rendered_um)} for s in schedule.steps]
        self._write("play", frequency_hz=schedule.frequency_hz, carrier_hz=schedule.carrier_hz,
                    total_ms=schedule.total_ms,
                    timing=schedule.timing, steps=steps,
                    segments=[[s.t_ms, s.duration_ms, s.channel, round(s.level, 6)]
                              for s in segments])
        self.levels = np.zeros(self.n_channels)  # the schedule ends with every channel off

    def _stop_all(self) -> None:
        self.levels = np.zeros(self.n_channels)
        self._write("stop_all")

    def _heartbeat(self) -> None:
        self._write("heartbeat")

    def _status(self) -> Status:
        self._write("status")
        return Status(0, round(self.limits.watchdog_s * 1e3), tuple(map(float, self.levels)))

    def _close(self) -> None:
        self._write("close")
        self.record.close()
