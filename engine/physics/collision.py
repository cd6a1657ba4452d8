"""Capsule-capsule contact between bodies: closest points between segments, vectorized over
all candidate capsule pairs, resolved by moving particles weighted by inverse mass."""

from __future__ import annotations

import ctypes
from dataclasses import dataclass

import numpy as np

from engine import native

_EPS = 1e-12

# The narrow phase and the contact projection in C (engine/native.py): the numpy code below
# operation for operation, in its order (dot products (x + y) + z, the contact sums end by end,
# the scatter in bincount's order), so a world steps to the same bits with or without a C
# compiler. A contact step runs them up to 8 times; each is one call instead of 6-35 numpy
# calls on arrays of a few pairs.
KERNEL_SOURCE = r"""
#include <math.h>
static double maxnan(double a, double b) { return (a >= b || a != a) ? a : b; }  /* np.maximum */
static double minnan(double a, double b) { return (a <= b || a != a) ? a : b; }  /* np.minimum */
static double dot3(const double *u, const double *w) { return (u[0] * w[0] + u[1] * w[1]) + u[2] * w[2]; }

/* CapsulePairs.narrow for the pairs idx: s, t, unit normal a->b (K, 3), depth. Returns how
   many pairs have (nearly) coincident closest points: the caller then redoes the call in numpy,
   whose fallback direction this does not implement. */
long long narrow(const double *restrict x, const long long *restrict quad, long long P,
                 const long long *restrict idx, long long K, const double *restrict rsum, double eps,
                 double *restrict s_out, double *restrict t_out, double *restrict n_out,
                 double *restrict depth_out)
{
    long long bad = 0;
    for (long long k = 0; k < K; k++) {
        long long p = idx[k];
        const double *e0 = x + 3 * quad[p], *e1 = x + 3 * quad[P + p];
        const double *e2 = x + 3 * quad[2 * P + p], *e3 = x + 3 * quad[3 * P + p];
        double v0[3], v1[3], v2[3];
        for (int i = 0; i < 3; i++) { v0[i] = e1[i] - e0[i]; v1[i] = e3[i] - e2[i]; v2[i] = e0[i] - e2[i]; }
        double a = dot3(v0, v0), b = dot3(v0, v1), c = dot3(v0, v2), e = dot3(v1, v1), f = dot3(v1, v2);
        double a_safe = maxnan(a, eps);
        double ae = a_safe * maxnan(e, eps);
        double sp = -c / a_safe, sq = (b - c) / a_safe;
        double denom = a * e - b * b;
        double lo = minnan(sp, sq), hi = maxnan(sp, sq);
        double s_par = 0.5 * (maxnan(lo, 0.0) + minnan(hi, 1.0));
        double s_gen = (b * f - c * e) / maxnan(denom, eps);
        double s = denom <= 1e-6 * ae ? s_par : s_gen;
        s = minnan(maxnan(s, 0.0), 1.0);
        double t = (b * s + f) / maxnan(e, eps);
        s = t < 0.0 ? sp : (t > 1.0 ? sq : s);
        s = minnan(maxnan(s, 0.0), 1.0);
        t = minnan(maxnan(t, 0.0), 1.0);
        double d[3];
        for (int i = 0; i < 3; i++) d[i] = (t * v1[i] - s * v0[i]) - v2[i];
        double dist = sqrt(dot3(d, d));
        depth_out[k] = rsum[p] - dist;
        s_out[k] = s;
        t_out[k] = t;
        if (dist < 1e-9) bad++;
        for (int i = 0; i < 3; i++) n_out[3 * k + i] = d[i] / dist;
    }
    return bad;
}

/* CapsulePairs.candidates: the pairs whose bounding spheres come within margin, ascending;
   returns how many were written to out. mid2 (C, 3) and extent (C,) are scratch. */
long long candidates(const double *restrict x, const long long *restrict caps, long long C,
                     const double *restrict diameters, const long long *restrict cap_a,
                     const long long *restrict cap_b, long long K, double margin,
                     double *restrict mid2, double *restrict extent, long long *restrict out)
{
    for (long long c = 0; c < C; c++) {
        const double *p = x + 3 * caps[2 * c], *q = x + 3 * caps[2 * c + 1];
        double axis[3];
        for (int i = 0; i < 3; i++) { mid2[3 * c + i] = p[i] + q[i]; axis[i] = q[i] - p[i]; }
        extent[c] = sqrt(dot3(axis, axis)) + diameters[c];
    }
    long long n = 0;
    for (long long k = 0; k < K; k++) {
        const double *ma = mid2 + 3 * cap_a[k], *mb = mid2 + 3 * cap_b[k];
        double d[3] = {mb[0] - ma[0], mb[1] - ma[1], mb[2] - ma[2]};
        double reach = (extent[cap_a[k]] + extent[cap_b[k]]) + 2.0 * margin;
        if (dot3(d, d) < reach * reach) out[n++] = k;
    }
    return n;
}

/* ContactSet.project: lambda_k = max(rsum_k - sum_q gn_qk . x_qk, 0), then the pushes scattered. */
void contact_project(double *restrict x, const long long *restrict quad, long long K,
                     const double *restrict gn, const double *restrict rsum, const double *restrict push,
                     const long long *restrict flat, double *restrict lam, double *restrict acc,
                     long long size)
{
    for (long long k = 0; k < K; k++) {
        double tot = 0.0;
        for (long long q = 0; q < 4; q++) {
            double sq = dot3(gn + 3 * (q * K + k), x + 3 * quad[q * K + k]);
            tot = q == 0 ? sq : tot + sq;
        }
        lam[k] = maxnan(rsum[k] - tot, 0.0);
    }
    for (long long q = 0; q < size; q++) acc[q] = 0.0;
    for (long long q = 0; q < 4; q++)
        for (long long k = 0; k < K; k++)
            for (long long i = 0; i < 3; i++) {
                long long m = (q * K + k) * 3 + i;
                acc[flat[m]] += push[m] * lam[k];
            }
    for (long long q = 0; q < size; q++) x[q] += acc[q];
}
"""
_kernels: list = []


