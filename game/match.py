"""The rules of a match: 3 rounds of 60 s, health, knockdowns and the count, a winner, pause.

Pure state advanced one 60 Hz step at a time; it knows nothing about bodies or rendering, so a
scripted match is reproducible and its state hashes. Rules, kept simple and deterministic:

- Health 100 each. A hit takes damage; at 0 the boxer goes down and the referee counts one
  number per second. A boxer rises at count 3 x (its knockdowns in the match, this one
  included), with 40 health; one who would rise at 10 or later is counted out (KO). Three knockdowns in one
  round end it (TKO).
- Every blow of a step counts before any knockdown is decided (`land` each, then
  `settle_knockdowns`), so the order of the contacts decides nothing. Both boxers floored in one
  step both go down and are counted together, each rising at its own count; when neither can
  go on (each counted out or stopped by its third knockdown of the round) the match is a draw,
  "double KO"; when only one cannot, the other wins by KO or TKO (a TKO winner floored in the
  same step gets up at once, with 40 health, as one who rises from the count).
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
DOUBLE_KO = "double KO"  # both floored in one step, and neither can go on: a draw


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
    downed: tuple[int, ...] = ()  # who is on the canvas (both after a double knockdown)
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
    downed: list[int] = field(default_factory=list)  # who is on the canvas, 0 and 1 in order
    count: int = 0  # the referee's current number
    count_steps: int = 0
    winner: int | None = None  # 0, 1, or None (draw / not over)
    result: str = ""  # "KO", "TKO", "points", "draw", "double KO" (winner None)
    hits: list[int] = field(default_factory=lambda: [0, 0])  # landed BY boxer i
    events: list[MatchEvent] = field(default_factory=list)  # since the last drain

    def __post_init__(self) -> None:
        if not self.clock_steps:
            self.clock_steps = self.round_seconds * self.hz

    # -- queries -----------------------------------------------------------------------
    @property
    def fighting(self) -> bool:
        """True while blows count: in a round, not paused, nobody down (the count stops them)."""
        return self.phase == FIGHT and not self.paused

    @property
    def over(self) -> bool:
        return self.phase == OVER

    def seconds_left(self) -> float:
        return self.clock_steps / self.hz

    def snapshot(self) -> MatchSnapshot:
        return MatchSnapshot(
            (self.health[0], self.health[1]), self.round, self.rounds, self.seconds_left(), self.phase,
            self.count, tuple(self.downed), (self.knockdowns[0], self.knockdowns[1]), self.winner, self.result, self.paused,
        )

    def _down_key(self) -> int | tuple[int, ...] | None:
        """Who is down, for the state hash: the one boxer as before double knockdowns existed
        (so a match without one hashes as it did), both as a pair."""
        if len(self.downed) == 1:
            return self.downed[0]
        return tuple(self.downed) or None

    def drain_events(self) -> list[MatchEvent]:
        """What happened since the last call: ("bell", -1), ("knockdown", i), ("rise", i), ("over", i)..."""
        ev, self.events = self.events, []
        return ev

    def state(self) -> tuple:
        """Everything that defines the match, for state hashes."""
        return (
            self.round, self.phase, self.paused, self.clock_steps, tuple(round(h, 6) for h in self.health),
            tuple(self.knockdowns), tuple(self.round_knockdowns), tuple(round(d, 6) for d in self.round_damage),
            tuple(self.scores), self._down_key(), self.count, self.count_steps, self.winner, self.result, tuple(self.hits),
        )

    # -- input -------------------------------------------------------------------------
    def toggle_pause(self) -> None:
        if self.phase != OVER:
            self.paused = not self.paused

    def hit(self, target: int, damage: float) -> bool:
        """One blow on its own: `land` it, then `settle_knockdowns`. Returns whether it counted."""
        counted = self.land(target, damage)
        self.settle_knockdowns()
        return counted

    def land(self, target: int, damage: float) -> bool:
        """Boxer `target` takes `damage`; whether it goes down waits for `settle_knockdowns`, once
        every blow of the step has landed (deciding at the first blow let the other boxer's blow
        in the same step go uncounted: the order of the contacts decided the trade). Returns True
        when the blow counted (not a NaN or infinite one: NaN knocked the boxer down,
        max(0, health - nan) being 0, and left NaN in the round's damage)."""
        if not self.fighting or not math.isfinite(damage) or damage <= 0:
            return False
        attacker = 1 - target
        self.health[target] = max(0.0, self.health[target] - damage)
        self.round_damage[attacker] += damage
        self.hits[attacker] += 1
        return True

    def settle_knockdowns(self) -> None:
        """Every boxer the step's blows took to 0 health goes down, both at once when both were."""
        if not self.fighting:
            return
        floored = [i for i in (0, 1) if self.health[i] <= 0.0]
        if floored:
            self._knockdown(floored)

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

    def _knockdown(self, boxers: list[int]) -> None:
        for boxer in boxers:
            self.knockdowns[boxer] += 1
            self.round_knockdowns[boxer] += 1
        self.downed = list(boxers)
        self.phase = COUNT
        self.count = 0
        self.count_steps = 0
        for boxer in boxers:
            self.events.append(MatchEvent("knockdown", boxer))
        stopped = [b for b in boxers if self.round_knockdowns[b] >= KNOCKDOWNS_FOR_TKO]
        if stopped:
            # the other one down too and unable to rise either: neither can go on
            out = [b for b in boxers if b in stopped or self.rise_count(b) >= COUNT_OUT]
            if len(out) == 2:
                self._finish(None, DOUBLE_KO)
            else:
                # the winner, floored in this step too, gets up (a KO winner has risen by the 10)
                for boxer in boxers:
                    if boxer not in stopped:
                        self._rise(boxer)
                self._finish(1 - stopped[0], "TKO")

    def _maybe_rise(self) -> None:
        """Each boxer down rises at its own count; at COUNT_OUT whoever is still down is out."""
        for boxer in list(self.downed):
            rise = self.rise_count(boxer)
            if rise < COUNT_OUT and self.count >= rise:
                self._rise(boxer)
        if self.downed and self.count >= COUNT_OUT:
            if len(self.downed) == 2:
                self._finish(None, DOUBLE_KO)
            else:
                self._finish(1 - self.downed[0], "KO")
        elif not self.downed:
            self.phase = FIGHT

    def _rise(self, boxer: int) -> None:
        self.health[boxer] = RISE_HEALTH
        self.downed.remove(boxer)
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
        if result in ("KO", "TKO", DOUBLE_KO):
            self.round_winners.append(winner)  # the round ends with the match
        self.phase = OVER
        self.winner = winner
        self.result = result
        if result not in ("KO", "TKO", DOUBLE_KO):
            self.downed = []  # (nobody is down when the bell ends a round)
        self.events.append(MatchEvent("over", -1 if winner is None else winner))
