"""Two hands (two sensors, D = 6): the discard after a punch ignores that hand's return, not the
other hand's punch (OTHER_HAND_*: a combo)."""

from __future__ import annotations

import numpy as np
import pytest

from engine.recognition import DualBufferRecognizer, Templates, rules
from tests.engine.recognition.test_dual_buffer import G, bump, rest  # one sensor's frames


def hands(right: np.ndarray, left: np.ndarray) -> np.ndarray:
    return np.hstack([right, left])


def make_templates() -> Templates:
    rng = np.random.default_rng(0)

    def trials(right_moves: bool) -> list[np.ndarray]:
        out = []
        for _ in range(3):
            m = np.vstack([rest(5), bump(0, 3.0), rest(5)])
            m = m + rng.normal(0, 0.02, m.shape)
            still = rest(len(m)) + rng.normal(0, 0.02, m.shape)
            out.append(hands(m, still) if right_moves else hands(still, m))
        return out

    return Templates.from_trials({"hook_r": trials(True), "hook_l": trials(False)})


def combo(gap: int) -> tuple[np.ndarray, int]:
    """A right punch, then `gap` frames after its beginning a left one, and rest; (frames, the
    left punch's first frame)."""
    right = np.vstack([rest(40), bump(0, 3.0), rest(60)])
    left = rest(len(right))
    at = 40 + gap
    left[at : at + 24] = bump(0, 3.0)
    return hands(right, left), at


def play(rec: DualBufferRecognizer, frames: np.ndarray, clip: int) -> tuple[list[dict], list[str]]:
    """Events and states, with a character whose clip ends `clip` frames after each start."""
    events, states, clip_end = [], [], None
    for i, f in enumerate(frames):
        evs = rec.push(f)
        events += evs
        if any(e["event"] == "start" for e in evs):
            clip_end = i + clip
        if clip_end is not None and i >= clip_end:
            rec.character_finished()
            clip_end = None
        states.append(rec.state)
    return events, states


def test_the_hand_shares_name_the_sensor_each_action_moves(templates):
    rec = DualBufferRecognizer(templates, noise_g=0.5)
    share = {a: rec._hand_share[i] for i, a in enumerate(rec.action_names)}
    assert share["hook_r"][0] > 0.8 and share["hook_l"][1] > 0.8


def test_the_other_hands_punch_ends_the_discard_and_starts(templates):
    frames, left_at = combo(gap=22)  # the left punch begins while the right one is discarded
    events, states = play(DualBufferRecognizer(templates, noise_g=0.5), frames, clip=8)
    starts = [(e["action"], e["frame"]) for e in events if e["event"] == "start"]
    assert [a for a, _ in starts] == ["hook_r", "hook_l"]
    assert starts[1][1] - left_at <= 10  # within the main buffer and a few frames of the launch
    assert "discard" in states[40:left_at]


def test_without_the_rule_the_combos_second_punch_is_lost_or_late(templates, monkeypatch):
    monkeypatch.setattr(rules, "OTHER_HAND_SHARE", 0.0)  # no sensor counts as the other hand
    frames, left_at = combo(gap=22)
    events, _ = play(DualBufferRecognizer(templates, noise_g=0.5), frames, clip=8)
    left = [e["frame"] for e in events if e["event"] == "start" and e["action"] == "hook_l"]
    assert not left or left[0] - left_at > 10


def right_swinging_on(left_g: float) -> np.ndarray:
    """A right punch whose hand swings on at 2 g after it (the discard holds while it does), and a
    left move of `left_g` in that discard."""
    right = np.vstack([rest(40), bump(0, 3.0)[:12], np.tile(G + [2.0, 0, 0], (40, 1)), rest(30)])
    right[52:92:2, 0] -= 4.0
    left = rest(len(right))
    left[58:82] = bump(0, left_g)
    return hands(right, left)


@pytest.mark.parametrize("bar", ["ratio", "gate"])
def test_a_smaller_move_of_the_other_hand_does_not_end_the_discard(templates, monkeypatch, bar):
    # The left hand moves while the right punch (3 g) is discarded, under one of the two bars:
    # "ratio", 1.0 g, over the 0.5 g gate but under OTHER_HAND_RATIO of the right punch's peak;
    # "gate", 1.6 g, over that share of the peak but under a 1.8 g gate (the right hand swings on
    # over it, so the discard holds). Everything happens as with the rule off.
    if bar == "ratio":
        frames, left_at = combo(gap=22)
        frames[left_at : left_at + 24, 3:] = bump(0, 1.0)
        noise_g, clip = 0.5, 8
    else:
        frames, noise_g, clip = right_swinging_on(1.6), 1.8, 4
    events, states = play(DualBufferRecognizer(templates, noise_g=noise_g), frames, clip)
    assert [e["action"] for e in events if e["event"] == "start"][:1] == ["hook_r"]
    assert states[60:70] == ["discard"] * 10
    monkeypatch.setattr(rules, "OTHER_HAND_SHARE", 0.0)
    assert play(DualBufferRecognizer(templates, noise_g=noise_g), frames, clip) == (events, states)


