"""`quickjab record` with a source that never connects: a clear error and exit 2, no file; a
recording cut short by a full disk still reads back."""

from __future__ import annotations

import os
import resource
import subprocess
import sys
import time
from pathlib import Path

from engine.recording import read_recording
from tools.cli import main

REPO = Path(__file__).resolve().parents[2]


def test_record_from_a_missing_serial_port_exits_2(tmp_path, capsys):
    out = tmp_path / "out.csv"
    rc = main(["record", "--source", f"serial://{tmp_path / 'no-such-port'}", "-o", str(out), "--connect-timeout", "0.5"])
    err = capsys.readouterr().err
    assert rc == 2
    assert "no device connected after 0.5 s" in err  # ended by the connect timeout, not by hand
    assert "wrote 0 samples" not in err
    assert not out.exists()


def test_record_from_serial_auto_without_a_board_exits_2(tmp_path, capsys):
    out = tmp_path / "out.csv"
    rc = main(["record", "--source", "serial://auto?vid=ffff&pid=fffe", "-o", str(out), "--connect-timeout", "0.3"])
    assert rc == 2
    assert "serial://auto" in capsys.readouterr().err
    assert not out.exists()


def test_a_wiimote_that_never_connects_gets_wiimote_advice(tmp_path, capsys):
    # the advice was the serial board's ("check the port ... the board is plugged in") for any source
    out = tmp_path / "out.csv"
    rc = main(["record", "--source", f"wiimote://{tmp_path / 'no-such-hidraw'}?wait=1", "-o", str(out), "--connect-timeout", "0.3"])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and not out.exists()
    assert "no device connected after 0.3 s" in err[-1] and "Wiimote is paired" in err[-1]
    assert "board" not in err[-1]


def test_record_with_seconds_shorter_than_the_timeout_still_fails(tmp_path, capsys):
    rc = main(["record", "--source", f"serial://{tmp_path / 'nothing'}", "-o", str(tmp_path / "o.csv"), "--seconds", "0.2"])
    assert rc == 2
    err = capsys.readouterr().err
    assert "never connected" in err and "check the port" in err  # the same advice as after the timeout
    assert f"quickjab devices {tmp_path / 'nothing'}" in err  # the probe for a port the list never shows


def test_a_full_disk_leaves_a_recording_that_reads_to_its_last_whole_row(tmp_path):
    """A write that fails part-way (a full disk; here a file size limit, EFBIG) left half a row at
    the end, and the whole file was unreadable (`N fields, header has M`): the crash lost every
    row, not the last second. The writer cuts the file back to its last whole row."""
    src = tmp_path / "long.csv"
    rows = "".join(f"{i / 200:.6f},0.0123,-0.0456,1.0078,0.0011,-0.0222,0.9988,\n" for i in range(3000))
    src.write_text("# rate_hz: 200\nt,rx,ry,rz,lx,ly,lz,label\n" + rows)
    out = tmp_path / "out.csv"
    limit = 20_000  # bytes: not a multiple of any row's length

    def small_files() -> None:  # Python ignores SIGXFSZ: a write past the limit fails with EFBIG
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, resource.RLIM_INFINITY))

    proc = subprocess.run(
        [sys.executable, "-m", "tools.cli", "record", "--source", f"replay://{src}?speed=50", "-o", str(out), "--seconds", "20"],
        cwd=REPO, env={**os.environ, "PYTHONPATH": str(REPO)}, capture_output=True, text=True, timeout=60,
        preexec_fn=small_files,
    )
    assert proc.returncode == 2, proc.stderr
    assert "Traceback" not in proc.stderr and f"{out}: cannot write" in proc.stderr
    data = out.read_bytes()
    assert 0 < len(data) <= limit and data.endswith(b"\n")
    rec = read_recording(out)  # raised RecordingError: a partial last row
    assert len(rec) > 100 and rec.sensors == 2


def test_sigterm_ends_a_recording_as_ctrl_c_does(tmp_path):
    """`kill`, a service manager or `timeout` stop a recording with SIGTERM: it ended the process
    on the spot (status -15), without the summary, the final sync or the samples still held for
    the rate. Now it is Ctrl-C's clean end: exit 0, 'wrote N samples', and N rows in the file."""
    import signal

    out = tmp_path / "out.csv"
    proc = subprocess.Popen(
        [sys.executable, "-m", "tools.cli", "record", "--source", "demo://?rate=200", "-o", str(out)],
        cwd=REPO, env={**os.environ, "PYTHONPATH": str(REPO)}, stderr=subprocess.PIPE, text=True,
    )
    try:
        deadline = time.monotonic() + 30
        while not (out.exists() and out.read_bytes().count(b"\n") > 20) and time.monotonic() < deadline:
            time.sleep(0.05)
        proc.send_signal(signal.SIGTERM)
        err = proc.communicate(timeout=30)[1]
    finally:
        proc.kill()
    assert proc.returncode == 0, err
    assert "Traceback" not in err
    rows = len(read_recording(out))
    assert f"wrote {rows} samples to {out}" in err


