"""The Interaction Graph at run time: load the table, map the live situation to its state,
look the best action up. The CPU boxer acts only when its body is back at the guard, as in
Shum et al.; choosing "guard" means waiting `rules.wait_frames` steps before choosing again.
"""

from __future__ import annotations

from collections import deque
from pathlib import Path

import numpy as np

from game.motion import PlayerController

from .lookup import StateIndex
from .state import Situation
from .table import GraphTable

DEFAULT_GRAPH = Path(__file__).resolve().parent.parent / "assets" / "graph.npz"
IDLE = "guard"


class InteractionGraph:
    def __init__(self, table: GraphTable, path: str | Path | None = None):
        self.table = table
        self.path = Path(path) if path is not None else None
        self.names = list(table.action_names)
        self._ids = {n: i for i, n in enumerate(self.names)}
        self.wait_id = self._ids[IDLE]
        self.index = StateIndex(table.grid, table.keys, (table.fill_keys, table.fill_state),
                                ready_action=self.wait_id)
        self.ready_frame = table.rules.wait_frames - 1
        self._best = table.best_action.tolist()
        self._best_names = [self.names[i] for i in self._best]

    @classmethod
    def load(cls, path: str | Path = DEFAULT_GRAPH, edges: bool = True) -> InteractionGraph:
        """`edges=False`: the policy and the look-up only (a match's needs; GraphTable.load)."""
        return cls(GraphTable.load(path, edges=edges), path)

    def library_mismatch(self, lib: dict) -> str | None:
        """Why the graph cannot play with the action library `lib`, or None: built from another
        library (its action names, or what the bout model read of the library, the fingerprint
        its build recorded, differ). Checked wherever a graph meets the library: `graph duel`,
        and a match, whose first look-up of an action the library lacks raised KeyError."""
        from .build import compile_table

        table = compile_table(lib, self.table.rules)
        built_from = self.table.build.get("library")
        if table.names != self.names or (built_from and built_from != table.fingerprint()):
            return "built from a different action library; rebuild it (quickjab graph build -o game/assets/graph.npz)"
        return None

    @property
    def n_states(self) -> int:
        return self.table.n_states

    @property
    def n_edges(self) -> int:
        return self.table.n_edges

    def other_code(self, action: str, phase: float) -> tuple[int, float]:
        """The table's (action id, frame) for the other boxer; idle or unknown -> READY."""
        aid = self._ids.get(action)
        if aid is None or aid == self.wait_id:
            return self.wait_id, self.ready_frame
        return aid, phase

    def state_of(self, s: Situation) -> int:
        aid, frame = self.other_code(s.other_action, s.other_phase)
        return self.index.nearest(s.distance, s.bearing_self, s.bearing_other, aid, frame)

    def best_action(self, s: Situation) -> str:
        """One of ACTION_NAMES, or "guard" to wait (also for a situation with NaN or
        infinite numbers, which a glitching body could produce: the loop must not crash)."""
        try:
            sid = self.state_of(s)
        except (ValueError, OverflowError):
            return IDLE
        return self._best_names[sid]

    def best_action_id(self, distance: float, bearing_self: float, bearing_other: float,
                       other_id: int, other_frame: float) -> int:
        """The same look-up on table ids (the headless duel's path)."""
        return self._best[self.index.nearest(distance, bearing_self, bearing_other, other_id,
                                             other_frame)]

    def info(self) -> dict:
        t = self.table
        out = {"states": t.n_states, "edges": t.n_edges, "actions": self.names[:t.n_choices],
               "grid": t.grid.as_dict(), "rules": t.rules.as_dict(), "rewards": t.rewards.as_dict(),
               "build": t.build}
        if self.path is not None and self.path.exists():
            out["file"] = str(self.path)
            out["file_bytes"] = self.path.stat().st_size
        return out


class OpponentController:
    """Drives the CPU boxer's PlayerController from the graph.

    `decide(situation)` is called every step; when the boxer is at the guard (and not
    waiting out a "guard" choice) it looks the best action up and plays it. Returns the
    action chosen this step ("guard" for a wait), or None when it did not choose.

    The policy (game/difficulty.py sets it): it takes the table's best action with probability
    `best_share`, else another choosable action at random; and it decides on the situation of
    `reaction_steps` steps ago (`observe` records the steps it does not decide on).
    """

    def __init__(self, graph: InteractionGraph, lib: dict, controller: PlayerController | None = None,
                 best_share: float = 1.0, reaction_steps: int = 0, rng: np.random.Generator | None = None):
        self.graph = graph
        self.controller = controller if controller is not None else PlayerController(lib)
        self._wait = 0
        self.rng = rng if rng is not None else np.random.default_rng(0)
        self.choices = list(graph.names[:graph.table.n_choices])
        self.best_share = best_share
        self._seen: deque[Situation] = deque(maxlen=1)
        self.set_policy(best_share, reaction_steps)

    def set_policy(self, best_share: float, reaction_steps: int) -> None:
        self.best_share = float(best_share)
        if self._seen.maxlen != reaction_steps + 1:
            self._seen = deque(self._seen, maxlen=max(0, int(reaction_steps)) + 1)

    def observe(self, situation: Situation) -> None:
        """Record this step's situation (the delayed decisions read it later)."""
        self._seen.append(situation)

    def choose(self, situation: Situation) -> str:
        """The policy's action for a situation: the best one, or by `1 - best_share` chance another."""
        best = self.graph.best_action(situation)
        if self.best_share < 1.0 and self.rng.random() >= self.best_share:
            others = [a for a in self.choices if a != best]
            if others:
                return others[int(self.rng.integers(len(others)))]
        return best

    def at_guard(self) -> bool:
        return self.controller.action == IDLE

    def decide(self, situation: Situation) -> str | None:
        self.observe(situation)
        if not self.at_guard():
            self._wait = 0
            return None
        if self._wait > 0:
            self._wait -= 1
            return None
        action = self.choose(self._seen[0])  # the oldest kept: reaction_steps ago
        if action == IDLE:
            self._wait = self.graph.table.rules.wait_frames - 1
        else:
            self.controller.play(action)
        return action

    def step(self):
        """Advance the wrapped controller one 60 Hz step (its reference posture)."""
        return self.controller.step()
