"""A protocol-faithful Wiimote + Nunchuk, standing in for `hid.device`, fed from a recording.

`EmulatedWiimote` is the hardware: an EEPROM image with the calibration blocks at 0x16 and
0x20, the Nunchuk's registers on the i2c bus (slave 0x52: data at 0x00, calibration at 0x20,
init at 0xF0/0xFB, ID at 0xFA), the reporting mode, LEDs, rumble and battery. It answers the
real output reports the way Dolphin's WiimoteEmu and WiiBrew describe a real remote:

- 0x17 reads reply in 0x21 chunks of 16 bytes, one read at a time (a second gets a busy ack,
  error 4), error 7 for an absent extension, 8 past the EEPROM; 0x16 writes are always acked (0x22);
  LEDs/mode/IR/speaker ack only when byte 1 bit 1 asks; rumble (bit 0) rides on every report.
- 0x12 with a valid mode starts data reports; continuous ones come every 10 ms (+ jitter).
- a Nunchuk plug/unplug sends an unsolicited 0x20 and stops data reports until 0x12 comes.
- the Nunchuk's registers (data, calibration, ID) read encrypted with the all-zero key until
  it is initialised (0x55 -> F0, then 0x00 -> FB).
- the host's buffer holds 64 reports (Linux hidraw): when nobody reads, newer ones are lost.

`EmulatedBus` is the `hid`/`hidraw` module stand-in (`enumerate`, `device`) the driver's
transport uses, so the driver under test is the real one. Values come from the recording (in
g), interpolated at each report's 10 ms slot, turned into raw counts with the emulator's own
calibration (X 10 bits, Y and Z 9), and the log of what was sent lets tests compare.

`wiimote-emu://recording.csv?opt=value&...` options:
  jitter_ms=2    delivery delay per report, uniform in [0, jitter_ms)
  latency_ms=4   reply delay to an output report
  pad=0          pad every input report to this many bytes (22 = Windows)
  drop=0         probability of losing each data report
  clone=0        1/garbage: garbage Nunchuk calibration and a bad EEPROM block at 0x16
                 (good copy at 0x20); zeros: all-zero Nunchuk calibration
  nunchuk=1      a Nunchuk is plugged at power-on
  seed=0         random seed (jitter, drops, garbage)
  loop=1         loop the recording
  start=0        begin this many seconds into the recording
  unplug_at=S, replug_at=S, nunchuk_out_at=S, nunchuk_in_at=S, foreign_mode_at=S
                 events, S seconds after the emulator starts (comma-separated lists allowed)
  loss=error     how an unplug looks: 'error' (reads fail, device gone) or 'silent'
  kernel_driver=0  1: pretend Linux's hid-wiimote is bound to the device
  status_stops=0 1: every status report stops data reporting (what Linux's hid-wiimote
                 assumes, "on status reports the drm is reset"; Dolphin stops it only on
                 extension events)
  player=1       LED the driver sets
  seconds=S      the source ends (state `ended`, as a replay does at its end) S seconds after
                 the emulator starts, so `record` and the game stop on their own; default:
                 never (a remote stays on; with loop=0 it holds the recording's last values)
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, fields
from typing import Any

import numpy as np

from engine.recording import MAX_DURATION_S, Recording, read_recording
from engine.sensors.source import (
    Sample,
    SourceError,
    SourceState,
    file_path,
    parse_source_url,
    url_flag,
    url_number,
)
from engine.sensors.wiimote import protocol as p
from engine.sensors.wiimote.driver import WiimoteSource
from engine.sensors.wiimote.emulated_memory import EmulatedMemory
from engine.sensors.wiimote.emulated_queue import ReportQueue
from engine.sensors.wiimote.playback import RecordingPlayback

PERIOD_S = 0.01
# the scripted events (wiimote-emu:// options `<event>_at`) and the methods that do them
EVENTS = {"unplug": "unplug", "replug": "replug", "nunchuk_out": "unplug_nunchuk",
          "nunchuk_in": "plug_nunchuk", "foreign_mode": "foreign_mode"}
MAX_PAD = 64  # input reports are at most 22 bytes; Windows pads them to 22

# A genuine-looking calibration, deliberately not the typical values and with low bits set,
# so that a driver ignoring the block or its low bits decodes wrongly.
GENUINE_WIIMOTE = p.Calibration(zero=(514, 506, 518), one_g=(617, 611, 622))
GENUINE_NUNCHUK = p.Calibration(
    zero=(509, 514, 506), one_g=(714, 719, 711),
    stick_min=(0x1E, 0x22), stick_max=(0xE1, 0xDD), stick_center=(0x80, 0x7F),
)  # fmt: skip


@dataclass
class SentData:
    """One data report the emulator produced (for tests to compare with the recording)."""

    slot: int  # 10 ms slot index since power-on
    rec_time: float  # the recording time its values were taken from
    right: tuple[int, int, int]  # raw counts sent for the Wiimote
    left: tuple[int, int, int] | None  # raw counts sent for the Nunchuk, None when unplugged
    dropped: bool = False
    read_at: float | None = None  # host time the driver read it; None if never read


@dataclass(frozen=True)
class WiimoteEmulatorDef:
    """The emulated remote's settings as data (`EmulatedWiimote.from_def`); the module docstring
    gives the matching `wiimote-emu://` URL options. The scripted events (unplug_at, ...) are
    not settings: they go to from_def beside it."""

    serial: str = "00:19:1d:00:00:01"  # its Bluetooth address, as enumerate() shows it
    product_id: int = 0x0306  # RVL-CNT-01; 0x0330 is the -TR (Wii Remote Plus)
    # Delivery delay per report (ms, uniform in [0, jitter_ms)): 2 ms, what Bluetooth HID adds
    # at 100 Hz on a quiet link.
    jitter_ms: float = 2.0
    latency_ms: float = 4.0  # reply delay to an output report (ms): a real remote's few ms
    pad: int = 0  # pad every input report to this many bytes: 0 as Linux reads them; 22 = Windows
    drop: float = 0.0  # probability of losing each data report: 0, a clean link
    # "" a genuine remote; "garbage" or "zeros": a clone's unreadable Nunchuk calibration.
    clone: str = ""
    nunchuk: bool = True  # a Nunchuk is plugged at power-on: the game's two-hand layout
    seed: int = 0  # random seed of the jitter, drops and garbage: reproducible by default
    loop: bool = True  # loop the recording (a demo runs as long as the player likes)
    loss: str = "error"  # how an unplug looks: "error" (reads fail) or "silent"
    kernel_driver: bool = False  # pretend Linux's hid-wiimote is bound to the device
    battery: int = 0xB4  # the status report's battery byte: 0xB4, a full set of AAs
    start: float = 0.0  # begin this many seconds into the recording
    # Every status report stops data reporting (what Linux's hid-wiimote assumes); False as
    # Dolphin's emulation, which stops it only on extension events.
    status_stops: bool = False

    def kwargs(self) -> dict[str, object]:
        """The EmulatedWiimote keywords this definition stands for."""
        return {f.name: getattr(self, f.name) for f in fields(self)}


class EmulatedWiimote:
    """The emulated remote (see the module docstring), with its memory (EmulatedMemory), the
    reports in flight (ReportQueue) and the recording it plays (RecordingPlayback)."""

    def __init__(
        self,
        rec: Recording,
        clock: Callable[[], float],
        *,
        serial: str = "00:19:1d:00:00:01",
        product_id: int = 0x0306,
        jitter_ms: float = 2.0,
        latency_ms: float = 4.0,
        pad: int = 0,
        drop: float = 0.0,
        clone: str = "",
        nunchuk: bool = True,
        seed: int = 0,
        loop: bool = True,
        loss: str = "error",
        kernel_driver: bool = False,
        battery: int = 0xB4,
        start: float = 0.0,
        status_stops: bool = False,
        events: list[tuple[float, str]] | None = None,
    ):
        self.rec = rec
        self.clock = clock
        self.definition = WiimoteEmulatorDef(serial, product_id, jitter_ms, latency_ms, pad, drop, clone, nunchuk,
                                             seed, loop, loss, kernel_driver, battery, start, status_stops)
        self.serial = serial
        self.product_id = product_id
        self.jitter = jitter_ms / 1000.0
        self.latency = latency_ms / 1000.0
        self.pad = pad
        self.drop = drop
        self.loop = loop
        self.loss = loss
        self.kernel_driver = "wiimote" if kernel_driver else None
        self.battery = battery
        self.rng = np.random.default_rng(seed)
        self.start = start
        self.status_stops = status_stops
        self.t0 = clock()
        self._playback = RecordingPlayback(rec, PERIOD_S)
        self._events = sorted(events or [])

        # The truth the emulator encodes with. A clone's Nunchuk block is unreadable, so what
        # it "really" is cannot be known; it is built to match the typical values.
        self.wiimote_cal = GENUINE_WIIMOTE
        self.nunchuk_cal = p.NUNCHUK_TYPICAL if clone else GENUINE_NUNCHUK
        self.stats: dict[str, int] = {}
        self.memory = EmulatedMemory(self.wiimote_cal, self.nunchuk_cal, clone, self.rng, self._count)

        self.nunchuk_plugged = nunchuk
        self.connected = True  # paired and in range
        self.connection = 0  # bumps on every re-plug: the OS gives it a new node
        self.sent: list[SentData] = []
        self.outputs: list[bytes] = []  # every output report received, in order
        self.lose_outputs = 0  # the next N output reports vanish on the air
        self._reset_link()

    # ---- link state ---------------------------------------------------------------------

    @classmethod
    def from_def(cls, rec: Recording, clock: Callable[[], float], emulator_def: WiimoteEmulatorDef | None = None,
                 events: list[tuple[float, str]] | None = None) -> EmulatedWiimote:
        """The remote `emulator_def` describes (None: the defaults); the same as its fields as keywords."""
        return cls(rec, clock, **(emulator_def or WiimoteEmulatorDef()).kwargs(), events=events)

    def _reset_link(self) -> None:
        """Power-on / new connection: no reporting, LEDs off, extension uninitialised."""
        self.mode: int | None = None
        self.continuous = False
        self.leds = 0
        self.rumble = False
        self.memory.reset_link()
        self._queue = ReportQueue(self.pad, self._count)
        self._next_slot = self._slot_at(self.clock()) + 1
        self._pumped_to = self.clock()

    @property
    def ext_stage(self) -> int:
        """How far the extension's init got: 1 after 0x55 -> F0; 2 (plain data) after 0x00 -> FB."""
        return self.memory.ext_stage

    @property
    def path(self) -> bytes:
        return f"emu-wiimote-{self.serial}-{self.connection}".encode()

    def _count(self, key: str) -> None:
        self.stats[key] = self.stats.get(key, 0) + 1

    def _slot_at(self, t: float) -> int:
        return int(np.floor((t - self.t0) / PERIOD_S + 1e-9))

    # ---- events (tests call these directly; URLs schedule them) -------------------------

    def unplug(self) -> None:
        """The remote switches off or leaves range."""
        self.connected = False
        self._queue.drop_all()

    def replug(self) -> None:
        """The remote comes back (a new Bluetooth connection: new node, reset state)."""
        self.connected = True
        self.connection += 1
        self._reset_link()

    def plug_nunchuk(self, plugged: bool = True) -> None:
        if plugged == self.nunchuk_plugged:
            return
        self.nunchuk_plugged = plugged
        self.memory.ext_stage = 0
        # Dolphin ProcessExtensionPortEvent: reporting stops, an unsolicited 0x20 follows.
        self.mode = None
        if self.connected:
            self._emit(self._status_report(), self.clock() + self.latency)

    def unplug_nunchuk(self) -> None:
        self.plug_nunchuk(False)

    def foreign_mode(self) -> None:
        """What Linux's hid-wiimote does when its input device is opened: its own mode."""
        if self.connected:
            self.mode, self.continuous = 0x31, True

    # ---- time ---------------------------------------------------------------------------

    def pump(self, now: float | None = None) -> None:
        """Produce everything due up to `now`: scheduled events and data reports."""
        now = self.clock() if now is None else now
        while self._events and self.t0 + self._events[0][0] <= now:
            at, name = self._events.pop(0)
            self._stream_until(self.t0 + at)
            getattr(self, EVENTS[name])()
        self._stream_until(now)

    def _stream_until(self, t: float) -> None:
        last = self._slot_at(t)
        if not (self.connected and self.mode is not None and self.continuous):
            self._next_slot = max(self._next_slot, last + 1)
            return
        while self._next_slot <= last:
            k = self._next_slot
            self._next_slot += 1
            data, sent = self._data_report(k)
            if self.drop and self.rng.random() < self.drop:
                sent.dropped = True
                self._count("dropped")
                self.sent.append(sent)
                continue
            self.sent.append(sent)
            due = self.t0 + k * PERIOD_S + (self.rng.random() * self.jitter if self.jitter else 0.0)
            self._emit(data, due, sent)

    def _emit(self, data: bytes, due: float, sent: SentData | None = None) -> None:
        self._queue.push(data, due, sent)

    def take(self, now: float) -> bytes | None:
        """The next input report the host has received by `now`, or None."""
        self.pump(now)
        return self._queue.pop(now)

    # ---- what it sends ------------------------------------------------------------------

    def _values_at(self, k: int) -> tuple[float, np.ndarray]:
        rel = self._playback.wrap(self.start + k * PERIOD_S, self.loop)
        return rel, self._playback.values_at(rel)

    def _data_report(self, k: int) -> tuple[bytes, SentData]:
        rel, g = self._values_at(k)
        right = quantize(self.wiimote_cal.from_g(g[0]), nine_bit_yz=True)
        left_g = g[1] if self.rec.sensors > 1 else np.array([0.0, 0.0, 1.0])
        left = quantize(self.nunchuk_cal.from_g(left_g)) if self.nunchuk_plugged else None
        sent = SentData(slot=k, rec_time=rel, right=right, left=left)
        if left is not None:
            plain = p.encode_nunchuk((0x80, 0x7F), left)
            self.memory.ext_regs[0:6] = plain
        ext = self.memory.ext_bytes(self.nunchuk_plugged)
        core = p.encode_core(0, right)
        return data_report(self.mode, core, ext), sent

    def _status_report(self) -> bytes:
        flags = (0x01 if self.battery < 0x20 else 0) | (0x02 if self.nunchuk_plugged else 0) | self.leds << 4
        return bytes([p.IN_STATUS, 0, 0, flags, 0, 0, self.battery])

    def _ack(self, rid: int, error: int, now: float) -> None:
        self._emit(bytes([p.IN_ACK, 0, 0, rid, error]), now + self.latency)

    # ---- what it receives ---------------------------------------------------------------

    def handle_output(self, data: bytes) -> bool:
        """One output report from the host. False when the link is down (the write fails)."""
        now = self.clock()
        self.pump(now)
        if not self.connected:
            return False
        data = bytes(data)
        self.outputs.append(data)
        if self.lose_outputs:  # lost on the air (tests set this)
            self.lose_outputs -= 1
            self._count("lost_output")
            return True
        if len(data) < 2:
            self._count("short_output")
            return True
        rid, b1 = data[0], data[1]
        self.rumble = bool(b1 & 0x01)  # every output report carries the motor bit
        ack = bool(b1 & 0x02)
        if rid == p.OUT_RUMBLE:
            pass  # never acked
        elif rid == p.OUT_LEDS:
            self.leds = b1 >> 4
            if ack:
                self._ack(rid, p.ERR_OK, now)
        elif rid == p.OUT_REPORT_MODE:
            if len(data) < 3 or data[2] not in p.DATA_LAYOUTS:
                self._count("invalid_mode")  # a real remote ignores the whole report
                return True
            self.mode, self.continuous = data[2], bool(b1 & 0x04)
            self._next_slot = self._slot_at(now) + 1
            if ack:
                self._ack(rid, p.ERR_OK, now)
        elif rid == p.OUT_STATUS_REQUEST:
            self._emit(self._status_report(), now + self.latency)
            if self.status_stops:
                self.mode = None
        elif rid == p.OUT_WRITE_MEMORY:
            self._write(data, now)
        elif rid == p.OUT_READ_MEMORY:
            self._read(data, now)
        elif rid in (p.OUT_IR_ENABLE, p.OUT_IR_ENABLE2, p.OUT_SPEAKER_ENABLE, p.OUT_SPEAKER_MUTE):
            if ack:
                self._ack(rid, p.ERR_OK, now)
        elif rid == p.OUT_SPEAKER_DATA:
            pass
        else:
            self._count("unknown_output")
        return True

    def _write(self, data: bytes, now: float) -> None:
        error = self.memory.write(data, self.nunchuk_plugged)
        if error is not None:
            self._ack(p.OUT_WRITE_MEMORY, error, now)

    def _read(self, data: bytes, now: float) -> None:
        for report, at in self.memory.read(data, self.nunchuk_plugged, now, self.latency):
            self._emit(report, at)


