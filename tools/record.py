"""`quickjab record --source URL -o file.csv [--seconds S] [--label NAME]`: record any source
to the recording CSV of docs/formats.md, flushed at least every 0.25 s."""

from __future__ import annotations

import argparse
import os
import stat
import sys
import time
from pathlib import Path

from engine import arguments
from engine.errors import InputError, refuse_overwriting
from engine.interrupt import stop_signals_as_ctrl_c
from engine.recording import RECORDER_KEY, RecordingWriter, say_notes
from engine.sensors import SourceState, open_source
from engine.sensors.source import url_file
from tools.devices import no_device_hint

CONNECT_TIMEOUT_S = 3.0  # a source that never connects (no port, no board) is an error by then
RATE_PROBE_S = 0.5  # without an announced rate, the rate is measured over the first samples


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("record", help="record a source to a CSV file", description=__doc__)
    p.add_argument("--source", required=True, help="source URL: wiimote://, serial:///dev/ttyACM0, replay://f.csv, ...")
    # its folder checked now: a missing or read-only one was said only once the source had
    # connected and sent samples (after pairing a Wiimote, the player ready to move)
    p.add_argument("-o", "--output", required=True, type=arguments.output_file, metavar="CSV", help="CSV file to write")
    p.add_argument("--seconds", type=arguments.positive_float, default=None, help="stop after this many seconds (default: Ctrl-C)")
    p.add_argument("--label", default="", help="label every row with this action name (for trials)")
    p.add_argument("--connect-timeout", type=arguments.positive_float, default=CONNECT_TIMEOUT_S, metavar="S",
                   help=f"give up with an error when the source has not connected after S seconds (default {CONNECT_TIMEOUT_S:g})")
    p.set_defaults(func=run)


def measured_rate(times: list[float]) -> float | None:
    """Samples per second over a run of sample times (None with fewer than two)."""
    if len(times) < 2 or times[-1] <= times[0]:
        return None
    return (len(times) - 1) / (times[-1] - times[0])


def part_path(output: str | Path, part: int) -> Path:
    """The file for the `part`-th sensor layout of one run: out.csv, then out.2.csv, out.3.csv..."""
    out = Path(output)
    return out if part == 1 else out.with_name(f"{out.stem}.{part}{out.suffix}")


def keep_aside(output: str | Path, unread: bool = False) -> Path | None:
    """A file with anything in it at `output` (through a link, the file it points to) moved to
    `<name>-old<suffix>` beside it, else `<name>-old-2<suffix>`, `-old-3`... (`unread`:
    `<name><suffix>.old`, `.old-2`...: a name the folder's readers, which take every `*.csv` or
    `*.json` in it, pass over, for a file in a folder of trials or of actions): the recording is
    written in place (what keeps a kill to the last rows), and opening the file emptied it, so a
    mistyped -o lost a take. None when nothing is there, the file is empty (mkstemp's: nothing
    to lose) or it is not a regular file (/dev/null, a pipe: written to as before)."""
    target = Path(output)
    if target.is_symlink():
        target = Path(os.path.realpath(target))
    try:
        st = os.stat(target)
    except FileNotFoundError:
        return None
    if not stat.S_ISREG(st.st_mode) or st.st_size == 0:
        return None
    n = 1
    while True:
        old = f"old{f'-{n}' if n > 1 else ''}"
        aside = target.with_name(f"{target.name}.{old}" if unread else f"{target.stem}-{old}{target.suffix}")
        try:
            os.link(target, aside)  # never over another file, as a rename would be
        except FileExistsError:
            n += 1
            continue
        except OSError:  # a file system without hard links (FAT on an SD card): checked, then renamed
            if aside.exists():
                n += 1
                continue
            os.rename(target, aside)
            return aside
        os.unlink(target)
        return aside


def aside_unless_same(output: str | Path, data: bytes, unread: bool = False) -> Path | None:
    """Before `data` is written whole over `output` (a synthesized trial or session, a cut
    action: files a person may have made there): keep_aside, unless the file there holds these
    very bytes (a second run with one seed: nothing would be lost, and a trial folder would gain
    a copy of each trial as one more trial). The place it was moved to, else None. A move that
    fails is an InputError naming the file, as `record -o`'s."""
    target = Path(output)
    try:
        if target.is_file() and target.stat().st_size == len(data) and target.read_bytes() == data:
            return None
        return keep_aside(target, unread)
    except OSError as exc:
        raise InputError(f"{target}: cannot move the file there aside ({exc.strerror or exc}); give another -o") from None


