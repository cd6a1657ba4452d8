"""`quickjab bridge faults|emulate` and `quickjab bench serial` through the real CLI."""

from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from engine.recording import Recording, read_recording, write_recording
from tools.cli import main

REPO = Path(__file__).resolve().parents[2]


def test_faults_command_prints_figures(capsys):
    rc = main(["bridge", "faults", "--random-mb", "0.2", "--corrupted", "3000", "--frames", "3000", "--events", "200"])
    out = capsys.readouterr().out
    assert rc == 0
    assert "false accepts: 0 over 209715 random bytes and 3000 corrupted frames" in out
    assert "dropped frames: 200 dropped, decoder counted 200 lost (equal)" in out
    for name in ("garbage burst between frames", "bit flip", "dropped byte"):
        assert name in out


def test_faults_bad_arguments_exit_2(capsys):
    assert main(["bridge", "faults", "--frames", "30", "--events", "20"]) == 2
    assert "--events 20" in capsys.readouterr().err


def test_emulate_bad_replay_file_exits_2(tmp_path, capsys):
    bad = tmp_path / "bad.csv"
    bad.write_text("t,rx,ry,rz\n0,1,2,x\n")
    assert main(["bridge", "emulate", "--replay", str(bad), "--seconds", "0.1"]) == 2
    err = capsys.readouterr().err
    assert str(bad) in err and len(err.strip().splitlines()) == 1


def emulate_and_record(tmp_path: Path, emulate: list[str], seconds: float) -> Recording:
    """`bridge emulate EMULATE --link` in one process, `record --source serial://LINK` for `seconds`
    in another: what came back through firmware loop, protocol, pty and source."""
    link = tmp_path / "port"
    emu = subprocess.Popen([sys.executable, "-m", "tools.cli", "bridge", "emulate", *emulate, "--link", str(link), "--quiet"],
                           cwd=REPO, stdout=subprocess.PIPE, text=True)
    try:
        assert emu.stdout.readline().startswith("port: /dev/pts/")
        out = tmp_path / "out.csv"
        rec = subprocess.run([sys.executable, "-m", "tools.cli", "record", "--source", f"serial://{link}", "-o", str(out),
                              "--seconds", str(seconds)], cwd=REPO, capture_output=True, text=True, timeout=30 + 2 * seconds)
        assert rec.returncode == 0, rec.stderr
    finally:
        emu.terminate()
        emu.wait(5)
    return read_recording(out)


def test_emulate_replay_then_record_end_to_end(tmp_path):
    """emulate --replay rec.csv in one process, quickjab record --source serial://... in another:
    the recording comes back through firmware loop, protocol, pty and source."""
    t = np.arange(0, 3, 1 / 100)
    accel = np.zeros((len(t), 2, 3))
    accel[:, 0, 0] = np.sin(2 * np.pi * 0.5 * t)  # a slow sine on the right hand's x
    accel[:, :, 2] = 1.0
    rec_in = tmp_path / "in.csv"
    write_recording(rec_in, Recording(t, accel))
    got = emulate_and_record(tmp_path, ["--replay", str(rec_in), "--seconds", "5"], seconds=3)
    assert got.sensors == 2 and len(got) > 250  # 200 Hz for ~2 s after the first HELLO
    assert np.allclose(got.accel[:, :, 2], 1.0, atol=0.02)  # gravity on z, in g
    assert got.accel[:, 0, 0].max() > 0.5 and got.accel[:, 0, 0].min() < -0.5  # the sine came through
    assert np.all(np.diff(got.t) >= 0)
    dt = np.median(np.diff(got.t))
    assert abs(dt - 0.005) < 0.001
    assert float(got.meta["rate_hz"]) == 200  # the rate the samples came at, not the 60 Hz default


def test_emulate_player_streams_a_virtual_boxer_the_recognizer_takes(tmp_path):
    """emulate --player: the simulated IMU plays a virtual player's boxing on the game's axes, so
    the no-hardware path (`play --source serial://...`) sees punches the shipped templates know
    (the default signal, a pulse on x over gravity on z, showed "no match" in the game)."""
    from engine.frames import recording_frames
    from engine.recognition import DualBufferRecognizer, Templates
    from game.virtual_player import PROFILES
    from tools.bridge import PLAYER_PROFILES

    assert PLAYER_PROFILES == tuple(PROFILES)
    got = emulate_and_record(tmp_path, ["--player", "experienced", "--seed", "1", "--seconds", "12"], seconds=6)
    # mostly the guard at rest, as the shipped templates expect it: about (0, 0.9, 0.4) g per hand
    np.testing.assert_allclose(np.median(got.accel, axis=0), [[0, 0.9, 0.4]] * 2, atol=0.12)
    assert np.abs(np.linalg.norm(got.accel, axis=2) - 1).max() > 1.0  # and punches
    rec = DualBufferRecognizer(Templates.load(REPO / "game" / "assets" / "templates.npz"))
    starts = [e for f in recording_frames(got)[1] for e in rec.push(f) if e["event"] == "start"]
    assert starts


def test_emulate_player_and_replay_are_one_or_the_other(tmp_path, capsys):
    assert main(["bridge", "emulate", "--player", "novice", "--replay", str(tmp_path / "x.csv")]) == 2
    assert "--replay and --player" in capsys.readouterr().err


def test_emulate_prints_a_port_that_opens(tmp_path):
    import serial

    proc = subprocess.Popen([sys.executable, "-m", "tools.cli", "bridge", "emulate", "--seconds", "2", "--quiet"],
                            cwd=REPO, stdout=subprocess.PIPE, text=True)
    try:
        path = proc.stdout.readline().split()[1]
        assert os.path.exists(path)
        port = serial.Serial(path, timeout=0)
        time.sleep(0.3)
        assert port.in_waiting > 0
        port.close()
    finally:
        proc.terminate()
        proc.wait(5)


