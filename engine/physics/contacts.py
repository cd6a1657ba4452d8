"""Contacts between bodies: the world's capsule table, which capsule pairs touch this step,
and which touched last step (so a Contact says whether it is new)."""

from __future__ import annotations

import numpy as np

from engine.physics.collision import CapsulePairs, Contact, ContactSet


class ContactDetector:
    """Capsules of every body (global particle pairs, radii, owner body, index within the
    body, tag) and the capsule pairs between different bodies; finds the contacts of a step
    and the contact constraints that keep those pairs apart while the sticks relax."""

    def __init__(self) -> None:
        self._caps = np.zeros((0, 2), dtype=np.int64)
        self._radii = np.zeros(0)
        self._cap_body = np.zeros(0, dtype=np.int64)
        self._cap_local = np.zeros(0, dtype=np.int64)
        self._cap_tags: list[str] = []

    def add_capsules(self, caps: np.ndarray, radii: np.ndarray, tags: list[str], bid: int) -> None:
        """Body `bid`'s capsules, `caps` already as indices into the world's particles."""
        self._caps = np.concatenate([self._caps, caps])
        self._radii = np.concatenate([self._radii, radii])
        self._cap_body = np.concatenate([self._cap_body, np.full(len(caps), bid)])
        self._cap_local = np.concatenate([self._cap_local, np.arange(len(caps))])
        self._cap_tags += tags

    @property
    def n_capsules(self) -> int:
        return len(self._caps)

    def rebuild(self, inv_mass: np.ndarray, n_particles: int) -> None:
        """Every pair of capsules on different bodies (after a body was added)."""
        ca, cb = np.meshgrid(np.arange(len(self._caps)), np.arange(len(self._caps)), indexing="ij")
        ca, cb = ca.ravel(), cb.ravel()
        keep = self._cap_body[ca] < self._cap_body[cb] if len(ca) else np.zeros(0, dtype=bool)
        self.pairs = CapsulePairs(ca[keep], cb[keep], self._caps, self._radii, inv_mass, n_particles)
        self.forget()

    def forget(self) -> None:
        """Forget which pairs touched last step (new body, teleport): Contact.new starts over."""
        self._touching = np.zeros(len(self.pairs), dtype=bool)  # pairs overlapping last step
        self._hit_idx = np.zeros(0, dtype=np.int64)

    def detect(self, x: np.ndarray, x_prev: np.ndarray, v: np.ndarray,
               margin: float) -> tuple[list[Contact], ContactSet | None, np.ndarray]:
        """Contacts at the integrated positions `x`, and this step's contact constraints: the
        pairs touching or within `margin` (so relaxing the sticks cannot push them into each
        other). Returns (contacts, ContactSet or None, their pair indices)."""
        contacts: list[Contact] = []
        cset = None
        near_idx = np.zeros(0, dtype=np.int64)
        cand = self.pairs.candidates(x, margin) if len(self.pairs) else near_idx
        if len(cand):
            s, t, n, depth = self.pairs.narrow(x, cand)
            near = np.flatnonzero(depth > -margin)
            if len(near):
                near_idx = cand[near]
                s, t, n, depth = s[near], t[near], n[near], depth[near]
                cset = self.pairs.contact_set(near_idx, s, t, n)
                closing = cset.closing_speeds(v)
                # a pair whose closest points were on the other side of each other at the start
                # of the step went past the middle within it (a fast fist): turn it back the
                # way it came. (The last step ended without overlap, so before this step's
                # motion the separation along n was positive unless they crossed.)
                flip = (depth > 0.0) & (cset.separations(x_prev) < 0.0)
                if flip.any():
                    n = np.where(flip[:, None], -n, n)
                    depth = np.where(flip, 2.0 * self.pairs.rsum[near_idx] - depth, depth)
                    closing = np.where(flip, -closing, closing)
                    cset = self.pairs.contact_set(near_idx, s, t, n)
                contacts = self._contacts(x, near_idx, s, n, depth, closing)
        # remember which pairs touch, for Contact.new
        self._touching[self._hit_idx] = False
        self._hit_idx = np.array([c.pair for c in contacts], dtype=np.int64) if contacts else near_idx[:0]
        self._touching[self._hit_idx] = True
        return contacts, cset, near_idx

    def separate(self, x: np.ndarray, near_idx: np.ndarray, passes: int, tolerance: float) -> None:
        """Up to `passes` contact passes linearized at the relaxed positions: the closest
        points moved during the iterations, and what the user sees must not interpenetrate
        by more than `tolerance`."""
        for _ in range(passes):
            s, t, n, depth = self.pairs.narrow(x, near_idx)
            pen = depth > tolerance
            if not pen.any():
                break
            self.pairs.contact_set(near_idx[pen], s[pen], t[pen], n[pen]).project(x)

    def _contacts(self, x, idx, s, n, depth, closing) -> list[Contact]:
        """Contacts among pairs `idx` that overlap at the integrated positions (before any
        resolution), with the closing speed of their closest points along the normal."""
        hit = np.flatnonzero(depth > 0.0)
        if len(hit) == 0:
            return []
        p = self.pairs
        k = idx[hit]
        n, depth = n[hit], depth[hit]
        ca = p.closest_on_a(x, k, s[hit])
        # midway between the two surfaces along the normal
        point = ca + n * (self._radii[p.cap_a[k]] - 0.5 * depth)[:, None]
        ga, gb = p.cap_a[k], p.cap_b[k]
        rows = zip(self._cap_body[ga].tolist(), self._cap_local[ga].tolist(), ga.tolist(),
                   self._cap_body[gb].tolist(), self._cap_local[gb].tolist(), gb.tolist(),
                   point, n, closing[hit].tolist(), depth.tolist(), strict=True)
        tags = self._cap_tags
        fresh = (~self._touching[k]).tolist()
        return [Contact(ba, la, tags[a], bb, lb, tags[b], pt, nn, sp, de, nw, pr)
                for (ba, la, a, bb, lb, b, pt, nn, sp, de), nw, pr in zip(rows, fresh, k.tolist(), strict=True)]
