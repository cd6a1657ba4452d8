"""The serial:// source on a pty at 60 Hz: poll cost per frame and the age of a sample when the game sees it, vs a naive bytewise decoder.

An emulated board (`quickjab bridge emulate`, a separate process, 200 Hz, device ticks locked to
CLOCK_MONOTONIC so a sample's true instant is known) streams to a pty; the game-side poller runs
on the fixed 60 Hz step. Same emulator, same run: first SerialSource, then the peer, a naive
reader that walks every byte in Python, decodes each frame on its own and stamps samples with
their arrival time.
"""

from __future__ import annotations

import argparse
import json
import os
import struct
import subprocess
import sys
import tempfile
import time
from typing import TYPE_CHECKING

import numpy as np

from engine import arguments
from engine.clock import RealClock

if TYPE_CHECKING:
    from firmware_bridge import protocol

TICK_MASK = (1 << 30) - 1


def add_arguments(p: argparse.ArgumentParser) -> None:
    # --seconds 0 was a division by zero; --rate as `bridge emulate --rate` takes it (its emulator
    # refused 0 in a process of its own, which came back as "emulator did not start", a traceback)
    p.add_argument("--seconds", type=arguments.float_range(0.0, 3600.0, lo_open=True), default=5.0, help="seconds per reader (default 5)")
    p.add_argument("--rate", type=arguments.int_range(1, 1000), default=200, help="emulated sample rate in Hz (default 200)")
    p.add_argument("--json", action="store_true", help="print JSON instead of a table")


def true_age_s(now_ns: int, t_us: int) -> float:
    """Age of a sample whose device ticks are CLOCK_MONOTONIC microseconds mod 2**30."""
    now_us = now_ns // 1000
    return ((now_us - t_us) & TICK_MASK) / 1e6


class NaiveReader:
    """The peer: reads what is waiting, then a Python loop over every byte, one frame at a time."""

    def __init__(self, port):
        from firmware_bridge import protocol

        self.protocol = protocol
        self.port = port
        self.buf = bytearray()
        self.hello: protocol.Hello | None = None
        self.frames = 0

    def poll(self, clock) -> list[tuple[float, np.ndarray, int]]:
        protocol = self.protocol
        out = []
        n = self.port.in_waiting
        data = self.port.read(n) if n else b""
        for byte in data:
            if byte:
                self.buf.append(byte)
                continue
            if not self.buf:
                continue
            body = protocol.cobs_decode(bytes(self.buf))
            self.buf.clear()
            frame = protocol.parse_body(body)[0] if body else None
            if frame is None:
                continue
            self.frames += 1
            if frame.msg_type == protocol.HELLO:
                self.hello = protocol.Hello(frame)
            elif frame.msg_type == protocol.SAMPLE and self.hello:
                vals = struct.unpack(f"<{len(frame.payload) // 2}h", frame.payload)
                accel = np.array(vals, dtype=np.float64).reshape(-1, 3) / self.hello.accel_lsb_per_g
                out.append((clock(), accel, frame.t_us))
        return out


def start_emulator(seconds: float, rate: int, link: str) -> subprocess.Popen:
    cmd = [sys.executable, "-m", "tools.cli", "bridge", "emulate", "--quiet", "--seconds", str(seconds),
           "--rate", str(rate), "--link", link]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, text=True)
    line = proc.stdout.readline()
    if not line.startswith("port:"):
        proc.kill()
        raise RuntimeError(f"emulator did not start: {line!r}")
    return proc


def warm_up(polls, seconds: float = 1.2) -> None:
    end = time.perf_counter() + seconds
    while time.perf_counter() < end:
        for poll in polls:
            poll()
        time.sleep(1 / 60)


def summarize(name: str, costs: list[float], ages: list[float], stamp_ages: list[float], frames: list[int]) -> dict:
    a = np.array(ages) if ages else np.zeros(1)
    c = np.array(costs) if costs else np.zeros(1)
    return {
        "reader": name,
        "samples": len(ages),
        "frames_per_poll": float(np.mean(frames)) if frames else 0.0,
        "poll_cost_us_per_frame": {"mean": float(c.mean()), "median": float(np.median(c)), "p99": float(np.percentile(c, 99))},
        "sample_age_ms": {"median": float(np.median(a)), "p99": float(np.percentile(a, 99)), "max": float(a.max())},
        "stamp_age_ms_median": float(np.median(stamp_ages)) if stamp_ages else 0.0,
    }


def run_readers(readers: dict, seconds: float) -> list[dict]:
    """Poll every reader once per 60 Hz step (alternating which goes first), so both see the
    same machine. A reader returns (frames decoded, [(stamp, t_us) per sample], t0_ns, t1_ns)
    where t0..t1 brackets its poll call alone, not the benchmark's bookkeeping."""
    clock = RealClock()
    step = 16_666_667
    deadline = clock.now_ns()
    end = deadline + int(seconds * 1e9)
    acc = {name: ([], [], [], []) for name in readers}
    names = list(readers)
    k = 0
    while deadline < end:
        deadline += step
        clock.wait_until(deadline)
        k += 1
        for name in names[k % 2 :] + names[: k % 2]:
            costs, ages, stamp_ages, frames_per_poll = acc[name]
            frames, samples, t0, t1 = readers[name]()
            if frames:
                costs.append((t1 - t0) / frames / 1000)
                frames_per_poll.append(frames)
            for stamp, t_us in samples:
                ages.append(true_age_s(t1, t_us) * 1000)
                stamp_ages.append((t1 / 1e9 - stamp) * 1000)
    return [summarize(name, *acc[name]) for name in names]


