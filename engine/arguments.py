"""Argparse types with ranges, for every command's numeric arguments.

A value out of range is refused by argparse itself (usage line, one error line naming the
argument, exit 2) before any work starts, instead of ending in a traceback, a hang or a
multi-gigabyte allocation later. Numbers are always finite: `nan` and `inf` never pass.
"""

from __future__ import annotations

import argparse
import contextlib
import math
import os
from collections.abc import Callable
from pathlib import Path
from typing import NoReturn

SEED_MAX = 2**63 - 1  # numpy's generators take any non-negative int; this keeps it a C long
SIZE_MIN = (160, 120)
SIZE_MAX = (7680, 4320)  # 8K: a 20000x20000 window asked for 7.3 GB of surfaces


def _number(v: float) -> str:
    return str(v) if isinstance(v, int) else f"{v:g}"  # an int bound exactly (a seed's 2**63 - 1)


def _describe(lo: float | None, hi: float | None) -> str:
    if lo is not None and hi is not None:
        return f"between {_number(lo)} and {_number(hi)}"
    if lo is not None:
        return f">= {_number(lo)}"
    return f"<= {_number(hi)}"


def int_range(lo: int | None = None, hi: int | None = None) -> Callable[[str], int]:
    """An argparse type: an integer in [lo, hi] (either end may be open)."""

    def parse(text: str) -> int:
        try:
            v = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected an integer, not {text!r}") from None
        if (lo is not None and v < lo) or (hi is not None and v > hi):
            raise argparse.ArgumentTypeError(f"{v} is out of range: must be {_describe(lo, hi)}")
        return v

    parse.__name__ = "integer"  # argparse names the type in its messages
    return parse


def float_range(lo: float | None = None, hi: float | None = None, *, lo_open: bool = False) -> Callable[[str], float]:
    """An argparse type: a finite number in [lo, hi], or (lo, hi] with lo_open."""

    def parse(text: str) -> float:
        try:
            v = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected a number, not {text!r}") from None
        if not math.isfinite(v):
            raise argparse.ArgumentTypeError(f"expected a finite number, not {text!r}")
        if (lo is not None and (v <= lo if lo_open else v < lo)) or (hi is not None and v > hi):
            what = (f"> {lo:g}" + (f" and <= {hi:g}" if hi is not None else "")) if lo_open else _describe(lo, hi)
            raise argparse.ArgumentTypeError(f"{v:g} is out of range: must be {what}")
        return v

    parse.__name__ = "number"
    return parse


seed = int_range(0, SEED_MAX)
positive_int = int_range(1)
non_negative_int = int_range(0)
positive_float = float_range(0.0, lo_open=True)
non_negative_float = float_range(0.0)


def window_size(text: str) -> str:
    """An argparse type for `--size WxH`: checks the form and the range, keeps the text (the
    commands parse it themselves)."""
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected WIDTHxHEIGHT, e.g. 1280x720, not {text!r}") from None
    if w < SIZE_MIN[0] or h < SIZE_MIN[1] or w > SIZE_MAX[0] or h > SIZE_MAX[1]:
        raise argparse.ArgumentTypeError(
            f"{w}x{h} is out of range: from {SIZE_MIN[0]}x{SIZE_MIN[1]} to {SIZE_MAX[0]}x{SIZE_MAX[1]}")
    return text


window_size.__name__ = "size"


def path_argument(text: str) -> str:
    """An argparse type for any path a command reads or writes: an empty one is refused, for
    Path("") is "." (the current folder): `recognize ""` said the folder was no recording,
    `templates build ""` read it as trials and `graph info ""` showed the shipped graph."""
    if not text:
        raise argparse.ArgumentTypeError("the path is empty")
    return text


path_argument.__name__ = "path"


def backslash_note(text: str) -> str:
    """One line for a path with a backslash where it separates no folders (not Windows), as
    `C:\\Users\\me\\t.npz` typed on Linux: a character of a name there, so one file of that
    name is written (in the current folder, here); "" for any other path."""
    if "\\" not in text or "\\" in (os.sep, os.altsep):
        return ""
    path = Path(text)
    return f"{text}: a backslash is not a folder separator on this system: this names one file, {path.name}, in {path.absolute().parent}"


def output_file(text: str) -> str:
    """An argparse type for a file a command writes at its end (a screenshot, a trace, a plot):
    a place it cannot be written is said before the work, not in a traceback after. Folders
    not made yet are fine: the command makes them when it writes (as `synth -o new/s.csv` and
    every other output do), so what is checked is the nearest folder that is there."""
    path_argument(text)
    if Path(text).is_dir():
        raise argparse.ArgumentTypeError(f"{text} is a directory, not a file name")
    folder = existing_folder(text)
    if not folder.is_dir():
        raise argparse.ArgumentTypeError(f"{text}: {folder} is not a directory")
    if not os.access(folder, os.W_OK):
        raise argparse.ArgumentTypeError(f"{text}: cannot write in {folder}")
    if folder == Path(text).parent:
        if not os.path.lexists(text):
            _try_creating(text)
    else:  # folders to be made: the first of them
        _try_making(text, next(p for p in Path(text).parents if p.parent == folder))
    return text


