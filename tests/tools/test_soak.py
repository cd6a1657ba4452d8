"""The soak: five minutes of simulated play (18,000 steps) with the full session headless, one
match after another: no exception, nothing dropped, memory flat after warm-up, and the play
was a real one (recognizer events, blows, rounds). Also the bounded History log it relies on."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from game.history import History
from tools.soak import passed, soak

REPO = Path(__file__).resolve().parents[2]


@pytest.mark.slow
def test_five_minutes_of_play_hold_steady(match_graph) -> None:
    fig = soak(18_000, seed=2, render_n=60, sample_seconds=10.0, warmup_seconds=60.0, graph=match_graph)
    assert fig["exception"] is None
    assert fig["steps"] == 18_000 and fig["dropped_steps"] == 0
    # a real match: the recognizer decided motions, blows landed, rounds went by
    ev = fig["recognizer_events"]
    assert ev.get("start", 0) > 50 and ev.get("end", 0) > 50
    assert fig["blows"] > 0
    assert fig["rounds"] >= 3
    # memory: measured, and flat after the first minute (an hour's limit is 10 MB)
    m = fig["memory"]
    assert m["rss_at_warmup_mb"] > 0 and m["samples"] == 31
    assert m["rss_growth_after_warmup_mb"] < 10.0
    assert passed(fig, 10.0)


def test_history_keeps_the_recent_items_and_hashes_all() -> None:
    a, b = History(3), History(3)
    for i in range(10):
        a.append(i)
        b.append(i)
    assert list(a) == [7, 8, 9] and a.total == 10
    assert a.digest() == b.digest()
    b.append(10)
    c = History(100)
    for i in range(11):
        c.append(i if i != 4 else -4)  # an early difference, long since dropped from the deque
    assert b.digest() != c.digest() and b.total == c.total


def test_soak_cli_json_and_bad_input(tmp_path) -> None:
    env = {"XDG_DATA_HOME": str(tmp_path), "PATH": "/usr/bin:/bin", "SDL_VIDEODRIVER": "dummy", "SDL_AUDIODRIVER": "dummy"}
    r = subprocess.run([sys.executable, "-m", "tools.cli", "soak", "--steps", "600", "--json", "--warmup-seconds", "2",
                        "--sample-seconds", "2"], cwd=REPO, capture_output=True, text=True, env=env, timeout=300)
    assert r.returncode == 0, r.stderr
    fig = json.loads(r.stdout)
    assert fig["steps"] == 600 and fig["passed"] is True
    for key in ("memory", "recognizer_events", "blows", "knockdowns", "rounds", "matches", "wall_seconds"):
        assert key in fig
    assert fig["memory"]["samples"] == 6
    bad = subprocess.run([sys.executable, "-m", "tools.cli", "soak", "--steps", "10", "--minutes", "1"],
                         cwd=REPO, capture_output=True, text=True, env=env, timeout=120)
    assert bad.returncode == 2 and bad.stderr.count("\n") == 1 and "not both" in bad.stderr


def test_a_soak_ends_on_sigterm(tmp_path, sigterm_when_running) -> None:
    """SDL turns SIGTERM into a quit event, which nothing in a soak reads: `kill` and `timeout`
    could not stop an hour's soak (it ran on, only SIGKILL ended it)."""
    import os
    import signal

    env = {**os.environ, "PYTHONPATH": str(REPO), "SDL_VIDEODRIVER": "dummy", "SDL_AUDIODRIVER": "dummy",
           "XDG_DATA_HOME": str(tmp_path)}
    code, _, _ = sigterm_when_running(["soak", "--minutes", "10", "--quiet"], env, settle=2.0)  # the session runs
    assert code == -signal.SIGTERM
