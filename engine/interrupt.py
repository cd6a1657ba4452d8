"""SIGTERM and SIGHUP ending a command as Ctrl-C does.

`kill`, a service manager and `timeout` stop a process with SIGTERM; closing its terminal sends
SIGHUP. Their default ends the process on the spot: nothing of a `finally` runs, so a recording
lost the samples held for its rate and its summary, and `play --trace` wrote no trace. Inside
`stop_signals_as_ctrl_c()` both raise KeyboardInterrupt instead, and the command ends the way it
ends on Ctrl-C (its files written, its summary said, its usual exit status).
"""

from __future__ import annotations

import contextlib
import signal
import sys
from collections.abc import Iterator

STOP_SIGNALS = tuple(filter(None, (signal.SIGTERM, getattr(signal, "SIGHUP", None))))  # Windows has no SIGHUP


class _Unheard:
    """A console stream whose writes may fail without a word: after SIGHUP the terminal is gone,
    and every line said to it (a "wrote" line, the summary) raised an I/O error that cut the
    cleanup short, the files after it never written."""

    def __init__(self, stream) -> None:
        self._stream = stream

    def write(self, text: str) -> int:
        with contextlib.suppress(OSError, ValueError):
            return self._stream.write(text)
        return len(text)

    def flush(self) -> None:
        with contextlib.suppress(OSError, ValueError):
            self._stream.flush()

    def __getattr__(self, name: str):
        return getattr(self._stream, name)


def _as_ctrl_c(signum: int, frame: object) -> None:
    for sig in STOP_SIGNALS:  # the cleanup the first one starts runs to its end
        signal.signal(sig, signal.SIG_IGN)
    if signum == getattr(signal, "SIGHUP", None):
        sys.stdout, sys.stderr = _Unheard(sys.stdout), _Unheard(sys.stderr)
    raise KeyboardInterrupt


@contextlib.contextmanager
def stop_signals_as_ctrl_c() -> Iterator[None]:
    """SIGTERM and SIGHUP raise KeyboardInterrupt in the block; the handlers before are put back
    after it. Installed before SDL starts, this also keeps SDL from taking SIGTERM for itself (it
    does only where the handler is still the default) and turning it into a closed window."""
    previous = {}
    for sig in STOP_SIGNALS:
        with contextlib.suppress(ValueError):  # not the main thread: the default stays
            previous[sig] = signal.signal(sig, _as_ctrl_c)
    try:
        yield
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
