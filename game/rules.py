"""The boxing rules the game and the Interaction Graph's bout model share, written once.

The game's session (referee, boxers) and `game.interaction.bout.BoutRules` (the model the graph
is solved with and judged by) read these names, so the table is solved for the fight the game
actually plays; tests/game/interaction/test_rules_agree.py checks that they agree.
"""

from __future__ import annotations

import numpy as np

from game.hits import Hit

MAX_HEALTH = 100.0  # each boxer's health at the bell (the bout model's hp)
BLOCKED_SHARE = 0.2  # the share of a blow's damage that goes through a block or parry
FACE_RATE = 0.2  # every step each boxer turns this share of the way to face the other
START_GAP = 1.1  # metres between the two roots at the bell: just out of a straight's reach
RING_LIMIT = 2.6  # metres from the centre a root may go (the ropes are at 3)
REFERENCE_SPEED = 4.0  # m/s: a blow closing at this speed does its window's damage
# Every blow counts for this share of its window's damage: at 1.0 nearly every match ended by
# TKO in round 1 (issue 17); the CPU's blows are scaled again by its difficulty.
BLOW_SCALE = 0.6


def blow_damage(hit: Hit | dict) -> float:
    """A blow's damage, the same in both modes: its window's damage, scaled by the closing
    speed and BLOW_SCALE, BLOCKED_SHARE of it through a block (the CPU's difficulty comes on
    top)."""
    hit = Hit.of(hit)
    scale = float(np.clip(hit.speed / REFERENCE_SPEED, 0.5, 1.5))
    return float(hit.damage) * scale * BLOW_SCALE * (BLOCKED_SHARE if hit.blocked else 1.0)
