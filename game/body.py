"""The boxer's particle body: one particle per skeleton joint, bones and torso braces as
sticks (Jakobsen's rigid-ish frame), elbow and knee range limits, and the capsules that
collide (head, torso, upper arms, forearms, fists, thighs, shins) with their contract tags."""

from __future__ import annotations

import numpy as np

from game.skeleton import BONE_LENGTHS, BONES, JOINTS, PARENTS, joint_index

J = joint_index

# kg, roughly a 75 kg boxer lumped on 17 particles (the fists carry glove and hand)
MASSES = np.array([
    12.0, 9.0, 12.0, 2.0, 5.0,  # pelvis spine chest neck head
    2.5, 1.8, 1.0,  # left arm
    2.5, 1.8, 1.0,  # right arm
    6.0, 3.5, 1.5,  # left leg
    6.0, 3.5, 1.5,  # right leg
])  # fmt: skip

# braces that keep the torso a frame (tetrahedra) and the head on it
_BRACES = [
    ("shoulder_l", "shoulder_r"), ("hip_l", "hip_r"), ("shoulder_l", "spine"), ("shoulder_r", "spine"),
    ("hip_l", "spine"), ("hip_r", "spine"), ("neck", "shoulder_l"), ("neck", "shoulder_r"),
    ("head", "chest"), ("shoulder_l", "pelvis"), ("shoulder_r", "pelvis"),
]  # fmt: skip
STICKS = np.vstack([BONES, np.array([(J(a), J(b)) for a, b in _BRACES])])

_CAPSULES = [
    ("head", "head", 0.11, "head"), ("spine", "chest", 0.15, "torso"), ("pelvis", "spine", 0.13, "torso"),
    ("shoulder_l", "elbow_l", 0.05, "upperarm_l"), ("elbow_l", "fist_l", 0.045, "forearm_l"),
    ("fist_l", "fist_l", 0.06, "fist_l"),
    ("shoulder_r", "elbow_r", 0.05, "upperarm_r"), ("elbow_r", "fist_r", 0.045, "forearm_r"),
    ("fist_r", "fist_r", 0.06, "fist_r"),
    ("hip_l", "knee_l", 0.07, "thigh_l"), ("knee_l", "ankle_l", 0.05, "shin_l"),
    ("hip_r", "knee_r", 0.07, "thigh_r"), ("knee_r", "ankle_r", 0.05, "shin_r"),
]  # fmt: skip
CAPSULES = np.array([(J(a), J(b)) for a, b, _, _ in _CAPSULES])
RADII = np.array([r for _, _, r, _ in _CAPSULES])
TAGS = [t for _, _, _, t in _CAPSULES]

# elbows and knees: neither folded shut nor bent past straight
LIMIT_PAIRS = np.array([(J("shoulder_l"), J("fist_l")), (J("shoulder_r"), J("fist_r")),
                        (J("hip_l"), J("ankle_l")), (J("hip_r"), J("ankle_r"))])  # fmt: skip


def limit_ranges() -> np.ndarray:
    """min/max shoulder-fist and hip-ankle distance: 12 % .. 100 % of the two bones."""
    length_to = dict(zip(BONES[:, 1].tolist(), BONE_LENGTHS.tolist(), strict=True))  # by child joint
    out = []
    for _a, c in LIMIT_PAIRS.tolist():
        full = length_to[PARENTS[c]] + length_to[c]  # the two bones: to the elbow/knee, then on
        out.append((0.12 * full, full))
    return np.array(out)


def add_boxer_body(world, positions: np.ndarray) -> int:
    """Add a body in the posture `positions` (17, 3 world) to `world`; returns its id. Brace
    rest lengths come from this posture (the guard), bones from the skeleton."""
    if np.shape(positions) != (len(JOINTS), 3):
        raise ValueError(f"a boxer body needs ({len(JOINTS)}, 3) positions")
    return world.add_body(positions, MASSES, STICKS, CAPSULES, RADII, TAGS, limits=(LIMIT_PAIRS, limit_ranges()))
