"""Capsule-capsule contact between bodies: closest points between segments, vectorized over
all candidate capsule pairs, resolved by moving particles weighted by inverse mass."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

_EPS = 1e-12


@dataclass(frozen=True)
class Contact:
    """Two capsules of different bodies touching in one step.

    `normal` points from capsule a towards capsule b; `rel_speed` is the closing speed along
    that normal before resolution (m/s, > 0 when the capsules move towards each other);
    `point` lies midway between the two surfaces; `depth` is the penetration in metres."""

    body_a: int
    capsule_a: int
    tag_a: str
    body_b: int
    capsule_b: int
    tag_b: str
    point: np.ndarray
    normal: np.ndarray
    rel_speed: float
    depth: float = 0.0


def _params(a, b, c, e, f) -> tuple[np.ndarray, np.ndarray]:
    """(s, t) from the segments' Gram entries a = d1.d1, b = d1.d2, c = d1.r, e = d2.d2,
    f = d2.r (d1 = q1 - p1, d2 = q2 - p2, r = p1 - p2). Ericson, Real-Time Collision
    Detection 5.1.9, with its branches turned into np.where over all pairs at once."""
    inv_a = 1.0 / np.maximum(a, _EPS)
    inv_e = 1.0 / np.maximum(e, _EPS)
    denom = a * e - b * b
    sp = -c * inv_a  # segment 2's ends projected on segment 1's line
    sq = (b - c) * inv_a
    # (near-)parallel segments have no single closest pair: take the middle of the part of
    # segment 1 that segment 2 overlaps, so side-by-side capsules are pushed apart at their
    # middle rather than at one end. This also covers either segment being a point.
    parallel = denom <= 1e-6 * np.maximum(a, _EPS) * np.maximum(e, _EPS)
    s_par = 0.5 * (np.maximum(np.minimum(sp, sq), 0.0) + np.minimum(np.maximum(sp, sq), 1.0))
    s = np.where(parallel, s_par, (b * f - c * e) / np.where(parallel, 1.0, denom))
    s = np.minimum(np.maximum(s, 0.0), 1.0)
    t = (b * s + f) * inv_e
    # t outside the segment: clamp it, and s becomes the projection of that end of segment 2
    s = np.where(t < 0.0, sp, np.where(t > 1.0, sq, s))
    s = np.minimum(np.maximum(s, 0.0), 1.0)
    t = np.minimum(np.maximum(t, 0.0), 1.0)
    return s, t


# rows: d1 = q1 - p1, d2 = q2 - p2, r = p1 - p2, from the four ends stacked (p1, q1, p2, q2)
_EDGES = np.array([[-1.0, 1.0, 0.0, 0.0], [0.0, 0.0, -1.0, 1.0], [1.0, 0.0, -1.0, 0.0]])


def _gram(ends: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """ends (4, K, 3) -> the three edge vectors V (3, K, 3) and their Gram matrices (3, 3, K)."""
    k = ends.shape[1]
    v = (_EDGES @ ends.reshape(4, -1)).reshape(3, k, 3)
    return v, np.einsum("aki,bki->abk", v, v)


def closest_params(p1: np.ndarray, q1: np.ndarray, p2: np.ndarray, q2: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Parameters (s, t) in [0, 1] of the closest points p1 + s (q1 - p1) and p2 + t (q2 - p2)
    of K segment pairs (all inputs (K, 3)). Degenerate segments (points) are handled."""
    _, g = _gram(np.stack([p1, q1, p2, q2]))
    return _params(g[0, 0], g[0, 1], g[0, 2], g[1, 1], g[1, 2])


def segment_distance(p1: np.ndarray, q1: np.ndarray, p2: np.ndarray, q2: np.ndarray) -> np.ndarray:
    """Distance between K segment pairs (inputs (K, 3)) -> (K,)."""
    s, t = closest_params(p1, q1, p2, q2)
    ca = p1 + s[:, None] * (q1 - p1)
    cb = p2 + t[:, None] * (q2 - p2)
    return np.sqrt(np.einsum("ij,ij->i", cb - ca, cb - ca))