def data_report(mode: int, core: bytes, ext: bytes) -> bytes:
    """An input data report in `mode`: what of the core (buttons, accel) and the extension
    bytes the mode's layout carries."""
    has_buttons, has_accel, ext_off, ext_len = p.DATA_LAYOUTS[mode]
    body = bytearray(p.INPUT_REPORT_LENGTHS[mode])
    body[0] = mode
    if has_buttons:
        body[1:3] = core[:2]
    if has_accel:
        body[3:6] = core[2:]
    if ext_len:
        body[ext_off : ext_off + ext_len] = ext[:ext_len].ljust(ext_len, b"\0")
    return bytes(body)


def quantize(raw: np.ndarray, nine_bit_yz: bool = False) -> tuple[int, int, int]:
    """Raw float counts to what the sensor sends: nearest count in 0..1023; the Wiimote's Y and Z
    have 9 bits (their lowest bit is always 0), so they go to the nearest even count."""
    v = np.clip(np.rint(raw), 0, 1023).astype(int)
    if nine_bit_yz:
        v[1:] = np.clip(2 * np.rint(raw[1:] / 2), 0, 1022).astype(int)
    return int(v[0]), int(v[1]), int(v[2])


class EmulatedHidDevice:
    """`hid.device` for an emulated remote: open_path, set_nonblocking, read, write, close."""

    def __init__(self, bus: EmulatedBus):
        self.bus = bus
        self._remote: EmulatedWiimote | None = None
        self._connection = -1

    def open(self, vendor_id: int = 0, product_id: int = 0, serial_number: str | None = None) -> None:
        for r in self.bus.remotes:
            if r.connected and (not product_id or r.product_id == product_id):
                return self.open_path(r.path)
        raise OSError("open failed")

    def open_path(self, path: bytes) -> None:
        for r in self.bus.remotes:
            r.pump()
            if r.connected and r.path == path:
                self._remote, self._connection = r, r.connection
                return
        raise OSError("open failed")

    def set_nonblocking(self, v: int) -> int:
        return 0

    def _alive(self) -> EmulatedWiimote:
        r = self._remote
        if r is None:
            raise ValueError("not open")
        if r.loss == "silent" and not r.connected:
            return r
        if not r.connected or r.connection != self._connection:
            raise OSError("read error")  # hidraw: the node went away (ENODEV)
        return r

    def read(self, max_length: int, timeout_ms: int = 0) -> list[int]:
        r = self._alive()
        if not r.connected or r.connection != self._connection:
            return []  # silent loss: nothing arrives
        data = r.take(r.clock())
        return list(data[:max_length]) if data else []

    def write(self, buff: bytes) -> int:
        r = self._remote
        if r is None:
            raise ValueError("not open")
        data = bytes(buff)
        if self.bus.require_write_length and len(data) != self.bus.require_write_length:
            return -1  # Windows' stack rejects writes of another length
        if r.connection != self._connection:
            return -1
        if not r.connected:
            return len(data) if r.loss == "silent" else -1
        return len(data) if r.handle_output(data) else -1

    def close(self) -> None:
        self._remote = None

    def error(self) -> str:
        return ""

    def get_product_string(self) -> str:
        return "Nintendo RVL-CNT-01" if self._remote is None or self._remote.product_id == 0x0306 else "Nintendo RVL-CNT-01-TR"

    def get_manufacturer_string(self) -> str:
        return "Nintendo"

    def get_serial_number_string(self) -> str:
        return self._remote.serial if self._remote else ""


