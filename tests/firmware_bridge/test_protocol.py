"""The wire protocol: COBS, frame layout, the streaming decoder's counters, and the
properties the issue asks for (hypothesis)."""

from __future__ import annotations

import random
import struct

from hypothesis import given, settings
from hypothesis import strategies as st

from firmware_bridge import faults, protocol

FRAMES = faults.make_frames(60, seed=3, hello_every=20)
SENT = faults.sent_keys(FRAMES)
STREAM = b"".join(FRAMES)


def cobs_reference(data: bytes) -> bytes:
    """The byte-at-a-time encoder of Cheshire & Baker (as in the Wikipedia C code)."""
    out = bytearray([0])
    code_i, code = 0, 1
    for i, byte in enumerate(data):
        if byte:
            out.append(byte)
            code += 1
        if not byte or code == 0xFF:
            out[code_i] = code
            code = 1
            code_i = len(out)
            if not byte or i < len(data) - 1:
                out.append(0)
    if code_i < len(out):  # C writes this code past the returned length after a full block
        out[code_i] = code
    return bytes(out)


@given(st.binary(max_size=700))
def test_cobs_matches_the_reference_and_round_trips(data):
    enc = protocol.cobs_encode(data)
    assert enc == cobs_reference(data)
    assert 0 not in enc
    assert protocol.cobs_decode(enc) == data


def test_cobs_long_runs_without_zero():
    for n in (253, 254, 255, 508, 509):
        data = bytes(range(1, 256)) * 3
        data = data[:n]
        assert protocol.cobs_encode(data) == cobs_reference(data)
        assert protocol.cobs_decode(protocol.cobs_encode(data)) == data


def test_body_layout_is_the_spec():
    fr = protocol.encode_sample(0x1234, 0x89ABCDEF, (1, -2, 4096), None, overrun=True)
    assert fr[0] == 0 and fr[-1] == 0 and 0 not in fr[1:-1]
    body = protocol.cobs_decode(fr[1:-1])
    assert body[0] == 0x11  # version 1, SAMPLE
    assert struct.unpack("<HIB", body[1:8]) == (0x1234, 0x89ABCDEF, 0x09)  # sensor A + overrun
    assert struct.unpack("<3h", body[8:14]) == (1, -2, 4096)
    import binascii

    assert struct.unpack("<I", body[14:])[0] == binascii.crc32(body[:14] + bytes([0x3C]))


def test_crc_extra_makes_a_type_mismatch_fail():
    fr = protocol.encode_text(5, 6, "hi")
    body = bytearray(protocol.cobs_decode(fr[1:-1]))
    body[0] = 0x11  # claim SAMPLE with TEXT's CRC
    dec = protocol.Decoder()
    assert dec.feed(b"\x00" + protocol.cobs_encode(bytes(body)) + b"\x00") == []
    assert dec.crc_errors == 1


def test_unknown_flag_bits_and_wrong_lengths_are_malformed():
    def raw(msg_type, flags, payload):
        body = struct.pack("<BHIB", 0x10 | msg_type, 1, 2, flags) + payload
        body += struct.pack("<I", protocol._crc(msg_type, body))
        return b"\x00" + protocol.cobs_encode(body) + b"\x00"

    dec = protocol.Decoder()
    assert dec.feed(raw(protocol.SAMPLE, 0x11, b"\x00" * 6)) == []  # unknown bit 4
    assert dec.feed(raw(protocol.SAMPLE, 0x03, b"\x00" * 6)) == []  # two sensors, one's data
    assert dec.feed(raw(protocol.HELLO, 0x03, b"\x00" * 13)) == []
    assert dec.feed(raw(protocol.TEXT, 0x0F, b"hi")) == []  # TEXT frames carry flags 0
    assert dec.malformed == 4
    assert len(dec.feed(raw(protocol.SAMPLE, 0x03, b"\x00" * 12))) == 1
    assert len(protocol.Decoder().feed(raw(protocol.TEXT, 0, b"hi"))) == 1


