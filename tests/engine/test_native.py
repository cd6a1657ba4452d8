"""engine/native.py when things go wrong: a corrupt or foreign cached library, one without the
expected symbol, a compiler that fails or rejects -march=native, an unwritable cache. Each
ends in the kernel or in numpy, never a traceback, and a failure is not retried on every start."""

from __future__ import annotations

import ctypes
import os
import stat
import tempfile
import time
from pathlib import Path

import pytest

from engine import native

SRC = "double twice(double x) { return 2.0 * x; }\n"
OTHER = "double thrice(double x) { return 3.0 * x; }\n"
needs_cc = pytest.mark.skipif(os.name != "posix" or native.compiler() is None, reason="no C compiler here")


def twice(lib: ctypes.CDLL) -> float:
    lib.twice.restype, lib.twice.argtypes = ctypes.c_double, [ctypes.c_double]
    return lib.twice(2.5)


def script(path: Path, body: str) -> str:
    """An executable shell script standing in for the C compiler."""
    path.write_text("#!/bin/sh\n" + body)
    path.chmod(0o755)
    return str(path)


@pytest.fixture
def cache(tmp_path, monkeypatch) -> Path:
    """A fresh cache dir, a private temp dir (the fallback), the real compiler."""
    for name in (native.NO_NATIVE_ENV, native.NO_JIT_ENV, "CC"):
        monkeypatch.delenv(name, raising=False)
    monkeypatch.setenv(native.CACHE_ENV, str(tmp_path / "cache"))
    (tmp_path / "tmp").mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path / "tmp"))
    return tmp_path / "cache"


@needs_cc
def test_built_once_then_loaded_without_the_compiler(cache, tmp_path, monkeypatch):
    assert twice(native.load_library("k", SRC, ("twice",))) == 5.0
    assert native.status()["k"].startswith("native: built")
    calls = tmp_path / "calls"
    monkeypatch.setenv("CC", script(tmp_path / "cc", f"echo x >> {calls}\nexit 1\n"))
    assert twice(native.load_library("k", SRC, ("twice",))) == 5.0
    assert native.status()["k"] == f"native: {native.library_path('k', SRC)}"
    assert not calls.exists()


# A library this process has opened is never rewritten in place here: the dynamic loader keeps
# it mapped (and hands the same handle back for the same path).
@needs_cc
def test_a_corrupt_library_is_deleted_and_built_again(cache):
    path = native.library_path("k", SRC)
    cache.mkdir()
    path.write_bytes(b"not an ELF file at all")
    assert twice(native.load_library("k", SRC, ("twice",))) == 5.0
    assert native.status()["k"].startswith("native: built")


@needs_cc
def test_a_library_without_the_symbol_is_rebuilt(cache):
    native.load_library("other", OTHER, ("thrice",))
    native.library_path("k", SRC).write_bytes(native.library_path("other", OTHER).read_bytes())
    assert twice(native.load_library("k", SRC, ("twice",))) == 5.0
    assert native.status()["k"].startswith("native: built")


@needs_cc
def test_a_library_without_the_symbol_and_no_compiler_is_numpy(cache, monkeypatch):
    native.load_library("other", OTHER, ("thrice",))
    path = native.library_path("k", SRC)
    path.write_bytes(native.library_path("other", OTHER).read_bytes())
    monkeypatch.setenv("CC", "/bin/false")
    assert native.load_library("k", SRC, ("twice",)) is None  # no traceback: numpy
    assert not path.exists()
    assert native.status()["k"].startswith("numpy: /bin/false exit 1")


def test_a_failed_build_is_remembered_per_compiler(cache, tmp_path, monkeypatch):
    calls = tmp_path / "calls"
    monkeypatch.setenv("CC", script(tmp_path / "cc", f"echo x >> {calls}\necho 'kernel.c:1: error: no' >&2\nexit 3\n"))
    assert native.load_library("k", SRC, ("twice",)) is None
    tried = len(calls.read_text().splitlines())
    assert tried == 2  # with -march=native, then once without
    assert native.status()["k"] == f"numpy: {tmp_path / 'cc'} exit 3: kernel.c:1: error: no"
    for _ in range(3):
        assert native.load_library("k", SRC, ("twice",)) is None
    assert len(calls.read_text().splitlines()) == tried  # not retried on every start
    assert "remembered" in native.status()["k"] and "exit 3" in native.status()["k"]
    # another compiler is tried afresh
    monkeypatch.setenv("CC", script(tmp_path / "cc2", f"echo y >> {calls}\nexit 1\n"))
    native.load_library("k", SRC, ("twice",))
    assert calls.read_text().count("y") == 2