def kernels():
    """(narrow, contact_project) as ctypes functions, or None without a C compiler."""
    if not _kernels:
        lib = native.load_library("contacts", KERNEL_SOURCE, ("narrow", "contact_project", "candidates"))
        if lib is None:
            _kernels.append(None)
        else:
            p, i64, f64 = ctypes.c_void_p, ctypes.c_longlong, ctypes.c_double
            lib.narrow.argtypes = [p, p, i64, p, i64, p, f64, p, p, p, p]
            lib.narrow.restype = i64
            lib.contact_project.argtypes = [p, p, i64, p, p, p, p, p, p, i64]
            lib.contact_project.restype = None
            lib.candidates.argtypes = [p, p, i64, p, p, p, i64, f64, p, p, p]
            lib.candidates.restype = i64
            _kernels.append((lib.narrow, lib.contact_project, lib.candidates))
    return _kernels[0]


@dataclass(frozen=True)
class Contact:
    """Two capsules of different bodies touching in one step.

    `normal` points from capsule a towards capsule b; `rel_speed` is the closing speed along
    that normal before resolution (m/s, > 0 when the capsules move towards each other);
    `point` lies midway between the two surfaces; `depth` is the penetration in metres.
    body_a < body_b always (pairs are ordered by body id), so a fist can be on either side;
    capsule_a/b index the body's own capsule list and tag_a/b are its tags. A touch that
    lasts is reported every step; `new` is True only on its first step (one punch, one hit)."""

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
    new: bool = True  # False when the same two capsules already touched the step before
    pair: int = -1  # index of the capsule pair in world.pairs


