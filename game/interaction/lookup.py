"""Nearest sampled state of a live situation.

The situation is first quantized to its grid cell (state.StateGrid); the cell maps to the
sampled state whose cell centre is nearest (grid units, both angle axes wrapping; ties to the
smaller state id) among states whose other boxer is in the same action and frame (the
bucket); when the bucket has no state, among the same action; failing that, among all.

The other's frame first snaps to the nearest frame its action was sampled at, so the bucket
always exists (when the action was never sampled at all, the other counts as READY).

Fast path: the build stores the answer for cells near sampled cells, the "fill" (sorted keys
+ state ids; see `neighbour_fill`), exact by construction. Cells outside the fill fall back
to a numpy scan of the bucket. A sampled cell is in the fill too (at distance 0, its own
state), so no separate dict of the 60,000 state keys is kept (it held 6 MB for ~0.7 us on
the lookups that land on a sampled cell, ~15 % of a match's).
"""

from __future__ import annotations

import math

import numpy as np

from .state import StateGrid, grid_distance2

FILL_RADIUS = 2


def neighbour_fill(grid: StateGrid, keys: np.ndarray,
                   radius: int = FILL_RADIUS) -> tuple[np.ndarray, np.ndarray]:
    """(fill_keys ascending, fill_state): the nearest state of every cell within `radius`
    cells (Chebyshev) of a sampled cell, in the same bucket, kept where that is provably
    the nearest: a state farther than `radius` cells along some axis is at least radius + 1
    units away, so only answers nearer than that are kept (vectorized)."""
    r = np.arange(-radius, radius + 1)
    RING = np.stack(np.meshgrid(r, r, r, indexing="ij"), axis=-1).reshape(-1, 3)
    keys = np.asarray(keys, dtype=np.int64)
    bucket, db, sb, ob = grid.split_key(keys)
    na, nd = grid.n_angle, grid.n_distance
    n = len(keys)
    cd = db[:, None] + RING[None, :, 0]
    cs = (sb[:, None] + RING[None, :, 1]) % na
    co = (ob[:, None] + RING[None, :, 2]) % na
    d2 = np.broadcast_to((RING ** 2).sum(axis=1)[None, :], (n, len(RING)))
    ok = (cd >= 0) & (cd < nd) & (d2 < (radius + 1) ** 2)
    ck = ((bucket[:, None] * nd + cd) * na + cs) * na + co
    sid = np.broadcast_to(np.arange(n)[:, None], (n, len(RING)))
    ck, d2, sid = ck[ok], d2[ok], sid[ok]
    order = np.lexsort((sid, d2, ck))
    ck, sid = ck[order], sid[order]
    first = np.ones(len(ck), dtype=bool)
    first[1:] = ck[1:] != ck[:-1]
    return ck[first], sid[first].astype(np.int32)


