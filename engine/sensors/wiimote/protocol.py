"""The Wiimote's HID protocol as pure functions: bytes in, decoded reports out; reports to send, out.

Nothing here touches a device or a clock. Byte layouts follow the Linux hid-wiimote driver
(drivers/hid/hid-wiimote-core.c, hid-wiimote-modules.c), Dolphin (Core/HW/WiimoteCommon/
WiimoteReport.h, WiimoteEmu) and WiiBrew. Input reports are given as hidapi returns them: the
report ID first, then the payload, possibly padded (Windows pads to 22 bytes, some stacks and
clones append bytes). A report's length comes from its ID, never from the read; extra bytes
are ignored.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # numpy loads in the two Calibration methods that use it: `quickjab devices`
    import numpy as np  # reads VENDOR_ID and model names from here without it (~40 ms, ~15 MB)

VENDOR_ID = 0x057E
PRODUCT_IDS = {0x0306: "RVL-CNT-01", 0x0330: "RVL-CNT-01-TR"}
# Devices sharing the vendor/product IDs that are not Wiimotes, recognised by product name.
NOT_WIIMOTE_NAMES = ("RVL-CNT-01-UC", "Pro Controller", "RVL-WBC-01", "Balance Board")

# Output report IDs (host -> Wiimote).
OUT_RUMBLE = 0x10
OUT_LEDS = 0x11
OUT_REPORT_MODE = 0x12
OUT_IR_ENABLE = 0x13
OUT_SPEAKER_ENABLE = 0x14
OUT_STATUS_REQUEST = 0x15
OUT_WRITE_MEMORY = 0x16
OUT_READ_MEMORY = 0x17
OUT_SPEAKER_DATA = 0x18
OUT_SPEAKER_MUTE = 0x19
OUT_IR_ENABLE2 = 0x1A
OUTPUT_REPORT_LENGTH = 22  # the largest output report, ID included (what Windows wants written)

# Input report IDs (Wiimote -> host).
IN_STATUS = 0x20
IN_READ_REPLY = 0x21
IN_ACK = 0x22
MODE_CORE_ACCEL_EXT16 = 0x35  # buttons + accelerometer + 16 extension bytes

# An off-brand remote ("NEW 2in1") cuts its 0x21 replies short; Dolphin (WiimoteController.cpp,
# ReportHandler::AddHandler) zero-fills them: one is read if its address came (6 bytes).
READ_REPLY_MIN_LENGTH = 6
# Length of each input report including the ID byte (hid-wiimote-core.c handler table).
INPUT_REPORT_LENGTHS = {
    0x20: 7, 0x21: 22, 0x22: 5,
    0x30: 3, 0x31: 6, 0x32: 11, 0x33: 18, 0x34: 22, 0x35: 22, 0x36: 22, 0x37: 22,
    0x3D: 22, 0x3E: 22, 0x3F: 22,
}  # fmt: skip
# Data reports: (has core buttons, has accelerometer, extension offset, extension length).
# Offsets count the ID byte. 0x3E/0x3F interleave accel and IR over two reports: the
# accelerometer needs both halves, so it is not decoded from one.
DATA_LAYOUTS = {
    0x30: (True, False, 0, 0),
    0x31: (True, True, 0, 0),
    0x32: (True, False, 3, 8),
    0x33: (True, True, 0, 0),
    0x34: (True, False, 3, 19),
    0x35: (True, True, 6, 16),
    0x36: (True, False, 13, 9),
    0x37: (True, True, 16, 6),
    0x3D: (False, False, 1, 21),
    0x3E: (True, False, 0, 0),
    0x3F: (True, False, 0, 0),
}

# Read-reply / ack error codes (Dolphin ErrorCode, WiiBrew).
ERR_OK = 0
ERR_BUSY = 4  # a read (or write) during an active read
ERR_INVALID_SPACE = 6
ERR_NACK = 7  # nothing answered on the i2c bus: no extension plugged
ERR_INVALID_ADDRESS = 8

# Memory map.
EEPROM_CALIBRATION = 0x0016
EEPROM_CALIBRATION_COPY = 0x0020
EXT_CALIBRATION = 0xA40020
EXT_ID = 0xA400FA
EXT_INIT1 = 0xA400F0  # write 0x55 ...
EXT_INIT2 = 0xA400FB  # ... then 0x00: extension initialised without encryption
# The Nunchuk's ID is `00 00` in bytes 4..5 of the 6-byte ID at 0xA400FA (WiiBrew: "0x0000 at
# 0xa400fe"). Linux (hid-wiimote-core.c, wiimote_cmd_read_ext) and Dolphin (WiimoteController.cpp,
# ProcessExtensionID) look at those two bytes only: third-party Nunchuks differ in bytes 0..3.
NUNCHUK_ID_SUFFIX = bytes([0x00, 0x00])
# Status battery byte of fresh cells: wiiuse's WM_MAX_BATTERY_CODE. Others differ: Linux
# (hid-wiimote-core.c) reports byte * 100 / 255; Dolphin (WiimoteReport.h) fits the Home
# menu's bars, charge = byte * 2.46 / 255 - 0.013 (full near 0x69).
BATTERY_FULL = 0xC8


@dataclass(frozen=True)
class Report:
    """One decoded input report. Fields that the report type does not carry are None."""

    report_id: int
    valid: bool
    buttons: int | None = None  # byte0 << 8 | byte1, accelerometer bits 0x60 of each cleared
    accel: tuple[int, int, int] | None = None  # raw 10-bit counts
    extension: bytes | None = None
    battery: int | None = None  # 0x20: 0..255
    battery_low: bool | None = None
    extension_connected: bool | None = None
    leds: int | None = None  # 0..15
    error: int | None = None  # 0x21 error nibble, 0x22 error byte
    size: int | None = None  # 0x21: number of data bytes, 1..16
    address: int | None = None  # 0x21: 16-bit offset of the first byte
    payload: bytes | None = None  # 0x21: the `size` data bytes
    acked_report: int | None = None  # 0x22: the output report acknowledged
    padded: bool = False  # more bytes arrived than the report ID defines
    truncated: bool = False  # 0x21 cut short (off-brand remotes): the missing data read as zeros


def _as_bytes(data: object) -> bytes | None:
    if isinstance(data, bytes):
        return data
    try:
        return bytes(data)  # type: ignore[arg-type]  # lists of ints from hidapi, bytearrays
    except (TypeError, ValueError, OverflowError):
        return None


def _core_buttons(b0: int, b1: int) -> int:
    return ((b0 & ~0x60) & 0xFF) << 8 | ((b1 & ~0x60) & 0xFF)


def _core_accel(b0: int, b1: int, ax: int, ay: int, az: int) -> tuple[int, int, int]:
    # hid-wiimote-core.c handler_accel: X has two low bits in button byte 0 bits 5-6; Y and Z
    # have one (bit 1 of the 10-bit value) in button byte 1 bits 5 and 6.
    x = ax << 2 | (b0 >> 5) & 0x3
    y = ay << 2 | (b1 >> 4) & 0x2
    z = az << 2 | (b1 >> 5) & 0x2
    return x, y, z


def decode_report(data: bytes) -> Report:
    """Decode one input report as hidapi returns it (ID first, maybe padded). Never raises."""
    raw = _as_bytes(data)
    if not raw:
        return Report(report_id=-1, valid=False)
    rid = raw[0]
    length = INPUT_REPORT_LENGTHS.get(rid)
    truncated = rid == IN_READ_REPLY and READ_REPLY_MIN_LENGTH <= len(raw) < length
    if length is None or (len(raw) < length and not truncated):
        return Report(report_id=rid, valid=False)
    r = raw[:length].ljust(length, b"\0")
    padded = len(raw) > length
    if rid == IN_STATUS:
        flags = r[3]
        return Report(
            report_id=rid, valid=True, buttons=_core_buttons(r[1], r[2]), battery=r[6],
            battery_low=bool(flags & 0x01), extension_connected=bool(flags & 0x02),
            leds=flags >> 4, padded=padded,
        )  # fmt: skip
    if rid == IN_READ_REPLY:
        size = (r[3] >> 4) + 1
        return Report(
            report_id=rid, valid=True, buttons=_core_buttons(r[1], r[2]), error=r[3] & 0x0F,
            size=size, address=r[4] << 8 | r[5], payload=bytes(r[6 : 6 + size]), padded=padded,
            truncated=truncated,
        )  # fmt: skip
    if rid == IN_ACK:
        return Report(
            report_id=rid, valid=True, buttons=_core_buttons(r[1], r[2]), acked_report=r[3],
            error=r[4], padded=padded,
        )  # fmt: skip
    has_buttons, has_accel, ext_off, ext_len = DATA_LAYOUTS[rid]
    return Report(
        report_id=rid,
        valid=True,
        buttons=_core_buttons(r[1], r[2]) if has_buttons else None,
        accel=_core_accel(r[1], r[2], r[3], r[4], r[5]) if has_accel else None,
        extension=bytes(r[ext_off : ext_off + ext_len]) if ext_len else None,
        padded=padded,
    )


@dataclass(frozen=True)
class Nunchuk:
    stick: tuple[int, int]  # raw 0..255, about 128 at rest
    accel: tuple[int, int, int]  # raw 10-bit counts
    c: bool  # pressed
    z: bool  # pressed


def decode_nunchuk(ext: bytes) -> Nunchuk | None:
    """Decode the first 6 extension bytes of an unencrypted Nunchuk (hid-wiimote-modules.c
    wiimod_nunchuk_in_ext, without Motion Plus). None when fewer than 6 bytes are given."""
    raw = _as_bytes(ext)
    if raw is None or len(raw) < 6:
        return None
    b5 = raw[5]
    accel = (
        raw[2] << 2 | (b5 >> 2) & 0x3,
        raw[3] << 2 | (b5 >> 4) & 0x3,
        raw[4] << 2 | (b5 >> 6) & 0x3,
    )
    return Nunchuk(stick=(raw[0], raw[1]), accel=accel, c=not b5 & 0x02, z=not b5 & 0x01)


@dataclass(frozen=True)
class Calibration:
    """Two-point accelerometer calibration in raw 10-bit counts: g = (raw - zero) / (one_g - zero)."""

    zero: tuple[int, int, int]
    one_g: tuple[int, int, int]
    stick_min: tuple[int, int] | None = None  # Nunchuk only
    stick_max: tuple[int, int] | None = None
    stick_center: tuple[int, int] | None = None

    def to_g(self, raw: Iterable[int]) -> np.ndarray:
        import numpy as np

        zero = np.asarray(self.zero, dtype=np.float64)
        return (np.asarray(tuple(raw), dtype=np.float64) - zero) / (np.asarray(self.one_g, dtype=np.float64) - zero)

    def from_g(self, g: Iterable[float]) -> np.ndarray:
        """The raw counts (float, unrounded) a sensor with this calibration reads for `g`."""
        import numpy as np

        zero = np.asarray(self.zero, dtype=np.float64)
        return zero + np.asarray(tuple(g), dtype=np.float64) * (np.asarray(self.one_g, dtype=np.float64) - zero)


# Typical values when a device's own block is unusable (Dolphin WiimoteEmu: ACCEL_ZERO_G 0x80,
# ACCEL_ONE_G 0x9A for the Wiimote and 0xB3 for the Nunchuk, upper 8 bits of 10).
WIIMOTE_TYPICAL = Calibration(zero=(0x80 << 2,) * 3, one_g=(0x9A << 2,) * 3)
NUNCHUK_TYPICAL = Calibration(
    zero=(0x80 << 2,) * 3, one_g=(0xB3 << 2,) * 3,
    stick_min=(0x80 - 0x60,) * 2, stick_max=(0x80 + 0x60,) * 2, stick_center=(0x80, 0x80),
)  # fmt: skip


def _point(b: bytes, at: int) -> tuple[int, int, int]:
    # Three upper bytes then a byte of low bits: x in bits 4-5, y in 2-3, z in 0-1
    # (Dolphin AccelCalibrationPoint).
    low = b[at + 3]
    return (b[at] << 2 | (low >> 4) & 3, b[at + 1] << 2 | (low >> 2) & 3, b[at + 2] << 2 | low & 3)


def _encode_point(p: Iterable[int]) -> bytes:
    x, y, z = (int(v) & 0x3FF for v in p)
    return bytes([x >> 2, y >> 2, z >> 2, (x & 3) << 4 | (y & 3) << 2 | z & 3])


def _usable(zero: tuple[int, int, int], one_g: tuple[int, int, int]) -> bool:
    return all(o != z for o, z in zip(one_g, zero, strict=True))


def parse_calibration(block: bytes) -> Calibration | None:
    """The Wiimote's 10-byte block (EEPROM 0x16, copy at 0x20): zero-g point, 1-g point, a spare
    byte, checksum (0x55 + sum of the first 9) & 0xFF. None when the checksum fails or the
    block cannot convert (a 1-g point equal to the zero point)."""
    raw = _as_bytes(block)
    if raw is None or len(raw) < 10 or (0x55 + sum(raw[:9])) & 0xFF != raw[9]:
        return None
    zero, one_g = _point(raw, 0), _point(raw, 4)
    return Calibration(zero, one_g) if _usable(zero, one_g) else None


def parse_nunchuk_calibration(block: bytes) -> Calibration | None:
    """The Nunchuk's 16 bytes at 0xA40020: zero-g point, 1-g point, stick x max/min/center, stick
    y max/min/center, then two checksums, byte 14 = 0x55 + sum of the first 14 and byte 15 =
    0xAA + the same sum (Dolphin UpdateCalibrationDataChecksum). None when either fails or the
    block cannot convert."""
    raw = _as_bytes(block)
    if raw is None or len(raw) < 16:
        return None
    s = sum(raw[:14])
    if (0x55 + s) & 0xFF != raw[14] or (0xAA + s) & 0xFF != raw[15]:
        return None
    zero, one_g = _point(raw, 0), _point(raw, 4)
    if not _usable(zero, one_g):
        return None
    return Calibration(
        zero, one_g, stick_max=(raw[8], raw[11]), stick_min=(raw[9], raw[12]), stick_center=(raw[10], raw[13])
    )


def encode_calibration(cal: Calibration, spare: int = 0) -> bytes:
    """The 10-byte EEPROM block for `cal`, checksum included (what a genuine Wiimote stores)."""
    body = _encode_point(cal.zero) + _encode_point(cal.one_g) + bytes([spare & 0xFF])
    return body + bytes([(0x55 + sum(body)) & 0xFF])


def encode_nunchuk_calibration(cal: Calibration) -> bytes:
    """The 16-byte Nunchuk calibration block for `cal`, both checksums included."""
    smax = cal.stick_max or (0xE0, 0xE0)
    smin = cal.stick_min or (0x20, 0x20)
    sc = cal.stick_center or (0x80, 0x80)
    body = _encode_point(cal.zero) + _encode_point(cal.one_g)
    body += bytes([smax[0], smin[0], sc[0], smax[1], smin[1], sc[1]])
    s = sum(body)
    return body + bytes([(0x55 + s) & 0xFF, (0xAA + s) & 0xFF])


def encode_core(buttons: int, accel: Iterable[int]) -> bytes:
    """The 5 bytes after the ID of a buttons+accelerometer report (inverse of decode_report)."""
    x, y, z = (int(v) & 0x3FF for v in accel)
    b0 = (buttons >> 8) & 0x9F | (x & 3) << 5
    b1 = buttons & 0x9F | (y >> 1 & 1) << 5 | (z >> 1 & 1) << 6
    return bytes([b0, b1, x >> 2, y >> 2, z >> 2])


def encode_nunchuk(stick: tuple[int, int], accel: Iterable[int], c: bool = False, z: bool = False) -> bytes:
    """The 6 unencrypted Nunchuk bytes (inverse of decode_nunchuk)."""
    ax, ay, az = (int(v) & 0x3FF for v in accel)
    b5 = (az & 3) << 6 | (ay & 3) << 4 | (ax & 3) << 2 | (0 if c else 0x02) | (0 if z else 0x01)
    return bytes([stick[0] & 0xFF, stick[1] & 0xFF, ax >> 2, ay >> 2, az >> 2, b5])


# ---- output reports ---------------------------------------------------------------------
# Byte 1 bit 0 of every output report is the rumble motor: it must stay set while rumbling,
# or any report (an LED change, a status request) stops the motor. Bit 1 asks for an ack
# (0x22) on reports that otherwise send none.


def _flags(rumble: bool, ack: bool = False) -> int:
    return (0x01 if rumble else 0) | (0x02 if ack else 0)


def build_rumble(on: bool) -> bytes:
    return bytes([OUT_RUMBLE, _flags(on)])


def build_leds(leds: int, rumble: bool = False, ack: bool = False) -> bytes:
    """LEDs 1-4 as bits 0-3 of `leds` (sent in bits 4-7)."""
    return bytes([OUT_LEDS, (leds & 0x0F) << 4 | _flags(rumble, ack)])


def build_report_mode(mode: int = MODE_CORE_ACCEL_EXT16, continuous: bool = True, rumble: bool = False, ack: bool = False) -> bytes:
    """`12 04 35`: send reports `mode` continuously (about 100 a second), not only on change."""
    return bytes([OUT_REPORT_MODE, (0x04 if continuous else 0) | _flags(rumble, ack), mode & 0xFF])


def build_status_request(rumble: bool = False) -> bytes:
    return bytes([OUT_STATUS_REQUEST, _flags(rumble)])


def _enable(rid: int, on: bool, rumble: bool, ack: bool) -> bytes:
    return bytes([rid, (0x04 if on else 0) | _flags(rumble, ack)])


def build_ir_enable(on: bool, rumble: bool = False, ack: bool = False) -> bytes:
    return _enable(OUT_IR_ENABLE, on, rumble, ack)


def build_ir_enable2(on: bool, rumble: bool = False, ack: bool = False) -> bytes:
    return _enable(OUT_IR_ENABLE2, on, rumble, ack)


def build_speaker_enable(on: bool, rumble: bool = False, ack: bool = False) -> bytes:
    return _enable(OUT_SPEAKER_ENABLE, on, rumble, ack)


def build_speaker_mute(on: bool, rumble: bool = False, ack: bool = False) -> bytes:
    return _enable(OUT_SPEAKER_MUTE, on, rumble, ack)


def build_speaker_data(data: bytes, rumble: bool = False) -> bytes:
    """Up to 20 bytes of speaker samples; length in bits 3-7 of byte 1."""
    data = bytes(data[:20])
    return bytes([OUT_SPEAKER_DATA, len(data) << 3 | _flags(rumble)]) + data.ljust(20, b"\0")


def _space(address: int, eeprom: bool | None) -> int:
    # Address space bits 2-3 of byte 1: 0 EEPROM, 1 (0x04) control registers / i2c bus.
    if eeprom is None:
        eeprom = address <= 0xFFFF
    return 0x00 if eeprom else 0x04


def build_write(address: int, data: bytes, eeprom: bool | None = None, rumble: bool = False) -> bytes:
    """Write 1-16 bytes at a 24-bit address (0x16; the Wiimote always acks with 0x22).
    `eeprom` None picks EEPROM for addresses up to 0xFFFF, registers (0xA4xxxx) above."""
    data = bytes(data)
    if not 1 <= len(data) <= 16:
        raise ValueError(f"a write carries 1-16 bytes, not {len(data)}")
    a = address & 0xFFFFFF
    head = [OUT_WRITE_MEMORY, _space(address, eeprom) | _flags(rumble), a >> 16, a >> 8 & 0xFF, a & 0xFF, len(data)]
    return bytes(head) + data.ljust(16, b"\0")


def build_read(address: int, size: int, eeprom: bool | None = None, rumble: bool = False) -> bytes:
    """Read `size` bytes at a 24-bit address (0x17); answered by 0x21 replies of up to 16 bytes."""
    if not 1 <= size <= 0xFFFF:
        raise ValueError(f"a read asks for 1-65535 bytes, not {size}")
    a = address & 0xFFFFFF
    return bytes([OUT_READ_MEMORY, _space(address, eeprom) | _flags(rumble), a >> 16, a >> 8 & 0xFF, a & 0xFF, size >> 8, size & 0xFF])


def with_rumble(report: bytes, on: bool) -> bytes:
    """`report` with byte 1 bit 0 set or cleared: how a driver keeps the motor state on every report."""
    if len(report) < 2:
        return report
    return bytes([report[0], (report[1] & 0xFE) | (0x01 if on else 0)]) + report[2:]


def is_nunchuk_id(ident: bytes) -> bool:
    """A 6-byte extension ID (0xA400FA) naming a Nunchuk: `.. .. .. .. 00 00` (Nintendo's
    is `00 00 A4 20 00 00`)."""
    return len(ident) >= 6 and bytes(ident[4:6]) == NUNCHUK_ID_SUFFIX


def model_name(product_id: int, product_string: str | None = "") -> str | None:
    """The Wiimote model for a HID device, or None when it is not a Wiimote (e.g. a Wii U Pro
    Controller, which shares product ID 0x0330, or a Balance Board)."""
    name = product_string or ""
    if product_id not in PRODUCT_IDS or any(bad.lower() in name.lower() for bad in NOT_WIIMOTE_NAMES):
        return None
    return PRODUCT_IDS[product_id]
