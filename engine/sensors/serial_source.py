"""`serial://`: IMUs on a microcontroller streaming protocol v1 frames (firmware_bridge/).

URLs:
- `serial:///dev/ttyACM0?baud=115200`: a port by path (USB CDC ignores the baud rate).
- `serial://auto`: the first port whose USB VID:PID is a known board (Pico, ESP32 bridges);
  `serial://auto?vid=2e8a&pid=0005` names the pair.
- `serial://<pyserial URL>`: anything after `serial://` that itself contains `://` is handed to
  `serial.serial_for_url`, e.g. `serial://loop://` for tests, less our own `baud`, `retry`,
  `window` and `axes` (`serial://socket://bridge.local:7000?axes=-x,y,z`).

Polling never waits: each poll drains `in_waiting` (the Linux tty buffer holds only 4095 bytes,
so a slow reader loses data), decodes frames, and maps device time to host time. A lost port
(OSError, SerialException, termios.error) becomes SourceState.RECONNECTING, and the port is
reopened every `retry` seconds until it comes back. So does an open port that brings no byte
for STALL_S (a board owes a HELLO every second: it has gone quiet), until its next byte. After every open, SAMPLEs wait for a HELLO
on that port (counted as `samples_before_hello`): a board back on the port may have rebooted or be
another one, and the previous HELLO's scales would misread it.

Hostile or broken input is counted and dropped, never raised: the decoder rejects HELLOs whose
fields make no sense (protocol.hello_problem) and frames replayed from earlier (same boot and
seq; a HELLO of the boot later in time resyncs the check after the host stopped reading for
32768 frames or more, and `missing` says a long run of replays). A board that reboots with
other sensors counts a `sensor_changes` (B alone after A and B too, whose shape stays 2 rows),
and one with another sensor count changes `sensors`: from then on its samples have the new
shape, which is how the frames stage (engine.frames.FrameResampler) and the recorder
(tools/record.py) learn of it. A new boot holds no sensor reading of the last one. Only a reboot
does: a HELLO that announces other sensors than its boot's earlier HELLO is counted as
`sensor_conflicts` and dropped (the boot's first sensors stay; a boot that announced none yet,
before finding its IMUs, may announce them). A SAMPLE with an acceleration over MAX_ACCEL_G
once scaled (possible with a tiny `accel_lsb_per_g`) is counted as `implausible` and dropped.
"""

from __future__ import annotations

import io
import os
import termios
from collections import deque
from urllib.parse import parse_qsl

import numpy as np
import serial
from serial.tools import list_ports

from engine.sensors.axes import AxisMap, parse_axes
from engine.sensors.serial_accel import SampleAccel, sample_width
from engine.sensors.source import (
    Clock,
    Sample,
    Source,
    SourceError,
    SourceState,
    register_scheme,
    url_number,
    url_params_known,
)
from firmware_bridge import protocol

# (VID, PID or None for any) of boards the firmware runs on
KNOWN_BOARDS = (
    (0x2E8A, 0x0005),  # Raspberry Pi Pico / Pico W running MicroPython
    (0x303A, None),  # Espressif native USB (ESP32-S2/S3/C3)
    (0x10C4, 0xEA60),  # CP210x on ESP32 DevKits
    (0x1A86, 0x7523),  # CH340 on ESP32 boards
    (0x1A86, 0x55D4),  # CH9102 on ESP32 boards
)
LOST = (OSError, serial.SerialException, termios.error)
MAX_READS_PER_POLL = 32  # bounds one poll's work even if the device outruns us
BACKLOG = 1024  # a read this big may have left more behind: read again in the same poll
# No byte for STALL_S on an open port, though a board owes a HELLO every second: it has gone quiet
# (its power, a crash). One stall is counted and the source is away (`reconnecting`) as a Wiimote
# gone silent is, so the game pauses under the lost overlay; the port stays open, and the first
# byte again is the board back (its samples flowed on with a frozen player before).
STALL_S = 2.0
REPLAY_RUN_SAY = 50  # frames dropped as replays in a row that `missing` says, at the least
MAX_WINDOW_S = 60.0  # `window=`: the clock keeps up to one minimum per poll over it (12,000 at 200 polls/s)