def test_values_hello_and_text_decode():
    dec = protocol.Decoder()
    got = dec.feed(protocol.encode_hello(0, 1, 0xCAFEBABE, 200, 4096, 65500, 30, 1, 3)
                   + protocol.encode_sample(1, 2, (1, 2, 3), (4, 5, 6), (7, 8, 9), (10, 11, 12))
                   + protocol.encode_text(2, 3, "héllo"))
    hello = protocol.Hello(got[0])
    assert (hello.boot_id, hello.rate_hz, hello.accel_lsb_per_g, hello.ts_bits, hello.sensors) == (0xCAFEBABE, 200, 4096, 30, 2)
    assert got[1].values() == (1, 2, 3, 7, 8, 9, 4, 5, 6, 10, 11, 12)
    assert got[2].payload.decode() == "héllo"
    assert dec.frames_ok == 3 and dec.lost == 0


def test_lost_reboots_and_oversize_are_counted():
    dec = protocol.Decoder()
    dec.feed(protocol.encode_hello(0, 0, 1, 200, 4096, 0, 30, 1, 1))
    dec.feed(protocol.encode_sample(1, 0, (0, 0, 1)))
    dec.feed(protocol.encode_sample(5, 0, (0, 0, 1)))  # 2, 3, 4 lost
    assert dec.lost == 3
    dec.feed(protocol.encode_hello(0, 0, 2, 200, 4096, 0, 30, 1, 1))  # new boot: seq restarts
    assert dec.reboots == 1 and dec.lost == 3 and dec.seq_jumps == 0
    dec.feed(b"\x01" * 1000 + protocol.encode_sample(1, 0, (0, 0, 1)))
    assert dec.oversize == 1 and dec.frames_ok == 5


@settings(max_examples=200)
@given(st.binary(max_size=3000), st.lists(st.integers(1, 64), max_size=50))
def test_decoder_never_raises(data, cuts):
    dec = protocol.Decoder()
    i = 0
    for c in cuts + [len(data)]:
        dec.feed(data[i : i + c])
        i += c
    dec.feed(bytearray(b"\x00\x05\x00"))
    dec.feed(memoryview(b"\x03\xff\x00"))
    assert sum(dec.counts()[k] for k in ("frames_ok", "crc_errors", "cobs_errors", "runts", "unknown_type", "malformed")) >= 0


@given(st.lists(st.integers(1, 40), min_size=1, max_size=200))
def test_any_chunking_gives_the_same_frames(sizes):
    dec = protocol.Decoder()
    got, i, k = [], 0, 0
    while i < len(STREAM):
        n = sizes[k % len(sizes)]
        got += dec.feed(STREAM[i : i + n])
        i, k = i + n, k + 1
    assert [f.key() for f in got] == SENT


@given(st.lists(st.tuples(st.integers(0, len(FRAMES)), st.binary(min_size=1, max_size=80)), max_size=20))
def test_garbage_between_frames_loses_none(inserts):
    parts = list(FRAMES)
    for pos, junk in sorted(inserts, reverse=True):
        parts.insert(pos, junk)
    got = protocol.Decoder().feed(b"".join(parts))
    assert [f.key() for f in got] == SENT


@given(st.integers(0, len(STREAM) - 1), st.integers(0, 255))
def test_one_corrupted_byte_costs_at_most_two_frames(pos, value):
    stream = bytearray(STREAM)
    if stream[pos] == value:
        value ^= 0xFF
    stream[pos] = value
    dec = protocol.Decoder()
    got = [f.key() for f in dec.feed(bytes(stream))]
    assert set(got) <= set(SENT)  # nothing false
    assert len(got) >= len(SENT) - 2


def test_fault_experiments_small():
    assert faults.random_bytes(200_000, seed=1).false_accepts == 0
    assert faults.corrupted_frames(5000, seed=1).false_accepts == 0
    d = faults.dropped_frames(3000, 100, seed=1)
    assert d.lost == 100 and d.decoder_lost == 100 and d.false_accepts == 0
    g = faults.garbage_bursts(3000, 100, between=True, seed=1)
    assert g.lost == 0 and g.false_accepts == 0
    for o in (faults.bit_flips(3000, 200, seed=1), faults.dropped_bytes(3000, 200, seed=1),
              faults.garbage_bursts(3000, 100, between=False, seed=1)):
        assert o.false_accepts == 0 and 0 < o.lost <= 2 * o.events


