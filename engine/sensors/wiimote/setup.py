"""Setting a connected Wiimote up and keeping it so: status, the Wiimote's calibration, the
extension (Nunchuk: initialised, identified, its calibration read) and the reporting mode, as
scripts run by the source's ScriptRunner; what a status report (0x20) changes in that set-up;
the battery refresh, and the mode set again when another driver changed it or data stopped."""

from __future__ import annotations

from typing import TYPE_CHECKING

from engine.sensors.wiimote import protocol as p
from engine.sensors.wiimote.scripts import DeviceGone, Script, ScriptRunner, SetupFailed

if TYPE_CHECKING:
    from engine.sensors.wiimote.driver import WiimoteSource

PROBE_S = 0.2  # silence after which a status request asks "are you there?"
LOSS_S = 0.45  # silence after which the remote is gone (the brief: detected within 0.5 s)
STATUS_EVERY_S = 10.0  # battery refresh (Dolphin does the same)
MODE_FIX_EVERY_S = 0.5  # at most this often re-assert our mode against another driver
# An extension the status says is plugged but that did not set up as a Nunchuk (an error, a
# half-inserted one's all-0xFF ID, another driver's reply taken for the ID) is tried again this
# often: Linux's hid-wiimote re-checks every 4 s (wiimote_init_check redoes the hot-plug).
EXT_RETRY_S = 4.0


