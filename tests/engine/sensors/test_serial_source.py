"""The serial:// source through pyserial's loop://, a real serial.Serial on a pty pair, and the
device emulator (unplug and replug)."""

from __future__ import annotations

import os
import threading
import time
import tty

import numpy as np
import pytest

from engine.sensors import SourceError, SourceState, open_source
from engine.sensors.serial_source import DeviceClock, SerialSource, parse_serial_url, write_now
from firmware_bridge import protocol
from firmware_bridge.emulator import (
    Emulator,
    EmulatorDef,
    Faults,
    start_in_thread,
    synthetic_motion,
)

HELLO2 = protocol.encode_hello(0, 0, 77, 200, 4096, 65500, 30, protocol.IMU_MPU6050, 3)


def samples(n, start_seq=1, t0=0):
    return b"".join(protocol.encode_sample(start_seq + i, t0 + 5000 * i, (0, 0, 4096), (2048, -4096, 0))
                    for i in range(n))


def poll_until(src, n: int) -> list:
    """Poll `src` every 10 ms until `n` samples came (or half a second passed); the samples."""
    got = []
    for _ in range(50):
        got += src.poll()
        if len(got) >= n:
            break
        time.sleep(0.01)
    return got


def test_loop_url_gives_samples_in_g():
    src = open_source("serial://loop://")
    assert isinstance(src, SerialSource) and src.state is SourceState.CONNECTED
    src.port.write(samples(3))  # before any HELLO: scales unknown, dropped and counted
    assert src.poll() == []
    assert src.stats["samples_before_hello"] == 3
    src.port.write(HELLO2 + samples(10, start_seq=1, t0=5000))
    before = time.perf_counter()
    got = src.poll()
    assert len(got) == 10
    assert got[0].accel.shape == (2, 3)
    np.testing.assert_allclose(got[0].accel, [[0, 0, 1], [0.5, -1, 0]])
    t = np.array([s.t for s in got])
    assert np.all(np.diff(t) > 0) and t[-1] <= time.perf_counter()
    np.testing.assert_allclose(np.diff(t), 0.005, atol=1e-9)  # device spacing kept
    assert t[-1] >= before - 1.0
    assert src.sensors == 2 and src.rate_hz == 200
    assert "MPU-6050" in src.description
    src.close()
    assert src.state is SourceState.DISCONNECTED and src.poll() == []


def test_one_sensor_hello_gives_one_row_and_text_is_kept():
    src = open_source("serial://loop://")
    src.port.write(protocol.encode_hello(0, 0, 1, 100, 4096, 0, 30, 1, protocol.FLAG_SENSOR_A)
                   + protocol.encode_text(1, 10, "hello from the board")
                   + protocol.encode_sample(2, 20, (4096, 0, 0)))
    got = src.poll()
    assert len(got) == 1 and got[0].accel.shape == (1, 3)
    assert list(src.messages) == ["hello from the board"]


def test_missing_sensor_holds_its_last_value():
    src = open_source("serial://loop://")
    src.port.write(HELLO2 + samples(1) + protocol.encode_sample(2, 10000, None, (0, 4096, 0)))
    got = src.poll()
    np.testing.assert_allclose(got[1].accel, [[0, 0, 1], [0, 1, 0]])
    assert src.stats["sensor_missing"] == 1


def test_device_clock_unwraps_and_follows_drift():
    dc = DeviceClock(window_s=1.0)
    dc.reset(30)
    mask = (1 << 30) - 1
    raw = mask - 10_000
    prev = dc.unwrap(raw)
    for _ in range(10):
        raw = (raw + 5000) & mask
        d = dc.unwrap(raw)
        assert d - prev == pytest.approx(0.005)
        prev = d
    assert dc.unwrap((raw - 100_000) & mask) is None  # backwards: a restarted clock
    # host runs 100 ppm fast and delays vary 1..10 ms: the mapped offset tracks the true one
    dc.reset(32)
    rng = np.random.default_rng(0)
    for k in range(2000):
        dev = k * 0.005
        host = 100.0 + dev * 1.0001 + 0.001 + rng.uniform(0, 0.009)
        dc.observe(host, dc.unwrap(int(dev * 1e6)))
    true_offset_now = 100.0 + dev * 0.0001 + 0.001
    assert abs(dc.offset - true_offset_now) < 0.0006


