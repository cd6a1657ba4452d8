"""Nearest sampled state of a situation: the state of its grid cell when that cell was sampled,
otherwise the nearest state (grid-normalized metric, angles wrapping) among those whose other
boxer is in the same action and phase bin; failing that, the same action; failing that, any.

`StateIndex.nearest` is the scalar run-time path (a dict probe: a few µs); `nearest_many` maps
arrays of situations at once (sorted keys + searchsorted) for the build and the duel.
"""

from __future__ import annotations

import math

import numpy as np

from .state import StateGrid, grid_distance2


class StateIndex:
    def __init__(self, grid: StateGrid, keys: np.ndarray):
        self.grid = grid
        self.keys = np.asarray(keys, dtype=np.int64)
        self.n = len(self.keys)
        self._order = np.argsort(self.keys, kind="stable")
        self._sorted = self.keys[self._order]
        self._by_key = dict(zip(self.keys.tolist(), range(self.n), strict=True))
        bucket, _, _, _ = grid.split_key(self.keys)
        self._bucket = bucket
        self._action = bucket // grid.n_phase
        self.centres = grid.cell_centres(self.keys)
        # per bucket and per action: the state ids, for the nearest-state fallback
        self._bucket_ids: dict[int, np.ndarray] = {}
        self._action_ids: dict[int, np.ndarray] = {}
        for table, labels in ((self._bucket_ids, bucket), (self._action_ids, self._action)):
            order = np.argsort(labels, kind="stable")
            uniq, first = np.unique(labels[order], return_index=True)
            for u, ids in zip(uniq.tolist(), np.split(order, first[1:]), strict=True):
                table[u] = ids
        # scalar-path constants
        self._ds = 1.0 / grid.distance_step
        self._as = 1.0 / grid.angle_step
        self._nd, self._na, self._np = grid.n_distance, grid.n_angle, grid.n_phase

    def _candidates(self, bucket: int) -> np.ndarray:
        ids = self._bucket_ids.get(bucket)
        if ids is None:
            ids = self._action_ids.get(bucket // self._np)
        if ids is None:
            ids = np.arange(self.n)
        return ids

    def nearest(self, distance: float, bearing_self: float, bearing_other: float,
                other_action: int, other_frame: float) -> int:
        """State id of one situation (the 60 Hz path: plain Python arithmetic + a dict probe)."""
        pi = math.pi
        two_pi = 2.0 * pi
        db = int(distance * self._ds)
        if db >= self._nd:
            db = self._nd - 1
        elif db < 0:
            db = 0
        s = ((bearing_self + pi) % two_pi) * self._as
        o = ((bearing_other + pi) % two_pi) * self._as
        sb = int(s) % self._na
        ob = int(o) % self._na
        pb = int(other_frame) // self.grid.phase_step
        if pb >= self._np:
            pb = self._np - 1
        elif pb < 0:
            pb = 0
        bucket = other_action * self._np + pb
        key = ((bucket * self._nd + db) * self._na + sb) * self._na + ob
        sid = self._by_key.get(key)
        if sid is not None:
            return sid
        ids = self._candidates(bucket)
        q = np.array([distance * self._ds, s, o])
        return int(ids[np.argmin(grid_distance2(self.centres[ids], q, self._na))])

    def nearest_many(self, distance, bearing_self, bearing_other, other_action, other_frame) -> np.ndarray:
        """State ids of many situations (vectorized; used by the build and the duel)."""
        g = self.grid
        keys = g.key(distance, bearing_self, bearing_other, other_action, other_frame)
        pos = np.searchsorted(self._sorted, keys)
        pos = np.minimum(pos, self.n - 1)
        found = self._sorted[pos] == keys
        out = np.where(found, self._order[pos], -1)
        miss = np.flatnonzero(~found)
        if len(miss):
            q = g.normalized(np.asarray(distance)[miss] if np.ndim(distance) else np.full(len(miss), distance),
                             np.broadcast_to(bearing_self, keys.shape)[miss],
                             np.broadcast_to(bearing_other, keys.shape)[miss])
            buckets = (keys[miss] // (g.n_angle * g.n_angle * g.n_distance))
            for bkt in np.unique(buckets).tolist():
                sel = np.flatnonzero(buckets == bkt)
                ids = self._candidates(bkt)
                cen = self.centres[ids]
                for c0 in range(0, len(sel), 2048):       # chunks keep the distance matrix small
                    part = sel[c0:c0 + 2048]
                    d2 = grid_distance2(cen[None, :, :], q[part][:, None, :], g.n_angle)
                    out[miss[part]] = ids[np.argmin(d2, axis=1)]
        return out

    def brute_force(self, distance: float, bearing_self: float, bearing_other: float,
                    other_action: int, other_frame: float) -> int:
        """The peer of `nearest`: scan every state with numpy (no index), same metric and
        bucket rule, for the benchmark and the tests."""
        g = self.grid
        pb = min(max(int(other_frame) // g.phase_step, 0), g.n_phase - 1)
        bucket = other_action * g.n_phase + pb
        q = g.normalized(distance, bearing_self, bearing_other)
        d2 = grid_distance2(self.centres, q, g.n_angle)
        ok = self._bucket == bucket
        if not ok.any():
            ok = self._action == other_action
        if not ok.any():
            ok = np.ones(self.n, dtype=bool)
        d2 = np.where(ok, d2, np.inf)
        return int(np.argmin(d2))
