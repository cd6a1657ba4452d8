"""Fault-injection experiments on the wire protocol: what the decoder accepts from noise and
corrupted frames, and how many good frames each kind of damage costs. Pure functions over
byte streams (no pty), so `quickjab bridge faults` and the tests share them.

Every experiment compares the decoder's output against the frames actually sent: a *false
accept* is a decoded frame that was not sent, *lost* is a sent frame not decoded.
"""

from __future__ import annotations

import random
from dataclasses import asdict, dataclass
from itertools import accumulate

from firmware_bridge import protocol


def make_frames(n: int, seed: int = 0, hello_every: int = 200) -> list[bytes]:
    """n wire frames as a device sends them: a HELLO every `hello_every`, SAMPLEs of random
    values (two sensors; every third with gyro), a TEXT now and then."""
    rng = random.Random(seed)
    frames = []
    boot = rng.getrandbits(32)
    for seq in range(n):
        t = (seq * 5000) & 0x3FFFFFFF
        if seq % hello_every == 0:
            frames.append(protocol.encode_hello(seq, t, boot, 200, 4096, 65500, 30, protocol.IMU_MPU6050,
                                                protocol.FLAGS_SENSORS))
        elif seq % 997 == 1:
            frames.append(protocol.encode_text(seq, t, f"note {seq}"))
        else:
            acc = [tuple(rng.randint(-32768, 32767) for _ in range(3)) for _ in range(2)]
            gyro = [tuple(rng.randint(-32768, 32767) for _ in range(3)) for _ in range(2)] if seq % 3 == 0 else [None, None]
            frames.append(protocol.encode_sample(seq, t, acc[0], acc[1], gyro[0], gyro[1]))
    return frames


def decode_all(stream: bytes, seed: int = 0, max_chunk: int = 97) -> tuple[list[protocol.Frame], protocol.Decoder]:
    """Feed `stream` in random chunk sizes, as reads from a port arrive."""
    rng = random.Random(seed)
    dec = protocol.Decoder()
    out: list[protocol.Frame] = []
    i = 0
    while i < len(stream):
        k = rng.randint(1, max_chunk)
        out += dec.feed(stream[i : i + k])
        i += k
    return out, dec


def sent_keys(frames: list[bytes]) -> list[tuple]:
    """The key of each wire frame, decoded on its own."""
    out = []
    for fr in frames:
        got = protocol.Decoder().feed(fr)
        out.append(got[0].key())
    return out


@dataclass
class Outcome:
    name: str
    events: int  # faults injected (bursts, flips, dropped bytes, dropped frames, ...)
    frames_sent: int
    frames_decoded: int
    false_accepts: int
    lost: int  # sent frames missing from the output (ground truth)
    decoder_lost: int  # what the decoder counted by sequence number

    @property
    def lost_per_event(self) -> float:
        return self.lost / self.events if self.events else 0.0

    def as_dict(self) -> dict:
        d = asdict(self)
        d["lost_per_event"] = self.lost_per_event
        return d


def _outcome(name: str, events: int, sent: list[tuple], got: list[protocol.Frame], dec: protocol.Decoder) -> Outcome:
    sent_set = set(sent)
    got_keys = [f.key() for f in got]
    false = sum(1 for k in got_keys if k not in sent_set)
    lost = len(sent_set - set(got_keys))
    return Outcome(name, events, len(sent), len(got), false, lost, dec.lost)


def random_bytes(nbytes: int, seed: int = 0) -> Outcome:
    """Pure noise: every frame decoded from it is a false accept."""
    rng = random.Random(seed)
    got, dec = decode_all(rng.randbytes(nbytes), seed, max_chunk=4096)
    return Outcome("random bytes", nbytes, 0, len(got), len(got), 0, dec.lost)


def corrupt_once(enc: bytes, rng: random.Random) -> bytes:
    """Damage the COBS content of one frame (between its delimiters) in one of several ways;
    the result always decodes differently from the input."""
    while True:
        b = bytearray(enc)
        kind = rng.randrange(7)
        i = rng.randrange(len(b))
        if kind == 0:  # one bit
            b[i] ^= 1 << rng.randrange(8)
        elif kind == 1:  # several bits
            for _ in range(rng.randint(2, 8)):
                j = rng.randrange(len(b))
                b[j] ^= 1 << rng.randrange(8)
        elif kind == 2:  # a byte replaced
            b[i] = rng.randrange(256)
        elif kind == 3:  # a burst replaced
            k = rng.randint(2, 16)
            b[i : i + k] = rng.randbytes(len(b[i : i + k]))
        elif kind == 4:  # truncated
            del b[i:]
        elif kind == 5:  # a byte inserted
            b.insert(i, rng.randrange(256))
        else:  # a byte dropped
            del b[i]
        # an extra 0x00 at either edge is only an empty frame, not damage: roll again
        if bytes(b).strip(b"\x00") != enc and b.strip(b"\x00"):
            return bytes(b)


