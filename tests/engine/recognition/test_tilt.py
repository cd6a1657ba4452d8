"""Tilted copies of the templates (engine/recognition/tilt.py): a grip the trials did not have."""

from __future__ import annotations

import numpy as np
import pytest

from engine.recognition import DualBufferRecognizer, RecognizerConfig, Templates
from engine.recognition.config import RecognizerConfigError
from engine.recognition.templates import activity
from engine.recognition.tilt import DIRECTIONS, MAX_COPIED, TILT_DEG, _turns, tilted_copies

G = np.array([0.0, 0.0, 1.0])


def rest(n: int) -> np.ndarray:
    return np.tile(G, (n, 1))


def bump(axis: int, amp: float = 3.0, n: int = 24) -> np.ndarray:
    x = rest(n)
    x[:, axis] += amp * np.sin(np.linspace(0, 2 * np.pi, n))
    return x


@pytest.fixture(scope="module")
def templates() -> Templates:
    rng = np.random.default_rng(0)
    return Templates.from_trials(
        {name: [np.vstack([rest(5), bump(axis) + rng.normal(0, 0.02, (24, 3)), rest(5)]) for _ in range(3)]
         for name, axis in (("jab", 0), ("upper", 2))}
    )


def decided(rec: DualBufferRecognizer, frames: np.ndarray) -> tuple[str | None, str | None]:
    """(first, final) action of the one motion in `frames`."""
    names = [e["action"] for f in frames for e in rec.push(f) if e["event"] in ("start", "switch")]
    return (names[0], names[-1]) if names else (None, None)