class RemoteSetup:
    """The set-up half of a WiimoteSource: fills in its calibrations and extension, and keeps
    the mode and the battery reading up to date."""

    def __init__(self, source: WiimoteSource, runner: ScriptRunner) -> None:
        self.src = source
        self.runner = runner
        self.ext_flag: bool | None = None  # the last status's "extension connected" (None: no status yet)
        self.ext_dirty = False  # the extension changed while a script ran: set it up again
        self.status_solicited_until = -1.0  # a status before then is the answer to our request
        self.next_status = 0.0
        self.last_mode_fix = -1e18
        self.last_data = 0.0  # when a data report came (or was asked for by setting the mode)
        self.next_ext_check = 0.0  # when a plugged extension that is not a Nunchuk is tried again

    def handshake(self) -> Script:
        src, run = self.src, self.runner
        src._send(p.build_leds(src.leds))
        self.status_solicited_until = src.clock() + LOSS_S
        yield from run.request(p.build_status_request(), lambda r: r.report_id == p.IN_STATUS, "status request")
        cal = None
        for where in (p.EEPROM_CALIBRATION, p.EEPROM_CALIBRATION_COPY):
            block = yield from run.read_memory(where, 10)
            cal = p.parse_calibration(block) if block else None
            if cal is not None:
                if where != p.EEPROM_CALIBRATION:
                    src._say("wiimote-copy", "Wiimote calibration at 0x16 unreadable or unusable (a read error, its checksum or its 1 g point); using the copy at 0x20")
                break
        if cal is None:
            cal = p.WIIMOTE_TYPICAL
            src._say("wiimote-typical", "Wiimote calibration unreadable (a clone?); using typical values")
        src.wiimote_calibration = cal
        src._accel.set_wiimote(cal)
        yield from self.configure_extension()

    def configure_extension(self) -> Script:
        """(Re)detect the extension, set it up, then set the reporting mode (which a 0x20 stopped)."""
        src = self.src
        while True:
            self.ext_dirty = False
            if self.ext_flag:
                yield from self._init_extension()
            else:
                self._drop_extension()
            if not self.ext_dirty:
                break
        self.set_mode(src.clock())
        src._streaming = True
        self.next_status = src.clock() + STATUS_EVERY_S
        self.next_ext_check = src.clock() + EXT_RETRY_S

    def _drop_extension(self) -> None:
        src = self.src
        if src.extension != "none":
            src.count("extension_removed")
        src.extension = "none"
        src.nunchuk = None
        src.nunchuk_calibration = None
        src._accel.set_nunchuk(None)

    def _init_extension(self) -> Script:
        src, run = self.src, self.runner
        try:
            # Without encryption ("the new way"): 0x55 to A400F0, then 0x00 to A400FB.
            err = yield from run.write_register(p.EXT_INIT1, b"\x55")
            if not err:
                err = yield from run.write_register(p.EXT_INIT2, b"\x00")
            ident = None if err else (yield from run.read_memory(p.EXT_ID, 6))
        except SetupFailed:
            # An extension that never answers (a loose plug): the remote streams on without it and
            # it is tried again (EXT_RETRY_S), as Linux's hid-wiimote goes on and Dolphin retries;
            # the whole remote was dropped and reconnected over and over
            src.count("extension_timeouts")
            ident = None
        if ident is None or ident == b"\xff" * 6:  # all 0xFF: half inserted (Linux: none)
            src.count("extension_init_errors")
            self._drop_extension()  # unplugged again meanwhile, or it would not answer
            return
        if not p.is_nunchuk_id(ident):
            if src.extension != "unknown":  # tried again (EXT_RETRY_S): not removed meanwhile
                self._drop_extension()
            src.extension = "unknown"
            src._say(f"ext-{ident.hex()}", f"extension {ident.hex(' ')} is not a Nunchuk; ignoring it")
            return
        try:
            block = yield from run.read_memory(p.EXT_CALIBRATION, 16)
        except SetupFailed:  # as above: the Nunchuk is there, its calibration typical
            src.count("extension_timeouts")
            block = None
        cal = p.parse_nunchuk_calibration(block) if block else None
        if cal is None:
            cal = p.NUNCHUK_TYPICAL
            src._say("nunchuk-typical", "Nunchuk calibration unreadable or unusable (a read error, its checksums or its 1 g point; a clone?); using typical values")
        src.nunchuk_calibration = cal
        src._accel.set_nunchuk(cal)
        if src.extension != "nunchuk":
            src.count("nunchuk_plugged")
        src.extension = "nunchuk"

    def on_status(self, rep: p.Report, now: float) -> None:
        """A status report: the battery, and an extension plugged or unplugged (set it up
        again) or else a mode to set again."""
        src = self.src
        src.count("status")
        src.battery_raw = rep.battery
        src.battery = min(1.0, (rep.battery or 0) / p.BATTERY_FULL)
        solicited = now <= self.status_solicited_until
        self.status_solicited_until = -1.0
        changed = self.ext_flag is not None and rep.extension_connected != self.ext_flag
        self.ext_flag = bool(rep.extension_connected)
        if changed:
            src.count("extension_events")
            if not self.runner.running:
                self.runner.start(self.configure_extension(), now)
            else:
                self.ext_dirty = True
        elif src._streaming and not self.runner.running:
            # WiiBrew: after an unrequested 0x20 the mode must be set again; Linux's
            # hid-wiimote (handler_status_K) re-sends it after every 0x20, and so do we.
            if not solicited:
                src.count("unsolicited_status")
            try:
                self.set_mode(now)
            except DeviceGone:
                pass

    def request_status(self, now: float) -> None:
        self.status_solicited_until = now + LOSS_S
        self.src._send(p.build_status_request())

    def set_mode(self, now: float) -> None:
        self.last_mode_fix = now
        self.last_data = now  # data should follow from now on
        self.src._send(p.build_report_mode(p.MODE_CORE_ACCEL_EXT16, continuous=True))

    def on_data(self, rep: p.Report, now: float) -> bool:
        """A data report: if it is not in our mode while we stream, another driver changed the
        mode: say so and set ours again (at most every MODE_FIX_EVERY_S). False: the link is lost."""
        src = self.src
        self.last_data = now
        if rep.report_id != p.MODE_CORE_ACCEL_EXT16 and src._streaming and not self.runner.running:
            src.count("foreign_mode")
            src._say(
                "foreign-mode",
                f"data report 0x{rep.report_id:02X} while mode 0x35 was set: another driver "
                "(Linux hid-wiimote?) changes the mode; re-asserting it",
            )
            if now - self.last_mode_fix >= MODE_FIX_EVERY_S:
                try:
                    self.set_mode(now)
                except DeviceGone:
                    return False
        return True

    def upkeep(self, now: float, probe: bool) -> None:
        """Once a poll while connected: the probe (`probe`: silence asks "are you there?") or
        else the battery refresh, and the mode set again when data stopped. May raise DeviceGone."""
        src = self.src
        if probe:
            src.count("probes")
            self.request_status(now)
        elif src._streaming and not self.runner.running and now >= self.next_status:
            self.next_status = now + STATUS_EVERY_S
            self.request_status(now)
        if (
            src._streaming
            and not self.runner.running
            and now - self.last_data >= PROBE_S
            and now - self.last_mode_fix >= MODE_FIX_EVERY_S
        ):
            # It answers but sends no data: our mode report was lost, or something
            # stopped reporting. Ask again (no harm if it was only slow).
            src.count("mode_resent")
            self.set_mode(now)
        self._retry_extension(now)

    def _retry_extension(self, now: float) -> None:
        """Set up again an extension the status says is plugged that is not a Nunchuk yet."""
        src = self.src
        if (
            src._streaming
            and not self.runner.running
            and self.ext_flag
            and src.extension != "nunchuk"
            and now >= self.next_ext_check
        ):
            src.count("extension_retries")
            self.runner.start(self.configure_extension(), now)
