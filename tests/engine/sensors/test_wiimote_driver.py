"""Whole sessions of the real driver against the emulator, on a virtual clock: start-up
sequence, data checked against the recording that fed the emulator (within one count),
Nunchuk unplug/plug mid-stream, padded reports, clone calibration, dropped reports,
disconnect and reconnect, rumble, battery, clean close."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from engine.clock import VirtualClock
from engine.recording import Recording, read_recording, write_recording
from engine.sensors import SourceError, SourceState, open_source
from engine.sensors.wiimote import WiimoteNotFound, WiimoteSource
from engine.sensors.wiimote import protocol as p
from engine.sensors.wiimote.emulator import EmulatedBus, EmulatedWiimote

STEP_NS = 16_666_667  # the game's 60 Hz step


@pytest.fixture(scope="module")
def rec_path(tmp_path_factory) -> Path:
    """Four seconds of two-hand motion inside both sensors' ranges (Nunchuk: about ±2.5 g)."""
    t = np.arange(0, 4, 1 / 60)
    a = np.empty((len(t), 2, 3))
    a[:, 0, 0] = 2.5 * np.sin(2 * np.pi * 1.3 * t)
    a[:, 0, 1] = -0.4 + 0.8 * np.cos(2 * np.pi * 0.7 * t)
    a[:, 0, 2] = 1.0 + 1.5 * np.sin(2 * np.pi * 2.1 * t + 0.3)
    a[:, 1, 0] = 1.2 * np.sin(2 * np.pi * 0.9 * t + 1.0)
    a[:, 1, 1] = 0.3 - 0.9 * np.sin(2 * np.pi * 1.7 * t)
    a[:, 1, 2] = 0.8 + 0.6 * np.cos(2 * np.pi * 1.1 * t)
    path = tmp_path_factory.mktemp("wiimote") / "rec.csv"
    write_recording(path, Recording(t, a))
    return path


def session(url: str, seconds: float, vc: VirtualClock | None = None, actions=None):
    """Open `url` on a virtual clock and poll at 60 Hz for `seconds`. `actions` maps a step
    index to a callable(source) run before that step's poll. Returns (source, samples, states)."""
    vc = vc or VirtualClock()
    src = open_source(url, clock=vc.seconds)
    samples, states = [], [(0.0, src.state)]
    for step in range(int(round(seconds * 60))):
        vc.advance(STEP_NS)
        if actions and step in actions:
            actions[step](src)
        samples += src.poll()
        if src.state is not states[-1][1]:
            states.append((vc.seconds(), src.state))
    return src, samples, states


def expected(rec: Recording, t: float) -> np.ndarray:
    rel = rec.t - rec.t[0]
    return np.array([[np.interp(t, rel, rec.accel[:, s, a]) for a in range(3)] for s in range(2)])


def check_against_recording(src, samples, rec: Recording, check_left: bool = True) -> int:
    """Every sample matches the recording value the emulator encoded, within one count. Returns
    how many left-hand (Nunchuk) values were checked."""
    emu = src.emulator
    read = [s for s in emu.sent if s.read_at is not None]
    assert len(samples) == len(read) > 0
    wcal, ncal = src.wiimote_calibration, src.nunchuk_calibration
    one_r = 1.0 / (np.asarray(wcal.one_g) - np.asarray(wcal.zero))
    checked_left = 0
    last_left = None
    for sample, sent in zip(samples, read, strict=True):
        assert sample.accel.shape == (2, 3)
        exp = expected(rec, sent.rec_time)
        assert np.all(np.abs(sample.accel[0] - exp[0]) <= one_r + 1e-9), (sample, exp, sent)
        if sent.left is not None and src.nunchuk_calibration is not None and check_left:
            one_l = 1.0 / (np.asarray(ncal.one_g) - np.asarray(ncal.zero))
            assert np.all(np.abs(sample.accel[1] - exp[1]) <= one_l + 1e-9), (sample, exp, sent)
            checked_left += 1
        elif last_left is not None and sent.left is None:
            assert np.array_equal(sample.accel[1], last_left)  # held while unplugged
        last_left = sample.accel[1].copy()
    ts = [s.t for s in samples]
    assert all(b > a for a, b in zip(ts, ts[1:], strict=False))  # stamped on arrival, strictly increasing
    return checked_left


