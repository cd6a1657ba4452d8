"""The serial source after the host stopped reading for 32768 frames or more (Ctrl-Z, a
suspended laptop) of a boot that had sent 65536 or more: the board's seq reads as behind and
already delivered (PROTOCOL.md, Receiver rules). Through a real pty pair."""

from __future__ import annotations

import os
import time
import tty

from engine.sensors import SourceState, open_source
from firmware_bridge import protocol
from tools.record import link_counts


def hello(seq: int, boot: int = 7) -> bytes:
    return protocol.encode_hello(seq, 5000 * seq, boot, 200, 4096, 65500, 30, protocol.IMU_MPU6050, 3)


def samples(first: int, n: int) -> list[bytes]:
    return [protocol.encode_sample(s, 5000 * s, (0, 0, 4096), (4096, 0, 0)) for s in range(first, first + n)]


def feed(master: int, src, frames: list[bytes]) -> int:
    """Write `frames` a hundred at a time, polling after each write; the samples polled."""
    got = 0
    for i in range(0, len(frames), 100):
        os.write(master, b"".join(frames[i : i + 100]))
        got += len(src.poll())
    for _ in range(20):
        time.sleep(0.005)
        got += len(src.poll())
    return got


def asked(master: int) -> bytes:
    os.set_blocking(master, False)
    try:
        return os.read(master, 100)
    except BlockingIOError:
        return b""


def test_a_host_stall_past_half_the_counter_recovers_at_the_boards_hello():
    master, slave = os.openpty()
    tty.setraw(slave)
    src = open_source(f"serial://{os.ttyname(slave)}")
    try:
        assert feed(master, src, [hello(0)] + samples(1, 70_000)) == 70_000  # every seq delivered once
        time.sleep(0.3)  # past the 0.25 s between two requests
        asked(master)  # the request sent at open
        seq = 70_001 + 40_000  # the host stopped; the board counted on, dropping (OVERRUN)
        assert feed(master, src, samples(seq, 300)) == 0  # no HELLO yet: not told from a replay
        assert asked(master) == protocol.HELLO_REQUEST  # ... so the host asks for one
        assert src.missing().startswith("every frame dropped as a replay")  # and says it
        seq += 300
        got = feed(master, src, [hello(seq)] + samples(seq + 1, 200))  # its HELLO, this boot's
        assert got == 200 and src.state is SourceState.CONNECTED and src.missing() == ""
        stats = src.stats
        assert stats["resyncs"] == 1 and stats["replays"] == stats["replays_ahead"] == 300
        assert "replays dropped 300 (300 later in time than the frames before them; resynced at the board's HELLO 1 time" \
            in link_counts(stats)
        assert "replays dropped 0 (resynced at the board's HELLO 1 time(s))" in link_counts({**stats, "replays_ahead": 0,
                                                                                           "replays": 0})
    finally:
        src.close()
        os.close(master)
        os.close(slave)
