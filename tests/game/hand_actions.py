"""A small hand-made action table for unit tests of the interaction graph (not game data):
objects with the game.actions.Action attributes the bout model reads."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

NAMES = ["straight_l", "straight_r", "uppercut_l", "uppercut_r", "hook_l", "hook_r",
         "parry_l", "parry_r", "block", "step_forward", "step_back", "step_left", "step_right"]


@dataclass
class AttackWindow:
    hand: str
    start: int
    end: int
    targets: tuple
    damage: float
    reach: float


@dataclass
class GuardWindow:
    start: int
    end: int
    covers: tuple
    kind: str


@dataclass
class HandAction:
    name: str
    kind: str
    frames: int
    move: tuple = (0.0, 0.0, 0.0)       # total (dx, dz, dyaw), spread evenly over the clip
    attacks: list = field(default_factory=list)
    guards: list = field(default_factory=list)

    def root_offset(self, f: float) -> np.ndarray:
        return np.asarray(self.move) * min(max(f / max(self.frames - 1, 1), 0.0), 1.0)


def hand_library() -> dict:
    """13 actions + guard + two reactions, with plausible timings and reaches."""
    A, G = AttackWindow, GuardWindow
    lib = [
        HandAction("straight_l", "attack", 16, attacks=[A("l", 5, 8, ("head",), 5.0, 0.85)]),
        HandAction("straight_r", "attack", 20, attacks=[A("r", 7, 10, ("head",), 8.0, 0.9)]),
        HandAction("uppercut_l", "attack", 24, attacks=[A("l", 10, 13, ("head", "body"), 10.0, 0.55)]),
        HandAction("uppercut_r", "attack", 26, attacks=[A("r", 11, 14, ("head", "body"), 12.0, 0.55)]),
        HandAction("hook_l", "attack", 22, attacks=[A("l", 9, 12, ("head",), 9.0, 0.65)]),
        HandAction("hook_r", "attack", 24, attacks=[A("r", 10, 13, ("head",), 11.0, 0.65)]),
        HandAction("parry_l", "defense", 14, guards=[G(2, 9, ("head",), "parry")]),
        HandAction("parry_r", "defense", 14, guards=[G(2, 9, ("head",), "parry")]),
        HandAction("block", "defense", 20, guards=[G(1, 17, ("head", "body"), "block")]),
        HandAction("step_forward", "step", 14, move=(0.0, 0.3, 0.0)),
        HandAction("step_back", "step", 14, move=(0.0, -0.3, 0.0)),
        HandAction("step_left", "step", 14, move=(-0.3, 0.0, 0.0)),
        HandAction("step_right", "step", 14, move=(0.3, 0.0, 0.0)),
        HandAction("guard", "idle", 30),
        HandAction("hit_head", "reaction", 18, move=(0.0, -0.1, 0.0)),
        HandAction("hit_body", "reaction", 16, move=(0.0, -0.05, 0.0)),
    ]
    return {a.name: a for a in lib}