@needs_cc
def test_a_rejected_march_native_is_retried_without_it(cache, tmp_path, monkeypatch):
    cc = native.compiler()
    monkeypatch.setenv("CC", script(tmp_path / "cc", 'case "$*" in *-march=native*) '
                                    "echo \"error: unrecognized command-line option '-march=native'\" >&2; exit 1;; esac\n"
                                    f'exec {cc} "$@"\n'))
    assert twice(native.load_library("k", SRC, ("twice",))) == 5.0
    assert native.library_path("k", SRC, native.PORTABLE_FLAGS).exists()
    assert not native.library_path("k", SRC).exists()
    monkeypatch.setenv("CC", "/bin/false")  # and the next start loads it without building
    assert twice(native.load_library("k", SRC, ("twice",))) == 5.0


@needs_cc
def test_an_unwritable_cache_falls_back_to_a_private_temp_dir_then_numpy(cache, tmp_path, monkeypatch):
    (tmp_path / "file").write_text("")
    monkeypatch.setenv(native.CACHE_ENV, str(tmp_path / "file" / "cache"))  # unwritable, even for root
    assert twice(native.load_library("k", SRC, ("twice",))) == 5.0
    assert native.fallback_dir() == tmp_path / "tmp" / f"quickjab-{os.getuid()}"
    assert native.library_path("k", SRC, directory=native.fallback_dir()).exists()
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path / "file"))  # neither can be written
    assert native.load_library("k2", SRC, ("twice",)) is None
    assert native.status()["k2"].startswith("numpy: no writable cache directory")


@needs_cc
def test_a_cache_path_too_long_to_probe_falls_back_as_an_unwritable_one_does(cache, tmp_path, monkeypatch):
    """A name too long for the file system: Path.exists() raised ENAMETOOLONG, and `recognize`
    and `play` ended with the errno, where an unwritable cache is passed over."""
    monkeypatch.setenv(native.CACHE_ENV, str(tmp_path / ("x" * 300)))
    assert twice(native.load_library("k", SRC, ("twice",))) == 5.0
    assert native.library_path("k", SRC, directory=native.fallback_dir()).exists()
    assert twice(native.load_library("k", SRC, ("twice",))) == 5.0  # found there at the next start


@needs_cc
def test_a_temp_dir_others_can_write_is_never_used(cache, tmp_path, monkeypatch):
    (tmp_path / "file").write_text("")
    monkeypatch.setenv(native.CACHE_ENV, str(tmp_path / "file" / "cache"))
    fb = native.fallback_dir()
    fb.mkdir()
    fb.chmod(0o777)  # someone could have planted a library there
    assert native.load_library("k", SRC, ("twice",)) is None
    assert stat.S_IMODE(fb.stat().st_mode) == 0o777 and not any(fb.iterdir())


@needs_cc
def test_a_build_prunes_older_builds_and_stale_temp_dirs(cache):
    cache.mkdir()
    old_build, other_stem = cache / "k-0123456789abcdef.so", cache / "kk-0123456789abcdef.so"
    old_build.write_bytes(b"old")
    other_stem.write_bytes(b"other kernel")
    stale, fresh = cache / "tmpstale", cache / "tmpfresh"
    for d in (stale, fresh):
        d.mkdir()
        (d / "kernel.c").write_text("")
    past = time.time() - 2 * native.STALE_TMP_SECONDS
    os.utime(stale, (past, past))
    native.load_library("k", SRC, ("twice",))
    assert not old_build.exists() and not stale.exists()
    assert other_stem.exists() and fresh.exists() and native.library_path("k", SRC).exists()