def test_startup_sequence_and_data(rec_path):
    src, samples, states = session(f"wiimote-emu://{rec_path}?jitter_ms=3", 2.0)
    emu = src.emulator
    # The exact start-up sequence on the wire (rumble bit clear throughout).
    assert emu.outputs[:8] == [
        bytes([0x11, 0x10]),  # LED 1 for player 1
        bytes([0x15, 0x00]),  # status request
        bytes([0x17, 0x00, 0x00, 0x00, 0x16, 0x00, 0x0A]),  # calibration, EEPROM 0x16
        p.build_write(0xA400F0, b"\x55"),  # extension init without encryption
        p.build_write(0xA400FB, b"\x00"),
        bytes([0x17, 0x04, 0xA4, 0x00, 0xFA, 0x00, 0x06]),  # extension ID
        bytes([0x17, 0x04, 0xA4, 0x00, 0x20, 0x00, 0x10]),  # Nunchuk calibration
        bytes([0x12, 0x04, 0x35]),  # continuous buttons + accel + 16 extension bytes
    ]
    assert [s for _, s in states] == [SourceState.CONNECTING, SourceState.CONNECTED]
    assert states[1][0] < 0.3  # set-up took a few round trips
    assert emu.leds == 0b0001 and emu.ext_stage == 2 and src.extension == "nunchuk"
    # The driver used the remote's own calibration, not the typical values.
    assert src.wiimote_calibration == emu.wiimote_cal and src.nunchuk_calibration == emu.nunchuk_cal
    assert check_against_recording(src, samples, read_recording(rec_path)) == len(samples)
    assert 170 <= len(samples) <= 200  # ~100 reports a second
    assert "malformed" not in src.stats and "timeouts" not in src.stats
    assert src.battery == pytest.approx(0xB4 / 0xC8) and src.notes == []
    assert src.stats["samples"] == len(samples)


def test_nunchuk_unplug_and_plug_mid_stream(rec_path):
    src, samples, _ = session(f"wiimote-emu://{rec_path}?nunchuk_out_at=0.8&nunchuk_in_at=1.6", 2.6)
    emu = src.emulator
    assert src.stats["extension_events"] == 2
    assert src.stats["nunchuk_plugged"] == 2 and src.stats["extension_removed"] == 1
    assert emu.outputs.count(bytes([0x12, 0x04, 0x35])) == 3  # mode set again after each 0x20
    assert src.extension == "nunchuk" and src.state is SourceState.CONNECTED
    read = [s for s in emu.sent if s.read_at is not None]
    without = [s for s in read if s.left is None]
    assert len(without) > 50  # the Wiimote kept streaming between the two events
    checked = check_against_recording(src, samples, read_recording(rec_path))
    assert checked == len(read) - len(without)
    # After re-plugging, the driver initialised the new Nunchuk before trusting its bytes.
    assert emu.ext_stage == 2


def test_the_source_says_the_nunchuk_is_missing_while_it_is_out(rec_path):
    # the remote streams on without it (the left hand reads a still 1 g): the game shows this
    seen = {}
    actions = {step: (lambda src, step=step: seen.setdefault(step, src.missing())) for step in (30, 70, 140)}
    src, _, _ = session(f"wiimote-emu://{rec_path}?nunchuk_out_at=0.8&nunchuk_in_at=1.6", 2.6, actions=actions)
    assert seen[30] == "" and seen[140] == "" and src.missing() == ""  # before, and plugged in again
    assert seen[70].startswith("no Nunchuk"), seen  # 1.17 s: out
    absent, _, _ = session(f"wiimote-emu://{rec_path}?nunchuk=0", 1.0)
    assert absent.missing().startswith("no Nunchuk")


