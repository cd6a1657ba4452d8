"""A '?' from the host is answered with a HELLO before the next SAMPLE (PROTOCOL.md, "Host to
device"), by the real Sampler.run loop (`quickjab bridge emulate`, in its own process) on a
real pty.

The emulator's device clock is CLOCK_MONOTONIC in microseconds (HostTicks with no start), shared
by every process, so the test can tell which SAMPLEs were stamped after a request had arrived:
none of those may come before the request's HELLO."""

from __future__ import annotations

import os
import random
import subprocess
import sys
import time
import tty
from pathlib import Path

from firmware_bridge import protocol
from firmware_bridge.emulator import TS_BITS

REPO = Path(__file__).resolve().parents[2]

MASK = (1 << TS_BITS) - 1


def now_us() -> int:
    return (time.monotonic_ns() // 1000) & MASK


def after(t: int, ref: int) -> bool:
    """Device time t is at or after ref (30-bit wrapping)."""
    return ((t - ref) & MASK) < (1 << (TS_BITS - 1))


def read_for(fd: int, dec: protocol.Decoder, frames: list, seconds: float) -> None:
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        try:
            frames += dec.feed(os.read(fd, 4096))
        except BlockingIOError:
            time.sleep(0.0005)


def test_hundred_requests_none_answered_after_a_later_sample():
    emu = subprocess.Popen([sys.executable, "-m", "game.cli", "bridge", "emulate", "--seconds", "60", "--seed", "1",
                            "--quiet"], cwd=REPO, stdout=subprocess.PIPE, text=True,
                           env={**os.environ, "PYTHONPATH": str(REPO)})
    try:
        port = emu.stdout.readline().split()[1]
        fd = os.open(port, os.O_RDWR | os.O_NOCTTY | os.O_NONBLOCK)
        tty.setraw(fd)
        dec = protocol.Decoder()
        frames: list[protocol.Frame] = []
        rng = random.Random(3)
        requests = []  # (before, after) the write: the byte arrived in between
        read_for(fd, dec, frames, 0.2)
        while len(requests) < 100:
            # anywhere in the 5 ms tick; requests at least two ticks apart so each has its own HELLO
            read_for(fd, dec, frames, rng.uniform(0.011, 0.02))
            before = now_us()
            os.write(fd, protocol.HELLO_REQUEST)
            done = now_us()
            if done - before < 500:  # else this process was preempted: the arrival is not known well
                requests.append((before, done))
        read_for(fd, dec, frames, 0.1)
        os.close(fd)
    finally:
        emu.kill()
        emu.wait(10)
    assert dec.crc_errors == 0 and dec.lost == 0 and dec.cobs_errors == 0, dec.counts()
    late_samples = 0
    for before, done in requests:
        # frames stamped after the request was sent, in wire order, up to the first HELLO: none of
        # them may be a SAMPLE stamped after the byte had certainly arrived
        later = [f for f in frames if after(f.t_us, before)]
        k = next(i for i, f in enumerate(later) if f.msg_type == protocol.HELLO)
        late_samples += sum(after(f.t_us, done) for f in later[:k])
    print(f"{len(requests)} requests, {late_samples} SAMPLEs between a request's arrival and its HELLO")
    assert late_samples == 0
    hellos = sum(f.msg_type == protocol.HELLO for f in frames)
    assert hellos >= 100  # one per request (the periodic ones come on top)
