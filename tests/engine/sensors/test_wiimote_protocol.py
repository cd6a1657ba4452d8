"""The pure protocol layer against byte layouts taken from the references (WiiBrew report
tables, Linux hid-wiimote-core.c handlers, Dolphin WiimoteReport.h / WiimoteEmu defaults)."""

from __future__ import annotations

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from engine.sensors.wiimote import (
    build_leds,
    build_read,
    build_report_mode,
    build_rumble,
    build_speaker_data,
    build_status_request,
    build_write,
    decode_nunchuk,
    decode_report,
    parse_calibration,
    parse_nunchuk_calibration,
)
from engine.sensors.wiimote import protocol as p


def test_status_report_fields():
    # (a1) 20 BB BB LF 00 00 VV: LF bit 1 extension, bit 0 battery low, bits 4-7 LEDs
    r = decode_report(bytes([0x20, 0x00, 0x08, 0x12, 0x00, 0x00, 0xC8]))
    assert r.valid and r.report_id == 0x20
    assert r.extension_connected is True and r.battery_low is False
    assert r.leds == 1 and r.battery == 200 and r.buttons == 0x0008
    r = decode_report(bytes([0x20, 0, 0, 0x81, 0, 0, 0x10]))
    assert r.extension_connected is False and r.battery_low is True and r.leds == 8


def test_read_reply_fields():
    # (a1) 21 BB BB SE AA AA DD*16: S = size-1 (high nibble), E = error (low nibble)
    data = bytes([0x21, 0, 0, 0x90, 0x00, 0x16]) + bytes(range(1, 17))
    r = decode_report(data)
    assert r.valid and r.size == 10 and r.error == 0 and r.address == 0x0016
    assert r.payload == bytes(range(1, 11))
    r = decode_report(bytes([0x21, 0, 0, 0xF7, 0x00, 0xFA]) + bytes(16))
    assert r.error == 7 and r.size == 16 and r.address == 0x00FA


def test_ack_fields():
    r = decode_report(bytes([0x22, 0, 0, 0x16, 0x07]))
    assert r.valid and r.acked_report == 0x16 and r.error == 7


def test_core_accel_bits():
    # X = a0 << 2 | byte0 bits 5-6; Y, Z = a << 2 | bit 1 from byte1 bits 5 and 6.
    b0 = 0x60 | 0x10  # both X low bits, plus the Plus button (bit 4)
    b1 = 0x20 | 0x08  # Y's low bit, plus the A button
    r = decode_report(bytes([0x31, b0, b1, 0x80, 0x81, 0x82]))
    assert r.accel == (0x80 << 2 | 3, 0x81 << 2 | 2, 0x82 << 2)
    assert r.buttons == 0x10 << 8 | 0x08  # accelerometer bits cleared
    r = decode_report(bytes([0x31, 0, 0x40, 1, 2, 3]))
    assert r.accel == (4, 8, 14)


def test_mode_35_extension_and_padding():
    ext = bytes(range(16))
    report = bytes([0x35, 0, 0, 0x80, 0x80, 0x9A]) + ext
    r = decode_report(report)
    assert r.valid and r.extension == ext and r.accel == (512, 512, 616) and not r.padded
    # Windows pads to 22 (already 22 here); stacks may append more: lengths come from the ID.
    r2 = decode_report(report + b"\xff\xff\xff")
    assert r2.valid and r2.padded and r2.extension == ext and r2.accel == r.accel
    short = decode_report(bytes([0x31, 0, 0, 1, 2]))  # 0x31 needs 6 bytes
    padded_short = decode_report(bytes([0x31, 0, 0, 1, 2, 3]).ljust(22, b"\0"))
    assert not short.valid and padded_short.valid and padded_short.padded


def test_invalid_inputs_never_raise():
    for data in (b"", [], None, [300], "xyz", bytes([0x99, 1, 2]), bytes([0x20]), bytes([0x21] * 5), object()):
        r = decode_report(data)  # type: ignore[arg-type]
        assert r.valid is False
    assert decode_report([0x30, 0x00, 0x01]).valid  # hidapi gives lists of ints


