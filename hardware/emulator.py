"""A device emulator speaking the frame protocol, for tests and for trying the host without
hardware. It enforces the rules docs/protocol.md asks of the firmware:

* every frame is answered: ACK, NAK with an error code (bad CRC, version, type, length,
  channel, level, on-time), or STATUS; a repeated sequence number gets the same answer again
  without the command being applied twice (the host retransmits after a lost reply);
* watchdog: no HEARTBEAT for ``watchdog_s`` -> every channel stopped and the schedule
  dropped, within one ``tick_s`` of the deadline;
* on-time: a channel running without a pause for ``max_on_s`` is stopped;
* levels beyond ``max_level`` and schedule segments longer than ``max_on_s`` are refused;
* STATUS reports its own limits (``max_level``, ``max_on_s``) besides the watchdog time.

Defaults are the actuator's rated limits, as the firmware's must be: ``max_level`` =
maximum / rated voltage of the ERM (:data:`DEFAULT_MAX_LEVEL`, 4.5 V / 3.3 V = 1.364;
:data:`hardware.limits.ERM_RATING` says where the numbers come from), ``max_on_s`` 10 s and
``watchdog_s`` 0.25 s (the host's defaults, project choices).

:class:`EmulatedArray` is the state machine (time passed in, so tests can drive it with a
fake clock); :class:`PtyEmulator` runs it in a thread behind a pseudo-terminal
(``os.openpty``) whose slave path a host opens as a serial port. Every level change is
recorded with its time and reason in ``events``; every frame received in ``received``.
"""

from __future__ import annotations

import os
import select
import threading
import time
import tty
from dataclasses import dataclass, field

from hardware.limits import ERM_RATING
from hardware.protocol import (
    APPEND,
    FRAME_TIMEOUT_S,
    LEVEL_SCALE,
    ST_ON_TIME,
    ST_PLAYING,
    ST_WATCHDOG,
    START_NOW,
    Decoder,
    ErrorCode,
    Frame,
    FrameError,
    Msg,
    Segment,
    Status,
    decode_levels,
    decode_schedule,
    encode,
    encode_ack,
    encode_nak,
    encode_status,
)

__all__ = ["DEFAULT_MAX_LEVEL", "DEFAULT_MAX_ON_S", "DEFAULT_WATCHDOG_S", "EmulatedArray",
           "Event", "PtyEmulator"]

DEFAULT_MAX_LEVEL = round(ERM_RATING.max_voltage_V / ERM_RATING.rated_voltage_V, 4)
DEFAULT_MAX_ON_S = 10.0
DEFAULT_WATCHDOG_S = 0.25


@dataclass(frozen=True)
class Event:
    """A channel's level changed at ``t`` (the emulator's clock, s) because of ``reason``."""

    t: float
    channel: int
    level: float
    reason: str


