"""`quickjab record --source URL -o file.csv [--seconds S] [--label NAME]`: record any source
to the recording CSV of FORMATS.md, flushed at least every 0.25 s."""

from __future__ import annotations

import argparse
import sys
import time

from engine.errors import InputError
from engine.recording import RecordingWriter
from engine.sensors import SourceState, open_source

CONNECT_TIMEOUT_S = 3.0  # a source that never connects (no port, no board) is an error by then
RATE_PROBE_S = 0.5  # without an announced rate, the rate is measured over the first samples


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("record", help="record a source to a CSV file", description=__doc__)
    p.add_argument("--source", required=True, help="source URL: wiimote://, serial:///dev/ttyACM0, replay://f.csv, ...")
    p.add_argument("-o", "--output", required=True, help="CSV file to write")
    p.add_argument("--seconds", type=float, default=None, help="stop after this many seconds (default: Ctrl-C)")
    p.add_argument("--label", default="", help="label every row with this action name (for trials)")
    p.add_argument("--connect-timeout", type=float, default=CONNECT_TIMEOUT_S, metavar="S",
                   help=f"give up with an error when the source has not connected after S seconds (default {CONNECT_TIMEOUT_S:g})")
    p.set_defaults(func=run)


def measured_rate(times: list[float]) -> float | None:
    """Samples per second over a run of sample times (None with fewer than two)."""
    if len(times) < 2 or times[-1] <= times[0]:
        return None
    return (len(times) - 1) / (times[-1] - times[0])


def record(url: str, output: str, seconds: float | None, label: str = "", poll_s: float = 0.005,
           connect_timeout: float = CONNECT_TIMEOUT_S) -> int:
    """Record until `seconds` pass, the source ends, or Ctrl-C. Returns the number of rows.
    The output file is created when the sample rate is known (the source's announced rate, e.g.
    the serial bridge's HELLO, else measured over the first RATE_PROBE_S of samples), so
    `rate_hz` in the file is the rate the samples came at, and a source that cannot be opened
    leaves nothing behind. A source that has neither connected nor delivered a sample after
    `connect_timeout` seconds (a missing port, `serial://auto` with no board) is an InputError."""
    source = open_source(url)
    meta = {"source": source.description or url, "recorded_from": url}
    writer: RecordingWriter | None = None
    pending: list = []  # samples held until the rate is known
    start = time.perf_counter()
    last_state = None
    ever_connected = False

    def open_writer() -> RecordingWriter:
        rate = source.rate_hz or measured_rate([s.t for s in pending])
        head = {**meta, "source": source.description or url}  # a HELLO may have named the device by now
        if rate:
            head = {"rate_hz": f"{rate:g}", **head}
        w = RecordingWriter(output, source.sensors, head)
        for s in pending:
            w.write(s, label)
        pending.clear()
        return w

    try:
        while seconds is None or time.perf_counter() - start < seconds:
            if source.state is not last_state:
                print(f"source {url}: {source.state.value}", file=sys.stderr)
                last_state = source.state
            ever_connected |= source.state is SourceState.CONNECTED
            samples = source.poll()
            ever_connected |= bool(samples)
            if writer is None:
                pending.extend(samples)
                if pending and (source.rate_hz or pending[-1].t - pending[0].t >= RATE_PROBE_S):
                    writer = open_writer()
            else:
                for sample in samples:
                    writer.write(sample, label)
            if writer is not None:
                writer.flush_if_due()  # a silent source still gets its rows synced
            if source.state is SourceState.ENDED:
                break
            if not ever_connected and time.perf_counter() - start >= connect_timeout:
                raise InputError(f"{url}: no device connected after {connect_timeout:g} s (source {source.state.value}); "
                                 "check the port (`quickjab devices`) and that the board is plugged in")
            time.sleep(poll_s)
    except KeyboardInterrupt:
        pass
    finally:
        source.close()
        if writer is not None:
            writer.close()
    if not ever_connected:
        raise InputError(f"{url}: the source never connected (state {source.state.value}); nothing recorded")
    if writer is None:
        writer = open_writer()
    writer.close()
    print(f"wrote {writer.rows} samples to {output}", file=sys.stderr)
    return writer.rows


def run(args: argparse.Namespace) -> int:
    if not args.connect_timeout > 0:
        raise InputError(f"--connect-timeout {args.connect_timeout}: must be positive")
    record(args.source, args.output, args.seconds, args.label, connect_timeout=args.connect_timeout)
    return 0
