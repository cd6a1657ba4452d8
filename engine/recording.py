"""The recording CSV of docs/formats.md: a reader, a whole-file writer and a streaming writer.

Readers accept any `# key: value` metadata, one- or two-hand columns, an optional label and
extra columns (ignored). A bad file raises RecordingError naming the file and line; the CLI
turns that into one line on stderr and exit code 2.
"""

from __future__ import annotations

import csv
import io
import itertools
import os
import sys
import time
from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from engine.clock import STEP_HZ
from engine.errors import InputError, not_a_regular_file
from engine.npz_files import write_replacing
from engine.sample import MAX_ACCEL_G, Sample  # MAX_ACCEL_G: the limit on |acceleration| in g

HAND_COLUMNS = (("rx", "ry", "rz"), ("lx", "ly", "lz"))
FLUSH_EVERY_S = 0.25  # fsync at least this often: a crashed machine loses at most 0.25 s
# What a reader accepts. Anything larger is refused with a message instead of exhausting memory:
MAX_RECORDING_BYTES = 256 * 2**20  # an hour at 430 Hz with two hands is about 100 MB
MAX_DURATION_S = 4 * 3600.0  # 4 h at 60 Hz is 864,000 frames (41 MB for two hands)
MAX_GAP_S = 600.0  # no sample for 10 minutes: not one recording any more
MAX_LINE_CHARS = 1 << 20  # metadata and header lines
MAX_META_KEYS = 1000  # distinct metadata keys: each is Python objects ~10x its text (a recording has a few)
CHUNK_ROWS = 8192  # rows converted to numbers at once
RECORDER_KEY = "recorded_from"  # the metadata key of files `quickjab record` wrote (docs/formats.md)
# Labels and metadata may come from bytes that are not UTF-8 (a file name, an argument), which
# Python holds as lone surrogates that UTF-8 cannot encode: written as \udcff, they stay readable
UNENCODABLE = "backslashreplace"


class RecordingError(InputError):
    """A recording file that cannot be read; the message names the file and line."""

    def __init__(self, path: str | os.PathLike, line: int | None, message: str):
        self.path, self.line = str(path), line
        where = f"{self.path}:{line}" if line else self.path
        super().__init__(f"{where}: {message}")


@dataclass
class Recording:
    """Samples of one recording. `accel` has shape (n, sensors, 3) in g; `labels` is '' when idle."""

    t: np.ndarray
    accel: np.ndarray
    labels: list[str] = field(default_factory=list)
    meta: dict[str, str] = field(default_factory=dict)
    # what the reader left out and why, one line each naming file:line (a row cut by a power cut)
    notes: list[str] = field(default_factory=list)

    def __post_init__(self) -> None:
        self.t = np.asarray(self.t, dtype=np.float64)
        self.accel = np.asarray(self.accel, dtype=np.float64).reshape(len(self.t), -1, 3)
        if not self.labels:
            self.labels = [""] * len(self.t)

    @property
    def sensors(self) -> int:
        return self.accel.shape[1]

    def __len__(self) -> int:
        return len(self.t)

    def samples(self) -> list[Sample]:
        return [Sample(float(t), a) for t, a in zip(self.t, self.accel, strict=True)]


def say_notes(notes: Iterable[str], prog: str) -> None:
    """Say each note (a Recording's `notes`, a source's `file_notes`) on stderr as every command
    says its lines: `quickjab <prog>: <note>`."""
    for note in notes:
        print(f"quickjab {prog}: {note}", file=sys.stderr)


def _header_columns(sensors: int) -> list[str]:
    return ["t"] + [c for hand in HAND_COLUMNS[:sensors] for c in hand]


