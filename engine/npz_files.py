"""Reading the project's .npz files (templates, the Interaction Graph) without trusting them.

`np.load` believes what an archive says: a 4.7 MB file whose member declares a 9 GB array
is decompressed into 9 GB before anything can object. `read_npz` looks first: it refuses what
is not a regular file, a bare `.npy`, an archive whose members declare more than the caller's
limit in total, and a member whose array header asks for more bytes than the member holds;
then it loads with `allow_pickle=False`, so object arrays are refused too.
"""

from __future__ import annotations

import json
import os
import time
import zipfile
import zlib
from collections.abc import Callable
from pathlib import Path

import numpy as np

from engine.errors import not_a_regular_file

try:
    import fcntl
except ImportError:  # Windows: no part file is locked, and none is removed
    fcntl = None

MAX_MEMBERS = 256


class NpzFileError(ValueError):
    """An .npz that is unreadable or over its limits; the message does not name the file (the
    loaders add the path and what the file should have been)."""


def _npy_bytes(zf: zipfile.ZipFile, info: zipfile.ZipInfo) -> int:
    """The array bytes a member's .npy header declares (from its first bytes only)."""
    with zf.open(info) as f:
        version = np.lib.format.read_magic(f)
        if version == (1, 0):
            shape, _, dtype = np.lib.format.read_array_header_1_0(f)
        else:
            shape, _, dtype = np.lib.format.read_array_header_2_0(f)
    if dtype.hasobject:
        raise NpzFileError(f"member {info.filename!r} holds Python objects (never loaded)")
    return int(np.prod(shape, dtype=object)) * dtype.itemsize


def _declared_members(fh) -> int:
    """The member count an archive's end record declares, found as zipfile finds it, but before
    zipfile reads the whole central directory into some 400 bytes of objects a member (24 MB of
    empty members took 115 MB before their count could be refused). 0 when there is no end record."""
    try:
        end = zipfile._EndRecData(fh)  # the record zipfile itself reads the count from
        count = 0 if end is None else int(end[zipfile._ECD_ENTRIES_TOTAL])
    except AttributeError:  # a zipfile without them: the count is checked once the directory is read
        count = 0
    fh.seek(0)
    return count


def read_npz(path: str | os.PathLike, max_bytes: int, keep: Callable[[str], bool] | None = None) -> dict[str, np.ndarray]:
    """Every array of an .npz (those whose name `keep` accepts, when given), after checking the
    whole file fits in `max_bytes` uncompressed. Raises FileNotFoundError for a missing file,
    NpzFileError for everything else that is wrong."""
    path = Path(path)
    st = os.stat(path)  # FileNotFoundError passes through: the loaders word it themselves
    if why := not_a_regular_file(st):
        raise NpzFileError(why)
    try:
        with open(path, "rb") as fh:
            head = fh.read(6)
            if head == b"\x93NUMPY":
                raise NpzFileError("a single .npy array, not an .npz archive")
            fh.seek(0)
            if (n := _declared_members(fh)) > MAX_MEMBERS:
                raise NpzFileError(f"{n} members, at most {MAX_MEMBERS}")
            with zipfile.ZipFile(fh) as zf:
                infos = zf.infolist()
                if len(infos) > MAX_MEMBERS:
                    raise NpzFileError(f"{len(infos)} members, at most {MAX_MEMBERS}")
                declared = sum(i.file_size for i in infos)
                if declared > max_bytes:
                    raise NpzFileError(f"{declared / 2**20:.1f} MiB uncompressed, over the {max_bytes / 2**20:.0f} MiB limit")
                for info in infos:
                    if not info.filename.endswith(".npy"):
                        raise NpzFileError(f"member {info.filename!r} is not an array")
                    if _npy_bytes(zf, info) > info.file_size:
                        raise NpzFileError(f"member {info.filename!r} declares more data than it holds")
            fh.seek(0)
            with np.load(fh, allow_pickle=False) as z:
                return {k: z[k] for k in z.files if keep is None or keep(k)}
    except NpzFileError:
        raise
    except (OSError, ValueError, EOFError, KeyError, zipfile.BadZipFile, zlib.error, NotImplementedError) as exc:
        raise NpzFileError(f"{exc.__class__.__name__}: {exc}") from None


def is_npz_head(head: bytes) -> bool:
    """Whether a file's first bytes are a zip archive's (an .npz is one; an empty archive starts
    with its end record): what an .npz output may replace (engine.errors.refuse_other_kind)."""
    return head.startswith((b"PK\x03\x04", b"PK\x05\x06"))


def read_json(array: np.ndarray) -> object:
    """The JSON text an .npz stores as a string array (a file's settings or meta record),
    parsed. NpzFileError (a ValueError) for text that is not JSON, holds an integer of over 4300
    digits or nests deeper than the parser recurses (`[` x 100,000 raised RecursionError)."""
    try:
        return json.loads(str(array))
    except RecursionError:
        raise NpzFileError("JSON nested too deeply") from None
    except ValueError as exc:
        raise NpzFileError(str(exc)) from None


PART_SUFFIX = ".part"
PART_RANDOM = 8  # the random characters tempfile.mkstemp puts in a name
_PART_CHARS = frozenset("abcdefghijklmnopqrstuvwxyz0123456789_")  # tempfile's alphabet


