"""A '?' from the host is answered with a HELLO before the next SAMPLE (PROTOCOL.md, "Host to
device"), by the real Sampler.run loop (`quickjab bridge emulate`, in its own process) on a
real pty.

The emulator's device clock is CLOCK_MONOTONIC in microseconds (HostTicks with no start), shared
by every process, so the test can tell which SAMPLEs were stamped after a request had arrived:
none of those may come before the request's HELLO.

A byte written to a pty becomes readable at the other end only when a kernel worker has moved
it, which on a loaded machine can take milliseconds: the request's arrival is then not known.
A probe pty of the test's own, written right after each request, measures that delay; requests
whose probe took over 0.5 ms are left out and replaced."""

from __future__ import annotations

import os
import random
import select
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


def kernel_delay_us(probe: tuple[int, int]) -> int:
    """How long a byte written to a pty's slave takes to become readable at its master now."""
    master, slave = probe
    start = time.monotonic_ns()
    os.write(slave, b"p")
    select.select([master], [], [], 1.0)
    took = (time.monotonic_ns() - start) // 1000
    os.read(master, 16)
    return took


def read_for(fd: int, dec: protocol.Decoder, frames: list, seconds: float) -> None:
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        try:
            frames += dec.feed(os.read(fd, 4096))
        except BlockingIOError:
            time.sleep(0.0005)


def measure(attempt: int) -> tuple[int, int, int]:
    """One run of 100 requests: (requests measured, late SAMPLEs, requests left out)."""
    emu = subprocess.Popen([sys.executable, "-m", "tools.cli", "bridge", "emulate", "--seconds", "60", "--seed",
                            str(attempt + 1), "--quiet"], cwd=REPO, stdout=subprocess.PIPE, text=True,
                           env={**os.environ, "PYTHONPATH": str(REPO)})
    try:
        port = emu.stdout.readline().split()[1]
        fd = os.open(port, os.O_RDWR | os.O_NOCTTY | os.O_NONBLOCK)
        tty.setraw(fd)
        dec = protocol.Decoder()
        frames: list[protocol.Frame] = []
        rng = random.Random(3 + attempt)
        requests = []  # (before, after) the write: the byte arrived in between
        probe = os.openpty()
        tty.setraw(probe[1])
        unsure = 0
        read_for(fd, dec, frames, 0.2)
        while len(requests) < 100 and unsure < 300:
            # anywhere in the 5 ms tick; requests at least two ticks apart so each has its own HELLO
            read_for(fd, dec, frames, rng.uniform(0.011, 0.02))
            before = now_us()
            os.write(fd, protocol.HELLO_REQUEST)
            done = now_us()
            # this process preempted, or the kernel slow to pass bytes on: arrival not known
            if done - before < 500 and kernel_delay_us(probe) < 500:
                requests.append((before, done))
            else:
                unsure += 1
        read_for(fd, dec, frames, 0.1)
        os.close(fd)
        for end in probe:
            os.close(end)
    finally:
        emu.kill()
        emu.wait(10)
    assert dec.crc_errors == 0 and dec.lost == 0 and dec.cobs_errors == 0, dec.counts()
    assert sum(f.msg_type == protocol.HELLO for f in frames) >= len(requests)  # one per request at least
    late_samples = 0
    for before, done in requests:
        # frames stamped after the request was sent, in wire order, up to the first HELLO: none of
        # them may be a SAMPLE stamped after the byte had certainly arrived
        later = [f for f in frames if after(f.t_us, before)]
        k = next(i for i, f in enumerate(later) if f.msg_type == protocol.HELLO)
        late_samples += sum(after(f.t_us, done) for f in later[:k])
    return len(requests), late_samples, unsure


def test_hundred_requests_none_answered_after_a_later_sample():
    # The probe cannot see every kernel hiccup (one in a few hundred requests on a machine with
    # a load average of 5 had its byte readable 15 ms late): a run with a late SAMPLE is run
    # again, up to three times. The loop this replaced failed every run (83 to 99 of 100 late).
    runs = []
    for attempt in range(3):
        n, late, unsure = measure(attempt)
        runs.append(late)
        print(f"run {attempt + 1}: {n} requests, {late} SAMPLEs between a request's arrival and its HELLO "
              f"({unsure} more left out: arrival not known to 0.5 ms)")
        assert n == 100
        if late == 0:
            break
    assert runs[-1] == 0, runs
