"""Build skeleton postures from a few boxing parameters (offline authoring aid).

A pose is described the way a coach would: where the pelvis is, how far hips and chest are
turned, how the trunk leans, where each glove and each foot is, and which way the elbows and
knees point. Two-bone IK places elbows and knees, so every posture has the skeleton's exact
bone lengths. tools/author_actions.py uses this to write game/assets/actions/*.json; the game
itself only reads the JSON.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from game.skeleton import BONE_LENGTHS, BONES, JOINTS, joint_index

J = joint_index


def _length(child: str) -> float:
    c = J(child)
    return float(BONE_LENGTHS[int(np.nonzero(BONES[:, 1] == c)[0][0])])


UPPER_ARM, FOREARM = _length("elbow_l"), _length("fist_l")
THIGH, SHIN = _length("knee_l"), _length("ankle_l")


def rot_y(deg: float) -> np.ndarray:
    """Yaw: positive turns forward (+z) towards the boxer's right (+x)."""
    a = np.radians(deg)
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def rot_x(deg: float) -> np.ndarray:
    """Forward lean: positive tips up (+y) towards forward (+z)."""
    a = np.radians(deg)
    c, s = np.cos(a), np.sin(a)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def rot_z(deg: float) -> np.ndarray:
    """Side lean: positive tips up (+y) towards the boxer's right (+x)."""
    a = np.radians(deg)
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])


def two_bone(root: np.ndarray, target: np.ndarray, l1: float, l2: float, pole: np.ndarray):
    """Middle joint and end point of a two-bone chain reaching for `target`, bending towards
    `pole` (a direction). A target out of reach is clamped onto the reach sphere."""
    d = target - root
    dist = float(np.linalg.norm(d))
    axis = d / max(dist, 1e-9)
    dist = min(max(dist, abs(l1 - l2) + 1e-4), (l1 + l2) * 0.9995)
    end = root + axis * dist
    a = (l1 * l1 - l2 * l2 + dist * dist) / (2.0 * dist)
    h = np.sqrt(max(l1 * l1 - a * a, 0.0))
    pole = np.asarray(pole, dtype=np.float64)
    perp = pole - axis * float(pole @ axis)
    if np.linalg.norm(perp) < 1e-6:  # pole along the chain: pick any perpendicular
        perp = np.cross(axis, [1.0, 0.0, 0.0])
        if np.linalg.norm(perp) < 1e-6:
            perp = np.cross(axis, [0.0, 0.0, 1.0])
    perp = perp / np.linalg.norm(perp)
    return root + axis * a + perp * h, end


@dataclass(frozen=True)
class Pose:
    """A boxing posture in the boxer's local frame (angles in degrees)."""

    pelvis: tuple = (0.0, 0.90, 0.0)
    hip_yaw: float = 25.0
    chest_yaw: float = 30.0
    lean_fwd: float = 4.0
    lean_side: float = 0.0
    head_pitch: float = 8.0  # chin tucked: head tipped forward relative to the trunk
    head_yaw: float = -25.0  # relative to the chest: eyes on the opponent despite the bladed chest
    fist_l: tuple = (-0.10, 1.44, 0.34)
    fist_r: tuple = (0.10, 1.42, 0.17)
    elbow_l: tuple = (-0.3, -1.0, -0.1)  # pole direction the elbow bends towards
    elbow_r: tuple = (0.3, -1.0, -0.1)
    ankle_l: tuple = (-0.15, 0.08, 0.22)
    ankle_r: tuple = (0.17, 0.08, -0.22)
    knee_l: tuple = (-0.2, 0.0, 1.0)
    knee_r: tuple = (0.3, 0.0, 1.0)
    extra: dict = field(default_factory=dict)

    def but(self, **kw) -> Pose:
        return replace(self, **kw)

    def joints(self) -> np.ndarray:
        out = np.zeros((len(JOINTS), 3))
        pelvis = np.array(self.pelvis, dtype=np.float64)
        lean = rot_y(self.hip_yaw) @ rot_x(self.lean_fwd) @ rot_z(self.lean_side)
        mid = rot_y(0.5 * (self.hip_yaw + self.chest_yaw)) @ rot_x(self.lean_fwd) @ rot_z(self.lean_side)
        upper = rot_y(self.chest_yaw) @ rot_x(self.lean_fwd) @ rot_z(self.lean_side)
        out[J("pelvis")] = pelvis
        out[J("spine")] = pelvis + lean @ [0.0, 0.15, 0.0]
        out[J("chest")] = out[J("spine")] + mid @ [0.0, 0.20, 0.0]
        out[J("neck")] = out[J("chest")] + upper @ [0.0, 0.20, 0.0]
        head = upper @ rot_y(self.head_yaw) @ rot_x(self.head_pitch)
        out[J("head")] = out[J("neck")] + head @ [0.0, 0.12, 0.0]
        hips = rot_y(self.hip_yaw)
        for side, sx in (("l", -1.0), ("r", 1.0)):
            sh = out[J("chest")] + upper @ [sx * 0.18, 0.15, 0.0]
            out[J(f"shoulder_{side}")] = sh
            fist = np.array(getattr(self, f"fist_{side}"), dtype=np.float64)
            elbow, fist = two_bone(sh, fist, UPPER_ARM, FOREARM, np.array(getattr(self, f"elbow_{side}")))
            out[J(f"elbow_{side}")], out[J(f"fist_{side}")] = elbow, fist
            hip = pelvis + hips @ [sx * 0.10, -0.03, 0.0]
            out[J(f"hip_{side}")] = hip
            ankle = np.array(getattr(self, f"ankle_{side}"), dtype=np.float64)
            knee, ankle = two_bone(hip, ankle, THIGH, SHIN, np.array(getattr(self, f"knee_{side}")))
            out[J(f"knee_{side}")], out[J(f"ankle_{side}")] = knee, ankle
        return out


GUARD = Pose()
