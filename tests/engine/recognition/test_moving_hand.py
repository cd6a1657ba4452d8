"""Two hands (two sensors): a decision names an action of the hand that moved clearly the most
since the onset (rules.MOVING_HAND_RATIO), not the other hand's because of how that hand sits."""

from __future__ import annotations

import numpy as np
import pytest

from engine.recognition import DualBufferRecognizer, Templates, rules
from tests.engine.recognition.test_dual_buffer import bump, rest
from tests.engine.recognition.test_other_hand import hands, make_templates


@pytest.fixture(scope="module")
def templates() -> Templates:
    return make_templates()  # hook_r moves sensor 0 along x, hook_l sensor 1 along x


def first_decision(templates: Templates, frames: np.ndarray) -> str | None:
    """The first start's action, without rejection: the synthetic templates' thresholds are
    tight enough to reject a punch thrown along another axis, and the rule is about which hand."""
    rec = DualBufferRecognizer(templates, noise_g=0.5, reject=False)
    for f in frames:
        for e in rec.push(f):
            if e["event"] == "start":
                return e["action"]
    return None


def right_punch_other_axis(left_amp: float, right_amp: float = 3.0) -> np.ndarray:
    """The right glove punches along y (its templates go along x) while the left glove moves
    along x, as the left templates do, but less."""
    right = np.vstack([rest(30), bump(1, right_amp), rest(30)])
    left = np.vstack([rest(30), bump(0, left_amp), rest(30)])
    return hands(right, left)


def test_the_hand_that_moved_most_names_the_action(templates, monkeypatch):
    frames = right_punch_other_axis(left_amp=0.8)
    assert first_decision(templates, frames) == "hook_r"
    monkeypatch.setattr(rules, "MOVING_HAND_RATIO", 0.0)  # the rule off: the DTW alone
    assert first_decision(templates, frames) == "hook_l"


def test_with_both_hands_moving_comparably_the_dtw_decides(templates, monkeypatch):
    frames = right_punch_other_axis(left_amp=1.6, right_amp=2.0)  # the left glove's peak is over half the right's
    decided = first_decision(templates, frames)
    monkeypatch.setattr(rules, "MOVING_HAND_RATIO", 0.0)
    assert decided == first_decision(templates, frames) == "hook_l"


def test_the_per_sensor_peaks_restart_with_each_motion(templates):
    def peaks_after(frames: np.ndarray) -> list[float]:
        rec = DualBufferRecognizer(templates, noise_g=0.5)
        for f in frames:
            rec.push(f)
        return rec._sensor_peak

    strong, gentle = right_punch_other_axis(left_amp=2.5), right_punch_other_axis(left_amp=0.8)
    assert peaks_after(np.vstack([strong, gentle])) == pytest.approx(peaks_after(gentle))
    assert peaks_after(strong)[1] > 2 * peaks_after(gentle)[1]  # the first motion's left peak is gone


def test_one_sensor_is_never_masked():
    rng = np.random.default_rng(0)
    trials = {a: [np.vstack([rest(5), bump(axis, 3.0), rest(5)]) + rng.normal(0, 0.02, (34, 3)) for _ in range(3)]
              for a, axis in (("jab", 0), ("hook", 1))}
    rec = DualBufferRecognizer(Templates.from_trials(trials), noise_g=0.5)
    scores = np.arange(len(rec.template_lengths), dtype=float)
    assert rec._moving_hand(scores) is scores
