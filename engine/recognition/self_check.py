"""How well a player's trained moves tell each other apart, as `quickjab train` reports when it
saves them: each new trial replayed through the game's recognizer with every template but its own
(leave one out). A move taken for another here is one the game will mistake too: the player
learns it at once, not in a match.

The held-out trial's template is left out; the other templates keep the rejection thresholds
measured with it among their action's trials (a little looser than a set built without it).
Rebuilding the held-out action's templates for each trial costs about half as much again and, on
the virtual player's sets (13 moves, experienced and novice, 3 or 5 trials: 369 trials), changed
no trial's answer: its mistakes are moves taken for others, not rejections."""

from __future__ import annotations

from collections import Counter
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from engine.recognition.dual_buffer import DualBufferRecognizer
from engine.recognition.templates import Templates

# Rest around a replayed trial (frames): its first reading before, as a player holds still before
# a move; its last after, time for the motion to end (as `quickjab evaluate` pads isolated trials).
PAD_BEFORE, PAD_AFTER = 20, 40


@dataclass
class SelfCheck:
    """`right` of `trials` held-out trials ended as their own action; `taken_for` counts the
    others by (action, what it was taken for: another action, or None for no decision)."""

    trials: int = 0
    right: int = 0
    taken_for: Counter[tuple[str, str | None]] = field(default_factory=Counter)


def final_action(events: Sequence) -> str | None:
    """The last action the trial's first decided motion was decided as (its start, then its
    switches, up to its end: a later motion is the hand's return), None when nothing was decided
    or the start was called off (as `quickjab evaluate` scores a trial)."""
    final = None
    for ev in events:
        if ev.event == "start":
            if final is not None:
                break  # a second motion
            final = ev.action
        elif final is not None and ev.event == "switch":
            final = ev.action
        elif final is not None and ev.event in ("end", "reject"):
            return None if ev.event == "reject" else final
    return final


def without(templates: Templates, k: int) -> Templates:
    """`templates` less its k-th template (thresholds, settings and meta as they are)."""
    keep = [i for i in range(len(templates)) if i != k]
    return Templates([templates.actions[i] for i in keep], [templates.signals[i] for i in keep],
                     templates.gravity[keep], templates.onsets[keep], templates.thresholds[keep],
                     templates.method, templates.feature, dict(templates.meta), templates.rest_noise,
                     dict(templates.recognizer))


def leave_one_out(templates: Templates, first: int, trials: Mapping[str, Sequence[np.ndarray]],
                  settings: Mapping[str, object] | None = None) -> SelfCheck:
    """Replay each of `trials` ({action: [trial (n, D)]}, in the order its templates were built:
    one template per trial from index `first` of `templates`, as `Templates.from_trials` with the
    "trials" method makes them) through a recognizer of `settings` built without its template."""
    out = SelfCheck()
    for out in leave_one_out_steps(templates, first, trials, settings):  # noqa: B007 - the last is the whole
        pass
    return out


def leave_one_out_steps(templates: Templates, first: int, trials: Mapping[str, Sequence[np.ndarray]],
                        settings: Mapping[str, object] | None = None) -> Iterator[SelfCheck]:
    """`leave_one_out` a trial at a time: the check so far after each (a game loop spreads the
    work over its steps, a trial a step, and its window keeps answering)."""
    out = SelfCheck()
    k = first
    for action, items in trials.items():
        for trial in items:
            if templates.actions[k] != action:
                raise ValueError(f"template {k} is {templates.actions[k]!r}, not the trial's {action!r}")
            if sum(a == action for a in templates.actions) > 1:  # a lone trial has nothing to match
                rec = DualBufferRecognizer.from_config(without(templates, k), settings)
                stream = np.vstack([np.repeat(trial[:1], PAD_BEFORE, 0), trial, np.repeat(trial[-1:], PAD_AFTER, 0)])
                taken = final_action([ev for frame in stream for ev in rec.push(frame)])
                out.trials += 1
                if taken == action:
                    out.right += 1
                else:
                    out.taken_for[(action, taken)] += 1
            k += 1
            yield out


def said(check: SelfCheck) -> list[str]:
    """The check in a few lines for the player: the figure, then each confusion."""
    if not check.trials:
        return []
    lines = [f"each new trial against the rest (the game's recognizer, its own template left out): "
             f"{check.right} of {check.trials} recognized"]
    for (action, taken), n in check.taken_for.most_common():
        lines.append(f"  {action}: {'not recognized' if taken is None else f'taken for {taken}'} {n} time{'s' * (n > 1)}")
    return lines
