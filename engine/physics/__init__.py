"""Jakobsen Verlet particle bodies (paper section V; Jakobsen, "Advanced Character Physics",
GDC 2001).

    from engine.physics import World, Contact
    world = World(gravity=(0, -9.81, 0), ground_y=0.0, damping=0.01, iterations=4)
    bid = world.add_body(positions, masses, sticks, capsules, radii, capsule_tags, limits=None)
    world.set_targets(bid, targets, stiffness_hz, damping_ratio=1.0)
    contacts = world.step(1 / 60)

Design (details in docs/physics.md):
- State: every body's particles live in one (N, 3) array `world.x` with the previous
  positions in `world.x_prev` (Verlet); a body is a slice. All per-step work is numpy over
  all particles, sticks and capsule pairs; Python loops only over solver colours/iterations.
- Integration: velocity-form Verlet, v = (x - x_prev)/dt, damped by `damping` per step,
  gravity, then the PD pull to the reference posture integrated implicitly per particle
  (backward Euler of a spring-damper with natural frequency `stiffness` Hz): stable for any
  stiffness, and since it is a force in the integration step (not a constraint), its
  effective stiffness does not depend on `iterations`. The pull's acceleration is clamped
  (`max_accel`) and every speed too (`max_speed`), so a discontinuous change of reference
  posture moves the body smoothly.
- Bones are distance constraints (lo == hi == rest length), joint limits are the same
  constraint with lo < hi (acts only when violated). Relaxed `iterations` times with
  graph-coloured Gauss-Seidel: sticks are edge-coloured so that no two in a colour share a
  particle, and each colour is one numpy batch. That is sequential Gauss-Seidel exactly,
  conserves momentum, and converges faster per iteration than Jacobi (measured by
  `quickjab bench physics` and tests/engine/physics/test_constraints.py); a Jacobi solver
  (momentum-conserving averaging, over-relaxed) is available as solver="jacobi".
- Collision: capsules (segment + radius; a == b is a sphere) of DIFFERENT bodies; a broad
  phase on bounding spheres once per step, then closest points between segments (Ericson)
  vectorized over the candidate pairs, recomputed in each iteration; overlaps are pushed
  apart along the normal, split between the four segment ends by inverse mass and
  barycentric weight. Contacts found at the integrated positions, before resolution, are
  returned with their closing speed along the normal.
- Ground: a plane y = ground_y that particles cannot go below (optional friction).
"""

from engine.physics.collision import Contact
from engine.physics.world import Body, World

__all__ = ["World", "Contact", "Body"]
