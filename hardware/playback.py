"""What a cut-short schedule did and did not play, and the JSON-lines record of a session.

When the device stops a schedule early (its watchdog or on-time limit, reported in STATUS),
the link is lost, or a command is refused while playing, the host knows the last moment it saw
the device playing normally (``played_ms`` after the start: a status poll without a stop flag).
:func:`playback_report` splits the pattern's steps at that moment: played in full, cut short
(with its channels), not played in full (those after it: not played, or started in the last
poll interval before the stop); ``play`` prints it and exits 1.
"""

from __future__ import annotations

import json
import time
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["REASONS", "JsonLines", "playback_report"]

REASONS = {
    "watchdog": "the device's watchdog stopped every channel (no heartbeat reached it in time: "
                "the host was frozen, overloaded or the link stalled)",
    "on-time": "the device's on-time limit stopped a channel",
    "link": "the link to the device was lost",
    "nak": "the device refused a command while playing",
}


def _channels(levels_rows: list[np.ndarray]) -> list[int]:
    on = np.zeros(len(levels_rows[0]), dtype=bool) if levels_rows else np.zeros(0, bool)
    for row in levels_rows:
        on |= np.asarray(row) > 0
    return [int(c) for c in np.flatnonzero(on)]


def _span(idx: list[int]) -> str:
    if not idx:
        return "none"
    return f"{idx[0]}" if len(idx) == 1 else f"{idx[0]}-{idx[-1]}"


def playback_report(schedule: Any, played_ms: float, reason: str,
                    detail: str = "") -> dict[str, Any]:
    """What of ``schedule`` (a :class:`hardware.schedule.Schedule`) was played up to
    ``played_ms`` [ms after its start], and why it stopped (a key of :data:`REASONS`)."""
    played, cut, dropped = [], None, []
    for k, s in enumerate(schedule.steps):
        if s.start_ms + s.duration_ms <= played_ms:
            played.append(k)
        elif s.start_ms < played_ms:
            cut = k
        else:
            dropped.append(k)
    steps = schedule.steps
    cut_ch = _channels([steps[cut].levels]) if cut is not None else []
    dropped_ch = _channels([steps[k].levels for k in dropped])
    why = REASONS[reason] + (f": {detail}" if detail else "")
    lines = [f"play interrupted after {played_ms:.0f} of {schedule.total_ms} ms: {why}.",
             f"  played in full: steps {_span(played)} ({len(played)} of {len(steps)})"]
    if cut is not None:
        lines.append(f"  cut short: step {cut} (channels {', '.join(map(str, cut_ch))})")
    lines.append(f"  not played in full: steps {_span(dropped)} ({len(dropped)} steps"
                 + (f"; channels {', '.join(map(str, dropped_ch))})" if dropped else ")"))
    return {"reason": reason, "detail": detail, "played_ms": round(float(played_ms), 1),
            "total_ms": schedule.total_ms, "steps_played": played, "step_cut": cut,
            "step_cut_channels": cut_ch, "steps_not_played": dropped,
            "channels_not_played": dropped_ch, "summary": "\n".join(lines)}


class JsonLines:
    """An append-only record, one JSON object a line with ``t_s`` (since it was opened,
    monotonic), ``utc`` and ``command``; flushed after every line, so a crash keeps
    everything up to it."""

    def __init__(self, path: str | Path, mode: str = "w") -> None:
        self.path = Path(path)
        self.file = self.path.open(mode, encoding="utf-8")
        self.t_open = time.monotonic()

    def write(self, command: str, **args: Any) -> None:
        if self.file.closed:
            return
        line = {"t_s": round(time.monotonic() - self.t_open, 6),
                "utc": datetime.now(UTC).isoformat(timespec="microseconds"),
                "command": command, **args}
        self.file.write(json.dumps(line, default=str) + "\n")
        self.file.flush()

    def close(self) -> None:
        self.file.close()
