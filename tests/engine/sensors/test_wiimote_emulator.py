"""The emulator answers output reports the way the references describe a real remote
(Dolphin WiimoteEmu: HandleReadData / ProcessReadDataRequest / HandleWriteData /
ProcessExtensionPortEvent; WiiBrew), so the driver tested against it meets real behaviour;
and the driver recovers when the air loses its reports."""

from __future__ import annotations

import numpy as np

from engine.clock import VirtualClock
from engine.recording import Recording
from engine.sensors import SourceState
from engine.sensors.wiimote import WiimoteSource, decode_report
from engine.sensors.wiimote import protocol as p
from engine.sensors.wiimote.emulator import EmulatedBus, EmulatedWiimote

REC = Recording(np.arange(0, 1, 1 / 60), np.tile([[0.0, 0.0, 1.0], [0.0, 0.0, 1.0]], (60, 1, 1)))


def remote(**kw):
    vc = VirtualClock()
    return vc, EmulatedWiimote(REC, vc.seconds, jitter_ms=0, **kw)


def drain(vc, emu, seconds=0.1):
    vc.advance(int(seconds * 1e9))
    out = []
    while (data := emu.take(vc.seconds())) is not None:
        out.append(decode_report(data))
    return out


def test_read_in_16_byte_chunks_and_one_read_at_a_time():
    vc, emu = remote()
    emu.handle_output(p.build_read(0x0000, 40))
    # Refused while a read is in progress: Dolphin HandleReadData, "a real wm+ sends a busy
    # ack" (0x22 for 0x17, ErrorCode::Busy 4), and the first read goes on.
    emu.handle_output(p.build_read(0x0016, 10))
    out = drain(vc, emu)
    acks = [(r.acked_report, r.error) for r in out if r.report_id == p.IN_ACK]
    replies = [r for r in out if r.report_id == p.IN_READ_REPLY]
    assert acks == [(p.OUT_READ_MEMORY, p.ERR_BUSY)]
    assert [(r.address, r.size, r.error) for r in replies] == [(0x00, 16, 0), (0x10, 16, 0), (0x20, 8, 0)]
    assert replies[1].payload[6:16] == p.encode_calibration(emu.wiimote_cal)
    assert emu.stats["read_busy"] == 1


def test_read_errors():
    vc, emu = remote(nunchuk=False)
    emu.handle_output(p.build_read(0xA400FA, 6))  # nothing on the i2c bus: error 7
    (r1,) = drain(vc, emu)
    emu.handle_output(p.build_read(0x16F0, 0x20))  # past the EEPROM: error 8, just one reply
    rest = drain(vc, emu)
    assert (r1.error, r1.address) == (7, 0x00FA)
    assert len(rest) == 1 and rest[0].error == 8 and rest[0].size == 16


def test_writes_always_acked_others_only_when_asked():
    vc, emu = remote(nunchuk=False)
    emu.handle_output(p.build_write(0xA400F0, b"\x55"))  # no extension: ack with error 7
    emu.handle_output(p.build_leds(0b0011))  # no ack asked
    emu.handle_output(p.build_leds(0b0011, ack=True))
    emu.handle_output(p.build_report_mode(0x99))  # invalid mode: ignored entirely
    acks = [r for r in drain(vc, emu) if r.report_id == p.IN_ACK]
    assert [(a.acked_report, a.error) for a in acks] == [(0x16, 7), (0x11, 0)]
    assert emu.leds == 0b0011 and emu.mode is None and emu.stats["invalid_mode"] == 1


def test_extension_event_stops_reporting_until_mode_set():
    vc, emu = remote()
    emu.handle_output(p.build_report_mode())
    assert any(r.report_id == 0x35 for r in drain(vc, emu))
    emu.unplug_nunchuk()
    after = drain(vc, emu)
    assert [r.report_id for r in after if r.report_id == 0x20] == [0x20]
    assert after[-1].report_id == 0x20 and after[-1].extension_connected is False
    assert drain(vc, emu) == []  # silence until 0x12 again
    emu.handle_output(p.build_report_mode())
    assert len(drain(vc, emu)) >= 9


def test_nunchuk_data_scrambled_until_initialised():
    vc, emu = remote()
    emu.handle_output(p.build_report_mode())
    raw = drain(vc, emu)[-1].extension
    emu.handle_output(p.build_write(0xA400F0, b"\x55"))
    emu.handle_output(p.build_write(0xA400FB, b"\x00"))
    plain = [r for r in drain(vc, emu) if r.report_id == 0x35][-1].extension
    assert raw[:6] != plain[:6]
    assert plain[:6] == p.encode_nunchuk((0x80, 0x7F), emu.sent[-1].left)


