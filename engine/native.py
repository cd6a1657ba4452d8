"""Small C kernels for the hot loops, built once with the system's C compiler and loaded with
ctypes (issue 14: numba's import and code load cost ~0.6 s and ~110 MB of every start).

A kernel is a C source string; `load_library(stem, source)` compiles it on its first use on a
machine into the user's cache directory (~0.3 s) and afterwards only opens it (~1 ms). Without
a compiler (cc, gcc, clang or $CC), on a non-POSIX system, or with QUICKJAB_NO_NATIVE=1 (or
QUICKJAB_NO_JIT=1: no compiled code at all) it returns None and the caller runs its numpy
version, which gives the same results: the C follows numpy's operations one for one (no fused
multiply-add, -ffp-contract=off; no reassociation; sqrt correctly rounded), so states hash the
same with or without a compiler.
"""

from __future__ import annotations

import ctypes
import hashlib
import os
import platform
import sys
from pathlib import Path

NO_NATIVE_ENV = "QUICKJAB_NO_NATIVE"
NO_JIT_ENV = "QUICKJAB_NO_JIT"
CACHE_ENV = "QUICKJAB_CACHE_DIR"
# Vectorized where it can be, the result bit for bit the plain loop's: no FMA contraction, and
# errno-free sqrt (same value; lets the compiler use the vector instruction).
FLAGS = ["-O3", "-march=native", "-shared", "-fPIC", "-std=c99", "-ffp-contract=off", "-fno-math-errno"]


def disabled() -> bool:
    return any(os.environ.get(v, "").strip() not in ("", "0") for v in (NO_NATIVE_ENV, NO_JIT_ENV))


def cache_dir() -> Path:
    """Where built libraries are kept: $QUICKJAB_CACHE_DIR, else $XDG_CACHE_HOME/quickjab or
    ~/.cache/quickjab."""
    if os.environ.get(CACHE_ENV):
        return Path(os.environ[CACHE_ENV])
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "quickjab"


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


def library_path(stem: str, source: str) -> Path:
    """The library's file name names the source, the flags and the machine (architecture and
    CPU features), so a changed kernel or another CPU never loads a stale build."""
    parts = [source, *FLAGS, platform.machine(), sys.platform, _cpu_features()]
    key = hashlib.sha256("\0".join(parts).encode()).hexdigest()[:16]
    return cache_dir() / f"{stem}-{key}.so"


def _build(target: Path, source: str) -> bool:
    """Compile `source` into `target` (atomically: a half-written library never loads)."""
    import shutil  # only for the build, once per machine: not on every start
    import subprocess
    import tempfile

    cc = os.environ.get("CC") or shutil.which("cc") or shutil.which("gcc") or shutil.which("clang")
    if not cc:
        return False
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryDirectory(dir=target.parent) as tmp:
            src, out = Path(tmp) / "kernel.c", Path(tmp) / target.name
            src.write_text(source)
            r = subprocess.run([cc, *FLAGS, "-o", str(out), str(src), "-lm"], capture_output=True, timeout=60)
            if r.returncode != 0 or not out.exists():
                return False
            os.replace(out, target)
        return True
    except (OSError, subprocess.SubprocessError):
        return False


def load_library(stem: str, source: str) -> ctypes.CDLL | None:
    """The compiled `source` (built now if this machine has never built it), or None."""
    if disabled() or os.name != "posix":
        return None
    path = library_path(stem, source)
    if not path.exists() and not _build(path, source):
        return None
    try:
        return ctypes.CDLL(str(path))
    except OSError:
        return None
