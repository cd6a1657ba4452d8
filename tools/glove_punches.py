"""The two-glove "punchbuddy" recordings: labelled from the signal, evaluated across sessions and
across people (`quickjab evaluate --punchbuddy DIR`, docs/recognition.md).

Each file `right-<kind>-<count>-<person>-combo-l<k>-<n>.csv` is one session of one person
throwing alternating left and right punches of one kind per hand, two glove IMUs recorded
together (right glove = sensor 0, left = sensor 1), without per-punch labels. A punch is a burst
of one glove's acceleration (`glove_bursts`); its true onset is measured on that glove alone
(`glove_intervals`: the other glove may be moving at the time).
"""

from __future__ import annotations

import re
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from engine.errors import InputError
from engine.recognition import DualBufferRecognizer
from tools.evaluate_recognition import (
    CLIP_FRAMES,
    Clips,
    Summary,
    replay_stream,
    score_stream,
    stream_rest,
    stream_trials,
)
from tools.trial_files import read_frames, templates_from_trials

GLOVE_PEAK_G = 3.0  # a punch: the glove's |a| at least this far (g) from 1 g ...
GLOVE_END_G = 1.0  # ... widened to the frames around it at least this far
GLOVE_GAP = 15  # frames: peaks at most this far apart are one punch
ONSET_SEARCH = 30  # frames after a burst's first frame in which its onset may lie
LEAD = 10  # frames of lead before a training punch (as `stream_trials` cuts them)
RIGHT_SENSOR, LEFT_SENSOR = 0, 1
RIGHT_KINDS = {"hook": "hook", "cross": "straight", "jab": "straight", "uppercut": "uppercut"}
LEFT_CODES = {"h": "hook", "j": "straight", "c": "straight", "u": "uppercut"}
GLOVE_NAME = re.compile(r"right-(?P<kind>hook|cross|jab|uppercut)-(?P<count>\d+)-(?P<person>[^-]+)"
                        r"-combo-l(?P<left>[hjcu])-(?P<session>\d+)\.csv")

Interval = tuple[str, int, int]
GloveFile = tuple[Path, str, str]  # (file, left action, right action)


def glove_bursts(frames: np.ndarray, sensor: int) -> list[tuple[int, int]]:
    """(first, end exclusive) of every burst of one sensor: its frames more than GLOVE_PEAK_G from
    1 g, grouped while at most GLOVE_GAP frames apart, each group widened both ways over the
    frames at least GLOVE_END_G from 1 g."""
    dev = np.abs(np.linalg.norm(np.asarray(frames, dtype=np.float64)[:, 3 * sensor : 3 * sensor + 3], axis=1) - 1.0)
    groups: list[list[int]] = []
    for i in np.flatnonzero(dev > GLOVE_PEAK_G):
        if groups and i - groups[-1][1] <= GLOVE_GAP:
            groups[-1][1] = int(i)
        else:
            groups.append([int(i), int(i)])
    out: list[tuple[int, int]] = []
    for a, b in groups:
        while a > 0 and dev[a - 1] >= GLOVE_END_G:
            a -= 1
        while b + 1 < len(dev) and dev[b + 1] >= GLOVE_END_G:
            b += 1
        if out and a < out[-1][1]:  # widened into the previous burst: one punch
            out[-1] = (out[-1][0], b + 1)
        else:
            out.append((a, b + 1))
    return out


def glove_intervals(frames: np.ndarray, left_action: str, right_action: str) -> tuple[list[Interval], list[int], list[int | None]]:
    """Every burst of both gloves as (action, first, end), sorted by first frame (left before right
    on a tie), each one's true onset and the frame after its rest: `stream_rest` on its own
    glove's readings, the rest searched after the same glove's previous burst."""
    x = np.asarray(frames, dtype=np.float64)
    ivs: list[Interval] = []
    onsets: list[int] = []
    rest_ends: list[int | None] = []
    for sensor, action in ((LEFT_SENSOR, left_action), (RIGHT_SENSOR, right_action)):
        own = x[:, 3 * sensor : 3 * sensor + 3]
        prev_end = 0
        for a, b in glove_bursts(x, sensor):
            ivs.append((action, a, b))
            rest_end, onset = stream_rest(own, a, a + ONSET_SEARCH, prev_end)
            onsets.append(onset)
            rest_ends.append(rest_end)
            prev_end = b
    order = sorted(range(len(ivs)), key=lambda i: ivs[i][1])  # stable: left first on a tie
    return [ivs[i] for i in order], [onsets[i] for i in order], [rest_ends[i] for i in order]


