"""The particle world: every body's particles in one (N, 3) array, stepped as a whole."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from engine.physics.collision import Contact, kernels
from engine.physics.constraints import DistanceConstraints, project_kernel
from engine.physics.contacts import ContactDetector
from engine.physics.world_def import WorldDef
from engine.state_hash import state_hash as _hash


@dataclass
class Body:
    """One body's place in the world's arrays; its particles are world.x[body.slice]."""

    id: int
    slice: slice
    capsule_slice: slice  # into the world's capsule arrays
    capsules: np.ndarray  # (C, 2) local particle pairs
    radii: np.ndarray  # (C,)
    capsule_tags: list[str]
    sticks: np.ndarray  # (S, 2) local
    rest_lengths: np.ndarray  # (S,)
    masses: np.ndarray  # (P,)
    limits: np.ndarray = field(default_factory=lambda: np.zeros((0, 2), dtype=np.int64))
    limit_ranges: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))

    @property
    def n_particles(self) -> int:
        return self.slice.stop - self.slice.start


def _parse_limits(limits, n: int) -> tuple[np.ndarray, np.ndarray]:
    """limits: None, a pair (pairs (L, 2) int, ranges (L, 2) float), or rows (i, j, lo, hi)."""
    if limits is None:
        return np.zeros((0, 2), dtype=np.int64), np.zeros((0, 2))
    if isinstance(limits, tuple) and len(limits) == 2:
        pairs = np.asarray(limits[0], dtype=np.int64).reshape(-1, 2)
        ranges = np.asarray(limits[1], dtype=float).reshape(-1, 2)
    else:
        rows = np.asarray(limits, dtype=float).reshape(-1, 4)
        pairs, ranges = rows[:, :2].astype(np.int64), rows[:, 2:]
    if len(pairs) != len(ranges):
        raise ValueError(f"limits: {len(pairs)} pairs but {len(ranges)} ranges")
    if len(pairs) and (pairs.min() < 0 or pairs.max() >= n):
        raise ValueError("limits: particle index out of range")
    if np.any(ranges[:, 0] > ranges[:, 1]) or np.any(ranges < 0):
        raise ValueError("limits: each range must be 0 <= min <= max")
    return pairs, ranges


def _body_arrays(positions, masses, sticks, capsules, radii, capsule_tags):
    """add_body's arguments as checked arrays: (positions, masses, sticks, capsules, radii, tags)."""
    pos = np.asarray(positions, dtype=float)
    if pos.ndim != 2 or pos.shape[1] != 3 or len(pos) == 0:
        raise ValueError(f"positions must be (P, 3), got {pos.shape}")
    p = len(pos)
    m = np.asarray(masses, dtype=float).reshape(-1)
    if m.shape != (p,) or not np.all(m > 0) or not np.all(np.isfinite(m)):
        raise ValueError("masses must be (P,) finite and > 0")
    st = np.asarray(sticks, dtype=np.int64).reshape(-1, 2)
    caps = np.asarray(capsules, dtype=np.int64).reshape(-1, 2)
    rad = np.asarray(radii, dtype=float).reshape(-1)
    tags = list(capsule_tags)
    for name, a in (("sticks", st), ("capsules", caps)):
        if len(a) and (a.min() < 0 or a.max() >= p):
            raise ValueError(f"{name}: particle index out of range 0..{p - 1}")
    if len(st) and np.any(st[:, 0] == st[:, 1]):
        raise ValueError("sticks: a stick needs two different particles")
    if len(rad) != len(caps) or len(tags) != len(caps) or np.any(rad < 0):
        raise ValueError("capsules, radii (>= 0) and capsule_tags must have the same length")
    return pos, m, st, caps, rad, tags


_D = WorldDef()


