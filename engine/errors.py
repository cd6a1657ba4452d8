"""Errors about input a user can fix (a bad file, a bad URL). The CLI prints them as one line
naming the file and exits with code 2, without a traceback."""

from __future__ import annotations

import os
import stat


class InputError(Exception):
    """Bad input that names itself: a file, a line, a URL."""


def not_a_regular_file(st: os.stat_result) -> str | None:
    """Why the file `st` describes cannot be read as input (None: it can). A FIFO or a device
    reports size 0, so no size limit stops it, and opening a FIFO blocks until a writer comes
    while /dev/zero never ends: every reader asks this before it opens a file."""
    if stat.S_ISREG(st.st_mode):
        return None
    return "a directory" if stat.S_ISDIR(st.st_mode) else "not a regular file (a pipe or a device?)"
