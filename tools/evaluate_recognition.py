"""Offline evaluation of the recognizer (paper VI-D, Figs. 8-9).

Each test motion is replayed through a DualBufferRecognizer frame by frame and its decisions
are put in the paper's four outcome groups:
  1 correct                -- the first decision was right and never changed,
  2 unnoticeable switch    -- right in the end, the last switch within 6 frames of the start,
  3 noticeable switch      -- right in the end, switched later than that,
  4 wrong or missed        -- wrong in the end, rejected, or never started.
plus the first-decision accuracy and the lag of the first decision from the TRUE motion onset,
not the frame the gate opens: the first frame whose acceleration is ONSET_G (0.3 g) away from
the rest before the motion (any sensor, |a - rest| per sensor). The rest: a trial's first
REST_FRAMES frames (the player starts from the guard; the trial starts where the motion does);
in a stream, the stillest REST_WINDOW frames (least spread of the readings) between the
previous labelled interval's end and the interval's first labelled frame, at most REST_SEARCH
frames back: hand labels begin 10-15 frames after the hand has left the rest, so the frames just
before the label are mid-wind-up. The search runs from the trial's first frame or from the end
of the stream's rest window; a motion that never gets 0.3 g away falls back to its 10 %-of-peak
onset (trials) or its first labelled frame (streams).

Two kinds of input: isolated trials (rest padded before and after, as a player starts from
the guard) and labelled streams (every labelled interval is one motion; starts outside any
interval are false starts). In streams a simulated character plays each started action's clip,
`clip_frames` (CLIP_FRAMES, 24) from its start (a switch continues the clip at n_p), and then calls
`character_finished()`, as the game does; clip_frames=0: no character. With `Clips` (what
`quickjab evaluate` runs), an action the game has is played as the game's boxer plays it: its own
clip, from a switch's n_p on, finished on its last frame.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from engine.errors import InputError
from engine.recognition import DualBufferRecognizer, Templates
from engine.recognition.templates import activity, rest_gravity, window_spread
from tools.evaluation_settings import CLIP_FRAMES
from tools.trial_files import read_labelled_frames, templates_from_trials

UNNOTICEABLE_FRAMES = 6
PAD_BEFORE, PAD_AFTER = 20, 40
ONSET_G = 0.3  # the true onset: this far (g) from the rest before the motion
REST_FRAMES = 5  # a trial's rest: the mean of its first frames
REST_WINDOW = 8  # a stream interval's rest: the stillest window of this many frames ...
REST_SEARCH = 45  # ... between the previous interval's end and the label, at most this far back
EARLY_TOLERANCE = 20  # frames a stream start may precede its labelled interval (1/3 s)
GROUPS = ("correct", "unnoticeable switch", "noticeable switch", "wrong or missed")


@dataclass
class Outcome:
    truth: str
    first: str | None  # first decision
    final: str | None  # decision when the motion ended
    last_switch_np: int  # n_p of the last switch, -1 if none
    lag: int | None  # frames from the true onset to the first decision
    # of which: frames from the true onset to the recognizer's own (back-dated) onset of the motion
    # it decided; negative when the recognizer's onset came first. The rest of `lag` is the main
    # buffer filling from there (docs/recognition.md, "Where the lag goes").
    onset_lag: int | None = None
    # whether a still rest came before the punch (`stream_rest`), so that its true onset is the
    # definition's, 0.3 g from that rest; without one (a shadow boxer's punches in a row) the
    # onset is measured from frames that still move, or is the first labelled frame
    rested: bool = True

    @property
    def group(self) -> int:
        if self.final != self.truth:
            return 3
        if self.last_switch_np < 0 and self.first == self.truth:
            return 0
        return 1 if self.last_switch_np <= UNNOTICEABLE_FRAMES else 2


@dataclass
class Summary:
    main: int | str
    outcomes: list[Outcome] = field(default_factory=list)
    false_starts: int = 0
    idle_minutes: float = 0.0
    extra_starts: int = 0  # starts inside a labelled interval that already had its own

    def add(self, other: Summary) -> None:
        """Pool `other` (the same main buffer, other punches) into this one."""
        self.outcomes += other.outcomes
        self.false_starts += other.false_starts
        self.extra_starts += other.extra_starts
        self.idle_minutes += other.idle_minutes

    def counts(self) -> np.ndarray:
        c = np.zeros(4, dtype=int)
        for o in self.outcomes:
            c[o.group] += 1
        return c

    def row(self) -> dict:
        n = max(len(self.outcomes), 1)
        c = self.counts() / n
        lags = [o.lag for o in self.outcomes if o.lag is not None]
        split = [(o.onset_lag, o.lag - o.onset_lag) for o in self.outcomes if o.lag is not None and o.onset_lag is not None]
        rested = [o.lag for o in self.outcomes if o.lag is not None and o.rested]
        started = sum(o.first is not None for o in self.outcomes)
        out = {
            "main": self.main,
            "n": len(self.outcomes),
            **{g: round(float(v), 4) for g, v in zip(GROUPS, c, strict=True)},
            "acceptable": round(float(c[0] + c[1]), 4),
            "final_correct": round(float(c[0] + c[1] + c[2]), 4),
            "first_correct": round(sum(o.first == o.truth for o in self.outcomes) / n, 4),
            "started": round(started / n, 4),
            "type": round(sum(o.final == o.truth for o in self.outcomes) / max(started, 1), 4),
            "lag_ms": round(float(np.median(lags)) * 1000 / 60, 1) if lags else None,
            "lag_p90_ms": round(float(np.percentile(lags, 90)) * 1000 / 60, 1) if lags else None,
        }
        if len(rested) < len(lags):  # some punches had no rest to measure from: the lag of those that had
            out["lag_rested_n"] = len(rested)
            out["lag_rested_ms"] = round(float(np.median(rested)) * 1000 / 60, 1) if rested else None
            out["lag_rested_p90_ms"] = round(float(np.percentile(rested, 90)) * 1000 / 60, 1) if rested else None
        if split:  # medians of each part: they need not add up to lag_ms
            out["lag_to_onset_ms"] = round(float(np.median([a for a, _ in split])) * 1000 / 60, 1)
            out["lag_onset_to_decision_ms"] = round(float(np.median([b for _, b in split])) * 1000 / 60, 1)
        if self.idle_minutes > 0:
            out["false_starts"] = self.false_starts
            out["extra_starts"] = self.extra_starts
            out["false_starts_per_idle_min"] = round(self.false_starts / self.idle_minutes, 3)
        return out


def _away_from_rest(frames: np.ndarray, rest: np.ndarray, threshold_g: float = ONSET_G) -> np.ndarray:
    """Indices of the frames at least `threshold_g` away from `rest` on any sensor."""
    dev = np.linalg.norm((np.asarray(frames, dtype=np.float64) - rest).reshape(len(frames), -1, 3), axis=2)
    return np.flatnonzero(dev.max(axis=1) >= threshold_g)


def true_onset(trial: np.ndarray, fraction: float = 0.1) -> int:
    """A trial's true onset: the first frame ONSET_G away from the rest (the mean of its first
    REST_FRAMES frames); else the first frame whose activity reaches `fraction` of its peak; 0
    for a trial that never moves (every frame alike: no activity reaches that)."""
    away = _away_from_rest(trial, rest_gravity(trial, REST_FRAMES))
    if len(away):
        return int(away[0])
    act = activity(trial, rest_gravity(trial))
    moving = np.flatnonzero(act >= fraction * max(float(act.max()), 1e-12))
    return int(moving[0]) if len(moving) else 0


def stream_onset(frames: np.ndarray, first: int, end: int, prev_end: int = 0) -> int:
    """A labelled interval [first, end)'s true onset (`stream_rest`'s second figure)."""
    return stream_rest(frames, first, end, prev_end)[1]


def stream_rest(frames: np.ndarray, first: int, end: int, prev_end: int = 0) -> tuple[int | None, int]:
    """A labelled interval [first, end)'s rest and true onset: (the frame after the rest, or
    None when that window is no rest, the onset). The rest: the mean of the stillest
    REST_WINDOW frames (least summed spread of the sensors' readings about their mean) in
    [max(prev_end, first - REST_SEARCH), first), `prev_end` being the previous interval's end
    (hand labels start after the wind-up, so the frames just before `first` are already
    moving). The onset: the first frame after that window ONSET_G away from the rest, before
    `end`; `first` when none is. A decision before the rest's end was made while the hand still
    rested: it is not this punch's. A window with a frame ONSET_G from its own mean is still
    moving by the onset's own measure (a shadow boxer's punches follow each other without
    one: the stillest frames between two are the next one's wind-up): no rest end then."""
    x = np.asarray(frames, dtype=np.float64)
    lo = max(prev_end, first - REST_SEARCH, 0)
    w = min(REST_WINDOW, first - lo)
    if w < 2:  # no room between the intervals: the frames just before the label
        lo, w = max(0, first - REST_WINDOW), min(REST_WINDOW, first)
    if w < 1:
        return None, first
    k = lo + int(np.argmin(window_spread(x[lo:first], w)))
    rest = x[k : k + w].mean(axis=0)
    away = _away_from_rest(x[k + w : end], rest)
    still = not len(_away_from_rest(x[k : k + w], rest))
    return k + w if still else None, k + w + int(away[0]) if len(away) else first


def _decisions(events: Iterable[dict]) -> tuple[str | None, str | None, int, int | None]:
    """(first, final, n_p of the last switch, frame of the first decision) of ONE motion."""
    first = final = None
    last_np, at = -1, None
    for e in events:
        kind = e["event"]
        if kind == "start":
            if first is not None:
                break  # a second motion
            first = final = e["action"]
            at = e["frame"]
        elif kind == "switch" and first is not None:
            final = e["action"]
            last_np = e["from_frame"]
        elif kind == "end" and first is not None:
            break
        elif kind == "reject" and first is not None:
            final = None  # the start was called off (docs/formats.md): no action in the end
            break
    return first, final, last_np, at


def _recognizer_onset(events: Iterable[dict], onset: int) -> int | None:
    """Frames from the true `onset` to the recognizer's own onset of the first decided motion
    in `events` (its `start` event's `onset_frame`); None without a start."""
    for e in events:
        if e["event"] == "start":
            return None if e.get("onset_frame") is None else e["onset_frame"] - onset
    return None


def replay_trial(rec: DualBufferRecognizer, trial: np.ndarray) -> tuple[list[dict], int]:
    """Events of one isolated trial padded with rest; and the offset of the trial in the stream."""
    rec.reset()
    stream = np.vstack([np.repeat(trial[:1], PAD_BEFORE, 0), trial, np.repeat(trial[-1:], PAD_AFTER, 0)])
    events: list[dict] = []
    for f in stream:
        events.extend(rec.push(f))
    return events, PAD_BEFORE


def session_order(tests: Mapping[str, Sequence[np.ndarray]]) -> list[tuple[str, np.ndarray]]:
    """The trials as one player's session would bring them: round robin over the actions, each
    action's trials in their order (file names sort by day and repetition), so a recognizer that
    adapts to the player sees them in time order rather than one action at a time."""
    out = []
    for i in range(max((len(t) for t in tests.values()), default=0)):
        out += [(action, trials[i]) for action, trials in tests.items() if i < len(trials)]
    return out


def evaluate_trials(
    templates: Templates,
    tests: Mapping[str, Sequence[np.ndarray]],
    mains: Sequence[int | str],
    fresh: bool = False,
    **rec_kwargs,
) -> list[Summary]:
    """Trials in session order through one recognizer (which may adapt to the player), or with
    `fresh` through a new recognizer for every trial: no adaptation and no gate learnt from the
    trials before (until the twenty-second round it was one recognizer that forgot its adaptation
    and kept its learnt gate: uWave 92.0 % against 91.8 % this way; docs/recognition.md)."""
    out = []
    for main in mains:
        rec = None
        s = Summary(main)
        for action, trial in session_order(tests):
            if fresh or rec is None:
                rec = DualBufferRecognizer(templates, main=main, **rec_kwargs)
            events, offset = replay_trial(rec, trial)
            first, final, last_np, at = _decisions(events)
            onset = offset + true_onset(trial)
            lag = None if at is None else at - onset
            s.outcomes.append(Outcome(action, first, final, last_np, lag, _recognizer_onset(events, onset)))
        out.append(s)
    return out


# -- labelled streams ---------------------------------------------------------------------------
def intervals(labels: Sequence[str]) -> list[tuple[str, int, int]]:
    """(action, first frame, end frame exclusive) of every labelled run."""
    out, cur, start = [], "", 0
    for i, lab in enumerate(list(labels) + [""]):
        if lab != cur:
            if cur:
                out.append((cur, start, i))
            cur, start = lab, i
    return out


def stream_trials(frames: np.ndarray, ivs: Sequence[tuple[str, int, int]], lead: int = 10) -> dict[str, list[np.ndarray]]:
    """Training trials cut from a labelled stream: each interval with `lead` frames before it."""
    out: dict[str, list[np.ndarray]] = {}
    for action, s, e in ivs:
        out.setdefault(action, []).append(frames[max(0, s - lead) : e])
    return out


@dataclass(frozen=True)
class Clips:
    """The simulated character's clips: `per_action` frames for the actions the game has (its
    boxer plays a started action's clip from frame 0 and a switch's from its n_p, and is done on
    the clip's last frame), `frames` from the motion's start for any other name (the phone sets'
    jab, hook, ...; a switch continues the clip)."""

    frames: int
    per_action: Mapping[str, int]


def game_clips(frames: int = CLIP_FRAMES) -> Clips | int:
    """The shipped action library's clip lengths (game/actions), `frames` for other names; 0 (no
    character) stays 0."""
    if frames <= 0:
        return 0
    from game.actions import load_library

    return Clips(frames, {name: clip.frames for name, clip in load_library().items() if not clip.loop})


def _clip_end(e: dict, clip_frames: int | Clips) -> int | None:
    """The frame after whose push the character is done with the action `e` starts or switches to."""
    from_frame = e.get("from_frame", 0)
    n = clip_frames.per_action.get(e["action"]) if isinstance(clip_frames, Clips) else None
    if n is not None:
        return e["frame"] + max(n - 1 - from_frame, 0)
    frames = clip_frames.frames if isinstance(clip_frames, Clips) else clip_frames
    return e["frame"] - from_frame + frames if frames > 0 else None


class SimulatedCharacter:
    """A character that finishes each action `clips` after its start (a switch continues at n_p,
    so the end does not move), or as the game's boxer does with `Clips`, and then calls the
    recognizer's `character_finished()`; with clips=0 it never does."""

    def __init__(self, clips: int | Clips) -> None:
        self.clips = clips
        self.clip_end: int | None = None

    def after_push(self, rec: DualBufferRecognizer, i: int, events: Sequence[dict]) -> None:
        """The character's turn after push number `i` (from 0) decided `events`."""
        for e in events:
            if e["event"] in ("start", "switch"):
                self.clip_end = _clip_end(e, self.clips)
        if self.clip_end is not None and i >= self.clip_end:
            rec.character_finished()
            self.clip_end = None


def replay_stream(rec: DualBufferRecognizer, frames: np.ndarray, clip_frames: int | Clips = CLIP_FRAMES) -> list[dict]:
    """Events of a whole stream, with a SimulatedCharacter playing `clip_frames`."""
    rec.reset()
    events: list[dict] = []
    character = SimulatedCharacter(clip_frames)
    for i, f in enumerate(frames):
        evs = rec.push(f)
        events.extend(evs)
        character.after_push(rec, i, evs)
    return events


def score_stream(
    events: Sequence[dict],
    ivs: Sequence[tuple[str, int, int]],
    n_frames: int,
    main: int | str,
    tolerance: int = EARLY_TOLERANCE,
    frames: np.ndarray | None = None,
    onsets: Sequence[int] | None = None,
    rest_ends: Sequence[int | None] | None = None,
) -> Summary:
    """Match starts to intervals, in order: each interval takes the first start not yet taken
    inside [first - tolerance, end) (hand-labelled intervals begin after the wind-up the sensor
    already sees, and a start in the last frames of an interval that already has one is the
    next punch's) and not before the end of the rest before it, where there is one (`stream_rest`):
    a start decided while the hand still rested (on the previous punch's return, or a drift)
    is not this punch's, whatever it names. Starts outside every (widened) interval are false starts; the other starts not
    taken, inside a (widened) interval, are `extra_starts` (a player sees a second punch, e.g.
    the return of a full blow after the character's clip ended). The lag is counted from each
    interval's true onset: `onsets[i]` and `rest_ends[i]` when given (a spliced stream's, see
    `mixed_stream`), else `stream_rest` (the rest after the previous interval) when the
    `frames` are given, else its first labelled frame (and no rest bound)."""
    s = Summary(main)
    starts = [e for e in events if e["event"] == "start"]
    used: set[int] = set()
    prev_end = 0
    for i, (action, a, b) in enumerate(ivs):
        prev, prev_end = prev_end, b
        rest_end, onset = (None, a) if frames is None else stream_rest(frames, a, b, prev)
        if onsets is not None:
            onset = onsets[i]
        if rest_ends is not None:
            rest_end = rest_ends[i]
        lo = a - tolerance if rest_end is None else max(a - tolerance, rest_end)
        mine = [k for k, e in enumerate(starts) if lo <= e["frame"] < b and k not in used]
        if not mine:
            s.outcomes.append(Outcome(action, None, None, -1, None))
            continue
        k = mine[0]
        used.add(k)
        e = starts[k]
        after = [x for x in events if x["frame"] >= e["frame"]]
        first, final, last_np, at = _decisions(after)
        s.outcomes.append(Outcome(action, first, final, last_np, at - onset, _recognizer_onset(after, onset),
                                  rested=rest_end is not None))
    labelled = np.zeros(n_frames, dtype=bool)
    for _, a, b in ivs:
        labelled[max(0, a - tolerance) : b] = True
    spare = [labelled[min(e["frame"], n_frames - 1)] for k, e in enumerate(starts) if k not in used]
    s.false_starts = spare.count(False)
    s.extra_starts = spare.count(True)
    s.idle_minutes = float((~labelled).sum()) / 60.0 / 60.0
    return s


def evaluate_stream_folds(
    frames: np.ndarray,
    labels: Sequence[str],
    mains: Sequence[int | str],
    folds: int = 2,
    template_kwargs: Mapping | None = None,
    clip_frames: int | Clips = CLIP_FRAMES,
    where: str = "the labelled stream",
    **rec_kwargs,
) -> list[Summary]:
    """K contiguous folds: templates from the intervals of the other folds, tested on this
    fold's stretch of the stream. Pooled over folds. A fold whose templates cannot be built (no
    interval in the other folds, one too short) is an InputError naming `where` (the file)."""
    ivs = intervals(labels)
    n = len(frames)
    bounds = np.linspace(0, n, folds + 1).astype(int)
    pooled = [Summary(m) for m in mains]
    for k in range(folds):
        lo, hi = bounds[k], bounds[k + 1]
        train = [iv for iv in ivs if not (lo <= iv[1] < hi)]
        test = [(a, s - lo, e - lo) for a, s, e in ivs if lo <= s < hi]
        if not train:
            raise InputError(f"{where}: fold {k + 1} of {folds} has no labelled interval in the other folds "
                             "to build templates from (fewer --folds, or --templates)")
        templates = templates_from_trials(stream_trials(frames, train), f"{where} (fold {k + 1} of {folds})",
                                          **(template_kwargs or {}))
        for m, pool in zip(mains, pooled, strict=True):
            rec = DualBufferRecognizer(templates, main=m, **rec_kwargs)
            events = replay_stream(rec, frames[lo:hi], clip_frames)
            s = score_stream(events, test, hi - lo, m, frames=frames[lo:hi])
            pool.add(s)
    return pooled


def evaluate_stream(
    templates: Templates,
    frames: np.ndarray,
    labels: Sequence[str],
    mains: Sequence[int | str],
    clip_frames: int | Clips = CLIP_FRAMES,
    **rec_kwargs,
) -> list[Summary]:
    """A labelled stream against given templates."""
    ivs = intervals(labels)
    out = []
    for m in mains:
        rec = DualBufferRecognizer(templates, main=m, **rec_kwargs)
        out.append(score_stream(replay_stream(rec, frames, clip_frames), ivs, len(frames), m, frames=frames))
    return out


def format_table(rows: Sequence[dict]) -> str:
    cols = ["main", "n", *GROUPS, "acceptable", "final_correct", "first_correct", "lag_ms", "lag_p90_ms",
            "lag_to_onset_ms", "lag_onset_to_decision_ms"]
    if any("false_starts" in r for r in rows):
        cols += ["started", "type", "false_starts", "false_starts_per_idle_min", "extra_starts"]
    if any("lag_rested_n" in r for r in rows):
        cols += ["lag_rested_n", "lag_rested_ms", "lag_rested_p90_ms"]
    head = " | ".join(cols)
    lines = [head, "-" * len(head)]
    for r in rows:
        lines.append(" | ".join(str(r.get(c, "")) for c in cols))
    return "\n".join(lines)


def plot(rows_by_title: Mapping[str, Sequence[dict]], path: str) -> dict:
    """Figs. 8-9: stacked outcome groups against the main-buffer size, one panel per set. The
    legend sits under the panels (inside, it covered the largest buffer sizes' bars). Returns the
    layout in image pixels: {"size": (w, h), "axes": [(x0, y0, x1, y1)...], "legend": (...)}."""
    from engine.errors import InputError

    try:
        import matplotlib
    except ImportError:
        raise InputError("--plot needs matplotlib (pip install 'quickjab[dev]')") from None
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    n = len(rows_by_title)
    dpi = 100
    fig, axes = plt.subplots(1, n, figsize=(6.4 * n, 4.8), squeeze=False, dpi=dpi)
    colors = ["#2a9d8f", "#8ab17d", "#e9c46a", "#e76f51"]
    for ax, (title, rows) in zip(axes[0], rows_by_title.items(), strict=True):
        x = [str(r["main"]) for r in rows]
        bottom = np.zeros(len(rows))
        for g, col in zip(GROUPS, colors, strict=True):
            v = np.array([r[g] for r in rows]) * 100
            ax.bar(x, v, bottom=bottom, color=col, label=g, width=0.8)
            bottom += v
        ax.plot(x, [r["first_correct"] * 100 for r in rows], "k.-", lw=1.5, label="first decision correct")
        ax.set_title(title, fontsize=13)
        ax.set_xlabel("main buffer (frames)", fontsize=12)
        ax.tick_params(labelsize=11)
        ax.set_ylim(0, 100)
    axes[0][0].set_ylabel("% of motions", fontsize=12)
    handles, labels = axes[0][0].get_legend_handles_labels()
    legend = fig.legend(handles, labels, loc="lower center", ncol=len(labels), fontsize=11, frameon=False)
    fig.tight_layout(rect=(0, 0.09, 1, 1))
    fig.canvas.draw()
    height = fig.bbox.height

    def box(b) -> tuple[float, float, float, float]:  # display (y up) -> image pixels (y down)
        return (b.x0, height - b.y1, b.x1, height - b.y0)

    layout = {"size": (int(round(fig.bbox.width)), int(round(height))),
              "axes": [box(ax.get_window_extent()) for ax in axes[0]],
              "legend": box(legend.get_window_extent())}
    from tools.profile import save_figure

    save_figure(fig, path, dpi)
    return layout


# -- cross-session: phone-punches -----------------------------------------------------------------
PUNCH_SETS = ("fast", "slow")
RECORDED_MIXED = "mixed"  # <hand>_mixed_<name>.csv: a recorded sequence of all kinds, every punch labelled


def punch_files(root: str | Path) -> dict[tuple[str, str], dict[str, Path]]:
    """{(hand, set): {punch: file}} of `<root>/<hand>_<punch>_<fast|slow>.csv`, and
    {(hand, "mixed"): {name: file}} of `<root>/<hand>_mixed_<name>.csv`."""
    out: dict[tuple[str, str], dict[str, Path]] = {}
    for f in sorted(Path(root).glob("*_*_*.csv")):
        hand, punch, kind = f.stem.split("_", 2)
        if kind in PUNCH_SETS:
            out.setdefault((hand, kind), {})[punch] = f
        elif punch == RECORDED_MIXED:
            out.setdefault((hand, RECORDED_MIXED), {})[kind] = f
    return out


def evaluate_cross_session(
    train: Mapping[str, tuple[np.ndarray, Sequence[str]]],
    test: Sequence[tuple[np.ndarray, Sequence[str]] | tuple[np.ndarray, Sequence[str], Sequence[int], Sequence[int]]],
    mains: Sequence[int | str],
    trials: int = 3,
    template_kwargs: Mapping | None = None,
    clip_frames: int | Clips = CLIP_FRAMES,
    where: str = "the training recordings",
    draw: int = 0,
    template_lead: int = 10,
    **rec_kwargs,
) -> list[Summary]:
    """Templates from the first `trials` labelled intervals of each action's training recording
    (`{action: (frames, labels)}`, each interval cut with `template_lead` frames before it, as
    `stream_trials` does),
    then every test recording replayed whole as a stream (a fresh recognizer per recording) and
    scored with `score_stream`; a spliced stream (`mixed_stream`) brings its punches' true onsets
    and rest ends as a third and fourth item. Pooled over the test recordings. Training recordings that give no templates
    (no interval of their action, one too short) are an InputError naming `where`."""
    templates = first_trials_templates(train, trials, template_kwargs, where, draw, template_lead)
    pooled = [Summary(m) for m in mains]
    for frames, labels, *spliced in test:
        ivs = intervals(labels)
        onsets, rest_ends = (spliced + [None, None])[:2]
        if onsets is not None and len(onsets) != len(ivs):
            raise ValueError(f"{len(onsets)} onsets for {len(ivs)} labelled intervals")
        for m, pool in zip(mains, pooled, strict=True):
            rec = DualBufferRecognizer(templates, main=m, **rec_kwargs)
            events = replay_stream(rec, frames, clip_frames)
            s = score_stream(events, ivs, len(frames), m, frames=frames, onsets=onsets, rest_ends=rest_ends)
            pool.add(s)
    return pooled


def first_trials_templates(
    train: Mapping[str, tuple[np.ndarray, Sequence[str]]],
    trials: int = 3,
    template_kwargs: Mapping | None = None,
    where: str = "the training recordings",
    draw: int = 0,
    lead: int = 10,
) -> Templates:
    """Templates from the first `trials` labelled intervals of each action's training recording
    (`{action: (frames, labels)}`), each cut with `lead` frames before it as `stream_trials` does;
    with `draw` k, the k-th next `trials` of them instead (draw 1: intervals 4-6 of 3 per draw)."""
    cut = {}
    for action, (frames, labels) in train.items():
        ivs = [iv for iv in intervals(labels) if iv[0] == action][draw * trials : (draw + 1) * trials]
        if not ivs:
            has = sum(iv[0] == action for iv in intervals(labels))
            raise InputError(f"{where}: {has} intervals labelled {action!r}, too few for template draw {draw + 1} ({trials} per draw)")
        cut[action] = stream_trials(frames, ivs, lead)[action]
    return templates_from_trials(cut, where, **(template_kwargs or {}))


def evaluate_isolated(
    train: Mapping[str, tuple[np.ndarray, Sequence[str]]],
    test: Sequence[tuple[np.ndarray, Sequence[str]]],
    mains: Sequence[int | str],
    trials: int = 3,
    template_kwargs: Mapping | None = None,
    where: str = "the training recordings",
    fresh: bool = False,
    lead: int = 10,
    draw: int = 0,
    template_lead: int = 10,
    **rec_kwargs,
) -> list[Summary]:
    """The templates of `evaluate_cross_session`, tested on every labelled punch of the test
    recordings replayed as an isolated trial (cut with `lead` frames before it, as the training
    punches are, and as many after; those frames may hold a neighbouring punch's tail), in session
    order through one recognizer (`evaluate_trials`; with `fresh`, a fresh one per trial): "the
    rest" of a person's punches, one at a time."""
    templates = first_trials_templates(train, trials, template_kwargs, where, draw, template_lead)
    tests: dict[str, list[np.ndarray]] = {}
    for frames, labels in test:
        for action, a, b in intervals(labels):
            tests.setdefault(action, []).append(frames[max(0, a - lead) : b + lead])
    return evaluate_trials(templates, tests, mains, fresh=fresh, **rec_kwargs)


def evaluate_phone_punches(
    root: str | Path,
    mains: Sequence[int | str],
    mixed: bool = False,
    seed: int = 0,
    isolated: bool = False,
    fresh: bool = False,
    draws: int = 1,
    **kwargs,
) -> dict[str, list[Summary]]:
    """Per hand, fast -> slow and slow -> fast: templates from the first trials of each punch in
    one set's files, tested on every punch of the other set's files (see evaluate_cross_session).
    With `mixed`, also on the other set's punches of all kinds spliced into one stream
    (`mixed_stream`, shuffled with `seed`): as recorded ("mixed"), every punch turned to one guard
    ("mixed, one guard"), and resting in one guard with the fist turned into each punch's own as
    it starts ("mixed, one guard, turned in"). Recorded mixed sequences of a hand
    (`<hand>_mixed_<name>.csv`) are tested too, with each set's templates ("fast -> recorded
    mixed", "slow -> recorded mixed"), whether or not `mixed` is given. With `isolated`, also each
    punch of the other set as an isolated trial ("isolated", `evaluate_isolated`; with `fresh`,
    "isolated, fresh recognizer per trial"). With `draws` k > 1, every row pools k disjoint
    draws of templates (the first `trials` punches of each kind, the next `trials`, ...): one draw
    of 3 moves a row by 10-30 points (docs/recognition.md, seventeenth round)."""
    if draws > 1:
        return pooled_draws(lambda d: evaluate_phone_punches(root, mains, mixed, seed, isolated, fresh, draw=d, **kwargs), draws, mains)
    files = punch_files(root)
    loaded: dict[Path, tuple[np.ndarray, list[str]]] = {}

    def load(f: Path) -> tuple[np.ndarray, list[str]]:
        if f not in loaded:
            loaded[f] = read_labelled_frames(f)
        return loaded[f]

    out = {}
    for hand in sorted({h for h, _ in files}):
        _check_punch_files(hand, files, load)
        for src, dst in (("fast", "slow"), ("slow", "fast")):
            if (hand, src) not in files:
                continue
            train = {p: load(f) for p, f in files[(hand, src)].items()}
            kw = {"where": f"{Path(root) / f'{hand}_*_{src}.csv'}", **kwargs}
            if (hand, dst) in files:
                test = [load(f) for f in files[(hand, dst)].values()]
                out[f"phone-punches {hand} {src} -> {dst}"] = evaluate_cross_session(train, test, mains, **kw)
                if mixed:
                    variants = (("mixed", False, 0), ("mixed, one guard", True, 0), ("mixed, one guard, turned in", True, TURN_IN))
                    for name, guard, turn_in in variants:
                        stream = mixed_stream(test, seed, one_guard=guard, turn_in=turn_in)
                        out[f"phone-punches {hand} {src} -> {dst} {name}"] = evaluate_cross_session(train, [stream], mains, **kw)
                if isolated:
                    ikw = {k: v for k, v in kw.items() if k != "clip_frames"}  # no character: one trial at a time
                    name = "isolated, fresh recognizer per trial" if fresh else "isolated"
                    out[f"phone-punches {hand} {src} -> {dst} {name}"] = evaluate_isolated(train, test, mains, fresh=fresh, **ikw)
            if (hand, RECORDED_MIXED) in files:
                recorded = [load(f) for f in files[(hand, RECORDED_MIXED)].values()]
                out[f"phone-punches {hand} {src} -> recorded mixed"] = evaluate_cross_session(train, recorded, mains, **kw)
    return out


def pooled_draws(
    run: Callable[[int], dict[str, list[Summary]]], draws: int, mains: Sequence[int | str]
) -> dict[str, list[Summary]]:
    """`run(draw)`'s rows for draws 0 .. draws - 1, each row pooled over them."""
    out: dict[str, list[Summary]] = {}
    for d in range(draws):
        for title, rows in run(d).items():
            for a, b in zip(out.setdefault(title, [Summary(m) for m in mains]), rows, strict=True):
                a.add(b)
    return out


def _check_punch_files(
    hand: str,
    files: Mapping[tuple[str, str], Mapping[str, Path]],
    load: Callable[[Path], tuple[np.ndarray, list[str]]],
) -> None:
    """A hand's recordings, when it has a fast or a slow set, must all be of one D (its
    templates are tested on each of them), and each `<hand>_<punch>_<fast|slow>.csv` must label
    some rows `<punch>` (its template is cut from them): else an InputError naming the file."""
    if not any((hand, kind) in files for kind in PUNCH_SETS):
        return
    first: tuple[int, Path] | None = None  # the hand's first recording: its D and file
    for (h, kind), mine in sorted(files.items()):
        if h != hand:
            continue
        for punch, f in mine.items():
            frames, labels = load(f)
            if kind != RECORDED_MIXED and punch not in labels:
                raise InputError(f"{f}: no row labelled {punch!r}: its {punch} template is cut from them")
            if first is None:
                first = (frames.shape[1], f)
            elif frames.shape[1] != first[0]:
                raise InputError(f"{f}: {frames.shape[1]} values per frame, {first[1].name} has {first[0]} "
                                 "(one- and two-hand recordings mixed)")


# -- mixed streams: the punch kinds interleaved -----------------------------------------------------
# The outside check tests a person's MIXED sequences (jab, hook, uppercut interleaved) with templates
# from single-kind files. Built here from the single-kind files: every labelled punch of the test
# set's files, with the rest around it, spliced into one stream in a seeded shuffled order.
SPLICE_FRAMES = 20  # a linear ramp between two spliced rests: a guard change of 1/3 s
# frames before the first punch, as recorded: meant as a rest for the auto gate to learn from, but
# on the phone-punches files the hand moves over the templates' gate within the first 9-24 of them
# (a start there, a false one), so the mixed rows keep the gate learnt from the templates' rest
LEAD_REST = 120
TURN_IN = 10  # "one guard, turned in": the fist turns from the guard into the punch's own in 1/6 s


def _stillest_window(x: np.ndarray, lo: int, hi: int, w: int = REST_WINDOW) -> int | None:
    """The first frame of the stillest `w` frames in x[lo:hi] (least summed spread of the sensors'
    readings about their mean, as `stream_onset` finds the rest); None when fewer than `w`."""
    if hi - lo < w:
        return None
    return lo + int(np.argmin(window_spread(x[lo:hi], w)))


def punch_segments(frames: np.ndarray, labels: Sequence[str]) -> list[tuple[np.ndarray, list[str], np.ndarray, int, int, int | None]]:
    """Every labelled punch of a recording with the rest around it: (frames, labels, rest, cut,
    onset, rest end), onset being the punch's true onset in the recording and rest end the
    frame after the rest before it (`stream_rest`),
    cut at frame `cut` in the middle of the stillest REST_WINDOW frames of the gap before it, up to
    the middle of those of the gap after it (at most REST_SEARCH frames from the label; the label's
    own edge when the gap is shorter); `rest` is the mean of the window before the punch (its guard)."""
    x = np.asarray(frames, dtype=np.float64)
    labels = list(labels)
    ivs = intervals(labels)
    cuts, rests, onsets, rest_ends = [], [], [], []  # rest_ends: int or None (`stream_rest`)
    prev_end = 0
    for _, a, b in ivs:
        rest_end, onset = stream_rest(x, a, b, prev_end)
        onsets.append(onset)
        rest_ends.append(rest_end)
        k = _stillest_window(x, max(prev_end, a - REST_SEARCH), a)
        k = k if k is not None else max(prev_end, a - REST_WINDOW)
        cuts.append(min(k + REST_WINDOW // 2, a))
        rests.append(x[k : k + REST_WINDOW].mean(axis=0))
        prev_end = b
    b = ivs[-1][2] if ivs else len(x)
    k = _stillest_window(x, b, min(len(x), b + REST_SEARCH))
    cuts.append(k + REST_WINDOW // 2 if k is not None else min(len(x), b + REST_WINDOW))
    return [(x[cuts[i] : cuts[i + 1]], labels[cuts[i] : cuts[i + 1]], rests[i], cuts[i], onsets[i], rest_ends[i])
            for i in range(len(ivs))]


def _turn(frames: np.ndarray, src: np.ndarray, dst: np.ndarray, share: np.ndarray | None = None) -> np.ndarray:
    """`frames` turned per sensor by the smallest rotation taking the direction of `src` to that
    of `dst` (Rodrigues): a punch held with another grip, from another guard. `share`: per frame,
    the part of that rotation's angle to apply (default all of it)."""
    out = np.asarray(frames, dtype=np.float64).reshape(len(frames), -1, 3).copy()
    share = np.ones(len(out)) if share is None else np.asarray(share, dtype=np.float64)
    for s in range(out.shape[1]):
        u = src[3 * s : 3 * s + 3] / max(np.linalg.norm(src[3 * s : 3 * s + 3]), 1e-9)
        v = dst[3 * s : 3 * s + 3] / max(np.linalg.norm(dst[3 * s : 3 * s + 3]), 1e-9)
        axis, c = np.cross(u, v), float(np.dot(u, v))
        sin = float(np.linalg.norm(axis))
        if sin < 1e-12 and c > 0:
            continue  # the same direction: no turn
        if sin < 1e-12:  # opposite: half a turn about an axis across u
            axis = np.cross(u, np.eye(3)[int(np.argmin(np.abs(u)))])
        k = axis / np.linalg.norm(axis)
        angle = share * np.arctan2(sin, c)  # (n,)
        kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
        rot = np.eye(3) + np.sin(angle)[:, None, None] * kx + (1.0 - np.cos(angle))[:, None, None] * (kx @ kx)
        out[:, s] = np.einsum("nij,nj->ni", rot, out[:, s])
    return out.reshape(len(frames), -1)


def _turned_in(
    frames: np.ndarray, labels: Sequence[str], rest: np.ndarray, guard: np.ndarray, cut: int, onset: int,
    rest_end: int | None, turn_in: int,
) -> tuple[np.ndarray, list[str], np.ndarray, int, int, int | None]:
    """A punch segment (`punch_segments`) whose rest is turned into `guard`, the turn undone over
    the `turn_in` frames before its own onset, the punch as recorded; and its true onset: the
    first frame of the turn or after it ONSET_G away from the turned rest (the punch's own onset
    when the turn is too small to get there); its rest ends where the turn begins, at the latest.
    A segment whose rest before the turn is shorter than
    REST_WINDOW frames starts with more rest: its first REST_WINDOW // 2 frames (the stillest
    window's second half, see `punch_segments`) played back and forth, so it keeps its noise."""
    pad = max(0, turn_in + REST_WINDOW - (onset - cut))
    half = min(REST_WINDOW // 2, len(frames))
    back_and_forth = np.r_[np.arange(1, half), np.arange(half - 2, -1, -1)] if half > 1 else np.zeros(1, dtype=int)
    frames = np.vstack([frames[np.resize(back_and_forth, pad)[::-1]], frames])  # ..., 2, 1, then 0, 1, 2, ...
    labels, cut = [""] * pad + list(labels), cut - pad
    at = onset - cut  # the punch's own onset in the segment
    turned = _turn(frames, rest, guard, np.clip((at - np.arange(len(frames))) / turn_in, 0.0, 1.0))
    away = _away_from_rest(turned[at - turn_in : at], _turn(rest[None], rest, guard)[0])
    turn_start = onset - turn_in
    return turned, labels, guard, cut, cut + (at - turn_in + int(away[0]) if len(away) else at), \
        None if rest_end is None else min(rest_end, turn_start)


def mixed_stream(
    recordings: Sequence[tuple[np.ndarray, Sequence[str]]], seed: int = 0, one_guard: bool = False, turn_in: int = 0
) -> tuple[np.ndarray, list[str], list[int], list[int | None]]:
    """One labelled stream of every punch of `recordings` (single-kind files), each with the rest
    around it (`punch_segments`), in an order shuffled with `seed`; SPLICE_FRAMES of linear ramp
    between two segments; the stream opens with LEAD_REST frames of the rest before one recording's
    first punch, then that punch. Returns the frames, the labels, each punch's true onset and the
    frame after its rest (`stream_rest`, never earlier than its segment, after the ramp): the
    one in its own recording (`stream_onset` there), not one measured in the stream, where the
    rest before a punch may lie before a splice's ramp (a guard change the splice made, not the
    player) and the onset would fall on the ramp.
    With `one_guard`, every segment is turned (`_turn`) so that its guard matches the mean guard of
    all segments: a player who starts every kind from the same guard, so the resting tilt no
    longer tells the kinds apart (in single-kind files it does: e.g. the left uppercut's rest is
    ~60 degrees from the jab's). That turns the whole punch, so it is thrown in another direction
    too. With `turn_in` frames as well, only the rest is turned: over the `turn_in` frames before
    its onset the hand turns from the mean guard into the punch's own, and the punch is as
    recorded (a player who rests in one guard and turns the fist into each kind as it starts);
    its true onset is then measured in its segment, on the turn."""
    segs, origin = [], []  # origin: (recording, its first punch's segment index)
    for r, (frames, labels) in enumerate(recordings):
        mine = punch_segments(frames, labels)
        origin += [(r, len(segs))] * len(mine)
        segs += mine
    if not segs:
        raise ValueError("no labelled punches to mix")
    order = list(np.random.default_rng(seed).permutation(len(segs)))
    # The stream opens with the rest before a recording's first punch, then that punch (the rest
    # and the punch are contiguous, so the auto gate learns from a real rest as it would per file).
    r0, first = origin[order[0]]
    j = order.index(first)
    order[0], order[j] = order[j], order[0]
    lead = np.asarray(recordings[r0][0][max(0, segs[first][3] - LEAD_REST) : segs[first][3]], dtype=np.float64)
    if one_guard:
        guard = np.mean([s[2] for s in segs], axis=0)
        lead = _turn(lead, segs[first][2], guard) if len(lead) else lead
        if turn_in > 0:
            segs = [_turned_in(f, lab, r, guard, c, on, re, turn_in) for f, lab, r, c, on, re in segs]
        else:
            segs = [(_turn(f, r, guard), lab, guard, c, on, re) for f, lab, r, c, on, re in segs]
    if not len(lead):
        lead = segs[first][0][:1]
    parts, labels, onsets, rest_ends = [lead], [""] * len(lead), [], []
    for n, i in enumerate(order):
        f, lab, _, cut, onset, rest_end = segs[i]
        ramp = np.linspace(parts[-1][-1], f[0], SPLICE_FRAMES + 2)[1:-1] if n else f[:0]
        parts += [ramp, f]
        labels += [""] * len(ramp)
        onsets.append(len(labels) + onset - cut)  # its own (a whole turn keeps the distances from the rest)
        rest_ends.append(None if rest_end is None else len(labels) + max(0, rest_end - cut))  # never on the ramp
        labels += list(lab)
    return np.vstack(parts), labels, onsets, rest_ends