def decode_only_us_per_frame(n: int = 4000, repeats: int = 5) -> tuple[float, float]:
    """Decoder.feed vs the naive bytewise loop on the same bytes in 4-frame chunks (best of)."""
    from firmware_bridge import protocol
    from firmware_bridge.faults import make_frames

    frames = make_frames(n, seed=1, hello_every=n)
    chunks = [b"".join(frames[i : i + 4]) for i in range(0, n, 4)]
    best_ours = best_naive = float("inf")
    for _ in range(repeats):
        dec = protocol.Decoder()
        t0 = time.perf_counter_ns()
        for c in chunks:
            dec.feed(c)
        best_ours = min(best_ours, (time.perf_counter_ns() - t0) / n / 1000)
        buf = bytearray()
        t0 = time.perf_counter_ns()
        for c in chunks:
            for byte in c:
                if byte:
                    buf.append(byte)
                elif buf:
                    body = protocol.cobs_decode(bytes(buf))
                    buf.clear()
                    if body:
                        protocol.parse_body(body)
        best_naive = min(best_naive, (time.perf_counter_ns() - t0) / n / 1000)
    return best_ours, best_naive


def timed_source_poll(src):
    """A reader (see run_readers) for the serial:// source: its decoder is tapped to see the
    t_us of each frame it decodes."""
    from firmware_bridge import protocol

    captured: list[protocol.Frame] = []
    feed = src.decoder.feed

    def tapped(data: bytes) -> list[protocol.Frame]:  # sees the t_us of each frame decoded
        got = feed(data)
        captured[:] = got
        return got

    src.decoder.feed = tapped

    def poll_source():
        captured.clear()
        t0 = time.perf_counter_ns()
        samples = src.poll()
        t1 = time.perf_counter_ns()
        t_us = [f.t_us for f in captured if f.msg_type == protocol.SAMPLE]
        paired = zip(samples, t_us[-len(samples):] if samples else [], strict=True)
        return len(captured), [(s.t, t) for s, t in paired], t0, t1

    return poll_source


def timed_naive_poll(naive: NaiveReader):
    """A reader (see run_readers) for the naive bytewise peer."""
    clock = time.perf_counter

    def poll_naive():
        before = naive.frames
        t0 = time.perf_counter_ns()
        got = naive.poll(clock)
        t1 = time.perf_counter_ns()
        return naive.frames - before, [(stamp, t_us) for stamp, _, t_us in got], t0, t1

    return poll_naive


def measure_both_readers(seconds: float, rate: int) -> tuple[dict, dict, dict]:
    """Both readers on their own pty, each fed by an emulated board: (the serial:// source's
    summary, the peer's summary, the source's counters)."""
    import serial

    from engine.sensors import open_source

    with tempfile.TemporaryDirectory(prefix="qj-bench-serial-") as tmp:
        link_a, link_b = os.path.join(tmp, "a"), os.path.join(tmp, "b")
        emus = [start_emulator(seconds + 4.0, rate, link) for link in (link_a, link_b)]
        try:
            src = open_source(f"serial://{link_a}")
            poll_source = timed_source_poll(src)
            port = serial.Serial(link_b, timeout=0)
            naive = NaiveReader(port)
            poll_naive = timed_naive_poll(naive)
            warm_up([src.poll, lambda: naive.poll(time.perf_counter)])
            ours, peer = run_readers({"serial:// source": poll_source, "peer: naive bytewise": poll_naive}, seconds)
            stats = dict(src.stats)
            src.close()
            port.close()
        finally:
            for emu in emus:
                emu.terminate()
                emu.wait(5)
    return ours, peer, stats


def print_report(args: argparse.Namespace, result: dict) -> None:
    """The benchmark's figures as text."""
    ours, peer = result["readers"]
    ratio = result["peer_median_cost_ratio"]
    dec_ours = result["decode_only_us_per_frame"]["decoder"]
    dec_naive = result["decode_only_us_per_frame"]["naive_bytewise"]
    print(f"two ptys, an emulated board on each at {args.rate} Hz, both readers polled in each 60 Hz step, {args.seconds:.0f} s")
    for r in (ours, peer):
        c, a = r["poll_cost_us_per_frame"], r["sample_age_ms"]
        print(f"{r['reader']:22} poll cost/frame: median {c['median']:6.1f} us, mean {c['mean']:6.1f} us, p99 {c['p99']:7.1f} us | "
              f"sample age when seen: median {a['median']:5.2f} ms, p99 {a['p99']:5.2f} ms, max {a['max']:5.2f} ms | "
              f"{r['samples']} samples, {r['frames_per_poll']:.1f} frames/poll")
    print(f"peer / serial:// poll cost per frame (medians): {ratio:.2f}x")
    print(f"decode only, best of 5 (4-frame chunks): Decoder.feed {dec_ours:.2f} us/frame, naive bytewise {dec_naive:.2f} us/frame "
          f"({dec_naive / dec_ours:.2f}x)")
    print(f"serial:// timestamp lag (now - Sample.t, median): {ours['stamp_age_ms_median']:.2f} ms "
          f"(true age minus the least transport delay seen)")
    print(f"source counters: {result['source_stats']}")


def run(args: argparse.Namespace) -> int:
    ours, peer, stats = measure_both_readers(args.seconds, args.rate)
    dec_ours, dec_naive = decode_only_us_per_frame()
    ratio = peer["poll_cost_us_per_frame"]["median"] / ours["poll_cost_us_per_frame"]["median"]
    result = {"rate_hz": args.rate, "poll_hz": 60, "readers": [ours, peer], "peer_median_cost_ratio": ratio,
              "decode_only_us_per_frame": {"decoder": dec_ours, "naive_bytewise": dec_naive},
              "source_stats": {k: v for k, v in stats.items() if v}}
    if args.json:
        print(json.dumps(result, indent=2))
        return 0
    print_report(args, result)
    return 0
