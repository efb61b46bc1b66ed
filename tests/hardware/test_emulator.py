"""The firmware rules on the emulator's state machine, with a clock the test sets."""

from __future__ import annotations

import struct

from hardware.emulator import EmulatedArray
from hardware.protocol import (
    APPEND,
    ST_ON_TIME,
    START_NOW,
    Decoder,
    ErrorCode,
    Frame,
    FrameError,
    Msg,
    Segment,
    decode_nak,
    decode_status,
    encode_levels,
    encode_schedule,
)


def reply(array: EmulatedArray, msg: Msg, seq: int, payload: bytes, now: float) -> Frame:
    (out,) = Decoder().feed(array.handle(Frame(msg, seq, payload), now))
    return out


def stops(array: EmulatedArray, reason: str) -> dict[int, float]:
    return {e.channel: e.t for e in array.events if e.level == 0 and e.reason == reason}


def test_watchdog_stops_every_channel_at_the_deadline():
    # times are binary fractions so that the deadline is exact
    a = EmulatedArray(4, watchdog_s=0.25, max_on_s=10.0)
    assert reply(a, Msg.HEARTBEAT, 1, b"", 0.125).type == Msg.ACK
    reply(a, Msg.SET_LEVELS, 2, encode_levels({c: 1.0 for c in range(4)}), 0.25)
    a.tick(0.374)
    assert a.levels == [1.0] * 4
    a.tick(0.375)
    assert a.levels == [0.0] * 4
    assert stops(a, "watchdog") == {c: 0.375 for c in range(4)}
    status = decode_status(reply(a, Msg.QUERY_STATUS, 3, b"", 0.5).payload)
    assert status.watchdog_tripped and status.levels == (0.0,) * 4
    assert not decode_status(reply(a, Msg.QUERY_STATUS, 4, b"", 0.5).payload).watchdog_tripped


def test_heartbeats_keep_it_running_and_only_heartbeats_count():
    a = EmulatedArray(2, watchdog_s=0.25, max_on_s=10.0)
    reply(a, Msg.SET_LEVELS, 1, encode_levels({0: 0.5}), 0.0)
    for k in range(1, 9):
        reply(a, Msg.HEARTBEAT, 1 + k, b"", 0.125 * k)
        a.tick(0.125 * k + 0.125)
    assert a.levels[0] == 0.5  # last heartbeat at 1.0
    for k in range(8):  # other commands do not feed the watchdog
        reply(a, Msg.QUERY_STATUS, 20 + k, b"", 1.0 + 0.03125 * k)
        a.tick(1.0 + 0.03125 * k)
    assert a.levels[0] == 0.5
    a.tick(1.25)
    assert stops(a, "watchdog") == {0: 1.25}


def test_on_time_limit_stops_one_channel():
    a = EmulatedArray(2, watchdog_s=0.25, max_on_s=1.0)
    reply(a, Msg.SET_LEVELS, 1, encode_levels({0: 1.0, 1: 0.0}), 0.0)
    reply(a, Msg.SET_LEVELS, 2, encode_levels({1: 1.0}), 0.5)
    for k in range(1, 10):
        reply(a, Msg.HEARTBEAT, 2 + k, b"", 0.125 * k)
        a.tick(0.125 * k)
    assert stops(a, "on-time") == {0: 1.0}
    assert a.levels == [0.0, 1.0]
    a.tick(1.5)
    assert stops(a, "on-time") == {0: 1.0, 1: 1.5}
    assert decode_status(reply(a, Msg.QUERY_STATUS, 50, b"", 1.5).payload).flags & ST_ON_TIME


def test_schedule_plays_in_time_and_appends():
    a = EmulatedArray(2, watchdog_s=10.0, max_on_s=10.0, max_level=2.0)
    first = [Segment(0, 10, 0, 1.5), Segment(10, 90, 0, 1.0)]
    reply(a, Msg.PLAY_SCHEDULE, 1, encode_schedule(first, 0), 0.0)
    reply(a, Msg.PLAY_SCHEDULE, 2, encode_schedule([Segment(100, 8, 0, -1.5)],
                                                    APPEND | START_NOW), 1.0)
    seen = {}
    for ms in (0, 5, 10, 50, 99, 100, 107, 108, 200):
        a.tick(1.0 + ms / 1e3)
        seen[ms] = a.levels[0]
    assert seen == {0: 1.5, 5: 1.5, 10: 1.0, 50: 1.0, 99: 1.0, 100: -1.5, 107: -1.5, 108: 0.0,
                    200: 0.0}
    assert a.t0 is None  # finished


def test_a_retransmitted_command_is_answered_again_but_applied_once():
    a = EmulatedArray(1, watchdog_s=10.0, max_on_s=10.0)
    p = encode_levels({0: 1.0})
    r1 = reply(a, Msg.SET_LEVELS, 9, p, 0.0)
    reply(a, Msg.STOP_ALL, 10, b"", 0.1)
    r2 = reply(a, Msg.STOP_ALL, 10, b"", 0.2)  # the ACK was lost: the host sends it again
    assert r1.type == r2.type == Msg.ACK
    assert [(e.level, e.reason) for e in a.events] == [(1.0, "set"), (0.0, "stop")]


def test_refusals_carry_their_error_code():
    a = EmulatedArray(2, watchdog_s=10.0, max_on_s=1.0, max_level=1.5)

    def code(msg, payload, seq):
        r = reply(a, msg, seq, payload, 0.0)
        assert r.type == Msg.NAK
        return decode_nak(r.payload)

    assert code(Msg.SET_LEVELS, encode_levels({2: 1.0}), 1) == (1, ErrorCode.BAD_CHANNEL)
    assert code(Msg.SET_LEVELS, encode_levels({0: 1.6}), 2) == (2, ErrorCode.LEVEL_RANGE)
    assert code(Msg.PLAY_SCHEDULE, encode_schedule([Segment(0, 1001, 0, 1.0)], START_NOW),
                3) == (3, ErrorCode.ON_TIME)
    assert code(0x42, b"", 4) == (4, ErrorCode.BAD_TYPE)
    assert code(Msg.SET_LEVELS, struct.pack("<B", 3), 5) == (5, ErrorCode.BAD_LENGTH)
    assert a.levels == [0.0, 0.0] and not a.events
    (nak,) = Decoder().feed(a.handle(FrameError(ErrorCode.BAD_CRC, 77), 0.0))
    assert decode_nak(nak.payload) == (77, ErrorCode.BAD_CRC)
