"""The referee's judgement: which touches are blows, how much they hurt, whether they were blocked.

Input is the physics step's contacts. A blow is a fist capsule of boxer A touching the head or
torso of boxer B while A's current clip has an AttackWindow for that hand open; B blocks it
when B's clip has a GuardWindow covering that target open, or when the fist met B's gloves or
forearms (the guard stopped it: a blocked blow at the head). Each punch lands at most once
(a fist stays in contact for several steps). Damage is the window's damage scaled by the
closing speed, a fifth of it through a block.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

REFERENCE_SPEED = 4.0  # m/s: a blow at this closing speed does the window's damage
BLOCKED_SHARE = 0.2
HEAVY_SPEED = 5.0


@dataclass
class Blow:
    attacker: int
    target: str  # "head" | "body"
    hand: str  # "l" | "r"
    speed: float
    direction: np.ndarray
    blocked: bool
    damage: float
    point: np.ndarray
    action: str

    def as_event(self) -> dict:
        """The CONTRACTS.md hit-event dict."""
        return {"attacker": self.attacker, "target": self.target, "hand": self.hand,
                "speed": self.speed, "direction": self.direction, "blocked": self.blocked}


def target_of(tag: str) -> str | None:
    """Which target a capsule tag is: head, body, "guard" (gloves and forearms: a punch into
    them is blocked), or nothing a blow scores on."""
    if tag.startswith("head"):
        return "head"
    if tag.startswith(("torso", "chest", "body", "abdomen", "spine", "pelvis")):
        return "body"
    if tag.startswith(("fist", "forearm")):
        return "guard"
    return None


class Referee:
    def __init__(self, lib: dict):
        self.lib = lib
        self._landed: list[tuple[str, int, str] | None] = [None, None]  # (action, window start, hand)

    def judge(self, contacts: list, body_ids: tuple[int, int], controllers: tuple) -> list[Blow]:
        """Blows among `contacts`; body_ids[i] and controllers[i] belong to boxer i."""
        index = {body_ids[0]: 0, body_ids[1]: 1}
        for i in (0, 1):  # a new clip may land again
            landed = self._landed[i]
            if landed is not None and controllers[i].action != landed[0]:
                self._landed[i] = None
        blows: list[Blow] = []
        for c in contacts:
            for body_a, tag_a, body_b, tag_b, sign in ((c.body_a, c.tag_a, c.body_b, c.tag_b, 1.0),
                                                        (c.body_b, c.tag_b, c.body_a, c.tag_a, -1.0)):
                if body_a not in index or body_b not in index or not tag_a.startswith("fist_"):
                    continue
                target = target_of(tag_b)
                if target is None:
                    continue
                a, b = index[body_a], index[body_b]
                hand = tag_a[-1]
                ctrl = controllers[a]
                action = self.lib.get(ctrl.action)
                if action is None:
                    continue
                window = action.attack_at(ctrl.frame, hand) if hasattr(action, "attack_at") else next(
                    (w for w in action.attacks if w.hand == hand and w.start <= ctrl.frame <= w.end), None)
                if window is None or (target != "guard" and target not in window.targets):
                    continue
                key = (ctrl.action, window.start, hand)
                if self._landed[a] == key:
                    continue
                self._landed[a] = key
                defender = self.lib.get(controllers[b].action)
                # into the gloves: blocked (a punch that the guard stops, at the head)
                blocked = target == "guard" or bool(defender is not None and any(
                    g.start <= controllers[b].frame <= g.end and target in g.covers for g in defender.guards))
                if target == "guard":
                    target = "head"
                speed = float(abs(c.rel_speed))
                scale = float(np.clip(speed / REFERENCE_SPEED, 0.5, 1.5))
                damage = window.damage * scale * (BLOCKED_SHARE if blocked else 1.0)
                # the normal points from a to b in the contact; flip when the fist is body_b
                direction = np.asarray(c.normal, dtype=np.float64) * sign
                blows.append(Blow(a, target, hand, speed, direction, blocked, damage,
                                  np.asarray(c.point, dtype=np.float64).copy(), ctrl.action))
        return blows


def reaction_name(blow: Blow, lib: dict) -> str:
    """The hit reaction the target plays: hit_<where>_<side>_<strength> where it exists."""
    kind = blow.action.split("_")[0]
    if kind == "hook":
        # a right hook arrives on the target's left side
        side = "left" if blow.hand == "r" else "right"
    else:
        side = "front"
    strength = "heavy" if blow.speed >= HEAVY_SPEED or blow.damage >= 12 else "light"
    name = f"hit_{blow.target}_{side}_{strength}"
    return name if name in lib else ("hit_head_front_light" if "hit_head_front_light" in lib else "guard")