class EmulatedBus:
    """The `hid` / `hidraw` module stand-in: `enumerate` and `device`."""

    def __init__(self, remotes: list[EmulatedWiimote], require_write_length: int | None = None):
        self.remotes = remotes
        self.require_write_length = require_write_length

    def enumerate(self, vendor_id: int = 0, product_id: int = 0) -> list[dict[str, Any]]:
        out = []
        for r in self.remotes:
            r.pump()  # scheduled events (a re-plug) happen whoever looks
            visible = r.connected or r.loss == "silent"
            if not visible or (vendor_id and vendor_id != p.VENDOR_ID) or (product_id and product_id != r.product_id):
                continue
            out.append(
                {
                    "path": r.path,
                    "vendor_id": p.VENDOR_ID,
                    "product_id": r.product_id,
                    "serial_number": r.serial,
                    "release_number": 0,
                    "manufacturer_string": "Nintendo",
                    "product_string": "Nintendo RVL-CNT-01" + ("-TR" if r.product_id == 0x0330 else ""),
                    "usage_page": 1,
                    "usage": 5,
                    "interface_number": -1,
                }
            )
        return out

    def device(self) -> EmulatedHidDevice:
        return EmulatedHidDevice(self)

    def kernel_driver(self, path: bytes) -> str | None:
        for r in self.remotes:
            if r.path == path:
                return r.kernel_driver
        return None


