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
  to hold it against a CPU that comes back (inf: neither; a rubber band, as boxing games do).

`adaptive` starts at normal and moves a continuous level in [0, 1] (0 easy, 0.5 normal, 1 hard)
after every round: up when the player won it, down when the player lost it, so the player's
round win rate settles near 50 %.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

LEVELS = ("easy", "normal", "hard")
CHOICES = (*LEVELS, "adaptive")
ADAPT_STEP = 0.15  # level change per round won or lost (a third of easy -> normal)
EASE_BEST = 0.9  # fully eased, the CPU takes its best action 90 % less often ...
EASE_REST = 5.0  # ... and rests six times as long between moves (what lets the novice back in)
PRESS_REST = 1.0  # trailing by ease_lead, it does not rest between moves at all


@dataclass(frozen=True)
class Difficulty:
    name: str
    best_share: float
    reaction_steps: int
    rest_steps: int
    damage: float
    ease_lead: float = float("inf")

    def eased(self, lead: float) -> tuple[float, int]:
        """(best_share, rest_steps) when the CPU leads the round by `lead` damage (< 0: trails)."""
        if not np.isfinite(self.ease_lead):
            return self.best_share, self.rest_steps
        f = float(np.clip(lead / self.ease_lead, -1.0, 1.0))
        ease, press = max(f, 0.0), max(-f, 0.0)
        return (self.best_share * (1.0 - EASE_BEST * ease),
                int(round(self.rest_steps * (1.0 + EASE_REST * ease) * (1.0 - PRESS_REST * press))))


# Tuned with `quickjab graph duel --opponent virtual` (docs/game.md has the figures).
PRESETS = {
    "easy": Difficulty("easy", best_share=0.6, reaction_steps=10, rest_steps=32, damage=0.6, ease_lead=2.0),
    "normal": Difficulty("normal", best_share=1.0, reaction_steps=0, rest_steps=14, damage=0.92, ease_lead=3.0),
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
                      1.0 / ease if ease > 0 else float("inf"))


class DifficultySetting:
    """The difficulty in play: a preset, or the adaptive level that follows the player."""

    def __init__(self, name: str = "normal", level: float = 0.5):
        if name not in CHOICES:
            raise ValueError(f"difficulty must be one of {', '.join(CHOICES)}, not {name!r}")
        self.name = name
        self.level = level
        self.current = PRESETS[name] if name in PRESETS else at_level(level)

    @property
    def label(self) -> str:
        return f"adaptive ({self.current.name.split()[-1]})" if self.name == "adaptive" else self.name

    def round_over(self, player_result: int) -> None:
        """A round ended: +1 the player won it, -1 the player lost it, 0 even."""
        if self.name == "adaptive" and player_result:
            self.level = float(np.clip(self.level + ADAPT_STEP * player_result, 0.0, 1.0))
            self.current = at_level(self.level)

    def next(self) -> DifficultySetting:
        """The next choice in the menu (easy -> normal -> hard -> adaptive -> easy)."""
        return DifficultySetting(CHOICES[(CHOICES.index(self.name) + 1) % len(CHOICES)], self.level)