def test_pty_real_serial_and_hangup():
    master, slave = os.openpty()
    tty.setraw(slave)
    name = os.ttyname(slave)
    src = open_source(f"serial://{name}?retry=0.05")
    try:
        assert src.state is SourceState.CONNECTED
        assert os.read(master, 16) == protocol.HELLO_REQUEST  # asked for a HELLO on open
        os.write(master, b"\x00garbage" + HELLO2 + samples(50))
        got = poll_until(src, 50)
        assert len(got) == 50 and src.stats["lost"] == 0
        os.close(master)
        os.close(slave)
        for _ in range(20):
            src.poll()
            if src.state is SourceState.RECONNECTING:
                break
            time.sleep(0.01)
        assert src.state is SourceState.RECONNECTING
        assert src.stats["disconnects"] == 1
        assert src.poll() == []  # still gone: no exception, just a state
    finally:
        src.close()


def test_a_board_gone_quiet_is_away_until_it_sends_again():
    """A board that stops sending (its power, a crash) kept the port open and the source
    "connected", with nothing on screen (only a `stalls` count), and the match went on with a
    frozen player. Now it is away (`reconnecting`, as a Wiimote gone silent: the game pauses), and
    the first byte again brings it back on the same port."""
    master, slave = os.openpty()
    tty.setraw(slave)
    now = [0.0]
    src = open_source(f"serial://{os.ttyname(slave)}?retry=0.05", clock=lambda: now[0])
    try:
        os.write(master, HELLO2 + samples(20))
        assert len(poll_until(src, 20)) == 20 and src.missing() == ""
        _drain(master)  # the HELLO request of the open
        now[0] += 1.0
        src.poll()
        assert src.missing() == "" and src.stats.get("stalls", 0) == 0  # a second of quiet: not yet
        now[0] += 1.5
        src.poll()
        assert src.state is SourceState.RECONNECTING and src.stats["stalls"] == 1
        assert os.read(master, 16) == protocol.HELLO_REQUEST  # asked again
        os.write(master, samples(5, start_seq=21, t0=100_000))
        assert len(poll_until(src, 5)) == 5 and src.state is SourceState.CONNECTED and src.missing() == ""
        assert src.stats.get("disconnects", 0) == 0 and src.stats["stalls"] == 1
    finally:
        src.close()
        os.close(master)
        os.close(slave)


def test_big_burst_is_drained_in_one_poll():
    master, slave = os.openpty()
    tty.setraw(slave)
    os.set_blocking(master, False)
    src = open_source(f"serial://{os.ttyname(slave)}")
    try:
        data = HELLO2 + samples(100)  # > 3 KB, near the 4095-byte tty buffer
        os.write(master, data)
        time.sleep(0.05)
        assert len(src.poll()) == 100
    finally:
        src.close()
        os.close(master)
        os.close(slave)


def start_linked(emu: Emulator, seconds: float, link: str) -> threading.Thread:
    """The emulator running in a thread, once its port's link exists (waited for up to 1 s)."""
    th = start_in_thread(emu, seconds)
    for _ in range(100):
        if os.path.exists(link):
            break
        time.sleep(0.01)
    return th


def test_emulator_unplug_replug_and_wrap_are_survived(tmp_path):
    link = str(tmp_path / "bridge")
    emu = Emulator(synthetic_motion(), rate_hz=200, link=link, ticks_start=(1 << 30) - 700_000,
                   faults=Faults(unplug_at=[0.8], unplug_s=0.4, garbage_every=0.1, stall_at=[2.6], stall_s=0.3,
                                 reboot_at=[3.2]))
    th = start_linked(emu, 4.6, link)
    src = open_source(f"serial://{link}?retry=0.1")
    states, got = [src.state], []
    try:
        while th.is_alive():
            got += [(s, src.state) for s in src.poll()]
            if src.state is not states[-1]:
                states.append(src.state)
            time.sleep(1 / 60)
    finally:
        src.close()
        th.join(2)
    assert states[:3] == [SourceState.CONNECTED, SourceState.RECONNECTING, SourceState.CONNECTED]
    assert src.stats["disconnects"] == 1 and src.stats["reconnects"] == 1
    # the source asks for a HELLO on (re)open and the emulated firmware answers at once, so few
    # samples wait for scales (the one-a-second HELLO alone would cost up to 200 per open)
    assert src.stats.get("samples_before_hello", 0) < 60
    assert src.stats["reboots"] == 2  # a replugged board powers up again; then --reboot-at
    assert emu.stats.garbage_bursts > 10 and emu.stats.stalls == 1
    t = np.array([s.t for s, _ in got])
    assert np.all(np.diff(t) >= 0)
    # the unplug and the stall each show as a gap in device time, not as bunched samples
    assert (np.diff(t) >= 0.25).sum() >= 2
    # samples before the unplug, across the 30-bit wrap (at ~0.7 s), and after the replug
    assert len(got) > 200
    assert t[-1] > t[0] + 2.0
    acc = np.array([s.accel for s, _ in got])
    assert acc.shape[1:] == (2, 3) and np.abs(np.linalg.norm(acc[:, 1], axis=1) - 1).min() < 0.1


