"""The recording CSV: every shared recording reads, the writer round-trips, bad files name
file and line, and the streaming writer's rows survive a SIGKILL."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

import engine.recording as recording
from engine.recording import (
    Recording,
    RecordingError,
    RecordingWriter,
    read_recording,
    write_recording,
)
from engine.sensors.source import Sample

REPO = Path(__file__).resolve().parents[2]


def test_reads_every_csv_under_shared_data(shared_data):
    paths = sorted(shared_data.rglob("*.csv"))
    assert len(paths) > 100
    sensors = set()
    for p in paths:
        rec = read_recording(p)
        assert len(rec) > 0 and rec.accel.shape == (len(rec), rec.sensors, 3)
        assert np.all(np.diff(rec.t) >= 0) and np.all(np.isfinite(rec.accel))
        assert len(rec.labels) == len(rec)
        sensors.add(rec.sensors)
    assert sensors == {1, 2}  # uWave and the phone are one hand, the gloves two


def test_phone_recording_has_labels_and_metadata(shared_data):
    rec = read_recording(shared_data / "phone-boxing" / "train.csv")
    assert rec.sensors == 1 and "source" in rec.meta and rec.meta["units"].startswith("g")
    assert {"jab", "cross", "hook", "uppercut"} <= set(rec.labels)
    assert "" in rec.labels


def random_recording(sensors: int, n: int = 300, seed: int = 0) -> Recording:
    rng = np.random.default_rng(seed)
    t = np.cumsum(rng.uniform(0.002, 0.04, n))
    accel = np.round(rng.normal(0, 1.5, (n, sensors, 3)), 4)
    labels = [("jab" if i % 50 < 20 else "") for i in range(n)]
    return Recording(t - t[0], accel, labels, {"source": "test, with a comma"})


@pytest.mark.parametrize("sensors", [1, 2])
def test_write_then_read_round_trips(tmp_path, sensors):
    rec = random_recording(sensors)
    path = tmp_path / "r.csv"
    write_recording(path, rec)
    back = read_recording(path)
    assert back.sensors == sensors and len(back) == len(rec)
    np.testing.assert_allclose(back.t, rec.t, atol=5e-7)
    np.testing.assert_array_equal(back.accel, rec.accel)
    assert back.labels == rec.labels
    assert back.meta["source"] == "test, with a comma"
    # and writing what was read gives the same bytes
    write_recording(tmp_path / "again.csv", back)
    assert (tmp_path / "again.csv").read_text() == path.read_text()


@pytest.mark.parametrize("sensors", [1, 2])
def test_streaming_writer_round_trips(tmp_path, sensors):
    rec = random_recording(sensors, seed=1)
    path = tmp_path / "s.csv"
    with RecordingWriter(path, sensors, {"source": "stream"}, t0=0.0) as w:
        for s, lab in zip(rec.samples(), rec.labels, strict=True):
            w.write(s, lab)
    back = read_recording(path)
    np.testing.assert_allclose(back.t, rec.t, atol=5e-7)
    np.testing.assert_array_equal(back.accel, rec.accel)
    assert back.labels == rec.labels and back.meta["source"] == "stream"


def test_writer_keeps_time_increasing(tmp_path):
    # docs/formats.md: t increases. A burst timed alike or a device clock that steps back would
    # write rows at one time (or going back, which the reader refuses: the whole file lost)
    path = tmp_path / "t.csv"
    with RecordingWriter(path, 1, t0=0.0) as w:
        for t in (0.0, 0.005, 0.005, 0.005, 0.004, 0.02):
            w.write(Sample(t, np.ones((1, 3))))
    assert w.nudged == 3
    assert read_recording(path).t.tolist() == [0.0, 0.005, 0.005001, 0.005002, 0.005003, 0.02]


def test_writer_starts_time_at_the_first_sample(tmp_path):
    path = tmp_path / "t.csv"
    with RecordingWriter(path, 1) as w:
        w.write(Sample(1000.5, np.ones((1, 3))))
        w.write(Sample(1000.75, np.ones((1, 3))))
    assert read_recording(path).t.tolist() == [0.0, 0.25]


def test_reader_accepts_extra_columns_any_order_and_blank_lines(tmp_path):
    path = tmp_path / "x.csv"
    path.write_text(
        "# rate_hz: 25\n# whatever: 1: 2\n\nlabel,gx,t,rz,ry,rx,buttons\n"
        "jab,9,0.0,1.0,0.5,0.25,A\n\n,9,0.04,1.5,0.5,0.25,\n"
    )
    rec = read_recording(path)
    assert rec.sensors == 1 and rec.meta == {"rate_hz": "25", "whatever": "1: 2"}
    np.testing.assert_array_equal(rec.accel[:, 0], [[0.25, 0.5, 1.0], [0.25, 0.5, 1.5]])
    assert rec.labels == ["jab", ""]


BAD_FILES = {
    "missing_column.csv": ("t,rx,ry,label\n0,1,2,\n", 1, "rz"),
    "text_in_number.csv": ("# rate_hz: 60\nt,rx,ry,rz\n0.0,1,2,3\n0.1,1,abc,3\n", 4, "abc"),
    "backwards.csv": ("t,rx,ry,rz,lx,ly,lz\n0.0,1,2,3,4,5,6\n0.2,1,2,3,4,5,6\n0.1,1,2,3,4,5,6\n", 4, "backwards"),
    "short_row.csv": ("t,rx,ry,rz\n0.0,1,2,3\n0.1,1\n", 3, "fields"),
    "half_left_hand.csv": ("t,rx,ry,rz,lx\n0.0,1,2,3,4\n", 1, "lx,ly,lz"),
    "nan.csv": ("t,rx,ry,rz\n0.0,1,nan,3\n", 2, "finite"),
    "huge_accel.csv": ("t,rx,ry,rz,lx,ly,lz\n0.0,0,0,1,0,0,1\n0.1,0,0,1,0,-1e300,1\n", 3, "over the 1000 g"),
    "accel_over_limit.csv": ("t,rx,ry,rz\n0.0,0,0,1\n0.1,1000.5,0,1\n", 3, "1000.5 g"),
    "empty.csv": ("# rate_hz: 60\n", None, "header"),
    "no_rows.csv": ("t,rx,ry,rz\n", None, "no samples"),
}


@pytest.mark.parametrize("name", sorted(BAD_FILES))
def test_bad_files_raise_an_error_naming_file_and_line(tmp_path, name):
    text, line, words = BAD_FILES[name]
    path = tmp_path / name
    path.write_text(text)
    with pytest.raises(RecordingError) as err:
        read_recording(path)
    msg = str(err.value)
    assert str(path) in msg and words in msg and "\n" not in msg
    assert err.value.line == line
    if line:
        assert f"{path}:{line}:" in msg


def test_accelerations_up_to_the_limit_are_read_and_time_is_not_one(tmp_path):
    """MAX_ACCEL_G bounds |rx..lz| only: t may be large, and +-1000 g itself is still read."""
    path = tmp_path / "edge.csv"
    path.write_text("t,rx,ry,rz\n5000.0,-1000,0,1000\n5000.1,0,0,1\n")
    rec = read_recording(path)
    assert recording.MAX_ACCEL_G == 1000.0 and rec.accel[0, 0].tolist() == [-1000.0, 0.0, 1000.0]


def test_binary_and_missing_files(tmp_path):
    path = tmp_path / "bin.csv"
    path.write_bytes(b"\xff\xfe\x00garbage")
    with pytest.raises(RecordingError, match="bin.csv"):
        read_recording(path)
    with pytest.raises(RecordingError, match="nope.csv"):
        read_recording(tmp_path / "nope.csv")


def test_writer_fsyncs_at_least_every_quarter_second(tmp_path, monkeypatch):
    now = [100.0]
    syncs = []
    monkeypatch.setattr(recording.time, "monotonic", lambda: now[0])
    monkeypatch.setattr(recording.os, "fsync", lambda fd: syncs.append(now[0]))
    w = RecordingWriter(tmp_path / "f.csv", 1)
    assert syncs == [100.0]  # the header
    w.write(Sample(0.0, np.zeros((1, 3))))
    now[0] = 100.1
    w.write(Sample(0.1, np.zeros((1, 3))))
    assert syncs == [100.0]
    now[0] = 100.3
    w.flush_if_due()  # a silent source: the recording loop still calls this
    assert syncs == [100.0, 100.3]
    now[0] = 101.0
    w.flush_if_due()  # nothing new since: no needless fsync
    assert syncs == [100.0, 100.3]
    w.close()


WRITER_SCRIPT = """
import sys, time
import numpy as np
from engine.recording import RecordingWriter
from engine.sensors.source import Sample
w = RecordingWriter(sys.argv[1], 2, t0=0.0)
for i in range(int(sys.argv[2])):
    w.write(Sample(i / 100, np.full((2, 3), i / 10)))