def link_counts(stats: dict[str, int]) -> str:
    """The end-of-run line about the link: what came in and what was lost or rejected on the way
    (the counters a source has; a serial source has them all)."""
    rejected = sum(stats.get(k, 0) for k in ("cobs_errors", "oversize", "runts", "unknown_type", "malformed"))
    jumps = stats.get("seq_jumps", 0)
    # a reboot whose HELLO was lost shows only as its sequence starting again: said apart, since
    # a board that reboots without a HELLO is another fault (power dips mid-send) than one that does
    unannounced = f" ({jumps} seen only as a sequence jump)" if jumps else ""
    return (f"received {stats.get('frames_ok', 0)} frames, lost {stats.get('lost', 0)}, "
            f"CRC-rejected {stats.get('crc_errors', 0)}, other rejects {rejected}, "
            f"replays dropped {stats.get('replays', 0)}{_ahead(stats)}, reboots {stats.get('reboots', 0) + jumps}{unannounced}, "
            f"sensor changes {stats.get('sensor_changes', 0)}, sensor conflicts {stats.get('sensor_conflicts', 0)}, "
            f"implausible {stats.get('implausible', 0)}")


def no_samples_reason(stats: dict[str, int]) -> str:
    """Why a source that connected gave no sample, as far as its counters tell (a serial board's:
    a silent port, SAMPLEs with no valid HELLO to scale them, frames the protocol rejects)."""
    counts = ", ".join(f"{k} {v}" for k, v in stats.items() if v) or "no counts"
    if "bytes_in" in stats and not stats["bytes_in"]:
        why = "the port sent nothing (a board not streaming, or another program reading the port)"
    elif stats.get("samples_before_hello"):
        why = "SAMPLEs came but no valid HELLO to scale them, though asked for with `?`"
    elif "frames_ok" in stats:
        why = "no SAMPLE the source could take (a HELLO whose fields make no sense counts as malformed)"
    else:
        why = "the source delivered no sample"
    return f"{why} ({counts})"


def _ahead(stats: dict[str, int]) -> str:
    """How many of the replays came later in time than the last frame delivered, and how often a
    HELLO of the board's boot resynced the sequence check (PROTOCOL.md: the host stopped reading
    for 32768 frames or more): said only when any did."""
    ahead, resyncs = stats.get("replays_ahead", 0), stats.get("resyncs", 0)
    said = ([f"{ahead} later in time than the frames before them"] if ahead else []) \
        + ([f"resynced at the board's HELLO {resyncs} time(s)"] if resyncs else [])
    return f" ({'; '.join(said)})" if said else ""


def record(url: str, output: str, seconds: float | None, label: str = "", poll_s: float = 0.005,
           connect_timeout: float = CONNECT_TIMEOUT_S) -> int:
    """Record until `seconds` pass, the source ends, or Ctrl-C. Returns the number of rows.
    The output file is created when the sample rate is known (the source's announced rate, e.g.
    the serial bridge's HELLO, else measured over the first RATE_PROBE_S of samples), so
    `rate_hz` in the file is the rate the samples came at, and a source that cannot be opened
    leaves nothing behind. A source that has neither connected nor delivered a sample after
    `connect_timeout` seconds (a missing port, `serial://auto` with no board) is an InputError;
    so is one that connected but gave no sample at all (a silent board, SAMPLEs without a valid
    HELLO): no file is written, an earlier one at `output` stays, and the error names the counters.

    A source whose sensor count changes mid-run (a board rebooting with one IMU fewer or more)
    continues in a new file, out.2.csv and so on, whose header has the new columns: a row never
    has another width than its file's header (docs/formats.md), so every file reads back."""
    source = open_source(url)
    say_notes(source.file_notes, "record")  # a replayed recording's row left out (a cut last row)
    parts = _RecordingParts(source, url, output, label)
    try:
        _poll_into(parts, seconds, poll_s, connect_timeout)
    except KeyboardInterrupt:
        pass
    except BaseException:
        parts.close()
        raise
    finally:
        source.close()
    parts.write(parts.pending)  # the source ended, or Ctrl-C, before the rate was known
    parts.close()
    if not parts.connected:
        raise InputError(f"{url}: the source never connected (state {source.state.value}); nothing recorded; "
                         + no_device_hint(url))
    if not parts.files:  # no sample at all: no file (one made now would guess its rate_hz)
        raise InputError(f"{url}: no samples; nothing recorded ({output} not written): {no_samples_reason(source.stats)}")
    rows = parts.finish()
    names = ", ".join(str(f) for f in parts.files)
    print(f"wrote {rows} samples to {names}", file=sys.stderr)
    if parts.nudged:  # t must increase: a burst timed alike, or a narrow device clock
        print(f"{parts.nudged} sample time(s) at or before the one before: written 1 us after it", file=sys.stderr)
    if "frames_ok" in source.stats:
        print(f"link: {link_counts(source.stats)}", file=sys.stderr)
    return rows


