"""A boxer: a Jakobsen particle body in the physics world, a PlayerController that plays its
actions, and the root transform (x, z, yaw) that places the clip's local postures in the ring.

Each step: the controller yields the local reference posture and the clip's root motion; the
root moves by it; the reference goes to the world frame and the body is pulled towards it
(PD pull of the physics world, with the reference's own velocity so fast punches do not lag).
The root also follows the body when the body is held back (two boxers walking into each
other, a hit that shoves): beyond ROOT_SLACK of horizontal disagreement between the simulated
and the reference pelvis, the root gives way, so the pull never fights a wall forever.

    world = World(); lib = load_library()
    a = Boxer(world, lib, x=0.0, z=-0.5, yaw=0.0); b = Boxer(world, lib, z=0.5, yaw=math.pi)
    a.step(dt); b.step(dt); contacts = world.step(dt); hits = hits_from_contacts(contacts, [a, b])
"""

from __future__ import annotations

import numpy as np

from game.actions import HEAVY_HIT_SPEED, Action, reaction_for
from game.body import add_boxer_body
from game.hits import Hit, hits_from_contacts
from game.motion import PlayerController
from game.rules import FACE_RATE
from game.skeleton import compose_root, joint_index, local_to_world, world_to_local

__all__ = ["Boxer", "Hit", "hits_from_contacts"]

STIFFNESS_HZ = 7.0  # body and legs
ARM_STIFFNESS_HZ = 12.0  # elbows and fists follow punches closely
ROOT_SLACK = 0.06  # metres the simulated pelvis may trail the reference before the root gives
_ARM = np.array([joint_index(j) for j in ("elbow_l", "fist_l", "elbow_r", "fist_r")])


class Boxer:
    def __init__(self, world, lib: dict[str, Action], x: float = 0.0, z: float = -1.0, yaw: float = 0.0,
                 controller: PlayerController | None = None):  # fmt: skip
        self.world = world
        self.lib = lib
        self.controller = controller or PlayerController(lib)
        self._root = (float(x), float(z), float(yaw))
        self.reference = local_to_world(self.controller.output, self._root)
        self.body = add_boxer_body(world, self.reference)
        self.stiffness = np.full(len(self.reference), STIFFNESS_HZ)
        self.stiffness[_ARM] = ARM_STIFFNESS_HZ
        self._spent: set[str] = set()
        self._swing = self.controller.swing

    @property
    def root(self) -> tuple[float, float, float]:
        return self._root

    def place(self, x: float, z: float, yaw: float) -> None:
        """Teleport to a root (between rounds): body at rest in the current posture."""
        self._root = (float(x), float(z), float(yaw))
        self.reference = local_to_world(self.controller.output, self._root)
        self.world.set_positions(self.body, self.reference)

    def step(self, dt: float) -> np.ndarray:
        """Controller step, root motion, PD targets on the body. Returns the world reference."""
        pc = self.controller
        posture = pc.step()
        self._track_swing()
        x, z, yaw = compose_root(self._root, pc.root_delta)
        # the root gives way when the body is held back or pushed
        pelvis = self.joint_positions()[0]
        lag = np.array([pelvis[0] - self.reference[0, 0], pelvis[2] - self.reference[0, 2]])
        dist = float(np.hypot(*lag))
        if dist > ROOT_SLACK:
            x, z = x + lag[0] * (1 - ROOT_SLACK / dist), z + lag[1] * (1 - ROOT_SLACK / dist)
        self._root = (x, z, yaw)
        previous = self.reference
        self.reference = local_to_world(posture, self._root)
        velocities = (self.reference - previous) / dt
        self.world.set_targets(self.body, self.reference, self.stiffness, 1.0, velocities=velocities)
        return self.reference

    def joint_positions(self) -> np.ndarray:
        """(17, 3) simulated joints, WORLD frame."""
        return self.world.x[self.world.bodies[self.body].slice]

    # ---- hits -------------------------------------------------------------------------------
    def _track_swing(self) -> None:
        # a new clip (PlayerController.play) lets both hands land again; a switch does not (the
        # same motion relabelled: it cleared the spent hand and landed the same swing again)
        if self.controller.swing != self._swing:
            self._spent.clear()
        self._swing = self.controller.swing

    def hand_spent(self, hand: str) -> bool:
        return hand in self._spent

    def spend_hand(self, hand: str) -> None:
        self._spent.add(hand)

    def react(self, hit: Hit | dict, heavy_speed: float | None = None) -> str:
        """Play the reaction to `hit` (an event where this boxer was struck); returns its name."""
        hit = Hit.of(hit)
        direction = world_to_local(np.asarray(hit.direction, dtype=float), (0.0, 0.0, self._root[2]))
        speed = hit.speed
        if heavy_speed is not None:  # the caller's own heavy threshold, rescaled to the library's
            speed = speed * HEAVY_HIT_SPEED / heavy_speed
        name = reaction_for(hit.target, direction, speed)
        if name in self.lib:
            self.controller.play(name)
        return name

    def turn_towards(self, x: float, z: float, rate: float = FACE_RATE) -> None:
        """Turn the root's yaw `rate` of the way towards the world point (x, z) (the game keeps
        the two boxers facing each other)."""
        rx, rz, yaw = self._root
        want = float(np.arctan2(x - rx, z - rz))  # yaw 0 faces +z, positive turns towards +x
        delta = (want - yaw + np.pi) % (2 * np.pi) - np.pi
        self._root = (rx, rz, yaw + rate * delta)

    def keep_inside(self, limit: float) -> None:
        """Keep the root within `limit` metres of the ring's centre lines (inside the ropes)."""
        rx, rz, yaw = self._root
        # plain floats: np.clip on a Python float costs ~2 us, four times a step (the same values,
        # NaN and -0.0 included)
        self._root = (min(max(float(rx), -limit), limit), min(max(float(rz), -limit), limit), yaw)
