"""Distance constraints (bones and joint limits) relaxed over all sticks at once.

One constraint keeps the distance between particles i and j inside [lo, hi]: a bone has
lo == hi == its rest length (an equality), a joint limit a range (an inequality that only
acts when violated). Both are projected the same way (Jakobsen): move the two ends along
their difference, split by inverse mass, so that the distance becomes clip(len, lo, hi).
A stretched stick (len > hi) pulls its ends together; a compressed one pushes them apart.

Two vectorized solvers:
- "jacobi" (default): all sticks at once from the same positions, the corrections summed per
  particle and scaled by min(1, omega / max(count_i, count_j)), omega = 2. The same factor at
  both ends keeps linear and angular momentum (plain per-particle averaging does not); the
  min(1, .) never over-projects a lone stick; omega = 2 over-relaxes where sticks meet. On
  the test humanoid pulled into a punch that a head stops, bones stretch 4.6 % (6 Hz pull)
  with omega = 2 against 6.6 % with 1.5; 2.5 went unstable when two bodies were crushed
  together.
- "gauss_seidel": the constraints are edge-coloured so that no two sticks of one colour
  share a particle; each colour is projected as one batch, in sequence. That is exactly
  sequential Gauss-Seidel and converges about twice as fast per iteration, but costs one
  batch per colour (6 on the test humanoid): at 17-34 particles numpy's per-call overhead
  is the whole cost, so in the same time Jacobi gets further (`quickjab bench physics`).
Chebyshev acceleration of the Jacobi sweeps (Wang 2015) was tried and dropped: with 2-4
sweeps and contacts in between it overshot (bones stretched 49 % at 2 sweeps, 10 Hz).
"""

from __future__ import annotations

import ctypes

import numpy as np

from engine import native

_EPS = 1e-12

# _Batch.project in C (engine/native.py), numpy's operations in numpy's order one for one (the
# row sum (d0 d0 + d1 d1) + d2 d2 as np.add.reduce does it, the scatter in bincount's order),
# so a world steps to the same bits with or without a C compiler. One call instead of eleven
# numpy calls on arrays of ~60 sticks, four times a step.
PROJECT_SOURCE = r"""
#include <math.h>
static double maxnan(double a, double b) { return (a >= b || a != a) ? a : b; }  /* np.maximum */
static double minnan(double a, double b) { return (a <= b || a != a) ? a : b; }  /* np.minimum */
void project(double *restrict x, const long long *restrict ends, long long s,
             const double *restrict k, const long long *restrict flat, const double *restrict lo,
             const double *restrict hi, double eps, double *restrict vals, double *restrict acc,
             long long size)
{
    for (long long m = 0; m < s; m++) {
        const double *xi = x + 3 * ends[m], *xj = x + 3 * ends[s + m];
        double d0 = xj[0] - xi[0], d1 = xj[1] - xi[1], d2 = xj[2] - xi[2];
        double len = (d0 * d0 + d1 * d1) + d2 * d2;
        len = maxnan(sqrt(len), eps);
        double f = minnan(maxnan(len, lo[m]), hi[m]);
        f = 1.0 - f / len;
        d0 *= f; d1 *= f; d2 *= f;
        double *vi = vals + 3 * m, *vj = vals + 3 * (s + m);
        vi[0] = k[m] * d0; vi[1] = k[m] * d1; vi[2] = k[m] * d2;
        vj[0] = k[s + m] * d0; vj[1] = k[s + m] * d1; vj[2] = k[s + m] * d2;
    }
    for (long long q = 0; q < size; q++) acc[q] = 0.0;
    for (long long q = 0; q < 6 * s; q++) acc[flat[q]] += vals[q];
    for (long long q = 0; q < size; q++) x[q] += acc[q];
}
"""
_kernel: list = []


def project_kernel():
    """The C projection (a ctypes function), or None without a compiler (numpy then)."""
    if not _kernel:
        lib = native.load_library("stick_project", PROJECT_SOURCE, ("project",))  # None: no such symbol either
        fn = None
        if lib is not None:
            fn = lib.project
            p, i64 = ctypes.c_void_p, ctypes.c_longlong
            fn.argtypes = [p, p, i64, p, p, p, p, ctypes.c_double, p, p, i64]
            fn.restype = None
        _kernel.append(fn)
    return _kernel[0]


def edge_colouring(pairs: np.ndarray) -> np.ndarray:
    """Greedy colouring of edges (S, 2) so that edges of one colour share no vertex -> (S,)
    colour ids. Edges at the busiest vertices go first, which keeps the colour count near the
    maximum degree. Runs when a body is added, never per step."""
    colours = np.full(len(pairs), -1, dtype=np.int64)
    if len(pairs) == 0:
        return colours
    deg = np.bincount(pairs.ravel())
    order = np.argsort(-(deg[pairs[:, 0]] + deg[pairs[:, 1]]), kind="stable")
    used: dict[int, set[int]] = {}
    for e in order:
        i, j = int(pairs[e, 0]), int(pairs[e, 1])
        taken = used.setdefault(i, set()) | used.setdefault(j, set())
        c = 0
        while c in taken:
            c += 1
        colours[e] = c
        used[i].add(c)
        used[j].add(c)
    return colours


