"""The game and the Interaction Graph's bout model play by the same rules (game/rules.py):
the same turn towards the other each step, the same share of a blow through a guard, the same
health. A rule changed on one side only makes the graph solve a different fight."""

from __future__ import annotations

import math

import pytest

from engine.physics import World
from game.actions import load_library
from game.boxer import Boxer
from game.interaction.bout import BoutRules, Bouts, Rewards, step
from game.interaction.build import compile_table
from game.match import Match
from game.rules import BLOCKED_SHARE, FACE_RATE, MAX_HEALTH, blow_damage

LIB = load_library()


def test_the_bout_model_reads_the_shared_numbers():
    rules = BoutRules()
    assert (rules.chip, rules.face_fraction, rules.hp) == (BLOCKED_SHARE, FACE_RATE, MAX_HEALTH)


@pytest.mark.parametrize("other", [(1.0, 1.0), (-0.4, 0.9), (0.8, -0.6)])
def test_a_boxer_turns_as_the_bout_model_turns(other):
    # the game's boxer, facing +z at the origin, turns one step towards the other's root
    boxer = Boxer(World(), LIB, x=0.0, z=0.0, yaw=0.0)
    boxer.turn_towards(*other)
    # the bout model, the same two roots, both waiting (no root motion): one step
    b = Bouts(compile_table(LIB, BoutRules()), 1)
    b.pos[0, 1] = other
    b.base_yaw[0, 1] = math.atan2(-other[0], -other[1])  # the other faces boxer 0
    step(b, BoutRules(), Rewards())
    assert float(b.yaw[0, 0]) == pytest.approx(boxer.root[2], abs=1e-12)
    assert boxer.root[2] != 0.0  # it did turn


def test_a_guarded_blow_does_the_same_share_in_the_game_and_the_model():
    hit = {"attacker": 0, "target": "head", "speed": 4.0, "damage": 9.0, "blocked": False}
    game_share = blow_damage({**hit, "blocked": True}) / blow_damage(hit)
    # the bout model: a straight whose window opens now, against a block held up in front
    rules = BoutRules()
    t = compile_table(LIB, rules)
    b = Bouts(t, 1)
    b.place(0.8, 0.0, 0.0)
    straight, block = LIB["straight_r"], LIB["block"]
    b.set_action(0, t.index("straight_r"), straight.attacks[0].start - 1)
    b.set_action(1, t.index("block"), block.guards[0].start + 2)
    out = step(b, rules, Rewards())
    assert out.blocked[0, 1] == 1.0 and out.landed[0, 0] == 0.0  # the block took it
    model_share = out.damage[0, 0] / straight.attacks[0].damage
    assert model_share == pytest.approx(game_share) == pytest.approx(BLOCKED_SHARE)
    assert b.hp[0, 1] == pytest.approx(-model_share * straight.attacks[0].damage)


def test_both_start_with_the_same_health():
    assert Match().health == [BoutRules().hp, BoutRules().hp] == [MAX_HEALTH, MAX_HEALTH]
