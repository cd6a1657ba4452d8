"""How hard the CPU boxes: `--difficulty easy|normal|hard|adaptive`.

The Interaction Graph's table gives the best action of every state; a difficulty decides how
the CPU uses it (issue 17: the graph alone won 200/200 bouts, and a human, whose every move
waits for the recognizer, was crushed):

- `best_share`: how often it takes the table's best action; otherwise one of the other
  actions, at random (a boxer who misreads the situation);
- `reaction_steps`: it sees the situation that many 60 Hz steps late (a human's reaction);
- `rest_steps`: steps at the guard after each of its moves before it may act again;
- `damage`: how much its blows count (a scale on the game's damage);
- `ease_lead`: when it leads the round by this much damage it eases off (takes its best action
  less often, rests longer; in proportion up to that lead), and when it trails by as much it
  presses (rests less): a player who falls behind gets back into the round, one who leads has
  to hold it (inf: neither; a rubber band, as boxing games do);
- `ease_form`, `ease_gain`: the CPU answers the player's success both ways (PlayerForm: the
  damage the player lands per round, from the rounds played). A player who lands less than
  `ease_form` (moves the recognizer rejects or misreads, blows that miss) gets a slower, gentler
  CPU: up to twice the easing when ahead, less pressing when behind, and blows that count down to
  30 %. One who lands more gets less easing (none at `ease_gain` times the excess = 1) and a CPU
  that presses: it rests less, takes its best action more often and its blows count more, up to
  a cap (FORM_PRESS_*). `ease_gain` 0: the form is not read. The rule reads outcomes, not the
  recognizer, so it corrects itself when recognition or the player gets better or worse.

`adaptive` starts at normal and moves a continuous level in [0, 1] (0 easy, 0.5 normal, 1 hard)
after every round: up when the player won it, down when the player lost it, so the player's
round win rate settles near 50 %.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

LEVELS = ("easy", "normal", "hard")
CHOICES = (*LEVELS, "adaptive")
ADAPT_STEP = 0.15  # level change per round won or lost (a third of easy -> normal)
EASE_BEST = 0.9  # fully eased, the CPU takes its best action 90 % less often ...
EASE_REST = 5.0  # ... rests six times as long between moves ...
EASE_DAMAGE = 0.7  # ... and its blows count 30 %
PRESS_REST = 1.0  # fully pressing, it does not rest between moves at all
LEAD_FORM = 1.0  # a struggling player's lead easing is up to twice as strong
# against a player who lands more than expected (by the full excess), at any lead:
FORM_PRESS_REST = 0.3  # it rests up to 30 % less between moves ...
FORM_PRESS_BEST = 1.0  # ... misses its best action up to never ...
FORM_PRESS_DAMAGE = 0.15  # ... and its blows count up to 15 % more (the cap)
FORM_PRIOR = 60.0  # damage per round a player not yet seen is taken to land
FORM_WEIGHT = 0.5  # the last round's weight in the average


class PlayerForm:
    """The player's recent success: the damage they land per round, from the rounds played
    (a moving average, so a few rounds tell). Read from the round's damage lead (the CPU's minus
    the player's) the CPU sees at each decision: a fall is the player landing a blow. Kept
    across matches and difficulty changes (it is the player's, not the CPU's)."""

    def __init__(self, per_round: float = FORM_PRIOR) -> None:
        self.per_round = per_round  # damage the player lands in a round, recent rounds weighted most
        self.landed = 0.0  # damage the player landed in this round so far
        self._lead = 0.0

    def observe(self, lead: float) -> None:
        """The round's damage lead of the CPU now."""
        change, self._lead = lead - self._lead, lead
        if change < 0.0:
            self.landed -= change

    def abandon_round(self) -> None:
        """A round left unfinished (a new match started in it): nothing of it counts, and the
        next lead is read from 0 (the new match's), not as a fall from the old round's."""
        self.landed = 0.0
        self._lead = 0.0

    def new_round(self) -> None:
        """A round ended: its damage joins the average; the next round counts from 0."""
        self.per_round += FORM_WEIGHT * (self.landed - self.per_round)
        self.landed = 0.0
        self._lead = 0.0