def test_nunchuk_absent_from_start(rec_path):
    src, samples, _ = session(f"wiimote-emu://{rec_path}?nunchuk=0", 1.0)
    assert src.extension == "none" and src.state is SourceState.CONNECTED
    assert all(np.array_equal(s.accel[1], [0.0, 0.0, 1.0]) for s in samples)
    assert src.stats["samples_without_nunchuk"] == len(samples)
    check_against_recording(src, samples, read_recording(rec_path))


def test_padded_reports(rec_path):
    src, samples, _ = session(f"wiimote-emu://{rec_path}?pad=22", 1.5)
    assert src.stats["padded"] > 0  # status (7), ack (5) padded to 22
    check_against_recording(src, samples, read_recording(rec_path))
    src2, samples2, _ = session(f"wiimote-emu://{rec_path}?pad=30", 1.0)
    assert src2.stats["padded"] >= len(samples2)
    check_against_recording(src2, samples2, read_recording(rec_path))


@pytest.mark.parametrize("clone", ["1", "zeros"])
def test_clone_calibration_falls_back_once(rec_path, clone):
    src, samples, _ = session(f"wiimote-emu://{rec_path}?clone={clone}&nunchuk_out_at=0.5&nunchuk_in_at=0.9", 1.5)
    assert src.nunchuk_calibration == p.NUNCHUK_TYPICAL
    said = [n for n in src.notes if "Nunchuk calibration" in n]
    assert len(said) == 1  # said once, though the Nunchuk was set up twice
    if clone == "1":  # the primary EEPROM block is bad too: the copy at 0x20 is used
        assert any("copy at 0x20" in n for n in src.notes)
        assert src.wiimote_calibration == src.emulator.wiimote_cal
    assert check_against_recording(src, samples, read_recording(rec_path)) > 0


def test_dropped_reports_and_jitter(rec_path):
    src, samples, _ = session(f"wiimote-emu://{rec_path}?drop=0.2&jitter_ms=8&seed=3", 2.0)
    emu = src.emulator
    assert emu.stats["dropped"] > 20
    check_against_recording(src, samples, read_recording(rec_path))


@pytest.mark.parametrize("loss", ["error", "silent"])
def test_disconnect_detected_and_reconnect(rec_path, loss):
    vc = VirtualClock()
    url = f"wiimote-emu://{rec_path}?loss={loss}&unplug_at=1.0&replug_at=2.0"
    src, samples, states = session(url, 3.5, vc)
    kinds = [s for _, s in states]
    assert kinds[:3] == [SourceState.CONNECTING, SourceState.CONNECTED, SourceState.DISCONNECTED]
    lost_at = states[2][0]
    assert 1.0 < lost_at <= 1.5  # within 0.5 s of the unplug
    if loss == "error":
        assert lost_at <= 1.0 + 2 / 60  # a read error is seen at the next poll
    assert SourceState.RECONNECTING in kinds and kinds[-1] is SourceState.CONNECTED
    back = [t for t, s in states if s is SourceState.CONNECTED][-1]
    assert 2.0 < back < 3.3
    assert src.stats["reconnects"] == 1 and src.stats["disconnects"] >= 1
    assert src.info.path.endswith(b"-1")  # a new node, found again by its serial
    check_against_recording(src, samples, read_recording(rec_path))
    # Nothing arrives while it is gone.
    assert not [s for s in samples if lost_at < s.t < 2.0]


def test_rumble_for_n_ms_keeps_bit_on_every_report(rec_path):
    vc = VirtualClock()
    src, _, _ = session(f"wiimote-emu://{rec_path}", 0.5, vc)
    emu = src.emulator
    n0 = len(emu.outputs)
    src.rumble(100)
    assert emu.rumble is True and emu.outputs[n0] == bytes([0x10, 0x01])
    src._request_status(vc.seconds())  # any report sent meanwhile keeps the motor on
    assert emu.outputs[-1] == bytes([0x15, 0x01]) and emu.rumble is True
    for _ in range(4):  # 67 ms
        vc.advance(STEP_NS)
        src.poll()
    assert emu.rumble is True
    for _ in range(3):  # past 100 ms
        vc.advance(STEP_NS)
        src.poll()
    assert emu.rumble is False and emu.outputs[-1] == bytes([0x10, 0x00])