def test_nunchuk_decode():
    # byte 5: bits 6-7 Z low, 4-5 Y low, 2-3 X low, bit 1 C, bit 0 Z (active low)
    n = decode_nunchuk(bytes([0x7F, 0x81, 0x80, 0x90, 0xB3, 0b11_10_01_10]))
    assert n.stick == (0x7F, 0x81)
    assert n.accel == (0x80 << 2 | 1, 0x90 << 2 | 2, 0xB3 << 2 | 3)
    assert n.c is False and n.z is True
    assert decode_nunchuk(bytes([0, 0, 0, 0, 0, 0x00])).c is True
    assert decode_nunchuk(b"\x00\x01") is None


def test_nunchuk_id_is_bytes_4_and_5():
    # Linux (wiimote_cmd_read_ext) and Dolphin (ProcessExtensionID) decide on bytes 4-5 only:
    # 00 00 is a Nunchuk whatever bytes 0-3 say; 01 01 a Classic Controller, 01 03 a guitar.
    assert p.is_nunchuk_id(bytes.fromhex("0000a4200000"))  # Nintendo's
    assert p.is_nunchuk_id(bytes.fromhex("ff00a4210000"))  # other bytes 0-3
    assert p.is_nunchuk_id(bytes.fromhex("0000a4200000ff"))  # a longer read: the first 6 count
    for other in ("0000a4200101", "0000a4200103", "0000a4200405", "ffffffffffff", "fefe9a1efefe", "0000a42000"):
        assert not p.is_nunchuk_id(bytes.fromhex(other)), other


def test_wiimote_calibration_dolphin_default():
    body = bytes([0x80, 0x80, 0x80, 0x00, 0x9A, 0x9A, 0x9A, 0x00, 0x00])
    cal = parse_calibration(body + bytes([(0x55 + sum(body)) & 0xFF]))
    assert cal.zero == (512, 512, 512) and cal.one_g == (616, 616, 616)
    assert parse_calibration(body + bytes([(0x54 + sum(body)) & 0xFF])) is None
    assert parse_calibration(bytes(10)) is None and parse_calibration(b"\x01") is None


def test_calibration_low_bits():
    # low-bits byte: x in bits 4-5, y in 2-3, z in 0-1 (Dolphin AccelCalibrationPoint)
    body = bytes([0x80, 0x81, 0x82, 0b00_11_10_01, 0x9A, 0x9B, 0x9C, 0b00_01_00_10, 0x00])
    cal = parse_calibration(body + bytes([(0x55 + sum(body)) & 0xFF]))
    assert cal.zero == (0x80 << 2 | 3, 0x81 << 2 | 2, 0x82 << 2 | 1)
    assert cal.one_g == (0x9A << 2 | 1, 0x9B << 2 | 0, 0x9C << 2 | 2)


def test_nunchuk_calibration_checksums():
    body = bytes([0x80, 0x80, 0x80, 0, 0xB3, 0xB3, 0xB3, 0, 0xE0, 0x20, 0x80, 0xE0, 0x20, 0x80])
    s = sum(body)
    block = body + bytes([(0x55 + s) & 0xFF, (0xAA + s) & 0xFF])
    cal = parse_nunchuk_calibration(block)
    assert cal.zero == (512,) * 3 and cal.one_g == (716,) * 3
    assert cal.stick_max == (0xE0, 0xE0) and cal.stick_min == (0x20, 0x20) and cal.stick_center == (0x80, 0x80)
    assert parse_nunchuk_calibration(block[:15] + bytes([block[15] ^ 1])) is None
    assert parse_nunchuk_calibration(bytes([block[0] ^ 4]) + block[1:]) is None
    assert parse_nunchuk_calibration(bytes(16)) is None  # what some clones return
    assert parse_nunchuk_calibration(b"\xff" * 16) is None