def _times(params: dict[str, str], key: str, url: str) -> list[float]:
    try:
        times = [float(x) for x in params.get(key, "").split(",") if x.strip()]
    except ValueError:
        raise SourceError(f"{url}: {key} must be seconds (comma-separated)") from None
    if not all(0 <= t <= MAX_DURATION_S for t in times):  # also refuses nan
        raise SourceError(f"{url}: {key} must be seconds from 0 to {MAX_DURATION_S:g}")
    return times


def emulator_from_url(url: str, clock: Callable[[], float]) -> tuple[EmulatedBus, EmulatedWiimote, dict[str, str]]:
    _, path, params = parse_source_url(url)
    if not path:
        raise SourceError(f"{url}: no recording (expected wiimote-emu://path/to/recording.csv)")
    rec = read_recording(file_path(path))
    events = [(t, name) for key, name in (
        ("unplug_at", "unplug"), ("replug_at", "replug"), ("nunchuk_out_at", "nunchuk_out"),
        ("nunchuk_in_at", "nunchuk_in"), ("foreign_mode_at", "foreign_mode"),
    ) for t in _times(params, key, url)]  # fmt: skip
    clone = params.get("clone", "0").lower()
    clone = "" if clone in ("0", "false", "no", "off", "") else ("zeros" if clone == "zeros" else "garbage")
    loss = params.get("loss", "error")
    if loss not in ("error", "silent"):
        raise SourceError(f"{url}: loss must be 'error' or 'silent'")
    def num(key: str, default: float, lo: float, hi: float, integer: bool = False) -> float:
        try:
            return url_number(url, params, key, default, lo, hi, integer=integer)
        except SourceError as exc:  # worded as before: "bad option (drop must be ...)"
            raise SourceError(f"{url}: bad option ({str(exc).removeprefix(f'{url}: ')})") from None

    d = WiimoteEmulatorDef()  # the defaults of the options not given
    try:
        remote = EmulatedWiimote.from_def(rec, clock, WiimoteEmulatorDef(
            jitter_ms=num("jitter_ms", d.jitter_ms, 0, 1000), latency_ms=num("latency_ms", d.latency_ms, 0, 1000),
            pad=int(num("pad", d.pad, 0, MAX_PAD, integer=True)), drop=num("drop", d.drop, 0, 1), clone=clone,
            nunchuk=url_flag(params, "nunchuk", "1"), seed=int(num("seed", d.seed, 0, 2**63 - 1, integer=True)),
            loop=url_flag(params, "loop", "1"), loss=loss, kernel_driver=url_flag(params, "kernel_driver"),
            start=num("start", d.start, 0, MAX_DURATION_S), status_stops=url_flag(params, "status_stops"),
        ), events=events)  # fmt: skip
    except ValueError as exc:
        raise SourceError(f"{url}: bad option ({exc})") from None
    return EmulatedBus([remote]), remote, params