def glove_files(root: str | Path) -> dict[str, list[GloveFile]]:
    """{person: [(file, left action, right action), ...]} of the files in `root` named
    `right-<kind>-<count>-<person>-combo-l<k>-<n>.csv`, in name order; other files are skipped."""
    out: dict[str, list[GloveFile]] = {}
    for f in sorted(Path(root).glob("*.csv"), key=lambda p: p.name):
        m = GLOVE_NAME.fullmatch(f.name)
        if m:
            left, right = LEFT_CODES[m["left"]] + "_l", RIGHT_KINDS[m["kind"]] + "_r"
            out.setdefault(m["person"], []).append((f, left, right))
    return out


class _Loaded:
    """Each file's 60 Hz frames, intervals and onsets, read once."""

    def __init__(self) -> None:
        self._cache: dict[Path, tuple[np.ndarray, list[Interval], list[int], list[int | None]]] = {}

    def __call__(self, f: GloveFile) -> tuple[np.ndarray, list[Interval], list[int], list[int | None]]:
        path, left, right = f
        if path not in self._cache:
            frames = read_frames(path)
            if frames.shape[1] != 6:
                raise InputError(f"{path}: {frames.shape[1] // 3} sensor(s); a two-glove recording has 2 (right, left)")
            self._cache[path] = (frames, *glove_intervals(frames, left, right))
        return self._cache[path]


def _training_trials(train: Sequence[GloveFile], load: _Loaded, trials: int) -> tuple[dict[str, list[np.ndarray]], list[Path]]:
    """Each action's first `trials` intervals (with LEAD frames before them, as `stream_trials`
    cuts them) from the first training file, in name order, that has intervals of the action;
    and the files they were cut from."""
    cut: dict[str, list[np.ndarray]] = {}
    used: list[Path] = []
    for f in train:
        frames, ivs, *_ = load(f)
        for action in f[1:]:
            mine = [iv for iv in ivs if iv[0] == action][:trials]
            if action not in cut and mine:
                cut[action] = stream_trials(frames, mine, LEAD)[action]
                if f[0] not in used:
                    used.append(f[0])
    return cut, used


def _test(train: Sequence[GloveFile], tests: Sequence[GloveFile], load: _Loaded, pooled: Sequence[Summary],
          trials: int, template_kwargs: Mapping | None, clip_frames: int | Clips, rec_kwargs: Mapping) -> int:
    """Templates from `train`, then each test file whose actions they all have replayed whole
    through a fresh recognizer per main size (`pooled`: one Summary per main), scored from each
    punch's own onset. Returns how many files were tested."""
    cut, used = _training_trials(train, load, trials)
    tested = [f for f in tests if set(f[1:]) <= cut.keys() and load(f)[1]]  # its actions, and punches
    if not tested:
        return 0
    templates = templates_from_trials(cut, ", ".join(map(str, used)), **(template_kwargs or {}))
    for f in tested:
        frames, ivs, onsets, rest_ends = load(f)
        for pool in pooled:
            rec = DualBufferRecognizer(templates, main=pool.main, **rec_kwargs)
            events = replay_stream(rec, frames, clip_frames)
            s = score_stream(events, ivs, len(frames), pool.main, frames=frames, onsets=onsets, rest_ends=rest_ends)
            pool.add(s)
    return len(tested)


def evaluate_gloves(
    root: str | Path,
    mains: Sequence[int | str],
    trials: int = 3,
    template_kwargs: Mapping | None = None,
    clip_frames: int | Clips = CLIP_FRAMES,
    **rec_kwargs,
) -> dict[str, list[Summary]]:
    """Rows "punchbuddy <person> across sessions" (templates from each of the person's files
    alone, tested on the person's other files; pooled) and "punchbuddy <A> -> <B>" (templates
    from A's files, each action from the first file having it, tested on all of B's files).
    A test file is used only when the templates have all its actions; a row with no test file
    is left out. `template_kwargs` go to `Templates.from_trials`, the rest to the recognizer."""
    files = glove_files(root)
    load = _Loaded()
    out: dict[str, list[Summary]] = {}

    def row(name: str, plan: Sequence[tuple[Sequence[GloveFile], Sequence[GloveFile]]]) -> None:
        pooled = [Summary(m) for m in mains]
        tested = sum(_test(train, tests, load, pooled, trials, template_kwargs, clip_frames, rec_kwargs) for train, tests in plan)
        if tested:
            out[name] = pooled

    for person, mine in files.items():
        row(f"punchbuddy {person} across sessions", [([f], [g for g in mine if g is not f]) for f in mine])
    for a, train in files.items():
        for b, tests in files.items():
            if a != b:
                row(f"punchbuddy {a} -> {b}", [(train, tests)])
    return out
