"""engine.arguments.output_file: a place where the output cannot be made is refused before the
work, also where os.access says yes (root on /proc or /sys); the check leaves nothing behind."""

from __future__ import annotations

import argparse
import os
from pathlib import Path

import pytest

from engine import arguments


@pytest.mark.skipif(not Path("/proc/self").exists(), reason="needs Linux's /proc")
def test_a_folder_where_no_file_can_be_made_is_refused_even_where_os_access_says_yes(monkeypatch):
    # root's view: os.access passes on /proc, so `play --trace /proc/x.json` played the whole
    # match and only then said it could not write the trace
    monkeypatch.setattr(arguments.os, "access", lambda *a, **k: True)
    with pytest.raises(argparse.ArgumentTypeError, match=r"^/proc/quickjab-x\.json: cannot write there"):
        arguments.output_file("/proc/quickjab-x.json")
    with pytest.raises(argparse.ArgumentTypeError, match="cannot write there"):
        arguments.trace_file("/proc/quickjab-x.json")


def test_the_check_leaves_no_file_and_never_touches_one_that_is_there(tmp_path):
    new = tmp_path / "new.json"
    assert arguments.output_file(str(new)) == str(new)
    assert not os.path.lexists(new) and list(tmp_path.iterdir()) == []
    there = tmp_path / "there.json"
    there.write_text("{}")
    os.utime(there, ns=(1_000_000_000, 1_000_000_000))
    assert arguments.output_file(str(there)) == str(there)
    assert there.read_text() == "{}" and there.stat().st_mtime_ns == 1_000_000_000
    dangling = tmp_path / "link.json"
    dangling.symlink_to(tmp_path / "elsewhere.json")
    arguments.output_file(str(dangling))
    assert not (tmp_path / "elsewhere.json").exists()  # not made through the link


def test_folders_not_made_yet_are_still_fine_and_not_made(tmp_path):
    out = tmp_path / "a" / "b" / "t.json"
    assert arguments.output_file(str(out)) == str(out)
    assert not (tmp_path / "a").exists()


@pytest.mark.skipif(not Path("/proc/self").exists(), reason="needs Linux's /proc")
def test_folders_that_cannot_be_made_are_refused_before_the_work(monkeypatch):
    """`--trace /proc/new/t.json` (folders to make in a place nothing can be made) was refused
    only after the match; the first folder to make is made and removed to see."""
    monkeypatch.setattr(arguments.os, "access", lambda *a, **k: True)
    with pytest.raises(argparse.ArgumentTypeError, match=r"^/proc/quickjab-new/t\.json: cannot make /proc/quickjab-new"):
        arguments.output_file("/proc/quickjab-new/t.json")


def test_a_probe_that_cannot_be_removed_is_no_traceback(tmp_path, monkeypatch):
    """A folder that lets one create but not remove (or a scanner holding the file): the probe
    stays, the argument passes, no PermissionError escapes argparse's type."""
    def refuse(path):
        raise PermissionError(13, "Permission denied", str(path))

    monkeypatch.setattr(arguments.os, "unlink", refuse)
    monkeypatch.setattr(arguments.os, "rmdir", refuse)
    assert arguments.output_file(str(tmp_path / "x.json")) == str(tmp_path / "x.json")
    assert arguments.output_file(str(tmp_path / "d" / "x.json")) == str(tmp_path / "d" / "x.json")


def test_a_file_put_in_the_probes_place_is_not_removed(tmp_path, monkeypatch):
    """Another writer renaming its finished output onto the path between the probe's creation
    and its removal keeps its file."""
    out = tmp_path / "x.json"
    real_fstat = os.fstat

    def fstat_then_replace(fd):
        st = real_fstat(fd)
        theirs = tmp_path / "theirs"
        theirs.write_text("theirs")
        os.replace(theirs, out)
        return st

    monkeypatch.setattr(arguments.os, "fstat", fstat_then_replace)
    arguments.output_file(str(out))
    assert out.read_text() == "theirs"
