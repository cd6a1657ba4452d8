"""The game's events are typed: a Hit from the physics contacts, a MatchEvent from the referee,
each with to_dict() for JSON; the dict keys docs/motion.md documents still read."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from engine.physics import World
from game.actions import load_library
from game.boxer import Boxer
from game.hits import Hit, hits_from_contacts
from game.match import Match, MatchEvent

LIB = load_library()
DT = 1 / 60


def landed_hit() -> Hit:
    w = World()
    a = Boxer(w, LIB, x=0.0, z=-0.425, yaw=0.0)
    b = Boxer(w, LIB, x=0.0, z=0.425, yaw=math.pi)
    hits: list = []
    for k in range(40):
        if k == 10:
            a.controller.play("straight_r")
        a.step(DT)
        b.step(DT)
        hits += hits_from_contacts(w.step(DT), [a, b])
    assert hits
    return hits[0]


def test_a_landed_punch_is_a_typed_hit_with_a_json_dict():
    hit = landed_hit()
    assert isinstance(hit, Hit)
    assert (hit.attacker, hit.target, hit.hand, hit.blocked) == (0, "head", "r", False)
    d = json.loads(json.dumps(hit.to_dict()))
    assert set(d) == {"attacker", "target", "hand", "speed", "direction", "blocked", "damage", "point"}
    assert d["speed"] == hit.speed and d["direction"] == hit.direction.tolist() and len(d["point"]) == 3
    # the documented dict keys still read, and a dict of them makes the same hit
    assert hit["speed"] == hit.speed and hit.get("point") is hit.point and hit.get("nope", 3) == 3
    with pytest.raises(KeyError):
        hit["nope"]
    again = Hit.of(d)
    assert again.to_dict() == d and Hit.of(hit) is hit


def test_a_hit_from_a_partial_dict_gets_the_defaults():
    hit = Hit.of({"attacker": 1, "target": "body", "speed": 3.0, "blocked": True})
    assert hit.damage == 8.0 and hit.point is None and "point" not in hit.to_dict()
    np.testing.assert_array_equal(hit.direction, [0.0, 0.0, 1.0])


def test_the_referee_drains_typed_events():
    m = Match(round_seconds=1)
    m.hit(1, 200.0)  # down at once
    events = m.drain_events()
    assert events == [MatchEvent("knockdown", 1)] and events[0].who == 1
    kind, who = events[0]  # still a pair
    assert (kind, who) == ("knockdown", 1)
    assert json.loads(json.dumps(events[0].to_dict())) == {"kind": "knockdown", "who": 1}
