"""Control-signal templates (paper III): per action, built from a handful of trials.

A trial is an (n, D) array at 60 Hz in g, gravity included, D = 3 per sensor. Building:
1. estimate each sensor's gravity from the trial's first frames (the player starts at rest),
2. trim the rest at both ends (activity below a fraction of the trial's peak),
3. combine the trials of an action by one of three methods:
   - "trials": keep every trial as its own template (nearest neighbour over several templates),
   - "average": Eq. 1, align every trial to the medoid trial with DTW and average along the path,
   - "dba": DTW barycenter averaging (Petitjean et al. 2011), a few refinement rounds from the
     medoid.
4. learn a rejection threshold per template from the spread of the action's other trials
   against it (as gesture toolkits such as GRT do: mean + k * std of the training distances).

Templates keep a few frames of lead-in before the trimmed onset: the recognizer cuts each one at
the frame its own noise gate would open, so template and live motion start at the same point.

Files are plain .npz (no pickles); a corrupt or foreign file raises TemplateFileError naming it.
"""

from __future__ import annotations

import json
import os
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from engine.errors import InputError
from engine.npz_files import NpzFileError, read_json, read_npz, write_replacing
from engine.recognition.config import RecognizerConfigError, check_settings
from engine.recognition.dtw import IncrementalDTW, dtw_distance

FORMAT_VERSION = 1
METHODS = ("trials", "average", "dba")
DEFAULT_METHOD = "trials"  # measured: see docs/recognition.md
FEATURES = ("log", "raw", "dynamic", "grip")
DEFAULT_FEATURE = "log"  # measured: see docs/recognition.md
LOG_SCALE_G = 0.5  # "log" feature: sign(a) * log(1 + |a| / LOG_SCALE_G)
MIN_PROGRESS = 1.25  # open-end scoring constraint (dtw.IncrementalDTW.min_progress); measured
REST_FRAMES = 3  # frames at a trial's start used as the resting gravity estimate
REST_WINDOW = 8  # trial_rest(): a trial's rest is the first window of this many frames before ...
REST_SPREAD_RATIO = 2.0  # ... its motion that is at most this x as spread as the stillest one,
TAIL_RATIO = 0.75  # ... and what comes before it is a tail: under this x the motion's peak activity
TRIM_FRACTION = 0.1  # activity below this fraction of the trial's peak is rest
LEAD_IN = 4  # frames kept before the trimmed onset (the recognizer re-cuts at its own gate)
REJECT_K = 2.0  # threshold = mean + REJECT_K * std of same-action training scores ...
REJECT_RATIO = 2.0  # ... and at least REJECT_RATIO * their max (docs/recognition.md)
REJECT_FLOOR_G = 0.05  # and never below this (g): identical trials must not reject all noise
CUT_OFF_FRACTION = 0.5  # representative_trials(): shorter or fainter than this x the median: cut off
# usable_trials() (`keep="usable"`, what `train` keeps of its 5 trials; docs/recognition.md,
# twentieth round): a trial whose summed distance to its action's others is over ODD_RATIO x their
# median is an odd one (a warm-up); one whose nearest trial of another action is closer than
# CONFUSABLE_MARGIN x its mean distance to its own action's, and that ratio under CONFUSABLE_REL x
# its action's median ratio, looks like another action and would draw that action's punches. At
# least MIN_USABLE trials of an action stay.
ODD_RATIO = 1.5
CONFUSABLE_MARGIN = 1.1
CONFUSABLE_REL = 0.9
MIN_USABLE = 2
REST_NOISE_QUANTILE = 90  # resting_noise(): this percentile of the resting activity ...
REST_NOISE_MIN_FRAMES = 6  # ... over at least this many resting frames
# Uncompressed; the shipped set is under 1 MB, and a template per trial of uWave's 4,480 (one
# hand, ~2 s each) would be about 13 MB. A loaded set takes ~5.6 x its signal bytes (13 templates
# of 400,000 frames, 250 MB, took 1.4 GB under the 256 MiB this was): 64 MiB, ~0.36 GB.
MAX_FILE_BYTES = 64 * 2**20
# Templates a file may hold: 10x the largest set the benchmarks run (1000), 250x the shipped 39.
# A million 3-frame templates deflate to 0.5 MB and took 1.7 GB once loaded.
MAX_TEMPLATES = 10_000


class TemplateFileError(InputError):
    """A template file that cannot be loaded; the message names the file."""

    def __init__(self, path: str | os.PathLike, message: str):
        self.path = str(path)
        super().__init__(f"{self.path}: {message}")


def mirrored_name(action: str) -> str:
    """An action's name in the mirror image (Templates.mirrored): _l and _r swapped."""
    if action.endswith("_l"):
        return action[:-2] + "_r"
    if action.endswith("_r"):
        return action[:-2] + "_l"
    return action