def test_an_output_folder_that_cannot_take_the_file_is_said_before_recording(tmp_path, capsys, monkeypatch):
    """-o in a missing folder was found out only once the source had connected and sent samples:
    a Wiimote paired and the player ready, then 'cannot write'. Now before the source is opened.
    (A missing folder is made now, as for every output: a file where the folder would go cannot be.)"""
    import pytest

    import tools.record

    def no_source(*args, **kwargs):
        raise AssertionError("the source was opened before -o was refused")

    monkeypatch.setattr(tools.record, "open_source", no_source)
    (tmp_path / "plain").write_text("x")
    with pytest.raises(SystemExit) as exc:
        main(["record", "--source", "demo://", "-o", str(tmp_path / "plain" / "sub" / "out.csv"), "--seconds", "2"])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert "is not a directory" in err and "source demo://" not in err


def _swinging_recording(path: Path) -> Path:
    """Two seconds of two still hands, the right one swinging: what the emulated remote replays."""
    import numpy as np

    from engine.recording import Recording, write_recording

    t = np.arange(0, 2, 1 / 60)
    accel = np.zeros((len(t), 2, 3))
    accel[:, :, 2] = 1.0
    accel[:, 0, 0] = np.sin(2 * np.pi * t)
    write_recording(path, Recording(t, accel))
    return path


def test_record_from_an_emulated_wiimote_with_seconds_stops_by_itself(tmp_path, capsys):
    """`wiimote-emu://...?seconds=S` ends the source: `record` without --seconds stops there, as
    it does at the end of a replay, and the file holds the samples stamped before S. (How many
    there are depends on the machine: the emulated remote reports on the real clock, after a
    set-up that takes real time; so does how long the run takes.)"""
    rec = _swinging_recording(tmp_path / "rec.csv")
    out = tmp_path / "out.csv"
    rc = main(["record", "--source", f"wiimote-emu://{rec}?seconds=0.6", "-o", str(out)])  # no --seconds: S ends it
    err = capsys.readouterr().err
    assert rc == 0 and "wrote" in err, err
    got = read_recording(out)
    assert got.sensors == 2 and len(got) >= 1
    assert f"wrote {len(got)} samples to {out}" in err
    assert got.t[-1] - got.t[0] < 0.6  # every sample stamped before S (the first one after the set-up)


def test_the_kernel_driver_warning_is_said_once(tmp_path):
    """The Wiimote driver says a bound hid-wiimote once (its `notes`, each also logged); record,
    play, train and scope said a source's notes again after opening it, so the line came twice.
    What they say now is the source's `file_notes` (a replayed file's cut row), another list."""
    from engine.sensors import open_source

    rec = _swinging_recording(tmp_path / "rec.csv")
    url = f"wiimote-emu://{rec}?kernel_driver=1&seconds=0.5"
    source = open_source(url)
    try:
        assert any("hid-wiimote" in note for note in source.notes) and source.file_notes == []
    finally:
        source.close()
    out = tmp_path / "out.csv"
    proc = subprocess.run(  # its own process: stderr as a user sees it, the driver's log line included
        [sys.executable, "-m", "tools.cli", "record", "--source", url, "-o", str(out)],
        cwd=REPO, env={**os.environ, "PYTHONPATH": str(REPO)}, capture_output=True, text=True, timeout=120,
    )
    assert proc.returncode == 0, proc.stderr
    said = [line for line in proc.stderr.splitlines() if "bound to the kernel's hid-wiimote driver" in line]
    assert len(said) == 1, proc.stderr


