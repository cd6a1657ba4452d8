"""Errors about input a user can fix (a bad file, a bad URL). The CLI prints them as one line
naming the file and exits with code 2, without a traceback."""

from __future__ import annotations

import os
import stat
from collections.abc import Callable, Iterable


class InputError(Exception):
    """Bad input that names itself: a file, a line, a URL."""


def not_a_regular_file(st: os.stat_result) -> str | None:
    """Why the file `st` describes cannot be read as input (None: it can). A FIFO or a device
    reports size 0, so no size limit stops it, and opening a FIFO blocks until a writer comes
    while /dev/zero never ends: every reader asks this before it opens a file."""
    if stat.S_ISREG(st.st_mode):
        return None
    return "a directory" if stat.S_ISDIR(st.st_mode) else "not a regular file (a pipe or a device?)"


def same_file(a: str | os.PathLike, b: str | os.PathLike) -> bool:
    """Whether `a` and `b` name one file: the same file through links and other spellings when
    both exist, else the same resolved path."""
    try:
        return os.path.samefile(a, b)
    except (OSError, ValueError):  # one of them is not there (yet)
        return os.path.realpath(a) == os.path.realpath(b)


def refuse_overwriting(outputs: dict[str, str | os.PathLike | None], inputs: Iterable[str | os.PathLike | None]) -> None:
    """InputError when a file a command is to write ({option: path}, None: not given) is one of
    the files it reads, or another of its outputs: `recognize rec.csv -o rec.csv` emptied the
    recording, `bvh cut a.bvh -o a.bvh` replaced the capture with JSON. Said before any work."""
    given = [(flag, out) for flag, out in outputs.items() if out is not None]
    inputs = [inp for inp in inputs if inp is not None and os.path.exists(inp)]  # what is not there is not lost
    for k, (flag, out) in enumerate(given):
        for inp in inputs:
            if same_file(out, inp):
                raise InputError(f"{flag} {out}: is the input {inp}; writing it would destroy it (give another file)")
        for other, out2 in given[k + 1:]:
            if same_file(out, out2):
                raise InputError(f"{flag} {out} and {other} {out2} are one file: give each its own")


HEAD_BYTES = 64  # enough for any kind's first line or magic number


def refuse_other_kind(path: str | os.PathLike, flag: str, kind: str, is_kind: Callable[[bytes], bool]) -> None:
    """InputError when `path` holds a file that is plainly not a `kind` (`is_kind` of its first
    HEAD_BYTES bytes is false): a derived output a command makes again (templates, a graph, a
    BVH, a screenshot, a trace: engine.file_kinds) replaces an earlier one of its kind, but not
    whatever else is there (`synth --templates -o cut.json` wrote an .npz over an action). Said
    before the work. Nothing there, an empty file and what is not a regular file (/dev/null)
    pass."""
    try:
        st = os.stat(path)
        if not stat.S_ISREG(st.st_mode) or st.st_size == 0:
            return
        with open(path, "rb") as f:
            head = f.read(HEAD_BYTES)
    except OSError:  # not there, or not readable: the write says what is wrong, if anything
        return
    if not is_kind(head):
        where = f"{flag} {path}" if flag else str(path)
        raise InputError(f"{where}: is there and is not {kind}; not replaced (give another file, or move it)")