def rest_gravity(trial: np.ndarray, frames: int = REST_FRAMES) -> np.ndarray:
    """(D,) the per-sensor gravity estimate: the mean of the trial's first frames."""
    return np.asarray(trial[: max(1, min(frames, len(trial)))], dtype=np.float64).mean(axis=0)


def window_spread(x: np.ndarray, w: int) -> np.ndarray:
    """(n - w + 1,) for each window of `w` frames of `x` (n, D): the summed spread of the sensors'
    readings about their mean (RMS distance per sensor, summed); small where the sensors rest."""
    win = np.lib.stride_tricks.sliding_window_view(np.asarray(x, dtype=np.float64), w, axis=0)  # (n, D, w)
    dev = win - win.mean(axis=2, keepdims=True)
    return np.sqrt((dev.reshape(len(win), -1, 3, w) ** 2).sum(axis=2).mean(axis=2)).sum(axis=1)


def trial_rest(trial: np.ndarray, window: int = REST_WINDOW) -> tuple[np.ndarray, int]:
    """(D,) the trial's resting gravity and the frame its rest begins. A trial cut from a stream
    with a long lead-in begins on the tail of the motion before it, and then its first frames are
    not the rest the motion left. The rest: of the `window`-frame windows before the trial's
    sharpest change (the motion), the first whose spread (summed over the sensors, of the readings
    about their mean, as the evaluation's true onset measures it) is at most REST_SPREAD_RATIO x
    the least, and whose frames before it move less than TAIL_RATIO x the motion's peak (else
    that window is a hold inside the motion). When that is the first window (a trial that starts
    at rest, as `train` records them) or there is none, the mean of the first REST_FRAMES frames,
    as before."""
    x = np.asarray(trial, dtype=np.float64)
    hi = int(np.argmax(np.linalg.norm(np.diff(x, axis=0), axis=1))) + 1 if len(x) > 1 else 0
    w = min(window, hi)
    if w < REST_FRAMES:
        return rest_gravity(x), 0
    spread = window_spread(x[:hi], w)
    # The earliest window about as still as the stillest: the slow crest of a motion can be a
    # little stiller than a short rest before it, and a trial that starts at rest keeps its rest.
    k = int(np.flatnonzero(spread <= REST_SPREAD_RATIO * spread.min())[0])
    if k == 0:
        return rest_gravity(x), 0
    gravity = x[k : k + w].mean(axis=0)
    act = activity(x, gravity)
    if act[:k].max() >= TAIL_RATIO * act[k:].max():
        # about as strong before that window as after it: the window is a hold inside the motion
        # (a block's), not a rest after another motion's tail, and the trial starts moving
        return rest_gravity(x), 0
    return gravity, k


def motion_activity(trial: np.ndarray) -> tuple[np.ndarray, np.ndarray, int]:
    """The trial's resting gravity (`trial_rest`), its activity against it with the frames before
    the rest zeroed (they are another motion's), and the frame the rest begins."""
    gravity, rest = trial_rest(trial)
    act = activity(trial, gravity)
    act[:rest] = 0.0
    return gravity, act, rest


def sensor_activity(frames: np.ndarray, gravity: np.ndarray) -> np.ndarray:
    """(n, sensors): each sensor's |a - g| (g per sensor)."""
    dev = (np.asarray(frames, dtype=np.float64) - gravity).reshape(len(frames), -1, 3)
    return np.linalg.norm(dev, axis=2)


def activity(frames: np.ndarray, gravity: np.ndarray) -> np.ndarray:
    """(n,) the gate signal of IV-A: the sum over sensors of |a - g| (g per sensor)."""
    return sensor_activity(frames, gravity).sum(axis=1)


def linear(frames: np.ndarray, gravity: np.ndarray) -> np.ndarray:
    """(n,) the sum over sensors of ||a| - |g||: the part of the activity a turn of the hand
    (a guard change, a drift) does not make."""
    a = np.linalg.norm(np.asarray(frames, dtype=np.float64).reshape(len(frames), -1, 3), axis=2)
    return np.abs(a - np.linalg.norm(np.asarray(gravity, dtype=np.float64).reshape(-1, 3), axis=1)).sum(axis=1)


def features(frames: np.ndarray, gravity: np.ndarray, kind: str) -> np.ndarray:
    """What DTW compares: "raw" is the signal as read (gravity included, so the hand's holding
    posture and its changes count); "log" is raw compressed per axis (a 12 g punch and a 1.5 g
    gesture both keep their shape, and big peaks do not swamp the posture); "dynamic"
    subtracts the resting gravity estimated before the onset; "grip" is the same for any way the
    sensor is held (see grip_features)."""
    if kind == "raw":
        return np.asarray(frames, dtype=np.float64)
    if kind == "log":
        x = np.asarray(frames, dtype=np.float64)
        return np.sign(x) * np.log1p(np.abs(x) / LOG_SCALE_G)
    if kind == "dynamic":
        return np.asarray(frames, dtype=np.float64) - gravity
    if kind == "grip":
        return grip_features(frames, gravity)
    raise ValueError(f"feature must be one of {FEATURES}, not {kind!r}")


