"""The Wiimote + Nunchuk source: a state machine over the protocol and the transport.

Every `poll()` reads whatever reports are waiting (never waits), feeds them to the state
machine and returns samples of shape (2, 3) in g: row 0 the Wiimote (right hand), row 1 the
Nunchuk (left hand). The slow parts (status, calibration reads, extension set-up) are written
as generator scripts that yield what reply they wait for, so they advance one reply per poll
and the loop never blocks.

Life of a connection:
  scan -> open -> LEDs, status (0x15 -> 0x20) -> calibration (EEPROM 0x16, copy at 0x20,
  else typical values) -> extension: 0x55 -> A400F0, 0x00 -> A400FB, ID at A400FA, calibration
  at A40020 (else typical values) -> mode 12 04 35 -> streaming.
An extension plug/unplug arrives as a 0x20 and stops data reports: the extension part is
redone and the mode set again. Silence for PROBE_S sends a status request; silence for LOSS_S
(or a read error) means the remote is gone: state DISCONNECTED, rescans every RESCAN_S, state
RECONNECTING while a returned remote is set up again, CONNECTED when samples flow.
"""

from __future__ import annotations

import logging
from typing import Any

from engine.sensors.source import Clock, Sample, Source, SourceState
from engine.sensors.wiimote import protocol as p
from engine.sensors.wiimote.accel import CalibratedAccel
from engine.sensors.wiimote.scripts import DeviceGone, ScriptRunner
from engine.sensors.wiimote.setup import LOSS_S, PROBE_S, RemoteSetup
from engine.sensors.wiimote.transport import (
    HidTransport,
    TransportError,
    WiimoteInfo,
    list_wiimotes,
)

log = logging.getLogger(__name__)

REPORT_PERIOD_S = 0.01  # about 100 reports a second over PC Bluetooth
RESCAN_S = 1.0  # how often a lost or absent remote is looked for
MAX_READS_PER_POLL = 256  # more than a hidraw buffer (64) holds


class Rumble:
    """The motor: on until `until`; its bit rides on every output report meanwhile."""

    __slots__ = ("on", "until")

    def __init__(self) -> None:
        self.on = False
        self.until = 0.0

    def start(self, now: float, ms: int) -> None:
        until = now + ms / 1000.0
        self.until = max(self.until, until) if self.on else until
        self.on = True

    def due_off(self, now: float) -> bool:
        """True once, when the time is up (the motor is then off)."""
        if self.on and now >= self.until:
            self.on = False
            return True
        return False


def nunchuk_missing(extension: str) -> str:
    """`Source.missing` for a remote streaming with this extension: the Nunchuk, when there is
    none (never plugged in, or its plug slipped out mid-match) or another extension is in its
    place; the left hand then holds its last reading (1 g if none was ever plugged in)."""
    if extension == "nunchuk":
        return ""
    if extension == "unknown":
        return "the extension is not a Nunchuk: left-hand moves need one"
    return "no Nunchuk: plug it in for left-hand moves"


