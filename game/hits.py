"""Hits: which world contacts count as a punch landing.

A contact counts when a fist capsule of boxer A touches boxer B's head or torso while A's
current action has an AttackWindow for that hand at its current frame. A contact that lasts
is reported by the physics every step, so each hand lands at most once per swing. A fist
that meets B's gloves or forearms while B's GuardWindow covers the target is reported as a
blocked hit; a fist that reaches the head or body through an active guard window (a parry
or block that was too late to stop it physically) is reported with blocked=True as well.

Event (docs/motion.md, "Boxers and hits"): {"attacker": 0|1, "target": "head"|"body", "hand": "l"|"r",
"speed": m/s, "direction": (3,), "blocked": bool}; extras: "damage" from the window,
"point" (3,) where it landed.
"""

from __future__ import annotations

import numpy as np

from game.skeleton import joint_index

TARGET_TAGS = {"head": "head", "torso": "body"}
GUARD_TAGS = ("fist_l", "fist_r", "forearm_l", "forearm_r")
_HEAD = joint_index("head")


def hits_from_contacts(contacts: list, boxers: list) -> list[dict]:
    """Hit events of this step. `boxers` is the list of Boxer (index = "attacker" number);
    each has .body (world body id), .controller, .joint_positions() and .hand_spent()/.spend_hand()."""
    by_body = {b.body: i for i, b in enumerate(boxers)}
    events: list[dict] = []
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
            events.append({
                "attacker": ai, "target": target, "hand": hand, "speed": float(max(c.rel_speed, 0.0)),
                "direction": np.asarray(normal, dtype=float), "blocked": bool(blocked),
                "damage": float(window.damage), "point": np.asarray(c.point, dtype=float),
            })  # fmt: skip
    return events