@needs_cc
def test_a_build_leaves_the_other_temp_dirs_of_a_shared_cache_dir(cache):
    """QUICKJAB_CACHE_DIR=~/.cache (or /tmp): a build deleted every directory there whose name
    starts with "tmp" and is over 5 minutes old, another program's and all it held. Only its
    own leftovers go: its named build dirs, and the old unnamed ones holding nothing but a
    kernel source and libraries."""
    cache.mkdir()
    theirs, ours, named = cache / "tmpimportant", cache / "tmpold", cache / f"{native.BUILD_PREFIX}k-x"
    for d in (theirs, ours, named):
        d.mkdir()
        (d / "kernel.c").write_text("")
    (theirs / "precious.txt").write_text("not ours")
    (ours / "k-0123456789abcdef.so").write_bytes(b"")
    past = time.time() - 2 * native.STALE_TMP_SECONDS
    for d in (theirs, ours, named):
        os.utime(d, (past, past))
    native.load_library("k", SRC, ("twice",))
    assert (theirs / "precious.txt").read_text() == "not ours"
    assert not ours.exists() and not named.exists()


def test_disabled_says_so(cache, monkeypatch):
    monkeypatch.setenv(native.NO_NATIVE_ENV, "1")
    assert native.load_library("k", SRC, ("twice",)) is None
    assert "QUICKJAB_NO_NATIVE" in native.status()["k"]


def test_a_build_that_failed_for_a_full_disk_is_tried_again_at_the_next_start(cache, tmp_path, monkeypatch):
    # the linker's "No space left on device" was remembered as the compiler's failure: the kernel
    # stayed on numpy (or on the portable flags) after the disk had room again
    calls = tmp_path / "calls"
    monkeypatch.setenv("CC", script(tmp_path / "cc", f"echo x >> {calls}\n"
                                    "echo '/usr/bin/ld: final link failed: No space left on device' >&2\n"
                                    "echo 'collect2: error: ld returned 1 exit status' >&2\nexit 1\n"))
    assert native.load_library("k", SRC, ("twice",)) is None
    assert native.status()["k"] == f"numpy: {tmp_path / 'cc'} exit 1: No space left on device"
    assert not list((tmp_path / "cache").glob("*.failed"))
    native.load_library("k", SRC, ("twice",))
    assert len(calls.read_text().splitlines()) == 4  # both flag sets, at both starts


def test_an_oserror_around_the_compiler_is_not_remembered_nor_an_empty_marker_left(cache, tmp_path, monkeypatch):
    # a full disk: the kernel's source cannot be written (the compiler never runs), and a marker
    # file is created but its reason cannot be written into it
    calls = tmp_path / "calls"
    monkeypatch.setenv("CC", script(tmp_path / "cc", f"echo x >> {calls}\nexit 3\n"))
    real_write = Path.write_text

    def full(self, text, *args, **kwargs):
        if self.name == "kernel.c" and os.environ.get("FULL_SRC"):
            raise OSError(28, "No space left on device")
        if self.suffix == ".failed":
            self.touch()  # created, then the write fails
            raise OSError(28, "No space left on device")
        return real_write(self, text, *args, **kwargs)

    monkeypatch.setattr(Path, "write_text", full)
    monkeypatch.setenv("FULL_SRC", "1")
    assert native.load_library("k", SRC, ("twice",)) is None
    assert "No space left on device" in native.status()["k"] and not calls.exists()
    monkeypatch.delenv("FULL_SRC")
    assert native.load_library("k", SRC, ("twice",)) is None  # the compiler's own failure now
    assert len(calls.read_text().splitlines()) == 2 and native.status()["k"].endswith("exit 3")
    assert not list((tmp_path / "cache").glob("*.failed"))  # its marker could not be written: none left
    native.load_library("k", SRC, ("twice",))
    assert len(calls.read_text().splitlines()) == 4


def test_an_empty_failure_marker_still_says_the_build_failed(cache, tmp_path, monkeypatch):
    cc = script(tmp_path / "cc", "exit 3\n")
    monkeypatch.setenv("CC", cc)
    d = tmp_path / "cache"
    d.mkdir(parents=True, exist_ok=True)
    for flags in (native.FLAGS, native.PORTABLE_FLAGS):
        native.failure_marker("k", SRC, flags, cc, d).write_text("")  # an older version's, on a full disk
    assert native.load_library("k", SRC, ("twice",)) is None
    assert native.status()["k"].startswith("numpy: the build failed (an earlier start's build, remembered")
