"""Wiimote + Nunchuk over hidapi, as the `wiimote://` source, and its emulator `wiimote-emu://`.

- `protocol`: pure bytes in / reports out and report builders (the public API below).
- `transport`: a thin non-blocking wrapper over hidapi's `hidraw` (Linux) or `hid` module.
- `driver`: the state machine that turns reports into samples of shape (2, 3) in g.
  Its parts: `scripts` (set-up scripts that wait for replies, one per poll), `setup` (the
  set-up itself: calibration, extension, mode, battery), `accel` (counts to g).
- `emulator`: a protocol-faithful stand-in for `hid.device`, fed from a recording.
  Its parts: `emulated_memory` (EEPROM, Nunchuk registers), `emulated_queue` (reports in
  flight, the host's buffer), `playback` (the recording at each report slot).

URLs:
  wiimote://                  the first Wiimote found; error with pairing help if none
  wiimote:///dev/hidraw3      that device
  wiimote://?wait=1&player=2  no error when absent: the source waits (DISCONNECTED) and
                              connects when one appears; LED of player 2
  wiimote-emu://rec.csv?...   the emulator (see emulator.py for its options)
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from engine.sensors.source import (
    Clock,
    SourceError,
    parse_source_url,
    register_scheme,
    url_flag,
    url_number,
    url_params_known,
)
from engine.sensors.wiimote.protocol import (
    Calibration,
    Nunchuk,
    Report,
    build_ir_enable,
    build_ir_enable2,
    build_leds,
    build_read,
    build_report_mode,
    build_rumble,
    build_speaker_data,
    build_speaker_enable,
    build_speaker_mute,
    build_status_request,
    build_write,
    decode_nunchuk,
    decode_report,
    parse_calibration,
    parse_nunchuk_calibration,
)
from engine.sensors.wiimote.transport import (
    BackendMissing,
    HidTransport,
    hid_backend,
    list_wiimotes,
)

if TYPE_CHECKING:
    from engine.sensors.wiimote.driver import WiimoteSource


def __getattr__(name: str) -> object:
    """WiimoteSource is imported with its driver (and numpy) when first asked for: `quickjab
    devices` lists Wiimotes through the transport and needs neither."""
    if name == "WiimoteSource":
        from engine.sensors.wiimote.driver import WiimoteSource

        globals()["WiimoteSource"] = WiimoteSource
        return WiimoteSource
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


PAIRING_STEPS = (
    "pair one first: press the red SYNC button under the battery cover (or hold 1+2), then on "
    "Linux `bluetoothctl` -> scan on, pair/trust/connect <its address> (no PIN), and allow "
    "access to /dev/hidraw* with the udev rule in docs/wiimote.md; Windows/macOS and known-bad "
    "setups are in docs/wiimote.md."
)
WAIT_HINT = "wiimote://?wait=1 waits for one instead of failing"
PAIRING_HELP = f"{PAIRING_STEPS} `quickjab devices` lists what is seen; {WAIT_HINT}"


class WiimoteNotFound(SourceError):
    """`wiimote://` opened with no Wiimote attached (and no ?wait=1)."""


def open_wiimote(url: str, clock: Clock) -> WiimoteSource:
    from engine.sensors.wiimote.driver import WiimoteSource

    _, path, params = parse_source_url(url)
    url_params_known(url, params, ("player", "wait"))
    try:
        backend = hid_backend()
    except BackendMissing as exc:
        raise SourceError(f"{url}: {exc}") from None
    player = int(url_number(url, params, "player", 1, 1, 4, integer=True))
    source = WiimoteSource(
        url=url,
        clock=clock,
        backend=backend,
        path=path.encode() if path else None,
        player=player,
        write_length=HidTransport.default_write_length(),
    )
    if source.info is None and not url_flag(params, "wait"):
        source.close()
        where = f" at {path}" if path else ""
        if source.last_error and source.last_error != "no Wiimote found":
            raise WiimoteNotFound(f"{url}: a Wiimote is there but cannot be opened ({source.last_error}); "
                                  "check permissions (udev rule in docs/wiimote.md)")
        raise WiimoteNotFound(f"{url}: no Wiimote found{where} (vendor 057e, product 0306/0330); {PAIRING_HELP}")
    return source


def open_wiimote_emu(url: str, clock: Clock) -> WiimoteSource:
    from engine.sensors.wiimote.emulator import open_emulated

    return open_emulated(url, clock)


register_scheme("wiimote", open_wiimote)
register_scheme("wiimote-emu", open_wiimote_emu)

__all__ = [
    "Calibration",
    "Nunchuk",
    "PAIRING_HELP",
    "PAIRING_STEPS",
    "WAIT_HINT",
    "Report",
    "WiimoteNotFound",
    "WiimoteSource",
    "build_ir_enable",
    "build_ir_enable2",
    "build_leds",
    "build_read",
    "build_report_mode",
    "build_rumble",
    "build_speaker_data",
    "build_speaker_enable",
    "build_speaker_mute",
    "build_status_request",
    "build_write",
    "decode_nunchuk",
    "decode_report",
    "hid_backend",
    "list_wiimotes",
    "open_wiimote",
    "parse_calibration",
    "parse_nunchuk_calibration",
]