def _params(a, b, c, e, f) -> tuple[np.ndarray, np.ndarray]:
    """(s, t) from the segments' Gram entries a = d1.d1, b = d1.d2, c = d1.r, e = d2.d2,
    f = d2.r (d1 = q1 - p1, d2 = q2 - p2, r = p1 - p2). Ericson, Real-Time Collision
    Detection 5.1.9, with its branches turned into np.where over all pairs at once."""
    a_safe = np.maximum(a, _EPS)
    ae = a_safe * np.maximum(e, _EPS)
    sp = -c / a_safe  # segment 2's ends projected on segment 1's line
    sq = (b - c) / a_safe
    denom = a * e - b * b
    # (near-)parallel segments have no single closest pair: take the middle of the part of
    # segment 1 that segment 2 overlaps, so side-by-side capsules are pushed apart at their
    # middle rather than at one end. This also covers either segment being a point.
    lo = np.minimum(sp, sq)
    hi = np.maximum(sp, sq)
    s = np.where(denom <= 1e-6 * ae, 0.5 * (np.maximum(lo, 0.0) + np.minimum(hi, 1.0)),
                 (b * f - c * e) / np.maximum(denom, _EPS))
    s = np.minimum(np.maximum(s, 0.0), 1.0)  # (np.clip costs a Python wrapper per call)
    t = (b * s + f) / np.maximum(e, _EPS)
    # t outside the segment: clamp it, and s becomes the projection of that end of segment 2
    s = np.where(t < 0.0, sp, np.where(t > 1.0, sq, s))
    s = np.minimum(np.maximum(s, 0.0), 1.0)
    t = np.minimum(np.maximum(t, 0.0), 1.0)
    return s, t


# from the four ends stacked (p1, q1, p2, q2): d1 = q1 - p1, d2 = q2 - p2, r = p1 - p2
_PLUS = np.array([1, 3, 0])
_MINUS = np.array([0, 2, 2])