def test_auto_without_a_board_waits_quietly(monkeypatch):
    monkeypatch.setattr("engine.sensors.serial_source.list_ports.comports", lambda: [])
    src = open_source("serial://auto?retry=0.01")
    assert src.state is SourceState.CONNECTING and src.poll() == []
    src.close()


def test_missing_port_is_a_state_not_an_error():
    src = open_source("serial:///dev/quickjab-no-such-port")
    assert src.state is SourceState.CONNECTING and src.poll() == []


def test_an_imu_mounted_another_way_reads_on_the_games_axes():
    """`?axes=-y,z,x`: the game's x is the IMU's -y, its y the IMU's z, its z the IMU's x, for
    every sensor, through a real serial port (a pty pair); the description says so."""
    master, slave = os.openpty()
    tty.setraw(slave)
    src = open_source(f"serial://{os.ttyname(slave)}?axes=-y,z,x&retry=0.05")
    try:
        assert os.read(master, 16) == protocol.HELLO_REQUEST
        os.write(master, HELLO2 + samples(5))
        got = poll_until(src, 5)
        assert len(got) == 5
        # the IMU read (0, 0, 1) and (0.5, -1, 0): on the game's axes (-y, z, x)
        np.testing.assert_allclose(got[0].accel, [[0, 1, 0], [1, 0, 0.5]])
        assert "axes -y,z,x" in src.description
    finally:
        src.close()
        os.close(master)
        os.close(slave)
    assert parse_serial_url("serial:///dev/x?axes=-y,z,x") == ("/dev/x", {"axes": "-y,z,x"})
    assert open_source("serial:///dev/nonexistent-qj").axes is None  # no mapping: as they are
    # the chip's axes are right-handed and the game's left-handed: a mapping that keeps the
    # handedness (the guard's reading cannot tell: x reads about 0 there) names the x that fits
    for kept, fits in (("y,z,x", "-y,z,x"), ("x,y,z", "-x,y,z"), ("-y,x,z", "y,x,z")):
        with pytest.raises(SourceError, match=rf"keeps the IMU's right-handed axes right-handed.*\(axes={fits}\)"):
            open_source(f"serial:///dev/nonexistent-qj?axes={kept}")
        assert str(open_source(f"serial:///dev/nonexistent-qj?axes={fits}").axes) == fits


@pytest.mark.parametrize("url", ["serial://", "serial:///dev/x?speed=3", "serial:///dev/x?baud=fast",
                                 "serial:///dev/x?retry=0", "serial://loop://?retry=0", "serial://loop://?logging=loud",
                                 "serial://nosuch://x",
                                 # nan passed `<= 0`: a retry of nan never reopened a lost port, and a
                                 # window of nan or inf never let the clock's minimum go (nor its deque)
                                 "serial:///dev/x?retry=nan", "serial:///dev/x?retry=inf", "serial:///dev/x?window=nan",
                                 "serial:///dev/x?window=inf", "serial:///dev/x?window=1e9", "serial:///dev/x?baud=0",
                                 "serial:///dev/x?axes=x,y", "serial:///dev/x?axes=x,x,z", "serial:///dev/x?axes=x,y,w",
                                 "serial:///dev/x?axes=--x,y,z", "serial:///dev/x?axes=", "serial:///dev/x?axes=x,y,z"])