class WiimoteSource(Source):
    """`wiimote://` (first found) or `wiimote://<path>`; see the module docstring."""

    def __init__(
        self,
        *,
        url: str = "wiimote://",
        clock: Clock,
        backend: Any,
        path: bytes | None = None,
        player: int = 1,
        write_length: int | None = None,
        rescan_s: float = RESCAN_S,
    ):
        super().__init__(url=url, sensors=2, clock=clock, state=SourceState.DISCONNECTED, description="wiimote")
        self.rate_hz = 1.0 / REPORT_PERIOD_S
        self.backend = backend
        self.want_path = path
        self.leds = 1 << (max(1, min(4, player)) - 1)
        self.write_length = write_length
        self.rescan_s = rescan_s
        self.info: WiimoteInfo | None = None
        self.notes: list[str] = []  # things said once (clone calibration, kernel driver, ...)
        self.extension = "none"  # 'none', 'nunchuk', 'unknown'
        self.buttons = 0
        self.nunchuk: p.Nunchuk | None = None
        self.wiimote_calibration: p.Calibration | None = None
        self.nunchuk_calibration: p.Calibration | None = None
        self.battery_raw: int | None = None
        self.last_error = ""
        self._said: set[str] = set()
        self._transport: HidTransport | None = None
        self._serial = ""
        self._closed = False
        self._ever_connected = False
        self._scripts = ScriptRunner(self._send, self.count, self._lost)
        self._setup = RemoteSetup(self, self._scripts)
        self._accel = CalibratedAccel()
        self._streaming = False
        self._last_rx = 0.0
        self._probe_sent = False
        self._next_scan = -1e18
        self._rumble = Rumble()
        self._last_t = -1e18
        self._try_connect(self.clock())

    # ---- public -------------------------------------------------------------------------

    def poll(self) -> list[Sample]:
        if self._closed:
            return []
        now = self.clock()
        if self._transport is None:
            if now >= self._next_scan:
                self._try_connect(now)
            return []
        raw: list[bytes] = []
        try:
            while len(raw) < MAX_READS_PER_POLL:
                data = self._transport.read()
                if data is None:
                    break
                raw.append(data)
        except TransportError as exc:
            self._lost(now, f"read failed ({exc})")
            # reports read before the error still count
        if raw:
            self._last_rx = now
            self._probe_sent = False
        out: list[Sample] = []
        reports = [p.decode_report(r) for r in raw]
        n_data = sum(1 for r in reports if r.valid and r.accel is not None)
        i_data = 0
        for rep in reports:
            if rep.valid and rep.accel is not None:
                # Reports carry no timestamp: stamp on arrival. Those read together arrived
                # between the last poll and this one; spread them back at the report period.
                t = max(now - (n_data - 1 - i_data) * REPORT_PERIOD_S, self._last_t + 1e-6)
                i_data += 1
                sample = self._handle(rep, now, t)
            else:
                sample = self._handle(rep, now, now)
            if sample is not None:
                out.append(sample)
                self._last_t = sample.t
        if self._transport is not None:
            self._timers(now)
        return out

    def rumble(self, ms: int) -> None:
        """Vibrate for `ms` milliseconds; the motor bit rides on every output report meanwhile."""
        if self._transport is None or ms <= 0:
            return
        now = self.clock()
        self._rumble.start(now, ms)
        try:
            self._send(p.build_rumble(True))
        except DeviceGone:
            pass

    def missing(self) -> str:
        return nunchuk_missing(self.extension) if self.state is SourceState.CONNECTED else ""

    def close(self) -> None:
        """Rumble off, LEDs off, handle closed. Safe to call twice."""
        if self._transport is not None:
            self._rumble.on = False
            for report in (p.build_rumble(False), p.build_leds(0)):
                try:
                    self._transport.write(report)
                except TransportError:
                    break
            self._transport.close()
            self._transport = None
        self._closed = True
        self._scripts.stop()
        self._streaming = False
        self.state = SourceState.DISCONNECTED

    # ---- connection ---------------------------------------------------------------------

    def _say(self, key: str, message: str) -> None:
        """Say something once per source (a clone's calibration, the kernel driver...)."""
        if key in self._said:
            return
        self._said.add(key)
        self.notes.append(message)
        log.warning("%s: %s", self.url, message)

    def _try_connect(self, now: float) -> None:
        self._next_scan = now + self.rescan_s
        try:
            found = list_wiimotes(self.backend)
        except Exception as exc:  # noqa: BLE001 - a broken backend is a state, not a crash
            self.last_error = f"scan failed: {exc}"
            self.count("scan_errors")
            return
        info = pick_wiimote(found, self.want_path, self._serial)
        if info is None:
            self.last_error = "no Wiimote found"
            return
        transport = HidTransport(self.backend, info.path, self.write_length)
        try:
            transport.open()
        except TransportError as exc:
            self.last_error = str(exc)
            self.count("open_failures")
            return
        self.info = info
        self._serial = info.serial or self._serial
        self.description = f"wiimote {info.model}"
        if info.kernel_driver == "wiimote":
            self._say(
                "kernel",
                f"{info.path_str} is bound to the kernel's hid-wiimote driver, which sends its own "
                "mode changes; QuickJab re-asserts mode 0x35 (see docs/wiimote.md to unbind it)",
            )
        self._transport = transport
        self.state = SourceState.RECONNECTING if self._ever_connected else SourceState.CONNECTING
        self.count("opens")
        self._last_rx = now
        self._probe_sent = False
        self._setup.ext_flag = None
        self._streaming = False
        self._rumble.on = False
        self._scripts.start(self._setup.handshake(), now)

    def _lost(self, now: float, reason: str) -> None:
        if self._transport is not None:
            self._transport.close()
            self._transport = None
        self._scripts.stop()
        self._streaming = False
        self._rumble.on = False
        self.last_error = reason
        self.state = SourceState.DISCONNECTED
        self.count("disconnects")
        self._next_scan = now + min(self.rescan_s, 0.25)  # first look soon: it may be a blip
        log.info("%s: lost the Wiimote: %s", self.url, reason)

    # ---- I/O helpers --------------------------------------------------------------------

    def _send(self, report: bytes) -> None:
        if self._transport is None:
            raise DeviceGone
        try:
            self._transport.write(p.with_rumble(report, self._rumble.on))
        except TransportError as exc:
            self._lost(self.clock(), f"write failed ({exc})")
            raise DeviceGone from None
        self.count("sent")

    def _request_status(self, now: float) -> None:
        self._setup.request_status(now)

    # ---- reports ------------------------------------------------------------------------

    def _handle(self, rep: p.Report, now: float, t: float) -> Sample | None:
        self.count("reports")
        if not rep.valid:
            self.count("malformed")
            return None
        if rep.padded:
            self.count("padded")
        if rep.truncated:
            self.count("truncated")
        if rep.buttons is not None:
            self.buttons = rep.buttons
        if rep.report_id == p.IN_STATUS:
            self._setup.on_status(rep, now)
        self._scripts.offer(rep, now)
        if rep.report_id in p.DATA_LAYOUTS:
            return self._on_data(rep, now, t)
        return None

    def _on_data(self, rep: p.Report, now: float, t: float) -> Sample | None:
        self.count("data_reports")
        if not self._setup.on_data(rep, now):
            return None
        if rep.accel is None or not self._accel.ready:
            return None
        accel, nun = self._accel.rows(rep, self.count)
        if nun is not None:
            self.nunchuk = nun
        self.count("samples")
        if self._streaming and self._transport is not None and self.state is not SourceState.CONNECTED:
            self.state = SourceState.CONNECTED
            if self._ever_connected:
                self.count("reconnects")
            self._ever_connected = True
        return Sample(t, accel)

    def _timers(self, now: float) -> None:
        try:
            if self._rumble.due_off(now):
                self._send(p.build_rumble(False))
            self._scripts.expire(now)
            if self._transport is None:
                return
            silence = now - self._last_rx
            if silence >= LOSS_S:
                self._lost(now, f"no reports for {silence:.2f} s")
                return
            probe = silence >= PROBE_S and not self._probe_sent
            if probe:
                self._probe_sent = True
            self._setup.upkeep(now, probe)
        except DeviceGone:
            pass


def pick_wiimote(found: list[WiimoteInfo], want_path: bytes | None, serial: str) -> WiimoteInfo | None:
    """The remote to open: the one at `want_path` if given, else the same remote as before
    (by `serial`, maybe on a new /dev/hidrawN), else the first found."""
    if want_path:
        for info in found:
            if info.path == want_path:
                return info
    if serial:  # the same remote back, maybe on a new /dev/hidrawN
        for info in found:
            if info.serial == serial:
                return info
    if want_path:
        return None
    return found[0] if found else None