def _dot3(u: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Row dot products of (K, 3) arrays, summed (x + y) + z: the order the C kernels use
    (einsum's own order is its business and changes with its inner loops)."""
    return (u * w).sum(1)


def _dot12(gn: np.ndarray, xq: np.ndarray) -> np.ndarray:
    """sum over the four ends q and x, y, z of gn * xq (both (4, K, 3)) -> (K,), per end
    (x + y) + z, then end by end: the C kernels' order."""
    return (gn * xq).sum(2).sum(0)


def _gram(ends: np.ndarray) -> tuple[np.ndarray, tuple[np.ndarray, ...]]:
    """ends (4, K, 3) -> the three edge vectors V (3, K, 3) and the Gram entries _params takes:
    d1.d1, d1.d2, d1.r, d2.d2, d2.r."""
    v = ends[_PLUS] - ends[_MINUS]
    return v, (_dot3(v[0], v[0]), _dot3(v[0], v[1]), _dot3(v[0], v[2]), _dot3(v[1], v[1]), _dot3(v[1], v[2]))


def closest_params(p1: np.ndarray, q1: np.ndarray, p2: np.ndarray, q2: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Parameters (s, t) in [0, 1] of the closest points p1 + s (q1 - p1) and p2 + t (q2 - p2)
    of K segment pairs (all inputs (K, 3)). Degenerate segments (points) are handled."""
    _, g = _gram(np.stack([p1, q1, p2, q2]))
    return _params(*g)


def segment_distance(p1: np.ndarray, q1: np.ndarray, p2: np.ndarray, q2: np.ndarray) -> np.ndarray:
    """Distance between K segment pairs (inputs (K, 3)) -> (K,)."""
    s, t = closest_params(p1, q1, p2, q2)
    ca = p1 + s[:, None] * (q1 - p1)
    cb = p2 + t[:, None] * (q2 - p2)
    return np.sqrt(((cb - ca) ** 2).sum(1))


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
        # broad phase: every capsule's two ends in one gather, then the pairs' capsules in one
        self.cap_ends = np.concatenate([caps[:, 0], caps[:, 1]])
        self.n_caps = len(caps)
        self.pair_ab = np.concatenate([cap_a, cap_b])
        self.not_sphere_a = (self.ia != self.ja).astype(float)
        self.not_sphere_b = (self.ib != self.jb).astype(float)
        self.quad_flat = self.quad[:, :, None] * 3 + np.arange(3)  # (4, K, 3) x.ravel() indices
        self.diameters = 2.0 * radii
        self._quad_c = np.ascontiguousarray(self.quad, dtype=np.int64)  # for the C narrow phase
        self._rsum_c = np.ascontiguousarray(self.rsum, dtype=np.float64)
        # for the C broad phase: each capsule's two end particles, and scratch
        self._caps_c = np.ascontiguousarray(np.stack([caps[:, 0], caps[:, 1]], axis=1), dtype=np.int64)
        self._diam_c = np.ascontiguousarray(self.diameters, dtype=np.float64)
        self._cap_a_c = np.ascontiguousarray(cap_a, dtype=np.int64)
        self._cap_b_c = np.ascontiguousarray(cap_b, dtype=np.int64)
        self._mid2, self._extent = np.empty((len(caps), 3)), np.empty(len(caps))
        self._cand = np.empty(len(cap_a), dtype=np.int64)
        # the kernels' fixed arguments, their addresses taken once (see native.address)
        adr = native.address
        self._broad_args = (adr(self._caps_c), self.n_caps, adr(self._diam_c), adr(self._cap_a_c),
                            adr(self._cap_b_c), len(self.cap_a))
        self._broad_out = (adr(self._mid2), adr(self._extent), adr(self._cand))
        self._narrow_args = (adr(self._quad_c), len(self.cap_a))
        self._rsum_addr = adr(self._rsum_c)

    def __len__(self) -> int:
        return len(self.cap_a)

    def candidates(self, x: np.ndarray, margin: float) -> np.ndarray:
        """Indices of pairs whose bounding spheres (capsule midpoint, half length + radius)
        come within `margin`: a cheap broad phase before the exact segment test (one C call
        when it can, else numpy)."""
        k = kernels()
        if k is not None and x.flags.c_contiguous and x.dtype == np.float64:
            n = k[2](native.array_address(x), *self._broad_args, float(margin), *self._broad_out)
            return self._cand[:n].copy()
        return self.candidates_numpy(x, margin)

    def candidates_numpy(self, x: np.ndarray, margin: float) -> np.ndarray:
        c = self.n_caps
        k = len(self.cap_a)
        ends = x[self.cap_ends]
        mid2 = ends[:c] + ends[c:]  # twice each capsule's midpoint
        axis = ends[c:] - ends[:c]
        # twice each capsule's bounding-sphere radius: its length plus twice its radius
        extent = np.sqrt((axis * axis).sum(1)) + self.diameters
        pair_mid = mid2[self.pair_ab]  # (2K, 3): side a rows, then side b rows
        d = pair_mid[k:] - pair_mid[:k]
        pair_ext = extent[self.pair_ab]
        reach = pair_ext[:k] + pair_ext[k:] + 2.0 * margin
        return np.flatnonzero((d * d).sum(1) < reach * reach)

    def narrow(self, x: np.ndarray, idx: np.ndarray):
        """For the pairs `idx`: (s, t, unit normal a->b, depth); depth > 0 means the capsules
        overlap. One C call when it can (see KERNEL_SOURCE), else numpy."""
        k = kernels()
        if k is not None and x.flags.c_contiguous and x.dtype == np.float64:
            idx = np.ascontiguousarray(idx, dtype=np.int64)
            n = len(idx)
            out = np.empty(6 * n)  # s, t, depth, normal (n, 3): one buffer, one address
            s, t, depth, normal = out[:n], out[n : 2 * n], out[2 * n : 3 * n], out[3 * n :].reshape(n, 3)
            a = native.address(out)
            bad = k[0](native.array_address(x), *self._narrow_args, native.address(idx), n, self._rsum_addr, _EPS,
                       a, a + 8 * n, a + 24 * n, a + 16 * n)
            if bad == 0:
                return s, t, normal, depth
        return self.narrow_numpy(x, idx)

    def narrow_numpy(self, x: np.ndarray, idx: np.ndarray):
        """`narrow` in numpy. Written for few numpy calls: at this size their overhead is the cost."""
        v, g = _gram(x[self.quad[:, idx]])
        s, t = _params(*g)
        d = t[:, None] * v[1] - s[:, None] * v[0] - v[2]  # closest point on b - on a
        dist = np.sqrt((d * d).sum(1))
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

    def contact_set(self, idx: np.ndarray, s: np.ndarray, t: np.ndarray, n: np.ndarray) -> ContactSet:
        """Contact constraints for pairs `idx`, linearized at this step's closest points."""
        # weights of the four ends in (closest point on b) - (closest point on a); a sphere's
        # two ends are one particle: all its weight on the first, so no particle appears twice
        # in one contact and sum w g^2 below is right
        sa = s * self.not_sphere_a[idx]
        tb = t * self.not_sphere_b[idx]
        g = np.stack([sa - 1.0, -sa, 1.0 - tb, tb])
        return ContactSet(self.quad[:, idx], self.quad_flat[:, idx], g, n, self.rsum[idx], self.inv_mass)


class ContactSet:
    """Non-penetration constraints C_k = (sum_q g_qk x_qk) . n_k - rsum_k >= 0 for one step,
    over the four segment ends q of each pair: the barycentric weights g and the normal n come
    from the closest points at detection and stay fixed for the step's iterations (standard
    PBD practice), so each iteration is one gather, one reduction and one scatter. Projection
    (Jacobi over the contacts): lambda_k = max(-C_k, 0) / sum_q w_q g_qk^2 and
    dx_q = w_q g_qk n_k lambda_k: the separation grows by exactly the depth, heavier particles
    moving less, and momentum is conserved. No BLAS: the sums are numpy's own, in a fixed
    order, so a run hashes the same on every CPU (BLAS kernels differ between CPUs)."""

    def __init__(self, quad: np.ndarray, quad_flat: np.ndarray, g: np.ndarray, n: np.ndarray,
                 rsum: np.ndarray, inv_mass: np.ndarray) -> None:
        self.quad = quad  # (4, K) particle indices
        self.rsum = rsum
        self.gn = g[:, :, None] * n[None, :, :]  # (4, K, 3)
        w = inv_mass[quad]  # (4, K)
        inv_wsum = 1.0 / np.maximum((w * (g * g)).sum(0), _EPS)
        self.push = self.gn * (w * inv_wsum)[:, :, None]  # displacement per unit lambda
        self.flat = quad_flat.reshape(-1)  # x.ravel() indices of the push
        self.size = 3 * len(inv_mass)
        k = kernels()
        self._c = None
        if k is not None:
            self.quad = np.ascontiguousarray(self.quad, dtype=np.int64)
            self.flat = np.ascontiguousarray(self.flat, dtype=np.int64)
            self.rsum = np.ascontiguousarray(self.rsum, dtype=np.float64)
            self._lam, self._acc = np.empty(self.quad.shape[1]), np.empty(self.size)
            adr = native.address
            self._c = (k[1], adr(self.quad), self.quad.shape[1], adr(self.gn), adr(self.rsum),
                       adr(self.push), adr(self.flat), adr(self._lam), adr(self._acc), self.size)

    def project(self, x: np.ndarray) -> None:
        if self._c is not None and x.flags.c_contiguous and x.dtype == np.float64 and x.size == self.size:
            fn, *args = self._c
            fn(native.array_address(x), *args)
            return
        self.project_numpy(x)

    def project_numpy(self, x: np.ndarray) -> None:
        depth = self.rsum - _dot12(self.gn, x[self.quad])
        lam = np.maximum(depth, 0.0, out=depth)
        dx = np.bincount(self.flat, weights=(self.push * lam[:, None]).reshape(-1), minlength=self.size)
        x += dx.reshape(x.shape)

    def separations(self, x: np.ndarray) -> np.ndarray:
        """(closest point on b - closest point on a) . n at positions x, with this step's
        barycentric weights and normals -> (K,)."""
        return _dot12(self.gn, x[self.quad])

    def closing_speeds(self, v: np.ndarray) -> np.ndarray:
        """Speed at which each pair's closest points approach along its normal (> 0 closing)."""
        return -_dot12(self.gn, v[self.quad])
