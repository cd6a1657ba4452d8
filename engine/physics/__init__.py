"""Jakobsen Verlet particle bodies (paper section V; Jakobsen, "Advanced Character Physics",
GDC 2001).

    from engine.physics import World, Contact
    world = World(gravity=(0, -9.81, 0), ground_y=0.0, damping=0.01, iterations=4)
    world = World.from_def(WorldDef(iterations=4))        # the same, settings as data (world_def.py)
    bid = world.add_body(positions, masses, sticks, capsules, radii, capsule_tags, limits=None)
    world.set_targets(bid, targets, stiffness_hz, damping_ratio=1.0)
    contacts = world.step(1 / 60)

Design (details in docs/physics.md):
- State: every body's particles live in one (N, 3) array `world.x` with the previous
  positions in `world.x_prev` (Verlet); a body is a slice. All per-step work is numpy over
  all particles, sticks and capsule pairs; Python loops only over solver colours/iterations.
- Integration: velocity-form Verlet, v = (x - x_prev)/dt, damped by `damping` per 1/60 s,
  gravity, then the PD pull to the reference posture integrated implicitly per particle
  (backward Euler of a spring-damper with natural frequency `stiffness` Hz): stable for any
  stiffness, and since it is a force in the integration step (not a constraint), its
  effective stiffness does not depend on `iterations`. The pull's acceleration is clamped
  (`max_accel`) and every speed too (`max_speed`), so a discontinuous change of reference
  posture moves the body smoothly.
- Bones are distance constraints (lo == hi == rest length), joint limits are the same
  constraint with lo < hi (acts only when violated). Relaxed `iterations` times, by default
  Jacobi-style: all sticks at once from the same positions, corrections split by inverse
  mass and scaled by min(1, relaxation / max(count_i, count_j)) with relaxation = 2 (the
  same at both ends, so momentum is conserved). Graph-coloured Gauss-Seidel (solver="gauss_seidel": edge-coloured batches
  of independent sticks) converges about twice as fast per iteration but costs one batch per
  colour (6 on the test humanoid); at 17-34 particles numpy's per-call overhead is the cost,
  so Jacobi gets further in the same time (`quickjab bench physics` prints both).
- Collision: capsules (segment + radius; a == b is a sphere) of DIFFERENT bodies; a broad
  phase on bounding spheres once per step, then closest points between segments (Ericson)
  vectorized over the candidate pairs. Pairs touching or within `collision_margin` become
  contact constraints linearized at those closest points and projected in every iteration,
  then re-linearized final passes leave no overlap deeper than 1 mm. Overlaps are pushed
  apart along the normal, split between the four segment ends by inverse mass and
  barycentric weight. Contacts found at the integrated positions, before resolution, are
  returned with their closing speed along the normal.
- Ground: a plane y = ground_y that particles cannot go below (optional friction).
- Reproducible: no BLAS in the step (OpenBLAS kernels differ per CPU and round differently);
  gathers, elementwise operations, numpy reductions and np.bincount scatters give the same
  state_hash on every machine.
- world.x / world.x_prev are reallocated by add_body: don't keep references across it.
"""

from engine.physics.collision import Contact
from engine.physics.world import Body, World
from engine.physics.world_def import WorldDef, default_world_def

__all__ = ["World", "WorldDef", "default_world_def", "Contact", "Body"]
