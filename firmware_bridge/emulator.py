"""A host-side device: the firmware's own sampling loop (firmware/sampler.py) against a
simulated IMU, writing to a pseudo-terminal, so `serial:///dev/pts/N` behaves like a board.

It can inject what real links do: garbage bursts, bit flips, dropped bytes, device stalls,
reboots, and unplug/replug (the pty vanishes and a new one appears; `link` is a symlink that
points at the current one, so a host can keep one path across replugs, and is gone while the
board is unplugged).
"""

from __future__ import annotations

import fcntl
import os
import random
import struct
import termios
import threading
import time
import tty
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np

from firmware_bridge import protocol
from firmware_bridge.firmware.sampler import Sampler

TS_BITS = 30  # as MicroPython's ticks_us on rp2 and esp32


class HostTicks:
    """MicroPython's ticks_us/ticks_add/ticks_diff/sleep_us on the host. With `start_us`
    None the ticks are CLOCK_MONOTONIC microseconds (shared by every process, so a benchmark
    can tell a sample's true age); otherwise they start at `start_us` (e.g. just before the
    wrap, to exercise the host's unwrapping)."""

    def __init__(self, bits: int = TS_BITS, start_us: int | None = None):
        self.mask = (1 << bits) - 1
        self.half = 1 << (bits - 1)
        now = time.monotonic_ns() // 1000
        self.offset = 0 if start_us is None else start_us - now

    def ticks_us(self) -> int:
        return (time.monotonic_ns() // 1000 + self.offset) & self.mask

    def ticks_add(self, t: int, delta: int) -> int:
        return (t + delta) & self.mask

    def ticks_diff(self, a: int, b: int) -> int:
        return ((a - b + self.half) & self.mask) - self.half

    def sleep_us(self, us: int) -> None:
        time.sleep(us / 1e6)


Signal = Callable[[float], np.ndarray]  # seconds -> (sensors, 3) accel in g


def synthetic_motion(sensors: int = 2, seed: int = 0) -> Signal:
    """Gravity plus a punch-like pulse (3 g, ~150 ms) every 1.5 s, alternating hands."""
    rng = np.random.default_rng(seed)
    tilt = rng.normal(0, 0.05, (sensors, 3))

    def signal(t: float) -> np.ndarray:
        a = np.zeros((sensors, 3))
        a[:, 2] = 1.0
        a += tilt
        k, phase = divmod(t, 1.5)
        pulse = 3.0 * np.exp(-(((phase - 0.3) / 0.05) ** 2)) - 1.0 * np.exp(-(((phase - 0.45) / 0.06) ** 2))
        a[int(k) % sensors, 0] += pulse
        return a

    return signal


class RecordingLike(Protocol):
    t: np.ndarray  # (n,) seconds, increasing
    accel: np.ndarray  # (n, sensors, 3) in g
    sensors: int


def recording_motion(path: str | os.PathLike, read: Callable[[str | os.PathLike], RecordingLike]) -> tuple[Signal, int]:
    """A recording played in a loop, interpolated at any instant. `read` reads the file (the
    host passes engine.recording.read_recording): the bridge never imports the engine."""
    rec = read(path)
    t = rec.t - rec.t[0]
    period = float(np.median(np.diff(t))) if len(t) > 1 else 1 / 60
    length = float(t[-1]) + period
    flat = rec.accel.reshape(len(t), -1)

    def signal(s: float) -> np.ndarray:
        x = s % length
        return np.array([np.interp(x, t, flat[:, d]) for d in range(flat.shape[1])]).reshape(-1, 3)

    return signal, rec.sensors


class SimIMU:
    """The drivers' interface (read() -> raw int16 accel + gyro) over a motion signal."""

    kind = protocol.IMU_SIMULATED
    accel_lsb_per_g = 4096
    gyro_mlsb_per_dps = 65500

    def __init__(self, signal: Signal, index: int, elapsed: Callable[[], float], noise_g: float = 0.002,
                 seed: int = 0):
        self.signal, self.index, self.elapsed = signal, index, elapsed
        self.noise = noise_g
        self.rng = random.Random(seed + index)

    def read(self) -> tuple[int, ...]:
        a = self.signal(self.elapsed())[self.index]
        g = self.accel_lsb_per_g
        n = self.noise
        return tuple(round((float(v) + self.rng.gauss(0, n)) * g) for v in a) + (0, 0, 0)


class PtyPort:
    """The device end of a pty pair. Writes never block: a full buffer is a short write."""

    def __init__(self, link: str | None = None):
        self.link = link
        self.master = self.slave = -1
        self.name = ""
        self.plug()

    def plug(self) -> str:
        self.master, self.slave = os.openpty()
        # raw at once: with the default line discipline the slave would echo our bytes back
        # into the master and translate them before any host opened the port
        tty.setraw(self.slave)
        os.set_blocking(self.master, False)
        self.name = os.ttyname(self.slave)
        if self.link:
            tmp = f"{self.link}.{os.getpid()}.tmp"
            if os.path.lexists(tmp):
                os.unlink(tmp)
            os.makedirs(os.path.dirname(tmp) or ".", exist_ok=True)  # `--link new/qj`: made, as every output's folder
            os.symlink(self.name, tmp)
            os.replace(tmp, self.link)
        return self.name

    def unplug(self) -> None:
        # the link goes first, as udev removes a board's /dev/serial/by-id link: left pointing at
        # the closed /dev/pts/N, a host opening it could get another program's new pty of that number
        if self.link and os.path.islink(self.link) and os.readlink(self.link) == self.name:
            os.unlink(self.link)
        for fd in (self.master, self.slave):
            if fd >= 0:
                os.close(fd)
        self.master = self.slave = -1

    def pending(self) -> int:
        """Bytes written to the port that the host has not read yet (the slave's input queue)."""
        if self.slave < 0:
            return 0
        try:
            return struct.unpack("i", fcntl.ioctl(self.slave, termios.FIONREAD, b"\0\0\0\0"))[0]
        except OSError:
            return 0

    def take_pending(self) -> int:
        """Read what the host has not read yet off the port ourselves (the device's end of an
        unplug: those bytes never reach the host) and return how many: a byte goes either to the
        host or to us, so the count is exact however the host's reads interleave."""
        if self.slave < 0:
            return 0
        os.set_blocking(self.slave, False)
        taken = 0
        while True:
            try:
                chunk = os.read(self.slave, 65536)
            except (BlockingIOError, OSError):
                return taken
            if not chunk:
                return taken
            taken += len(chunk)

    def read_host(self) -> bytes:
        """What the host wrote to the port since the last call (b'' when nothing)."""
        if self.master < 0:
            return b""
        try:
            return os.read(self.master, 256)
        except (BlockingIOError, OSError):
            return b""

    def write(self, data: bytes) -> int:
        if self.master < 0:
            return 0
        try:
            return os.write(self.master, data)
        except (BlockingIOError, OSError):
            return 0

    def close(self) -> None:
        self.unplug()


@dataclass
class Faults:
    """What to inject, in seconds since start. *_every: a period (0 = never)."""

    garbage_every: float = 0.0
    garbage_len: int = 32
    flip_every: float = 0.0
    drop_every: float = 0.0
    stall_at: list[float] = field(default_factory=list)
    stall_s: float = 0.5
    reboot_at: list[float] = field(default_factory=list)
    unplug_at: list[float] = field(default_factory=list)
    unplug_s: float = 1.0


@dataclass
class EmulatorStats:
    """What reached the host. A frame counts once the host has read all of it: frames still in
    the port's queue when it closes (end of run, unplug) count as `undelivered` instead."""

    frames: int = 0  # whole frames delivered (intact + broken)
    samples: int = 0  # intact frames delivered, by type
    hellos: int = 0
    texts: int = 0
    broken: int = 0  # delivered with a flipped or dropped byte: no receiver can accept them
    undelivered: int = 0  # written whole, never read by the host
    bytes: int = 0  # bytes delivered, garbage and cut frames included
    short_writes: int = 0
    garbage_bursts: int = 0
    bit_flips: int = 0
    dropped_bytes: int = 0
    stalls: int = 0
    reboots: int = 0
    unplugs: int = 0


@dataclass(frozen=True)
class EmulatorDef:
    """The emulated board's settings as data (`Emulator.from_def`); the faults to inject are
    `Faults`, the motion a `Signal`, the port a `link`."""

    # IMUs on the board (1 or 2): two, a Wiimote + Nunchuk's layout (right hand, then left).
    sensors: int = 2
    # Sampling rate (Hz) the firmware's loop runs at: 200, the boards' (firmware/main.py RATE_HZ),
    # well above the game's 60 Hz, so resampling hides the link's jitter.
    rate_hz: int = 200
    # Gaussian noise on each simulated axis (g): 0.002 g, a quiet MEMS accelerometer at rest.
    noise_g: float = 0.002
    # Width of the board's microsecond tick counter (bits): 30, as MicroPython's ticks_us on
    # rp2 and esp32, so hosts meet the wrap they meet on a real board. A counter wider than 32
    # bits goes out as its low 32 (t_us is a u32), and the HELLO announces 32.
    ts_bits: int = TS_BITS
    # The first boot's tick counter (us), e.g. just before the wrap; None: the host's monotonic clock.
    ticks_start: int | None = None
    # Seed of boot ids, faults and noise; None: they differ on every run (as real boots do).
    seed: int | None = None

    def __post_init__(self) -> None:
        if self.sensors not in (1, 2):
            raise ValueError(f"sensors must be 1 or 2, not {self.sensors}")
        if not 1 <= self.rate_hz <= 65535 or self.noise_g < 0 or not 8 <= self.ts_bits <= 62:
            # rate_hz: a u16 in the HELLO (PROTOCOL.md)
            raise ValueError("rate_hz must be 1..65535, noise_g >= 0 and ts_bits from 8 to 62")
        if 1 << (self.ts_bits - 1) <= 2 * (1_000_000 // self.rate_hz):
            # the sampler times its ticks by differences of tick counts, right only under half the
            # counter's period: a period of two samples must fit (PROTOCOL.md's narrow_clock)
            raise ValueError(f"ts_bits {self.ts_bits} is too narrow for {self.rate_hz} Hz: "
                             f"2**(ts_bits - 1) must exceed two sample periods ({2 * (1_000_000 // self.rate_hz)} us)")


class Emulator:
    """Runs Sampler.run against SimIMUs on a PtyPort until `seconds` pass or stop() is called.
    `on_port(path)` is told the port path at start and after every replug. The keyword defaults
    are EmulatorDef's."""

    def __init__(self, signal: Signal, sensors: int = 2, *, rate_hz: int = 200, faults: Faults | None = None,
                 link: str | None = None, ticks_start: int | None = None, seed: int | None = None,
                 on_port: Callable[[str], None] | None = None, on_event: Callable[[str], None] | None = None,
                 noise_g: float = 0.002, ts_bits: int = TS_BITS):
        self.signal, self.sensors, self.rate_hz = signal, sensors, rate_hz
        self.noise_g, self.ts_bits = noise_g, ts_bits
        self.faults = faults or Faults()
        self.rng = random.Random(seed)  # seed None: boot ids and faults differ on every run
        self.seed = seed
        self.ticks_start = ticks_start
        self.port = PtyPort(link)
        self.stats = EmulatorStats()
        self.on_port = on_port or (lambda p: None)
        self.on_event = on_event or (lambda e: None)
        self._stop = threading.Event()
        self.seconds: float | None = None
        self._reason = "end"
        self._t0 = time.monotonic()
        # periodic faults: kind -> period in s (0 = never), next due time, bursts still to inject
        self._every = {"garbage": self.faults.garbage_every, "flip": self.faults.flip_every,
                       "drop": self.faults.drop_every}
        self._next = dict(self._every)
        self._pending = dict.fromkeys(self._every, 0)
        self._stalls = sorted(self.faults.stall_at)
        self._reboots = sorted(self.faults.reboot_at)
        self._unplugs = sorted(self.faults.unplug_at)
        # frames written to the port, not yet known to be read: (end byte offset, type, broken)
        self._in_flight: deque[tuple[int, int, bool]] = deque()
        self._written = 0  # bytes written to the current port

    @classmethod
    def from_def(cls, signal: Signal, emulator_def: EmulatorDef | None = None, *, faults: Faults | None = None,
                 link: str | None = None, on_port: Callable[[str], None] | None = None,
                 on_event: Callable[[str], None] | None = None) -> Emulator:
        """The board `emulator_def` describes (None: the defaults); the same as its fields as keywords."""
        d = emulator_def or EmulatorDef()
        return cls(signal, d.sensors, rate_hz=d.rate_hz, faults=faults, link=link, ticks_start=d.ticks_start,
                   seed=d.seed, on_port=on_port, on_event=on_event, noise_g=d.noise_g, ts_bits=d.ts_bits)

    @property
    def definition(self) -> EmulatorDef:
        """This emulator's settings as an EmulatorDef."""
        return EmulatorDef(self.sensors, self.rate_hz, self.noise_g, self.ts_bits, self.ticks_start, self.seed)

    @property
    def path(self) -> str:
        return self.port.link or self.port.name

    def elapsed(self) -> float:
        return time.monotonic() - self._t0

    def stop(self) -> None:
        self._stop.set()

    def _write(self, frame: bytes) -> int:
        """The sampler's write, through the fault injector."""
        data = frame
        broken = False
        for kind in ("garbage", "flip", "drop"):
            if self._pending[kind]:
                self._pending[kind] -= 1
                if kind == "garbage":
                    n = self.rng.randint(1, self.faults.garbage_len)
                    data = self.rng.randbytes(n) + data
                    self.stats.garbage_bursts += 1
                elif kind == "flip":
                    # within the frame (delimiters included): a flip anywhere breaks it
                    b = bytearray(data)
                    i = len(data) - len(frame) + self.rng.randrange(len(frame))
                    b[i] ^= 1 << self.rng.randrange(8)
                    data = bytes(b)
                    self.stats.bit_flips += 1
                    broken = True
                else:
                    # inside the frame's COBS bytes: a dropped delimiter would cost nothing
                    # (its neighbour's delimiter stands in), so every drop breaks its frame
                    i = len(data) - len(frame) + 1 + self.rng.randrange(len(frame) - 2)
                    data = data[:i] + data[i + 1 :]
                    self.stats.dropped_bytes += 1
                    broken = True
        n = max(self.port.write(data), 0)
        self._written += n
        if n < len(data):
            self.stats.short_writes += 1
            return 0
        # the body's first byte (after 0x00 and the COBS code) is ver_type; never 0 in v1
        self._in_flight.append((self._written, frame[2] & 0x0F, broken))
        self._settle()
        return len(frame)

    def _settle(self, closing: bool = False, pending: int | None = None) -> None:
        """Move frames the host has read (all their bytes left the port's queue) into the
        stats; when closing, the rest are undelivered. `pending`: the queue as measured just
        before the port closed (default: now)."""
        pending = self.port.pending() if pending is None else pending
        read_up_to = self._written - pending
        s = self.stats
        q = self._in_flight
        while q and q[0][0] <= read_up_to:
            _, kind, broken = q.popleft()
            s.frames += 1
            if broken:
                s.broken += 1
            elif kind == protocol.SAMPLE:
                s.samples += 1
            elif kind == protocol.HELLO:
                s.hellos += 1
            else:
                s.texts += 1
        if closing:
            s.undelivered += len(q)
            q.clear()
            s.bytes += read_up_to
            self._written = 0

    def _close_port(self, drain_s: float) -> None:
        """Give the host up to `drain_s` to read what is queued (0: a real unplug loses it),
        then close and count what it got."""
        time.sleep(0.02)  # let the kernel move the last write into the queue FIONREAD sees
        end = time.monotonic() + drain_s
        while self.port.pending() and time.monotonic() < end:
            time.sleep(0.005)
        # What is still queued is taken off the port by us, not measured: between a measure and the
        # close the host could still read (a loaded machine preempts us there), and
        # test_every_fault_option_counts_agree_exactly saw 1649 and 2700 bytes more than the count.
        pending = self.port.take_pending()
        self.port.unplug()
        self._settle(closing=True, pending=pending)

    def _control(self, sampler: Sampler) -> bool:
        """Called by Sampler.run every loop: schedule faults; True ends this boot."""
        if self._stop.is_set() or (self.seconds is not None and self.elapsed() >= self.seconds):
            self._reason = "end"
            return True
        t = self.elapsed()
        for kind, every in self._every.items():
            if every > 0 and t >= self._next[kind]:
                self._next[kind] += every
                self._pending[kind] += 1
        if self._stalls and t >= self._stalls[0]:
            self._stalls.pop(0)
            self.stats.stalls += 1
            self.on_event(f"stall {self.faults.stall_s:.2f} s")
            self._stop.wait(self.faults.stall_s)  # the device hangs (a long GC, a busy I2C bus)
        if self._reboots and t >= self._reboots[0]:
            self._reboots.pop(0)
            self._reason = "reboot"
            return True
        if self._unplugs and t >= self._unplugs[0]:
            self._unplugs.pop(0)
            self._reason = "unplug"
            return True
        # last, after any stall: a request that came meanwhile is answered before this tick's SAMPLE
        if protocol.HELLO_REQUEST in self.port.read_host():
            sampler.request_hello()
        return False

    def _sampler(self, boot: int) -> Sampler:
        start = self.ticks_start
        ticks = HostTicks(self.ts_bits, None if start is None else (start if boot == 0 else 0))
        imus = [SimIMU(self.signal, i, self.elapsed, noise_g=self.noise_g, seed=self.seed or 0) for i in range(self.sensors)]
        imus += [None] * (2 - len(imus))
        return Sampler(imus, self._write, ticks, rate_hz=self.rate_hz,
                       boot_id=self.rng.getrandbits(32), ts_bits=self.ts_bits)

    def run(self, seconds: float | None = None) -> EmulatorStats:
        self.seconds = seconds
        self._t0 = time.monotonic()
        boot = 0
        try:
            # inside the try: a SIGTERM (KeyboardInterrupt) that comes while the port is announced,
            # as soon as a reader saw the line, left the port open and the --link symlink behind
            self.on_port(self.port.name)
            while True:
                self._reason = "end"
                self._sampler(boot).run(self._control)
                boot += 1
                if self._reason == "end":
                    break
                if self._reason == "unplug":
                    self.stats.unplugs += 1
                    self.on_event(f"unplug for {self.faults.unplug_s:.2f} s")
                    self._close_port(0.0)
                    self.port.unplug()
                    if self._stop.wait(self.faults.unplug_s):
                        break
                    self.port.plug()
                    # faults due while nothing was plugged in never happened
                    for kind, every in self._every.items():
                        self._pending[kind] = 0
                        while 0 < every and self._next[kind] <= self.elapsed():
                            self._next[kind] += every
                    self.on_port(self.port.name)
                # a replugged USB device powered up again: it reboots too
                self.stats.reboots += 1
                self.on_event("reboot")
        finally:
            self._close_port(0.0 if self._stop.is_set() else 1.0)
            self.port.close()
        return self.stats


def start_in_thread(emu: Emulator, seconds: float | None = None) -> threading.Thread:
    th = threading.Thread(target=emu.run, args=(seconds,), daemon=True, name="bridge-emulator")
    th.start()
    return th
