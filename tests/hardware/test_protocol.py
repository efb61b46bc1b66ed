"""The frame protocol: CRC, round trips, and a decoder that survives corrupted bytes."""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hardware.protocol import (
    MAX_PAYLOAD,
    START,
    Decoder,
    ErrorCode,
    Frame,
    FrameError,
    Msg,
    Segment,
    Status,
    crc16,
    decode_levels,
    decode_nak,
    decode_schedule,
    decode_status,
    encode,
    encode_levels,
    encode_nak,
    encode_schedule,
    encode_status,
    from_level,
    to_level,
)

frames = st.builds(lambda t, s, p: (t, s, p), st.sampled_from(list(Msg)),
                   st.integers(0, 255), st.binary(max_size=64))


def test_crc_is_ccitt_false_with_its_published_check_value():
    assert crc16(b"123456789") == 0x29B1
    assert crc16(b"") == 0xFFFF


def test_frame_layout_by_hand():
    f = encode(Msg.SET_LEVELS, 7, b"\x01\x02")
    assert f[:6] == bytes([START, 1, 0x01, 7, 2, 0])
    assert f[6:8] == b"\x01\x02"
    assert int.from_bytes(f[8:], "big") == crc16(f[1:8])


@given(st.lists(frames, max_size=8), st.integers(1, 17))
@settings(max_examples=150, deadline=None)
def test_any_frames_in_any_chunking_round_trip(items, chunk):
    wire = b"".join(encode(t, s, p) for t, s, p in items)
    dec = Decoder()
    got = []
    for i in range(0, len(wire), chunk):
        got += dec.feed(wire[i:i + chunk])
    assert got == [Frame(int(t), s, p) for t, s, p in items]
    assert not dec.buffer


@given(st.lists(st.tuples(st.integers(0, 255), st.floats(-7.99, 7.99)), max_size=40,
                unique_by=lambda x: x[0]))
def test_levels_round_trip_to_one_level_step(pairs):
    d = dict(pairs)
    back = decode_levels(encode_levels(d))
    assert set(back) == set(d)
    assert all(abs(back[k] - d[k]) <= 0.5 / 4096 for k in d)


@given(st.lists(st.builds(Segment, st.integers(0, 2**32 - 1), st.integers(0, 65535),
                          st.integers(0, 255), st.integers(-32768, 32767).map(from_level)),
                max_size=50), st.integers(0, 3))
def test_schedules_round_trip_exactly(segs, flags):
    assert decode_schedule(encode_schedule(segs, flags)) == (flags, segs)


def test_status_and_nak_round_trip():
    s = Status(0x05, 250, (0.0, 1.0, -1.25, 0.5))
    assert decode_status(encode_status(s)) == s
    assert s.watchdog_tripped and not s.playing
    assert decode_nak(encode_nak(9, ErrorCode.ON_TIME)) == (9, ErrorCode.ON_TIME)


def test_out_of_range_values_are_refused():
    with pytest.raises(ValueError, match="level"):
        to_level(8.0)
    with pytest.raises(ValueError, match="seq"):
        encode(Msg.ACK, 256)
    with pytest.raises(ValueError, match="payload"):
        encode(Msg.ACK, 0, bytes(MAX_PAYLOAD + 1))
    with pytest.raises(ValueError, match="count"):
        decode_levels(b"\x02\x00\x00\x00")


def _decode_all(wire: bytes) -> list[Frame | FrameError]:
    dec = Decoder()
    return dec.feed(wire) + dec.timeout()


@given(frames, frames, st.data())
@settings(max_examples=300, deadline=None)
def test_a_bit_flip_never_yields_a_wrong_frame_and_the_next_frame_survives(a, b, data):
    bad = bytearray(encode(*a))
    i = data.draw(st.integers(0, len(bad) - 1))
    bad[i] ^= 1 << data.draw(st.integers(0, 7))
    good = encode(*b)
    got = [x for x in _decode_all(bytes(bad) + good) if isinstance(x, Frame)]
    assert got == [Frame(int(b[0]), b[1], b[2])]  # the good frame only, never the bad one


def test_a_bad_crc_is_reported_with_its_sequence_number():
    bad = bytearray(encode(Msg.HEARTBEAT, 42))
    bad[-1] ^= 0xFF
    got = Decoder().feed(bytes(bad) + encode(Msg.HEARTBEAT, 43))
    assert got[0] == FrameError(ErrorCode.BAD_CRC, 42, "CRC mismatch")
    assert got[-1] == Frame(Msg.HEARTBEAT, 43)


@given(frames, st.data())
def test_a_truncated_frame_waits_then_times_out_and_the_next_frame_survives(a, data):
    wire = encode(*a)
    cut = data.draw(st.integers(1, len(wire) - 1))
    dec = Decoder()
    assert [x for x in dec.feed(wire[:cut]) if isinstance(x, Frame)] == []
    timed_out = dec.timeout()
    assert not [x for x in timed_out if isinstance(x, Frame)]
    assert dec.feed(encode(Msg.STOP_ALL, 1)) == [Frame(Msg.STOP_ALL, 1)]


@given(st.lists(frames, min_size=1, max_size=5), st.lists(st.binary(max_size=20), min_size=6,
                                                           max_size=6))
@settings(max_examples=150, deadline=None)
def test_garbage_between_frames_is_skipped(items, junk):
    wire = b"".join(j.replace(bytes([START]), b"") + encode(*f) for j, f in zip(junk, items,
                                                                                 strict=False))
    got = [x for x in _decode_all(wire + junk[-1].replace(bytes([START]), b""))
           if isinstance(x, Frame)]
    assert got == [Frame(int(t), s, p) for t, s, p in items]


def test_a_huge_length_field_is_rejected_at_once_and_resynchronised():
    bogus = bytes([START, 1, Msg.HEARTBEAT, 3]) + (MAX_PAYLOAD + 1).to_bytes(2, "little")
    got = Decoder().feed(bogus + encode(Msg.HEARTBEAT, 4))
    assert got[0].code == ErrorCode.BAD_LENGTH
    assert got[-1] == Frame(Msg.HEARTBEAT, 4)


def test_another_version_is_refused_by_code():
    f = bytearray(encode(Msg.HEARTBEAT, 5))
    f[1] = 2
    f[-2:] = crc16(bytes(f[1:-2])).to_bytes(2, "big")
    assert Decoder().feed(bytes(f)) == [FrameError(ErrorCode.BAD_VERSION, 5, "version 2")]