def _open_regular(path: Path):
    """Open a recording for streaming text reads, refusing what is not a regular file of
    sane size: a FIFO or a device would block or never end, a huge file would take memory."""
    try:
        st = os.stat(path)
    except OSError as exc:
        raise RecordingError(path, None, f"cannot read: {exc.strerror or exc}") from None
    if why := not_a_regular_file(st):
        raise RecordingError(path, None, f"cannot read: {why}")
    if st.st_size > MAX_RECORDING_BYTES:
        raise RecordingError(path, None, f"{st.st_size / 2**20:.0f} MiB is over the {MAX_RECORDING_BYTES // 2**20} MiB "
                                         "limit for a recording: split it into shorter files")
    try:
        # a spreadsheet's BOM is not part of "t"; newline="" lets csv see quoted line breaks
        return open(path, encoding="utf-8-sig", newline="")
    except OSError as exc:
        raise RecordingError(path, None, f"cannot read: {exc.strerror or exc}") from None


def read_recording(path: str | os.PathLike) -> Recording:
    """Read a recording CSV. Raises RecordingError (file and line) on anything malformed.

    Streams the file: rows are converted to numbers CHUNK_ROWS at a time, so memory is the
    numbers' own (about 60 bytes a row for two hands), not the text's many times over."""
    path = Path(path)
    with _open_regular(path) as f:
        try:
            return _read_rows(path, f, _count_lines(path))
        except UnicodeDecodeError as exc:
            raise RecordingError(path, None, f"cannot read: not UTF-8 text ({exc.reason})") from None
        except csv.Error as exc:  # a field over csv's 128 KiB limit, a NUL byte, ...
            raise RecordingError(path, None, f"not a CSV recording ({exc})") from None


def _count_lines(path: Path) -> int:
    """Lines in the file (an upper bound on its rows), counted in binary blocks: the numbers
    then go straight into one array of that size instead of chunks joined at the end."""
    n = 1
    with open(path, "rb") as fb:
        while block := fb.read(1 << 20):
            n += block.count(b"\n") + block.count(b"\r")
    return n


