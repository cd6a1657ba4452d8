"""Recognizer events are typed (RecognizerEvent); their JSON lines are the contract's, byte for byte."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest

from engine.recognition import DualBufferRecognizer, RecognizerEvent, Templates

FORMATS = Path(__file__).resolve().parents[3] / "docs" / "formats.md"


def _contract_lines() -> list[str]:
    """The JSON lines under "Recognition event keys" in docs/formats.md."""
    text = FORMATS.read_text(encoding="utf-8")
    section = text[text.index("### Recognition event keys"):]
    block = re.search(r"```[a-z]*\n(.*?)```", section, flags=re.S).group(1)
    return [line for line in block.splitlines() if line.startswith("{")]


def test_the_contract_examples_round_trip_byte_for_byte():
    lines = _contract_lines()
    assert len(lines) >= 5
    kinds = set()
    for line in lines:
        ev = RecognizerEvent.from_dict(json.loads(line))
        kinds.add(ev.event)
        assert json.dumps(ev.to_dict()) == line
    assert kinds == {"start", "switch", "end", "reject"}


def test_an_older_files_whole_motion_switch_reads_back():
    # files written before the late whole-motion switch was removed (docs/formats.md) hold the flag
    line = ('{"event": "switch", "action": "hook_r", "frame": 58, "t": 0.967, "from_frame": 17, "score": 0.3, '
            '"speed": 1.4, "direction": [0.7, 0.7, 0.0], "peak_g": 2.6, "onset_frame": 33, "whole_motion": true}')
    ev = RecognizerEvent.from_dict(json.loads(line))
    assert ev.event == "switch" and ev.action == "hook_r" and ev.from_frame == 17 and "whole_motion" not in ev


def test_an_event_reads_like_its_dict():
    ev = RecognizerEvent("switch", "hook_r", 58, t=0.967, from_frame=17, score=0.3, speed=1.4,
                         direction=(0.7, 0.7, 0.0), peak_g=2.6, onset_frame=33)
    assert ev["action"] == ev.action == "hook_r"
    assert ev.get("from_frame", 0) == 17 and ev.get("reason") is None
    assert "onset_frame" in ev and "called_off" not in ev
    assert dict(ev) == ev.to_dict()
    assert ev.to_dict()["direction"] == [0.7, 0.7, 0.0]
    with pytest.raises(KeyError):
        ev["reason"]
    end = RecognizerEvent("end", "hook_r", 70)
    assert list(end.to_dict()) == ["event", "action", "frame"]  # no motion keys, no false flags


def _jab(rng: np.random.Generator, n: int = 40) -> np.ndarray:
    """A quiet rest, then a 3 g push along x and back, on one sensor (D = 3)."""
    x = np.tile([0.0, 0.0, 1.0], (n, 1)) + rng.normal(0, 0.01, (n, 3))
    x[10:20, 0] += 3.0 * np.sin(np.linspace(0, np.pi, 10))
    return x


def test_the_recognizer_emits_typed_events_that_round_trip():
    rng = np.random.default_rng(0)
    templates = Templates.from_trials({"jab": [_jab(rng) for _ in range(3)]})
    rec = DualBufferRecognizer(templates)
    events = [e for _ in range(3) for f in _jab(rng, 60) for e in rec.push(f, t=0.5)]
    assert {e.event for e in events} >= {"start", "end"}
    for e in events:
        assert isinstance(e, RecognizerEvent)
        assert RecognizerEvent.from_dict(json.loads(json.dumps(e.to_dict()))) == e


@pytest.mark.parametrize("t", [float("nan"), float("inf"), -float("inf")])
def test_a_time_that_is_not_a_number_gives_events_without_one(t):
    """push(frame, t=nan) wrote "t": NaN into the event's JSON line, which no JSON reader takes: a
    time that is no number is left out, as when none is given."""
    rng = np.random.default_rng(0)
    rec = DualBufferRecognizer(Templates.from_trials({"jab": [_jab(rng) for _ in range(3)]}))
    events = [e for f in _jab(rng, 60) for e in rec.push(f, t=t)]
    assert events and all("t" not in e.to_dict() for e in events)
    json.loads(json.dumps([e.to_dict() for e in events], allow_nan=False))
