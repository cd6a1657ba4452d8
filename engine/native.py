"""Small C kernels for the hot loops, built once with the system's C compiler and loaded with
ctypes (issue 14: numba's import and code load cost ~0.6 s and ~110 MB of every start).

A kernel is a C source string; `load_library(stem, source, symbols)` compiles it on its first
use on a machine into the user's cache directory (see docs/performance.md for the first-build
time) and afterwards only opens it (~1 ms). Without a compiler (cc, gcc, clang or $CC), on a
non-POSIX system, or with QUICKJAB_NO_NATIVE=1 (or QUICKJAB_NO_JIT=1: no compiled code at all)
it returns None and the caller runs its numpy version. The physics kernels follow numpy's
operations one for one (no fused multiply-add, -ffp-contract=off; no reassociation; sqrt
correctly rounded), so worlds step to the same bits with or without a compiler; so do the DTW
kernel's scores and the numpy "loop" method that `method="auto"` runs without it
(engine/recognition/dtw_loop.py), so the recognizer decides the same.

What can go wrong is handled once, not on every start: a cached library that does not open or
lacks its symbols (corrupt, another machine's) is deleted and rebuilt once; a failed build is
remembered in a marker file (keyed like the library plus the compiler) with its reason; a
rejected -march=native is retried once without it; an unwritable cache directory falls back
to a per-user temporary one. `status()` says, per kernel, whether it runs native or numpy and
why (`quickjab bench frame` and `bench startup` print it).
"""

from __future__ import annotations

import ctypes
import errno
import hashlib
import os
import platform
import sys
from pathlib import Path

from engine.xdg import is_there

NO_NATIVE_ENV = "QUICKJAB_NO_NATIVE"
NO_JIT_ENV = "QUICKJAB_NO_JIT"
CACHE_ENV = "QUICKJAB_CACHE_DIR"
# Vectorized where it can be, the result bit for bit the plain loop's: no FMA contraction, and
# errno-free sqrt (same value; lets the compiler use the vector instruction).
FLAGS = ["-O3", "-march=native", "-shared", "-fPIC", "-std=c99", "-ffp-contract=off", "-fno-math-errno"]
# the retry when the compiler rejects -march=native (some ARM gccs, older clangs)
PORTABLE_FLAGS = [f for f in FLAGS if not f.startswith("-march")]
# a compiler that failed because its output could not be written: tried again at the next start
FULL_DISK = tuple(os.strerror(e) for e in (errno.ENOSPC, errno.EDQUOT))
STALE_TMP_SECONDS = 300.0  # a build takes seconds; a temporary dir older than this was left by a killed one
BUILD_PREFIX = ".quickjab-build-"  # a build's temporary dir: the cache dir may be shared (~/.cache, /tmp)

_status: dict[str, str] = {}  # stem -> "native: ..." or "numpy: ..." (this process's loads)


def address(a) -> int:
    """The data pointer of a C-contiguous numpy array, for a kernel call. `a.ctypes.data` builds
    numpy's ctypes helper object on every access (2-8 us here, more than the kernels it feeds:
    a contact step made ~60 such lookups); a ctypes view of the buffer is ~4x cheaper. Read-only
    and empty arrays (no writable buffer) take numpy's way."""
    try:
        return ctypes.addressof(ctypes.c_char.from_buffer(a))
    except (TypeError, ValueError, BufferError):
        return a.ctypes.data


_last_array: list = [None, 0]  # the last array `array_address` was asked for, and its address


def array_address(a) -> int:
    """address(a), remembered for the array asked for last (held, so its id cannot be reused):
    the world's positions go to every kernel call of a step."""
    if a is not _last_array[0]:
        _last_array[0], _last_array[1] = a, address(a)
    return _last_array[1]


def disabled() -> bool:
    return any(os.environ.get(v, "").strip() not in ("", "0") for v in (NO_NATIVE_ENV, NO_JIT_ENV))


def cache_dir() -> Path:
    """Where built libraries are kept: $QUICKJAB_CACHE_DIR, else $XDG_CACHE_HOME/quickjab or
    ~/.cache/quickjab."""
    if os.environ.get(CACHE_ENV):
        return Path(os.environ[CACHE_ENV])
    from engine.xdg import base_dir

    return base_dir("XDG_CACHE_HOME", ".cache") / "quickjab"  # a relative one is ignored (the XDG spec)


def fallback_dir() -> Path:
    """The per-user temporary cache used when cache_dir() cannot be written."""
    import tempfile

    return Path(tempfile.gettempdir()) / f"quickjab-{os.getuid()}"


def _safe_fallback(path: Path) -> bool:
    """The temporary dir is ours alone: created by this user and writable by no one else (a
    library planted there by another user must never be loaded)."""
    try:
        st = path.stat()
    except OSError:
        return False
    return path.is_dir() and st.st_uid == os.getuid() and not st.st_mode & 0o022