def _row_bound(f: io.TextIOBase, lines: int, numbers: int) -> int:
    """Rows the file can hold: one a line, and one per 2 * numbers bytes (a character and a
    separator per number). The line count alone let 250 MB of bare '\r' (262 million line
    ends, two rows) ask np.empty for 13.7 GiB."""
    return min(lines, os.fstat(f.fileno()).st_size // (2 * numbers) + 1)


def _read_metadata(path: Path, f: io.TextIOBase) -> tuple[dict[str, str], str, int]:
    """The `# key: value` lines before the header, the header line and its number."""
    meta: dict[str, str] = {}
    lineno = 0
    while True:
        line = f.readline(MAX_LINE_CHARS + 1)
        if len(line) > MAX_LINE_CHARS:
            raise RecordingError(path, lineno + 1, f"a line over {MAX_LINE_CHARS} characters")
        if not line:
            raise RecordingError(path, None, "no header line (expected t,rx,ry,rz,...)")
        lineno += 1
        if line.startswith("#") or not line.strip():
            body = line[1:].strip()
            if ":" in body:
                key, value = body.split(":", 1)
                meta[key.strip()] = value.strip()
                if len(meta) > MAX_META_KEYS:  # 33 MB of keys took 400 MB
                    raise RecordingError(path, lineno, f"over {MAX_META_KEYS} metadata keys before the header (a recording has a few)")
            continue
        return meta, line, lineno


def _read_rows(path: Path, f: io.TextIOBase, max_rows: int) -> Recording:
    meta, line, header_line = _read_metadata(path, f)
    header = [h.strip() for h in next(csv.reader([line]))]
    missing = [c for c in ("t", "rx", "ry", "rz") if c not in header]
    if missing:
        raise RecordingError(path, header_line, f"missing column(s) {', '.join(missing)}")
    two_hands = all(c in header for c in HAND_COLUMNS[1])
    if not two_hands and any(c in header for c in HAND_COLUMNS[1]):
        raise RecordingError(path, header_line, "left-hand columns need all of lx,ly,lz")
    sensors = 2 if two_hands else 1
    numeric = [header.index(c) for c in _header_columns(sensors)]
    label_col = header.index("label") if "label" in header else None

    max_rows = _row_bound(f, max_rows, len(numeric))
    values = np.empty((max_rows, len(numeric)), dtype=np.float64)
    lines = np.empty(max_rows, dtype=np.int32)  # each row's line in the file, for messages
    n = 0
    labels: list[str] = []
    seen_labels: dict[str, str] = {}  # one str object per distinct label, not one per row
    fields: list[list[str]] = []  # the numeric fields of the rows not yet converted, as text
    linenos: list[int] = []
    need = max(numeric) + 1
    # `quickjab record` writes this key and ends every row with a line end: in its files a last
    # line without one is a row cut mid-write (a power cut), its last number maybe cut short
    # ('1.1234' read as '1.1'); a hand-written CSV may well end without one, and keeps its row
    cut: list[int] | None = [] if RECORDER_KEY in meta else None
    reader = csv.reader(itertools.chain.from_iterable(_line_blocks(path, f, header_line, cut)))
    for row in reader:
        line_at = header_line + reader.line_num
        if not row or (len(row) == 1 and not row[0].strip()):
            continue
        if len(row) < need:
            raise RecordingError(path, line_at, f"{len(row)} fields, header has {len(header)}")
        fields.append([row[j] for j in numeric])
        linenos.append(line_at)
        label = row[label_col].strip() if label_col is not None and label_col < len(row) else ""
        labels.append(seen_labels.setdefault(label, label))
        if len(fields) >= CHUNK_ROWS:
            n = _store(path, fields, linenos, values, lines, n)
            fields, linenos = [], []
    if fields:
        n = _store(path, fields, linenos, values, lines, n)
    if not n:
        raise RecordingError(path, None, "no samples")
    values = values[:n]
    _check_times(path, values[:, 0], lines[:n])
    notes = [f"{path}:{line}: the last row has no line end (the recording was cut mid-write): left out" for line in cut or []]
    return Recording(values[:, 0], values[:, 1:].reshape(n, sensors, 3), labels, meta, notes)


def _line_blocks(path: Path, f: io.TextIOBase, lineno: int, cut: list[int] | None = None) -> Iterator[list[str]]:
    """The file's lines after line `lineno` in blocks, each line held to MAX_LINE_CHARS as the
    header is: csv's field limit bounds one field, not a row, and a 200 MB row of "0," split
    into 100 million fields took 1 GB before any check could see it. Blocks keep the check at
    C speed (a generator step per line made a 100 MB file 60 % slower to read; these, about 10 %).
    With `cut` (a list), a last line without its line end is left out and its number appended."""
    while lines := f.readlines(1 << 14):
        if max(map(len, lines)) > MAX_LINE_CHARS:
            k = next(i for i, line in enumerate(lines) if len(line) > MAX_LINE_CHARS)
            raise RecordingError(path, lineno + k + 1, f"a line over {MAX_LINE_CHARS} characters")
        lineno += len(lines)
        if cut is not None and not lines[-1].endswith(("\n", "\r")):  # only a file's last line can
            cut.append(lineno)
            lines = lines[:-1]
        yield lines


def _store(path: Path, fields: list[list[str]], linenos: list[int], values: np.ndarray, lines: np.ndarray, n: int) -> int:
    k = len(fields)
    values[n : n + k] = _numbers(path, fields, linenos)
    lines[n : n + k] = linenos
    return n + k


def _numbers(path: Path, fields: list[list[str]], linenos: list[int]) -> np.ndarray:
    """One C-level conversion of a chunk of rows; on failure, the culprit for the message."""
    try:
        values = np.array(fields, dtype=np.float64)
    except ValueError:
        for line, row in zip(linenos, fields, strict=True):
            bad = next((f for f in row if not _is_float(f)), None)
            if bad is not None:
                raise RecordingError(path, line, f"not a number: {bad[:40]!r}") from None
        raise RecordingError(path, None, "numbers that cannot be parsed") from None
    finite = np.isfinite(values).all(axis=1)
    if not finite.all():
        raise RecordingError(path, linenos[int(np.argmin(finite))], "not a finite number")
    plausible = (np.abs(values[:, 1:]) <= MAX_ACCEL_G).all(axis=1)  # column 0 is t
    if not plausible.all():
        k = int(np.argmin(plausible))
        g = float(np.abs(values[k, 1:]).max())
        raise RecordingError(path, linenos[k], f"an acceleration of {g:.6g} g, over the {MAX_ACCEL_G:g} g "
                                               "a sensor can read (accelerations are in g)")
    return values


def _check_times(path: Path, t: np.ndarray, lines: np.ndarray) -> None:
    """Time must increase and stay within what the 60 Hz resampler can be asked for: two rows
    at t = 0 and t = 1e7 would otherwise ask for 6e8 frames (13.8 GB)."""
    step = np.diff(t)
    back = np.flatnonzero(step < 0)
    if len(back):
        k = int(back[0]) + 1
        raise RecordingError(path, int(lines[k]), f"time goes backwards ({t[k]} after {t[k - 1]})")
    if len(t) > 1 and t[-1] == t[0]:
        raise RecordingError(path, None, f"every sample has the same time t = {t[0]}")
    if t[-1] - t[0] > MAX_DURATION_S:
        raise RecordingError(path, None, f"lasts {t[-1] - t[0]:.6g} s, over the {MAX_DURATION_S / 3600:g} h limit for a recording")
    if len(step) and step.max() > MAX_GAP_S:
        k = int(np.argmax(step)) + 1
        raise RecordingError(path, int(lines[k]), f"a gap of {step[k - 1]:.6g} s since the sample before (at most {MAX_GAP_S:g} s)")


def _is_float(s: str) -> bool:
    try:
        float(s)
    except ValueError:
        return False
    return True


def _format_row(t: float, accel: np.ndarray, label: str) -> str:
    # t to the microsecond (430 Hz phones are 2.3 ms apart), g to 0.1 mg (sensor noise is ~10 mg)
    vals = ",".join(f"{v:.4f}" for v in np.asarray(accel, dtype=np.float64).ravel())
    if any(c in label for c in ',"\r\n'):
        label = '"' + label.replace('"', '""').replace("\r", " ").replace("\n", " ") + '"'
    return f"{t:.6f},{vals},{label}\n"


def _metadata_lines(meta: dict[str, str]) -> str:
    def one_line(x: object) -> str:
        return " ".join(str(x).splitlines())

    return "".join(f"# {one_line(k)}: {one_line(v)}\n" for k, v in meta.items())


def _file_head(sensors: int, meta: dict[str, str]) -> str:
    """Metadata lines (rate_hz and units first, overridable) and the header with a label column."""
    return _metadata_lines({"rate_hz": str(STEP_HZ), "units": "g", **meta}) + ",".join(_header_columns(sensors) + ["label"]) + "\n"


def recording_bytes(rec: Recording) -> bytes:
    """The whole file write_recording writes for `rec` (docs/formats.md layout, label column
    always present)."""
    buf = io.StringIO()
    buf.write(_file_head(rec.sensors, rec.meta))
    for t, a, lab in zip(rec.t, rec.accel, rec.labels, strict=True):
        buf.write(_format_row(float(t), a, lab))
    return buf.getvalue().encode("utf-8", UNENCODABLE)


def write_recording(path: str | os.PathLike, rec: Recording | bytes) -> None:
    """Write a whole recording (or its recording_bytes), beside `path` and renamed over it once
    whole: a full disk or a kill halfway through left a truncated file (or a cut last row) where
    the player's recording had been."""
    data = rec if isinstance(rec, bytes) else recording_bytes(rec)
    try:
        write_replacing(path, lambda f: f.write(data))
    except OSError as exc:  # a full disk: ENOSPC names no file, a read-only folder the temporary one
        raise RecordingError(path, None, f"cannot write: {exc.strerror or exc}") from None


class RecordingWriter:
    """Streams samples to a recording CSV.

    The file is unbuffered and each row is one write, so every row reaches the operating system
    as it is written: a process killed mid-recording (even by SIGKILL) loses nothing written. On
    top of that the file is fsynced at least every FLUSH_EVERY_S while rows come in (from
    `write`, or from `flush_if_due`, which a recording loop calls when a source is silent), so a
    crash of the whole machine loses at most the last 0.25 s. A write that fails part-way (a full
    disk, a file size limit) is cut back to the last whole row before the error is raised: a
    partial last row made the whole file unreadable (`N fields, header has M`)."""

    def __init__(
        self,
        path: str | os.PathLike,
        sensors: int,
        meta: dict[str, str] | None = None,
        t0: float | None = None,
    ):
        self.path = Path(path)
        self.sensors = sensors
        self.t0 = t0  # recording time = host time - t0; the first sample sets it when None
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)  # `record -o new/r.csv`: made, as every output's folder
            self._file = open(self.path, "wb", buffering=0)
        except OSError as exc:
            raise RecordingError(self.path, None, f"cannot write: {exc.strerror}") from None
        self._size = 0  # bytes of whole lines in the file
        self._put(_file_head(sensors, meta or {}))
        self._last_flush = time.monotonic()
        self.rows = 0
        # t must increase (docs/formats.md; a reader refuses a row whose time goes back): a
        # sample timed at or before the previous row (a burst mapped to one host time, a narrow
        # device clock) is written 1 us after it, and counted
        self.nudged = 0
        self._last_us: int | None = None
        self._dirty = False
        self._flush()

    def write(self, sample: Sample, label: str = "") -> None:
        if self.t0 is None:
            self.t0 = sample.t
        accel = np.asarray(sample.accel, dtype=np.float64).reshape(-1, 3)[: self.sensors]
        if len(accel) < self.sensors:  # a short row would make the file unreadable: the caller
            # starts a new file for a new sensor count (tools/record.py)
            raise ValueError(f"{self.path}: a sample with {len(accel)} sensor(s) in a file of {self.sensors}")
        t_us = round((sample.t - self.t0) * 1e6)
        if self._last_us is not None and t_us <= self._last_us:
            t_us = self._last_us + 1
            self.nudged += 1
        self._put(_format_row(t_us / 1e6, accel, label))
        self._last_us = t_us
        self.rows += 1
        self._dirty = True
        self.flush_if_due()

    def flush_if_due(self) -> None:
        """fsync when rows came in since the last one and FLUSH_EVERY_S has passed."""
        if self._dirty and time.monotonic() - self._last_flush >= FLUSH_EVERY_S:
            self._flush()

    def _put(self, text: str) -> None:
        """Write whole lines, or none: a write that fails part-way is cut back to the lines before."""
        data = memoryview(text.encode("utf-8", UNENCODABLE))
        size = self._size + len(data)
        try:
            while data:
                data = data[self._file.write(data):]  # a raw write may take only part
        except OSError as exc:
            try:
                os.ftruncate(self._file.fileno(), self._size)
                self._file.seek(self._size)
            except OSError:
                pass  # the error below still names the file; a reader then names the bad line
            raise self._cannot_write(exc) from None
        self._size = size

    def _flush(self) -> None:
        try:
            os.fsync(self._file.fileno())
        except OSError as exc:
            raise self._cannot_write(exc) from None
        self._last_flush = time.monotonic()
        self._dirty = False

    def _cannot_write(self, exc: OSError) -> RecordingError:
        """A write that failed (a full disk: ENOSPC names no file), as an error naming the file."""
        return RecordingError(self.path, None, f"cannot write: {exc.strerror or exc}")

    def close(self) -> None:
        if not self._file.closed:
            self._flush()
            self._file.close()

    def __enter__(self) -> RecordingWriter:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