def test_clean_close(rec_path):
    vc = VirtualClock()
    src, _, _ = session(f"wiimote-emu://{rec_path}", 0.5, vc)
    emu = src.emulator
    src.rumble(1000)
    src.close()
    assert emu.outputs[-2:] == [bytes([0x10, 0x00]), bytes([0x11, 0x00])]
    assert emu.rumble is False and emu.leds == 0
    assert src.state is SourceState.DISCONNECTED
    vc.advance(STEP_NS)
    assert src.poll() == [] and src.state is SourceState.DISCONNECTED
    src.close()  # twice is fine


def test_player_leds_and_battery(rec_path):
    src, _, _ = session(f"wiimote-emu://{rec_path}?player=3", 0.5)
    assert src.emulator.leds == 0b0100
    assert src.battery_raw == 0xB4


def test_kernel_driver_mode_changes_are_reasserted(rec_path):
    src, samples, _ = session(f"wiimote-emu://{rec_path}?kernel_driver=1&foreign_mode_at=1.0", 2.0)
    assert any("hid-wiimote" in n for n in src.notes)
    assert src.stats["foreign_mode"] >= 1
    assert src.emulator.mode == 0x35  # put back
    assert src.emulator.outputs.count(bytes([0x12, 0x04, 0x35])) == 2
    # 0x31 reports (no extension bytes) still give Wiimote samples
    check_against_recording(src, samples, read_recording(rec_path), check_left=False)


def test_stalled_loop_loses_only_what_the_host_buffer_drops(rec_path):
    vc = VirtualClock()
    src, samples, _ = session(f"wiimote-emu://{rec_path}", 0.5, vc)
    vc.advance(1_000_000_000)  # the loop hitches for a second
    more = src.poll()
    assert len(more) == 64  # hidraw keeps 64 reports; no false disconnect
    assert src.state is SourceState.CONNECTED and src.emulator.stats["overflow"] > 20
    assert all(b.t > a.t for a, b in zip(samples + more, (samples + more)[1:], strict=False))


def test_windows_exact_write_length(rec_path):
    vc = VirtualClock()
    rec = read_recording(rec_path)
    strict = EmulatedBus([EmulatedWiimote(rec, vc.seconds)], require_write_length=22)
    bad = WiimoteSource(clock=vc.seconds, backend=strict)  # writes 2-7 bytes: rejected
    good = WiimoteSource(
        clock=vc.seconds, backend=EmulatedBus([EmulatedWiimote(rec, vc.seconds)], require_write_length=22), write_length=22
    )
    for _ in range(30):
        vc.advance(STEP_NS)
        bad.poll()
        good.poll()
    assert bad.state is SourceState.DISCONNECTED and "write failed" in bad.last_error
    assert good.state is SourceState.CONNECTED


def test_no_wiimote_found(monkeypatch):
    import engine.sensors.wiimote as wm

    vc = VirtualClock()
    # The real hidraw/hid backend of this machine (no Wiimote attached in CI).
    if not wm.list_wiimotes():
        with pytest.raises(WiimoteNotFound, match="no Wiimote found.*SYNC"):
            open_source("wiimote://", clock=vc.seconds)
    monkeypatch.setattr(wm, "hid_backend", lambda: EmulatedBus([]))
    with pytest.raises(WiimoteNotFound, match="no Wiimote found at /dev/hidraw9"):
        open_source("wiimote:///dev/hidraw9", clock=vc.seconds)
    src = open_source("wiimote://?wait=1", clock=vc.seconds)
    assert src.state is SourceState.DISCONNECTED and src.poll() == []


def test_waiting_source_connects_when_a_remote_appears(rec_path, monkeypatch):
    import engine.sensors.wiimote as wm

    vc = VirtualClock()
    bus = EmulatedBus([])
    monkeypatch.setattr(wm, "hid_backend", lambda: bus)
    src = open_source("wiimote://?wait=1", clock=vc.seconds)
    for _ in range(30):
        vc.advance(STEP_NS)
        assert src.poll() == []
    bus.remotes.append(EmulatedWiimote(read_recording(rec_path), vc.seconds))
    got = []
    for _ in range(120):
        vc.advance(STEP_NS)
        got += src.poll()
    assert src.state is SourceState.CONNECTED and len(got) > 50