@dataclass(frozen=True)
class Difficulty:
    name: str
    best_share: float
    reaction_steps: int
    rest_steps: int
    damage: float
    ease_lead: float = float("inf")
    ease_form: float = 60.0
    ease_gain: float = 0.0

    def shortfall(self, per_round: float) -> float:
        """How far the player's damage per round falls short of this level's `ease_form`, -1..1
        (< 0: the player lands more)."""
        return float(np.clip(self.ease_gain * (1.0 - per_round / self.ease_form), -1.0, 1.0))

    def eased(self, lead: float, per_round: float = float("nan")) -> tuple[float, int, float]:
        """(best_share, rest_steps, damage) when the CPU leads the round by `lead` damage (< 0:
        trails) against a player who lands `per_round` damage a round (nan: as expected)."""
        w = self.shortfall(per_round) if np.isfinite(per_round) else 0.0
        f = float(np.clip(lead / self.ease_lead, -1.0, 1.0)) if np.isfinite(self.ease_lead) else 0.0
        ease = max(f, 0.0) * max(1.0 + LEAD_FORM * w, 0.0)
        press = max(-f, 0.0) * (1.0 - max(w, 0.0))
        excess = max(-w, 0.0)  # the player lands more than expected: the CPU presses
        best = self.best_share + (1.0 - self.best_share) * FORM_PRESS_BEST * excess
        return (best * (1.0 - EASE_BEST * min(ease, 1.0)),
                int(round(self.rest_steps * (1.0 + EASE_REST * ease) * (1.0 - PRESS_REST * press)
                          * (1.0 - FORM_PRESS_REST * excess))),
                self.damage * (1.0 - EASE_DAMAGE * max(w, 0.0)) * (1.0 + FORM_PRESS_DAMAGE * excess))


# Tuned with `quickjab graph duel --opponent virtual` (docs/game.md has the figures).
PRESETS = {
    "easy": Difficulty("easy", best_share=0.6, reaction_steps=10, rest_steps=32, damage=0.6,
                       ease_lead=2.0, ease_form=80.0, ease_gain=1.0),
    "normal": Difficulty("normal", best_share=1.0, reaction_steps=0, rest_steps=14, damage=0.92,
                         ease_lead=3.0, ease_form=60.0, ease_gain=1.5),
    "hard": Difficulty("hard", best_share=1.0, reaction_steps=0, rest_steps=12, damage=1.0),
}


def at_level(level: float) -> Difficulty:
    """The presets interpolated: 0 easy, 0.5 normal, 1 hard (the adaptive CPU's settings)."""
    level = float(np.clip(level, 0.0, 1.0))
    lo, hi, f = (PRESETS["easy"], PRESETS["normal"], level / 0.5) if level <= 0.5 else \
        (PRESETS["normal"], PRESETS["hard"], (level - 0.5) / 0.5)

    def mix(a: float, b: float) -> float:
        return a + (b - a) * f

    # easing mixed as its strength (1 / lead): none (hard) is 0
    ease = mix(1.0 / lo.ease_lead, 1.0 / hi.ease_lead)
    return Difficulty(f"adaptive {level:.2f}", mix(lo.best_share, hi.best_share),
                      int(round(mix(lo.reaction_steps, hi.reaction_steps))),
                      int(round(mix(lo.rest_steps, hi.rest_steps))), mix(lo.damage, hi.damage),
                      1.0 / ease if ease > 0 else float("inf"), mix(lo.ease_form, hi.ease_form),
                      mix(lo.ease_gain, hi.ease_gain))


@dataclass
class CpuPolicy:
    """The CPU in play: a level's Difficulty, eased by the player's form. The session reads
    `best_share` / `reaction_steps` (the policy's base), `eased(lead)` at each decision and
    `damage` at each of its blows."""

    level: Difficulty
    form: PlayerForm = field(default_factory=PlayerForm)

    @property
    def name(self) -> str:
        return self.level.name

    @property
    def best_share(self) -> float:
        return self.level.best_share

    @property
    def reaction_steps(self) -> int:
        return self.level.reaction_steps

    @property
    def rest_steps(self) -> int:
        return self.level.rest_steps

    @property
    def damage(self) -> float:
        """How much its next blow counts, against the player's form now."""
        return self.level.eased(0.0, self.form.per_round)[2]

    def eased(self, lead: float) -> tuple[float, int]:
        """(best_share, rest_steps) for its next decision, given the round's damage lead of the
        CPU now (the form learns from it)."""
        self.form.observe(lead)
        best, rest, _ = self.level.eased(lead, self.form.per_round)
        return best, rest


class DifficultySetting:
    """The difficulty in play: a preset, or the adaptive level that follows the player."""

    def __init__(self, name: str = "normal", level: float = 0.5, form: PlayerForm | None = None):
        if name not in CHOICES:
            raise ValueError(f"difficulty must be one of {', '.join(CHOICES)}, not {name!r}")
        self.name = name
        self.level = level
        self.form = form if form is not None else PlayerForm()
        self.current = CpuPolicy(PRESETS[name] if name in PRESETS else at_level(level), self.form)

    @property
    def label(self) -> str:
        return f"adaptive ({self.current.name.split()[-1]})" if self.name == "adaptive" else self.name

    def round_over(self, player_result: int) -> None:
        """A round ended: +1 the player won it, -1 the player lost it, 0 even."""
        self.form.new_round()
        if self.name == "adaptive" and player_result:
            self.level = float(np.clip(self.level + ADAPT_STEP * player_result, 0.0, 1.0))
            self.current = CpuPolicy(at_level(self.level), self.form)

    def next(self) -> DifficultySetting:
        """The next choice in the menu (easy -> normal -> hard -> adaptive -> easy); the player's
        form carries over."""
        return DifficultySetting(CHOICES[(CHOICES.index(self.name) + 1) % len(CHOICES)], self.level, self.form)