def resting_noise(trials: Iterable[Sequence[np.ndarray]], quantile: float = REST_NOISE_QUANTILE) -> float:
    """The sensor's resting noise as the gate sees it (g): the `quantile` (%) of the activity
    against each trial's resting gravity over the frames before its trimmed onset, pooled over
    all trials; nan when the trials hold fewer than REST_NOISE_MIN_FRAMES such frames."""
    pre = []
    for items in trials:
        for t in items:
            t = np.asarray(t, dtype=np.float64)
            _, act, rest = motion_activity(t)
            peak = float(act.max())
            first = int(np.flatnonzero(act >= TRIM_FRACTION * peak)[0]) if peak > 0 else len(t)
            pre.append(act[rest + (REST_WINDOW if rest else REST_FRAMES) : first])  # past what gravity averaged
    pre = np.concatenate(pre) if pre else np.array([])
    return float(np.percentile(pre, quantile)) if len(pre) >= REST_NOISE_MIN_FRAMES else float("nan")


def grip_features(frames: np.ndarray, gravity: np.ndarray) -> np.ndarray:
    """(n, D) per sensor, against the resting gravity g before the motion: the vertical component
    a . g/|g|, the horizontal magnitude |a - (a . u) u| and the gravity-removed magnitude |a - g|,
    each log-compressed as "log" is. A sensor turned in the hand (another grip, another resting
    tilt) turns a and g alike, so these stay the same; the horizontal direction is lost."""
    a = np.asarray(frames, dtype=np.float64).reshape(len(frames), -1, 3)
    g = np.asarray(gravity, dtype=np.float64).reshape(1, -1, 3)
    u = g / np.maximum(np.linalg.norm(g, axis=2, keepdims=True), 1e-9)
    v = (a * u).sum(axis=2)
    h = np.linalg.norm(a - v[..., None] * u, axis=2)
    d = np.linalg.norm(a - g, axis=2)
    out = np.stack([v, h, d], axis=2).reshape(len(frames), -1)
    return np.sign(out) * np.log1p(np.abs(out) / LOG_SCALE_G)


def trim_rest(trial: np.ndarray, fraction: float = TRIM_FRACTION, lead_in: int = LEAD_IN) -> tuple[np.ndarray, int]:
    """The trial without its resting frames at both ends (keeping `lead_in` frames before the
    onset), and the index of the onset inside the returned array."""
    trial = np.asarray(trial, dtype=np.float64)
    _, act, rest = motion_activity(trial)
    peak = float(act.max())
    if peak <= 0:
        return trial[rest:], 0
    first = _after_last_rest(act, fraction * peak, int(np.flatnonzero(act >= fraction * peak)[0]))
    # The end: the last frame that still changes (the hand may stop in a new orientation, so
    # "rest" at the end is stillness, not closeness to the starting gravity).
    change = np.r_[0.0, np.linalg.norm(np.diff(trial, axis=0), axis=1)]
    change[: rest + 1 if rest else 0] = 0.0  # another motion's, and the step from it into the rest
    moving = np.flatnonzero(change >= fraction * max(float(change.max()), 1e-9))
    last = max(int(moving[-1]) if len(moving) else len(trial) - 1, first)
    start = max(rest, first - lead_in)
    return trial[start : last + 1], first - start


def _after_last_rest(act: np.ndarray, bar: float, first: int) -> int:
    """The onset: `first` (the first frame at `bar`), or later, after the last rest before the
    motion's peak (REST_WINDOW frames in a row under `bar`). A trial cut with a long lead holds
    the previous motion's tail or a fidget that reaches the bar; the template starts at the motion
    that follows the rest (twentieth round: phone-punches cut with 30 / 45 frames of lead, mean
    first decision 78.6 -> 81.5 / 80.1 -> 82.6 %; 10 and 20 frames unchanged). A pause inside a
    wind-up is shorter than a rest."""
    run = 0
    for i in range(int(np.argmax(act)), first - 1, -1):
        run = run + 1 if act[i] < bar else 0
        if run == REST_WINDOW:
            return i + REST_WINDOW
    return first


