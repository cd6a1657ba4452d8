"""WorldDef: the world's constants as data, giving exactly the world the keywords give."""

from __future__ import annotations

import dataclasses
import inspect

import pytest

from engine.physics import World, WorldDef, default_world_def
from tests.engine.physics.test_world import _scenario


def test_fields_are_exactly_the_world_keywords_with_their_defaults():
    sig = inspect.signature(World.__init__)
    keywords = {n: p.default for n, p in sig.parameters.items() if n != "self"}
    assert default_world_def().kwargs() == keywords
    assert World().world_def == WorldDef()


def test_from_def_steps_bit_identical_to_the_keywords():
    # the session's world (game/session.py builds it with these keywords)
    session_like = World(gravity=(0.0, -9.81, 0.0), ground_y=0.0, damping=0.01, iterations=4)
    h = _scenario(session_like)
    assert _scenario(World.from_def(WorldDef())) == h
    assert _scenario(World.from_def()) == h
    assert _scenario(World.from_def(WorldDef(iterations=2))) == _scenario(World(iterations=2)) != h
    w = World.from_def(WorldDef(damping=0.05, contact_passes=1, collision_margin=0.02, solver="gauss_seidel"))
    assert w.world_def == WorldDef(damping=0.05, contact_passes=1, collision_margin=0.02, solver="gauss_seidel")


def test_frozen_and_checked():
    with pytest.raises(dataclasses.FrozenInstanceError):
        WorldDef().damping = 0.5  # type: ignore[misc]
    for bad in ({"iterations": 0}, {"damping": 1.0}, {"solver": "sor"}, {"gravity": (0.0, 1.0)}, {"contact_passes": -1}):
        with pytest.raises(ValueError):
            WorldDef(**bad)