class DistanceConstraints:
    """All distance constraints of the world, laid out for one solver; rebuilt when a body is
    added. `relax(x)` runs one iteration in place."""

    def __init__(self, pairs: np.ndarray, lo: np.ndarray, hi: np.ndarray, inv_mass: np.ndarray,
                 solver: str = "jacobi", omega: float = 2.0) -> None:
        if solver not in ("gauss_seidel", "jacobi"):
            raise ValueError(f"unknown solver {solver!r}: use 'gauss_seidel' or 'jacobi'")
        self.solver = solver
        self.pairs = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
        self.lo = np.asarray(lo, dtype=float)
        self.hi = np.asarray(hi, dtype=float)
        i, j = self.pairs[:, 0], self.pairs[:, 1]
        wsum = inv_mass[i] + inv_mass[j]
        # share of the correction each end takes: the lighter end moves more
        ki = inv_mass[i] / np.maximum(wsum, _EPS)
        kj = inv_mass[j] / np.maximum(wsum, _EPS)
        n = len(inv_mass)
        if solver == "gauss_seidel":
            colours = edge_colouring(self.pairs)
            self.n_colours = int(colours.max()) + 1 if len(colours) else 0
            groups = [np.flatnonzero(colours == c) for c in range(self.n_colours)]
            scale = np.ones(len(self.pairs))  # within a colour no particle is shared
        else:
            self.n_colours = 1 if len(self.pairs) else 0
            groups = [np.arange(len(self.pairs))] if len(self.pairs) else []
            count = np.bincount(self.pairs.ravel(), minlength=n).astype(float)
            scale = np.minimum(1.0, omega / np.maximum(np.maximum(count[i], count[j]), 1.0))
        self.batches = [_Batch(i[g], j[g], self.lo[g], self.hi[g], ki[g] * scale[g], kj[g] * scale[g], n)
                        for g in groups]

    def __len__(self) -> int:
        return len(self.pairs)

    def relax(self, x: np.ndarray) -> None:
        """One relaxation iteration over every constraint, in place on x (N, 3): one batch
        (Jacobi) or one batch per colour in turn (Gauss-Seidel)."""
        for batch in self.batches:
            batch.project(x)

    def errors(self, x: np.ndarray) -> np.ndarray:
        """Per-constraint violation in metres (0 inside [lo, hi]) -> (S,)."""
        d = x[self.pairs[:, 1]] - x[self.pairs[:, 0]]
        length = np.sqrt((d * d).sum(1))
        return np.abs(length - np.clip(length, self.lo, self.hi))


class _Batch:
    """Constraints projected together from the same positions: one gather of both ends of
    every stick, a few elementwise operations, and one scatter (np.bincount) of the
    corrections back to the particles, mass split and relaxation scale folded in. No BLAS:
    bincount and numpy's elementwise operations give the same bits on every CPU, where BLAS
    kernels (chosen per CPU) do not, and runs must hash the same everywhere."""

    def __init__(self, i, j, lo, hi, ki, kj, n: int) -> None:
        s = len(i)
        self.s = s
        self.ends = np.concatenate([i, j])  # gather: rows 0..s-1 the i ends, then the j ends
        # correction of end i is +ki * c, of end j is -kj * c, c the stick's correction vector
        self.k = np.stack([ki, -kj])[:, :, None]  # (2, S, 1)
        self.flat = (self.ends[:, None] * 3 + np.arange(3)).reshape(-1)  # x.ravel() indices
        self.size = 3 * n
        self.lo = np.ascontiguousarray(np.maximum(lo, _EPS), dtype=np.float64)  # a zero minimum must not divide by zero
        self.hi = np.ascontiguousarray(hi, dtype=np.float64)
        self.ends = np.ascontiguousarray(self.ends, dtype=np.int64)
        self.flat = np.ascontiguousarray(self.flat, dtype=np.int64)
        self._len = np.zeros(s)
        self._sq = np.zeros((s, 3))
        self._d = np.zeros((s, 3))
        self._xe = np.zeros((2 * s, 3))
        self._f = np.zeros(s)
        self._vals = np.zeros((2, s, 3))
        self._acc = np.zeros(self.size)
        self._k_flat = np.ascontiguousarray(self.k.reshape(2, s))
        self.kernel = project_kernel()
        self._args = (self.ends.ctypes.data, s, self._k_flat.ctypes.data, self.flat.ctypes.data,
                      self.lo.ctypes.data, self.hi.ctypes.data, _EPS, self._vals.ctypes.data,
                      self._acc.ctypes.data, self.size)

    def project(self, x: np.ndarray) -> None:
        if self.kernel is not None and x.flags.c_contiguous and x.dtype == np.float64 and x.size == self.size:
            self.kernel(native.array_address(x), *self._args)
            return
        self.project_numpy(x)

    def project_numpy(self, x: np.ndarray) -> None:
        # written for few numpy calls: at this size each call's overhead is the cost
        xe = np.take(x, self.ends, axis=0, out=self._xe)
        d = np.subtract(xe[self.s:], xe[:self.s], out=self._d)  # x_j - x_i
        length = np.add.reduce(np.multiply(d, d, out=self._sq), 1, None, self._len)
        np.sqrt(length, out=length)
        np.maximum(length, _EPS, out=length)
        f = np.maximum(length, self.lo, out=self._f)
        np.minimum(f, self.hi, out=f)  # the target length, clip(len, lo, hi)
        # 1 - target / len = (len - target) / len: > 0 stretched (the ends move together),
        # < 0 compressed (apart), 0 inside [lo, hi]
        np.divide(f, length, out=f)
        np.subtract(1.0, f, out=f)
        d *= f[:, None]
        vals = np.multiply(self.k, d, out=self._vals)  # (2, S, 3): i ends, then j ends
        x += np.bincount(self.flat, weights=vals.reshape(-1), minlength=self.size).reshape(x.shape)
