"""The boxer's skeleton: 17 joints, the bones between them and their lengths.

Coordinates (docs/motion.md): metres, y up. A boxer's LOCAL frame has its origin on the ground
under the pelvis, +z forward (the way the boxer faces), +x the boxer's right. A boxer is
placed in the world by a root transform (x, z, yaw); yaw = 0 faces +z and a positive yaw
turns the boxer towards its right (+x): local forward (0, 0, 1) becomes (sin yaw, 0, cos yaw)
and local right (1, 0, 0) becomes (cos yaw, 0, -sin yaw). `local_to_world` does exactly this,
so every module places boxers the same way.
"""

from __future__ import annotations

import numpy as np

JOINTS: tuple[str, ...] = (
    "pelvis", "spine", "chest", "neck", "head",
    "shoulder_l", "elbow_l", "fist_l",
    "shoulder_r", "elbow_r", "fist_r",
    "hip_l", "knee_l", "ankle_l",
    "hip_r", "knee_r", "ankle_r",
)  # fmt: skip

_INDEX = {name: i for i, name in enumerate(JOINTS)}

# Each joint's parent (the pelvis is the root); BONES lists (parent, child) index pairs.
PARENTS: tuple[int, ...] = (
    -1, 0, 1, 2, 3,
    2, 5, 6,
    2, 8, 9,
    0, 11, 12,
    0, 14, 15,
)  # fmt: skip

BONES: np.ndarray = np.array([(p, c) for c, p in enumerate(PARENTS) if p >= 0], dtype=np.int64)

# Bone lengths of a ~1.78 m boxer, in metres, indexed like BONES (the child joint names the
# bone). The fist "joint" is the centre of the glove, so the forearm runs elbow -> glove.
_LENGTH_BY_CHILD = {
    "spine": 0.15, "chest": 0.20, "neck": 0.20, "head": 0.12,
    "shoulder_l": 0.2343, "elbow_l": 0.29, "fist_l": 0.30,
    "shoulder_r": 0.2343, "elbow_r": 0.29, "fist_r": 0.30,
    "hip_l": 0.1044, "knee_l": 0.43, "ankle_l": 0.43,
    "hip_r": 0.1044, "knee_r": 0.43, "ankle_r": 0.43,
}  # fmt: skip
BONE_LENGTHS: np.ndarray = np.array([_LENGTH_BY_CHILD[JOINTS[c]] for _, c in BONES])

# Joints grouped by depth in the tree, so bone lengths can be re-imposed one level at a time
# with whole-array numpy operations (5 levels instead of 16 bones).
_DEPTH = [0] * len(JOINTS)
for _j, _p in enumerate(PARENTS):
    _DEPTH[_j] = 0 if _p < 0 else _DEPTH[_p] + 1
LEVELS: list[np.ndarray] = [
    np.array([j for j in range(len(JOINTS)) if _DEPTH[j] == d], dtype=np.int64)
    for d in range(1, max(_DEPTH) + 1)
]
_CHILD_LENGTH = np.zeros(len(JOINTS))
for (_p, _c), _length in zip(BONES, BONE_LENGTHS, strict=True):
    _CHILD_LENGTH[_c] = _length
_PARENT_ARR = np.array(PARENTS, dtype=np.int64)
_LEVEL_PARENTS = [_PARENT_ARR[level] for level in LEVELS]
_LEVEL_LENGTHS = [_CHILD_LENGTH[level][:, None] for level in LEVELS]  # the skeleton's, per level


def joint_index(name: str) -> int:
    """Index of a joint in JOINTS; raises KeyError naming the joint when unknown."""
    try:
        return _INDEX[name]
    except KeyError:
        raise KeyError(f"unknown joint {name!r}; joints are {', '.join(JOINTS)}") from None


def bone_lengths(posture: np.ndarray) -> np.ndarray:
    """Lengths of BONES measured on a (..., 17, 3) posture."""
    p = np.asarray(posture)
    return np.linalg.norm(p[..., BONES[:, 1], :] - p[..., BONES[:, 0], :], axis=-1)


def impose_bone_lengths(posture: np.ndarray, lengths: np.ndarray | None = None) -> np.ndarray:
    """Forward kinematics from directions: keep the pelvis, then place every child along its
    (interpolated) bone direction at the skeleton's bone length. Interpolating joint positions
    shortens bones on arcs; this puts them back. Works on (17, 3) or (n, 17, 3)."""
    src = np.asarray(posture, dtype=np.float64)
    out = src.copy()
    level_lengths = _LEVEL_LENGTHS
    if lengths is not None:
        child_len = np.zeros(len(JOINTS))
        child_len[BONES[:, 1]] = lengths
        level_lengths = [child_len[level][:, None] for level in LEVELS]
    for level, parents, length in zip(LEVELS, _LEVEL_PARENTS, level_lengths, strict=True):
        d = src[..., level, :] - src[..., parents, :]
        norm = np.sqrt((d * d).sum(-1))[..., None]
        d *= (length / np.maximum(norm, 1e-9))
        out[..., level, :] = out[..., parents, :] + d
    return out


def local_to_world(points: np.ndarray, root: tuple[float, float, float]) -> np.ndarray:
    """Points (..., 3) in a boxer's local frame -> world, for root = (x, z, yaw)."""
    # written out rather than `@`: matmul goes to BLAS, whose kernels round differently on
    # different CPUs, and the state hash must be the same on every machine
    x, z, yaw = root
    p = np.asarray(points, dtype=np.float64)
    c, s = np.cos(yaw), np.sin(yaw)
    out = np.empty(p.shape)
    out[..., 0] = c * p[..., 0] + s * p[..., 2] + x
    out[..., 1] = p[..., 1]
    out[..., 2] = c * p[..., 2] - s * p[..., 0] + z
    return out


def world_to_local(points: np.ndarray, root: tuple[float, float, float]) -> np.ndarray:
    """Inverse of local_to_world."""
    x, z, yaw = root
    p = np.asarray(points, dtype=np.float64)
    c, s = np.cos(yaw), np.sin(yaw)
    dx, dz = p[..., 0] - x, p[..., 2] - z
    out = np.empty(p.shape)
    out[..., 0] = c * dx - s * dz
    out[..., 1] = p[..., 1]
    out[..., 2] = s * dx + c * dz
    return out


def compose_root(root: tuple[float, float, float], offset: np.ndarray) -> tuple[float, float, float]:
    """Apply a clip's root offset (dx, dz, dyaw), expressed in the boxer's local frame at the
    clip's start, to a world root (x, z, yaw)."""
    x, z, yaw = root
    dx, dz, dyaw = (float(v) for v in offset)
    c, s = np.cos(yaw), np.sin(yaw)
    return (x + c * dx + s * dz, z - s * dx + c * dz, yaw + dyaw)
