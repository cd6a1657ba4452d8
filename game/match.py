"""The rules of a match: 3 rounds of 60 s, health, knockdowns and the count, a winner, pause.

Pure state advanced one 60 Hz step at a time; it knows nothing about bodies or rendering, so a
scripted match is reproducible and its state hashes. Rules, kept simple and deterministic:

- Health 100 each. A hit takes damage; at 0 the boxer goes down and the referee counts one
  number per second. A boxer rises at count 3 x (its knockdowns in the match, this one
  included), with 40 health; one who would rise at 10 or later is counted out (KO). Three knockdowns in one
  round end it (TKO).
- Between rounds a 3 s break; each boxer recovers 20 health.
- After round 3 the scorecards decide: each round 10-9 to whoever dealt more damage (10-10
  when even), minus one point per knockdown suffered in the round. Equal totals: a draw.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import NamedTuple

from engine.clock import STEP_HZ
from game.rules import MAX_HEALTH

HZ = STEP_HZ
ROUNDS = 3
ROUND_SECONDS = 60
BREAK_SECONDS = 3
COUNT_OUT = 10
RISE_HEALTH = 40.0
BREAK_RECOVERY = 20.0
KNOCKDOWNS_FOR_TKO = 3



class MatchEvent(NamedTuple):
    """Something the referee did this step, drained by the session: "bell", "knockdown",
    "count", "rise", "over". A pair, so `for kind, who in match.drain_events()` reads it."""

    kind: str
    who: int  # the boxer (0 | 1) it concerns, -1 for none; the number called for "count"

    def to_dict(self) -> dict:
        return {"kind": self.kind, "who": self.who}


@dataclass(frozen=True, slots=True)
class MatchSnapshot:
    """What the HUD shows of a match, taken once a step (`Match.snapshot()`)."""

    health: tuple[float, float] = (MAX_HEALTH, MAX_HEALTH)
    round: int = 1
    rounds: int = ROUNDS
    seconds_left: float = float(ROUND_SECONDS)
    phase: str = "fight"
    count: int = 0
    down: int | None = None
    knockdowns: tuple[int, int] = (0, 0)
    winner: int | None = None
    result: str = ""
    paused: bool = False


# phases
FIGHT = "fight"
COUNT = "count"
BREAK = "break"
OVER = "over"


@dataclass
class Match:
    rounds: int = ROUNDS
    round_seconds: int = ROUND_SECONDS
    hz: int = HZ
    round: int = 1
    phase: str = FIGHT
    paused: bool = False
    clock_steps: int = 0  # steps left in the current round (or break)
    health: list[float] = field(default_factory=lambda: [MAX_HEALTH, MAX_HEALTH])
    knockdowns: list[int] = field(default_factory=lambda: [0, 0])  # in the match
    round_knockdowns: list[int] = field(default_factory=lambda: [0, 0])
    round_damage: list[float] = field(default_factory=lambda: [0.0, 0.0])  # dealt BY boxer i
    scores: list[int] = field(default_factory=lambda: [0, 0])
    # who won each round so far: the round's points (damage, knockdowns), or the KO/TKO; None even
    round_winners: list[int | None] = field(default_factory=list)
    down: int | None = None  # who is on the canvas
    count: int = 0  # the referee's current number
    count_steps: int = 0
    winner: int | None = None  # 0, 1, or None (draw / not over)
    result: str = ""  # "KO", "TKO", "points", "draw"
    hits: list[int] = field(default_factory=lambda: [0, 0])  # landed BY boxer i
    events: list[MatchEvent] = field(default_factory=list)  # since the last drain

    def __post_init__(self) -> None:
        if not self.clock_steps:
            self.clock_steps = self.round_seconds * self.hz

    # -- queries -----------------------------------------------------------------------
    @property
    def fighting(self) -> bool:
        """True while blows count: in a round, not paused, nobody down."""
        return self.phase == FIGHT and not self.paused

    @property
    def over(self) -> bool:
        return self.phase == OVER

    def seconds_left(self) -> float:
        return self.clock_steps / self.hz

    def snapshot(self) -> MatchSnapshot:
        return MatchSnapshot(
            (self.health[0], self.health[1]), self.round, self.rounds, self.seconds_left(), self.phase,
            self.count, self.down, (self.knockdowns[0], self.knockdowns[1]), self.winner, self.result, self.paused,
        )

    def drain_events(self) -> list[MatchEvent]:
        """What happened since the last call: ("bell", -1), ("knockdown", i), ("rise", i), ("over", i)..."""
        ev, self.events = self.events, []
        return ev

    def state(self) -> tuple:
        """Everything that defines the match, for state hashes."""
        return (
            self.round, self.phase, self.paused, self.clock_steps, tuple(round(h, 6) for h in self.health),
            tuple(self.knockdowns), tuple(self.round_knockdowns), tuple(round(d, 6) for d in self.round_damage),
            tuple(self.scores), self.down, self.count, self.count_steps, self.winner, self.result, tuple(self.hits),
        )

    # -- input -------------------------------------------------------------------------
    def toggle_pause(self) -> None:
        if self.phase != OVER:
            self.paused = not self.paused

    def hit(self, target: int, damage: float) -> bool:
        """Boxer `target` takes `damage`. Returns True when the blow counted (not a NaN or
        infinite one: NaN knocked the boxer down, max(0, health - nan) being 0, and left NaN in
        the round's damage)."""
        if not self.fighting or not math.isfinite(damage) or damage <= 0:
            return False
        attacker = 1 - target
        self.health[target] = max(0.0, self.health[target] - damage)
        self.round_damage[attacker] += damage
        self.hits[attacker] += 1
        if self.health[target] <= 0.0:
            self._knockdown(target)
        return True

    # -- time --------------------------------------------------------------------------
    def step(self) -> None:
        """Advance one step."""
        if self.paused or self.phase == OVER:
            return
        if self.phase == FIGHT:
            self.clock_steps -= 1
            if self.clock_steps <= 0:
                self._end_round()
        elif self.phase == COUNT:
            self.count_steps += 1
            if self.count_steps >= self.hz:
                self.count_steps = 0
                self.count += 1
                self.events.append(MatchEvent("count", self.count))
                self._maybe_rise()
        elif self.phase == BREAK:
            self.clock_steps -= 1
            if self.clock_steps <= 0:
                self.round += 1
                self.phase = FIGHT
                self.clock_steps = self.round_seconds * self.hz
                self.events.append(MatchEvent("bell", -1))

    # -- rules -------------------------------------------------------------------------
    def rise_count(self, boxer: int) -> int:
        """The count at which `boxer`, down now, gets up (knockdowns already include this one)."""
        return 3 * self.knockdowns[boxer]

    def _knockdown(self, boxer: int) -> None:
        self.knockdowns[boxer] += 1
        self.round_knockdowns[boxer] += 1
        self.down = boxer
        self.phase = COUNT
        self.count = 0
        self.count_steps = 0
        self.events.append(MatchEvent("knockdown", boxer))
        if self.round_knockdowns[boxer] >= KNOCKDOWNS_FOR_TKO:
            self._finish(1 - boxer, "TKO")

    def _maybe_rise(self) -> None:
        boxer = self.down
        assert boxer is not None
        rise = self.rise_count(boxer)
        if rise >= COUNT_OUT and self.count >= COUNT_OUT:
            self._finish(1 - boxer, "KO")
        elif rise < COUNT_OUT and self.count >= rise:
            self.health[boxer] = RISE_HEALTH
            self.down = None
            self.phase = FIGHT
            self.events.append(MatchEvent("rise", boxer))

    def _score_round(self) -> None:
        d = self.round_damage
        points = [(10 if d[i] >= d[1 - i] else 9) - self.round_knockdowns[i] for i in (0, 1)]
        for i in (0, 1):
            self.scores[i] += points[i]
        self.round_winners.append(None if points[0] == points[1] else int(points[1] > points[0]))

    def _end_round(self) -> None:
        self._score_round()
        self.events.append(MatchEvent("bell", -1))
        if self.round >= self.rounds:
            if self.scores[0] == self.scores[1]:
                self._finish(None, "draw")
            else:
                self._finish(0 if self.scores[0] > self.scores[1] else 1, "points")
            return
        self.phase = BREAK
        self.clock_steps = BREAK_SECONDS * self.hz
        self.round_damage = [0.0, 0.0]
        self.round_knockdowns = [0, 0]
        self.health = [min(MAX_HEALTH, h + BREAK_RECOVERY) for h in self.health]

    def _finish(self, winner: int | None, result: str) -> None:
        if result in ("KO", "TKO"):
            self.round_winners.append(winner)  # the round ends with the match
        self.phase = OVER
        self.winner = winner
        self.result = result
        self.down = self.down if result in ("KO", "TKO") else None
        self.events.append(MatchEvent("over", -1 if winner is None else winner))
