"""`quickjab record --source URL -o file.csv [--seconds S] [--label NAME]`: record any source
to the recording CSV of FORMATS.md, flushed at least every 0.25 s."""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from engine.recording import RecordingWriter
from engine.sensors import SourceState, open_source


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("record", help="record a source to a CSV file", description=__doc__)
    p.add_argument("--source", required=True, help="source URL: wiimote://, serial:///dev/ttyACM0, replay://f.csv, ...")
    p.add_argument("-o", "--output", required=True, help="CSV file to write")
    p.add_argument("--seconds", type=float, default=None, help="stop after this many seconds (default: Ctrl-C)")
    p.add_argument("--label", default="", help="label every row with this action name (for trials)")
    p.set_defaults(func=run)


def part_path(output: str | Path, part: int) -> Path:
    """The file for the `part`-th sensor layout of one run: out.csv, then out.2.csv, out.3.csv..."""
    out = Path(output)
    return out if part == 1 else out.with_name(f"{out.stem}.{part}{out.suffix}")


def link_counts(stats: dict[str, int]) -> str:
    """The end-of-run line about the link: what came in and what was lost or rejected on the way
    (the counters a source has; a serial source has them all)."""
    rejected = sum(stats.get(k, 0) for k in ("cobs_errors", "oversize", "runts", "unknown_type", "malformed"))
    return (f"received {stats.get('frames_ok', 0)} frames, lost {stats.get('lost', 0)}, "
            f"CRC-rejected {stats.get('crc_errors', 0)}, other rejects {rejected}, "
            f"replays dropped {stats.get('replays', 0)}, reboots {stats.get('reboots', 0) + stats.get('seq_jumps', 0)}, "
            f"sensor changes {stats.get('sensor_changes', 0)}")


def record(url: str, output: str, seconds: float | None, label: str = "", poll_s: float = 0.005) -> int:
    """Record until `seconds` pass, the source ends, or Ctrl-C. Returns the number of rows.
    The output file is created when the first sample arrives (or at the end, empty), so a
    source that cannot be opened leaves nothing behind.

    A source whose sensor count changes mid-run (a board rebooting with one IMU fewer or more)
    continues in a new file, out.2.csv and so on, whose header has the new columns: a row never
    has another width than its file's header (FORMATS.md), so every file reads back."""
    source = open_source(url)
    meta = {"source": source.description or url, "recorded_from": url}
    writer: RecordingWriter | None = None
    rows = 0
    files: list[Path] = []
    t0: float | None = None  # every file of a run keeps the run's time origin
    start = time.perf_counter()
    last_state = None
    try:
        while seconds is None or time.perf_counter() - start < seconds:
            if source.state is not last_state:
                print(f"source {url}: {source.state.value}", file=sys.stderr)
                last_state = source.state
            for sample in source.poll():
                width = len(sample.accel)
                if writer is not None and width != writer.sensors:
                    rows += writer.rows
                    writer.close()
                    print(f"source {url}: now {width} sensor(s), continuing in a new file", file=sys.stderr)
                    writer = None
                if writer is None:
                    files.append(part_path(output, len(files) + 1))
                    part_meta = {**meta, "source": source.description or url}
                    if len(files) > 1:
                        part_meta["continues"] = str(files[-2].name)
                    writer = RecordingWriter(files[-1], width, part_meta, t0=t0)
                writer.write(sample, label)
                t0 = writer.t0
            if writer is not None:
                writer.flush_if_due()  # a silent source still gets its rows synced
            if source.state is SourceState.ENDED:
                break
            time.sleep(poll_s)
    except KeyboardInterrupt:
        pass
    finally:
        source.close()
        if writer is not None:
            writer.close()
    if writer is None:
        writer = RecordingWriter(output, source.sensors, meta)
        writer.close()
        files.append(Path(output))
    rows += writer.rows
    names = ", ".join(str(f) for f in files)
    print(f"wrote {rows} samples to {names}", file=sys.stderr)
    if "frames_ok" in source.stats:
        print(f"link: {link_counts(source.stats)}", file=sys.stderr)
    return rows


def run(args: argparse.Namespace) -> int:
    record(args.source, args.output, args.seconds, args.label)
    return 0
