"""A 17-particle humanoid-like test body for the physics tests, in the joint order of the
contract (game.skeleton's JOINTS) but built here so the tests need nothing from game/."""

from __future__ import annotations

import numpy as np

JOINTS = ["pelvis", "spine", "chest", "neck", "head", "shoulder_l", "elbow_l", "fist_l",
          "shoulder_r", "elbow_r", "fist_r", "hip_l", "knee_l", "ankle_l", "hip_r", "knee_r", "ankle_r"]
J = {name: i for i, name in enumerate(JOINTS)}

# LOCAL frame: +x the body's right, y up, +z forward; a loose boxing guard
GUARD = np.array([
    [0.00, 1.00, 0.00],   # pelvis
    [0.00, 1.15, 0.00],   # spine
    [0.00, 1.35, 0.00],   # chest
    [0.00, 1.50, 0.00],   # neck
    [0.00, 1.65, 0.02],   # head
    [-0.20, 1.45, 0.00],  # shoulder_l
    [-0.25, 1.20, 0.15],  # elbow_l
    [-0.15, 1.45, 0.30],  # fist_l
    [0.20, 1.45, 0.00],   # shoulder_r
    [0.25, 1.20, 0.15],   # elbow_r
    [0.15, 1.45, 0.30],   # fist_r
    [-0.10, 0.95, 0.00],  # hip_l
    [-0.12, 0.52, 0.06],  # knee_l
    [-0.12, 0.08, 0.00],  # ankle_l
    [0.10, 0.95, 0.00],   # hip_r
    [0.12, 0.52, 0.06],   # knee_r
    [0.12, 0.08, 0.00],   # ankle_r
])

MASSES = np.array([10, 8, 12, 2, 5, 3, 2, 1, 3, 2, 1, 5, 4, 2, 5, 4, 2], dtype=float)

_BONES = [("pelvis", "spine"), ("spine", "chest"), ("chest", "neck"), ("neck", "head"),
          ("chest", "shoulder_l"), ("shoulder_l", "elbow_l"), ("elbow_l", "fist_l"),
          ("chest", "shoulder_r"), ("shoulder_r", "elbow_r"), ("elbow_r", "fist_r"),
          ("pelvis", "hip_l"), ("hip_l", "knee_l"), ("knee_l", "ankle_l"),
          ("pelvis", "hip_r"), ("hip_r", "knee_r"), ("knee_r", "ankle_r")]
# braces that make the torso a rigid-ish frame (Jakobsen's tetrahedra)
_BRACES = [("shoulder_l", "shoulder_r"), ("hip_l", "hip_r"), ("shoulder_l", "spine"),
           ("shoulder_r", "spine"), ("hip_l", "spine"), ("hip_r", "spine"), ("neck", "shoulder_l"),
           ("neck", "shoulder_r"), ("head", "chest")]
STICKS = np.array([(J[a], J[b]) for a, b in _BONES + _BRACES])

# capsule (a, b, radius, tag); a == b is a sphere
_CAPS = [("head", "head", 0.11, "head"), ("spine", "chest", 0.15, "torso"),
         ("pelvis", "spine", 0.13, "torso"),
         ("shoulder_l", "elbow_l", 0.05, "upperarm_l"), ("elbow_l", "fist_l", 0.045, "forearm_l"),
         ("fist_l", "fist_l", 0.06, "fist_l"),
         ("shoulder_r", "elbow_r", 0.05, "upperarm_r"), ("elbow_r", "fist_r", 0.045, "forearm_r"),
         ("fist_r", "fist_r", 0.06, "fist_r"),
         ("hip_l", "knee_l", 0.07, "thigh_l"), ("knee_l", "ankle_l", 0.05, "shin_l"),
         ("hip_r", "knee_r", 0.07, "thigh_r"), ("knee_r", "ankle_r", 0.05, "shin_r")]
CAPSULES = np.array([(J[a], J[b]) for a, b, _, _ in _CAPS])
RADII = np.array([r for _, _, r, _ in _CAPS])
TAGS = [t for _, _, _, t in _CAPS]

# elbows and knees may not fold shut nor (beyond straight) over-extend
LIMIT_PAIRS = np.array([(J["shoulder_l"], J["fist_l"]), (J["shoulder_r"], J["fist_r"]),
                        (J["hip_l"], J["ankle_l"]), (J["hip_r"], J["ankle_r"])])


def limit_ranges() -> np.ndarray:
    """min/max distance of each limit pair: 35 % .. 100 % of the two bones' length."""
    rng = []
    for a, c in LIMIT_PAIRS:
        b = {J["fist_l"]: J["elbow_l"], J["fist_r"]: J["elbow_r"],
             J["ankle_l"]: J["knee_l"], J["ankle_r"]: J["knee_r"]}[int(c)]
        full = np.linalg.norm(GUARD[b] - GUARD[a]) + np.linalg.norm(GUARD[c] - GUARD[b])
        rng.append((0.35 * full, full))
    return np.array(rng)


def place(local: np.ndarray, x: float, z: float, yaw: float) -> np.ndarray:
    """LOCAL joint positions -> WORLD, for a root at (x, z) facing yaw (0 faces +z)."""
    c, s = np.cos(yaw), np.sin(yaw)
    out = np.empty_like(local)
    out[:, 0] = c * local[:, 0] + s * local[:, 2] + x
    out[:, 1] = local[:, 1]
    out[:, 2] = -s * local[:, 0] + c * local[:, 2] + z
    return out


def add_humanoid(world, x: float = 0.0, z: float = 0.0, yaw: float = 0.0, limits: bool = True) -> int:
    """Add the test humanoid to `world` at root (x, z, yaw); returns its body id."""
    lim = (LIMIT_PAIRS, limit_ranges()) if limits else None
    return world.add_body(place(GUARD, x, z, yaw), MASSES, STICKS, CAPSULES, RADII, TAGS, limits=lim)