class World:
    """Jakobsen particle bodies: Verlet integration with damping and an implicit PD pull to
    each particle's target, then `iterations` rounds of stick/limit relaxation, capsule
    collision between bodies and the ground plane. See engine/physics/__init__.py."""

    # The keyword defaults are WorldDef's (engine/physics/world_def.py documents each one).
    def __init__(self, gravity=_D.gravity, ground_y: float = _D.ground_y, damping: float = _D.damping,
                 iterations: int = _D.iterations, solver: str = _D.solver, relaxation: float = _D.relaxation,
                 max_accel: float = _D.max_accel, max_speed: float = _D.max_speed,
                 ground_friction: float = _D.ground_friction, collision_margin: float = _D.collision_margin,
                 contact_passes: int = _D.contact_passes, contact_tolerance: float = _D.contact_tolerance) -> None:
        if iterations < 1:
            raise ValueError("iterations must be >= 1")
        self.gravity = np.asarray(gravity, dtype=float).reshape(3)
        self.ground_y = float(ground_y)
        if not 0.0 <= damping < 1.0:
            raise ValueError("damping must be in [0, 1)")
        self.damping = float(damping)  # fraction of velocity lost per 1/60 s (Jakobsen's per step)
        self.iterations = int(iterations)
        self.solver = solver  # "jacobi" (default) or "gauss_seidel", see constraints.py
        self.relaxation = float(relaxation)  # Jacobi over-relaxation factor omega
        self.max_accel = float(max_accel)  # clamp on the PD pull's acceleration, m/s^2
        self.max_speed = float(max_speed)  # clamp on any particle's speed, m/s
        self.ground_friction = float(ground_friction)  # 0..1 of sliding removed on the ground
        self.collision_margin = float(collision_margin)
        self.contact_passes = int(contact_passes)  # re-linearized contact passes after the iterations, at most
        self.contact_tolerance = float(contact_tolerance)  # m of overlap those passes leave alone
        self.bodies: list[Body] = []
        self._pd_key: list = []  # per body: the (stiffness, damping) last set, as bytes
        self._target_vel_on: list[bool] = []
        self.steps = 0
        self._dt_prev: float | None = None
        self._alloc(0)
        self._detector = ContactDetector()
        self._rebuild()
        # The C kernels now, not in the first step with a contact: their first build on a
        # machine (a compiler run, seconds on a slow board) must not stall a match's opening.
        kernels()
        project_kernel()

    @classmethod
    def from_def(cls, world_def: WorldDef | None = None) -> World:
        """The world `world_def` describes (None: the defaults); the same as its fields as keywords."""
        return cls(**(world_def or WorldDef()).kwargs())

    @property
    def world_def(self) -> WorldDef:
        """This world's settings as a WorldDef."""
        return WorldDef(tuple(self.gravity.tolist()), self.ground_y, self.damping, self.iterations, self.solver,
                        self.relaxation, self.max_accel, self.max_speed, self.ground_friction,
                        self.collision_margin, self.contact_passes, self.contact_tolerance)

    # ---- building -------------------------------------------------------------------------

    def _alloc(self, n: int) -> None:
        self.x = np.zeros((n, 3))
        self.x_prev = np.zeros((n, 3))
        self.mass = np.ones(n)
        self.inv_mass = np.ones(n)
        self.targets = np.zeros((n, 3))
        self.target_vel = np.zeros((n, 3))
        self._w2 = np.zeros(n)  # omega^2 of the PD pull per particle (0: no pull)
        self._c = np.zeros(n)  # 2 zeta omega
        self._pd_dt = None  # dt the cached PD coefficients were computed for (None: stale)
        self._has_target_vel = False
        self._v = np.zeros((n, 3))  # per-step scratch buffers
        self._dv = np.zeros((n, 3))
        self._tmp = np.zeros((n, 3))

    def _grow(self, n_new: int) -> None:
        old = {k: getattr(self, k) for k in ("x", "x_prev", "mass", "inv_mass", "targets", "target_vel", "_w2", "_c")}
        n_old = len(self.x)
        self._alloc(n_old + n_new)
        for k, a in old.items():
            getattr(self, k)[:n_old] = a

    def add_body(self, positions, masses, sticks, capsules, radii, capsule_tags, limits=None) -> int:
        """Add a body; returns its id. Sticks keep their initial lengths. `limits` is None, a
        pair (pairs (L, 2) int, ranges (L, 2) float min/max distance) or rows (i, j, min, max)."""
        pos, m, st, caps, rad, tags = _body_arrays(positions, masses, sticks, capsules, radii, capsule_tags)
        p = len(pos)
        lim, lim_rng = _parse_limits(limits, p)
        rest = np.linalg.norm(pos[st[:, 1]] - pos[st[:, 0]], axis=1)

        start = len(self.x)
        self._grow(p)
        sl = slice(start, start + p)
        self.x[sl] = pos
        self.x_prev[sl] = pos
        self.mass[sl] = m
        self.inv_mass[sl] = 1.0 / m
        self.targets[sl] = pos
        c0 = self._detector.n_capsules
        bid = len(self.bodies)
        self._detector.add_capsules(caps + start, rad, tags, bid)
        self._pd_key.append(None)
        self._target_vel_on.append(False)
        self.bodies.append(Body(bid, sl, slice(c0, c0 + len(caps)), caps, rad, tags, st, rest, m, lim, lim_rng))
        self._rebuild()
        return bid

    def _rebuild(self) -> None:
        """Global constraint and capsule-pair tables from all bodies (on add_body only)."""
        pairs, lo, hi = [np.zeros((0, 2), dtype=np.int64)], [np.zeros(0)], [np.zeros(0)]
        for b in self.bodies:
            s0 = b.slice.start
            pairs += [b.sticks + s0, b.limits + s0]
            lo += [b.rest_lengths, b.limit_ranges[:, 0]]
            hi += [b.rest_lengths, b.limit_ranges[:, 1]]
        self.constraints = DistanceConstraints(np.concatenate(pairs), np.concatenate(lo),
                                               np.concatenate(hi), self.inv_mass, self.solver,
                                               self.relaxation)
        self._detector.rebuild(self.inv_mass, len(self.x))

    @property
    def pairs(self):
        """The capsule pairs between different bodies (a collision.CapsulePairs)."""
        return self._detector.pairs

    # ---- control --------------------------------------------------------------------------

    def set_targets(self, bid: int, targets, stiffness, damping_ratio=1.0, velocities=None) -> None:
        """Pull body `bid` towards `targets` (P, 3) world positions with a spring-damper of
        natural frequency `stiffness` Hz (scalar or (P,); 0 = no pull) and `damping_ratio`
        (1 = critical). `velocities` (P, 3), optional, are the targets' own velocities: the
        damper then acts on the velocity error and the body lags less behind a moving target.
        Integrated implicitly in the Verlet step, so the stiffness does not depend on
        `iterations` and any frequency is stable."""
        b = self.bodies[bid]
        sl = b.slice
        t = np.asarray(targets, dtype=float)
        if t.shape != (b.n_particles, 3):
            raise ValueError(f"targets must be ({b.n_particles}, 3), got {t.shape}")
        if not np.isfinite(t).all():  # one NaN would spread through the sticks to every particle
            raise ValueError("targets must be finite")
        self.targets[sl] = t
        k = np.asarray(stiffness, dtype=float)
        z = np.asarray(damping_ratio, dtype=float)
        key = (k.tobytes(), k.shape, z.tobytes(), z.shape)
        if self._pd_key[bid] != key:  # the game sets the same gains every step: skip the work
            omega = 2.0 * np.pi * k
            self._w2[sl] = omega * omega
            self._c[sl] = 2.0 * z * omega
            self._pd_dt = None
            self._pd_key[bid] = key
        if velocities is not None:
            self.target_vel[sl] = velocities
            self._target_vel_on[bid] = True
        elif self._target_vel_on[bid]:
            self.target_vel[sl] = 0.0
            self._target_vel_on[bid] = False
        self._has_target_vel = any(self._target_vel_on)

    def clear_targets(self, bid: int) -> None:
        """No pull on body `bid` (it goes limp: a knockdown)."""
        sl = self.bodies[bid].slice
        self._w2[sl] = 0.0
        self._c[sl] = 0.0
        self._pd_dt = None
        self._pd_key[bid] = None

    def set_positions(self, bid: int, positions) -> None:
        """Teleport body `bid` to `positions` (P, 3) at rest (no velocity)."""
        sl = self.bodies[bid].slice
        self.x[sl] = positions
        self.x_prev[sl] = self.x[sl]
        self._detector.forget()

    def velocity(self, dt: float) -> np.ndarray:
        """Particle velocities (N, 3) over the last step of length dt."""
        return (self.x - self.x_prev) / dt

    # ---- stepping -------------------------------------------------------------------------

    def _integrate(self, dt: float) -> np.ndarray:
        """Verlet in velocity form: v = (x - x_prev) / dt_prev, damped, gravity, the implicit PD
        pull (clamped), then x_prev <- x, x <- x + v dt. Returns v (a scratch buffer)."""
        x, v, dv, tmp = self.x, self._v, self._dv, self._tmp
        dt_prev = self._dt_prev or dt
        np.subtract(x, self.x_prev, out=v)
        # the same damping per second whatever dt: (1 - d) per 60 Hz step
        keep = (1.0 - self.damping) ** (dt * 60.0) if dt != 1.0 / 60.0 else 1.0 - self.damping
        v *= keep / dt_prev
        v += self.gravity * dt
        # Backward Euler on x'' = w2 (T - x') - c (v' - v_T), x' = x + dt v' gives
        #   v' - v = (dt w2 (T - x) + dt c v_T - (dt c + dt^2 w2) v) / (1 + dt c + dt^2 w2)
        # which is stable for any stiffness; particles with w2 = c = 0 get dv = 0.
        if self._pd_dt != dt:
            cdt = self._c * dt
            w2dt = self._w2 * dt
            denom = 1.0 + cdt + w2dt * dt
            self._pd_k = (w2dt / denom)[:, None]
            self._pd_kv = (cdt / denom)[:, None]
            self._pd_kd = ((cdt + w2dt * dt) / denom)[:, None]
            self._pd_dt = dt
        np.subtract(self.targets, x, out=dv)
        dv *= self._pd_k
        if self._has_target_vel:
            dv += np.multiply(self._pd_kv, self.target_vel, out=tmp)
        dv -= np.multiply(self._pd_kd, v, out=tmp)
        # max acceleration clamp: a discontinuous target moves the body smoothly
        amax = self.max_accel * dt
        n2 = (dv * dv).sum(1)
        if n2.max(initial=0.0) > amax * amax:
            dv *= np.minimum(1.0, amax / np.sqrt(np.maximum(n2, 1e-30)))[:, None]
        v += dv
        n2 = (v * v).sum(1)
        if n2.max(initial=0.0) > self.max_speed * self.max_speed:
            v *= np.minimum(1.0, self.max_speed / np.sqrt(np.maximum(n2, 1e-30)))[:, None]
        self.x_prev[:] = x
        x += np.multiply(v, dt, out=tmp)
        return v

    def step(self, dt: float) -> list[Contact]:
        """Advance by dt seconds; returns the capsule contacts between bodies found this step."""
        if not dt > 0:
            raise ValueError(f"dt must be > 0, got {dt}")
        x = self.x
        v = self._integrate(dt)
        self._dt_prev = dt
        contacts, cset, near_idx = self._detector.detect(x, self.x_prev, v, self.collision_margin)

        ground = x[:, 1]
        relax = self.constraints.relax
        for _ in range(self.iterations):
            relax(x)
            if cset is not None:
                cset.project(x)
            np.maximum(ground, self.ground_y, out=ground)
        if cset is not None:
            self._detector.separate(x, near_idx, self.contact_passes, self.contact_tolerance)
            np.maximum(ground, self.ground_y, out=ground)

        if self.ground_friction > 0.0:
            on = x[:, 1] <= self.ground_y + 1e-9
            if on.any():
                # the horizontal columns x and z (::2) at once; y is the ground's business
                pk = self.x_prev[on, ::2]
                x[on, ::2] = pk + (x[on, ::2] - pk) * (1.0 - self.ground_friction)
        self.steps += 1
        return contacts

    def state_hash(self) -> str:
        """Hash of the simulation state (positions, previous positions, step count)."""
        return _hash(self.x, self.x_prev, self.steps)