def _try_creating(text: str) -> None:
    """Create the file `text` (which is not there) and remove it at once: os.access passes for
    root where nothing can be made (/proc, /sys, a read-only mount), so a match was played whole
    before its trace was refused. O_EXCL: a file that appeared meanwhile is never touched, and
    one put in the probe's place before it is removed (another writer's rename) is not removed."""
    try:
        fd = os.open(text, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
    except FileExistsError:
        return
    except OSError as exc:
        raise argparse.ArgumentTypeError(f"{text}: cannot write there ({exc.strerror})") from None
    try:
        probe = os.fstat(fd)
        with contextlib.suppress(OSError):  # a folder that lets one create but not remove: left, harmless
            if os.path.samestat(probe, os.lstat(text)):
                os.unlink(text)
    finally:
        os.close(fd)


def _try_making(text: str, first_missing: Path) -> None:
    """As _try_creating, for an output whose folders are not made yet: make the first of them
    and remove it at once (`--trace /proc/new/t.json` was refused only after the match)."""
    try:
        os.mkdir(first_missing)
    except FileExistsError:
        return
    except OSError as exc:
        raise argparse.ArgumentTypeError(f"{text}: cannot make {first_missing} ({exc.strerror})") from None
    with contextlib.suppress(OSError):  # emptied again: only a folder that filled meanwhile stays
        os.rmdir(first_missing)


def output_of_kind(kind: str, is_kind: Callable[[bytes], bool]) -> Callable[[str], str]:
    """output_file for a file a command makes again and again (a screenshot, a trace): an
    earlier file of its kind is replaced, but a file plainly of another kind at the path (a
    recording, an action) is refused before the work (engine.errors.refuse_other_kind)."""
    from engine.errors import InputError, refuse_other_kind

    def parse(text: str) -> str:
        output_file(text)
        try:
            refuse_other_kind(text, "", kind, is_kind)
        except InputError as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None
        return text

    return parse


def image_file(text: str) -> str:
    """A screenshot or contact sheet to write: output_of_kind, an image."""
    from engine.file_kinds import is_image_head

    return output_of_kind("an image", is_image_head)(text)


def trace_file(text: str) -> str:
    """A Chrome trace to write: output_of_kind, a trace."""
    from engine.file_kinds import is_trace_head

    return output_of_kind("a Chrome trace", is_trace_head)(text)


image_file.__name__ = trace_file.__name__ = "file"


def existing_folder(path: str | os.PathLike) -> Path:
    """The nearest of `path`'s parents that exists (it may be a file: then nothing can be made
    under it): the folder in which a missing output folder would be made."""
    folder = Path(path).parent
    while not os.path.lexists(folder) and folder != folder.parent:
        folder = folder.parent
    return folder


output_file.__name__ = "file"


def plot_file(text: str) -> str:
    """output_of_kind (an image or a document), in a format matplotlib writes (it goes by the
    suffix). Returns the path matplotlib writes: with no suffix it adds `.png` (`--plot p/noext`
    wrote p/noext.png while the command named p/noext, and the checks were of p/noext). Imports
    matplotlib, so only commands given a plot pay for it."""
    from engine.file_kinds import HEADLESS_PLOT_FORMATS, is_pixels_head, is_plot_head

    path_argument(text)
    suffix = os.path.splitext(text)[1][1:].lower()  # as matplotlib's savefig reads it
    written = text if suffix else text.rstrip(".") + ".png"  # savefig's default format
    if suffix in HEADLESS_PLOT_FORMATS:
        output_of_kind("raw pixels", is_pixels_head)(written)
    else:
        output_of_kind("an image or a plot", is_plot_head)(written)
    try:
        from matplotlib.backend_bases import FigureCanvasBase
    except ImportError:  # the command says "--plot needs matplotlib" itself
        return written
    formats = FigureCanvasBase.get_supported_filetypes()
    if suffix and suffix not in formats:
        raise argparse.ArgumentTypeError(f"{text}: matplotlib writes no .{suffix} (" + ", ".join(sorted(formats)) + ")")
    if suffix == "pgf":  # said now, not after an evaluation of minutes
        import shutil

        from matplotlib import rcParams

        if shutil.which(rcParams["pgf.texsystem"]) is None:
            raise argparse.ArgumentTypeError(f"{text}: a .pgf plot needs {rcParams['pgf.texsystem']} (LaTeX), not found")
    return written


plot_file.__name__ = "plot file"


class OneLineErrorParser(argparse.ArgumentParser):
    """A bad argument is one line on stderr and exit 2, like every other input error (issue 16);
    argparse's usage block is for `--help`. Subcommands' parsers are of this class too
    (add_subparsers makes its parsers of the parent's class). `quickjab` and `python -m game`
    both parse with it."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: {message} (see {self.prog} --help)\n")

    def _get_values(self, action, arg_strings):  # argparse's, called for every option given
        """As argparse's, but an option given the value `--` (`--size=--`, `-o--`) is refused:
        argparse takes `--` out of the values and hands on [] without calling `type=`, so
        `play --size=--` ended in a traceback and `play --trace=--` was silently ignored."""
        if action.option_strings and "--" in arg_strings:
            raise argparse.ArgumentError(action, "expected a value, got '--'")
        return super()._get_values(action, arg_strings)

    def parse_args(self, args=None, namespace=None):  # argparse's signature
        """As argparse's, but an unknown option is named by the (sub)command that was given it:
        `quickjab play: unrecognized arguments: --low-pwer (see quickjab play --help)`, whose
        --help lists the options, not `quickjab: ...` pointing at the list of commands."""
        parsed, extras = self.parse_known_args(args, namespace)
        if extras:
            self.chosen(parsed).error("unrecognized arguments: " + " ".join(extras))
        return parsed

    def chosen(self, parsed: argparse.Namespace) -> argparse.ArgumentParser:
        """The innermost subcommand's parser that `parsed` names (this parser without one)."""
        parser: argparse.ArgumentParser = self
        while True:
            subs = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
            name = getattr(parsed, subs[0].dest, None) if subs else None
            if name not in (subs[0].choices if subs else {}):
                return parser
            parser = subs[0].choices[name]