def test_recording_over_a_file_keeps_the_old_one_beside_it(tmp_path, capsys):
    """-o naming a file that is there (a mistyped name, the last take) emptied it when the
    recording began: that take was lost. A file with anything in it is moved to a numbered name
    beside it first, and said; an empty one (mkstemp's) is written over without a word."""
    out = tmp_path / "take.csv"
    out.write_bytes(b"an earlier take\n")
    argv = ["record", "--source", "demo://?rate=200", "-o", str(out), "--seconds", "0.7"]
    assert main(argv) == 0
    aside = tmp_path / "take-old.csv"
    assert aside.read_bytes() == b"an earlier take\n"
    err = capsys.readouterr().err
    assert [line for line in err.splitlines() if "take-old" in line] == [f"{out} was not empty: moved to {aside}"]
    first = out.read_bytes()
    assert len(read_recording(out)) > 50
    assert main(argv) == 0
    assert (tmp_path / "take-old-2.csv").read_bytes() == first and aside.read_bytes() == b"an earlier take\n"
    assert f"moved to {tmp_path / 'take-old-2.csv'}" in capsys.readouterr().err
    empty = tmp_path / "empty.csv"
    empty.touch()
    assert main(["record", "--source", "demo://?rate=200", "-o", str(empty), "--seconds", "0.7"]) == 0
    assert "moved" not in capsys.readouterr().err and len(read_recording(empty)) > 50
    assert sorted(p.name for p in tmp_path.iterdir()) == ["empty.csv", "take-old-2.csv", "take-old.csv", "take.csv"]


def test_replaying_a_recording_cut_mid_row_says_the_row_left_out(tmp_path, capsys):
    # read_recording leaves the cut row out and notes it; the command that opened the file says it
    src = tmp_path / "cut.csv"
    rows = "".join(f"{i / 100:.6f},0.1234,0.1234,1.1234,\n" for i in range(40))
    src.write_text("# rate_hz: 100\n# recorded_from: demo://\nt,rx,ry,rz,label\n" + rows[:-4])  # '1.1234' cut to '1.1'
    out = tmp_path / "out.csv"
    assert main(["record", "--source", f"replay://{src}?speed=20", "-o", str(out), "--seconds", "5"]) == 0
    err = capsys.readouterr().err
    assert f"{src}:43: the last row has no line end" in err
    rec = read_recording(out)
    assert len(rec) == 39 and (rec.accel[:, 0, 2] == 1.1234).all()


def test_the_no_board_hint_offers_the_probe_for_a_named_port_only():
    """`quickjab devices auto` would try a file named auto: the hint for serial://auto leaves the
    probe out, and names the port for a path."""
    from tools.devices import no_device_hint

    assert "quickjab devices /dev/ttyACM0`" in no_device_hint("serial:///dev/ttyACM0?axes=x,y,z")
    assert "devices auto" not in no_device_hint("serial://auto?vid=2e8a") and "lists USB serial ports" in no_device_hint("serial://auto")


def _record_from_a_pty_board(tmp_path: Path, board_bytes: bytes) -> tuple[int, Path]:
    """`quickjab record` for 1 s from a raw pty whose board end writes `board_bytes` (from a
    thread, once the source has opened the port: its `?` asking for a HELLO; bytes written before
    are flushed by the open) over an existing out.csv."""
    import select
    import threading
    import tty

    master, slave = os.openpty()
    tty.setraw(slave)
    out = tmp_path / "out.csv"
    out.write_text("an earlier take\n")

    def board() -> None:
        if not board_bytes:
            return
        if select.select([master], [], [], 10.0)[0]:  # the host's `?` when it opened the port
            os.read(master, 64)
        for i in range(0, len(board_bytes), 2700):
            os.write(master, board_bytes[i : i + 2700])

    th = threading.Thread(target=board)
    th.start()
    try:
        rc = main(["record", "--source", f"serial://{os.ttyname(slave)}", "-o", str(out), "--seconds", "1"])
    finally:
        th.join()
        os.close(master)
        os.close(slave)
    return rc, out


def test_record_with_nothing_usable_from_the_board_writes_no_file_and_says_why(tmp_path, capsys):
    # A silent port, SAMPLEs without any HELLO, only malformed HELLOs: exit 0 and a header-only file
    # over the earlier one, `rate_hz: 60` guessed, and no word of what the board did send.
    from firmware_bridge import protocol

    sample = [protocol.encode_sample(i, 5000 * i, (0, 0, 4096), (0, 0, 4096)) for i in range(1, 101)]
    bad_hello = protocol.encode_frame(protocol.HELLO, 0, 0, 3, protocol.struct.pack(protocol.HELLO_FMT, 0, 65500, 200, 9, 30, 1))
    for board, said in ((b"", "the port sent nothing"),
                        (b"".join(sample), "samples_before_hello 100"),
                        (bad_hello * 3 + b"".join(sample), "malformed 3")):
        rc, out = _record_from_a_pty_board(tmp_path, board)
        err = capsys.readouterr().err.strip().splitlines()
        assert rc == 2 and out.read_text() == "an earlier take\n" and not (tmp_path / "out-old.csv").exists()
        assert "no samples" in err[-1] and said in err[-1] and "nothing recorded" in err[-1], err[-1]
