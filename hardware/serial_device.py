"""The ``serial`` back end: the frame protocol over a serial port (pyserial).

Every command is one frame with a new sequence number; the host waits ``timeout_s`` for the
device's ACK (STATUS for QUERY_STATUS) carrying that number. A NAK for a transient fault (bad
CRC, bad length: the frame was damaged on the way) or no answer in time -> the same frame is
sent again, at most ``retries`` times; a NAK for a refused command (channel, level, on-time)
is raised at once. A failing port (unplugged: ``SerialException``/``OSError``) marks the
device disconnected and raises :class:`DeviceError`; the firmware's watchdog then stops the
array, since no heartbeat arrives any more.

A refused PLAY_SCHEDULE (the schedule never started) is :class:`DeviceRefused` (bad input for
this device: exit 2). While a schedule plays (``wait``), the host polls STATUS every
``POLL_S``: a watchdog or on-time stop the device reports, a lost link or a refusal ends the
wait with :class:`PlaybackInterrupted`, whose report says up to which step the pattern was
played (:func:`hardware.playback.playback_report`); the exposure played so far is added to the
meter at least every ``ACCRUE_S`` (written through). ``record`` (a
:class:`hardware.playback.JsonLines`) keeps the session's events.
"""

from __future__ import annotations

import threading
import time
from typing import Any

import numpy as np
from numpy.typing import NDArray

from hardware.device import Device, DeviceError, DeviceRefused, PlaybackInterrupted
from hardware.limits import DeviceLimits
from hardware.playback import JsonLines, playback_report
from hardware.protocol import (
    APPEND,
    MAX_SEGMENTS,
    START_NOW,
    Decoder,
    ErrorCode,
    Frame,
    Msg,
    Segment,
    Status,
    decode_nak,
    decode_status,
    encode,
    encode_levels,
    encode_schedule,
)
from hardware.safety import ACCRUE_S, ExposureMeter, SafetyLimits
from hardware.schedule import Schedule

__all__ = ["SerialDevice"]

TRANSIENT = (ErrorCode.BAD_CRC, ErrorCode.BAD_LENGTH, ErrorCode.BAD_VERSION)
POLL_S = 0.05  # STATUS poll period while a schedule plays [s]
REFUSALS = {ErrorCode.ON_TIME: "a segment longer than the device's on-time limit",
            ErrorCode.LEVEL_RANGE: "a level beyond the device's own limit",
            ErrorCode.BAD_CHANNEL: "a channel the device does not have",
            ErrorCode.SCHEDULE_FULL: "more segments than the device holds",
            ErrorCode.BAD_TYPE: "a command the device does not know"}


class NakError(DeviceError):
    """The device refused a command (a NAK that is not a transmission fault)."""

    def __init__(self, msg: Msg, code: ErrorCode) -> None:
        super().__init__(f"the device refused {msg.name}: {code.name}")
        self.code = code