class DeviceClock:
    """Device timestamps to host seconds.

    Unwraps the device's `ts_bits`-bit microsecond counter, then maps it with the minimum of
    (host arrival time - device time) over a sliding window: transport delay is never negative,
    so the minimum is the offset plus the least delay seen, and a window (rather than all time)
    follows the drift between the two crystals.
    """

    def __init__(self, window_s: float = 2.0):
        self.window_s = window_s
        self.last_t = -float("inf")  # the last host time handed out; kept across resets
        self.reset(32)

    def reset(self, ts_bits: int) -> None:
        self.mask = (1 << ts_bits) - 1
        self._last_raw: int | None = None
        self._us = 0  # unwrapped device microseconds
        self._mins: deque[tuple[float, float]] = deque()  # (host t, offset), offsets increasing

    def unwrap(self, raw: int) -> float | None:
        """Device seconds, or None for a jump backwards (a restarted device clock)."""
        raw &= self.mask
        if self._last_raw is None:
            self._us = raw
        else:
            delta = (raw - self._last_raw) & self.mask
            if delta > self.mask // 2:
                return None
            self._us += delta
        self._last_raw = raw
        return self._us / 1e6

    def observe(self, host_t: float, device_s: float) -> None:
        """Everything up to device time `device_s` had arrived by host time `host_t`."""
        offset = host_t - device_s
        q = self._mins
        while q and q[-1][1] >= offset:
            q.pop()
        q.append((host_t, offset))
        while q[0][0] < host_t - self.window_s:
            q.popleft()

    @property
    def offset(self) -> float:
        return self._mins[0][1]


def write_now(port: serial.SerialBase, data: bytes) -> None:
    """Write without waiting, or raise OSError (BlockingIOError when there is no room). A port
    with a file descriptor (a tty, a socket://; pyserial keeps both non-blocking) is written
    directly: pyserial's own write with write_timeout=0 retries EAGAIN without end, so a device
    that never reads its input (its buffer full) would hang the caller. Others (loop://) as usual."""
    try:
        fd = port.fileno()
    except (AttributeError, io.UnsupportedOperation):  # loop:// and other ports with no descriptor
        port.write(data)
    else:
        os.write(fd, data)


def read_waiting(port: serial.SerialBase) -> bytes:
    """Everything waiting on `port`, without waiting. A zero-timeout read(1) when nothing is waiting
    makes a hung-up pty or unplugged port raise here instead of looking merely quiet."""
    n = port.in_waiting
    if not n:
        return port.read(1)
    data = port.read(n)
    if n < BACKLOG:  # the usual case: one ioctl, one read
        return data
    chunks = [data]  # a backlog: keep draining while the device refills the buffer
    for _ in range(MAX_READS_PER_POLL):
        n = port.in_waiting
        if not n:
            break
        chunks.append(port.read(n))
    return b"".join(chunks)


def find_board(vid: int | None = None, pid: int | None = None) -> str | None:
    """The device path of the first known board (or the given VID/PID), or None."""
    wanted = ((vid, pid),) if vid is not None else KNOWN_BOARDS
    for port in sorted(list_ports.comports(), key=lambda p: p.device):
        for v, p in wanted:
            if port.vid == v and (p is None or port.pid == p):
                return port.device
    return None


def describe(port_name: str | None, hello: protocol.Hello, axes: AxisMap | None) -> str:
    """The source's description after `hello`. Made from every HELLO, not only a new boot's: a
    boot's first HELLO may come before its IMUs are found (x0, kind unknown), and a later one of
    the same boot may change rate_hz; `record` writes it into its file."""
    kind = {1: "MPU-6050", 2: "LSM6DS3", 3: "simulated"}.get(hello.imu_kind, "IMU")
    turned = f", axes {axes}" if axes is not None else ""
    return f"serial bridge {port_name} ({kind} x{hello.sensors}, {hello.rate_hz} Hz{turned})"


def missing_sensor_a(hello: protocol.Hello | None) -> str:
    """`Source.missing` for a board whose HELLO announces sensor B (the left hand, PROTOCOL.md)
    alone: its samples keep two rows, the right hand's holding still."""
    if hello is not None and hello.flags & protocol.FLAGS_SENSORS == protocol.FLAG_SENSOR_B:
        return "no right-hand sensor (sensor A): the right hand holds still"
    return ""


def missing_now(hello: protocol.Hello | None, decoder: protocol.Decoder) -> str:
    """`Source.missing` of a connected serial source: a second's worth of frames or more in a
    row dropped as replays (the board owes a HELLO every second, and one at once when asked, and
    a HELLO of its boot later in time resyncs the decoder: a board that sends none, or bytes
    that are all old ones played back), else a B-only board's still right hand."""
    if decoder.replay_run >= max(hello.rate_hz if hello is not None else 0, REPLAY_RUN_SAY):
        return ("every frame dropped as a replay: its seq was delivered before in this boot (bytes played "
                "back, or the host stopped reading for a while and no HELLO of the board has come since)")
    return missing_sensor_a(hello)


