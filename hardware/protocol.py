"""The binary frame protocol between the host and an array controller (version 1).

Every message is one frame (multi-byte fields little-endian; docs/protocol.md has the table)::

    offset  size  field
    0       1     START = 0xA5
    1       1     VERSION = 1
    2       1     message type (:class:`Msg`)
    3       1     sequence number (0-255, wraps; a reply carries the request's number)
    4       2     payload length n (0 <= n <= MAX_PAYLOAD)
    6       n     payload
    6+n     2     CRC-16/CCITT-FALSE over bytes 1 .. 5+n (big-endian on the wire)

CRC-16/CCITT-FALSE: polynomial 0x1021, initial value 0xFFFF, no reflection, no final XOR; its
check value over ASCII "123456789" is 0x29B1 (Greg Cook's CRC catalogue, "CRC-16/IBM-3740").
``binascii.crc_hqx`` computes exactly this CRC.

Levels travel as signed 16-bit integers in units of 1/LEVEL_SCALE of the nominal drive level
(1.0 = the plan's nominal voltage); negative levels are reverse drive (ERM braking).

:class:`Decoder` is a streaming decoder: it accepts bytes in any chunking, skips garbage
before a start byte, and after a frame whose CRC, version or length is bad it drops that
start byte only and searches again from the next byte, so a valid frame that follows (or
hides inside) corrupted bytes is still found. Bad frames are reported as
:class:`FrameError` items so that a receiver can answer with a NAK.
"""

from __future__ import annotations

import binascii
import struct
from dataclasses import dataclass, field
from enum import IntEnum

__all__ = ["FRAME_TIMEOUT_S", "LEVEL_SCALE", "MAX_PAYLOAD", "START", "VERSION", "Decoder",
           "ErrorCode", "Frame", "FrameError", "Msg", "Segment", "Status", "crc16", "decode_ack",
           "decode_levels", "decode_nak", "decode_schedule", "decode_status", "encode",
           "encode_ack",
           "encode_levels", "encode_nak", "encode_schedule", "encode_status", "from_level",
           "to_level"]

START = 0xA5
VERSION = 1
HEADER = struct.Struct("<BBBBH")  # start, version, type, seq, length
MAX_PAYLOAD = 4096
FRAME_TIMEOUT_S = 0.02  # a frame's bytes arrive within this (4 kB at 115200 baud: 0.36 s;
# the timeout runs from the last byte received, so it bounds the gap between bytes)
LEVEL_SCALE = 4096  # int16 level units per nominal level: range about -8 .. +8
SEGMENT = struct.Struct("<IHBh")  # t_ms, duration_ms, channel, level
MAX_SEGMENTS = (MAX_PAYLOAD - 3) // SEGMENT.size

# PLAY_SCHEDULE flags
APPEND = 0x01  # add to the schedule already loaded (else replace it)
START_NOW = 0x02  # start playing when this frame is accepted

# STATUS flags
ST_WATCHDOG = 0x01  # the watchdog stopped every channel since the last status
ST_PLAYING = 0x02
ST_ON_TIME = 0x04  # a channel was stopped by the on-time limit


class Msg(IntEnum):
    """Message types (host -> device below 0x80, device -> host from 0x80)."""

    SET_LEVELS = 0x01  # payload: u8 count, count x (u8 channel, i16 level)
    PLAY_SCHEDULE = 0x02  # payload: u8 flags, u16 count, count x segment (t, duration, ch, lvl)
    STOP_ALL = 0x03  # empty
    HEARTBEAT = 0x04  # empty
    QUERY_STATUS = 0x05  # empty
    ACK = 0x80  # payload: u8 sequence number acknowledged
    NAK = 0x81  # payload: u8 sequence number refused, u8 ErrorCode
    STATUS = 0x82  # payload: u8 flags, u8 channels, u16 watchdog_ms, channels x i16 level,
    # then (optional) the device's own limits: i16 max_level, u16 max_on_ms


class ErrorCode(IntEnum):
    """Why a device refused a frame (NAK payload)."""

    BAD_CRC = 1
    BAD_VERSION = 2
    BAD_TYPE = 3
    BAD_LENGTH = 4  # frame length field too large, or payload size wrong for its type
    BAD_CHANNEL = 5
    LEVEL_RANGE = 6  # a level beyond the device's own limit
    SCHEDULE_FULL = 7
    ON_TIME = 8  # a schedule segment longer than the device's on-time limit