def _cpu_features() -> str:
    """The CPU's feature flags (Linux), part of the library's key: it is built with
    -march=native, so a cache shared with another CPU (a network home) must not run it there."""
    try:
        with open("/proc/cpuinfo") as fh:
            for line in fh:
                if line.startswith(("flags", "Features")):
                    return line
    except OSError:
        pass
    return ""


def _key(*parts: str) -> str:
    return hashlib.sha256("\0".join(parts).encode()).hexdigest()[:16]


def _library_name(stem: str, source: str, flags: list[str]) -> str:
    return f"{stem}-{_key(source, *flags, platform.machine(), sys.platform, _cpu_features())}.so"


def library_path(stem: str, source: str, flags: list[str] | None = None, directory: Path | None = None) -> Path:
    """The library's file name names the source, the flags and the machine (architecture and
    CPU features), so a changed kernel or another CPU never loads a stale build."""
    return (directory or cache_dir()) / _library_name(stem, source, FLAGS if flags is None else flags)


def failure_marker(stem: str, source: str, flags: list[str], cc: str, directory: Path | None = None) -> Path:
    """The file that remembers a failed build: the library's key plus the compiler's path, so
    another compiler (or CC) is tried afresh. Delete it to retry."""
    name = _library_name(stem, source, flags)[: -len(".so")]
    return (directory or cache_dir()) / f"{name}-{_key(cc)}.failed"


def compiler() -> str | None:
    import shutil

    return os.environ.get("CC") or shutil.which("cc") or shutil.which("gcc") or shutil.which("clang")


def _writable(d: Path) -> bool:
    try:
        d.mkdir(parents=True, exist_ok=True, mode=0o700)
    except OSError:
        return False
    return d.is_dir() and os.access(d, os.W_OK | os.X_OK)


def _dirs() -> list[Path]:
    """Where libraries are looked for: the cache, then the temporary fallback if it is ours."""
    fb = fallback_dir()
    return [cache_dir()] + ([fb] if is_there(fb) and _safe_fallback(fb) else [])


def _build_dir() -> Path | None:
    """The first directory a build can write: the cache, else the per-user temporary one."""
    if _writable(cache_dir()):
        return cache_dir()
    fb = fallback_dir()
    return fb if _writable(fb) and _safe_fallback(fb) else None


def _open(path: Path, symbols: tuple[str, ...]) -> ctypes.CDLL | None:
    """The library, or None when it does not load here or lacks one of `symbols`."""
    try:
        lib = ctypes.CDLL(str(path))
    except OSError:
        return None
    try:
        for name in symbols:
            getattr(lib, name)
    except AttributeError:
        import _ctypes

        # closed, or the dynamic loader would hand this same library back for the rebuilt file
        _ctypes.dlclose(lib._handle)
        return None
    return lib


def _remove(path: Path) -> None:
    try:
        path.unlink()
    except OSError:
        pass


def _one_line(text: str, limit: int = 160) -> str:
    lines = [line.strip() for line in text.splitlines() if line.strip()]
    line = next((x for x in lines if "error" in x.lower()), lines[0] if lines else "")
    return line[:limit]


def _build(target: Path, source: str, flags: list[str], cc: str) -> tuple[str, bool] | None:
    """Compile `source` into `target` (atomically: a half-written library never loads).
    None when built, else (the reason in one line, whether to remember it): the compiler's
    failure is remembered (it would fail again, and costs its run); an OSError around it (a full
    disk, a directory gone, a compiler that does not run) is not: it costs nothing to try again
    and may be gone by the next start."""
    import subprocess
    import tempfile

    try:
        with tempfile.TemporaryDirectory(dir=target.parent, prefix=BUILD_PREFIX) as tmp:
            src, out = Path(tmp) / "kernel.c", Path(tmp) / target.name
            src.write_text(source)
            r = subprocess.run([cc, *flags, "-o", str(out), str(src), "-lm"], capture_output=True, timeout=60)
            if r.returncode != 0 or not out.exists():
                stderr = r.stderr.decode(errors="replace")
                full = next((m for m in FULL_DISK if m in stderr), "")  # the disk's, not the compiler's
                why = full or _one_line(stderr)
                return f"{cc} exit {r.returncode}" + (f": {why}" if why else ""), not full
            os.replace(out, target)
        return None
    except subprocess.TimeoutExpired:
        return f"{cc} took over 60 s", True
    except (OSError, subprocess.SubprocessError) as e:
        return f"{cc}: {e}", False


def _remember(marker: Path, reason: str) -> None:
    """Write a failed build's marker; one that cannot be written whole (a full disk) is removed:
    an empty marker said nothing and kept the kernel on numpy after the disk had room again."""
    try:
        marker.write_text(reason + "\n")
    except OSError:
        _remove(marker)