def _check_trials(trials: Mapping[str, Sequence[np.ndarray]]) -> tuple[dict[str, list[np.ndarray]], int]:
    if not trials:
        raise ValueError("no trials given")
    out: dict[str, list[np.ndarray]] = {}
    dim = None
    for action, items in trials.items():
        arrs = [np.asarray(t, dtype=np.float64) for t in items]
        if not arrs:
            raise ValueError(f"action {action!r} has no trials")
        for a in arrs:
            if a.ndim != 2 or a.shape[1] % 3 or a.shape[1] == 0 or len(a) < 2:
                raise ValueError(f"action {action!r}: a trial must be (n >= 2, D = 3k), got {a.shape}")
            if not np.all(np.isfinite(a)):
                raise ValueError(f"action {action!r}: a trial has non-finite values")
            if dim is None:
                dim = a.shape[1]
            elif a.shape[1] != dim:
                raise ValueError(f"all trials need the same D; {action!r} has {a.shape[1]}, others {dim}")
        if str(action) in out:  # {1: ..., "1": ...}: the second one's trials replaced the first's
            raise ValueError(f"action {str(action)!r} given twice ({action!r})")
        out[str(action)] = arrs
    return out, int(dim)


def dtw_path(a: np.ndarray, b: np.ndarray) -> list[tuple[int, int]]:
    """The optimal closed-end warping path between a and b (same step pattern as dtw.py)."""
    n, m = len(a), len(b)
    cost = np.sqrt(((a[:, None, :] - b[None, :, :]) ** 2).sum(axis=2))
    acc = np.full((n + 1, m + 1), np.inf)
    acc[0, 0] = 0.0
    for i in range(1, n + 1):
        c = cost[i - 1]
        up = acc[i - 1, 1:] + c
        diag = acc[i - 1, :-1] + 2.0 * c
        row = np.minimum(up, diag)
        # left steps: min-plus scan along the row
        cum = np.cumsum(c)
        acc[i, 1:] = np.minimum.accumulate(row - cum) + cum
    i, j, path = n, m, []
    while i > 0 and j > 0:
        path.append((i - 1, j - 1))
        c = cost[i - 1, j - 1]
        options = ((acc[i - 1, j - 1] + 2 * c, i - 1, j - 1), (acc[i - 1, j] + c, i - 1, j), (acc[i, j - 1] + c, i, j - 1))
        _, i, j = min(options, key=lambda o: o[0])
    path.reverse()
    return path


def representative_trials(trials: Sequence[np.ndarray], keep: int = 3, feature: str = DEFAULT_FEATURE) -> list[np.ndarray]:
    """The `keep` most representative of an action's trials, in their recorded order: trials
    whose motion is cut off (trimmed length under CUT_OFF_FRACTION of the median) or faint (peak
    activity under CUT_OFF_FRACTION of the median) go first, then the remaining trials farthest
    from the others (summed DTW distance of their trimmed motions) until `keep` are left. A
    player's first trials are often warm-ups and recorded trials can be cut short."""
    trials = [np.asarray(t, dtype=np.float64) for t in trials]
    if len(trials) <= keep:
        return trials
    motions = _motions(trials, feature)
    cand = _whole(trials, motions, keep)
    d = pairwise_distances([motions[i] for i in cand])
    kept = list(range(len(cand)))
    while len(kept) > keep:
        kept.pop(int(np.argmax(d[np.ix_(kept, kept)].sum(axis=1))))
    return [trials[cand[i]] for i in kept]


def usable_trials(
    trials: Mapping[str, Sequence[np.ndarray]],
    feature: str = DEFAULT_FEATURE,
    others: Mapping[str, Sequence[np.ndarray]] | None = None,
) -> dict[str, list[np.ndarray]]:
    """Every trial that makes a good template, per action, in recorded order: not cut off or
    faint (as `representative_trials`), not an odd one among its action's, not one that looks like
    another action (see ODD_RATIO, CONFUSABLE_MARGIN). `others`: more actions' trials a trial may
    look like (the moves a player keeps from an earlier session), never dropped themselves. Both
    rules compare with the action's median, so at most half of its trials go and at least
    MIN_USABLE stay (the look-alike rule needs 3: of 2 it would drop one). Keeping every good
    trial beats keeping the 3 most representative of 5 (docs/recognition.md, twentieth round)."""
    trials, dim = _check_trials(trials)
    refs = {a: [np.asarray(t, dtype=np.float64) for t in ts] for a, ts in (others or {}).items() if a not in trials}
    pool = {**{a: ts for a, ts in refs.items() if ts and all(t.ndim == 2 and t.shape[1] == dim for t in ts)}, **trials}
    motions = {a: _motions(ts, feature) for a, ts in pool.items()}
    cand = {a: _whole(ts, motions[a], MIN_USABLE) if a in trials else range(len(ts)) for a, ts in pool.items()}
    index = [(a, i) for a in pool for i in cand[a]]
    d = pairwise_distances([motions[a][i] for a, i in index])
    owner = np.array([a for a, _ in index])
    rows = {a: [int(k) for k in np.flatnonzero(owner == a)] for a in trials}
    for a, own in rows.items():  # odd ones
        sums = d[np.ix_(own, own)].sum(axis=1)
        rows[a] = [k for k, v in zip(own, sums, strict=True) if not v > ODD_RATIO * np.median(sums)]
    alive = ~np.isin(owner, list(trials))  # the references, and the trials still kept
    alive[[k for own in rows.values() for k in own]] = True
    for a, own in rows.items():  # look-alikes
        near = np.flatnonzero(alive & (owner != a))
        if len(own) <= MIN_USABLE or not len(near):
            continue
        mine = d[np.ix_(own, own)].sum(axis=1) / (len(own) - 1)
        ratio = d[np.ix_(own, near)].min(axis=1) / np.maximum(mine, 1e-12)
        bar = min(CONFUSABLE_MARGIN, CONFUSABLE_REL * float(np.median(ratio)))
        rows[a] = [k for k, r in zip(own, ratio, strict=True) if not r < bar]
    return {a: [trials[a][index[k][1]] for k in rows[a]] for a in trials}


