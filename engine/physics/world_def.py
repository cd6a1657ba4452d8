"""The particle world's settings as data: `WorldDef`, a frozen dataclass of every constant
`World` is built with, with its default (as Box2D's `b2DefaultWorldDef()`).

    world = World.from_def(WorldDef(iterations=2))  # == World(iterations=2)

`World`'s keyword defaults are these fields, so `World()` and `World.from_def(WorldDef())` are
the same world, step for step (the state hash tests hold them to the bit).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

SOLVERS = ("jacobi", "gauss_seidel")


@dataclass(frozen=True)
class WorldDef:
    """Every setting of engine.physics.World (docs/physics.md has the model)."""

    # Gravity (m/s^2, world axes; y is up): the Earth's, so a knocked-down boxer falls as a body does.
    gravity: tuple[float, float, float] = (0.0, -9.81, 0.0)
    # The ground plane's height (m): no particle goes below it. 0: the ring's canvas.
    ground_y: float = 0.0
    # Damping (fraction of velocity lost per 1/60 s, Jakobsen's per-step damping): 0.01 takes the
    # jitter out of the PD pull without making blows look slow.
    damping: float = 0.01
    # Relaxation iterations per step of the sticks, joint limits and contacts: 4 keeps bones
    # within a millimetre at 60 Hz on the humanoid (the low-power mode halves it).
    iterations: int = 4
    # Constraint solver: "jacobi" (all sticks at once; the fastest at 17-34 particles with numpy)
    # or "gauss_seidel" (edge-coloured batches; converges faster per iteration, costs more per
    # call). `quickjab bench physics` prints both.
    solver: str = "jacobi"
    # Jacobi over-relaxation factor omega: corrections are scaled by min(1, omega / count) per
    # particle; 2 converges quickly and stays stable on the humanoid's joints.
    relaxation: float = 2.0
    # Clamp on the PD pull's acceleration (m/s^2): a sudden change of reference posture moves the
    # body smoothly instead of teleporting it. 200 is about 20 g, a fast punch's.
    max_accel: float = 200.0
    # Clamp on any particle's speed (m/s): 15 is above a punch's fist speed (about 10).
    max_speed: float = 15.0
    # Ground friction (0..1 of the sliding removed on the ground): 0, the boxers' roots are driven.
    ground_friction: float = 0.0
    # Capsule pairs closer than this (m) become contacts, so a blow is seen a step early: 5 cm.
    collision_margin: float = 0.05
    # Re-linearized contact passes after the iterations, at most: 3 leave no deep overlap.
    contact_passes: int = 3
    # Overlap (m) those passes leave alone: 1 mm, below what the renderer can show.
    contact_tolerance: float = 0.001

    def __post_init__(self) -> None:
        object.__setattr__(self, "gravity", tuple(float(v) for v in self.gravity))
        if len(self.gravity) != 3:
            raise ValueError("gravity must be 3 numbers (m/s^2)")
        if self.iterations < 1:
            raise ValueError("iterations must be >= 1")
        if not 0.0 <= self.damping < 1.0:
            raise ValueError("damping must be in [0, 1)")
        if self.solver not in SOLVERS:
            raise ValueError(f"solver must be one of {', '.join(SOLVERS)}, not {self.solver!r}")
        if self.contact_passes < 0 or self.contact_tolerance < 0:
            raise ValueError("contact_passes and contact_tolerance must be >= 0")

    def kwargs(self) -> dict[str, object]:
        """The World keywords this definition stands for."""
        return {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}


def default_world_def() -> WorldDef:
    """The default world's settings (Box2D's b2DefaultWorldDef())."""
    return WorldDef()
