"""`quickjab devices PATH...` probes ports pyserial's list never shows (a pty from `quickjab bridge
emulate` or socat) for a board answering with the serial protocol's HELLO: over real ptys, the
bridge emulator in its own process, or bytes of the test's own on a pty pair."""

from __future__ import annotations

import json
import os
import select
import subprocess
import sys
import threading
import time
import tty
from pathlib import Path

import pytest

from firmware_bridge import protocol
from tools.cli import main

REPO = Path(__file__).resolve().parents[2]


@pytest.fixture
def emulated_board(request):
    """`quickjab bridge emulate` on a pty (its own process): the port's path."""
    extra = getattr(request, "param", [])
    emu = subprocess.Popen([sys.executable, "-m", "tools.cli", "bridge", "emulate", "--seconds", "60", "--quiet", *extra],
                           cwd=REPO, stdout=subprocess.PIPE, text=True, env={**os.environ, "PYTHONPATH": str(REPO)})
    try:
        line = emu.stdout.readline()
        assert line.startswith("port: /dev/pts/"), line
        yield line.split()[1]
    finally:
        emu.terminate()
        emu.wait(5)


@pytest.fixture
def pty_pair():
    """(master fd, slave path): the test writes the 'device' side, the probe opens the path."""
    master, slave = os.openpty()
    tty.setraw(master)
    path = os.ttyname(slave)
    os.close(slave)
    yield master, path
    try:
        os.close(master)
    except OSError:
        pass


def devices(capsys, *argv: str) -> tuple[int, str]:
    rc = main(["devices", *argv])
    return rc, capsys.readouterr().out


def test_a_board_on_a_pty_answers_with_its_hello(emulated_board, capsys):
    rc, out = devices(capsys, emulated_board)
    assert rc == 0
    assert out.index("Wiimotes:") < out.index("Serial ports:") < out.index("Probed:")  # the listing as before, then the probe
    line = out.split("Probed:\n", 1)[1].strip()
    assert line.startswith(emulated_board)
    assert "a board answers (HELLO): simulated IMU x2, right and left hands, 200 Hz" in line
    assert line.endswith(f"serial://{emulated_board}")
    rc, out = devices(capsys, "--json", emulated_board)
    probed = json.loads(out)["probed"]
    assert rc == 0 and len(probed) == 1 and probed[0]["answered"] and probed[0]["url"] == f"serial://{emulated_board}"
    assert probed[0]["hello"]["sensors"] == 2 and probed[0]["hello"]["rate_hz"] == 200 and probed[0]["counts"] == {}


@pytest.mark.parametrize("emulated_board", [["--sensors", "1", "--rate", "100"]], indirect=True)
def test_a_one_sensor_board_is_said_to_give_the_right_hand_only(emulated_board, capsys):
    rc, out = devices(capsys, f"serial://{emulated_board}")  # the source URL works as well as the path
    assert rc == 0 and "x1, right hand only (sensor A), 100 Hz" in out


def test_without_paths_the_json_listing_is_as_before(capsys):
    rc, out = devices(capsys, "--json")
    assert rc == 0 and set(json.loads(out)) == {"wiimotes", "serial_ports", "problems"}
    rc, out = devices(capsys)
    assert "Probed:" not in out


def feed(master: int, data: bytes, every_s: float, stop: threading.Event) -> threading.Thread:
    def run():
        while not stop.is_set():
            try:
                os.write(master, data)
            except OSError:
                return
            time.sleep(every_s)

    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    return thread


def test_a_silent_pty_and_a_missing_path_are_no_board(pty_pair, tmp_path, capsys):
    master, path = pty_pair
    missing = str(tmp_path / "no-such-port")
    rc, out = devices(capsys, "--probe-seconds", "0.4", path, missing)
    assert rc == 1
    lines = out.split("Probed:\n", 1)[1].splitlines()
    assert lines[0].split()[0] == path and "nothing in 0.4 s: no board there" in lines[0]
    assert lines[1].split()[0] == missing and "cannot open it as a serial port" in lines[1]
    assert select.select([master], [], [], 1.0)[0]
    assert b"?" in os.read(master, 64)  # it was asked for a HELLO (PROTOCOL.md, host to device)


