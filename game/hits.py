"""Hits: which world contacts count as a punch landing.

A contact counts when a fist capsule of boxer A touches boxer B's head or torso while A's
current action has an AttackWindow for that hand at its current frame. A contact that lasts
is reported by the physics every step, so each hand lands at most once per swing. A fist
that meets B's gloves or forearms while B's GuardWindow covers the target is reported as a
blocked hit; a fist that reaches the head or body through an active guard window (a parry
or block that was too late to stop it physically) is reported with blocked=True as well.

Event (docs/motion.md, "Boxers and hits"): a `Hit` with attacker 0|1, target "head"|"body",
hand "l"|"r", speed m/s, direction (3,), blocked; extras: damage from the window, point (3,)
where it landed. `Hit.to_dict()` is the dict of those keys (JSON-ready).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from game.skeleton import joint_index

TARGET_TAGS = {"head": "head", "torso": "body"}
GUARD_TAGS = ("fist_l", "fist_r", "forearm_l", "forearm_r")
_HEAD = joint_index("head")
DEFAULT_DAMAGE = 8.0  # a blow with no window damage (an outside caller's hit) does this much


@dataclass(frozen=True, eq=False)  # eq=False: its arrays have no single truth value
class Hit:
    """A punch that landed this step (blocked or clean), from the physics contacts."""

    attacker: int  # 0 | 1: who threw it; the target boxer is the other one
    target: str  # "head" | "body"
    hand: str  # "l" | "r"
    speed: float  # closing speed along the contact normal, m/s
    direction: np.ndarray  # (3,) the contact normal, from the fist into the target
    blocked: bool
    damage: float = DEFAULT_DAMAGE  # the attack window's damage
    point: np.ndarray | None = None  # (3,) world point of the contact, when known

    def to_dict(self) -> dict[str, Any]:
        """The hit as plain JSON values (arrays as lists)."""
        out: dict[str, Any] = {"attacker": self.attacker, "target": self.target, "hand": self.hand,
                               "speed": self.speed, "direction": np.asarray(self.direction).tolist(),
                               "blocked": self.blocked, "damage": self.damage}
        if self.point is not None:
            out["point"] = np.asarray(self.point).tolist()
        return out

    # read like the dict it replaced (docs/motion.md documents these keys): hit["speed"]
    def __getitem__(self, key: str) -> Any:
        if key not in HIT_KEYS:
            raise KeyError(key)
        return getattr(self, key)

    def get(self, key: str, default: Any = None) -> Any:
        value = getattr(self, key, None) if key in HIT_KEYS else None
        return default if value is None else value

    @classmethod
    def of(cls, hit: Hit | dict) -> Hit:
        """A Hit as it is, or one from a dict with Hit's keys (callers outside the game)."""
        if isinstance(hit, Hit):
            return hit
        return cls(attacker=int(hit["attacker"]), target=hit["target"], hand=hit.get("hand", "r"),
                   speed=float(hit["speed"]), direction=np.asarray(hit.get("direction", (0.0, 0.0, 1.0)), dtype=float),
                   blocked=bool(hit["blocked"]), damage=float(hit.get("damage", DEFAULT_DAMAGE)),
                   point=None if hit.get("point") is None else np.asarray(hit["point"], dtype=float))


HIT_KEYS = frozenset(Hit.__dataclass_fields__)


def hits_from_contacts(contacts: list, boxers: list) -> list[Hit]:
    """Hit events of this step. `boxers` is the list of Boxer (index = "attacker" number);
    each has .body (world body id), .controller, .joint_positions() and .hand_spent()/.spend_hand()."""
    by_body = {b.body: i for i, b in enumerate(boxers)}
    events: list[Hit] = []
    for c in contacts:
        for side in (0, 1):
            if side == 0:
                body_f, tag_f, body_t, tag_t, normal = c.body_a, c.tag_a, c.body_b, c.tag_b, c.normal
            else:
                body_f, tag_f, body_t, tag_t, normal = c.body_b, c.tag_b, c.body_a, c.tag_a, -np.asarray(c.normal)
            if not tag_f.startswith("fist_") or body_f not in by_body or body_t not in by_body:
                continue
            ai, di = by_body[body_f], by_body[body_t]
            if ai == di:
                continue
            attacker, defender = boxers[ai], boxers[di]
            hand = tag_f[-1]
            pc = attacker.controller
            window = pc.clip.attack_at(pc.frame, hand)
            if window is None or attacker.hand_spent(hand):
                continue
            on_guard = tag_t in GUARD_TAGS
            if tag_t in TARGET_TAGS:
                target = TARGET_TAGS[tag_t]
                if target not in window.targets:
                    continue
            elif on_guard:
                head_y = defender.joint_positions()[_HEAD, 1]
                target = "head" if float(c.point[1]) > head_y - 0.2 else "body"
            else:
                continue
            dpc = defender.controller
            blocked = dpc.clip.guard_at(dpc.frame, target) is not None
            if on_guard and not blocked:
                continue  # glove on glove: a hit only if the defender is guarding, and then blocked
            attacker.spend_hand(hand)
            events.append(Hit(
                attacker=ai, target=target, hand=hand, speed=float(max(c.rel_speed, 0.0)),
                direction=np.asarray(normal, dtype=float), blocked=bool(blocked),
                damage=float(window.damage), point=np.asarray(c.point, dtype=float),
            ))  # fmt: skip
    return events