def _build_leftover(p: Path) -> bool:
    """A temporary dir a killed build left: named so, or (before BUILD_PREFIX) a "tmp..." dir
    holding only a kernel source and libraries. $QUICKJAB_CACHE_DIR may be ~/.cache or /tmp,
    where other programs' "tmp..." dirs are not ours to delete."""
    if not p.is_dir() or p.is_symlink():
        return False
    if p.name.startswith(BUILD_PREFIX):
        return True
    names = [c.name for c in p.iterdir()] if p.name.startswith("tmp") else []
    return "kernel.c" in names and all(n == "kernel.c" or n.endswith(".so") for n in names)


def _prune(directory: Path, stem: str, keep: Path, markers: set[str]) -> None:
    """After a build: other builds of this kernel (an older source, another CPU), its stale
    failure markers, and temporary dirs left by killed builds."""
    import re
    import shutil
    import time

    pattern = re.compile(rf"{re.escape(stem)}-[0-9a-f]{{16}}(-[0-9a-f]{{16}}\.failed|\.so)")
    now = time.time()
    try:
        entries = list(directory.iterdir())
    except OSError:
        return
    for p in entries:
        try:
            if pattern.fullmatch(p.name) and p != keep and p.name not in markers:
                p.unlink()
            elif _build_leftover(p) and now - p.stat().st_mtime > STALE_TMP_SECONDS:
                shutil.rmtree(p, ignore_errors=True)
        except OSError:
            pass


def _numpy(stem: str, reason: str) -> None:
    _status[stem] = f"numpy: {reason}"
    return None


def load_library(stem: str, source: str, symbols: tuple[str, ...] = ()) -> ctypes.CDLL | None:
    """The compiled `source` (built now if this machine has never built it), or None. A cached
    library that does not open or lacks one of `symbols` is deleted and built again, once."""
    if disabled():
        return _numpy(stem, f"{NO_NATIVE_ENV} or {NO_JIT_ENV} is set")
    if os.name != "posix":
        return _numpy(stem, "not a POSIX system")
    variants = (FLAGS, PORTABLE_FLAGS)
    for d in _dirs():
        for flags in variants:
            path = library_path(stem, source, flags, d)
            if is_there(path):
                lib = _open(path, symbols)
                if lib is not None:
                    _status[stem] = f"native: {path}"
                    return lib
                _remove(path)  # corrupt, or another machine's: built again below
    cc = compiler()
    if not cc:
        return _numpy(stem, "no C compiler (cc, gcc, clang or $CC)")
    d = _build_dir()
    if d is None:
        return _numpy(stem, f"no writable cache directory ({cache_dir()}, {fallback_dir()})")
    markers = {failure_marker(stem, source, flags, cc, d).name for flags in variants}
    reason = ""
    for flags in variants:
        path, marker = library_path(stem, source, flags, d), failure_marker(stem, source, flags, cc, d)
        if is_there(marker):
            try:
                reason = marker.read_text().strip() or "the build failed"
            except OSError:
                reason = "the build failed"
            reason += f" (an earlier start's build, remembered: delete {d}/*.failed to retry)"  # one reason for all kernels
            continue
        failed = _build(path, source, flags, cc)
        if failed is None:
            lib = _open(path, symbols)
            if lib is not None:
                _prune(d, stem, path, markers)
                _status[stem] = f"native: built {path}"
                return lib
            if not is_there(path):  # pruned by another kernel version's build meanwhile: not a failure
                return _numpy(stem, f"{path} was removed while loading it; the next start builds it again")
            _remove(path)
            failed = f"{cc} built a library that does not load or lacks {', '.join(symbols)}", True
        reason, remember = failed
        if remember:
            _remember(marker, reason)
    return _numpy(stem, reason)


def status() -> dict[str, str]:
    """Per kernel loaded in this process: "native: <library>" or "numpy: <why>"."""
    return dict(_status)


def describe(stems: tuple[str, ...] | None = None) -> str:
    """One line: whether the kernels loaded so far (or those of `stems`) run native or numpy, and why."""
    loaded = {k: v for k, v in sorted(_status.items()) if stems is None or k in stems}
    if not loaded:
        return "C kernels: none loaded"
    numpy = {k: v for k, v in loaded.items() if v.startswith("numpy")}
    if not numpy:
        return f"C kernels: native ({', '.join(loaded)})"
    why = sorted(set(v[len("numpy: "):] for v in numpy.values()))
    return f"C kernels: numpy for {', '.join(numpy)} ({'; '.join(why)})" + (
        f"; native: {', '.join(k for k in loaded if k not in numpy)}" if len(numpy) < len(loaded) else "")
