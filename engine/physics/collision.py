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


def closest_params(p1: np.ndarray, q1: np.ndarray, p2: np.ndarray, q2: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Parameters (s, t) in [0, 1] of the closest points p1 + s (q1 - p1) and p2 + t (q2 - p2)
    of K segment pairs (all inputs (K, 3)). Degenerate segments (points) are handled.
    Ericson, Real-Time Collision Detection 5.1.9, with the branches turned into np.where."""
    d1 = q1 - p1
    d2 = q2 - p2
    r = p1 - p2
    a = np.einsum("ij,ij->i", d1, d1)
    e = np.einsum("ij,ij->i", d2, d2)
    f = np.einsum("ij,ij->i", d2, r)
    c = np.einsum("ij,ij->i", d1, r)
    b = np.einsum("ij,ij->i", d1, d2)
    a_safe = np.maximum(a, _EPS)
    e_safe = np.maximum(e, _EPS)
    denom = a * e - b * b
    # s on the infinite lines; (near-)parallel segments have no single closest pair: take the
    # middle of the part of segment 1 that segment 2 overlaps, so a contact between two
    # side-by-side capsules is pushed apart at its middle rather than at one end
    sp = -c / a_safe  # segment 2's ends projected on segment 1
    sq = (b - c) / a_safe
    s_par = 0.5 * (np.maximum(np.minimum(sp, sq), 0.0) + np.minimum(np.maximum(sp, sq), 1.0))
    parallel = denom <= 1e-6 * a_safe * e_safe
    s = np.where(parallel, s_par, (b * f - c * e) / np.where(parallel, 1.0, denom))
    np.clip(s, 0.0, 1.0, out=s)
    t = (b * s + f) / e_safe
    below = t < 0.0
    above = t > 1.0
    s = np.where(below, -c / a_safe, np.where(above, (b - c) / a_safe, s))
    # segment 2 a point: t = 0, s from projecting it on segment 1
    s = np.where(e <= _EPS, -c / a_safe, s)
    np.clip(s, 0.0, 1.0, out=s)
    np.clip(t, 0.0, 1.0, out=t)
    t[e <= _EPS] = 0.0
    return s, t


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
        self.rsum = radii[cap_a] + radii[cap_b]
        self.inv_mass = inv_mass
        self.n = n_particles
        # capsule midpoints and half axes of all capsules in one matmul each
        c = np.arange(len(caps))
        self.mid = np.zeros((len(caps), n_particles))
        np.add.at(self.mid, (c, caps[:, 0]), 0.5)
        np.add.at(self.mid, (c, caps[:, 1]), 0.5)
        self.half = np.zeros((len(caps), n_particles))
        np.add.at(self.half, (c, caps[:, 1]), 0.5)
        np.add.at(self.half, (c, caps[:, 0]), -0.5)

    def __len__(self) -> int:
        return len(self.cap_a)

    def candidates(self, x: np.ndarray, margin: float) -> np.ndarray:
        """Indices of pairs whose bounding spheres (capsule midpoint, half length + radius)
        come within `margin`: a cheap broad phase before the exact segment test."""
        mid = self.mid @ x
        h = self.half @ x
        half = np.sqrt(np.einsum("ij,ij->i", h, h))
        d = mid[self.cap_b] - mid[self.cap_a]
        reach = half[self.cap_a] + half[self.cap_b] + (self.rsum + margin)
        return np.flatnonzero(np.einsum("ij,ij->i", d, d) < reach * reach)

    def narrow(self, x: np.ndarray, idx: np.ndarray):
        """For the pairs `idx`: (s, t, closest point on a, unit normal a->b, depth); depth > 0
        means the capsules overlap."""
        ia, ja, ib, jb = self.ia[idx], self.ja[idx], self.ib[idx], self.jb[idx]
        p1, q1, p2, q2 = x[ia], x[ja], x[ib], x[jb]
        s, t = closest_params(p1, q1, p2, q2)
        ca = p1 + s[:, None] * (q1 - p1)
        cb = p2 + t[:, None] * (q2 - p2)
        d = cb - ca
        dist = np.sqrt(np.einsum("ij,ij->i", d, d))
        # coincident axes: no direction from the closest points; fall back to the line between
        # the segment midpoints, then to +x, so the push is still well defined
        bad = dist < 1e-9
        if bad.any():
            alt = 0.5 * (p2 + q2 - p1 - q1)[bad]
            alen = np.linalg.norm(alt, axis=1)
            alt[alen < 1e-9] = (1.0, 0.0, 0.0)
            alen[alen < 1e-9] = 1.0
            d[bad] = alt / alen[:, None]
            dist = np.where(bad, 1.0, dist)
            depth = self.rsum[idx] - np.where(bad, 0.0, dist)
        else:
            depth = self.rsum[idx] - dist
        return s, t, ca, d / dist[:, None], depth

    def contact_set(self, idx: np.ndarray, s: np.ndarray, t: np.ndarray, n: np.ndarray) -> ContactSet:
        """Contact constraints for pairs `idx`, linearized at this step's closest points."""
        k = np.arange(len(idx))
        g = np.zeros((len(idx), self.n))
        # G @ x = (closest point on b) - (closest point on a); a sphere's two ends are one
        # particle and its weights add up to 1
        np.add.at(g, (np.concatenate([k, k, k, k]),
                      np.concatenate([self.ib[idx], self.jb[idx], self.ia[idx], self.ja[idx]])),
                  np.concatenate([1.0 - t, t, s - 1.0, -s]))
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
