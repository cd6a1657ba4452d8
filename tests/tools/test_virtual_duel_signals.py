"""`graph duel --opponent virtual` plays its matches in worker processes. SIGTERM to the command
ended it on the spot and left the workers behind, unkillable by `kill` (SDL, or the parent's
Ctrl-C handler, had SIGTERM) and waiting for work forever. Now SIGTERM, SIGHUP and Ctrl-C end
the workers and the command exits 130 without a traceback; a killed parent takes its workers
with it; a killed worker ends the command with one line. Real processes and real signals; each
wait polls against a generous deadline."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")

REPO = Path(__file__).resolve().parents[2]
DEADLINE = 120.0  # seconds: a loaded 2-core machine


def children(pid: int) -> list[int]:
    out = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                fields = (entry / "stat").read_text().rsplit(")", 1)[1].split()
            except OSError:
                continue
            if int(fields[1]) == pid:
                out.append(int(entry.name))
    return out


def cpu_ticks(pid: int) -> int:
    """User + system CPU time of `pid` in clock ticks (0 when it is gone)."""
    try:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    except OSError:
        return 0
    return int(fields[11]) + int(fields[12])


def alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


def poll(condition, what: str) -> None:
    deadline = time.monotonic() + DEADLINE
    while not condition():
        assert time.monotonic() < deadline, what
        time.sleep(0.1)


@pytest.fixture
def duel(tmp_path, match_graph):
    """The command started (its own session, Ctrl-C at its default whatever ran pytest) once
    both workers play: each has used a CPU second, well past pygame.init()."""
    env = {**os.environ, "PYTHONPATH": str(REPO), "SDL_VIDEODRIVER": "dummy", "SDL_AUDIODRIVER": "dummy",
           "XDG_DATA_HOME": str(tmp_path)}
    cmd = [sys.executable, "-m", "tools.cli", "graph", "duel", "--opponent", "virtual", "--matches", "3",
           "--difficulty", "easy", "--jobs", "2"]
    if match_graph is not None:
        cmd += ["--graph", str(match_graph)]
    p = subprocess.Popen(cmd, cwd=REPO, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                         start_new_session=True, preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    workers: list[int] = []
    try:
        hz = os.sysconf("SC_CLK_TCK")
        poll(lambda: len(children(p.pid)) >= 2 or p.poll() is not None, "the workers never started")
        assert p.poll() is None, p.stderr.read()
        workers = children(p.pid)
        poll(lambda: all(cpu_ticks(w) >= hz for w in workers), "the workers never played")
        yield p, workers
    finally:
        for pid in [p.pid, *workers]:  # only what this test started
            if alive(pid):
                os.kill(pid, signal.SIGKILL)
        p.wait(timeout=DEADLINE)
        p.stderr.close()


@pytest.mark.parametrize("how", ["term", "hup", "ctrl-c"])
def test_a_stop_signal_ends_the_workers_and_exits_130(duel, how):
    p, workers = duel
    if how == "ctrl-c":
        os.killpg(p.pid, signal.SIGINT)  # the terminal's Ctrl-C: the whole group
    else:
        p.send_signal(signal.SIGTERM if how == "term" else signal.SIGHUP)
    assert p.wait(timeout=DEADLINE) == 130
    err = p.stderr.read()
    assert "Traceback" not in err and err.count("\n") <= 1, err
    poll(lambda: not any(alive(w) for w in workers), "a worker outlived the command")


def test_a_killed_parent_takes_its_workers(duel):
    p, workers = duel
    p.kill()
    assert p.wait(timeout=DEADLINE) == -signal.SIGKILL
    poll(lambda: not any(alive(w) for w in workers), "a worker outlived its killed parent")


def test_kill_ends_a_worker_and_the_command_says_so_in_one_line(duel):
    p, workers = duel
    os.kill(workers[0], signal.SIGTERM)
    poll(lambda: not alive(workers[0]), "`kill` did not end the worker")
    assert p.wait(timeout=DEADLINE) == 2
    err = p.stderr.read()
    assert err.count("\n") == 1 and "worker process ended" in err, err
    poll(lambda: not any(alive(w) for w in workers), "a worker outlived the command")


def _pid() -> int:
    return os.getpid()


@pytest.mark.parametrize("method", ["fork", "spawn", "forkserver"])
def test_a_worker_set_up_by_as_worker_works_under_every_start_method(method):
    # as_worker took the command's pid for the worker's parent: under "forkserver" (Python 3.14's
    # default on Linux) the parent is the fork server, and every worker ended on its first task
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor

    from engine.interrupt import as_worker

    if method not in multiprocessing.get_all_start_methods():
        pytest.skip(f"no {method} here")
    with ProcessPoolExecutor(max_workers=1, mp_context=multiprocessing.get_context(method), initializer=as_worker) as pool:
        assert pool.submit(_pid).result(timeout=120) != os.getpid()