def test_output_builders():
    assert build_report_mode() == bytes([0x12, 0x04, 0x35])
    assert build_report_mode(0x31, continuous=False, rumble=True) == bytes([0x12, 0x01, 0x31])
    assert build_leds(0b0001) == bytes([0x11, 0x10])
    assert build_leds(0b1001, rumble=True) == bytes([0x11, 0x91])
    assert build_status_request() == bytes([0x15, 0x00])
    assert build_rumble(True) == bytes([0x10, 0x01])
    assert build_read(0x0016, 10) == bytes([0x17, 0x00, 0x00, 0x00, 0x16, 0x00, 0x0A])
    assert build_read(0xA40020, 16) == bytes([0x17, 0x04, 0xA4, 0x00, 0x20, 0x00, 0x10])
    w = build_write(0xA400F0, b"\x55")
    assert w[:7] == bytes([0x16, 0x04, 0xA4, 0x00, 0xF0, 0x01, 0x55]) and len(w) == 22
    assert len(build_speaker_data(b"\x01\x02")) == 22
    assert p.with_rumble(build_leds(1), True) == bytes([0x11, 0x11])
    assert p.with_rumble(bytes([0x11, 0x11]), False) == bytes([0x11, 0x10])


def test_model_names():
    assert p.model_name(0x0306, "Nintendo RVL-CNT-01") == "RVL-CNT-01"
    assert p.model_name(0x0330, "Nintendo RVL-CNT-01-TR") == "RVL-CNT-01-TR"
    assert p.model_name(0x0330, "Nintendo RVL-CNT-01-UC") is None  # Wii U Pro Controller
    assert p.model_name(0x0306, "Nintendo RVL-WBC-01") is None  # Balance Board
    assert p.model_name(0x1234, "") is None


@given(st.integers(0, 1023), st.integers(0, 511), st.integers(0, 511), st.integers(0, 0xFFFF))
def test_core_roundtrip(x, y9, z9, buttons):
    accel = (x, y9 * 2, z9 * 2)
    body = p.encode_core(buttons, accel)
    r = decode_report(bytes([0x31]) + body)
    assert r.accel == accel
    assert r.buttons == buttons & 0x9F9F


@given(st.tuples(*[st.integers(0, 1023)] * 3), st.tuples(*[st.integers(0, 1023)] * 3), st.booleans(), st.booleans())
def test_nunchuk_roundtrip(accel, zero, c, z):
    n = decode_nunchuk(p.encode_nunchuk((12, 240), accel, c, z))
    assert n.accel == accel and n.c == c and n.z == z and n.stick == (12, 240)
    one_g = tuple((v + 100) % 1024 for v in zero)
    cal = p.Calibration(zero, one_g)
    assert parse_nunchuk_calibration(p.encode_nunchuk_calibration(cal)).zero == zero
    assert parse_calibration(p.encode_calibration(cal)).one_g == one_g


def test_calibration_to_g():
    cal = p.Calibration((500, 510, 520), (600, 610, 620))
    assert np.allclose(cal.to_g((600, 510, 420)), [1.0, 0.0, -1.0])
    assert np.allclose(cal.from_g([1.0, 0.0, -1.0]), [600, 510, 420])


def test_shortened_read_reply_from_an_off_brand_remote():
    # Dolphin (InputCommon/ControllerInterface/Wiimote/WiimoteController.cpp, ReportHandler::
    # AddHandler): 'Off-brand "NEW 2in1" Wii Remote likes to shorten read data replies'; it
    # zero-fills them. The 10-byte calibration read at 0x16 answered with 6 + 10 bytes:
    block = bytes([0x80, 0x80, 0x80, 0x00, 0x9A, 0x9A, 0x9A, 0x00, 0x00])
    block += bytes([(0x55 + sum(block)) & 0xFF])
    r = decode_report(bytes([0x21, 0x00, 0x00, 0x90, 0x00, 0x16]) + block)
    assert r.valid and r.size == 10 and r.error == 0 and r.address == 0x0016
    assert r.payload == block and r.truncated and not r.padded
    assert parse_calibration(r.payload).one_g == (616, 616, 616)
    # cut inside the data: what came, zero-filled (the checksum then decides)
    r = decode_report(bytes([0x21, 0, 0, 0x90, 0x00, 0x16]) + block[:4])
    assert r.valid and r.payload == block[:4] + bytes(6) and r.truncated
    # an error reply cut after its address still says which read failed
    r = decode_report(bytes([0x21, 0, 0, 0xF7, 0x00, 0xFA]))
    assert r.valid and r.error == 7 and r.address == 0x00FA
    # without the address it cannot be matched to a read: still malformed
    assert not decode_report(bytes([0x21, 0, 0, 0x90, 0x00])).valid
    assert not decode_report(bytes([0x21, 0, 0, 0x90, 0x00, 0x16]) + block).padded