def _poll_into(parts: _RecordingParts, seconds: float | None, poll_s: float, connect_timeout: float) -> None:
    """Poll the source into `parts` until `seconds` pass or it ends; say each state change."""
    source, url = parts.source, parts.url
    start = time.perf_counter()
    last_state, last_missing = None, ""
    while seconds is None or time.perf_counter() - start < seconds:
        if source.state is not last_state:
            print(f"source {url}: {source.state.value}", file=sys.stderr)
            last_state = source.state
        # a Wiimote without its Nunchuk records a still left hand; said while connected only (a
        # source away misses nothing: "nothing missing now" came with each disconnection)
        missing = source.missing() if source.state is SourceState.CONNECTED else last_missing
        if missing != last_missing:
            print(f"source {url}: {missing or 'nothing missing now'}", file=sys.stderr)
            last_missing = missing
        parts.connected |= source.state is SourceState.CONNECTED
        samples = source.poll()
        parts.connected |= bool(samples)
        parts.take(samples)
        if parts.writer is not None:
            parts.writer.flush_if_due()  # a silent source still gets its rows synced
        if source.state is SourceState.ENDED:
            break
        if not parts.connected and time.perf_counter() - start >= connect_timeout:
            raise InputError(f"{url}: no device connected after {connect_timeout:g} s (source {source.state.value}); "
                             + no_device_hint(url))
        time.sleep(poll_s)


class _RecordingParts:
    """The files of one recording run: samples are held until the rate is known, and a change
    of sensor count continues in the next part file."""

    def __init__(self, source, url: str, output: str, label: str):
        self.source, self.url, self.output, self.label = source, url, output, label
        self.meta = {"source": source.description or url, RECORDER_KEY: url}
        self.writer: RecordingWriter | None = None
        self.pending: list = []  # samples held until the rate is known
        self.rows = 0  # rows in the part files already closed
        self.nudged = 0  # ... and of them, rows whose time was moved past the one before
        self.files: list[Path] = []
        self.t0: float | None = None  # every file of a run keeps the run's time origin
        self.connected = False  # the source has connected or delivered a sample

    def open_writer(self, width: int) -> RecordingWriter:
        source = self.source
        rate = source.rate_hz or measured_rate([s.t for s in self.pending])
        head = {**self.meta, "source": source.description or self.url}  # a HELLO may have named the device by now
        if rate:
            head = {"rate_hz": f"{rate:g}", **head}
        path = part_path(self.output, len(self.files) + 1)
        if self.files:
            head["continues"] = str(self.files[-1].name)
        try:
            aside = keep_aside(path)
        except OSError as exc:
            raise InputError(f"{path}: cannot move the file there aside ({exc.strerror or exc}); give another -o") from None
        if aside is not None:
            print(f"{path} was not empty: moved to {aside}", file=sys.stderr)
        w = RecordingWriter(path, width, head, t0=self.t0)
        self.files.append(path)
        return w

    def write(self, samples: list) -> None:
        for sample in samples:
            width = len(sample.accel)
            if self.writer is not None and width != self.writer.sensors:
                self.rows += self.writer.rows
                self.nudged += self.writer.nudged
                self.writer.close()
                print(f"source {self.url}: now {width} sensor(s), continuing in a new file", file=sys.stderr)
                self.writer = None
            if self.writer is None:
                self.writer = self.open_writer(width)
            self.writer.write(sample, self.label)
            self.t0 = self.writer.t0

    def take(self, samples: list) -> None:
        """Hold samples until the rate is announced or measured, then write them."""
        if not self.files:
            self.pending.extend(samples)
            if self.pending and (self.source.rate_hz or self.pending[-1].t - self.pending[0].t >= RATE_PROBE_S):
                self.write(self.pending)
                self.pending.clear()
        else:
            self.write(samples)

    def close(self) -> None:
        if self.writer is not None:
            self.writer.close()

    def finish(self) -> int:
        """The run's row count (a run without samples has written no file: `record` says why)."""
        if self.writer is not None:
            self.rows += self.writer.rows
            self.nudged += self.writer.nudged
        return self.rows


def run(args: argparse.Namespace) -> int:
    if not args.connect_timeout > 0:
        raise InputError(f"--connect-timeout {args.connect_timeout}: must be positive")
    refuse_overwriting({"-o": args.output}, [url_file(args.source)])
    # SIGTERM (`kill`, a service manager, `timeout`) and SIGHUP (the terminal closed) end a
    # recording as Ctrl-C does: the samples held for the rate are written, the file is synced and
    # closed, and the summary says what was written (their default: none of it, and exit 143)
    with stop_signals_as_ctrl_c():
        record(args.source, args.output, args.seconds, args.label, connect_timeout=args.connect_timeout)
    return 0

