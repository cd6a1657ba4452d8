"""Two hands (two sensors, D = 6), a character playing a clip longer than the punch: a decided
motion that the `complete` rule ends while the clip plays goes into the discard the clip's end
would have begun (HANDOVER_OVER, docs/recognition.md, twenty-seventh round), so the punching hand's
return starts nothing, and the other hand's launch ends that discard."""

from __future__ import annotations

import numpy as np
import pytest

from engine.recognition import DualBufferRecognizer, rules
from tests.engine.recognition.test_dual_buffer import bump, rest
from tests.engine.recognition.test_other_hand import hands, make_templates, play

CLIP = 40  # frames from the start: the clip outlasts the punch, whose motion ends `complete` first
GATE = 0.3


def bouncing(right_return: bool, left_at: int | None = None, left_g: float = 3.0) -> np.ndarray:
    """A right punch (frames 40-63) whose glove then bounces at ~0.4 g (over the gate: the motion
    ends by the `complete` rule at frame 66, no null signal), with the hand's return (a 2 g swing
    the same way as the punch, frames 68-91) or not, and a left punch of `left_g` at `left_at`."""
    right = np.vstack([rest(40), bump(0, 3.0), rest(80)])
    right[64:110, 1] += 0.4 + 0.05 * np.sin(np.arange(46) * 0.7)
    if right_return:
        right[68:92, 0] += bump(0, 2.0)[:, 0]
    left = rest(len(right))
    if left_at is not None:
        left[left_at : left_at + 24] = bump(0, left_g)
    return hands(right, left)


def recognizer(templates, character: bool) -> DualBufferRecognizer:
    rec = DualBufferRecognizer(templates, noise_g=GATE)
    if character:
        rec.character_finished()  # a caller with a character (nothing to finish yet)
    return rec


def starts(events: list[dict]) -> list[tuple[str, int]]:
    return [(e["action"], e["frame"]) for e in events if e["event"] == "start"]


@pytest.fixture(scope="module")
def templates():
    return make_templates()


def test_the_punching_hands_return_after_a_complete_end_starts_nothing_while_the_clip_plays(templates):
    frames = bouncing(right_return=True)
    events, states = play(recognizer(templates, character=True), frames, CLIP)
    ends = [e for e in events if e["event"] == "end"]
    assert ends[0]["reason"] == "complete" and ends[0]["frame"] < 46 + CLIP  # before the clip's end
    assert states[ends[0]["frame"]] == "discard"
    assert starts(events) == [("hook_r", 46)]
    # without a character (a caller that only pushes frames) the complete end goes back to idle as
    # before, and the return starts the punching hand's action again
    events, states = play(recognizer(templates, character=False), frames, 1 << 30)
    assert [a for a, _ in starts(events)] == ["hook_r", "hook_r"]
    assert "discard" not in states


def test_the_other_hands_launch_ends_that_discard_and_starts(templates):
    events, states = play(recognizer(templates, character=True), bouncing(False, left_at=70), CLIP)
    assert "discard" in states[66:70]
    (first, _), (second, at) = starts(events)
    assert (first, second) == ("hook_r", "hook_l") and at - 70 <= 10


def test_an_action_without_another_hand_does_not_hand_over(templates, monkeypatch):
    # no sensor counts as the other hand: the complete end goes back to idle, as without a character
    monkeypatch.setattr(rules, "OTHER_HAND_SHARE", 0.0)
    _, states = play(recognizer(templates, character=True), bouncing(True), CLIP)
    assert "discard" not in states


def test_a_launch_under_half_the_punchs_peak_ends_the_handover_once_it_outmoves_the_punching_hand(templates, monkeypatch):
    # a 1.2 g left move: under OTHER_HAND_RATIO of the right punch's 3 g, over HANDOVER_OVER x the
    # right glove's 0.4 g bounce: it ends the discard the complete end began ...
    frames = bouncing(False, left_at=70, left_g=1.2)
    _, states = play(recognizer(templates, character=True), frames, CLIP)
    quick = states.index("discard", 66)
    quick_end = next(i for i in range(quick, len(states)) if states[i] != "discard")
    assert quick_end <= 76
    # ... and without HANDOVER_OVER it does not: the discard runs on
    monkeypatch.setattr(rules, "HANDOVER_OVER", float("inf"))
    _, states = play(recognizer(templates, character=True), frames, CLIP)
    assert states[quick_end] == "discard"
