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
from collections.abc import Callable, Generator
from typing import Any

import numpy as np

from engine.sensors.source import Clock, Sample, Source, SourceState
from engine.sensors.wiimote import protocol as p
from engine.sensors.wiimote.transport import (
    HidTransport,
    TransportError,
    WiimoteInfo,
    list_wiimotes,
)

log = logging.getLogger(__name__)

REPORT_PERIOD_S = 0.01  # about 100 reports a second over PC Bluetooth
REPLY_TIMEOUT_S = 0.15  # a live Wiimote answers within a few tens of ms
REPLY_RETRIES = 2
PROBE_S = 0.2  # silence after which a status request asks "are you there?"
LOSS_S = 0.45  # silence after which the remote is gone (the brief: detected within 0.5 s)
RESCAN_S = 1.0  # how often a lost or absent remote is looked for
STATUS_EVERY_S = 10.0  # battery refresh (Dolphin does the same)
MODE_FIX_EVERY_S = 0.5  # at most this often re-assert our mode against another driver
MAX_READS_PER_POLL = 256  # more than a hidraw buffer (64) holds
REST = np.array([0.0, 0.0, 1.0])  # what a still, level sensor reads


class ReplyTimeout(Exception):
    """Thrown into a script when the reply it waits for does not come in time."""


class DeviceGone(Exception):
    """A write failed: the connection is already marked lost."""


class SetupFailed(Exception):
    """A script gave up (no reply after retries)."""


class Wait:
    """What a script waits for: a report matching `match`, within `timeout` seconds."""

    __slots__ = ("match", "timeout")

    def __init__(self, match: Callable[[p.Report], bool], timeout: float = REPLY_TIMEOUT_S):
        self.match = match
        self.timeout = timeout


