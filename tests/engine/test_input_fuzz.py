"""Fuzzing the engine's input readers (issue 16): recordings, template files, traces, source
URLs and argument types. Property of every reader: a clean error (an InputError naming the
input) or a valid result; never another exception, never memory that grows with what a file
merely claims, never a hang (each example has a deadline)."""

from __future__ import annotations

import argparse
import io
import json
import math
import os
import tracemalloc
import zipfile
from datetime import timedelta
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from engine import arguments
from engine.errors import InputError
from engine.frames import recording_frames
from engine.npz_files import NpzFileError, read_npz
from engine.recognition.templates import TemplateFileError, Templates
from engine.recording import (
    MAX_ACCEL_G,
    MAX_DURATION_S,
    MAX_META_KEYS,
    RecordingError,
    read_recording,
)
from engine.sensors.source import SourceError, SourceState, open_source
from engine.trace import TraceError, read_chrome_trace
from tools.profile import profile_summary

REPO = Path(__file__).resolve().parents[2]
TEMPLATES = REPO / "game" / "assets" / "templates.npz"
FUZZ = settings(max_examples=25, deadline=timedelta(seconds=10), derandomize=True,
                suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])

GOOD_CSV = "# rate_hz: 60\nt,rx,ry,rz,lx,ly,lz,label\n" + "".join(
    f"{i / 60:.6f},0.1,0.2,1.0,0.0,0.1,0.9,{'jab' if 10 <= i < 20 else ''}\n" for i in range(40)
)
# pieces a hostile edit splices in: numbers out of range, quotes, separators, long fields
NASTY = st.sampled_from([
    "nan", "inf", "-inf", "1e308", "1e7", "-1", "0", "", ",", '"', "\n", "\r", "\x00", "#", "t",
    "x" * 200_000, "1" * 5000, "\ufeff", "\xff", ",,,,,,,,", "1e-320", "10000000", "  ",
])


def _mutate(text: str, data: st.DataObject) -> str:
    for _ in range(data.draw(st.integers(1, 4))):
        i = data.draw(st.integers(0, len(text)))
        j = data.draw(st.integers(i, min(len(text), i + 12)))
        text = text[:i] + data.draw(NASTY | st.text(max_size=8)) + text[j:]
    return text


@FUZZ
@given(st.data())
def test_recording_reader_gives_a_valid_recording_or_a_clean_error(tmp_path_factory, data):
    path = tmp_path_factory.mktemp("rec") / "r.csv"
    path.write_text(_mutate(GOOD_CSV, data), encoding="utf-8", errors="surrogatepass")
    try:
        rec = read_recording(path)
    except RecordingError as exc:
        assert str(path) in str(exc) and "\n" not in str(exc)
        return
    assert np.isfinite(rec.t).all() and (np.abs(rec.accel) <= MAX_ACCEL_G).all()
    assert (np.diff(rec.t) >= 0).all() and rec.t[-1] - rec.t[0] <= MAX_DURATION_S
    assert len(rec) == 1 or rec.t[-1] > rec.t[0]
    times, frames, labels = recording_frames(rec)  # the resampler copes with anything accepted
    assert len(frames) == len(times) == len(labels) <= MAX_DURATION_S * 60 + 1


@FUZZ
@given(st.binary(max_size=4000))
def test_recording_reader_on_random_bytes(tmp_path_factory, blob):
    path = tmp_path_factory.mktemp("rec") / "r.csv"
    path.write_bytes(blob)
    try:
        read_recording(path)
    except RecordingError:
        pass


def test_tiny_recording_claiming_a_long_time_is_refused_without_memory(tmp_path):
    path = tmp_path / "gap.csv"
    path.write_text("t,rx,ry,rz\n0,0,0,1\n10000000,0,0,1\n")
    tracemalloc.start()
    try:
        with pytest.raises(RecordingError, match="limit|gap"):
            read_recording(path)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 5 * 2**20


