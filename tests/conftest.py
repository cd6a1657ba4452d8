"""Shared fixtures. Real recordings are read from ../shared/data (never copied into the repo);
tests that need them skip cleanly when that folder is absent."""

from __future__ import annotations

import atexit
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import tracemalloc
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
os.environ.setdefault("SDL_AUDIODRIVER", "dummy")
# No test reads the real user's config file (game/user_config.py); subprocesses inherit this.
# Removed when the run ends (each run left one behind in the temporary folder for good).
_CONFIG_HOME = tempfile.mkdtemp(prefix="quickjab-test-config-")
os.environ["XDG_CONFIG_HOME"] = _CONFIG_HOME
atexit.register(shutil.rmtree, _CONFIG_HOME, True)

REPO = Path(__file__).resolve().parent.parent
SHARED_DATA = Path(os.environ.get("QUICKJAB_SHARED_DATA", REPO.parent / "shared" / "data"))


@pytest.fixture(scope="session")
def shared_data() -> Path:
    """../shared/data, or skip the test when it is not there."""
    if not SHARED_DATA.is_dir():
        pytest.skip(f"shared data not found at {SHARED_DATA}")
    return SHARED_DATA


@pytest.fixture
def peak_memory() -> Callable[[Callable[[], Any]], tuple[Any, int]]:
    """`peak_memory(call)`: call() and the peak of the memory Python allocated during it (bytes)."""

    def measure(call: Callable[[], Any]) -> tuple[Any, int]:
        tracemalloc.start()
        try:
            out = call()
            return out, tracemalloc.get_traced_memory()[1]
        finally:
            tracemalloc.stop()

    return measure


@pytest.fixture
def sigterm_when_running() -> Callable[..., tuple[int, str, str]]:
    """`sigterm_when_running(argv, env, settle=1.0)`: start `quickjab argv` in `env`, send it
    SIGTERM once it has loaded SDL and run `settle` seconds more (its loop going), and return its
    exit code, stdout and stderr. SDL makes SIGTERM a quit event: the commands' tests check it
    ends them as Ctrl-C does."""

    def run(argv: list[str], env: dict[str, str], settle: float = 1.0) -> tuple[int, str, str]:
        p = subprocess.Popen([sys.executable, "-m", "tools.cli", *argv], cwd=REPO, env=env,
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        try:
            deadline = time.monotonic() + 60
            while p.poll() is None and "libSDL2" not in Path(f"/proc/{p.pid}/maps").read_text() \
                    and time.monotonic() < deadline:
                time.sleep(0.1)
            time.sleep(settle)
            assert p.poll() is None, f"quickjab {argv[0]} ended by itself"
            p.send_signal(signal.SIGTERM)
            out, err = p.communicate(timeout=60)
        finally:
            if p.poll() is None:
                p.kill()
                p.wait()
        return p.returncode, out, err

    return run