def test_driver_recovers_lost_output_reports():
    vc = VirtualClock()
    emu = EmulatedWiimote(REC, vc.seconds)
    src = WiimoteSource(clock=vc.seconds, backend=EmulatedBus([emu]))
    # Lose the status request and, later, the mode report: retries and the mode watchdog cope.
    emu.lose_outputs = 1
    for _ in range(90):
        vc.advance(16_666_667)
        src.poll()
    assert src.state is SourceState.CONNECTED and src.stats["timeouts"] >= 1
    emu.unplug_nunchuk()
    emu.lose_outputs = 10**6  # everything the driver sends now is lost ...
    for _ in range(6):
        vc.advance(16_666_667)
        src.poll()
    emu.lose_outputs = 0  # ... for 0.1 s
    got = []
    for _ in range(90):
        vc.advance(16_666_667)
        got += src.poll()
    assert src.state is SourceState.CONNECTED and src.extension == "none" and len(got) > 50
    assert src.stats["probes"] >= 1  # the silence was noticed and the mode asked for again


def test_driver_sets_up_a_remote_that_shortens_its_read_replies():
    # An off-brand remote ("NEW 2in1", Dolphin WiimoteController.cpp) sends 0x21 replies cut
    # to their data (here the 10-byte EEPROM block and the 6-byte ID): the set-up must still
    # read the calibrations and the Nunchuk's ID.
    vc = VirtualClock()
    emu = EmulatedWiimote(REC, vc.seconds)
    take = emu.take

    def shortened(now):
        data = take(now)
        if data and data[0] == p.IN_READ_REPLY and not data[3] & 0x0F:
            data = data[: 6 + (data[3] >> 4) + 1]
        return data

    emu.take = shortened
    src = WiimoteSource(clock=vc.seconds, backend=EmulatedBus([emu]))
    for _ in range(60):
        vc.advance(16_666_667)
        src.poll()
    assert src.state is SourceState.CONNECTED and src.extension == "nunchuk"
    assert src.wiimote_calibration == emu.wiimote_cal and src.nunchuk_calibration == emu.nunchuk_cal
    assert src.stats["truncated"] >= 2 and not src.stats.get("malformed")


def test_uninitialised_nunchuk_reads_as_encrypted_with_the_zero_key():
    # WiiBrew (Wiimote/Extension Controllers; the older WiiLi page): with the all-zero key a
    # byte decrypts as (x ^ 0x17) + 0x17, so the extension sends (p - 0x17) ^ 0x17; the
    # Nunchuk's ID 00 00 at 0xA400FE reads FE FE encrypted. Dolphin's real-remote code
    # (WiimoteController.cpp) finds an uninitialised extension's ID unrecognisable.
    def decrypt(data):
        return bytes(((b ^ 0x17) + 0x17) & 0xFF for b in data)

    vc, emu = remote()
    emu.handle_output(p.build_report_mode())
    raw = [r for r in drain(vc, emu) if r.report_id == 0x35][-1].extension
    assert decrypt(raw[:6]) == p.encode_nunchuk((0x80, 0x7F), emu.sent[-1].left)
    emu.handle_output(p.build_read(p.EXT_ID, 6))
    ident = [r for r in drain(vc, emu) if r.report_id == 0x21][-1]
    assert ident.error == 0 and ident.payload == bytes.fromhex("fefe9a1efefe")
    assert decrypt(ident.payload) == bytes.fromhex("0000a4200000") and not p.is_nunchuk_id(ident.payload)


def test_a_nunchuk_that_never_answers_leaves_the_remote_streaming_and_is_tried_again():
    # A loose plug: the status says an extension is in, but its set-up writes get no ack. Three
    # unanswered tries dropped the whole remote, which reconnected and failed again, over and
    # over; Linux's hid-wiimote goes on without the extension and Dolphin retries it.
    vc = VirtualClock()
    emu = EmulatedWiimote(REC, vc.seconds)
    write = emu.memory.write
    emu.memory.write = lambda data, plugged: None if emu.deaf and data[2] >> 1 == 0x52 else write(data, plugged)
    emu.deaf = True
    src = WiimoteSource(clock=vc.seconds, backend=EmulatedBus([emu]))
    got = []
    for _ in range(180):  # 3 s
        vc.advance(16_666_667)
        got += src.poll()
    assert src.state is SourceState.CONNECTED and not src.stats.get("disconnects") and not src.stats.get("setup_failures")
    assert src.extension == "none" and src.missing().startswith("no Nunchuk") and len(got) > 100
    assert src.stats["extension_timeouts"] >= 1
    emu.deaf = False  # the plug seated: the next try (every 4 s) sets it up
    for _ in range(360):
        vc.advance(16_666_667)
        src.poll()
    assert src.extension == "nunchuk" and src.missing() == "" and not src.stats.get("disconnects")