def test_help_for_every_new_command(capsys):
    for argv in (["bridge", "--help"], ["bridge", "emulate", "--help"], ["bridge", "faults", "--help"],
                 ["bench", "serial", "--help"]):
        try:
            main(argv)
        except SystemExit as exc:
            assert exc.code == 0
    assert "--replay" in capsys.readouterr().out


@pytest.mark.parametrize("option, value, said", [
    ("--seconds", "0", "0 is out of range: must be > 0 and <= 3600"),
    ("--rate", "0", "0 is out of range: must be between 1 and 1000"),
])
def test_bench_serial_numbers_out_of_range_are_one_line(capsys, option, value, said):
    """--seconds 0 was a division by zero, --rate 0 "emulator did not start" (a RuntimeError:
    the emulator refused it in a process of its own)."""
    with pytest.raises(SystemExit) as exit_:
        main(["bench", "serial", option, value])
    err = capsys.readouterr().err.strip().splitlines()
    assert exit_.value.code == 2 and len(err) == 1, err
    assert err[0].startswith(f"quickjab bench serial: argument {option}: {said}"), err


def test_bench_serial_runs_and_reports_both_readers(capsys):
    import json

    assert main(["bench", "serial", "--seconds", "1", "--json"]) == 0
    fig = json.loads(capsys.readouterr().out)
    names = [r["reader"] for r in fig["readers"]]
    assert names == ["serial:// source", "peer: naive bytewise"]
    for r in fig["readers"]:
        assert r["samples"] > 100  # 200 Hz for 1 s
        assert r["poll_cost_us_per_frame"]["median"] > 0 and r["sample_age_ms"]["median"] > 0
    assert fig["decode_only_us_per_frame"]["decoder"] > 0


def test_bad_numbers_are_one_line_and_exit_2(capsys):
    for argv in (["faults", "--random-mb", "-1"], ["faults", "--random-mb", "nan"], ["emulate", "--seconds", "nan"],
                 ["emulate", "--seconds", "-1"], ["emulate", "--seconds", "inf"], ["emulate", "--flip-every", "-0.5"],
                 ["emulate", "--stall-s", "nan"], ["emulate", "--reboot-at", "inf"], ["emulate", "--garbage-len", "0"],
                 ["emulate", "--ticks-start", "-5"]):
        start = time.perf_counter()
        assert main(["bridge", *argv]) == 2, argv
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and argv[1] in err[0], (argv, err)
        assert time.perf_counter() - start < 5  # no hang


def test_a_link_in_a_missing_folder_is_one_line_before_the_port_opens(tmp_path, capsys):
    """The review: `--link /no/such/dir/l` ended in `[Errno 2] No such file or directory:
    '/dev/pts/0' -> '/no/such/dir/l.12435.tmp'`, after the port was announced. A missing folder
    is made now (as for every output); one that cannot be (a file in its place) is refused."""
    (tmp_path / "plain").write_text("x")
    link = tmp_path / "plain" / "missing" / "qj-bridge"
    with pytest.raises(SystemExit) as exit_:
        main(["bridge", "emulate", "--seconds", "1", "--link", str(link)])
    assert exit_.value.code == 2
    assert capsys.readouterr().err == (f"quickjab bridge emulate: argument --link: {link}: {tmp_path / 'plain'} is not a directory"
                                       " (see quickjab bridge emulate --help)\n")


def test_boot_id_is_random_per_boot_unless_seeded():
    from firmware_bridge.emulator import Emulator, synthetic_motion

    def boot_ids(seed, boots=3):
        emu = Emulator(synthetic_motion(), seed=seed)
        try:
            return [emu._sampler(b).boot_id for b in range(boots)]
        finally:
            emu.port.close()

    a, b = boot_ids(None), boot_ids(None)
    assert len(set(a + b)) == 6  # every boot of every run its own (2^-32 chance of a clash)
    assert boot_ids(5) == boot_ids(5) and len(set(boot_ids(5))) == 3


def test_a_terminated_emulator_removes_its_link(tmp_path):
    # killed (SIGTERM, as `kill` and `timeout` send), it left the --link symlink pointing at a pty
    # number another terminal may get later
    link = tmp_path / "port"
    emu = subprocess.Popen([sys.executable, "-m", "tools.cli", "bridge", "emulate", "--seconds", "30", "--link", str(link),
                            "--quiet"], cwd=REPO, stdout=subprocess.PIPE, text=True)
    try:
        assert emu.stdout.readline().startswith("port: /dev/pts/")
        assert os.path.islink(link)
        emu.terminate()
        assert emu.wait(10) == 0
    finally:
        if emu.poll() is None:
            emu.kill()
    assert not os.path.lexists(link)


def test_an_interrupt_while_the_port_is_announced_still_removes_the_link(tmp_path):
    # the race the test above lost now and then: SIGTERM (a KeyboardInterrupt here) as soon as a
    # reader saw the "port:" line, before the emulator's loop had begun, left the link behind
    from firmware_bridge.emulator import Emulator, EmulatorDef, synthetic_motion

    link = str(tmp_path / "port")

    def announced(path: str) -> None:
        assert os.path.islink(link)
        raise KeyboardInterrupt

    emu = Emulator.from_def(synthetic_motion(), EmulatorDef(2), link=link, on_port=announced)
    try:
        emu.run(5.0)
    except KeyboardInterrupt:
        pass
    assert not os.path.lexists(link) and emu.port.master < 0