def _motions(trials: Sequence[np.ndarray], feature: str) -> list[np.ndarray]:
    """Each trial's trimmed motion in `feature`s, from its own rest."""
    out = []
    for t in trials:
        sig, on = trim_rest(t)
        out.append(features(sig[on:], trial_rest(t)[0], feature))
    return out


def _whole(trials: Sequence[np.ndarray], motions: Sequence[np.ndarray], least: int) -> list[int]:
    """The trials neither cut off nor faint (under CUT_OFF_FRACTION of the median length or peak
    activity), or all of them when fewer than `least` would be left."""
    lengths = np.array([len(m) for m in motions], dtype=float)
    peaks = np.array([motion_activity(t)[1].max() for t in trials])
    ok = (lengths >= CUT_OFF_FRACTION * np.median(lengths)) & (peaks >= CUT_OFF_FRACTION * np.median(peaks))
    return [int(i) for i in np.flatnonzero(ok)] if ok.sum() >= least else list(range(len(trials)))


def pairwise_distances(motions: Sequence[np.ndarray]) -> np.ndarray:
    """(n, n) closed-end normalized DTW distances (`dtw_distance`) between every two motions, one
    DTW over all of them per motion."""
    n = len(motions)
    d = np.zeros((n, n))
    if n < 2:
        return d
    dtw = IncrementalDTW([np.asarray(m, dtype=np.float64) for m in motions], method="scan")
    for i, m in enumerate(motions):
        dtw.reset()
        for x in m:
            dtw.push(x)
        d[i] = dtw.closed_scores()
    np.fill_diagonal(d, 0.0)
    return (d + d.T) / 2  # the same up to the summation order; exactly symmetric


def _medoid(seqs: list[np.ndarray]) -> int:
    if len(seqs) <= 2:
        return int(np.argmax([len(s) for s in seqs])) if len(seqs) == 2 else 0
    d = np.zeros((len(seqs), len(seqs)))
    for i in range(len(seqs)):
        for j in range(i + 1, len(seqs)):
            d[i, j] = d[j, i] = dtw_distance(seqs[i], seqs[j])
    return int(np.argmin(d.sum(axis=1)))


def average_eq1(seqs: list[np.ndarray]) -> np.ndarray:
    """Eq. 1: every trial aligned to the reference (medoid) by DTW, then the frames mapped to
    each reference frame averaged (the reference's timing is kept)."""
    ref = seqs[_medoid(seqs)]
    total = ref.copy()
    count = np.ones(len(ref))
    for s in seqs:
        if s is ref:
            continue
        sums = np.zeros_like(ref)
        hits = np.zeros(len(ref))
        for i, j in dtw_path(s, ref):
            sums[j] += s[i]
            hits[j] += 1
        total += sums / hits[:, None]
        count += 1
    return total / count[:, None]


def dba(seqs: list[np.ndarray], rounds: int = 5) -> np.ndarray:
    """DTW barycenter averaging: start at the medoid, repeatedly replace each frame of the
    average by the mean of all trial frames aligned to it."""
    avg = seqs[_medoid(seqs)].copy()
    for _ in range(rounds):
        sums = np.zeros_like(avg)
        hits = np.zeros(len(avg))
        for s in seqs:
            for i, j in dtw_path(s, avg):
                sums[j] += s[i]
                hits[j] += 1
        new = sums / hits[:, None]
        if np.allclose(new, avg):
            break
        avg = new
    return avg


def _prefix_scores(query: np.ndarray, template: np.ndarray, upto: int = 60) -> np.ndarray:
    dtw = IncrementalDTW([template], method="scan", min_progress=MIN_PROGRESS)
    return np.array([dtw.push(x)[0] for x in query[:upto]])