def crc16(data: bytes) -> int:
    """CRC-16/CCITT-FALSE of ``data``."""
    return binascii.crc_hqx(data, 0xFFFF)


@dataclass(frozen=True)
class Frame:
    """One decoded frame."""

    type: int
    seq: int
    payload: bytes = b""


@dataclass(frozen=True)
class FrameError:
    """A frame the decoder rejected: ``code`` says why; ``seq`` is the header's (may itself
    be corrupted) or None when no header was read."""

    code: ErrorCode
    seq: int | None
    detail: str = ""


def encode(msg: int, seq: int, payload: bytes = b"") -> bytes:
    """One frame as bytes."""
    if not 0 <= seq <= 255:
        raise ValueError(f"seq = {seq}: allowed 0 <= seq <= 255")
    if len(payload) > MAX_PAYLOAD:
        raise ValueError(f"payload of {len(payload)} bytes: allowed at most {MAX_PAYLOAD}")
    body = HEADER.pack(START, VERSION, int(msg), seq, len(payload))[1:] + payload
    return bytes([START]) + body + struct.pack(">H", crc16(body))


@dataclass
class Decoder:
    """Streaming frame decoder: ``feed(bytes)`` returns the frames and errors completed."""

    buffer: bytearray = field(default_factory=bytearray)
    garbage: int = 0  # bytes skipped while searching for a start byte (a statistic)

    def feed(self, data: bytes) -> list[Frame | FrameError]:
        self.buffer += data
        out: list[Frame | FrameError] = []
        while True:
            start = self.buffer.find(START)
            if start < 0:
                self.garbage += len(self.buffer)
                self.buffer.clear()
                return out
            if start:
                self.garbage += start
                del self.buffer[:start]
            if len(self.buffer) < HEADER.size:
                return out
            _, version, msg, seq, length = HEADER.unpack_from(self.buffer)
            if length > MAX_PAYLOAD:
                out.append(FrameError(ErrorCode.BAD_LENGTH, seq, f"length {length}"))
                del self.buffer[:1]
                continue
            end = HEADER.size + length + 2
            if len(self.buffer) < end:
                return out
            body = bytes(self.buffer[1:HEADER.size + length])
            (crc,) = struct.unpack_from(">H", self.buffer, HEADER.size + length)
            if crc != crc16(body):
                out.append(FrameError(ErrorCode.BAD_CRC, seq, "CRC mismatch"))
                del self.buffer[:1]
                continue
            if version != VERSION:
                out.append(FrameError(ErrorCode.BAD_VERSION, seq, f"version {version}"))
                del self.buffer[:end]
                continue
            out.append(Frame(msg, seq, bytes(self.buffer[HEADER.size:HEADER.size + length])))
            del self.buffer[:end]

    def timeout(self) -> list[Frame | FrameError]:
        """The line went quiet with an incomplete frame buffered (a corrupted length field
        makes the decoder wait for bytes that never come): drop its start byte and decode
        what follows, until nothing is left waiting. Receivers call this after
        ``FRAME_TIMEOUT_S`` without new bytes."""
        if not self.buffer:
            return []
        seq = self.buffer[3] if len(self.buffer) > 3 else None
        out: list[Frame | FrameError] = [
            FrameError(ErrorCode.BAD_LENGTH, seq, "incomplete frame timed out")]
        while self.buffer:
            del self.buffer[:1]
            out += self.feed(b"")
        return out


# ---- payloads -------------------------------------------------------------------------------


def to_level(x: float) -> int:
    """A level (fraction of nominal; negative: reverse drive) as its int16 wire value."""
    q = round(float(x) * LEVEL_SCALE)
    if not -32768 <= q <= 32767:
        raise ValueError(f"level {x!r}: allowed {-32768 / LEVEL_SCALE:g} .. "
                         f"{32767 / LEVEL_SCALE:g}")
    return q


def from_level(q: int) -> float:
    return q / LEVEL_SCALE


def encode_levels(levels: dict[int, float]) -> bytes:
    """SET_LEVELS payload: channel -> level."""
    if len(levels) > 255:
        raise ValueError(f"{len(levels)} channels in one SET_LEVELS: allowed at most 255")
    return bytes([len(levels)]) + b"".join(struct.pack("<Bh", ch, to_level(v))
                                           for ch, v in sorted(levels.items()))