def corrupted_frames(n: int, seed: int = 0) -> Outcome:
    """n frames each damaged once: every frame decoded is a false accept."""
    rng = random.Random(seed)
    frames = make_frames(n, seed)
    bad = [b"\x00" + corrupt_once(fr[1:-1], rng) + b"\x00" for fr in frames]
    got, dec = decode_all(b"".join(bad), seed, max_chunk=512)
    # every frame sent was damaged, so anything decoded is a false accept
    return Outcome("corrupted frames", n, n, len(got), len(got), n - len(got), dec.lost)


def dropped_frames(n: int, k: int, seed: int = 0) -> Outcome:
    """Drop k whole frames (never the first or last, which no receiver can know of)."""
    rng = random.Random(seed)
    frames = make_frames(n, seed)
    drop = set(rng.sample(range(1, n - 1), k))
    kept = [fr for i, fr in enumerate(frames) if i not in drop]
    got, dec = decode_all(b"".join(kept), seed)
    return _outcome("dropped frames", k, sent_keys(frames), got, dec)


def garbage_bursts(n: int, bursts: int, max_len: int = 64, between: bool = True, seed: int = 0) -> Outcome:
    """Random bursts (zeros included) between frames, or at any byte offset when not `between`."""
    rng = random.Random(seed)
    frames = make_frames(n, seed)
    stream = bytearray(b"".join(frames))
    if between:
        where = sorted(rng.sample(_frame_starts(frames), bursts), reverse=True)
    else:
        where = sorted(rng.sample(range(len(stream)), bursts), reverse=True)
    for pos in where:
        stream[pos:pos] = rng.randbytes(rng.randint(1, max_len))
    got, dec = decode_all(bytes(stream), seed)
    name = "garbage burst between frames" if between else "garbage burst anywhere"
    return _outcome(name, bursts, sent_keys(frames), got, dec)


def _frame_starts(frames: list[bytes]) -> list[int]:
    """The byte offset of each frame in their concatenation, and the stream's end."""
    return [0, *accumulate(len(fr) for fr in frames)]


def _spaced_positions(frames: list[bytes], events: int, rng: random.Random) -> list[int]:
    """One random byte offset inside each of `events` distinct frames (delimiters included),
    frames at least 3 apart so each event's cost can be told apart."""
    starts = _frame_starts(frames)
    picks = sorted(rng.sample(range(0, len(frames) // 3), events))
    return [starts[3 * p] + rng.randrange(len(frames[3 * p])) for p in picks]


def bit_flips(n: int, flips: int, seed: int = 0) -> Outcome:
    rng = random.Random(seed)
    frames = make_frames(n, seed)
    stream = bytearray(b"".join(frames))
    for pos in _spaced_positions(frames, flips, rng):
        stream[pos] ^= 1 << rng.randrange(8)
    got, dec = decode_all(bytes(stream), seed)
    return _outcome("bit flip", flips, sent_keys(frames), got, dec)


def dropped_bytes(n: int, drops: int, seed: int = 0) -> Outcome:
    rng = random.Random(seed)
    frames = make_frames(n, seed)
    stream = bytearray(b"".join(frames))
    for pos in sorted(_spaced_positions(frames, drops, rng), reverse=True):
        del stream[pos]
    got, dec = decode_all(bytes(stream), seed)
    return _outcome("dropped byte", drops, sent_keys(frames), got, dec)


def run_all(random_mb: float = 1.0, corrupted: int = 100_000, frames: int = 20_000, events: int = 1000,
            seed: int = 0) -> list[Outcome]:
    return [
        random_bytes(int(random_mb * 1024 * 1024), seed),
        corrupted_frames(corrupted, seed),
        dropped_frames(frames, events, seed),
        garbage_bursts(frames, events, between=True, seed=seed),
        garbage_bursts(frames, events, between=False, seed=seed),
        bit_flips(frames, min(events, frames // 3), seed),
        dropped_bytes(frames, min(events, frames // 3), seed),
    ]
