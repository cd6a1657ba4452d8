"""`usable_trials` (`keep="usable"`, what `train` keeps of its 5 trials): every trial that makes a
good template, not the 3 most representative."""

import numpy as np
import pytest

from engine.recognition.dtw import dtw_distance
from engine.recognition.templates import (
    MIN_USABLE,
    Templates,
    pairwise_distances,
    representative_trials,
    usable_trials,
)

G = np.array([0.0, 0.0, 1.0])


def rest(n: int) -> np.ndarray:
    return np.tile(G, (n, 1))


def bump(axis: int, amp: float, n: int = 24, rng: np.random.Generator | None = None) -> np.ndarray:
    x = np.tile(G, (n, 1))
    x[:, axis] += amp * np.sin(np.linspace(0, np.pi, n))
    return x if rng is None else x + rng.normal(0.0, 0.05, x.shape)


def trial(axis: int, amp: float, rng: np.random.Generator, n: int = 24) -> np.ndarray:
    return np.vstack([rest(10), bump(axis, amp, n, rng), rest(10)])


def same(a: np.ndarray, b: np.ndarray) -> bool:
    return a.shape == b.shape and np.array_equal(a, b)


def test_pairwise_distances_are_the_dtw_distance_of_every_two_motions():
    rng = np.random.default_rng(0)
    motions = [rng.normal(size=(int(rng.integers(5, 60)), 6)) for _ in range(6)]
    d = pairwise_distances(motions)
    want = np.array([[dtw_distance(a, b) if i != j else 0.0 for j, b in enumerate(motions)] for i, a in enumerate(motions)])
    np.testing.assert_allclose(d, want, rtol=1e-12, atol=1e-15)
    assert np.array_equal(d, d.T)


def look_alike(rng: np.random.Generator) -> np.ndarray:
    """Recorded as a jab (axis 0), moved mostly as an uppercut (axis 2)."""
    x = trial(2, 2.1, rng)
    x[10:34, 0] += 0.9 * np.sin(np.linspace(0, np.pi, 24))
    return x


def test_usable_trials_keep_every_good_trial_and_drop_the_cut_off_and_the_warm_up():
    rng = np.random.default_rng(1)
    jabs = [trial(0, 3.0, rng) for _ in range(4)]
    cut_off = np.vstack([rest(10), bump(0, 3.0)[:6]])  # the recording window closed early
    warm_up = np.vstack([rest(10), bump(1, 2.0, 40), rest(10)])  # a different, slower motion
    kept = usable_trials({"jab": [warm_up, jabs[0], cut_off, jabs[1], jabs[2], jabs[3]]})["jab"]
    assert len(kept) == 4 and all(same(k, j) for k, j in zip(kept, jabs, strict=True))  # in order
    assert len(representative_trials(jabs, keep=3)) == 3  # the older rule: 3 of them, whatever they are
    assert len(Templates.from_trials({"jab": [warm_up, *jabs, cut_off]}, keep="usable")) == 4


def test_a_trial_that_looks_like_another_action_is_dropped(monkeypatch):
    """The confusable rule alone (the odd-one rule off): a jab trial nearer the uppercuts than
    its own action's trials would draw uppercuts to the jab."""
    import engine.recognition.templates as templates

    rng = np.random.default_rng(1)
    jabs = [trial(0, 3.0, rng) for _ in range(4)]
    uppers = [trial(2, 3.0, rng) for _ in range(4)]
    recorded = {"jab": [jabs[0], look_alike(rng), *jabs[1:]], "upper": uppers}
    monkeypatch.setattr(templates, "ODD_RATIO", np.inf)
    kept = usable_trials(recorded)
    assert [len(kept["jab"]), len(kept["upper"])] == [4, 4]
    assert all(same(k, j) for k, j in zip(kept["jab"], jabs, strict=True))
    monkeypatch.setattr(templates, "CONFUSABLE_MARGIN", 0.0)
    assert len(usable_trials(recorded)["jab"]) == 5  # with neither rule the look-alike stays


