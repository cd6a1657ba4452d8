"""Headless bouts: the graph opponent (boxer 0) against a random or a greedy one (boxer 1),
all bouts at once in the bout model (the same timing the graph was built with). A bout ends
by knockout (hp <= 0) or after `seconds`; the winner has more hp left (equal: a draw)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from engine.clock import STEP_HZ

from .bout import ActionTable, Bouts, greedy_choice, step
from .build import canonical_other, compile_table
from .runtime import InteractionGraph

OPPONENTS = ("random", "greedy", "graph")


@dataclass
class DuelResult:
    opponent: str
    bouts: int
    wins: int
    losses: int
    draws: int
    knockouts: int
    hits_landed: int
    hits_received: int
    damage_dealt: float
    damage_taken: float

    @property
    def win_rate(self) -> float:
        return self.wins / max(self.bouts, 1)

    def as_dict(self) -> dict:
        d = dict(self.__dict__)
        d["win_rate"] = round(self.win_rate, 4)
        d["damage_dealt"] = round(self.damage_dealt, 1)
        d["damage_taken"] = round(self.damage_taken, 1)
        return d


def _choose(policy: str, b: Bouts, who: int, rows: np.ndarray, graph: InteractionGraph,
            table: ActionTable, rng: np.random.Generator) -> np.ndarray:
    if policy == "random":     # any of the 13 actions, uniformly
        return rng.choice(table.choices[table.choices != table.wait], len(rows))
    if policy == "greedy":
        return greedy_choice(b, who, rows, graph.table.rules)
    d, bs, bo = b.pose(who, rows)
    act, frame = canonical_other(b, np.full(b.n, who))
    act, frame = act[rows], frame[rows]
    return np.array([graph.best_action_id(float(d[k]), float(bs[k]), float(bo[k]), int(act[k]),
                                          float(frame[k])) for k in range(len(rows))], dtype=np.int64)


def duel(graph: InteractionGraph, lib: dict, opponent: str = "random", bouts: int = 200,
         seconds: float = 60.0, seed: int = 0, us: str = "graph") -> DuelResult:
    """Boxer 0 plays `us` (normally the graph), boxer 1 plays `opponent`."""
    if opponent not in OPPONENTS or us not in OPPONENTS:
        raise ValueError(f"policies are {', '.join(OPPONENTS)}")
    rules, rewards = graph.table.rules, graph.table.rewards
    why = graph.library_mismatch(lib)
    if why is not None:
        raise ValueError(why)
    table = compile_table(lib, rules)
    rng = np.random.default_rng(seed)
    b = Bouts(table, bouts)
    b.place(rng.uniform(1.6, 2.0, bouts), rng.normal(0, 0.05, bouts), rng.normal(0, 0.05, bouts))
    b.hp[:] = rules.hp
    policies = (us, opponent)
    alive = np.ones(bouts, dtype=bool)
    landed = np.zeros((bouts, 2))
    dealt = np.zeros((bouts, 2))
    ko = np.zeros(bouts, dtype=bool)
    for _ in range(int(seconds * STEP_HZ)):
        done = b.done()
        if done.any():
            first = rng.integers(0, 2, bouts)
            for order in (0, 1):
                for who in (0, 1):
                    rows = np.flatnonzero(done[:, who] & ((first == who) if order == 0 else (first != who)))
                    if len(rows):
                        b.start(rows, who, _choose(policies[who], b, who, rows, graph, table, rng))
        sr = step(b, rules, rewards)
        landed += sr.landed * alive[:, None]
        dealt += sr.damage * alive[:, None]
        down = alive & (b.hp <= 0).any(axis=1)
        ko |= down
        alive &= ~down
        if not alive.any():
            break
    hp = rules.hp - dealt[:, ::-1]
    wins = int((hp[:, 0] > hp[:, 1]).sum())
    losses = int((hp[:, 0] < hp[:, 1]).sum())
    return DuelResult(opponent=opponent, bouts=bouts, wins=wins, losses=losses,
                      draws=bouts - wins - losses, knockouts=int(ko.sum()),
                      hits_landed=int(landed[:, 0].sum()), hits_received=int(landed[:, 1].sum()),
                      damage_dealt=float(dealt[:, 0].sum()), damage_taken=float(dealt[:, 1].sum()))
