"""Trials on disk (docs/formats.md): `<root>/<action>/<anything>.csv`, each resampled to 60 Hz frames."""

from __future__ import annotations

import fnmatch
from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np

from engine.errors import InputError
from engine.frames import recording_frames
from engine.recognition import Templates
from engine.recording import read_recording, say_notes

# The grid phase every recording is read at (`quickjab evaluate --phases`: each set at several
# phases, pooled); 0 everywhere else. Set only through `grid_phase`.
_grid_phase = 0.0


@contextmanager
def grid_phase(phase: float) -> Iterator[None]:
    """Recordings read in this block are put on the grid (k + phase) / 60 (engine.frames.recording_frames)."""
    global _grid_phase
    before, _grid_phase = _grid_phase, float(phase)
    try:
        yield
    finally:
        _grid_phase = before


def read_labelled_frames(path: str | Path, prog: str = "evaluate") -> tuple[np.ndarray, list[str]]:
    """A recording's (m, D) frames on the 60 Hz grid (at the `grid_phase`) and a label per frame.
    What the reader left out (a trial recorded with `quickjab record` and cut by a power cut) is
    said as `quickjab <prog>: ...`: `evaluate` reads most trials, `templates build` passes its own."""
    rec = read_recording(path)
    say_notes(rec.notes, prog)
    _, frames, labels = recording_frames(rec, phase=_grid_phase)
    return frames, labels


def read_frames(path: str | Path, prog: str = "evaluate") -> np.ndarray:
    """A recording's (m, D) frames on the 60 Hz grid (at the `grid_phase`)."""
    return read_labelled_frames(path, prog)[0]


def trial_paths(root: str | Path, pattern: str = "*.csv") -> dict[str, list[Path]]:
    """{action: [file, ...]}: the files matching `pattern` (a glob on the file name) in each
    action folder, sorted by name; {} when `root` is not a directory."""
    root = Path(root)
    if not root.is_dir():
        return {}
    out: dict[str, list[Path]] = {}
    for folder in sorted(p for p in root.iterdir() if p.is_dir()):
        files = sorted(f for f in folder.iterdir() if f.suffix == ".csv" and fnmatch.fnmatch(f.name, pattern))
        if files:
            out[folder.name] = files
    return out


def load_trials_dir(root: str | Path, pattern: str = "*.csv", prog: str = "evaluate") -> dict[str, list[np.ndarray]]:
    """{action: [frames, ...]} for the files of `trial_paths`, a note said as `quickjab <prog>: `
    (read_labelled_frames). Raises InputError when nothing is there."""
    root = Path(root)
    if not root.is_dir():
        raise InputError(f"{root}: not a directory of trials (<root>/<action>/*.csv)")
    out = {action: [read_frames(f, prog) for f in files] for action, files in trial_paths(root, pattern).items()}
    if not out:
        raise InputError(f"{root}: no trials matching {pattern!r} under <root>/<action>/")
    dims = {t.shape[1] for ts in out.values() for t in ts}
    if len(dims) != 1:
        raise InputError(f"{root}: trials mix one- and two-hand recordings (D = {sorted(dims)})")
    return out


def templates_from_trials(trials: Mapping[str, Sequence[np.ndarray]], where: str | Path, **kwargs: Any) -> Templates:
    """`Templates.from_trials` for a command: the ValueError it raises over the trials themselves
    (none given, a trial under 2 frames, trials of different D) becomes an InputError naming
    `where` they came from (a file, a folder), one line and exit code 2."""
    try:
        return Templates.from_trials(trials, **kwargs)
    except ValueError as exc:
        raise InputError(f"{where}: cannot build templates: {exc}") from None


def trials_dim(trials: Mapping[str, Sequence[np.ndarray]]) -> int:
    """The values per frame of `load_trials_dir`'s trials (one D for all: it checks that)."""
    return next(t.shape[1] for ts in trials.values() for t in ts)


def labelled_trials(paths: Sequence[str | Path], lead: int = 10, first: int | None = None,
                    prog: str = "templates") -> dict[str, list[np.ndarray]]:
    """{action: [frames, ...]} cut from labelled recordings (a `label` per row, docs/formats.md):
    every labelled run with `lead` frames before it, on the 60 Hz grid of the whole recording, as
    `quickjab evaluate` cuts its training punches (evaluate_recognition.stream_trials); `first`:
    only each action's first so many, in file order. InputError when no row is labelled."""
    from tools.evaluate_recognition import intervals, stream_trials

    out: dict[str, list[np.ndarray]] = {}
    for path in paths:
        frames, labels = read_labelled_frames(path, prog)
        for action, cut in stream_trials(frames, intervals(labels), lead).items():
            out.setdefault(action, []).extend(cut)
    if not out:
        raise InputError(f"{', '.join(map(str, paths))}: no labelled rows to cut trials from (a `label` column, docs/formats.md)")
    if first is not None:
        out = {action: cuts[:first] for action, cuts in out.items()}
    dims = {t.shape[1] for ts in out.values() for t in ts}
    if len(dims) != 1:
        raise InputError(f"{', '.join(map(str, paths))}: recordings mix one- and two-hand sensors (D = {sorted(dims)})")
    return out
