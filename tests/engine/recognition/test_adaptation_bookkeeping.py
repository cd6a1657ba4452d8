"""Template adaptation edits the recognizer's templates in place (`_adopt`: the adopted motion at
its action's slot, the oldest dropped, the DTW moving a column or two); it must decide exactly
as the bookkeeping it replaced, which rebuilt the whole sorted template set on every adoption.
That old code is kept here, verbatim, as the reference: both run over the same streams (the
game's virtual players, and real uWave gestures when ../shared/data is there) and must give the
same events, scores included, and the same templates after every adoption."""

from __future__ import annotations

import numpy as np
import pytest

from engine.recognition import DualBufferRecognizer, Templates, dtw
from engine.recognition.dual_buffer import ADAPT_MARGIN


class RebuildingRecognizer(DualBufferRecognizer):
    """The adaptation as it was before the in-place bookkeeping (main at fafc147)."""

    adoptions = 0
    replacements = 0  # adoptions that dropped the action's oldest adapted template

    def _adapt(self) -> None:
        n = self._stop_n if self._stopped else self.dtw.n
        if n < 2:
            return
        scores = self._stop_scores if self._stopped else self.dtw.closed_scores()
        mine = self._tmpl_action == self.action
        best, other = float(scores[mine].min()), float(scores[~mine].min(initial=np.inf))
        k = int(np.flatnonzero(mine)[np.argmin(scores[mine])])
        if not best < (1.0 - ADAPT_MARGIN) * other or best > self.thresholds[k]:
            return
        kept = self._adapted.setdefault(self.action, [])
        kept.append((self._motion[:n].copy(), self._peaks(self._acts[:n])))
        self.replacements += len(kept) > self.adapt
        del kept[: -self.adapt]
        self.adoptions += 1
        self._rebuild()

    def _rebuild(self) -> None:
        cut, acts, thr, peaks = self._base
        extra = [(motion, a, peak) for a, kept in self._adapted.items() for motion, peak in kept]
        new_acts = np.array([a for _, a, _ in extra], dtype=acts.dtype)
        loosest = np.maximum.reduceat(thr, self._base_starts)
        acts = np.concatenate([acts, new_acts])
        thr = np.concatenate([thr, loosest[new_acts]])
        peaks = np.concatenate([peaks, [peak for _, _, peak in extra]]) if extra else peaks
        cut = [*cut, *(motion for motion, _, _ in extra)]
        order = np.argsort(acts, kind="stable")
        self._is_adapted = order >= len(self._base[1])
        self._is_copy = np.r_[self._base_copy, np.zeros(len(extra), dtype=bool)][order]  # tilted copies (tilt.py)
        self._not_copy = ~self._is_copy
        self._tmpl_action = acts[order]
        self._action_starts = np.flatnonzero(np.r_[True, np.diff(self._tmpl_action) != 0])
        self._action_ends = np.r_[self._action_starts[1:], len(order)]
        self.thresholds = thr[order]
        self._peak_act = peaks[order]
        self._action_bar = np.minimum.reduceat(self._peak_act[:, 0], self._action_starts)
        cut = [cut[k] for k in order]
        self.template_lengths = np.array([len(c) for c in cut])
        self.dtw.update_templates(cut)
        self._stop_scores = np.empty(len(cut))

    def forget_adaptation(self) -> None:
        if self._adapted:
            self._adapted = {}
            self._rebuild()


def assert_same_templates(new: DualBufferRecognizer, ref: RebuildingRecognizer) -> None:
    for name in ("_tmpl_action", "_action_starts", "_action_ends", "thresholds", "_peak_act", "template_lengths",
                 "_is_adapted", "_is_copy", "_action_bar"):
        np.testing.assert_array_equal(getattr(new, name), getattr(ref, name), err_msg=name)
    assert new.dtw.T == ref.dtw.T and len(new._stop_scores) == len(ref._stop_scores)
    np.testing.assert_array_equal(new.dtw.lengths, ref.dtw.lengths)
    for a, b in zip(new.dtw.sources, ref.dtw.sources, strict=True):
        np.testing.assert_array_equal(a, b)
    L = min(new.dtw.L, ref.dtw.L)  # native keeps its padding after a removal: zeros past each end
    np.testing.assert_array_equal(new.dtw.tmpl[:L], ref.dtw.tmpl[:L])


def play_both(templates: Templates, frames: np.ndarray, method: str, **kw) -> tuple[list, list, RebuildingRecognizer]:
    """Both recognizers over the frames: their events (one list each) and the reference;
    the templates are compared after every frame that adopted a motion."""
    new = DualBufferRecognizer(templates, dtw_method=method, **kw)
    ref = RebuildingRecognizer(templates, dtw_method=method, **kw)
    got, want = [], []
    for i, f in enumerate(frames):
        before = ref.adoptions
        got += new.push(f, t=i / 60)
        want += ref.push(f, t=i / 60)
        if ref.adoptions != before:
            assert_same_templates(new, ref)
        if i == len(frames) * 2 // 3:  # a new player, then adapting again from the trained set
            new.forget_adaptation()
            ref.forget_adaptation()
            assert_same_templates(new, ref)
    assert_same_templates(new, ref)
    return got, want, ref