def decode_levels(payload: bytes) -> dict[int, float]:
    if not payload or len(payload) != 1 + 3 * payload[0]:
        raise ValueError("SET_LEVELS payload size does not match its count")
    return {ch: from_level(q) for ch, q in struct.iter_unpack("<Bh", payload[1:])}


@dataclass(frozen=True)
class Segment:
    """One schedule entry: ``channel`` at ``level`` from ``t_ms`` for ``duration_ms``."""

    t_ms: int
    duration_ms: int
    channel: int
    level: float


def encode_schedule(segments: list[Segment], flags: int) -> bytes:
    """PLAY_SCHEDULE payload (at most MAX_SEGMENTS segments; split longer schedules and send
    the rest with APPEND)."""
    if len(segments) > MAX_SEGMENTS:
        raise ValueError(f"{len(segments)} segments in one frame: allowed {MAX_SEGMENTS}")
    head = struct.pack("<BH", flags, len(segments))
    return head + b"".join(SEGMENT.pack(s.t_ms, s.duration_ms, s.channel, to_level(s.level))
                           for s in segments)


def decode_schedule(payload: bytes) -> tuple[int, list[Segment]]:
    if len(payload) < 3:
        raise ValueError("PLAY_SCHEDULE payload too short")
    flags, count = struct.unpack_from("<BH", payload)
    if len(payload) != 3 + count * SEGMENT.size:
        raise ValueError("PLAY_SCHEDULE payload size does not match its count")
    segs = [Segment(t, d, ch, from_level(q)) for t, d, ch, q in
            SEGMENT.iter_unpack(payload[3:])]
    return flags, segs


def encode_ack(seq: int) -> bytes:
    return bytes([seq])


def decode_ack(payload: bytes) -> int:
    if len(payload) != 1:
        raise ValueError("ACK payload must be 1 byte")
    return payload[0]


def encode_nak(seq: int, code: ErrorCode) -> bytes:
    return bytes([seq, int(code)])


def decode_nak(payload: bytes) -> tuple[int, ErrorCode]:
    if len(payload) != 2:
        raise ValueError("NAK payload must be 2 bytes")
    return payload[0], ErrorCode(payload[1])


@dataclass(frozen=True)
class Status:
    """A device's state: ``flags`` (ST_*), watchdog time [ms], present level per channel,
    and the device's own limits when it reports them (``max_level`` in levels, ``max_on_ms``
    the longest continuous on-time per channel [ms]; None: not reported)."""

    flags: int
    watchdog_ms: int
    levels: tuple[float, ...]
    max_level: float | None = None
    max_on_ms: int | None = None

    @property
    def watchdog_tripped(self) -> bool:
        return bool(self.flags & ST_WATCHDOG)

    @property
    def on_time_tripped(self) -> bool:
        return bool(self.flags & ST_ON_TIME)

    @property
    def playing(self) -> bool:
        return bool(self.flags & ST_PLAYING)


STATUS_LIMITS = struct.Struct("<hH")  # the optional tail of STATUS: max_level, max_on_ms


def encode_status(status: Status) -> bytes:
    n = len(status.levels)
    out = struct.pack("<BBH", status.flags, n, status.watchdog_ms) + b"".join(
        struct.pack("<h", to_level(v)) for v in status.levels)
    if status.max_level is not None:
        out += STATUS_LIMITS.pack(to_level(status.max_level), status.max_on_ms or 0)
    return out


def decode_status(payload: bytes) -> Status:
    if len(payload) < 4:
        raise ValueError("STATUS payload too short")
    flags, n, wd = struct.unpack_from("<BBH", payload)
    end = 4 + 2 * n
    if len(payload) not in (end, end + STATUS_LIMITS.size):
        raise ValueError("STATUS payload size does not match its channel count")
    levels = tuple(from_level(q) for (q,) in struct.iter_unpack("<h", payload[4:end]))
    if len(payload) == end:
        return Status(flags, wd, levels)
    q, on_ms = STATUS_LIMITS.unpack_from(payload, end)
    return Status(flags, wd, levels, from_level(q), on_ms or None)