Script = Generator[Wait, Any, Any]


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
        self._script: Script | None = None
        self._wait: Wait | None = None
        self._wait_deadline = 0.0
        self._ext_flag: bool | None = None
        self._ext_dirty = False
        self._streaming = False
        self._status_solicited_until = -1.0
        self._last_rx = 0.0
        self._last_data = 0.0
        self._probe_sent = False
        self._next_scan = -1e18
        self._next_status = 0.0
        self._last_mode_fix = -1e18
        self._rumble_on = False
        self._rumble_until = 0.0
        self._last_t = -1e18
        self._left = REST.copy()
        self._rz = self._rs = self._nz = self._ns = None  # calibration as arrays: zero, span
        self._try_connect(self.clock())

    # ---- public -------------------------------------------------------------------------

    @property
    def connected(self) -> bool:
        return self.state is SourceState.CONNECTED

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
        until = now + ms / 1000.0
        self._rumble_until = max(self._rumble_until, until) if self._rumble_on else until
        self._rumble_on = True
        try:
            self._send(p.build_rumble(True))
        except DeviceGone:
            pass

    def close(self) -> None:
        """Rumble off, LEDs off, handle closed. Safe to call twice."""
        if self._transport is not None:
            self._rumble_on = False
            for report in (p.build_rumble(False), p.build_leds(0)):
                try:
                    self._transport.write(report)
                except TransportError:
                    break
            self._transport.close()
            self._transport = None
        self._closed = True
        self._script = None
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

    def _pick(self, found: list[WiimoteInfo]) -> WiimoteInfo | None:
        if self.want_path:
            for info in found:
                if info.path == self.want_path:
                    return info
        if self._serial:  # the same remote back, maybe on a new /dev/hidrawN
            for info in found:
                if info.serial == self._serial:
                    return info
        if self.want_path:
            return None
        return found[0] if found else None

    def _try_connect(self, now: float) -> None:
        self._next_scan = now + self.rescan_s
        try:
            found = list_wiimotes(self.backend)
        except Exception as exc:  # noqa: BLE001 - a broken backend is a state, not a crash
            self.last_error = f"scan failed: {exc}"
            self.count("scan_errors")
            return
        info = self._pick(found)
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
        self._ext_flag = None
        self._streaming = False
        self._rumble_on = False
        self._start(self._handshake(), now)

    def _lost(self, now: float, reason: str) -> None:
        if self._transport is not None:
            self._transport.close()
            self._transport = None
        self._script = None
        self._wait = None
        self._streaming = False
        self._rumble_on = False
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
            self._transport.write(p.with_rumble(report, self._rumble_on))
        except TransportError as exc:
            self._lost(self.clock(), f"write failed ({exc})")
            raise DeviceGone from None
        self.count("sent")

    def _request_status(self, now: float) -> None:
        self._status_solicited_until = now + LOSS_S
        self._send(p.build_status_request())

    def _set_mode(self, now: float) -> None:
        self._last_mode_fix = now
        self._last_data = now  # data should follow from now on
        self._send(p.build_report_mode(p.MODE_CORE_ACCEL_EXT16, continuous=True))

    # ---- scripts ------------------------------------------------------------------------

    def _start(self, script: Script, now: float) -> None:
        self._script = script
        self._advance(now, None)

    def _advance(self, now: float, value: Any, error: BaseException | None = None) -> None:
        script = self._script
        if script is None:
            return
        try:
            wait = script.throw(error) if error is not None else script.send(value)
        except (StopIteration, DeviceGone):  # done, or the connection is already marked lost (or closed)
            if self._script is script:
                self._script = None
                self._wait = None
            return
        except SetupFailed as exc:
            self.count("setup_failures")
            self._lost(now, str(exc))
            return
        if self._script is script:
            self._wait = wait
            self._wait_deadline = now + wait.timeout

    def _request(self, report: bytes, match: Callable[[p.Report], bool], what: str) -> Script:
        for _ in range(REPLY_RETRIES + 1):
            self._send(report)
            try:
                return (yield Wait(match))
            except ReplyTimeout:
                self.count("timeouts")
        raise SetupFailed(f"no reply to {what}")

    def _write_register(self, address: int, data: bytes) -> Script:
        """Write and wait for the 0x22 ack; returns its error code."""
        rep = yield from self._request(
            p.build_write(address, data),
            lambda r: r.report_id == p.IN_ACK and r.acked_report == p.OUT_WRITE_MEMORY,
            f"write at {address:06X}",
        )
        return rep.error

    def _read_memory(self, address: int, size: int) -> Script:
        """Read `size` bytes in 16-byte replies; returns the bytes, or None on a read error."""
        for _ in range(REPLY_RETRIES + 1):
            buf = bytearray()
            self._send(p.build_read(address, size))
            try:
                while len(buf) < size:
                    offset = (address + len(buf)) & 0xFFFF
                    rep = yield Wait(lambda r, o=offset: r.report_id == p.IN_READ_REPLY and r.address == o)
                    if rep.error:
                        self.count("read_errors")
                        return None
                    buf += rep.payload
                return bytes(buf[:size])
            except ReplyTimeout:
                self.count("timeouts")
        raise SetupFailed(f"no reply to a read at {address:06X}")

    def _handshake(self) -> Script:
        self._send(p.build_leds(self.leds))
        self._status_solicited_until = self.clock() + LOSS_S
        yield from self._request(p.build_status_request(), lambda r: r.report_id == p.IN_STATUS, "status request")
        cal = None
        for where in (p.EEPROM_CALIBRATION, p.EEPROM_CALIBRATION_COPY):
            block = yield from self._read_memory(where, 10)
            cal = p.parse_calibration(block) if block else None
            if cal is not None:
                if where != p.EEPROM_CALIBRATION:
                    self._say("wiimote-copy", "Wiimote calibration at 0x16 failed its checksum; using the copy at 0x20")
                break
        if cal is None:
            cal = p.WIIMOTE_TYPICAL
            self._say("wiimote-typical", "Wiimote calibration unreadable (a clone?); using typical values")
        self.wiimote_calibration = cal
        self._rz, self._rs = self._arrays(cal)
        yield from self._configure_extension()

    def _configure_extension(self) -> Script:
        """(Re)detect the extension, set it up, then set the reporting mode (which a 0x20 stopped)."""
        while True:
            self._ext_dirty = False
            if self._ext_flag:
                yield from self._init_extension()
            else:
                self._drop_extension()
            if not self._ext_dirty:
                break
        self._set_mode(self.clock())
        self._streaming = True
        self._next_status = self.clock() + STATUS_EVERY_S

    def _drop_extension(self) -> None:
        if self.extension != "none":
            self.count("extension_removed")
        self.extension = "none"
        self.nunchuk = None
        self.nunchuk_calibration = None
        self._nz = self._ns = None

    def _init_extension(self) -> Script:
        # Without encryption ("the new way"): 0x55 to A400F0, then 0x00 to A400FB.
        err = yield from self._write_register(p.EXT_INIT1, b"\x55")
        if not err:
            err = yield from self._write_register(p.EXT_INIT2, b"\x00")
        ident = None if err else (yield from self._read_memory(p.EXT_ID, 6))
        if ident is None or ident == b"\xff" * 6:  # all 0xFF: half inserted (Linux: none)
            self.count("extension_init_errors")
            self._drop_extension()  # unplugged again meanwhile, or it would not answer
            return
        if not p.is_nunchuk_id(ident):
            self._drop_extension()
            self.extension = "unknown"
            self._say(f"ext-{ident.hex()}", f"extension {ident.hex(' ')} is not a Nunchuk; ignoring it")
            return
        block = yield from self._read_memory(p.EXT_CALIBRATION, 16)
        cal = p.parse_nunchuk_calibration(block) if block else None
        if cal is None:
            cal = p.NUNCHUK_TYPICAL
            self._say("nunchuk-typical", "Nunchuk calibration fails its checksum (a clone?); using typical values")
        self.nunchuk_calibration = cal
        self._nz, self._ns = self._arrays(cal)
        if self.extension != "nunchuk":
            self.count("nunchuk_plugged")
        self.extension = "nunchuk"

    @staticmethod
    def _arrays(cal: p.Calibration) -> tuple[np.ndarray, np.ndarray]:
        zero = np.asarray(cal.zero, dtype=np.float64)
        return zero, np.asarray(cal.one_g, dtype=np.float64) - zero

    # ---- reports ------------------------------------------------------------------------

    def _handle(self, rep: p.Report, now: float, t: float) -> Sample | None:
        self.count("reports")
        if not rep.valid:
            self.count("malformed")
            return None
        if rep.padded:
            self.count("padded")
        if rep.buttons is not None:
            self.buttons = rep.buttons
        if rep.report_id == p.IN_STATUS:
            self._on_status(rep, now)
        if self._wait is not None and self._wait.match(rep):
            self._wait = None
            self._advance(now, rep)
        if rep.report_id in p.DATA_LAYOUTS:
            return self._on_data(rep, now, t)
        return None

    def _on_status(self, rep: p.Report, now: float) -> None:
        self.count("status")
        self.battery_raw = rep.battery
        self.battery = min(1.0, (rep.battery or 0) / p.BATTERY_FULL)
        solicited = now <= self._status_solicited_until
        self._status_solicited_until = -1.0
        changed = self._ext_flag is not None and rep.extension_connected != self._ext_flag
        self._ext_flag = bool(rep.extension_connected)
        if changed:
            self.count("extension_events")
            if self._script is None:
                self._start(self._configure_extension(), now)
            else:
                self._ext_dirty = True
        elif self._streaming and self._script is None:
            # WiiBrew: after an unrequested 0x20 the mode must be set again; Linux's
            # hid-wiimote (handler_status_K) re-sends it after every 0x20, and so do we.
            if not solicited:
                self.count("unsolicited_status")
            try:
                self._set_mode(now)
            except DeviceGone:
                pass

    def _on_data(self, rep: p.Report, now: float, t: float) -> Sample | None:
        self.count("data_reports")
        self._last_data = now
        if rep.report_id != p.MODE_CORE_ACCEL_EXT16 and self._streaming and self._script is None:
            self.count("foreign_mode")
            self._say(
                "foreign-mode",
                f"data report 0x{rep.report_id:02X} while mode 0x35 was set: another driver "
                "(Linux hid-wiimote?) changes the mode; re-asserting it",
            )
            if now - self._last_mode_fix >= MODE_FIX_EVERY_S:
                try:
                    self._set_mode(now)
                except DeviceGone:
                    return None
        if rep.accel is None or self._rs is None:
            return None
        accel = np.empty((2, 3))
        accel[0] = (np.asarray(rep.accel, dtype=np.float64) - self._rz) / self._rs
        if self._ns is not None and rep.extension is not None and len(rep.extension) >= 6:
            nun = p.decode_nunchuk(rep.extension)
            if nun is not None:
                self.nunchuk = nun
                self._left = (np.asarray(nun.accel, dtype=np.float64) - self._nz) / self._ns
        else:
            self.count("samples_without_nunchuk")
        accel[1] = self._left  # held while no Nunchuk is plugged (REST until one ever was)
        self.count("samples")
        if self._streaming and self._transport is not None and self.state is not SourceState.CONNECTED:
            self.state = SourceState.CONNECTED
            if self._ever_connected:
                self.count("reconnects")
            self._ever_connected = True
        return Sample(t, accel)

    def _timers(self, now: float) -> None:
        try:
            if self._rumble_on and now >= self._rumble_until:
                self._rumble_on = False
                self._send(p.build_rumble(False))
            if self._wait is not None and now >= self._wait_deadline:
                self._wait = None
                self._advance(now, None, ReplyTimeout())
            if self._transport is None:
                return
            silence = now - self._last_rx
            if silence >= LOSS_S:
                self._lost(now, f"no reports for {silence:.2f} s")
                return
            if silence >= PROBE_S and not self._probe_sent:
                self._probe_sent = True
                self.count("probes")
                self._request_status(now)
            elif self._streaming and self._script is None and now >= self._next_status:
                self._next_status = now + STATUS_EVERY_S
                self._request_status(now)
            if (
                self._streaming
                and self._script is None
                and now - self._last_data >= PROBE_S
                and now - self._last_mode_fix >= MODE_FIX_EVERY_S
            ):
                # It answers but sends no data: our mode report was lost, or something
                # stopped reporting. Ask again (no harm if it was only slow).
                self.count("mode_resent")
                self._set_mode(now)
        except DeviceGone:
            pass
