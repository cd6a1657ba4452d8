"""The attract mode's player (`quickjab play --demo`): the Interaction Graph picks the player's
move from the player's side, the virtual player behind a PLAYABLE source (keyboard://)
performs it, and the REAL recognizer has to recognize it before the boxer moves."""

from __future__ import annotations

import numpy as np

from engine.sensors.source import PLAYABLE, Source
from game.interaction import Situation

PILOT_SETTLE_STEPS = 90  # the pilot's hands rest first: the recognizer learns gravity at rest
PILOT_VARIETY = 0.4
# how the virtual player boxes, by its profile (keyboard://?profile=...): how often it picks a
# move other than the graph's best for its side, and the steps its hands rest between motions
PILOT_STYLE = {"experienced": (PILOT_VARIETY, 12), "novice": (PILOT_VARIETY, 12)}
PILOT_REACH = 1.0
PILOT_ATTACKS = ("straight_l", "straight_r", "hook_l", "hook_r", "uppercut_l", "uppercut_r", "block", "step_left", "step_right")
PILOT_RETRY_STEPS = 8  # the graph chose to wait: ask it again this many steps later


class DemoPilot:
    """Presses the player's next move on the source when the player's boxer is at the guard.
    Reads the match, both boxers and the graph; writes only to the source (a press)."""

    def __init__(self, graph, lib: dict, rng: np.random.Generator):
        self.graph = graph
        self.lib = lib
        self.rng = rng
        self.wait = PILOT_SETTLE_STEPS
        self.seen = True  # the recognizer started something since the last press

    def settle(self) -> None:
        """A new match: the hands rest first again."""
        self.wait = PILOT_SETTLE_STEPS

    def saw(self, event: dict) -> None:
        """A recognizer event: a start means the last motion was recognized."""
        self.seen |= event.get("event") == "start"

    def step(self, source: Source, fighting: bool, player, opponent) -> None:
        if PLAYABLE not in source.capabilities or source.busy or not fighting:
            return
        if player.controller.action != "guard":
            return
        if self.wait > 0:
            self.wait -= 1
            return
        me, them = player.controller, opponent.controller
        situation = Situation.from_roots(player.root, me.action, me.frame, opponent.root, them.action, them.frame)
        action = self.graph.best_action(situation)
        unrecognized = not self.seen  # the last motion started nothing: try another
        variety, rest = PILOT_STYLE.get(source.profile, PILOT_STYLE["experienced"])
        if unrecognized or self.rng.random() < variety:
            # an attract mode that only ever throws the one best punch is dull to watch: now
            # and then a different move (closing in when out of reach)
            near = situation.distance < PILOT_REACH
            choices = PILOT_ATTACKS if near else ("step_forward",)
            action = choices[int(self.rng.integers(len(choices)))]
        if action in self.lib and action != "guard":
            source.press(action)
            self.seen = False
            self.wait = rest  # the hands come back to rest before the next motion
        else:
            self.wait = PILOT_RETRY_STEPS