def test_resync_forgets_partial_frame():
    dec = protocol.Decoder()
    fr = FRAMES[1]
    dec.feed(fr[:-5])
    dec.resync()
    assert dec.feed(fr[-5:]) == []
    rng = random.Random(0)
    assert len(dec.feed(rng.choice(FRAMES))) == 1


# -- a host that stopped reading for 32768 frames or more (PROTOCOL.md, Receiver rules) ------

def _wrapped_boot(n: int = 70_000) -> tuple[protocol.Decoder, int]:
    """A decoder that took a boot's HELLO and `n` samples at 200 Hz (every 16-bit seq delivered
    once n >= 65536), and the boot's next seq."""
    dec = protocol.Decoder()
    dec.feed(protocol.encode_hello(0, 0, 7, 200, 4096, 65500, 30, 1, 3))
    dec.feed(b"".join(protocol.encode_sample(s, 5000 * s, (0, 0, 4096), None) for s in range(1, n + 1)))
    assert dec.frames_ok == n + 1
    return dec, n + 1


def test_a_stall_past_half_the_counter_resyncs_at_the_boots_next_hello():
    # Ctrl-Z, a suspended laptop: the board counts on (dropping with OVERRUN) for 40000 frames.
    # Every seq was delivered once: its next frames read as behind and already seen, and every
    # frame, this boot's HELLOs too, was dropped as a replay for good.
    dec, seq = _wrapped_boot()
    seq += 40_000
    after = b"".join(protocol.encode_sample(seq + i, 5000 * (seq + i), (0, 0, 4096), None) for i in range(10))
    assert dec.feed(after) == []  # no HELLO yet: cannot be told from bytes played back
    assert (dec.replays, dec.replays_ahead, dec.replay_run) == (10, 10, 10)  # said apart: later in time
    seq += 10
    hello = protocol.encode_hello(seq, 5000 * seq, 7, 200, 4096, 65500, 30, 1, 3)
    more = b"".join(protocol.encode_sample(seq + i, 5000 * (seq + i), (0, 0, 4096), None) for i in range(1, 101))
    assert len(dec.feed(hello + more)) == 101
    assert dec.resyncs == 1 and dec.seq_jumps == 0 and dec.reboots == 0 and dec.replay_run == 0
    assert dec.lost == 40_010  # at least: seq counts modulo 65536
    # the replay check goes on: bytes from before the stall played back are still dropped
    old = (seq + 100 - 1000) & protocol.SEQ_MASK  # 1000 behind: delivered on the first pass
    assert dec.feed(protocol.encode_sample(old, 5000 * old, (0, 0, 4096), None)) == []
    assert dec.replays == 11 and dec.replays_ahead == 10 and dec.resyncs == 1


def test_a_same_boot_hello_played_back_does_not_resync():
    # its time is at or before what was delivered: old bytes, dropped as before
    dec, seq = _wrapped_boot()
    old = protocol.encode_hello(seq - 1000, 5000 * (seq - 1000), 7, 200, 4096, 65500, 30, 1, 3)
    assert dec.feed(old) == []
    assert (dec.replays, dec.replays_ahead, dec.resyncs) == (1, 0, 0)
    nxt = protocol.encode_sample(seq, 5000 * seq, (0, 0, 4096), None)
    assert len(dec.feed(nxt)) == 1 and dec.lost == 0


def test_a_stall_before_the_counter_wrapped_is_a_resync_not_a_reboot():
    # 40000 frames in: a stall of 40000 makes seq 80001 & 0xFFFF = 14465, behind and never seen.
    # Taken before as a reboot whose HELLO was lost (a seq_jump) though the HELLO says the same
    # boot; a later real reboot's HELLO then went uncounted.
    dec, seq = _wrapped_boot(40_000)
    seq += 40_000
    hello = protocol.encode_hello(seq & protocol.SEQ_MASK, 5000 * seq, 7, 200, 4096, 65500, 30, 1, 3)
    assert len(dec.feed(hello)) == 1
    assert (dec.resyncs, dec.seq_jumps, dec.lost) == (1, 0, 40_000)
    assert len(dec.feed(protocol.encode_hello(0, 0, 8, 200, 4096, 65500, 30, 1, 3))) == 1
    assert dec.reboots == 1


