"""`quickjab record` with a source that never connects: a clear error and exit 2, no file."""

from __future__ import annotations

import time

from tools.cli import main


def test_record_from_a_missing_serial_port_exits_2(tmp_path, capsys):
    out = tmp_path / "out.csv"
    t0 = time.perf_counter()
    rc = main(["record", "--source", f"serial://{tmp_path / 'no-such-port'}", "-o", str(out), "--connect-timeout", "0.5"])
    elapsed = time.perf_counter() - t0
    err = capsys.readouterr().err
    assert rc == 2
    assert "no device connected after 0.5 s" in err
    assert "wrote 0 samples" not in err
    assert not out.exists()
    assert elapsed < 10  # ended by the connect timeout, not by hand


def test_record_from_serial_auto_without_a_board_exits_2(tmp_path, capsys):
    out = tmp_path / "out.csv"
    rc = main(["record", "--source", "serial://auto?vid=ffff&pid=fffe", "-o", str(out), "--connect-timeout", "0.3"])
    assert rc == 2
    assert "serial://auto" in capsys.readouterr().err
    assert not out.exists()


def test_record_with_seconds_shorter_than_the_timeout_still_fails(tmp_path, capsys):
    rc = main(["record", "--source", f"serial://{tmp_path / 'nothing'}", "-o", str(tmp_path / "o.csv"), "--seconds", "0.2"])
    assert rc == 2
    assert "never connected" in capsys.readouterr().err