def test_bytes_that_are_no_frames_are_told_apart_from_silence(pty_pair, capsys):
    master, path = pty_pair
    stop = threading.Event()
    writer = feed(master, b"boot: hello world\r\n", 0.02, stop)  # a board speaking something else
    try:
        rc, out = devices(capsys, "--json", "--probe-seconds", "0.4", path)
    finally:
        stop.set()
        writer.join()  # before the fixture closes the master: never a write to a reused descriptor
    r = json.loads(out)["probed"][0]
    assert rc == 1 and not r["answered"] and r["bytes"] > 0 and r["frames"] == 0
    assert "but no protocol v1 frame" in r["result"]


def test_a_board_that_found_no_imu_yet_answers_but_says_so(pty_pair, capsys):
    master, path = pty_pair
    hello = protocol.encode_hello(0, 1000, 77, 200, 4096, 65500, 30, protocol.IMU_MPU6050, 0)  # flags 0: no sensor
    stop = threading.Event()
    writer = feed(master, hello, 0.05, stop)
    try:
        rc, out = devices(capsys, "--probe-seconds", "0.4", path)
    finally:
        stop.set()
        writer.join()  # before the fixture closes the master: never a write to a reused descriptor
    assert rc == 0 and "a board answers (HELLO) but has found no IMU yet" in out


def close_once_asked(master: int) -> threading.Thread:
    """Close `master` once the probe has asked for a HELLO: the request is sent only once its port
    is open, so the other end goes away while it probes (a timer raced the open: 'cannot open')."""
    def run():
        asked, deadline = b"", time.monotonic() + 60  # the deadline only ends a probe that never asks
        try:
            while protocol.HELLO_REQUEST not in asked and time.monotonic() < deadline:
                if not select.select([master], [], [], 0.1)[0]:
                    continue
                try:
                    asked += os.read(master, 64)
                except OSError:  # EIO: nobody has the other end open yet
                    time.sleep(0.01)
        finally:
            os.close(master)

    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    return thread


def test_a_pty_whose_other_end_closes_is_said_lost(capsys):
    master, slave = os.openpty()  # its own pair: the master is closed by close_once_asked, once
    path = os.ttyname(slave)
    os.close(slave)
    closer = close_once_asked(master)
    rc, out = devices(capsys, "--probe-seconds", "30", path)  # the loss ends it, not the 30 s
    closer.join()
    assert rc == 1 and "the port was lost while probing" in out, out


def _probe_board(pty_pair, capsys, data: bytes) -> tuple[int, dict]:
    """`quickjab devices --json` on a pty whose board end writes `data` every 0.05 s."""
    master, path = pty_pair
    stop = threading.Event()
    writer = feed(master, data, 0.05, stop)
    try:
        rc, out = devices(capsys, "--json", "--probe-seconds", "0.5", path)
    finally:
        stop.set()
        writer.join()  # before the fixture closes the master: never a write to a reused descriptor
    return rc, json.loads(out)["probed"][0]


def _board(accel: int = 4096, ts_bits: int = 30) -> bytes:
    hello = protocol.encode_hello(0, 1000, 77, 200, accel, 65500, ts_bits, protocol.IMU_MPU6050, 3)
    return hello + b"".join(protocol.encode_sample(i, 1000 + 5000 * i, (0, 0, 4096), (0, 0, 4096)) for i in range(1, 6))


@pytest.mark.parametrize(("accel", "ts_bits", "said"), [(0, 30, "accel_lsb_per_g is 0"), (4096, 7, "ts_bits 7 outside 8..32")])
def test_a_board_whose_hello_is_malformed_is_told_what_is_wrong(pty_pair, capsys, accel, ts_bits, said):
    # was: "protocol v1 frames but no HELLO: a board that does not answer `?`"; it answers, wrongly
    rc, r = _probe_board(pty_pair, capsys, _board(accel, ts_bits))
    assert rc == 1 and not r["answered"] and r["counts"]["malformed"] > 0
    assert said in r["result"] and "malformed" in r["result"] and "does not answer" not in r["result"], r["result"]


@pytest.mark.parametrize(("accel", "ts_bits", "said"), [(1, 30, "implausible"), (4096, 12, "narrow_clock")])
def test_a_hello_the_source_takes_but_cannot_use_is_said(pty_pair, capsys, accel, ts_bits, said):
    # accel_lsb_per_g 1: its 4096 counts read as 4096 g, every SAMPLE dropped; ts_bits 12 at 200 Hz:
    # t_us wraps within two sample periods, every sample time wrong. Both said to be fine.
    rc, r = _probe_board(pty_pair, capsys, _board(accel, ts_bits))
    assert rc == 1 and r["answered"] and said in r["problem"] and said in r["result"], r