def test_real_punches_through_the_emulator(shared_data):
    """A real two-glove recording (25 Hz, punches beyond a Wiimote's range) through the
    emulator and the driver: in range within one count, out of range saturated like the sensor."""
    path = shared_data / "punchbuddy" / "right-hook-100-egor-combo-lh-0.csv"
    rec = read_recording(path)
    src, samples, _ = session(f"wiimote-emu://{path}?jitter_ms=4&pad=22&start=12", 3.0)
    read = [s for s in src.emulator.sent if s.read_at is not None]
    assert len(samples) == len(read) > 200
    saturated = 0
    for sample, sent in zip(samples, read, strict=True):
        exp = expected(rec, sent.rec_time)
        for row, cal in ((0, src.wiimote_calibration), (1, src.nunchuk_calibration)):
            raw = cal.from_g(exp[row])
            one = 1.0 / (np.asarray(cal.one_g) - np.asarray(cal.zero))
            inside = (raw >= 0) & (raw <= 1022)
            assert np.all(np.abs(sample.accel[row] - exp[row])[inside] <= one[inside] + 1e-9)
            edge = cal.to_g(np.where(raw < 0, 0, np.where(raw > 1022, [1023, 1022, 1022] if row == 0 else 1023, raw)))
            assert np.allclose(sample.accel[row][~inside], edge[~inside])
            saturated += int((~inside).sum())
    assert saturated > 0  # the recording does go past the range


@pytest.mark.parametrize("status_stops", ["0", "1"])
def test_status_requests_mid_stream_keep_data_flowing(rec_path, status_stops):
    """Whether a status report stops reporting (Linux's assumption) or not (Dolphin's), the
    driver's battery polls must not leave a gap: it sets the mode again after each 0x20."""
    vc = VirtualClock()
    src, samples, _ = session(f"wiimote-emu://{rec_path}?status_stops={status_stops}", 0.5, vc)
    for _ in range(3):
        src._request_status(vc.seconds())  # what the 10 s battery refresh does
        got = []
        for _ in range(12):  # 0.2 s
            vc.advance(STEP_NS)
            got += src.poll()
        assert len(got) >= 17  # no gap beyond a report or two
        samples += got
    assert src.state is SourceState.CONNECTED and "mode_resent" not in src.stats
    check_against_recording(src, samples, read_recording(rec_path))


@pytest.mark.parametrize("first_id", [b"\xff" * 6, bytes.fromhex("0000a6200005")])
def test_extension_that_failed_to_set_up_is_tried_again(rec_path, first_id):
    """The status says an extension is plugged but its first set-up failed: a half-inserted
    Nunchuk's all-0xFF ID, or another driver's read reply (hid-wiimote's Motion Plus poll at
    0xA600FA also answers at 0x00FA) taken for the ID. Linux's hid-wiimote checks again every
    4 s (wiimote_init_check: EXT_PLUGGED without a known extension redoes the hot-plug); so
    must we, or the left hand stays dead until the Nunchuk is re-plugged."""
    vc = VirtualClock()
    src = open_source(f"wiimote-emu://{rec_path}", clock=vc.seconds)
    emu = src.emulator
    real_id = bytes(emu.memory.ext_regs[0xFA:0x100])
    emu.memory.ext_regs[0xFA:0x100] = first_id
    for _ in range(60):  # 1 s: set up with the bad ID
        vc.advance(STEP_NS)
        src.poll()
    assert src.extension in ("none", "unknown") and src.state is SourceState.CONNECTED
    emu.memory.ext_regs[0xFA:0x100] = real_id  # seated now; no new status report comes
    samples = []
    for _ in range(6 * 60):
        vc.advance(STEP_NS)
        samples += src.poll()
    assert src.extension == "nunchuk" and src.state is SourceState.CONNECTED
    assert src.stats["nunchuk_plugged"] == 1 and "extension_removed" not in src.stats
    assert not np.array_equal(samples[-1].accel[1], [0.0, 0.0, 1.0])  # the left hand moves


