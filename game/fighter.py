"""A boxer in the ring: a particle body in the physics world, a PlayerController playing clips,
and a root transform (x, z, yaw) moved by the clips' root motion.

The CONTRACTS.md `game.boxer.Boxer` API (constructor, `controller`, `step(dt)`,
`joint_positions()`, `root`), used by the session until the motion helper's game.boxer lands.
Every step the controller gives the local reference posture, the root advances by the clip's
root motion (kept inside the ropes), and the body is pulled to the posture placed at the root
with a PD spring (stiffer at the hands, so punches arrive crisp).
"""

from __future__ import annotations

import numpy as np

from game.motion import PlayerController
from game.skeleton import BONES, JOINTS, compose_root, joint_index, local_to_world

RING_LIMIT = 2.6  # metres from the centre a root may go (the ropes are at 3)

_MASS = {"pelvis": 10.0, "spine": 8.0, "chest": 12.0, "neck": 2.0, "head": 5.0,
         "shoulder": 3.0, "elbow": 2.0, "fist": 1.0, "hip": 4.0, "knee": 4.0, "ankle": 2.0}  # fmt: skip
_STIFF = {"fist": 14.0, "elbow": 11.0, "head": 9.0}  # Hz; the rest STIFFNESS_HZ
STIFFNESS_HZ = 8.0

# (joint a, joint b, radius, tag): the collision capsules
CAPSULES = (
    ("head", "head", 0.12, "head"),
    ("pelvis", "chest", 0.16, "torso"),
    ("shoulder_l", "elbow_l", 0.05, "upperarm_l"), ("elbow_l", "fist_l", 0.045, "forearm_l"),
    ("fist_l", "fist_l", 0.07, "fist_l"),
    ("shoulder_r", "elbow_r", 0.05, "upperarm_r"), ("elbow_r", "fist_r", 0.045, "forearm_r"),
    ("fist_r", "fist_r", 0.07, "fist_r"),
    ("hip_l", "knee_l", 0.07, "thigh_l"), ("knee_l", "ankle_l", 0.055, "shin_l"),
    ("hip_r", "knee_r", 0.07, "thigh_r"), ("knee_r", "ankle_r", 0.055, "shin_r"),
)  # fmt: skip


def _by_prefix(table: dict[str, float], name: str, default: float) -> float:
    return table.get(name, table.get(name.split("_")[0], default))


class Boxer:
    def __init__(self, world, lib: dict, x: float = 0.0, z: float = 0.0, yaw: float = 0.0):
        self.world = world
        self.lib = lib
        self.controller = PlayerController(lib)
        self.root = (float(x), float(z), float(yaw))
        posture = local_to_world(self.controller.output, self.root)
        masses = np.array([_by_prefix(_MASS, n, 2.0) for n in JOINTS])
        self.stiffness = np.array([_by_prefix(_STIFF, n, STIFFNESS_HZ) for n in JOINTS])
        caps = np.array([(joint_index(a), joint_index(b)) for a, b, _, _ in CAPSULES])
        radii = np.array([r for _, _, r, _ in CAPSULES])
        tags = [t for _, _, _, t in CAPSULES]
        self.body_id = world.add_body(posture, masses, BONES, caps, radii, tags)
        self.slice = world.bodies[self.body_id].slice
        self.targets = posture

    def face(self, x: float, z: float, rate: float = 0.2) -> None:
        """Turn the root towards a point (the other boxer), `rate` of the way per call."""
        rx, rz, yaw = self.root
        want = np.arctan2(x - rx, z - rz)  # yaw 0 faces +z; positive yaw turns towards +x
        delta = (want - yaw + np.pi) % (2 * np.pi) - np.pi
        self.root = (rx, rz, yaw + rate * delta)

    def step(self, dt: float) -> None:
        posture = self.controller.step()
        x, z, yaw = compose_root(self.root, self.controller.root_delta)
        self.root = (float(np.clip(x, -RING_LIMIT, RING_LIMIT)), float(np.clip(z, -RING_LIMIT, RING_LIMIT)), float(yaw))
        self.targets = local_to_world(posture, self.root)
        self.world.set_targets(self.body_id, self.targets, self.stiffness)

    def push_root(self, dx: float, dz: float) -> None:
        """Move the root (the session keeps the two boxers apart)."""
        x, z, yaw = self.root
        self.root = (float(np.clip(x + dx, -RING_LIMIT, RING_LIMIT)), float(np.clip(z + dz, -RING_LIMIT, RING_LIMIT)), yaw)

    def joint_positions(self) -> np.ndarray:
        """(17, 3) simulated joints in the world frame (a view: copy to keep)."""
        return self.world.x[self.slice]