print("written", flush=True)
time.sleep(60)  # killed long before this ends; the writer is never closed
"""


def test_rows_written_before_a_sigkill_are_in_the_file(tmp_path):
    path = tmp_path / "killed.csv"
    proc = subprocess.Popen(
        [sys.executable, "-c", WRITER_SCRIPT, str(path), "37"],
        cwd=REPO, stdout=subprocess.PIPE, text=True,
        env={**os.environ, "PYTHONPATH": str(REPO)},
    )
    try:
        assert proc.stdout.readline().strip() == "written"
        # a reader sees the rows while the writer is still alive (not closed, not flushed by exit)
        deadline = time.monotonic() + 5
        while len(read_recording(path)) < 37 and time.monotonic() < deadline:
            time.sleep(0.05)
        assert len(read_recording(path)) == 37
    finally:
        proc.send_signal(signal.SIGKILL)
        proc.wait()
    rec = read_recording(path)
    assert len(rec) == 37 and rec.sensors == 2
    assert rec.accel[-1, 1, 2] == pytest.approx(3.6)


def test_awkward_labels_metadata_and_a_bom_round_trip(tmp_path):
    rec = Recording(np.array([0.0, 0.5]), np.zeros((2, 1, 3)), ['jab, then "cross"', "hook"],
                    {"note": "two\nlines"})
    path = tmp_path / "odd.csv"
    write_recording(path, rec)
    back = read_recording(path)
    assert back.labels == rec.labels and back.meta["note"] == "two lines"
    bom = tmp_path / "bom.csv"
    bom.write_bytes(b"\xef\xbb\xbft,rx,ry,rz\r\n0,1,2,3\r\n")
    assert read_recording(bom).accel.tolist() == [[[1.0, 2.0, 3.0]]]


def test_text_from_a_non_utf8_file_name_or_argument_is_written_escaped(tmp_path):
    """Python hands bytes that are not UTF-8 in argv or a file name over as lone surrogates:
    `record --label $'\\xff'` or `--source replay://$'\\xff'.csv` (its URL is the metadata's
    recorded_from) raised UnicodeEncodeError on the first row or the header."""
    odd = "\udcff"  # what b"\xff" decodes to with the file system's surrogateescape
    path = tmp_path / "odd.csv"
    with RecordingWriter(path, 1, {"recorded_from": f"replay://{odd}.csv"}) as w:
        w.write(Sample(0.0, np.array([0.0, 0.0, 1.0])), odd)
        w.write(Sample(0.1, np.array([0.0, 0.0, 1.0])), odd)
    back = read_recording(path)
    assert back.labels == ["\\udcff"] * 2 and back.meta["recorded_from"] == "replay://\\udcff.csv"
    write_recording(tmp_path / "whole.csv", Recording(back.t, back.accel, [odd] * 2, {"source": odd}))
    assert read_recording(tmp_path / "whole.csv").labels == ["\\udcff"] * 2


def _recorded(path: Path, rows: int) -> bytes:
    """A file as `quickjab record` writes it (its `recorded_from` line), `rows` two-hand rows."""
    with RecordingWriter(path, 2, {"source": "demo", "recorded_from": "demo://"}) as w:
        for i in range(rows):
            w.write(Sample(i / 100, np.full((2, 3), 0.1234 + i)), "jab")
    return path.read_bytes()


@pytest.mark.parametrize("keep", [-3, -8, -30])  # inside the label, inside the last number, fields short
def test_a_recording_cut_mid_row_reads_without_its_cut_row_and_says_so(tmp_path, keep):
    """A power cut mid-write leaves the last row without its line end, often inside a number
    ('1.1234' cut to '1.1'): that row was read as if whole. Our writer ends every row with one,
    so in a file of ours a last line without it is a cut row: left out, and noted (file, line)."""
    path = tmp_path / "cut.csv"
    data = _recorded(path, 10)
    path.write_bytes(data[:keep])
    rec = read_recording(path)
    assert len(rec) == 9
    assert rec.accel[-1, 1, 2] == pytest.approx(8.1234)
    line = data.count(b"\n")  # the cut row's line: the file's last
    assert len(rec.notes) == 1 and rec.notes[0].startswith(f"{path}:{line}: ")
    assert "cut" in rec.notes[0] and "\n" not in rec.notes[0]
    path.write_bytes(data)
    assert len(read_recording(path)) == 10 and read_recording(path).notes == []


def test_a_hand_written_csv_without_a_final_line_end_keeps_its_last_row(tmp_path):
    # only a file that says it is ours (`recorded_from`) is known to end every row with a line end
    path = tmp_path / "hand.csv"
    path.write_text("# rate_hz: 60\n# source: made by hand\nt,rx,ry,rz\n0.0,0,0,1\n0.1,0,0,1.25")
    rec = read_recording(path)
    assert len(rec) == 2 and rec.accel[-1, 0, 2] == 1.25 and rec.notes == []
    path.write_text("t,rx,ry,rz\n0.0,0,0,1\n0.1,0")
    with pytest.raises(RecordingError, match="fields"):  # as before: a short row in a file of anyone's
        read_recording(path)