def test_bad_urls_name_themselves(url):
    with pytest.raises(SourceError, match="serial://"):
        open_source(url)


def test_url_syntax():
    assert parse_serial_url("serial:///dev/ttyACM0?baud=9600") == ("/dev/ttyACM0", {"baud": "9600"})
    assert parse_serial_url("serial://auto") == (None, {})
    assert parse_serial_url("serial://loop://") == ("loop://", {})
    assert parse_serial_url("serial://socket://localhost:7777") == ("socket://localhost:7777", {})


def test_auto_finds_a_known_board_by_vid_pid(monkeypatch):
    from types import SimpleNamespace

    from engine.sensors.serial_source import find_board

    ports = [SimpleNamespace(device="/dev/ttyUSB0", vid=0x0403, pid=0x6001),
             SimpleNamespace(device="/dev/ttyACM1", vid=0x2E8A, pid=0x0005),
             SimpleNamespace(device="/dev/ttyS0", vid=None, pid=None)]
    monkeypatch.setattr("engine.sensors.serial_source.list_ports.comports", lambda: ports)
    assert find_board() == "/dev/ttyACM1"
    assert find_board(0x0403, 0x6001) == "/dev/ttyUSB0"
    assert find_board(0x1234, None) is None


@pytest.mark.parametrize("error", ["oserror", "termios", "serial"])
def test_every_kind_of_unplug_becomes_a_state(error):
    import termios

    import serial

    exc = {"oserror": OSError(5, "Input/output error"), "termios": termios.error(5, "EIO"),
           "serial": serial.SerialException("device disconnected")}[error]

    class Unplugged:
        @property
        def in_waiting(self):
            raise exc

        def close(self):
            raise exc

    src = open_source("serial://loop://")
    src.port = Unplugged()
    assert src.poll() == []
    assert src.state is SourceState.RECONNECTING and src.port is None
    assert src.stats["disconnects"] == 1


def test_times_never_go_back_across_a_reboot():
    src = open_source("serial://loop://")
    src.port.write(HELLO2 + samples(20, start_seq=1, t0=10_000_000))
    first = src.poll()
    # a rebooted board: new boot_id, its clock restarts near zero
    src.port.write(protocol.encode_hello(0, 100, 78, 200, 4096, 65500, 30, 1, 3) + samples(5, start_seq=1, t0=200))
    second = src.poll()
    assert len(first) == 20 and len(second) == 5 and src.stats["reboots"] == 1
    assert second[0].t >= first[-1].t


def _fill_output(fd: int) -> None:
    """Write to a pty's slave end until the tty's output buffer is full (nobody reads the master)."""
    os.set_blocking(fd, False)
    for _ in range(3):  # the kernel may move some on to the master meanwhile: fill again
        for size in (4096, 256, 1):
            try:
                while True:
                    os.write(fd, b"x" * size)
            except BlockingIOError:
                pass
        time.sleep(0.02)


def _drain(fd: int) -> None:
    os.set_blocking(fd, False)
    try:
        while os.read(fd, 65536):
            pass
    except BlockingIOError:
        pass


