"""The state of an interaction between two boxers, seen by the one about to choose.

A decision happens when a boxer is back at the guard (its clip finished), as in Shum et al.
(I3D 2008): the chooser is always at the guard, so its own action is not part of the state.
What matters to it is where the other boxer is and what the other is doing:

- ``distance``      metres between the two roots (ground plane),
- ``bearing_self``  angle of the other as seen from the chooser's facing (0 = straight ahead,
                    positive towards the chooser's right), radians in [-pi, pi),
- ``bearing_other`` angle of the chooser as seen from the other's facing, same convention,
- ``other_action``  the other's action (an index into the bout model's action table; the
                    READY code means "also at the guard, about to choose"),
- ``other_frame``   how far the other is into that action, in 60 Hz clip frames.

The relative facing is not stored: with the two bearings and the distance the planar
relative pose is fixed (rel_facing = pi + bearing_self - bearing_other), so storing it would
only add a redundant dimension to quantize.

Continuous parts are quantized on a grid (``StateGrid``): states whose cells coincide are
merged, so the grid steps are the merge threshold, and a live situation maps to the state of
its cell; when that cell was never sampled, to the nearest sampled state of the same action
and phase bucket in the grid-normalized metric (one grid step = one unit in each dimension).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

TWO_PI = 2.0 * math.pi


def wrap_angle(a):
    """Angle(s) wrapped to [-pi, pi)."""
    return (np.asarray(a) + math.pi) % TWO_PI - math.pi


def bearing(from_xz, from_yaw, to_xz):
    """Angle of `to` seen from a boxer at `from_xz` facing `from_yaw` (vectorized)."""
    d = np.asarray(to_xz) - np.asarray(from_xz)
    return wrap_angle(np.arctan2(d[..., 0], d[..., 1]) - from_yaw)


def relative_pose(self_xz, self_yaw, other_xz, other_yaw):
    """(distance, bearing_self, bearing_other) of two planar roots (vectorized)."""
    self_xz = np.asarray(self_xz, dtype=float)
    other_xz = np.asarray(other_xz, dtype=float)
    dist = np.hypot(*(other_xz - self_xz).T) if self_xz.ndim > 1 else float(
        np.hypot(*(other_xz - self_xz)))
    return dist, bearing(self_xz, self_yaw, other_xz), bearing(other_xz, other_yaw, self_xz)


@dataclass(frozen=True)
class StateGrid:
    """Quantization of the continuous state parts; the cell size is the merge threshold."""

    distance_step: float = 0.025     # metres
    angle_step_deg: float = 5.0      # degrees, both bearings
    phase_step: int = 1              # clip frames
    distance_max: float = 4.0        # beyond this, all distances share the last bin
    max_frames: int = 256            # upper bound of any action's length (sizes the key)

    @property
    def angle_step(self) -> float:
        return math.radians(self.angle_step_deg)

    @property
    def n_distance(self) -> int:
        return int(math.ceil(self.distance_max / self.distance_step))

    @property
    def n_angle(self) -> int:
        return int(round(360.0 / self.angle_step_deg))

    @property
    def n_phase(self) -> int:
        return self.max_frames // self.phase_step + 1

    def bins(self, distance, bearing_self, bearing_other, other_frame):
        """Integer bins (d, bs, bo, phase), vectorized."""
        nd, na = self.n_distance, self.n_angle
        # multiply by the reciprocal, as the scalar look-up does, so both agree on borders
        ds, as_ = 1.0 / self.distance_step, 1.0 / self.angle_step
        two_pi = 2.0 * math.pi
        db = np.clip(np.floor(np.asarray(distance) * ds), 0, nd - 1).astype(np.int64)
        sb = np.floor(((np.asarray(bearing_self) + math.pi) % two_pi) * as_).astype(np.int64) % na
        ob = np.floor(((np.asarray(bearing_other) + math.pi) % two_pi) * as_).astype(np.int64) % na
        pb = np.clip(np.asarray(other_frame) // self.phase_step, 0, self.n_phase - 1).astype(np.int64)
        return db, sb, ob, pb

    def bucket(self, other_action, phase_bin):
        """The discrete part of a key: which action the other is in and how far."""
        return np.asarray(other_action, dtype=np.int64) * self.n_phase + phase_bin

    def key(self, distance, bearing_self, bearing_other, other_action, other_frame):
        """One int64 per state cell (vectorized)."""
        db, sb, ob, pb = self.bins(distance, bearing_self, bearing_other, other_frame)
        na = self.n_angle
        return ((self.bucket(other_action, pb) * self.n_distance + db) * na + sb) * na + ob

    def split_key(self, key):
        """Inverse of `key`: (bucket, d_bin, bs_bin, bo_bin)."""
        key = np.asarray(key, dtype=np.int64)
        na, nd = self.n_angle, self.n_distance
        ob = key % na
        sb = (key // na) % na
        db = (key // (na * na)) % nd
        bucket = key // (na * na * nd)
        return bucket, db, sb, ob

    def normalized(self, distance, bearing_self, bearing_other):
        """Continuous coordinates in grid units (angles unwrapped to [0, n_angle))."""
        return np.stack([
            np.asarray(distance, dtype=float) / self.distance_step,
            (wrap_angle(bearing_self) + math.pi) / self.angle_step,
            (wrap_angle(bearing_other) + math.pi) / self.angle_step,
        ], axis=-1)

    def cell_centres(self, key):
        """Grid-unit coordinates of the centres of these cells, shape (n, 3)."""
        _, db, sb, ob = self.split_key(key)
        return np.stack([db + 0.5, sb + 0.5, ob + 0.5], axis=-1).astype(float)

    def as_dict(self) -> dict:
        return {"distance_step": self.distance_step, "angle_step_deg": self.angle_step_deg,
                "phase_step": self.phase_step, "distance_max": self.distance_max,
                "max_frames": self.max_frames}


def grid_distance2(a, b, n_angle: int):
    """Squared distance in grid units between coordinates (.., 3); the two angle axes wrap."""
    diff = np.abs(np.asarray(a) - np.asarray(b))
    diff[..., 1:] = np.minimum(diff[..., 1:], n_angle - diff[..., 1:])
    return np.einsum("...k,...k->...", diff, diff)


@dataclass
class Situation:
    """A live situation, from the point of view of the boxer asking (the run-time API of docs/interaction_graph.md).

    Angles are radians (see the module docstring); phases are clip frames at 60 Hz, as
    `PlayerController.frame` reports them. Actions are names; "guard" means idle.
    """

    distance: float
    bearing_self: float
    bearing_other: float
    rel_facing: float
    own_action: str
    own_phase: float
    other_action: str
    other_phase: float

    @classmethod
    def from_roots(cls, own_root, own_action: str, own_phase: float,
                   other_root, other_action: str, other_phase: float) -> Situation:
        """Build from two `Boxer.root` tuples (x, z, yaw) and the two controllers' states."""
        sx, sz, syaw = own_root
        ox, oz, oyaw = other_root
        d, bs, bo = relative_pose((sx, sz), syaw, (ox, oz), oyaw)
        return cls(float(d), float(bs), float(bo), float(wrap_angle(oyaw - syaw)),
                   own_action, float(own_phase), other_action, float(other_phase))
