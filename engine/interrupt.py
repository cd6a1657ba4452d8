"""SIGTERM and SIGHUP ending a command as Ctrl-C does.

`kill`, a service manager and `timeout` stop a process with SIGTERM; closing its terminal sends
SIGHUP. Their default ends the process on the spot: nothing of a `finally` runs, so a recording
lost the samples held for its rate and its summary, and `play --trace` wrote no trace. Inside
`stop_signals_as_ctrl_c()` both raise KeyboardInterrupt instead, and the command ends the way it
ends on Ctrl-C (its files written, its summary said, its usual exit status).
"""

from __future__ import annotations

import contextlib
import functools
import signal
import sys
from collections.abc import Callable, Iterator
from typing import TypeVar

F = TypeVar("F", bound=Callable)

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


def ends_as_ctrl_c(run: F) -> F:
    """`run` (a command's) inside stop_signals_as_ctrl_c(): for a command that starts pygame, where
    SDL otherwise made SIGTERM a quit event the loop took for a closed window or the end of a
    match (`bench frame` went on to its next run and reported the cut run as a pass, exit 0)."""

    @functools.wraps(run)
    def guarded(*args, **kwargs):
        with stop_signals_as_ctrl_c():
            return run(*args, **kwargs)

    return guarded  # type: ignore[return-value]


def as_worker() -> None:
    """The initializer of a worker process that a command under stop_signals_as_ctrl_c() starts
    (a ProcessPoolExecutor's): a forked worker inherited the parent's handlers, so SIGTERM raised
    KeyboardInterrupt in the middle of its task, and pygame.init() in a worker with SIGTERM at
    its default made SIGTERM a quit event nothing read; either way `kill` did not end it. Here
    SIGTERM and SIGHUP end the worker (their default, SDL kept off them), Ctrl-C to the process
    group is left to the parent, which ends its workers, and the worker ends when its parent does
    (a parent killed outright left its workers waiting for work forever). The parent is the
    process that started the worker, whatever the start method: the command's own under "fork"
    and "spawn", the fork server under "forkserver" (Python 3.14's default on Linux), which ends
    with the command."""
    import os

    parent = os.getppid()
    os.environ["SDL_NO_SIGNAL_HANDLERS"] = "1"
    for sig in STOP_SIGNALS:
        signal.signal(sig, signal.SIG_DFL)
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    _end_with_parent(parent)


def _end_with_parent(parent: int) -> None:
    """SIGTERM to this process when `parent` ends: Linux's parent-death signal, else a thread
    that looks for a new parent twice a second."""
    import os

    if sys.platform.startswith("linux"):
        import ctypes

        with contextlib.suppress(OSError, AttributeError):
            if ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGTERM, 0, 0, 0) == 0:  # PR_SET_PDEATHSIG
                if os.getppid() != parent:  # it ended before the signal was asked for
                    os._exit(128 + signal.SIGTERM)
                return
    import threading
    import time

    def watch() -> None:
        while os.getppid() == parent:
            time.sleep(0.5)
        os._exit(128 + signal.SIGTERM)

    threading.Thread(target=watch, name="end-with-parent", daemon=True).start()