def methods() -> list[str]:
    return ["scan", *(["native"] if dtw.native_available() else [])]


def virtual_player_frames(profile: str, seed: int, n: int) -> np.ndarray:
    """What the attract mode's keyboard source plays: random moves with rests, 60 Hz, (n, 6)."""
    from engine.sensors import open_source

    t = [0.0]
    src = open_source(f"keyboard://?auto=1&profile={profile}&seed={seed}", clock=lambda: t[0])
    out = []
    while len(out) < n:
        out += [s.accel.reshape(-1) for s in src.poll()]
        t[0] += 1 / 60
    return np.array(out[:n])


@pytest.fixture(scope="module")
def game_templates() -> Templates:
    from tools.scripted_match import default_templates

    return Templates.load(default_templates())


@pytest.mark.parametrize("method", methods())
@pytest.mark.parametrize("profile", ["experienced", "novice"])
def test_in_place_adaptation_decides_exactly_as_rebuilding_on_the_game_stream(game_templates, profile, method):
    frames = virtual_player_frames(profile, seed=3, n=5400)
    got, want, ref = play_both(game_templates, frames, method)
    assert got == want
    assert sum(e["event"] == "start" for e in got) > 30
    # the stream exercised both paths: a template added, and (experienced) the oldest replaced
    assert ref.adoptions >= 3 and (profile == "novice" or ref.replacements >= 10), (ref.adoptions, ref.replacements)


@pytest.mark.parametrize("method", methods())
def test_in_place_adaptation_decides_exactly_as_rebuilding_on_uwave(shared_data, method):
    """Real gestures: uWave user 1, day-1 templates, days 2-7 played one after another with
    rests between (a template drift adaptation follows, and long motions: templates longer
    than every trained one)."""
    from tools.trial_files import load_trials_dir

    root = shared_data / "uwave" / "U1"
    templates = Templates.from_trials(load_trials_dir(root, "d1-r0[1-3].csv"))
    tests = load_trials_dir(root, "d[2-7]-*.csv")
    rng = np.random.default_rng(0)
    trials = [t for ts in tests.values() for t in ts[::3]]
    rng.shuffle(trials)
    g = trials[0][0]
    rest = np.tile(g, (40, 1)) + rng.normal(0, 0.01, (40, len(g)))
    frames = np.vstack([np.vstack([rest, t]) for t in trials])
    got, want, ref = play_both(templates, frames, method, noise_g=0.3)
    assert got == want
    assert ref.adoptions >= 20 and ref.replacements >= 3, (ref.adoptions, ref.replacements)


def test_lowering_adapt_at_run_time_keeps_the_newest(game_templates):
    """`adapt` lowered after adoptions: the next adoption keeps the newest `adapt` of that action."""
    frames = virtual_player_frames("experienced", seed=5, n=3600)
    new = DualBufferRecognizer(game_templates)
    ref = RebuildingRecognizer(game_templates)
    got, want = [], []
    for i, f in enumerate(frames):
        if i == len(frames) // 2:
            new.adapt = ref.adapt = 1
        got += new.push(f)
        want += ref.push(f)
    assert got == want
    assert_same_templates(new, ref)
    assert max(len(k) for k in new._adapted.values()) == 1


def test_replace_template_scores_as_a_dtw_built_on_the_new_list():
    rng = np.random.default_rng(4)

    def make(n: int, longest: int = 30) -> list[np.ndarray]:
        return [np.cumsum(rng.normal(0, 0.3, (int(rng.integers(3, longest)), 6)), axis=0) for _ in range(n)]

    query = np.cumsum(rng.normal(0, 0.3, (25, 6)), axis=0)
    for method in methods():
        current = make(10)
        d = dtw.IncrementalDTW(current, method=method, min_progress=0.5)
        for step in range(20):
            drop, at = (int(i) for i in rng.integers(0, len(current), 2))
            t = make(1, 60 if step == 7 else 30)[0]  # once longer than every template
            del current[drop]
            current.insert(at, t)
            d.push(query[0])
            d.replace_template(drop, t, at)
            ref = dtw.IncrementalDTW(current, method=method, min_progress=0.5)
            assert d.n == 0 and d.sources == current
            np.testing.assert_array_equal(d.lengths, ref.lengths)
            for f in query:
                np.testing.assert_array_equal(d.push(f), ref.push(f))
            np.testing.assert_array_equal(d.closed_scores(), ref.closed_scores())
        with pytest.raises(ValueError):
            d.replace_template(d.T, current[0], 0)
        with pytest.raises(ValueError):
            d.replace_template(0, np.zeros((3, 5)), 0)