class StateIndex:
    def __init__(self, grid: StateGrid, keys: np.ndarray,
                 fill: tuple[np.ndarray, np.ndarray] | None = None, ready_action: int = 0):
        self.grid = grid
        self.keys = np.asarray(keys, dtype=np.int64)
        self.n = len(self.keys)
        if fill is None:
            fill = neighbour_fill(grid, self.keys)
        self.fill_keys = np.asarray(fill[0], dtype=np.int64)
        # int32 as stored (a state id fits): the fill has ~900,000 cells, 3.5 MB less than int64
        self.fill_state = np.asarray(fill[1], dtype=np.int32)
        self._nfill = len(self.fill_keys)
        bucket, _, _, _ = grid.split_key(self.keys)
        self._bucket = bucket
        self._action = bucket // grid.n_phase
        self.centres = grid.cell_centres(self.keys)
        # per bucket and per action: the state ids, for the fallback scan
        self._bucket_ids: dict[int, np.ndarray] = {}
        self._action_ids: dict[int, np.ndarray] = {}
        for table, labels in ((self._bucket_ids, bucket), (self._action_ids, self._action)):
            order = np.argsort(labels, kind="stable")
            uniq, first = np.unique(labels[order], return_index=True)
            for u, ids in zip(uniq.tolist(), np.split(order, first[1:]), strict=True):
                table[u] = ids
        # per action: the nearest sampled phase bin of every phase bin
        self._snap: dict[int, list[int]] = {}
        all_bins = np.arange(grid.n_phase)
        for act, ids in self._action_ids.items():
            # the sampled phase bins, sorted (bincount, not np.unique: that imports numpy.ma, 7 ms
            # and 1 MB at start-up for nothing)
            have = np.flatnonzero(np.bincount(bucket[ids] % grid.n_phase, minlength=grid.n_phase))
            pos = np.clip(np.searchsorted(have, all_bins), 1, max(len(have) - 1, 1))
            lo, hi = have[pos - 1], have[np.minimum(pos, len(have) - 1)]
            snap = np.where(np.abs(all_bins - lo) <= np.abs(hi - all_bins), lo, hi)
            self._snap[act] = snap.tolist()
        self.ready_action = ready_action
        # scalar-path constants
        self._ds = 1.0 / grid.distance_step
        self._as = 1.0 / grid.angle_step
        self._nd, self._na, self._np = grid.n_distance, grid.n_angle, grid.n_phase
        self._ps = grid.phase_step
        self._search = self.fill_keys.searchsorted

    def _candidates(self, bucket: int) -> np.ndarray:
        ids = self._bucket_ids.get(bucket)
        if ids is None:
            ids = self._action_ids.get(bucket // self._np)
        if ids is None:
            ids = np.arange(self.n)
        return ids

    def nearest(self, distance: float, bearing_self: float, bearing_other: float,
                other_action: int, other_frame: float) -> int:
        """State id of one situation (the 60 Hz path: Python arithmetic, at most one binary
        search; a numpy scan only outside the fill)."""
        pi = math.pi
        two_pi = 2.0 * pi
        nd, na, npb = self._nd, self._na, self._np
        db = int(distance * self._ds)
        if db >= nd:
            db = nd - 1
        elif db < 0:
            db = 0
        sb = int(((bearing_self + pi) % two_pi) * self._as) % na
        ob = int(((bearing_other + pi) % two_pi) * self._as) % na
        pb = int(other_frame) // self._ps
        if pb >= npb:
            pb = npb - 1
        elif pb < 0:
            pb = 0
        snap = self._snap.get(other_action)
        if snap is None:
            other_action, snap = self._no_action(other_action)
        bucket = other_action * npb + snap[pb]
        key = ((bucket * nd + db) * na + sb) * na + ob
        i = int(self._search(key))
        if i < self._nfill and self.fill_keys[i] == key:
            return int(self.fill_state[i])
        return self._scan(bucket, db, sb, ob)

    def _no_action(self, other_action: int) -> tuple[int, list[int]]:
        """An action no state was sampled with: take the READY code's states (the other
        treated as about to choose), else the first sampled action."""
        act = self.ready_action if self.ready_action in self._snap else min(self._snap)
        return act, self._snap[act]

    def snap(self, other_action, other_frame) -> tuple[np.ndarray, np.ndarray]:
        """Vectorized: (action, frame) moved to the nearest sampled bucket."""
        a = np.atleast_1d(np.asarray(other_action, dtype=np.int64)).copy()
        pb = np.clip(np.atleast_1d(np.asarray(other_frame)).astype(np.int64) // self.grid.phase_step,
                     0, self.grid.n_phase - 1)
        out = np.empty_like(pb)
        for act in np.unique(a).tolist():
            m = a == act
            if act not in self._snap:
                a[m], table = self._no_action(act)
            else:
                table = self._snap[act]
            out[m] = np.asarray(table)[pb[m]]
        return a, out * self.grid.phase_step

    def _scan(self, bucket: int, db: int, sb: int, ob: int) -> int:
        ids = self._candidates(bucket)
        q = np.array([db + 0.5, sb + 0.5, ob + 0.5])
        return int(ids[np.argmin(grid_distance2(self.centres[ids], q, self._na))])

    def nearest_many(self, distance, bearing_self, bearing_other, other_action, other_frame) -> np.ndarray:
        """State ids of many situations (vectorized; used by the build and the duel)."""
        g = self.grid
        other_action, other_frame = self.snap(other_action, other_frame)
        keys = np.atleast_1d(g.key(distance, bearing_self, bearing_other, other_action, other_frame))
        pos = np.minimum(np.searchsorted(self.fill_keys, keys), self._nfill - 1)
        found = self.fill_keys[pos] == keys
        out = np.where(found, self.fill_state[pos].astype(np.int64), -1)
        miss = np.flatnonzero(~found)
        if len(miss):
            q = g.cell_centres(keys[miss])
            buckets = g.split_key(keys[miss])[0]
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
        """The peer of `nearest`: the same rule by scanning every state with numpy (no fill,
        no dict), for the benchmark and the tests."""
        g = self.grid
        a, f = self.snap(other_action, other_frame)
        key = int(g.key(distance, bearing_self, bearing_other, a[0], f[0]))
        bucket = int(g.split_key(key)[0])
        d2 = grid_distance2(self.centres, g.cell_centres(np.array([key]))[0], g.n_angle)
        ok = self._bucket == bucket
        if not ok.any():
            ok = self._action == other_action
        if not ok.any():
            ok = np.ones(self.n, dtype=bool)
        return int(np.argmin(np.where(ok, d2, np.inf)))