class CapsulePairs:
    """All capsule pairs of different bodies, as flat index arrays; rebuilt when a body is
    added (rare), read every step (cheap)."""

    def __init__(self, cap_a: np.ndarray, cap_b: np.ndarray, caps: np.ndarray, radii: np.ndarray,
                 inv_mass: np.ndarray, n_particles: int) -> None:
        self.cap_a = cap_a  # (K,) global capsule index of side a
        self.cap_b = cap_b
        self.ia = caps[cap_a, 0]  # particle indices of the four segment ends
        self.ja = caps[cap_a, 1]
        self.ib = caps[cap_b, 0]
        self.jb = caps[cap_b, 1]
        self.quad = np.stack([self.ia, self.ja, self.ib, self.jb])  # (4, K) for one gather
        self.rsum = radii[cap_a] + radii[cap_b]
        self.inv_mass = inv_mass
        self.n = n_particles
        # broad-phase matrices: pair_mid @ x = midpoint(b) - midpoint(a) for every pair,
        # half @ x = half axis of every capsule, pair_caps @ |half| = sum of the two half lengths
        c = np.arange(len(caps))
        mid = np.zeros((len(caps), n_particles))
        np.add.at(mid, (c, caps[:, 0]), 0.5)
        np.add.at(mid, (c, caps[:, 1]), 0.5)
        self.pair_mid = mid[cap_b] - mid[cap_a]
        self.half = np.zeros((len(caps), n_particles))
        np.add.at(self.half, (c, caps[:, 1]), 0.5)
        np.add.at(self.half, (c, caps[:, 0]), -0.5)
        k = np.arange(len(cap_a))
        self.pair_caps = np.zeros((len(cap_a), len(caps)))
        self.pair_caps[k, cap_a] += 1.0
        self.pair_caps[k, cap_b] += 1.0

    def __len__(self) -> int:
        return len(self.cap_a)

    def candidates(self, x: np.ndarray, margin: float) -> np.ndarray:
        """Indices of pairs whose bounding spheres (capsule midpoint, half length + radius)
        come within `margin`: a cheap broad phase before the exact segment test."""
        d = self.pair_mid @ x
        h = self.half @ x
        reach = self.pair_caps @ np.sqrt(np.einsum("ij,ij->i", h, h)) + (self.rsum + margin)
        return np.flatnonzero(np.einsum("ij,ij->i", d, d) < reach * reach)

    def narrow(self, x: np.ndarray, idx: np.ndarray):
        """For the pairs `idx`: (s, t, unit normal a->b, depth); depth > 0 means the capsules
        overlap. Written for few numpy calls: at this size their overhead is the cost."""
        v, g = _gram(x[self.quad[:, idx]])
        s, t = _params(g[0, 0], g[0, 1], g[0, 2], g[1, 1], g[1, 2])
        d = t[:, None] * v[1] - s[:, None] * v[0] - v[2]  # closest point on b - on a
        dist = np.sqrt(np.einsum("ij,ij->i", d, d))
        depth = self.rsum[idx] - dist
        bad = dist < 1e-9
        if bad.any():
            # coincident axes: no direction from the closest points; fall back to the line
            # between the segment midpoints, then to +x, so the push is still well defined
            alt = 0.5 * (v[1] - v[0] - 2.0 * v[2])[bad]
            alen = np.linalg.norm(alt, axis=1)
            alt[alen < 1e-9] = (1.0, 0.0, 0.0)
            alen[alen < 1e-9] = 1.0
            d[bad] = alt / alen[:, None]
            dist = np.where(bad, 1.0, dist)
        return s, t, d / dist[:, None], depth

    def closest_on_a(self, x: np.ndarray, idx: np.ndarray, s: np.ndarray) -> np.ndarray:
        """The closest points on side a's segments for pairs idx at parameters s -> (K, 3)."""
        p = x[self.ia[idx]]
        return p + s[:, None] * (x[self.ja[idx]] - p)

    def relative(self, v: np.ndarray, idx: np.ndarray, s: np.ndarray, t: np.ndarray) -> np.ndarray:
        """v at the closest point on a minus v at the closest point on b -> (K, 3)."""
        w = np.stack([1.0 - s, s, t - 1.0, -t])  # (4, K) barycentric weights, b negated
        return np.einsum("qk,qki->ki", w, v[self.quad[:, idx]])

    def contact_set(self, idx: np.ndarray, s: np.ndarray, t: np.ndarray, n: np.ndarray) -> ContactSet:
        """Contact constraints for pairs `idx`, linearized at this step's closest points."""
        k = np.arange(len(idx))
        g = np.zeros((len(idx), self.n))
        # G @ x = (closest point on b) - (closest point on a); the two bodies share no particle,
        # and a sphere's two ends are one particle whose weights add up to 1
        g[k, self.ib[idx]] = 1.0 - t
        g[k, self.jb[idx]] += t
        g[k, self.ia[idx]] = s - 1.0
        g[k, self.ja[idx]] -= s
        return ContactSet(g, n, self.rsum[idx], self.inv_mass)


class ContactSet:
    """Non-penetration constraints C_k = (G_k @ x) . n_k - rsum_k >= 0 for one step: the
    barycentric weights (s, t) and the normal n come from the closest points at detection and
    stay fixed for the step's iterations (standard PBD practice), so each iteration is a few
    matmuls. Projection (Jacobi over the contacts): lambda_k = max(-C_k, 0) / sum_p w_p G_kp^2,
    dx_p = w_p sum_k G_kp n_k lambda_k: the separation grows by exactly the depth, heavier
    particles moving less, and momentum is conserved."""

    def __init__(self, g: np.ndarray, n: np.ndarray, rsum: np.ndarray, inv_mass: np.ndarray) -> None:
        self.g = g
        self.n = n
        self.rsum = rsum
        self.w = inv_mass[:, None]
        self.inv_wsum = 1.0 / np.maximum((g * g) @ inv_mass, _EPS)

    def project(self, x: np.ndarray) -> None:
        depth = self.rsum - np.einsum("ij,ij->i", self.g @ x, self.n)
        lam = np.maximum(depth, 0.0) * self.inv_wsum
        x += self.w * (self.g.T @ (lam[:, None] * self.n))
