"""Writers that replace a file the player had write the new one beside it and rename it over:
a write that fails halfway (a full disk; here a file size limit, EFBIG) or a kill mid-write
leaves the previous file as it was, never a truncated one in its place."""

from __future__ import annotations

import contextlib
import resource

import numpy as np
import pytest

from engine.recording import Recording, RecordingError, read_recording, write_recording

LIMIT = 4096  # bytes a write may reach: every new file below is larger


@contextlib.contextmanager
def small_files():
    """Writes past LIMIT bytes fail with EFBIG (Python ignores SIGXFSZ)."""
    soft, hard = resource.getrlimit(resource.RLIMIT_FSIZE)
    resource.setrlimit(resource.RLIMIT_FSIZE, (LIMIT, hard))
    try:
        yield
    finally:
        resource.setrlimit(resource.RLIMIT_FSIZE, (soft, hard))


def _recording(n: int, seed: int) -> Recording:
    rng = np.random.default_rng(seed)
    return Recording(np.arange(n) / 60.0, rng.normal(0, 0.3, (n, 2, 3)), meta={"seed": str(seed)})


def test_a_recording_written_over_another_is_whole_or_not_at_all(tmp_path):
    path = tmp_path / "rec.csv"
    write_recording(path, _recording(50, 1))  # under the limit
    before = path.read_bytes()
    with small_files(), pytest.raises(RecordingError) as err:
        write_recording(path, _recording(2000, 2))
    assert str(path) in str(err.value) and "cannot write" in str(err.value)
    assert path.read_bytes() == before  # was cut at LIMIT bytes, the old recording gone
    assert len(read_recording(path)) == 50
    assert [p.name for p in tmp_path.iterdir()] == ["rec.csv"]  # no part file left


def test_a_trace_written_over_another_is_whole_or_not_at_all(tmp_path):
    from engine.trace import TraceError, write_chrome_trace
    from tests.engine.test_trace import traced_loop

    path = tmp_path / "trace.json"
    path.write_text('{"traceEvents": []}')
    with small_files(), pytest.raises(TraceError):
        write_chrome_trace(traced_loop(frames=40).budget, path)
    assert path.read_text() == '{"traceEvents": []}'


def test_a_graph_saved_over_another_is_whole_or_not_at_all(tmp_path):
    from game.interaction import DEFAULT_GRAPH
    from game.interaction.table import GraphTable

    if not DEFAULT_GRAPH.exists():
        pytest.skip("no shipped graph to save")
    path = tmp_path / "graph-small.npz"
    path.write_bytes(b"the cache the player had")
    table = GraphTable.load(DEFAULT_GRAPH)
    with small_files(), pytest.raises(OSError):
        table.save(path)
    assert path.read_bytes() == b"the cache the player had"


def test_the_new_file_is_synced_before_it_replaces_the_old(tmp_path, monkeypatch):
    """A rename without a sync first may reach the disk before the data: after a power cut the
    player's file could be empty instead of the old one or the new."""
    import os

    from engine import npz_files

    calls = []
    real_fsync, real_replace = os.fsync, os.replace
    monkeypatch.setattr(npz_files.os, "fsync", lambda fd: (calls.append("fsync"), real_fsync(fd))[1])
    monkeypatch.setattr(npz_files.os, "replace", lambda a, b: (calls.append("replace"), real_replace(a, b))[1])
    npz_files.write_replacing(tmp_path / "t.npz", lambda f: f.write(b"data"))
    assert calls == ["fsync", "replace"]
    assert (tmp_path / "t.npz").read_bytes() == b"data"


SLOW_WRITER = """
import sys, time
from engine.npz_files import write_replacing

def write(f):
    f.write(b"half a file")
    f.flush()
    print("writing", flush=True)
    time.sleep(120)  # killed before this ends

write_replacing(sys.argv[1], write)
"""