@dataclass
class Templates:
    """Per-template signals (gravity included, lightly trimmed), their action names, resting
    gravity, onset index, and rejection thresholds on the normalized DTW score."""

    actions: list[str]
    signals: list[np.ndarray]
    gravity: np.ndarray  # (T, D)
    onsets: np.ndarray  # (T,) index of the trimmed onset inside each signal
    thresholds: np.ndarray  # (T,) reject when the best score is above; inf = never
    method: str = DEFAULT_METHOD
    feature: str = DEFAULT_FEATURE
    meta: dict[str, str] = field(default_factory=dict)
    rest_noise: float = float("nan")  # g: the gate's activity at rest before the trials' motions (nan: unknown)
    # Recognizer settings saved with the templates (RecognizerConfig names -> values; only those
    # the player set): a player's tuned gate travels with their moves. Empty: the defaults.
    recognizer: dict[str, object] = field(default_factory=dict)

    def __post_init__(self) -> None:
        n = len(self.actions)
        if n == 0 or len(self.signals) != n:
            raise ValueError("templates need one signal per action name, at least one")
        self.signals = [np.asarray(s, dtype=np.float64) for s in self.signals]
        self.gravity = np.asarray(self.gravity, dtype=np.float64).reshape(n, -1)
        self.onsets = np.asarray(self.onsets, dtype=np.int64).reshape(n)
        self.thresholds = np.asarray(self.thresholds, dtype=np.float64).reshape(n)
        self.recognizer = check_settings(self.recognizer, "the templates' recognizer settings")
        dims = {s.shape[1] for s in self.signals} | {self.gravity.shape[1]}
        if len(dims) != 1 or next(iter(dims)) % 3:
            raise ValueError(f"inconsistent template dimensions {sorted(dims)}")
        if dims == {0}:  # 0 is a multiple of 3, but there is nothing to compare a sensor with
            raise ValueError("templates of no values per frame (D = 0), not 3 per sensor")

    @property
    def dim(self) -> int:
        return self.signals[0].shape[1]

    @property
    def action_names(self) -> list[str]:
        """Distinct actions, in first-seen order."""
        return list(dict.fromkeys(self.actions))

    def __len__(self) -> int:
        return len(self.actions)

    # -- building ----------------------------------------------------------------------------
    @classmethod
    def from_trials(
        cls,
        trials: Mapping[str, Sequence[np.ndarray]],
        method: str = DEFAULT_METHOD,
        reject_k: float = REJECT_K,
        feature: str = DEFAULT_FEATURE,
        keep: int | str | None = None,
    ) -> Templates:
        """Templates from {action: [trial (n, D), ...]} at 60 Hz in g, gravity included. With
        `keep` k, each action keeps only its k most representative trials
        (`representative_trials`: e.g. 5 recorded, 3 kept); with `keep="usable"`, every trial
        that makes a good template (`usable_trials`, what `train` keeps)."""
        if method not in METHODS:
            raise ValueError(f"method must be one of {METHODS}, not {method!r}")
        features(np.zeros((1, 3)), np.zeros(3), feature)  # validates the name
        trials, _ = _check_trials(trials)
        if keep == "usable":
            trials = usable_trials(trials, feature)
        elif keep is not None:
            # a whole count: 2.5 kept 2 trials, nan and inf all of them, True 1
            if isinstance(keep, bool) or not isinstance(keep, (int, np.integer)) or keep < 1:
                raise ValueError(f"keep must be a whole number >= 1 or 'usable', not {keep!r}")
            trials = {a: representative_trials(ts, keep, feature) for a, ts in trials.items()}
        actions, signals, gravity, onsets, thresholds = [], [], [], [], []
        for action, items in trials.items():
            trimmed = [trim_rest(t) for t in items]
            grav = [trial_rest(t)[0] for t in items]
            # Combine on the motion itself; the lead-in is put back from the medoid afterwards.
            motions = [s[k:] for s, k in trimmed]
            if method == "trials" or len(items) == 1:
                built = list(range(len(items)))
                sigs = [s for s, _ in trimmed]
                ons = [k for _, k in trimmed]
                gr = grav
            else:
                m = _medoid(motions)
                body = average_eq1(motions) if method == "average" else dba(motions)
                lead, k = trimmed[m][0][: trimmed[m][1]], trimmed[m][1]
                built = [m]
                sigs = [np.vstack([lead, body])]
                ons = [k]
                gr = [np.mean(grav, axis=0)]
            for idx, sig, on, g in zip(built, sigs, ons, gr, strict=True):
                # Spread: how far the action's OTHER trials score against this template, at
                # every prefix the recognizer can look at (from 3 frames to the whole motion).
                others = [i for i in range(len(motions)) if i != idx or method != "trials"]
                ref = features(sig[on:], g, feature)
                scores = [_prefix_scores(features(motions[i], grav[i], feature), ref)[2:] for i in others]
                scores = np.concatenate(scores) if scores else np.array([])
                thresholds.append(_threshold(scores, reject_k))
                actions.append(action)
                signals.append(sig)
                onsets.append(on)
                gravity.append(g)
        noise = resting_noise(trials.values())
        return cls(actions, signals, np.array(gravity), np.array(onsets), np.array(thresholds), method, feature, rest_noise=noise)

    # -- transforms --------------------------------------------------------------------------
    def mirrored(self) -> Templates:
        """The set for a left-handed player: hands swapped (two-sensor data), the lateral x axis
        negated, and action names' _l/_r suffixes swapped."""

        def flip(x: np.ndarray) -> np.ndarray:
            y = x.reshape(x.shape[0], -1, 3).copy()
            y[..., 0] *= -1.0
            if y.shape[1] == 2:
                y = y[:, ::-1]
            return y.reshape(x.shape)

        return Templates(
            [mirrored_name(a) for a in self.actions],
            [flip(s) for s in self.signals],
            flip(self.gravity),
            self.onsets.copy(),
            self.thresholds.copy(),
            self.method,
            self.feature,
            {**self.meta, "mirrored": "1" if self.meta.get("mirrored") != "1" else "0"},
            self.rest_noise,
            dict(self.recognizer),
        )

    # -- files -------------------------------------------------------------------------------
    def save(self, path: str | os.PathLike) -> None:
        lengths = np.array([len(s) for s in self.signals], dtype=np.int64)
        keys = np.array(list(self.meta.keys()), dtype=str)
        vals = np.array(list(self.meta.values()), dtype=str)
        # only when set: a file without settings has the keys it always had
        settings = {"recognizer": np.array(json.dumps(self.recognizer, sort_keys=True))} if self.recognizer else {}

        def write(f) -> None:  # a file object: np.savez would append .npz to a name without it
            np.savez_compressed(
                f,
                format=np.array("quickjab-templates"),
                version=np.array(FORMAT_VERSION),
                actions=np.array(self.actions, dtype=str),
                lengths=lengths,
                signals=np.concatenate(self.signals, axis=0),
                gravity=self.gravity,
                onsets=self.onsets,
                thresholds=self.thresholds,
                method=np.array(self.method),
                feature=np.array(self.feature),
                meta_keys=keys,
                meta_values=vals,
                rest_noise=np.array(self.rest_noise),
                **settings,
            )

        try:
            write_replacing(path, write)
        except OSError as exc:  # a full disk: ENOSPC names no file
            raise TemplateFileError(path, f"cannot write ({exc.strerror or exc})") from None

    @classmethod
    def load(cls, path: str | os.PathLike) -> Templates:
        path = Path(path)
        try:
            data = read_npz(path, MAX_FILE_BYTES)
        except FileNotFoundError:
            raise TemplateFileError(path, "no such file") from None
        except NpzFileError as exc:
            raise TemplateFileError(path, f"not a template file ({exc})") from None
        except (OSError, ValueError, EOFError) as exc:
            raise TemplateFileError(path, f"not a template file ({exc.__class__.__name__}: {exc})") from None
        except Exception as exc:  # zipfile.BadZipFile and friends: still a bad file, not a crash
            raise TemplateFileError(path, f"not a template file ({exc.__class__.__name__})") from None
        if "format" in data and data["format"].dtype.kind == "S":
            raise TemplateFileError(path, "its strings are bytes (numpy 'S'); a template file holds unicode strings")
        if str(data.get("format", "")) != "quickjab-templates":
            raise TemplateFileError(path, "not a QuickJab template file (no format marker)")
        try:
            if data["version"].shape != () or data["version"].dtype.kind not in "iu":
                raise ValueError(f"version must be the integer {FORMAT_VERSION}, not {data['version'].tolist()!r}")
            version = int(data["version"])
            if version != FORMAT_VERSION:
                raise TemplateFileError(path, f"template format version {version}, expected {FORMAT_VERSION}")
            _checked_text(data)
            lengths, signals = _checked_signals(data)
            cuts = np.cumsum(lengths)[:-1]
            meta = dict(zip(data["meta_keys"].tolist(), data["meta_values"].tolist(), strict=True))
            t = cls(
                [str(a) for a in data["actions"].tolist()],
                np.split(signals, cuts),
                data["gravity"],
                _checked_onsets(data["onsets"], lengths),
                data["thresholds"],
                str(data["method"]),
                str(data["feature"]),
                meta,
                float(data["rest_noise"]) if "rest_noise" in data else float("nan"),  # absent in older files
                _saved_settings(data, path),
            )
            if not (np.isnan(t.rest_noise) or 0 <= t.rest_noise <= 100):  # nan: not measured
                raise ValueError(f"rest_noise {t.rest_noise} g out of range")
            if t.feature not in FEATURES:
                raise ValueError(f"unknown feature {t.feature!r}")
        except TemplateFileError:
            raise
        except KeyError as exc:
            raise TemplateFileError(path, f"corrupt template file: no {exc.args[0]!r} array") from None
        except (ValueError, TypeError, IndexError) as exc:
            raise TemplateFileError(path, f"corrupt template file: {exc}") from None
        return t