def test_seconds_ends_the_emulated_source_as_a_replay_ends(rec_path):
    """`seconds=S`: the source delivers what was stamped before S s after the emulator started,
    then is ENDED (what makes `record` and the game stop), the remote's rumble and LEDs off as
    at a close. Without it the remote streams on past its recording (looped, or held with loop=0)."""
    vc = VirtualClock()
    src, samples, states = session(f"wiimote-emu://{rec_path}?seconds=1.5", 3.0, vc)
    assert src.state is SourceState.ENDED
    assert [state for _, state in states][-2:] == [SourceState.CONNECTED, SourceState.ENDED]
    ended_at = states[-1][0]
    assert 1.5 <= ended_at < 1.5 + 1.5 / 60  # the first poll at or after 1.5 s
    assert samples and max(s.t for s in samples) < 1.5 and max(s.t for s in samples) > 1.4
    assert src.poll() == [] and src.state is SourceState.ENDED
    assert src.emulator.outputs[-1] == p.build_leds(0)  # closed: LEDs off
    read = [d for d in src.emulator.sent if d.read_at is not None]
    assert len(read) - 2 <= len(samples) < len(read)  # those read in the last poll but stamped from 1.5 s on are not
    for query in ("", "?loop=0"):
        src, samples, _ = session(f"wiimote-emu://{rec_path}{query}", 6.0)  # the recording is 4 s
        assert src.state is SourceState.CONNECTED and max(s.t for s in samples) > 5.9


@pytest.mark.parametrize("bad", ["0", "-1", "nan", "1e9", "soon"])
def test_seconds_out_of_range_is_one_line(rec_path, bad):
    with pytest.raises(SourceError, match="seconds must be a number above 0"):
        open_source(f"wiimote-emu://{rec_path}?seconds={bad}", clock=VirtualClock().seconds)


@pytest.mark.parametrize("ident", ["0000a4210000", "ff00a0200000", "010000000000"])
def test_a_nunchuk_whose_id_differs_in_bytes_0_to_3_is_a_nunchuk(rec_path, ident):
    """The remote's ID register says 00 00 in bytes 4-5 but not Nintendo's A4 20 before them
    (third-party Nunchuks): Linux's hid-wiimote and Dolphin take it for a Nunchuk, and so do we;
    the emulated one answers the real set-up (encrypted until initialised) with that ID."""
    vc = VirtualClock()
    src = open_source(f"wiimote-emu://{rec_path}", clock=vc.seconds)
    src.emulator.memory.ext_regs[0xFA:0x100] = bytes.fromhex(ident)
    samples = []
    for _ in range(2 * 60):
        vc.advance(STEP_NS)
        samples += src.poll()
    assert src.extension == "nunchuk" and src.stats["nunchuk_plugged"] == 1, src.stats
    assert not any("not a Nunchuk" in note for note in src.notes), src.notes
    assert not np.array_equal(samples[-1].accel[1], [0.0, 0.0, 1.0])  # the left hand moves


def test_an_extension_that_is_not_a_nunchuk_is_tried_again_every_4_s_not_every_poll(rec_path):
    """A Classic Controller (or any extension that never sets up as a Nunchuk) stays plugged:
    hid-wiimote's check every 4 s, not a set-up script after every poll."""
    vc = VirtualClock()
    src = open_source(f"wiimote-emu://{rec_path}", clock=vc.seconds)
    src.emulator.memory.ext_regs[0xFA:0x100] = bytes.fromhex("0000a4200101")  # a Classic Controller
    for _ in range(10 * 60):  # 10 s
        vc.advance(STEP_NS)
        src.poll()
    assert src.extension == "unknown" and src.state is SourceState.CONNECTED
    assert 1 <= src.stats["extension_retries"] <= 3, src.stats