def test_a_device_that_never_reads_cannot_hang_the_host():
    # A board (the user's own, say) that never reads its input: the tty's output buffer fills with
    # what the host sends, and asking for a HELLO then found no room. pyserial's write with
    # write_timeout=0 retries EAGAIN forever: the constructor (the '?' on open) and every poll
    # asking while SAMPLEs came without a HELLO spun at 100 % CPU and never returned.
    master, slave = os.openpty()
    tty.setraw(slave)
    now = [0.0]
    made: list = []
    try:
        _fill_output(slave)
        th = threading.Thread(target=lambda: made.append(open_source(f"serial://{os.ttyname(slave)}",
                                                                     clock=lambda: now[0])), daemon=True)
        th.start()
        th.join(2.0)
        hung_on_open = th.is_alive()
        while th.is_alive():  # make room, so that a hung write ends and the thread with it
            _drain(master)
            th.join(0.01)
        assert not hung_on_open
        src = made[0]
        assert src.state is SourceState.CONNECTED
        _drain(master)
        _fill_output(slave)
        polls: list = []

        def poll_without_hello() -> None:
            for k in range(5):  # SAMPLEs, no HELLO: the source asks again every 0.25 s
                now[0] += 0.3
                os.write(master, protocol.encode_sample(k, 5000 * k, (0, 0, 4096), None))
                time.sleep(0.01)
                polls.append(src.poll())

        th = threading.Thread(target=poll_without_hello, daemon=True)
        th.start()
        th.join(2.0)
        hung_on_poll = th.is_alive()
        while th.is_alive():
            _drain(master)
            th.join(0.01)
        assert not hung_on_poll and polls == [[]] * 5
        for _ in range(100):  # a loaded machine may pass the last SAMPLE on late
            if src.stats.get("samples_before_hello") == 5:
                break
            assert src.poll() == []
            time.sleep(0.01)
        assert src.stats["samples_before_hello"] == 5
        _drain(master)  # the board reads at last: a request gets through, the HELLO comes
        now[0] += 0.3
        os.write(master, protocol.encode_hello(5, 25000, 77, 200, 4096, 65500, 30, protocol.IMU_MPU6050, 3)
                 + samples(3, start_seq=6, t0=30000))
        time.sleep(0.02)
        assert len(src.poll()) == 3
        src.close()
    finally:
        os.close(master)
        os.close(slave)


def test_after_a_reconnect_no_sample_is_read_with_the_last_devices_scales(tmp_path):
    # Unplugged, and what comes back on the same path may be another board (or the same one,
    # rebooted with one IMU fewer): its SAMPLEs before its HELLO were converted with the old
    # board's scales and sensors (a 1 g reading came out as 4 g, beside an invented sensor B).
    link = str(tmp_path / "board")

    def plug() -> tuple[int, int]:
        master, slave = os.openpty()
        tty.setraw(slave)
        if os.path.lexists(link):
            os.unlink(link)
        os.symlink(os.ttyname(slave), link)
        return master, slave

    def poll_until(src, done) -> list:
        got: list = []
        for _ in range(100):
            got += src.poll()
            if done():
                break
            time.sleep(0.01)
        return got

    master, slave = plug()
    src = open_source(f"serial://{link}?retry=0.01")
    try:
        os.write(master, HELLO2 + samples(10))
        assert len(poll_until(src, lambda: src.stats["frames_ok"] == 11)) == 10
        os.close(master)
        os.close(slave)
        poll_until(src, lambda: src.state is SourceState.RECONNECTING)
        master, slave = plug()
        poll_until(src, lambda: src.state is SourceState.CONNECTED)
        assert os.read(master, 16) == protocol.HELLO_REQUEST
        # another board: 16384 counts per g (an LSM6DS3 at +-2 g), sensor A only; two SAMPLEs
        # made before the request arrived, then the HELLO that answers it
        other = (b"".join(protocol.encode_sample(s, 5000 * s, (0, 0, 16384), None) for s in (3, 4))
                 + protocol.encode_hello(5, 25000, 99, 200, 16384, 65500, 30, protocol.IMU_LSM6DS3, 1)
                 + b"".join(protocol.encode_sample(s, 5000 * s, (0, 0, 16384), None) for s in (6, 7)))
        os.write(master, other)
        got = poll_until(src, lambda: src.stats["frames_ok"] == 16)
        assert [s.accel.tolist() for s in got] == [[[0.0, 0.0, 1.0]]] * 2
        assert src.sensors == 1 and src.stats["samples_before_hello"] == 2 and src.stats["reboots"] == 1
        assert src.stats.get("sensor_missing", 0) == 0
    finally:
        src.close()
        os.close(master)
        os.close(slave)


def test_an_emulated_board_with_a_counter_wider_than_32_bits_streams(tmp_path):
    # EmulatorDef allows tick counters up to 62 bits (a 64-bit esp_timer, say), but t_us is a u32
    # on the wire: the HELLO announced ts_bits 40, outside 8..32, so every HELLO was malformed
    # and the host never got a sample. Such a board sends its counter's low 32 bits: ts_bits 32
    link = str(tmp_path / "bridge")
    emu = Emulator.from_def(synthetic_motion(), EmulatorDef(ts_bits=40, ticks_start=(1 << 32) - 300_000), link=link)
    th = start_linked(emu, 1.2, link)
    src = open_source(f"serial://{link}")
    got = []
    try:
        while th.is_alive():
            got += src.poll()
            time.sleep(0.02)
    finally:
        src.close()
        th.join(2)
    assert src.stats["malformed"] == 0 and src.hello is not None and src.hello.ts_bits == 32
    assert len(got) > 100 and src.stats.get("time_jumps", 0) == 0  # across the 32-bit wrap, 0.3 s in
    t = np.array([s.t for s in got])
    np.testing.assert_allclose(np.median(np.diff(t)), 0.005, atol=0.001)


