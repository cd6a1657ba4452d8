"""`quickjab record --source URL -o file.csv [--seconds S] [--label NAME]`: record any source
to the recording CSV of FORMATS.md, flushed at least every 0.25 s."""

from __future__ import annotations

import argparse
import sys
import time

from engine import arguments
from engine.recording import RecordingWriter
from engine.sensors import SourceState, open_source


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("record", help="record a source to a CSV file", description=__doc__)
    p.add_argument("--source", required=True, help="source URL: wiimote://, serial:///dev/ttyACM0, replay://f.csv, ...")
    p.add_argument("-o", "--output", required=True, help="CSV file to write")
    p.add_argument("--seconds", type=arguments.positive_float, default=None, help="stop after this many seconds (default: Ctrl-C)")
    p.add_argument("--label", default="", help="label every row with this action name (for trials)")
    p.set_defaults(func=run)


def record(url: str, output: str, seconds: float | None, label: str = "", poll_s: float = 0.005) -> int:
    """Record until `seconds` pass, the source ends, or Ctrl-C. Returns the number of rows.
    The output file is created when the first sample arrives (or at the end, empty), so a
    source that cannot be opened leaves nothing behind."""
    source = open_source(url)
    meta = {"source": source.description or url, "recorded_from": url}
    writer: RecordingWriter | None = None
    start = time.perf_counter()
    last_state = None
    try:
        while seconds is None or time.perf_counter() - start < seconds:
            if source.state is not last_state:
                print(f"source {url}: {source.state.value}", file=sys.stderr)
                last_state = source.state
            for sample in source.poll():
                if writer is None:
                    writer = RecordingWriter(output, source.sensors, meta)
                writer.write(sample, label)
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
    print(f"wrote {writer.rows} samples to {output}", file=sys.stderr)
    return writer.rows


def run(args: argparse.Namespace) -> int:
    record(args.source, args.output, args.seconds, args.label)
    return 0