def _part_target(name: str) -> str | None:
    """The file name a write_replacing temporary file is for (`.<target_name>.<8 random
    characters>.part`), None for any other name: the exact shape, so that the parts of
    `take.csv.old` are not taken for those of `take.csv`."""
    if not (name.startswith(".") and name.endswith(PART_SUFFIX)):
        return None
    target, dot, middle = name[1:-len(PART_SUFFIX)].rpartition(".")
    return target if dot and target and len(middle) == PART_RANDOM and set(middle) <= _PART_CHARS else None


def _is_part_of(name: str, target_name: str) -> bool:
    """Whether `name` is one of write_replacing's temporary files for `target_name`."""
    return _part_target(name) == target_name


def _lock(fd: int, blocking: bool) -> bool:
    """An exclusive flock on `fd`; False when another holds it (blocking=False). The lock goes
    with the process, even at a SIGKILL: a part file nobody holds is one whose writer is gone."""
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | (0 if blocking else fcntl.LOCK_NB))
    except BlockingIOError:
        return False
    return True


STALE_PART_S = 3600  # a part of another file's name untouched this long, and unlocked, is a dead writer's


def _is_stale_part(entry: os.DirEntry, name: str) -> bool:
    """Whether `entry` may be a dead writer's part file, to be removed if no writer holds its lock:
    any part of `name` (ours by its name), and a part of another name untouched for STALE_PART_S
    (a just-made temporary file of the same shape may be another program's, which takes no lock)."""
    target = _part_target(entry.name)
    if target is None or target == name:
        return target == name
    try:
        return entry.stat(follow_symlinks=False).st_mtime < time.time() - STALE_PART_S
    except OSError:
        return False


def _remove_stale_parts(target: str) -> None:
    """Remove the part files in `target`'s folder left by writers that were killed (SIGKILL, a
    power cut): each such kill left one for good, and one of a file never written again (a trace
    named for its run) stayed whatever was written beside it. A part holds nothing to recover: a
    kill mid-write cuts a whole file's bytes short (an .npz's zip, a trace's JSON without its
    end: no reader takes them), of an output its command makes again; `quickjab record`'s takes,
    the data only a player has, are written in place, never as a part. A writer still alive holds
    a lock on its own, so two processes writing one file at once never take each other's. Best
    effort: a folder that cannot be listed, or a part that cannot be removed, is left as it was."""
    folder, name = os.path.dirname(target), os.path.basename(target)
    try:
        entries = [e for e in os.scandir(folder) if _is_stale_part(e, name)]
    except OSError:
        return
    for entry in entries:
        try:
            if not entry.is_file(follow_symlinks=False):
                continue
            fd = os.open(entry.path, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK)
        except OSError:
            continue
        try:
            # the lock held while the name is removed: a writer that made this file an instant
            # ago and locks it now finds it gone (write_replacing then makes another)
            if _lock(fd, blocking=False) and os.path.samestat(os.fstat(fd), os.stat(entry.path, follow_symlinks=False)):
                os.unlink(entry.path)
        except OSError:
            pass
        finally:
            os.close(fd)


def _own_part(target: str) -> tuple[int, str, int | None]:
    """A new part file for `target`: (its fd, its name, a second fd holding its lock, None
    without flock). The lock fd stays open until the file is renamed over `target`, so the lock
    is held from the file's first byte to the rename."""
    import tempfile

    while True:
        fd, tmp = tempfile.mkstemp(dir=os.path.dirname(target), prefix=f".{os.path.basename(target)}.", suffix=PART_SUFFIX)
        if fcntl is None:
            return fd, tmp, None
        lock_fd = os.dup(fd)  # one open file, so the lock outlives `fd` (closed before the rename);
        # not opened again by name: a cleaner may have removed that name already
        try:
            _lock(lock_fd, blocking=True)
        except OSError:  # a file system without locks: written unlocked, as before (cleaners skip it)
            return fd, tmp, lock_fd
        if os.fstat(lock_fd).st_nlink:  # not removed by a cleaner between mkstemp and the lock
            return fd, tmp, lock_fd
        os.close(lock_fd)
        os.close(fd)


def write_replacing(path: str | os.PathLike, write: Callable[[object], None]) -> None:
    """Call `write(f)` with a binary file that becomes `path` only once it is whole: written
    beside it, synced and renamed over it, so a full disk or a Ctrl-C halfway leaves the previous
    file as it was and no part of the new one. A `path` that exists and is not a regular file (a
    device such as /dev/full, a pipe) is written in place; a link keeps pointing where it did.
    The part files of earlier writes of `path` that were killed are removed first."""
    import stat

    target = os.path.realpath(path)
    try:
        mode = os.stat(target).st_mode
    except FileNotFoundError:
        mode = None
    if mode is not None and not stat.S_ISREG(mode):
        with open(target, "wb") as f:
            write(f)
        return
    if fcntl is not None:  # without flock a dead writer's part cannot be told from a live one's
        _remove_stale_parts(target)
    fd, tmp, lock_fd = _own_part(target)
    try:
        with os.fdopen(fd, "wb") as f:
            write(f)
            f.flush()
            os.fsync(f.fileno())  # on disk before the rename: a machine that crashes just after
            # it could otherwise show the new name with no data (an empty file where the old one was)
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, stat.S_IMODE(mode) if mode is not None else 0o666 & ~umask)
        os.replace(tmp, target)
    except BaseException:
        os.unlink(tmp)
        raise
    finally:
        if lock_fd is not None:
            os.close(lock_fd)