def test_a_hello_request_reaches_a_port_with_no_file_descriptor():
    # loop:// (and other URL ports) have fileno() raising io.UnsupportedOperation, an OSError:
    # the direct write must fall back to the port's own, not drop every request as a lost port
    import serial

    port = serial.serial_for_url("loop://", timeout=0.5)
    try:
        write_now(port, protocol.HELLO_REQUEST)
        assert port.read(1) == protocol.HELLO_REQUEST
    finally:
        port.close()


def test_auto_with_a_pid_but_no_vid_is_an_error_not_ignored():
    """`serial://auto?pid=0005` used to look for the known boards, silently ignoring the pid."""
    with pytest.raises(SourceError, match="pid"):
        open_source("serial://auto?pid=0005")


def test_description_follows_a_boots_later_hello():
    """A boot's first HELLO may come before its IMUs are found (flags 0, kind unknown); the
    description `record` writes into its file must name what the later HELLO of the same boot
    announces, not "IMU x0"."""
    src = open_source("serial://loop://")
    src.port.write(protocol.encode_hello(0, 0, 5, 200, 4096, 65500, 30, protocol.IMU_UNKNOWN, 0)
                   + protocol.encode_hello(1, 10, 5, 100, 4096, 65500, 30, protocol.IMU_MPU6050, 3)
                   + protocol.encode_sample(2, 20, (0, 0, 4096), (0, 0, 4096)))
    assert len(src.poll()) == 1
    assert "MPU-6050 x2, 100 Hz" in src.description, src.description


def test_a_board_with_only_sensor_b_streams_the_left_hand():
    """PROTOCOL.md: sensor B is the left hand (lx,ly,lz). A board whose HELLO announces B alone
    (its sensor A not found at boot) must not have B's readings taken for the right hand, nor an
    unannounced A's readings taken for B's."""
    src = open_source("serial://loop://")
    hello_b = protocol.encode_hello(0, 0, 9, 200, 4096, 65500, 30, protocol.IMU_MPU6050, protocol.FLAG_SENSOR_B)
    src.port.write(hello_b + protocol.encode_sample(1, 5000, None, (0, 2048, 4096))
                   + protocol.encode_sample(2, 10000, (4096, 0, 0), (0, 4096, 0)))  # A: unannounced
    got = src.poll()
    assert src.sensors == 2 and len(got) == 2
    np.testing.assert_allclose(got[0].accel[1], [0, 0.5, 1])  # the left hand's row
    np.testing.assert_allclose(got[1].accel[1], [0, 1, 0])  # B's values, not A's
    np.testing.assert_allclose(got[1].accel[0], got[0].accel[0])  # the right hand holds still
    assert src.stats["sensor_unannounced"] == 1
    assert "right" in src.missing()


def test_a_pyserial_url_takes_our_axes_and_keeps_its_own_query():
    """`serial://socket://bridge:7000?axes=-x,y,z` (a board on the network, its IMU turned): the
    whole query went to pyserial, which refused `axes` with a bare KeyError('debug|info|...')."""
    from engine.sensors.serial_source import parse_serial_url
    from firmware_bridge import protocol

    assert parse_serial_url("serial://loop://?logging=debug&axes=-x,y,z") == ("loop://?logging=debug", {"axes": "-x,y,z"})
    src = open_source("serial://loop://?axes=-x,y,z&retry=1")
    try:
        src.port.write(protocol.encode_hello(0, 0, 1, 200, 4096, 65500, 30, protocol.IMU_MPU6050, protocol.FLAG_SENSOR_A)
                       + protocol.encode_sample(1, 5000, (4096, 0, 0)))
        (got,) = src.poll()
        assert got.accel.tolist() == [[-1.0, 0.0, 0.0]] and str(src.axes) == "-x,y,z"
    finally:
        src.close()