class EmulatedWiimoteSource(WiimoteSource):
    """The real driver on an emulated remote, which with `seconds` ends as a finite source
    does: a real remote never ends, so the end is the source's, not a report the emulator
    sends. Samples stamped from `seconds` on are not delivered; the driver is closed (rumble
    and LEDs off, as at any close) and the state is ENDED from then on."""

    def __init__(self, *, emulator: EmulatedWiimote, seconds: float | None = None, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self.emulator = emulator  # for tests
        # on the emulator's time line, as its `<event>_at` times are
        self.end_at = None if seconds is None else emulator.t0 + seconds

    def poll(self) -> list[Sample]:
        if self.state is SourceState.ENDED:
            return []
        out = super().poll()
        if self.end_at is not None and self.clock() >= self.end_at:
            out = [s for s in out if s.t < self.end_at]
            self.close()
            self.state = SourceState.ENDED
        return out


def open_emulated(url: str, clock: Callable[[], float]) -> EmulatedWiimoteSource:
    """`wiimote-emu://recording.csv?options`: the real driver on an emulated remote."""
    bus, remote, params = emulator_from_url(url, clock)
    player = int(url_number(url, params, "player", 1, 1, 4, integer=True))
    seconds = url_number(url, params, "seconds", 0, 0, MAX_DURATION_S, lo_open=True) if "seconds" in params else None
    source = EmulatedWiimoteSource(url=url, clock=clock, backend=bus, player=player, emulator=remote, seconds=seconds)
    source.description = f"wiimote-emu {remote.rec.meta.get('source', '')}".strip()
    # a row the reader left out (a cut last row), said by who opened it as for replay://; the
    # driver's own `notes` (the kernel driver, a clone's calibration) it logs itself
    source.file_notes = list(remote.rec.notes)
    return source