class SerialSource(Source):
    """Samples of shape (sensors, 3) in g from a protocol v1 device."""

    def __init__(self, url: str, clock: Clock, target: str | None, *, baud: int = 115200,
                 retry: float = 0.5, window_s: float = 2.0, vid: int | None = None, pid: int | None = None,
                 axes: AxisMap | None = None):
        super().__init__(url=url, sensors=2, clock=clock, description=f"serial bridge {target or 'auto'}")
        self.axes = axes  # the IMU's axes onto the game's (`?axes=`, engine/sensors/axes.py); None: as they are
        self.target = target  # a path or pyserial URL; None: find by VID/PID
        self.baud = baud
        self.retry = retry
        self.vid, self.pid = vid, pid
        self.port: serial.SerialBase | None = None
        self.port_name: str | None = None
        self.decoder = protocol.Decoder()
        self.devclock = DeviceClock(window_s)
        self.hello: protocol.Hello | None = None
        self.messages: deque[str] = deque(maxlen=32)  # the device's TEXT lines
        self._accel = SampleAccel(self.count)  # SAMPLE payloads to g, each sensor's last value
        self._next_try = 0.0
        self._last_byte = clock()
        self._stalled = False
        self._next_hello_request = 0.0
        self._hello_on_port = False  # a HELLO came since the port was (re)opened
        self.sensors_known = False  # until a HELLO names its sensors, `sensors` is a guess
        self._polled = False
        self._open()

    # The decoder's counters join the source's own when stats is read, not on every poll.
    @property
    def stats(self) -> dict[str, int]:
        own = self.__dict__.setdefault("_own_stats", {})
        decoder = self.__dict__.get("decoder")
        return {**own, **decoder.counts()} if decoder is not None else own

    @stats.setter
    def stats(self, value: dict[str, int]) -> None:
        self.__dict__["_own_stats"] = value

    def count(self, key: str, n: int = 1) -> None:
        own = self.__dict__.setdefault("_own_stats", {})
        own[key] = own.get(key, 0) + n

    # -- connection -------------------------------------------------------------------------
    def _open(self) -> None:
        self._next_try = self.clock() + self.retry
        name = self.target or find_board(self.vid, self.pid)
        if name is None:
            return
        try:
            if "://" in name:
                port = serial.serial_for_url(name, baudrate=self.baud, timeout=0)
            else:
                # write_timeout=0: asking for a HELLO must never block the game loop
                port = serial.Serial(name, baudrate=self.baud, timeout=0, write_timeout=0)
        except LOST:
            return  # not there (yet): a state, retried every `retry` s
        except Exception as exc:  # pyserial's own URL and setting checks (ValueError, KeyError...)
            if self._polled:  # poll never raises: a later failure is counted and retried
                self.count("open_errors")
                return
            raise SourceError(f"{self.url}: cannot open {name}: {exc!r}") from None
        self.port, self.port_name = port, name
        if self.state is not SourceState.CONNECTING:
            self.count("reconnects")
        self.state = SourceState.CONNECTED
        self.decoder.resync()
        self.devclock.reset(self.hello.ts_bits if self.hello else 32)
        self._last_byte = self.clock()
        self._stalled = False
        self._next_hello_request = 0.0
        # what is on the port now may have rebooted, or be another board: its SAMPLEs wait for
        # its HELLO, as at the first open (self.hello stays, for the sensor-conflict check)
        self._hello_on_port = False
        self._ask_hello()

    def _ask_hello(self) -> None:
        """Ask for a HELLO now (protocol.HELLO_REQUEST), not in up to a second: pyserial flushed any earlier one."""
        now = self.clock()
        if self.port is None or now < self._next_hello_request:
            return
        self._next_hello_request = now + 0.25
        try:
            write_now(self.port, protocol.HELLO_REQUEST)
        except (*LOST, serial.SerialTimeoutException):
            pass  # a read will notice a lost port; a full output buffer just means no request

    def _lost(self) -> None:
        self.count("disconnects")
        self._drop_port()
        self.state = SourceState.RECONNECTING
        self._next_try = self.clock() + self.retry

    def _drop_port(self) -> None:
        if self.port is not None:
            try:
                self.port.close()
            except LOST:
                pass
        self.port = None

    def missing(self) -> str:
        return missing_now(self.hello, self.decoder) if self.state is SourceState.CONNECTED else ""

    def close(self) -> None:
        self._drop_port()
        self.state = SourceState.DISCONNECTED

    # -- reading ----------------------------------------------------------------------------
    def poll(self) -> list[Sample]:
        if self.state is SourceState.DISCONNECTED:
            return []
        self._polled = True
        if self.port is None:
            if self.clock() >= self._next_try:
                self._open()
            if self.port is None:
                return []
        try:
            data = read_waiting(self.port)
        except LOST:
            self._lost()
            return []
        now = self.clock()
        if not data:
            if not self._stalled and now - self._last_byte > STALL_S:  # gone quiet: away (STALL_S)
                self._stalled, self.state = True, SourceState.RECONNECTING
                self.count("stalls")
                self._ask_hello()
            return []
        if self._stalled:
            self.state, self._stalled = SourceState.CONNECTED, False
        self._last_byte = now
        replays = self.decoder.replays
        frames = self.decoder.feed(data)
        if self.decoder.replays > replays or any(f.jump for f in frames):
            # a reboot whose HELLO was lost: its frames are replays or a jump until its next HELLO,
            # which the board sends within a second anyway; asked for, it comes on its next tick
            self._ask_hello()
        return self._samples(frames, now)

    def _apply_hello(self, f: protocol.Frame) -> bool:
        """Take a HELLO's scales and layout; False (counted, dropped) if a field is invalid. The
        decoder already drops those: this guards against a decoder that lets one through, since
        a zero scale here would raise in the game loop."""
        if len(f.payload) != protocol.HELLO_SIZE or protocol.hello_problem(f.payload, f.flags) is not None:
            self.count("bad_hellos")
            return False
        hello = protocol.Hello(f)
        same_boot = self.hello is not None and hello.boot_id == self.hello.boot_id
        if same_boot and self.hello.sensors and hello.flags & protocol.FLAGS_SENSORS != self.hello.flags & protocol.FLAGS_SENSORS:
            # A boot's sensors are found once, at boot (PROTOCOL.md, HELLO): only a reboot changes
            # them. A board that announces others within one boot is broken; taking each such
            # HELLO would reshape the samples, and `record` would start a new file, every second.
            self.count("sensor_conflicts")
            return False
        changed = not same_boot or hello.ts_bits != self.hello.ts_bits
        if self._accel.take_hello(hello, same_boot):  # other sensors than the ones announced before
            self.count("sensor_changes")  # (B alone after A and B too: the same width, 2 rows)
        if hello.sensors:  # `sensors` is only a guess (2) until the first HELLO that names some
            self.sensors, self.sensors_known = sample_width(hello.flags), True  # B alone: still 2 rows
        self.hello = hello
        self._hello_on_port = True
        self.rate_hz = float(hello.rate_hz)
        if changed:
            self.devclock.reset(hello.ts_bits)
            if protocol.narrow_clock(hello.ts_bits, hello.rate_hz):
                # t_us wraps within two sample periods: its wraps cannot be told apart, so the
                # sample times are wrong (PROTOCOL.md, HELLO); the HELLO is valid and taken
                self.count("narrow_clock")
        self.description = describe(self.port_name, hello, self.axes)  # every HELLO: see describe
        return True

    def _samples(self, frames: list[protocol.Frame], now: float) -> list[Sample]:
        out: list[Sample] = []
        times: list[float] = []
        sample_frames: list[protocol.Frame] = []
        latest = None
        for f in frames:
            # A HELLO may bring new scales or a new clock, and a seq jump (a reboot whose HELLO was
            # lost) restarts the device clock: the SAMPLEs before it are mapped first, with the
            # scales and clock offset they came with. Mapped with the new offset, an old boot's
            # samples land as far in the future as it had been up (PROTOCOL.md "Host time").
            if f.msg_type == protocol.HELLO or f.jump:
                out += self._flush(times, sample_frames, latest, now)
                times, sample_frames, latest = [], [], None
                if f.msg_type == protocol.HELLO:
                    if not self._apply_hello(f):
                        continue
                else:
                    self.devclock.reset(self.devclock.mask.bit_length())
            dev = self.devclock.unwrap(f.t_us)
            if dev is None:  # device clock went back without a HELLO: start the mapping over
                self.count("time_jumps")
                self._ask_hello()  # a reboot whose HELLO was lost after a seq past 32767: no jump
                # the same as above: what came before the jump keeps the clock it came with
                # (a single frame with a wild t_us ahead is then mapped no later than `now`)
                out += self._flush(times, sample_frames, latest, now)
                times, sample_frames, latest = [], [], None
                self.devclock.reset(self.devclock.mask.bit_length())
                dev = self.devclock.unwrap(f.t_us)
            latest = dev
            if f.msg_type == protocol.TEXT:
                self.messages.append(f.payload.decode("utf-8", "replace"))
                self.count("texts")
            elif f.msg_type == protocol.SAMPLE:
                if not self._hello_on_port:  # scales unknown until a HELLO on this port: ask for one
                    self.count("samples_before_hello")
                    self._ask_hello()
                    continue
                if not self.hello.flags & protocol.FLAGS_SENSORS:
                    # its HELLO announced no sensor (sent before the board found one): the values
                    # have no place (PROTOCOL.md); the board's next HELLO, asked for now, will say
                    self.count("sensor_unannounced")
                    self._ask_hello()
                    continue
                if f.flags & protocol.FLAG_OVERRUN:
                    self.count("device_overruns")
                if not self._accel.plausible(f, self.hello):
                    # a tiny accel_lsb_per_g (PROTOCOL.md allows 1) scales counts past what any
                    # sensor reads: passed on, it would make `record` write a file nothing reads
                    self.count("implausible")
                    continue
                times.append(dev)
                sample_frames.append(f)
        return out + self._flush(times, sample_frames, latest, now)

    def _flush(self, times: list[float], sample_frames: list[protocol.Frame], latest: float | None,
               now: float) -> list[Sample]:
        """Samples for one run of frames under one device clock: everything up to device time
        `latest` had arrived by `now`, so none is mapped later than `now`."""
        if latest is not None:
            self.devclock.observe(now, latest)
        return self._map(times, sample_frames, now) if times else []

    def _map(self, times: list[float], sample_frames: list[protocol.Frame], now: float) -> list[Sample]:
        """Samples for SAMPLE frames of one layout and clock, at device times `times`, never
        later than `now` (dev + offset, offset = now - dev, can round one step past it)."""
        # a few samples per poll: plain floats beat numpy calls here
        offset, last = self.devclock.offset, self.devclock.last_t
        out = []
        rows = self._accel.rows(sample_frames, self.hello, self.sensors)
        if self.axes is not None:
            rows = self.axes.apply(np.asarray(rows))  # (frames, sensors, 3)
        for dev, a in zip(times, rows, strict=True):
            last = min(max(dev + offset, last), now)  # never backwards
            out.append(Sample(last, a))
        self.devclock.last_t = last
        return out


