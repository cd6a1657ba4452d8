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
from collections.abc import Iterator


def _as_ctrl_c(signum: int, frame: object) -> None:
    raise KeyboardInterrupt


@contextlib.contextmanager
def stop_signals_as_ctrl_c() -> Iterator[None]:
    """SIGTERM and SIGHUP raise KeyboardInterrupt in the block; the handlers before are put back
    after it. Installed before SDL starts, this also keeps SDL from taking SIGTERM for itself (it
    does only where the handler is still the default) and turning it into a closed window."""
    previous = {}
    for sig in filter(None, (signal.SIGTERM, getattr(signal, "SIGHUP", None))):  # Windows has no SIGHUP
        with contextlib.suppress(ValueError):  # not the main thread: the default stays
            previous[sig] = signal.signal(sig, _as_ctrl_c)
    try:
        yield
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