def test_bytes_from_before_the_stall_played_back_after_a_resync_are_replays():
    # After the resync the last pass's seq values read as ahead of the new position: their time,
    # not later than the last delivered frame's, tells them from new frames.
    dec, seq = _wrapped_boot()
    old = b"".join(protocol.encode_sample(s, 5000 * s, (0, 0, 4096), None) for s in range(seq - 100, seq))
    seq += 40_000
    hello = protocol.encode_hello(seq, 5000 * seq, 7, 200, 4096, 65500, 30, 1, 3)
    assert len(dec.feed(hello)) == 1 and dec.resyncs == 1
    assert dec.feed(old) == [] and dec.replays == 100
    live = b"".join(protocol.encode_sample(seq + i, 5000 * (seq + i), (0, 0, 4096), None) for i in range(1, 51))
    assert len(dec.feed(live)) == 50 and dec.lost == 40_000  # the live frames go on where they were


def test_a_clock_too_short_to_order_a_seq_cycle_never_resyncs():
    # 16-bit t_us at 200 Hz wraps every 65 ms: a HELLO played back from seconds ago reads as
    # "later" about half the time, so t_us cannot tell a stall from old bytes: no resync.
    dec = protocol.Decoder()
    dec.feed(protocol.encode_hello(0, 0, 7, 200, 4096, 65500, 16, 1, 3))
    dec.feed(b"".join(protocol.encode_sample(s, (5000 * s) & 0xFFFF, (0, 0, 4096), None) for s in range(1, 70_001)))
    for back in range(100, 3000, 37):
        s = 70_000 - back
        assert dec.feed(protocol.encode_hello(s, (5000 * s) & 0xFFFF, 7, 200, 4096, 65500, 16, 1, 3)) == []
    assert dec.resyncs == 0


def test_a_same_boot_hello_played_back_from_before_the_host_opened_the_port_is_a_replay():
    # The host opened the port mid-boot (first frame seq 5000); old bytes then bring this boot's
    # HELLO of seq 4000, ten seconds earlier: never delivered, so it was taken for a reboot whose
    # HELLO was lost (a seq_jump, `lost` 61000-odd) and its fields applied. PROTOCOL.md: a
    # same-boot HELLO at or before the last delivered time is a replay.
    dec = protocol.Decoder()
    dec.feed(protocol.encode_hello(5000, 5000 * 5000, 7, 200, 4096, 65500, 30, 1, 3))
    dec.feed(b"".join(protocol.encode_sample(s, 5000 * s, (0, 0, 4096), None) for s in range(5001, 5101)))
    old = protocol.encode_hello(4000, 5000 * 4000, 7, 200, 4096, 65500, 30, 1, 3)
    assert dec.feed(old) == []
    assert (dec.replays, dec.seq_jumps, dec.lost, dec.reboots) == (1, 0, 0, 0)
    nxt = b"".join(protocol.encode_sample(s, 5000 * s, (0, 0, 4096), None) for s in range(5101, 5111))
    assert len(dec.feed(nxt)) == 10 and dec.lost == 0 and dec.seq_jumps == 0


def test_a_same_boot_hello_that_reads_ahead_in_seq_but_earlier_in_time_is_a_replay():
    # a HELLO from the last pass of the 16-bit seq, played back: ahead by its seq, earlier by its
    # time. Taken, its fields were applied, 499 counted lost, and the live frames after it read as
    # replays until the board's next HELLO resynced (65,000 more "lost")
    dec = protocol.Decoder()
    dec.feed(protocol.encode_hello(0, 0, 7, 200, 4096, 65500, 30, 1, 3))
    dec.feed(b"".join(protocol.encode_sample(s, 5000 * s, (0, 0, 4096), None) for s in range(1, 1001)))
    old = protocol.encode_hello(1500, 5000 * 500, 7, 100, 2048, 65500, 30, 1, 3)  # other fields, too
    assert dec.feed(old) == []
    assert (dec.replays, dec.lost, dec.hello.rate_hz) == (1, 0, 200)
    live = b"".join(protocol.encode_sample(s, 5000 * s, (0, 0, 4096), None) for s in range(1001, 1011))
    assert len(dec.feed(live)) == 10 and dec.lost == 0 and dec.replays == 1