@dataclass
class EmulatedArray:
    """The firmware's state machine."""

    n_channels: int
    watchdog_s: float = DEFAULT_WATCHDOG_S
    max_on_s: float = DEFAULT_MAX_ON_S
    max_level: float = DEFAULT_MAX_LEVEL
    start_time: float = 0.0
    report_limits: bool = True  # False: a firmware of the shorter STATUS (no limits in it)
    levels: list[float] = field(init=False)
    events: list[Event] = field(default_factory=list)
    received: list[tuple[float, Frame | FrameError]] = field(default_factory=list)
    heartbeats: list[float] = field(default_factory=list)

    def __post_init__(self) -> None:
        self.levels = [0.0] * self.n_channels
        self.on_since: dict[int, float] = {}
        self.last_heartbeat = self.start_time
        self.flags = 0
        self.schedule: list[Segment] = []
        self.t0: float | None = None
        self._last: tuple[int, int, bytes] | None = None  # (type, seq, reply) for repeats

    # ---- levels ------------------------------------------------------------------------------

    def _set(self, ch: int, level: float, now: float, reason: str) -> None:
        if self.levels[ch] == level:
            return
        self.levels[ch] = level
        self.events.append(Event(now, ch, level, reason))
        if level == 0:
            self.on_since.pop(ch, None)
        else:
            self.on_since.setdefault(ch, now)

    def _stop_all(self, now: float, reason: str) -> None:
        self.schedule, self.t0 = [], None
        for ch in range(self.n_channels):
            self._set(ch, 0.0, now, reason)

    # ---- frames ------------------------------------------------------------------------------

    def handle(self, item: Frame | FrameError, now: float) -> bytes:
        """Apply one decoded frame; returns the reply frame's bytes."""
        self.received.append((now, item))
        if isinstance(item, FrameError):
            return self._nak(item.seq or 0, item.code)  # the header's seq (may be damaged)
        if self._last is not None and self._last[:2] == (item.type, item.seq):
            return self._last[2]  # a retransmission: answer again, do not apply again
        reply = self._apply(item, now)
        self._last = (item.type, item.seq, reply)
        return reply

    def _nak(self, seq: int, code: ErrorCode) -> bytes:
        return encode(Msg.NAK, seq, encode_nak(seq, code))

    def _apply(self, f: Frame, now: float) -> bytes:
        ack = encode(Msg.ACK, f.seq, encode_ack(f.seq))
        try:
            if f.type == Msg.HEARTBEAT:
                self.last_heartbeat = now
                self.heartbeats.append(now)
            elif f.type == Msg.STOP_ALL:
                self._stop_all(now, "stop")
            elif f.type == Msg.QUERY_STATUS:
                limits = (self.max_level, min(round(self.max_on_s * 1e3), 65535)) \
                    if self.report_limits else (None, None)
                status = Status(self.flags | (ST_PLAYING if self.t0 is not None else 0),
                                round(self.watchdog_s * 1e3), tuple(self.levels), *limits)
                self.flags = 0
                return encode(Msg.STATUS, f.seq, encode_status(status))
            elif f.type == Msg.SET_LEVELS:
                levels = decode_levels(f.payload)
                code = self._check(levels.items())
                if code:
                    return self._nak(f.seq, code)
                for ch, v in levels.items():
                    self._set(ch, v, now, "set")
            elif f.type == Msg.PLAY_SCHEDULE:
                flags, segs = decode_schedule(f.payload)
                code = self._check((s.channel, s.level) for s in segs)
                if not code and any(s.duration_ms > self.max_on_s * 1e3 for s in segs):
                    code = ErrorCode.ON_TIME
                if code:
                    return self._nak(f.seq, code)
                self.schedule = (self.schedule if flags & APPEND else []) + segs
                if flags & START_NOW:
                    self.t0 = now
            else:
                return self._nak(f.seq, ErrorCode.BAD_TYPE)
        except ValueError:
            return self._nak(f.seq, ErrorCode.BAD_LENGTH)
        return ack

    def _check(self, items) -> ErrorCode | None:
        for ch, v in items:
            if not 0 <= ch < self.n_channels:
                return ErrorCode.BAD_CHANNEL
            if abs(v) > self.max_level + 1 / LEVEL_SCALE:  # one wire step of rounding
                return ErrorCode.LEVEL_RANGE
        return None

    # ---- time --------------------------------------------------------------------------------

    def tick(self, now: float) -> None:
        """Advance to ``now``: the schedule, then the on-time limit, then the watchdog."""
        if self.t0 is not None:
            t_ms = (now - self.t0) * 1e3
            want = [0.0] * self.n_channels
            for s in self.schedule:
                if s.t_ms <= t_ms < s.t_ms + s.duration_ms:
                    want[s.channel] = s.level
            for ch, v in enumerate(want):
                self._set(ch, v, now, "schedule")
            if t_ms >= max((s.t_ms + s.duration_ms for s in self.schedule), default=0):
                self.schedule, self.t0 = [], None
        for ch, since in list(self.on_since.items()):
            if now - since >= self.max_on_s:
                self.schedule = [s for s in self.schedule if s.channel != ch]
                self._set(ch, 0.0, now, "on-time")
                self.flags |= ST_ON_TIME
        if now - self.last_heartbeat >= self.watchdog_s and (
                any(self.levels) or self.t0 is not None):
            self._stop_all(now, "watchdog")
            self.flags |= ST_WATCHDOG


class PtyEmulator:
    """:class:`EmulatedArray` behind a pseudo-terminal, in a thread (a context manager).
    ``port`` is the path a host opens (``serial.Serial(port)``)."""

    def __init__(self, n_channels: int, watchdog_s: float = DEFAULT_WATCHDOG_S,
                 max_on_s: float = DEFAULT_MAX_ON_S, max_level: float = DEFAULT_MAX_LEVEL,
                 tick_s: float = 0.001, report_limits: bool = True) -> None:
        self.master, self.slave = os.openpty()
        tty.setraw(self.slave)
        self.port = os.ttyname(self.slave)
        self.tick_s = tick_s
        self.array = EmulatedArray(n_channels, watchdog_s, max_on_s, max_level,
                                   start_time=time.monotonic(), report_limits=report_limits)
        self.lock = threading.Lock()
        self.decoder = Decoder()
        self.last_byte = time.monotonic()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="pty-emulator", daemon=True)

    def _run(self) -> None:
        while not self._stop.is_set():
            ready, _, _ = select.select([self.master], [], [], self.tick_s)
            data = os.read(self.master, 4096) if ready else b""
            with self.lock:
                now = time.monotonic()
                if data:
                    self.last_byte = now
                    items = self.decoder.feed(data)
                elif self.decoder.buffer and now - self.last_byte > FRAME_TIMEOUT_S:
                    items = self.decoder.timeout()
                else:
                    items = []
                for item in items:
                    os.write(self.master, self.array.handle(item, now))
                self.array.tick(time.monotonic())

    def start(self) -> PtyEmulator:
        self._thread.start()
        return self

    def stop(self) -> None:
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join()
        for fd in (self.master, self.slave):
            try:
                os.close(fd)
            except OSError:
                pass

    def __enter__(self) -> PtyEmulator:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()