def _checked_text(data: Mapping[str, np.ndarray]) -> None:
    """The file's strings: unicode (numpy 'U'); the names one per template, the notes in pairs.
    ValueError says what is wrong."""
    for k in ("actions", "method", "feature", "meta_keys", "meta_values"):
        if data[k].dtype.kind != "U" and data[k].size:  # (an empty one has no strings to be)
            raise ValueError(f"{k} must hold unicode strings, not {data[k].dtype}")
    if data["actions"].ndim != 1 or data["meta_keys"].ndim != 1 or data["meta_keys"].shape != data["meta_values"].shape:
        raise ValueError("actions must be one name per template, and meta_keys and meta_values pairs")


def _checked_signals(data: Mapping[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """A template file's lengths (T,) and signals (frames, D), checked: their types and shapes,
    the template count, finite readings a sensor can give. ValueError says what is wrong."""
    if data["lengths"].dtype.kind not in "iu" or str(data["method"]) not in METHODS:
        raise ValueError("lengths must be integers and method one of " + ", ".join(METHODS))
    for k in ("signals", "gravity", "thresholds"):  # complex: astype() dropped the imaginary part, with a warning
        if data[k].dtype.kind not in "iuf":
            raise ValueError(f"{k} must hold real numbers, not {data[k].dtype}")
    if data["lengths"].ndim == 1 and len(data["lengths"]) > MAX_TEMPLATES:  # before building any
        raise ValueError(f"{len(data['lengths'])} templates, at most {MAX_TEMPLATES}")
    lengths = data["lengths"].astype(np.int64)
    signals = data["signals"].astype(np.float64)
    if lengths.ndim == 1 and not len(lengths):
        raise ValueError("no templates")
    # each length at most the data's: their sum in int64 cannot wrap round to the frame count
    if lengths.ndim != 1 or lengths.min() < 1 or lengths.max() > len(signals) or lengths.sum() != len(signals) \
            or signals.ndim != 2:
        raise ValueError("signal lengths do not match the signal data")
    if not np.all(np.isfinite(signals)):
        raise ValueError("non-finite values in the signals")
    if not np.isfinite(data["gravity"]).all() or not (data["thresholds"] >= 0).all():  # inf: never reject
        raise ValueError("gravity must be finite and thresholds >= 0")
    # the recording reader's limit, in g too (imported here: recognition reads no recordings)
    from engine.recording import MAX_ACCEL_G

    peak = max(float(np.abs(signals).max(initial=0.0)), float(np.abs(data["gravity"]).max(initial=0.0)))
    if peak > MAX_ACCEL_G:
        raise ValueError(f"an acceleration of {peak:.6g} g in the signals or gravity, over the {MAX_ACCEL_G:g} g a sensor can read")
    return lengths, signals


def _checked_onsets(onsets: np.ndarray, lengths: np.ndarray) -> np.ndarray:
    """A template file's onsets (T,) as int64, checked: whole frame numbers inside their
    templates. The format gives onsets no type, so 3.0 is frame 3; the int64 cast read 3.7 as 3
    and the text "3" as 3, so fractions and non-numbers are refused before it."""
    if onsets.dtype.kind not in "iuf":
        raise ValueError(f"onsets must hold numbers, not {onsets.dtype}")
    onsets = onsets.reshape(-1)
    if len(onsets) != len(lengths):
        raise ValueError(f"{len(onsets)} onsets for {len(lengths)} templates")
    if not np.all((onsets >= 0) & (onsets < lengths)):  # nan too
        raise ValueError("onset outside its template")
    fractions = onsets[onsets % 1 != 0]
    if len(fractions):
        raise ValueError(f"onset {fractions[0]:g} is not a whole frame number")
    return onsets.astype(np.int64)


def _saved_settings(data: Mapping[str, np.ndarray], path: Path) -> dict[str, object]:
    """The optional `recognizer` key: a JSON object of RecognizerConfig settings (absent in
    older files: none). An unknown name or a wrong value is an error naming the file."""
    if "recognizer" not in data:
        return {}
    try:
        values = read_json(data["recognizer"])
    except ValueError as exc:
        raise ValueError(f"recognizer settings are not JSON ({exc})") from None
    try:
        return check_settings(values, "recognizer settings")
    except RecognizerConfigError as exc:
        raise TemplateFileError(path, str(exc)) from None


def _threshold(scores: np.ndarray, k: float) -> float:
    if len(scores) == 0 or not np.isfinite(k):
        return float("inf")
    mean, std, top = float(scores.mean()), float(scores.std()), float(scores.max())
    return max(mean + k * std, REJECT_RATIO * top, REJECT_FLOOR_G)