def parse_serial_url(url: str) -> tuple[str | None, dict[str, str]]:
    """(target, params): target is a path, a pyserial URL, or None for `auto`. A pyserial URL
    keeps its own query but gives up ours (`serial://socket://host:7000?axes=-x,y,z`: a board on
    the network with its IMU turned; pyserial refused `axes` with a bare KeyError)."""
    rest = url.split("://", 1)[1] if "://" in url else ""
    if "://" in rest:
        base, _, query = rest.partition("?")
        pieces = [p for p in query.split("&") if p]
        ours = [p for p in pieces if p.partition("=")[0] in PYSERIAL_URL_OURS]
        theirs = "&".join(p for p in pieces if p not in ours)
        return base + (f"?{theirs}" if theirs else ""), dict(parse_qsl("&".join(ours), keep_blank_values=True))
    path, _, query = rest.partition("?")
    params = dict(parse_qsl(query, keep_blank_values=True))  # `axes=` is an error, not the default
    if not path:
        raise SourceError(f"{url}: no port (expected serial:///dev/ttyACM0, serial://auto or serial://loop://)")
    return (None if path == "auto" else path), params


PYSERIAL_URL_OURS = ("baud", "retry", "window", "axes")  # the parameters no pyserial URL handler has


def open_serial(url: str, clock: Clock) -> SerialSource:
    target, params = parse_serial_url(url)
    url_params_known(url, params, ("baud", "retry", "window", "vid", "pid", "axes"))
    axes = parse_axes(url, params["axes"]) if "axes" in params else None
    # finite and in range: nan passed `<= 0`, and a retry of nan never reopened a lost port while
    # a window of nan or inf never dropped an old minimum from the clock (nor from its deque)
    baud = int(url_number(url, params, "baud", 115200, 1, 2**31 - 1, integer=True))
    retry = url_number(url, params, "retry", 0.5, 0, 3600, lo_open=True)
    window = url_number(url, params, "window", 2.0, 0, MAX_WINDOW_S, lo_open=True)
    try:
        vid = int(params["vid"], 16) if "vid" in params else None
        pid = int(params["pid"], 16) if "pid" in params else None
    except ValueError:
        raise SourceError(f"{url}: vid and pid must be hex") from None
    if pid is not None and vid is None:
        raise SourceError(f"{url}: pid needs a vid too (e.g. serial://auto?vid=2e8a&pid=0005)")
    return SerialSource(url, clock, target, baud=baud, retry=retry, window_s=window, vid=vid, pid=pid, axes=axes)


register_scheme("serial", open_serial)