def test_reading_a_big_recording_streams(tmp_path, peak_memory):
    """Memory of a 14 MB CSV: the numbers (56 bytes a row) plus one chunk of rows as text, not
    the text many times over (the whole-text reader peaked at 16x the file)."""
    path = tmp_path / "big.csv"
    rows = 400_000
    with open(path, "w") as f:
        f.write("t,rx,ry,rz,lx,ly,lz,label\n")
        for start in range(0, rows, 50_000):
            f.write("".join(f"{i / 100:.2f},0.1,0.2,1.0,0.0,0.1,0.9,jab\n" for i in range(start, start + 50_000)))
    size = path.stat().st_size
    rec, peak = peak_memory(lambda: read_recording(path))
    assert len(rec) == rows
    assert peak < rows * 56 * 1.5 + 8 * 2**20 < 3 * size, (peak, size)


def test_a_flood_of_line_ends_does_not_size_the_array(tmp_path, peak_memory):
    path = tmp_path / "cr.csv"  # every '\r' a line end: the line count said a million rows
    path.write_bytes(b"t,rx,ry,rz,lx,ly,lz,label\n0,0,0,1,0,0,1,\n" + b"\r" * 2**20 + b"1,0,0,1,0,0,1,\n")
    rec, peak = peak_memory(lambda: read_recording(path))
    assert len(rec) == 2
    # room for the rows the bytes can hold, 60 bytes of numbers per 14 bytes of text (was 60x)
    assert peak < 5 * path.stat().st_size, (peak, path.stat().st_size)


def test_a_row_of_millions_of_fields_is_refused_before_it_is_split(tmp_path, peak_memory):
    """csv's field limit bounds one field, not a row: a 200 MB row of "0," (extra columns,
    ignored) was split into 100 million fields first, 1 GB of list. A row is a line, held to
    the header's limit."""
    path = tmp_path / "wide.csv"
    path.write_text("t,rx,ry,rz,lx,ly,lz,label\n0,0,0,1,0,0,1,\n0.1,0,0,1,0,0,1" + ",0" * 4_000_000 + "\n")
    err, peak = peak_memory(lambda: pytest.raises(RecordingError, read_recording, path))
    assert "line over" in str(err.value) and err.value.line == 3
    assert peak < 3 * path.stat().st_size, (peak, path.stat().st_size)  # split, the row took 4x


def test_a_flood_of_metadata_keys_is_refused_without_holding_them(tmp_path, peak_memory):
    """Every distinct `# key: value` line was kept in the metadata dict: some 100 bytes of
    Python objects per line, 11 times the file (33 MB of keys took 400 MB)."""
    path = tmp_path / "meta.csv"
    path.write_text("".join(f"#k{i:x}: v\n" for i in range(300_000)) + "t,rx,ry,rz\n0,0,0,1\n0.1,0,0,1\n")
    err, peak = peak_memory(lambda: pytest.raises(RecordingError, read_recording, path))
    assert "metadata" in str(err.value) and err.value.line == MAX_META_KEYS + 1
    assert peak < path.stat().st_size, (peak, path.stat().st_size)
    ok = tmp_path / "ok.csv"  # as many keys as allowed, and any number of comments or repeats
    ok.write_text("".join(f"# k{i}: v\n# a comment\n# k0: again\n" for i in range(MAX_META_KEYS)) + "t,rx,ry,rz\n0,0,0,1\n")
    assert len(read_recording(ok).meta) == MAX_META_KEYS


@pytest.mark.parametrize("kind", ["fifo", "dir"])
def test_non_regular_files_are_refused_at_once(tmp_path, kind):
    path = tmp_path / "x.csv"
    if kind == "fifo":
        os.mkfifo(path)  # opening it would block until a writer comes: it must not be opened
    else:
        path.mkdir()
    with pytest.raises(RecordingError, match="regular file|directory"):
        read_recording(path)
    with pytest.raises(TemplateFileError):
        Templates.load(path)
    with pytest.raises(TraceError):
        read_chrome_trace(path)


# ------------------------------------------------------------------------------ npz files