class SerialDevice(Device):
    """An array controller on ``port`` (a path, or an open pyserial-like object)."""

    needs_heartbeat = True

    def __init__(self, port: Any, n_channels: int, limits: SafetyLimits | None = None,
                 exposure: ExposureMeter | None = None, *, baudrate: int = 115200,
                 timeout_s: float = 0.1, retries: int = 3, wait: bool = True,
                 record: JsonLines | None = None) -> None:
        super().__init__(n_channels, limits, exposure)
        import serial  # the `hardware` extra (pyserial)

        self.link_errors: tuple[type[BaseException], ...] = (OSError, serial.SerialException)
        if isinstance(port, str):
            try:
                port = serial.Serial(port, baudrate=baudrate, timeout=0)
            except (serial.SerialException, OSError) as err:  # bad input: exit 2 in the CLI
                raise ValueError(f"cannot open serial port {port!r}: {err}") from None
        self.port = port
        self.timeout_s = timeout_s
        self.retries = retries
        self.wait = wait
        self.decoder = Decoder()
        self.lock = threading.Lock()
        self.seq = 0
        self.disconnected = False
        self.retransmissions = 0  # frames sent again
        self.transient_naks = 0  # of which after a NAK (the rest after a timeout)
        self.record = record
        status = self._status()
        self.first_status = status
        if len(status.levels) < n_channels:
            raise DeviceError(f"the device has {len(status.levels)} channels: the plan needs "
                              f"{n_channels}")
        self.device_watchdog_s = status.watchdog_ms / 1e3

    @property
    def watchdog_s(self) -> float:
        """The shorter of the host's and the device's watchdog times [s]."""
        return min(self.limits.watchdog_s, self.device_watchdog_s or self.limits.watchdog_s)

    def _transact(self, msg: Msg, payload: bytes = b"") -> Frame:
        """Send one command and return its reply, retrying as the module docstring says."""
        if self.disconnected:
            raise DeviceError("the serial device is disconnected")
        with self.lock:
            self.seq = (self.seq + 1) % 256
            frame = encode(msg, self.seq, payload)
            for attempt in range(self.retries + 1):
                self.retransmissions += attempt > 0
                try:
                    self.port.write(frame)
                    reply = self._await(self.seq)
                except self.link_errors as err:
                    self.disconnected = True
                    raise DeviceError(f"serial link lost: {err}") from None
                if reply is None:
                    self.decoder.buffer.clear()  # a stale partial reply
                    continue  # no answer in time: send again
                if reply.type == Msg.NAK:
                    _, code = decode_nak(reply.payload)
                    if code in TRANSIENT:
                        self.transient_naks += 1
                        continue
                    raise NakError(msg, code)
                return reply
        raise DeviceError(f"no acknowledgement of {msg.name} after {self.retries + 1} "
                          f"attempts of {self.timeout_s:g} s")

    def _await(self, seq: int) -> Frame | None:
        deadline = time.monotonic() + self.timeout_s
        while time.monotonic() < deadline:
            data = self.port.read(4096)
            if not data:
                time.sleep(0.0005)
                continue
            for item in self.decoder.feed(data):
                if isinstance(item, Frame) and item.seq == seq and item.type in (
                        Msg.ACK, Msg.NAK, Msg.STATUS):
                    return item
        return None

    def _set_levels(self, levels: NDArray) -> None:
        self._transact(Msg.SET_LEVELS, encode_levels(dict(enumerate(map(float, levels)))))

    def reported_limits(self) -> DeviceLimits:
        st = self.first_status
        return DeviceLimits(st.max_level, None if st.max_on_ms is None else st.max_on_ms / 1e3,
                            st.watchdog_ms / 1e3 if st.watchdog_ms else None)

    def note(self, event: str, **info: Any) -> None:
        if self.record is not None:
            self.record.write(event, **info)

    def _play(self, schedule: Schedule, segments: list[Segment]) -> None:
        chunks = [segments[i:i + MAX_SEGMENTS] for i in range(0, len(segments), MAX_SEGMENTS)]
        for i, chunk in enumerate(chunks or [[]]):
            flags = (APPEND if i else 0) | (START_NOW if i == len(chunks) - 1 else 0)
            try:
                self._transact(Msg.PLAY_SCHEDULE, encode_schedule(chunk, flags))
            except NakError as err:  # START_NOW rides on the last chunk: nothing started
                raise DeviceRefused(f"the device refused the schedule ({err.code.name}: "
                                    f"{REFUSALS.get(err.code, 'refused')}); nothing was "
                                    "played", err.code.name) from None
        if self.wait:  # keep the host alive (and its heartbeat going) while it plays
            self._watch(schedule, time.monotonic())

    def _watch(self, schedule: Schedule, t0: float) -> None:
        """Poll STATUS until the schedule's end; raise PlaybackInterrupted on a stop."""
        total = schedule.total_ms
        ok_ms, accrued_at = 0.0, t0
        while True:
            asked = (time.monotonic() - t0) * 1e3
            try:
                st = self._status()
            except NakError as err:
                raise PlaybackInterrupted(playback_report(schedule, ok_ms, "nak",
                                                          str(err))) from None
            except DeviceError as err:
                raise PlaybackInterrupted(playback_report(schedule, ok_ms, "link",
                                                          str(err))) from None
            if st.watchdog_tripped or st.on_time_tripped:
                self.accrue(schedule, min(asked, total))  # possibly on until now: counted
                reason = "watchdog" if st.watchdog_tripped else "on-time"
                raise PlaybackInterrupted(playback_report(schedule, ok_ms, reason))
            ok_ms = min(asked, total)
            if time.monotonic() - accrued_at >= ACCRUE_S:
                self.accrue(schedule, ok_ms)
                accrued_at = time.monotonic()
            if asked >= total:
                return
            time.sleep(min(POLL_S, max(0.0, (total - asked) / 1e3)))

    def _stop_all(self) -> None:
        self._transact(Msg.STOP_ALL)

    def _heartbeat(self) -> None:
        self._transact(Msg.HEARTBEAT)

    def _status(self) -> Status:
        reply = self._transact(Msg.QUERY_STATUS)
        if reply.type != Msg.STATUS:
            raise DeviceError("QUERY_STATUS answered without a STATUS frame")
        return decode_status(reply.payload)

    def _close(self) -> None:
        try:
            self.port.close()
        except Exception:
            pass

    @property
    def levels(self) -> NDArray:
        return np.array(self.status().levels[:self.n_channels])