def test_a_move_over_both_bars_does_end_that_discard(templates):
    # the "gate" case above with the left hand at 2.2 g: over the gate too, so the discard ends
    _, states = play(DualBufferRecognizer(templates, noise_g=1.8), right_swinging_on(2.2), 4)
    assert "discard" in states[50:60] and states[62:70] == ["active"] * 8


def test_the_punching_hands_own_return_is_still_discarded(templates, monkeypatch):
    # the right hand keeps swinging after its clip (its return, 2 g) and the left one sways
    # under the gate: the discard holds as with one sensor (DISCARD_HOLD x discard_frames), and
    # everything happens as with the rule off
    right = np.vstack([rest(40), bump(0, 3.0)[:12], np.tile(G + [2.0, 0, 0], (40, 1))])
    right[52::2, 0] -= 4.0
    left = rest(len(right))
    left[:, 1] += 0.3 * np.sin(np.arange(len(right)) * 0.5)
    events, states = play(DualBufferRecognizer(templates, noise_g=0.5), hands(right, left), clip=4)
    first = states.index("discard")
    held = int(rules.DISCARD_HOLD * 20)
    assert states[first : first + held] == ["discard"] * held and states[first + held] != "discard"
    monkeypatch.setattr(rules, "OTHER_HAND_SHARE", 0.0)
    assert play(DualBufferRecognizer(templates, noise_g=0.5), hands(right, left), clip=4) == (events, states)


@pytest.fixture(scope="module")
def templates() -> Templates:
    return make_templates()


def right_never_resting(left_at: int) -> np.ndarray:
    """A right punch whose hand then sways at 1.2-1.8 g (no null signal ends the right motion) until
    6 frames after the left punch launches at frame `left_at`, and that left punch."""
    right = np.vstack([rest(40), bump(0, 3.0), rest(96)])
    right[64 : left_at + 6, 1] += 1.5 + 0.3 * np.cos(np.arange(left_at + 6 - 64) * 0.7)
    left = rest(len(right))
    left[left_at : left_at + 24] = bump(0, 3.0)
    return hands(right, left)


NO_CHARACTER = 1 << 30  # a caller that only pushes frames: character_finished() is never called


def starts_and_ends(events: list[dict]) -> list[tuple]:
    return [(e["event"], e["action"], e["frame"]) for e in events if e["event"] in ("start", "end")]


@pytest.mark.parametrize("left_at", [70, 90])
def test_without_a_character_the_other_hands_punch_ends_a_motion_that_ran_its_course(templates, monkeypatch, left_at):
    # The right motion never rests, and it has run its course (its ~25-frame template) when the left
    # hand launches: the launch ends it (`complete`) and the left punch starts in its main buffer.
    frames = right_never_resting(left_at)
    events, _ = play(DualBufferRecognizer(templates, noise_g=0.5), frames, NO_CHARACTER)
    (_, first, _), (_, ended, end_at), (_, second, start_at) = starts_and_ends(events)[:3]
    assert (first, ended, second) == ("hook_r", "hook_r", "hook_l")
    assert end_at - left_at <= 3 and start_at - left_at <= 10
    assert next(e for e in events if e["event"] == "end")["reason"] == "complete"
    # without the rule the right motion holds on past the launch and the left punch is lost
    monkeypatch.setattr(DualBufferRecognizer, "_ran_course", lambda self: False)
    events, _ = play(DualBufferRecognizer(templates, noise_g=0.5), frames, NO_CHARACTER)
    assert [a for kind, a, _ in starts_and_ends(events) if kind == "start"] == ["hook_r"]


def test_the_other_hand_does_not_end_a_motion_before_its_course_is_run(templates, monkeypatch):
    # the left hand launches 4 frames after the right punch's start: the right motion goes on
    # until it has run its best template past the main buffer
    frames = right_never_resting(left_at=50)
    rec = DualBufferRecognizer(templates, noise_g=0.5)
    events, _ = play(rec, frames, NO_CHARACTER)
    (_, first, start_at), (_, _, end_at) = starts_and_ends(events)[:2]
    assert first == "hook_r" and end_at - start_at >= int(rec.template_lengths.min()) - rec.main
    monkeypatch.setattr(DualBufferRecognizer, "_ran_course", lambda self: self.state == rules.ACTIVE and self.action is not None)
    events, _ = play(DualBufferRecognizer(templates, noise_g=0.5), frames, NO_CHARACTER)
    assert starts_and_ends(events)[1][2] - start_at < 8  # a rule without the course ends it at the launch