def _good_template_arrays() -> dict[str, np.ndarray]:
    with np.load(TEMPLATES, allow_pickle=False) as z:
        return {k: z[k] for k in z.files}


def _save(path: Path, arrays: dict[str, np.ndarray]) -> None:
    with open(path, "wb") as f:
        np.savez_compressed(f, **arrays)


def _bomb(path: Path, member: str, nbytes: int) -> None:
    """An npz whose member really decompresses to `nbytes` (of zeros): small on disk."""
    header = np.lib.format.header_data_from_array_1_0(np.zeros(1))
    header["shape"] = (nbytes // 8,)
    buf = io.BytesIO()
    np.lib.format.write_array_header_1_0(buf, header)
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED, compresslevel=1) as z, z.open(member + ".npy", "w", force_zip64=True) as f:
        f.write(buf.getvalue())
        chunk = bytes(2**22)
        for _ in range(nbytes // len(chunk)):
            f.write(chunk)


def test_template_zip_bomb_is_refused_before_it_is_inflated(tmp_path):
    path = tmp_path / "bomb.npz"
    _bomb(path, "signals", 300 * 2**20)
    assert path.stat().st_size < 2 * 2**20
    tracemalloc.start()
    try:
        with pytest.raises(TemplateFileError, match="limit"):
            Templates.load(path)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 20 * 2**20


def test_an_archive_of_a_great_many_members_is_refused_before_its_directory_is_read(tmp_path, peak_memory):
    """zipfile reads the whole central directory, some 400 bytes of Python objects per entry,
    before the member count could be checked: 24 MB of empty entries took 115 MB."""
    path = tmp_path / "many.npz"
    with zipfile.ZipFile(path, "w", zipfile.ZIP_STORED) as z:
        for i in range(100_000):
            z.writestr(f"{i:x}", b"")
    err, peak = peak_memory(lambda: pytest.raises(NpzFileError, read_npz, path, 2**30))
    assert "members" in str(err.value)
    assert peak < path.stat().st_size / 4, (peak, path.stat().st_size)


def test_npz_member_claiming_more_than_it_holds_is_refused(tmp_path):
    path = tmp_path / "lie.npz"
    header = np.lib.format.header_data_from_array_1_0(np.zeros(1))
    header["shape"] = (10**12,)
    buf = io.BytesIO()
    np.lib.format.write_array_header_1_0(buf, header)
    with zipfile.ZipFile(path, "w") as z:
        z.writestr("signals.npy", buf.getvalue() + bytes(64))
    with pytest.raises(NpzFileError, match="more data than it holds"):
        read_npz(path, 2**30)


def test_npy_instead_of_npz_is_named(tmp_path):
    path = tmp_path / "a.npy"
    np.save(path, np.zeros(3))
    with pytest.raises(TemplateFileError, match=r"\.npy"):
        Templates.load(path)


def test_deeply_nested_settings_are_a_corrupt_file_not_a_recursion_error(tmp_path):
    path = tmp_path / "deep.npz"
    _save(path, {**_good_template_arrays(), "recognizer": np.array("[" * 100_000)})
    with pytest.raises(TemplateFileError, match="nested too deeply"):
        Templates.load(path)


def test_shipped_templates_still_load():
    t = Templates.load(TEMPLATES)
    assert len(t) > 0 and np.isfinite(t.gravity).all()


VALUES = st.sampled_from([np.nan, np.inf, -np.inf, -1.0, 0.0, 1e300, 7.0])


@FUZZ
@given(st.data())
def test_template_loader_gives_templates_or_a_clean_error(tmp_path_factory, data):
    arrays = _good_template_arrays()
    for _ in range(data.draw(st.integers(1, 3))):
        key = data.draw(st.sampled_from(sorted(arrays)))
        how = data.draw(st.sampled_from(["drop", "poke", "shape", "dtype", "text", "empty"]))
        a = arrays[key]
        if how == "drop":
            arrays.pop(key)
        elif how == "poke" and a.size and a.dtype.kind in "iuf":
            a = a.astype(np.float64).copy()
            a.flat[data.draw(st.integers(0, a.size - 1))] = data.draw(VALUES)
            arrays[key] = a
        elif how == "shape" and a.ndim:
            arrays[key] = a[: data.draw(st.integers(0, max(0, len(a) - 1)))]
        elif how == "dtype":
            arrays[key] = np.asarray(a).astype(str)
        elif how == "text":
            arrays[key] = np.array(data.draw(st.text(max_size=10)))
        elif how == "empty":
            arrays[key] = np.zeros((0,) * max(a.ndim, 1))
    path = tmp_path_factory.mktemp("tpl") / "t.npz"
    _save(path, arrays)
    try:
        t = Templates.load(path)
    except TemplateFileError as exc:
        assert str(path) in str(exc) and "\n" not in str(exc)
        return
    assert np.isfinite(t.gravity).all() and not np.isnan(t.thresholds).any() and (t.thresholds >= 0).all()
    assert all(np.isfinite(s).all() and s.shape[1] == t.dim for s in t.signals)
    assert ((t.onsets >= 0) & (t.onsets < [len(s) for s in t.signals])).all()


# ------------------------------------------------------------------------------ traces

JSON_LEAF = st.none() | st.booleans() | st.integers(-(10**20), 10**20) | st.floats(allow_nan=True) | st.text(max_size=6)
JSON = st.recursive(JSON_LEAF, lambda kids: st.lists(kids, max_size=4) | st.dictionaries(st.text(max_size=6), kids, max_size=4),
                    max_leaves=20)
FIELD = st.sampled_from(["ph", "name", "ts", "dur", "args", "steps", "wait_us", "unaccounted_us", "dropped", "depth"])


def _good_trace() -> dict:
    frame = {"ph": "X", "name": "frame", "ts": 0, "dur": 900, "args": {"steps": 1, "wait_us": 100, "unaccounted_us": 3}}
    stage = {"ph": "X", "name": "physics", "ts": 5, "dur": 200, "args": {"depth": 0}}  # every X event has args
    return {"traceEvents": [frame, stage, {**frame, "ts": 1000}, {**stage, "ts": 1005}],
            "otherData": {"frame_budget_ms": 16.7, "stages": {"physics": {"budget_ms": 2.0}}}}


@FUZZ
@given(st.data())
def test_trace_reader_and_profile_give_a_summary_or_a_clean_error(tmp_path_factory, data):
    trace = _good_trace()
    for _ in range(data.draw(st.integers(1, 3))):
        target = data.draw(st.sampled_from(["event", "args", "other", "stages", "root"]))
        value = data.draw(JSON)
        try:  # an earlier edit may have replaced what this one edits: then this one is moot
            if target == "event":
                trace["traceEvents"][data.draw(st.integers(0, 3))][data.draw(FIELD)] = value
            elif target == "args":
                trace["traceEvents"][data.draw(st.integers(0, 3))]["args"][data.draw(FIELD)] = value
            elif target == "other":
                trace["otherData"][data.draw(st.sampled_from(["frame_budget_ms", "frame_period_ms", "stages"]))] = value
            elif target == "stages":
                trace["otherData"]["stages"]["physics"] = value
            else:
                trace[data.draw(st.sampled_from(["traceEvents", "otherData"]))] = value
        except (TypeError, KeyError, IndexError):
            pass
    path = tmp_path_factory.mktemp("trace") / "t.json"
    path.write_text(json.dumps(trace), encoding="utf-8")
    try:
        t = read_chrome_trace(path)
    except TraceError as exc:
        assert str(path) in str(exc) and "\n" not in str(exc)
        return
    s = profile_summary(t)
    assert s["frames"] >= 1 and math.isfinite(s["frame_budget_ms"]) and s["frame_budget_ms"] > 0


def test_deeply_nested_trace_is_a_clean_error(tmp_path):
    path = tmp_path / "deep.json"
    path.write_text("[" * 100_000 + "]" * 100_000)
    with pytest.raises(TraceError, match="nested"):
        read_chrome_trace(path)


# ------------------------------------------------------------------------------ source URLs

@pytest.fixture(scope="module")
def small_recording(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("url") / "r.csv"
    path.write_text(GOOD_CSV)
    return path


URL_VALUES = st.sampled_from(["nan", "inf", "-1", "0", "2", "1e9", "1e-300", "x", "", "0.5", "4", "22", "100", "-0"])


@FUZZ
@given(st.data())
def test_source_urls_open_and_poll_or_give_a_clean_error(small_recording, data):
    scheme, keys = data.draw(st.sampled_from([
        ("demo://", ["rate"]),
        (f"replay://{small_recording}", ["speed", "loop"]),
        (f"wiimote-emu://{small_recording}", ["drop", "latency_ms", "jitter_ms", "pad", "seed", "start", "player",
                                               "unplug_at", "loss", "clone"]),
    ]))
    params = data.draw(st.dictionaries(st.sampled_from(keys), URL_VALUES, max_size=3))
    url = scheme + ("?" + "&".join(f"{k}={v}" for k, v in params.items()) if params else "")
    now = [0.0]
    try:
        src = open_source(url, clock=lambda: now[0])
    except SourceError as exc:
        assert "\n" not in str(exc)
        return
    try:
        for _ in range(30):
            now[0] += 1 / 60
            for s in src.poll():
                assert np.isfinite(s.accel).all()
        assert src.state in tuple(SourceState)
    finally:
        src.close()


def test_wiimote_emulator_polls_a_long_recording(tmp_path):
    """A 400k-row recording delivers what a 400-row one does. Each report used to interp over
    whole copied columns (O(n) per report: 400k rows never returned); the deadline here is a
    hang guard, far above the time the work takes, not a speed figure (tools/bench_wiimote)."""
    from time import monotonic

    def samples_in(rows: int) -> int:
        path = tmp_path / f"r{rows}.csv"
        path.write_text("t,rx,ry,rz,lx,ly,lz\n" + "".join(f"{i / 100:.2f},0.1,0,1,0,0.1,1\n" for i in range(rows)))
        now = [0.0]
        src = open_source(f"wiimote-emu://{path}?jitter_ms=0", clock=lambda: now[0])
        got, deadline = 0, monotonic() + 60
        for _ in range(120):
            now[0] += 1 / 60
            got += len(src.poll())
            assert monotonic() < deadline, "poll() stalls on a long recording"
        src.close()
        return got

    assert samples_in(400_000) == samples_in(400) > 100


# ------------------------------------------------------------------------------ argument types

@FUZZ
@given(st.text(max_size=12) | st.sampled_from(["nan", "inf", "-inf", "-1", "0", "1e400", "1_000", "20000x20000", "0x0", "160x120"]))
def test_argument_types_give_a_value_in_range_or_an_argparse_error(text):
    for parse, ok in (
        (arguments.seed, lambda v: 0 <= v <= arguments.SEED_MAX),
        (arguments.positive_int, lambda v: v >= 1),
        (arguments.float_range(0.0, 10.0, lo_open=True), lambda v: 0 < v <= 10 and math.isfinite(v)),
        (arguments.non_negative_float, lambda v: v >= 0 and math.isfinite(v)),
        (arguments.window_size, lambda v: True),
    ):
        try:
            v = parse(text)
        except argparse.ArgumentTypeError:
            continue
        assert ok(v), (parse, text, v)
    try:
        arguments.window_size(text)
    except argparse.ArgumentTypeError:
        return
    w, h = (int(x) for x in text.lower().split("x"))
    assert arguments.SIZE_MIN[0] <= w <= arguments.SIZE_MAX[0] and arguments.SIZE_MIN[1] <= h <= arguments.SIZE_MAX[1]


def test_input_errors_are_input_errors():
    for cls in (RecordingError, TemplateFileError, TraceError, SourceError):
        assert issubclass(cls, InputError)
