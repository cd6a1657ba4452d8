"""A double (a punch launched straight after the previous one's stop, no rest between) starts a
second action at its own launch (rules.RELAUNCH_*); a first decision needs GATE_FLOOR x the gate."""

from __future__ import annotations

import numpy as np
import pytest

from engine.recognition import DualBufferRecognizer, Templates, rules, template_set
from tests.engine.recognition.test_dual_buffer import G, bump, rest, run, trials_of

CLIP = 24  # the simulated character's clip, as `quickjab evaluate` plays it


@pytest.fixture(scope="module")
def templates() -> Templates:
    rng = np.random.default_rng(0)
    return Templates.from_trials({"jab": trials_of(bump(0, 3.0), rng), "upper": trials_of(bump(2, 3.0), rng)})


def double() -> np.ndarray:
    # the second jab launches while the first is still stopping (its last 4 frames cut, the
    # second's first 3): the hand never calms between the two
    return np.vstack([rest(10), bump(0, 3.0)[:20], bump(0, 3.0)[3:], rest(30)])


def with_character(rec: DualBufferRecognizer, frames: np.ndarray) -> list[dict]:
    """Events with a character that finishes each clip CLIP frames after its start."""
    out, clip_end = [], None
    for i, f in enumerate(frames):
        evs = rec.push(f)
        for e in evs:
            if e["event"] in ("start", "switch"):
                clip_end = e["frame"] - e.get("from_frame", 0) + CLIP
        out += evs
        if clip_end is not None and i >= clip_end:
            rec.character_finished()
            clip_end = None
    return out


def test_a_double_starts_twice_at_the_second_launch(templates, monkeypatch):
    frames = double()
    evs = with_character(DualBufferRecognizer(templates), frames)
    starts = [e for e in evs if e["event"] == "start"]
    assert [e["action"] for e in starts] == ["jab", "jab"]
    # the first ends (`complete`) where the second launches, which is the second's onset
    first_end = next(e for e in evs if e["event"] == "end")
    assert first_end["reason"] == "complete" and first_end["frame"] == starts[1]["onset_frame"]
    assert 10 + 20 <= starts[1]["onset_frame"] <= 10 + 20 + 6  # the second bump's launch
    # without the rule the two are one motion: the clip and the discard swallow the second
    monkeypatch.setattr(rules, "RELAUNCH_WITHIN", -1)
    again = with_character(DualBufferRecognizer(templates), frames)
    assert [e["action"] for e in again if e["event"] == "start"] == ["jab"]


def test_a_double_after_the_clip_ends_the_discard(templates, monkeypatch):
    # a short clip: the character finishes during the first jab's stop, and the second jab
    # launches inside the discard; it starts there instead of being discarded
    frames = double()

    def starts(clip: int) -> list[dict]:
        rec, out, clip_end = DualBufferRecognizer(templates), [], None
        for i, f in enumerate(frames):
            evs = rec.push(f)
            out += [e for e in evs if e["event"] == "start"]
            if any(e["event"] == "start" for e in evs):
                clip_end = evs[-1]["frame"] + clip
            if clip_end is not None and i >= clip_end:
                rec.character_finished()
                clip_end = None
        return out

    got = starts(8)
    assert [e["action"] for e in got] == ["jab", "jab"] and got[1]["onset_frame"] <= 10 + 20 + 6
    monkeypatch.setattr(rules, "RELAUNCH_WITHIN", -1)
    assert [e["action"] for e in starts(8)] == ["jab"]


def test_a_gentle_double_is_not_split(templates, monkeypatch):
    # launches under RELAUNCH_MIN x the gate (2.5 g over a 1 g gate): one motion, as before
    frames = np.vstack([rest(10), bump(0, 2.5)[:20], bump(0, 2.5)[3:], rest(30)])
    evs = with_character(DualBufferRecognizer(templates, noise_g=1.0), frames)
    assert not any(e.get("reason") == "complete" and e["frame"] < 10 + 20 + 6 for e in evs if e["event"] == "end")
    monkeypatch.setattr(rules, "RELAUNCH_MIN", 0.0)
    again = with_character(DualBufferRecognizer(templates, noise_g=1.0), frames)
    assert any(e.get("reason") == "complete" and 10 + 20 <= e["frame"] <= 10 + 20 + 6 for e in again if e["event"] == "end")


def test_a_shake_whose_templates_relaunch_is_not_split(monkeypatch):
    # an action that is itself several strokes back to back (a shake): its motion is one action
    rng = np.random.default_rng(1)
    shake = np.vstack([bump(0, 3.0)[:20], bump(0, 3.0)[3:20], bump(0, 3.0)[3:]])
    tm = Templates.from_trials({"shake": trials_of(shake, rng), "upper": trials_of(bump(2, 3.0), rng)})
    rec = DualBufferRecognizer(tm)
    assert rec._strokes == [True, False]
    frames = np.vstack([rest(10), shake, rest(30)])
    assert [e["action"] for e in run(rec, frames) if e["event"] == "start"] == ["shake"]
    monkeypatch.setattr(template_set, "shaken_actions", lambda *a: [False, False])
    split = run(DualBufferRecognizer(tm), frames)
    assert [e["event"] for e in split].count("start") >= 2


def test_a_motion_barely_over_the_gate_does_not_start(templates, monkeypatch):
    # 2.5 g against a 2 g gate (GATE_FLOOR x 2 g = 2.6 g): within reach of the noise, however well
    # it fits the jab's shape; a 3 g jab starts
    def starts(amp: float) -> list[str]:
        frames = np.vstack([rest(10), bump(0, amp), rest(30)])
        return [e["action"] for e in run(DualBufferRecognizer(templates, noise_g=2.0), frames) if e["event"] == "start"]

    assert starts(2.5) == [] and starts(3.0) == ["jab"]
    monkeypatch.setattr(rules, "GATE_FLOOR", 0.0)
    assert starts(2.5) == ["jab"]


def test_relaunches_needs_a_stop_of_two_frames():
    # a buzz flipping sign every frame has no stop; a bump followed at once by another relaunches
    buzz = np.tile(G + np.array([2.0, 0.0, 0.0]), (30, 1))
    buzz[::2, 0] -= 4.0
    assert not rules.relaunches(buzz, G, 0.5)
    assert rules.relaunches(np.vstack([bump(0, 3.0)[:20], bump(0, 3.0)[3:]]), G, 0.5)
    assert not rules.relaunches(bump(0, 3.0), G, 0.5)