def test_a_part_file_left_by_a_killed_writer_goes_when_the_file_is_written_again(tmp_path):
    """A SIGKILL mid-write (a templates set, a graph cache, a trace) left `.<name>.<random>.part`
    beside the file for good, one more each time. The next write of that file removes those of
    writers that are gone, and never the one a writer still alive is writing."""
    import os
    import subprocess
    import sys
    from pathlib import Path

    from engine.npz_files import write_replacing

    repo = Path(__file__).resolve().parents[2]
    target = tmp_path / "trace.json"
    other = tmp_path / ".trace.json.old.abcdefgh.part"  # another file's name: never touched
    other.write_bytes(b"not ours")
    proc = subprocess.Popen([sys.executable, "-c", SLOW_WRITER, str(target)], cwd=repo, stdout=subprocess.PIPE,
                            text=True, env={**os.environ, "PYTHONPATH": str(repo)})
    try:
        assert proc.stdout.readline() == "writing\n"
        live = sorted(tmp_path.glob(".trace.json.????????.part"))
        assert len(live) == 1 and live[0].read_bytes() == b"half a file"
        write_replacing(target, lambda f: f.write(b"first"))  # while the other writer is alive
        assert sorted(tmp_path.glob(".trace.json.????????.part")) == live and target.read_bytes() == b"first"
    finally:
        proc.kill()
        proc.wait()
    assert live[0].exists()  # nothing runs at a SIGKILL
    write_replacing(target, lambda f: f.write(b"second"))
    assert sorted(p.name for p in tmp_path.iterdir()) == [other.name, "trace.json"]
    assert target.read_bytes() == b"second" and other.read_bytes() == b"not ours"


BUSY_WRITER = """
import sys
from engine.npz_files import write_replacing

for i in range(300):
    write_replacing(sys.argv[1], lambda f: f.write(sys.argv[2].encode() * 4096))
"""


def test_processes_writing_one_file_at_once_never_take_each_others_part_file(tmp_path):
    # each write clears the parts of writers that are gone: one still writing, or one that has
    # just made its part file and not yet locked it, keeps its own (a first version lost writes so)
    import os
    import subprocess
    import sys
    from pathlib import Path

    repo = Path(__file__).resolve().parents[2]
    target = tmp_path / "templates.npz"
    procs = [subprocess.Popen([sys.executable, "-c", BUSY_WRITER, str(target), tag], cwd=repo, stderr=subprocess.PIPE,
                              text=True, env={**os.environ, "PYTHONPATH": str(repo)}) for tag in "ab"]
    errors = [p.communicate(timeout=120)[1] for p in procs]
    assert [p.returncode for p in procs] == [0, 0], errors
    assert [p.name for p in tmp_path.iterdir()] == ["templates.npz"]
    assert target.read_bytes() in (b"a" * 4096, b"b" * 4096)


def test_a_write_also_clears_old_part_files_of_other_names_whose_writer_is_gone(tmp_path):
    """A killed writer's part of a file never written again (a trace named for its run, a
    synthesized take) stayed for good. A write into the folder removes the parts of other names
    that no writer holds (the flock is free) and that nothing has touched for an hour; one a
    writer holds, or one just made (another program's temporary file in the same shape, which
    takes no lock), stays."""
    import fcntl
    import os
    import time

    from engine.npz_files import STALE_PART_S, write_replacing

    def part(name: str, age_s: float):
        p = tmp_path / name
        p.write_bytes(b"half a file")
        then = time.time() - age_s
        os.utime(p, (then, then))
        return p

    gone = part(".take.csv.abcdefgh.part", STALE_PART_S + 60)
    held = part(".templates.npz.ijklmnop.part", STALE_PART_S + 60)
    fresh = part(".graph.npz.qrstuvwx.part", 5)
    not_a_part = part(".notes.txt.part", STALE_PART_S + 60)  # no random middle: not write_replacing's
    with open(held, "rb") as f:
        fcntl.flock(f.fileno(), fcntl.LOCK_EX)  # a live writer's
        write_replacing(tmp_path / "trace.json", lambda fh: fh.write(b"{}"))
    assert not gone.exists()
    assert held.exists() and fresh.exists() and not_a_part.exists()