def test_usable_trials_leave_at_least_two_of_an_action(monkeypatch):
    """Both rules compare with the action's median, so at most half of its trials go; the
    look-alike rule skips an action of 2 trials (it would drop one of them)."""
    import engine.recognition.templates as templates

    rng = np.random.default_rng(2)
    good = trial(0, 3.0, rng)
    warm_up = np.vstack([rest(10), bump(1, 2.0, 40), rest(10)])
    assert len(usable_trials({"jab": [good, trial(0, 3.0, rng), warm_up]})["jab"]) == 2
    assert len(usable_trials({"jab": [good, warm_up]})["jab"]) == MIN_USABLE  # both kept
    assert len(usable_trials({"jab": [good]})["jab"]) == 1
    monkeypatch.setattr(templates, "ODD_RATIO", np.inf)
    uppers = {"upper": [trial(2, 3.0, rng) for _ in range(4)]}
    assert len(usable_trials({"jab": [good, look_alike(rng)], **uppers})["jab"]) == 2  # of 2, none goes
    assert len(usable_trials({"jab": [good, trial(0, 3.0, rng), look_alike(rng)], **uppers})["jab"]) == 2


def test_moves_kept_from_an_earlier_session_count_as_other_actions(monkeypatch):
    """Retraining one move (`train --actions jab`): its trials are compared with the moves the
    player keeps, given as `others` (never dropped themselves; another D is ignored)."""
    import engine.recognition.templates as templates

    monkeypatch.setattr(templates, "ODD_RATIO", np.inf)
    rng = np.random.default_rng(1)
    jabs = [trial(0, 3.0, rng) for _ in range(4)]
    recorded = {"jab": [jabs[0], look_alike(rng), *jabs[1:]]}
    uppers = [trial(2, 3.0, rng) for _ in range(4)]
    assert len(usable_trials(recorded)["jab"]) == 5  # nothing to look like
    kept = usable_trials(recorded, others={"upper": uppers, "jab": uppers, "two_hands": [np.zeros((30, 6))]})
    assert list(kept) == ["jab"] and all(same(k, j) for k, j in zip(kept["jab"], jabs, strict=True))
    with pytest.raises(ValueError, match="non-finite"):
        usable_trials({"jab": [np.full((30, 3), np.nan)]})


def test_keep_is_a_count_or_usable():
    rng = np.random.default_rng(3)
    recorded = {"jab": [trial(0, 3.0, rng) for _ in range(3)]}
    with pytest.raises(ValueError, match="usable"):
        Templates.from_trials(recorded, keep="best")
    with pytest.raises(ValueError, match="usable"):
        Templates.from_trials(recorded, keep=0)


@pytest.mark.parametrize("keep", [2.5, float("nan"), float("inf"), True, "3", "USABLE", [3], -1])
def test_keep_is_a_whole_count(keep):
    """keep=2.5 kept 2 trials, nan and inf kept every one and True kept 1, as if asked; a list
    was a TypeError. Each is a ValueError saying what keep takes; a numpy integer is a count."""
    rng = np.random.default_rng(3)
    recorded = {"jab": [trial(0, 3.0, rng) for _ in range(3)]}
    with pytest.raises(ValueError, match="keep must be"):
        Templates.from_trials(recorded, keep=keep)
    assert len(Templates.from_trials(recorded, keep=np.int64(2))) == 2


def test_two_actions_of_one_name_are_refused_not_merged():
    """{1: ..., "1": ...}: both are action "1", and the second one's trials replaced the first's."""
    rng = np.random.default_rng(4)
    jabs, uppers = [trial(0, 3.0, rng) for _ in range(3)], [trial(2, 3.0, rng) for _ in range(3)]
    for build in (Templates.from_trials, usable_trials):
        with pytest.raises(ValueError, match="action '1' given twice"):
            build({1: jabs, "1": uppers})
