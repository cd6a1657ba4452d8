"""The commands end to end, as a user runs them: record from the emulated Wiimote, record
from a real one when none is attached, list devices."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from engine.recording import Recording, read_recording, write_recording
from engine.sensors.wiimote import list_wiimotes

REPO = Path(__file__).resolve().parents[3]


def quickjab(*args: str, timeout: float = 60) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": str(REPO), "SDL_VIDEODRIVER": "dummy", "SDL_AUDIODRIVER": "dummy"}
    return subprocess.run(
        [sys.executable, "-m", "tools.cli", *args], cwd=REPO, env=env, capture_output=True, text=True, timeout=timeout
    )


def test_record_from_emulated_wiimote(tmp_path):
    t = np.arange(0, 3, 1 / 60)
    a = np.zeros((len(t), 2, 3))
    a[:, 0] = [0.1, -0.2, 0.95]  # still hands: any stretch of the recording reads the same
    a[:, 1] = [-0.3, 0.25, 0.9]
    src = tmp_path / "in.csv"
    write_recording(src, Recording(t, a))
    out = tmp_path / "out.csv"
    r = quickjab("record", "--source", f"wiimote-emu://{src}?pad=22&jitter_ms=3", "-o", str(out), "--seconds", "1")
    assert r.returncode == 0, r.stderr
    assert "connected" in r.stderr
    rec = read_recording(out)
    assert rec.sensors == 2
    assert 50 <= len(rec) <= 110  # ~100 Hz for a second, less the set-up round trips
    # Within one count of the recording (and the 4-decimal CSV rounding).
    assert np.allclose(rec.accel[:, 0], [0.1, -0.2, 0.95], atol=1 / 100 + 1e-4)
    assert np.allclose(rec.accel[:, 1], [-0.3, 0.25, 0.9], atol=1 / 200 + 1e-4)


def record_still_hands(tmp_path, params: str, seconds: str) -> list[str]:
    """`quickjab record` from the emulated remote replaying still hands with `params`; what it
    said about its source on the console, in order."""
    t = np.arange(0, 3, 1 / 60)
    src = tmp_path / "in.csv"
    write_recording(src, Recording(t, np.tile([0.0, 0.0, 1.0], (len(t), 2, 1))))
    url = f"wiimote-emu://{src}?{params}"
    r = quickjab("record", "--source", url, "-o", str(tmp_path / "out.csv"), "--seconds", seconds)
    assert r.returncode == 0, r.stderr
    return [line.split(": ", 1)[1] for line in r.stderr.splitlines() if line.startswith(f"source {url}: ")]


def test_record_says_when_the_nunchuk_is_out_and_back(tmp_path):
    # the left hand's columns lie still meanwhile: the console says why
    said = record_still_hands(tmp_path, "nunchuk_out_at=0.3&nunchuk_in_at=0.7", "1.2")
    assert said[-2:] == ["no Nunchuk: plug it in for left-hand moves", "nothing missing now"], said


def test_record_does_not_say_the_nunchuk_is_back_when_the_remote_goes(tmp_path):
    # the remote lost with its Nunchuk out: "nothing missing now" came with the disconnection
    said = record_still_hands(tmp_path, "nunchuk=0&unplug_at=0.5&replug_at=1", "2")
    assert "disconnected" in said and "connected" in said[said.index("disconnected"):], said
    assert said.count("no Nunchuk: plug it in for left-hand moves") == 1 and "nothing missing now" not in said, said


def test_record_from_absent_wiimote_explains_pairing(tmp_path):
    if list_wiimotes():
        return  # a Wiimote is really attached here: nothing to explain
    r = quickjab("record", "--source", "wiimote://", "-o", str(tmp_path / "x.csv"), "--seconds", "1")
    assert r.returncode == 2
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and "no Wiimote found" in lines[0] and "pair" in lines[0]
    assert "Traceback" not in r.stderr


def test_devices_lists_both_kinds():
    r = quickjab("devices")
    assert r.returncode == 0, r.stderr
    assert "Wiimotes:" in r.stdout and "Serial ports:" in r.stdout
    if "none found" in r.stdout:  # the pairing hint, without pointing at this very command
        assert "pair one first" in r.stdout and "quickjab devices" not in r.stdout
    j = json.loads(quickjab("devices", "--json").stdout)
    assert set(j) >= {"wiimotes", "serial_ports"}
    for w in j["wiimotes"]:
        assert w["model"].startswith("RVL-CNT-01") and w["path"]


def test_bench_wiimote_prints_figures():
    r = quickjab("bench", "wiimote", "--seconds", "2", "--json")
    assert r.returncode == 0, r.stderr
    fig = json.loads(r.stdout)
    assert 80 <= fig["samples_per_s"] <= 110  # (2 s minus the set-up) at ~100 Hz
    assert fig["poll_median_us"] > 0 and fig["decode_report_us"] > 0


@pytest.mark.parametrize("args", [("bench", "wiimote", "--seconds", "nan"), ("bench", "wiimote", "--seconds", "-1"),
                                  ("scope", "--headless", "--frames", "1", "--connect-timeout", "inf")])
def test_bad_seconds_are_an_argparse_error(args, capsys):
    from tools.cli import main

    with pytest.raises(SystemExit) as exit_:
        main(list(args))
    assert exit_.value.code == 2
    err = capsys.readouterr().err
    assert args[-2] in err and "Traceback" not in err


def test_emulator_bad_input_names_itself(tmp_path):
    missing = tmp_path / "nope.csv"
    r = quickjab("record", "--source", f"wiimote-emu://{missing}", "-o", str(tmp_path / "o.csv"), "--seconds", "1")
    assert r.returncode == 2 and str(missing) in r.stderr and "Traceback" not in r.stderr
    write_recording(tmp_path / "ok.csv", Recording(np.arange(0, 1, 1 / 60), np.zeros((60, 1, 3))))
    r = quickjab("record", "--source", f"wiimote-emu://{tmp_path / 'ok.csv'}?drop=lots", "-o", str(tmp_path / "o.csv"))
    assert r.returncode == 2 and "bad option" in r.stderr