@pytest.mark.parametrize("axis", [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
def test_a_grip_turned_20_degrees_is_recognized_with_the_copies_and_rejected_without(templates, axis):
    """The whole recording, the rest included, turned 20 degrees about an axis across gravity: the
    player holds the sensor otherwise than in the trials. No trained template fits it; their
    copies turned 10 degrees do, from the first decision on."""
    turn = _turns(np.array(axis), np.radians(20.0))
    for name, k in (("jab", 0), ("upper", 2)):
        played = np.vstack([rest(10), bump(k), rest(20)]) @ turn.T
        assert decided(DualBufferRecognizer(templates, adapt=0, tilt_deg=0), played) == (None, None)
        assert decided(DualBufferRecognizer(templates, adapt=0), played) == (name, name)


def test_copies_keep_their_source_activity_threshold_and_action(templates):
    out, source = tilted_copies(templates, TILT_DEG)
    n, per = len(templates), len(DIRECTIONS)
    assert len(out) == (1 + per) * n and source.tolist() == list(range(n)) + [k for k in range(n) for _ in range(per)]
    for c in range(n, len(out)):
        k = source[c]
        assert out.actions[c] == templates.actions[k]
        assert out.thresholds[c] == templates.thresholds[k] and out.onsets[c] == templates.onsets[k]
        # the same motion, turned: its activity |a - g| (the energy bars) is the source's own
        np.testing.assert_allclose(activity(out.signals[c], out.gravity[c]),
                                   activity(templates.signals[k], templates.gravity[k]), atol=1e-12)
        cos = out.gravity[c] @ templates.gravity[k] / np.linalg.norm(out.gravity[c]) / np.linalg.norm(templates.gravity[k])
        assert np.degrees(np.arccos(np.clip(cos, -1.0, 1.0))) == pytest.approx(TILT_DEG)
    # a template's copies lie in as many directions around it
    assert len({tuple(np.round(g, 9)) for g in out.gravity[n : n + per]}) == per


def test_no_copies_at_0_degrees_for_the_grip_feature_or_about_no_gravity(templates):
    assert tilted_copies(templates, 0.0)[0] is templates
    grip = Templates(templates.actions, templates.signals, templates.gravity, templates.onsets,
                     templates.thresholds, feature="grip")
    assert len(tilted_copies(grip, TILT_DEG)[0]) == len(grip)  # turning changes no grip feature
    # two sensors, the second without a gravity (0 g): it stays as it is in every copy
    two = Templates(["a"], [np.hstack([bump(0), np.zeros((24, 3))])], [np.r_[G, 0.0, 0.0, 0.0]], [0], [1.0])
    out, _ = tilted_copies(two, TILT_DEG)
    assert len(out) == 1 + len(DIRECTIONS) and np.isfinite(np.vstack(out.signals)).all()
    assert all(np.array_equal(s[:, 3:], np.zeros((24, 3))) for s in out.signals)
    assert not any(np.array_equal(s[:, :3], bump(0)) for s in out.signals[1:])
    # over MAX_COPIED templates: none (each copy costs a DTW row every frame)
    many = Templates(["a"] * (MAX_COPIED + 1), [bump(0)] * (MAX_COPIED + 1), np.tile(G, (MAX_COPIED + 1, 1)),
                     np.zeros(MAX_COPIED + 1, dtype=int), np.ones(MAX_COPIED + 1))
    assert len(tilted_copies(many, TILT_DEG)[0]) == MAX_COPIED + 1
    assert len(tilted_copies(Templates(many.actions[1:], many.signals[1:], many.gravity[1:], many.onsets[1:],
                                       many.thresholds[1:]), TILT_DEG)[0]) == MAX_COPIED * (1 + len(DIRECTIONS))
    # no sensor with a gravity: nothing to turn, no copies (they would be the template again)
    flat = Templates(["a"], [bump(0) - G], [np.zeros(3)], [0], [1.0])
    assert len(tilted_copies(flat, TILT_DEG)[0]) == 1


def test_copies_give_the_first_decision_only_where_no_other_template_fits(templates):
    rec = DualBufferRecognizer(templates)
    copy = int(np.flatnonzero(rec._is_copy)[0])
    trained = int(np.flatnonzero(~rec._is_copy)[0])
    scores = rec.thresholds * 2.0  # nothing fits
    scores[copy] = 0.0
    assert np.array_equal(rec._first_usable(scores), scores)  # the copy may decide
    scores[trained] = rec.thresholds[trained] * 0.5  # a trained template fits: copies left out
    usable = rec._first_usable(scores)
    assert np.isinf(usable[rec._is_copy]).all() and np.array_equal(usable[~rec._is_copy], scores[~rec._is_copy])


@pytest.mark.parametrize("value", [-1.0, 45.5, float("nan"), float("inf")])
def test_tilt_outside_0_to_45_degrees_is_refused(templates, value):
    with pytest.raises(RecognizerConfigError, match="tilt_deg"):
        RecognizerConfig(tilt_deg=value)
    with pytest.raises(ValueError, match="tilt_deg"):
        DualBufferRecognizer(templates, tilt_deg=value)


def test_a_template_the_moving_hand_rules_out_does_not_leave_the_copies_out():
    """Two sensors: the right hand (sensor 0) moves alone, so the left hand's action is ruled out
    (`_moving_hand`). That its trained templates fit must not leave out the right hand's copies,
    the only templates of a usable action that fit: the first decision is theirs."""
    g2 = np.r_[G, G]
    rng = np.random.default_rng(0)

    def hand(col: int) -> np.ndarray:
        x = np.tile(g2, (24, 1))
        x[:, col] += 3.0 * np.sin(np.linspace(0, 2 * np.pi, 24))
        return np.vstack([np.tile(g2, (5, 1)), x + rng.normal(0, 0.02, (24, 6)), np.tile(g2, (5, 1))])

    tm = Templates.from_trials({"right": [hand(0) for _ in range(3)], "left": [hand(3) for _ in range(3)]})
    rec = DualBufferRecognizer(tm, adapt=0)
    a_left = rec.action_names.index("left")
    left = rec._tmpl_action == a_left
    assert rec._barely[a_left, 0] and not rec._barely[1 - a_left, 0]  # the left barely moves sensor 0
    fitting = (left & ~rec._is_copy) | (~left & rec._is_copy)  # the left's trained ones and the right's copies
    real_push = rec.dtw.push
    rec.dtw.push = lambda f: np.where(fitting, 0.5, 3.0) * rec.thresholds + 0.0 * real_push(f)
    frames = np.vstack([np.tile(g2, (10, 1)), hand(0), np.tile(g2, (20, 1))])  # sensor 0 alone moves
    assert decided(rec, frames)[0] == "right"


def test_an_action_of_one_trial_does_not_keep_the_copies_out(templates):
    """A template of one trial has no threshold (inf: nothing to measure its spread on), so it
    'fit' every motion and kept every other action's copies out of the first decision: a jab held
    20 degrees otherwise was missed once a one-trial action joined. Such a template fits where the
    loosest known threshold would take it."""
    sway = rest(34)
    sway[5:29, 1] += np.sin(np.linspace(0, np.pi, 24))
    rng = np.random.default_rng(0)
    trials = {name: [np.vstack([rest(5), bump(axis) + rng.normal(0, 0.02, (24, 3)), rest(5)]) for _ in range(3)]
              for name, axis in (("jab", 0), ("upper", 2))}
    with_sway = Templates.from_trials({**trials, "sway": [sway]})
    assert np.isinf(with_sway.thresholds[-1])
    turn = _turns(np.array([1.0, 0.0, 0.0]), np.radians(20.0))
    played = np.vstack([rest(10), bump(0), rest(20)]) @ turn.T
    assert decided(DualBufferRecognizer(with_sway, adapt=0), played) == ("jab", "jab")
