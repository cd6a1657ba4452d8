"""Incremental DTW of one growing query against every template at once (paper IV-B).

The alignment is anchored at the motion onset (query frame 0 meets template frame 0) and open
at the template's end: after n query frames, a template's score is the best normalized cost of
matching the whole query to any PREFIX of the template, so a half-done punch matches the first
half of its template. Each pushed frame adds one row of the cost matrix for all templates in a
few numpy calls; nothing is ever recomputed.

Step pattern: "symmetric2" (horizontal and vertical steps weigh the local cost once, diagonal
steps twice, the start cell twice). Every path from (0, 0) to (i, j) then has total weight
i + j + 2, so dividing by it normalizes by path length exactly while the DP stays optimal.

Within a row, D[i, j] = min(a_j, D[i, j-1] + c_j) with a_j from the previous row: a min-plus
scan. Four ways to run it (equal scores, to the bit but for the scan, see below):
- "scan": the closed form D_j = C_j + min_{k<=j}(a_k - C_k), C = cumsum(c), i.e. numpy
  `cumsum` and `minimum.accumulate` over the whole (L, T) block. A fixed handful of calls:
  fastest for a few dozen templates.
- "loop": a Python loop over template positions j, each step one vectorized operation across
  all T templates, doing the C kernel's operations in its order (dtw_loop.py): its scores are
  "native"'s and "jit"'s bit for bit. Per call cost grows with T slowly (at the game's 156
  templates about a quarter over the scan's, at 13 several times it).
- "jit": one compiled numba call per frame (dtw_kernel.push_row_kernel()) doing the local costs, the
  row, the normalization and the per-template minimum; no numpy call overhead, and its loop over
  templates vectorizes. Needs numba (not installed, or QUICKJAB_NO_JIT=1: unavailable).
- "native": the same kernel in C (dtw_native.py), built once with the system's C compiler and
  loaded with ctypes: no numba import (~0.6 s, ~110 MB) at start-up. Same results as "jit".
`method="auto"` picks "native" when it can be had; else "jit" from JIT_FROM_TEMPLATES templates
(where its start-up cost pays) when numba is available; else "loop". All three give the same
scores to the bit, so a run's events and state hash do not depend on which one a machine (or a
process whose kernel build failed) runs. The scan's scores differ in the last bits (up to ~1e-9
on game input: its expanded costs cancel where a frame equals a template frame) and it is
used only when named.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from engine.recognition.dtw_kernel import push_row_kernel
from engine.recognition.dtw_loop import loop_buffers, loop_row
from engine.recognition.dtw_native import push_row_native
from engine.recognition.dtw_templates import TemplateEdits, pad_templates

# Local costs: |t - q|^2 = |t|^2 - 2 t.q + |q|^2 from precomputed squared norms and one
# matrix-vector product (half the cost of a broadcast subtract-square-sum; rounding ~1e-7 g).
# `exact_costs=True` computes them the direct way (the reference tests use it; "jit", "native"
# and "loop" always do, in the kernel's order).
METHODS = ("scan", "loop", "jit", "native")
# numba's import and code load cost ~0.6 s and ~110 MB of a process (issue 14): without the C
# kernel, auto takes it only from here, where numpy's per-frame cost passes ~0.25 ms.
JIT_FROM_TEMPLATES = 200


def jit_available() -> bool:
    """True when the "jit" method can run (numba importable and QUICKJAB_NO_JIT not set)."""
    return push_row_kernel() is not None


def native_available() -> bool:
    """True when the "native" method can run (the C kernel built or buildable here, and neither
    QUICKJAB_NO_NATIVE nor QUICKJAB_NO_JIT set)."""
    return push_row_native() is not None


def auto_method(n_templates: int) -> str:
    """The method `method="auto"` runs for this many templates (numba imported only when chosen):
    always one whose scores are the C kernel's bit for bit, so that a run's decisions do not
    depend on whether a compiler was there ("scan" rounds differently: only by name)."""
    if native_available():
        return "native"
    if n_templates >= JIT_FROM_TEMPLATES and jit_available():
        return "jit"
    return "loop"


class IncrementalDTW(TemplateEdits):
    """Open-end DTW of a growing query against T templates of shape (L_k, D).

    push(frame) -> (T,) normalized scores of the query so far (lower is closer). Changing
    the templates (add_, remove_, replace_, update_templates) is TemplateEdits' part."""

    def __init__(
        self,
        templates: Sequence[np.ndarray],
        method: str = "auto",
        min_progress: float = 0.0,
        exact_costs: bool = False,
    ):
        tmpl, lengths = pad_templates([np.asarray(t, dtype=np.float64) for t in templates])
        if method == "auto":
            method = auto_method(tmpl.shape[1])
        if method not in METHODS:
            raise ValueError(f"method must be 'auto', 'scan', 'loop', 'jit' or 'native', not {method!r}")
        if method == "jit" and not jit_available():
            raise ValueError("method 'jit' needs numba (not importable here, or QUICKJAB_NO_JIT=1 is set)")
        if method == "native" and not native_available():
            raise ValueError("method 'native' needs a C compiler (none here, or QUICKJAB_NO_NATIVE=1 is set)")
        self.method = method
        # Scoring only (the accumulated costs are plain DTW): after n query frames the query's
        # end may only align to template positions j + 1 >= min(L, min_progress * n), so a
        # template cannot win by matching a short prefix of itself to a long query.
        self.min_progress = float(min_progress)
        self._exact_costs = exact_costs
        # The templates as given, in order: update_templates() tells kept ones by identity.
        self.sources = list(templates)
        # The kernel's template layout: (L, D, T), a position's values contiguous across
        # templates (its innermost loop); always the direct |t - q| (exact costs).
        self._kernel = push_row_kernel() if method == "jit" else push_row_native() if method == "native" else None
        self._set_padded(tmpl, lengths)
        if self._kernel is not None:
            # Compile (or load from numba's cache) now, not on the first game frame.
            self.n = 0
            self.push(np.zeros(self.D))
        self.reset()

    @property
    def tmpl(self) -> np.ndarray:
        """(L, T, D) zero-padded templates (for "native" a view of its own layout)."""
        return self._ldt_full[:, :, : self.T].transpose(0, 2, 1) if self.method == "native" else self._tmpl

    def _set_padded(self, tmpl: np.ndarray, lengths: np.ndarray) -> None:
        """Take the (L, T, D) padded templates and their lengths; size every per-frame buffer."""
        L, T, D = tmpl.shape
        self.L, self.D = L, D
        pos = np.arange(L)[:, None]
        self._steps = pos + 1.0  # (L, 1): j + 1, the path-length term of the normalization
        self._cur = 0
        self._recip: dict[int, tuple[np.ndarray, np.ndarray]] = {}
        self._take: dict[tuple[int, float], np.ndarray] = {}
        self._q = np.empty(D)  # kernels: frames are copied here (float64, contiguous, right length)
        if self.method == "native":
            # Room for more templates: the C kernel takes the row stride (capacity) apart from T,
            # so add_templates() writes a column instead of reallocating (the adaptation).
            cap = T + max(8, T // 2)
            self._ldt_full = np.zeros((L, D, cap))
            self._ldt_full[:, :, :T] = tmpl.transpose(0, 2, 1)
            self._len_full = np.zeros(cap, dtype=np.int64)
            self._len_full[:T] = lengths
            self._arange_full = np.arange(cap)
            self._ext_full = [np.full((L + 1, cap), np.inf) for _ in range(2)]
            self._init_full = np.full((L + 1, cap), np.inf)
            self._init_full[0] = 0.0
            self._scratch = [np.empty(cap), np.empty(cap), np.empty(cap, dtype=np.int64), np.empty(cap)]
            self._bind_native()
            self._set_count(T)
            return
        self._tmpl, self.lengths, self.T = tmpl, lengths, T
        self._cols = np.arange(T)
        self._ext = [np.full((L + 1, T), np.inf) for _ in range(2)]
        self._init = np.full((L + 1, T), np.inf)
        self._init[0] = 0.0
        self._row = self._ext[0][1:]
        self.scores = np.empty(T)
        if self.method == "jit":
            self._tmpl_ldt = np.ascontiguousarray(tmpl.transpose(0, 2, 1))
            self._jit_cost = np.empty(T)
            self._jit_left = np.empty(T)
            self._jit_first = np.empty(T, dtype=np.int64)
            self._rows = [e[1:] for e in self._ext]
        else:
            self._init_numpy_buffers(self._exact_costs)

    def _set_count(self, T: int) -> None:
        """"native": the first T columns of the buffers are the templates; views of them."""
        self.T = T
        self.lengths = self._len_full[:T]
        self._cols = self._arange_full[:T]
        self._ext = [e[:, :T] for e in self._ext_full]
        self._init = self._init_full[:, :T]
        self._rows = [e[1:] for e in self._ext]
        self._row = self._rows[self._cur]
        self.scores = self._scratch[3][:T]

    def _bind_native(self) -> None:
        """The C kernel's arguments as addresses, taken once per allocation (ctypes converts
        ints cheaply; the arrays never move while this DTW holds them)."""
        self._native_prev = [self._init_full.ctypes.data, *(e.ctypes.data for e in self._ext_full)]
        self._native_args = ((self._ldt_full.ctypes.data, self._len_full.ctypes.data, self._q.ctypes.data),
                             *(a.ctypes.data for a in self._scratch), len(self._len_full))

    def _push_native(self, frame: np.ndarray) -> np.ndarray:
        self._q[:] = frame
        (tmpl, lengths, q), cost, left, first, scores, stride = self._native_args
        prev = self._native_prev[0 if self.n == 0 else 1 + self._cur]
        self._cur ^= 1
        self._kernel(tmpl, lengths, q, prev, self._native_prev[1 + self._cur], cost, left, first,
                     self.L, self.D, self.T, stride, self.n, self.min_progress, scores)
        self._row = self._rows[self._cur]
        self.n += 1
        return self.scores

    def _init_numpy_buffers(self, exact_costs: bool) -> None:
        """What the numpy methods ("scan", "loop") reuse every frame; "jit" needs none of it."""
        self._expanded = not exact_costs
        self._loop = loop_buffers(self.tmpl) if self.method == "loop" else None
        sqnorm = np.einsum("ltd,ltd->lt", self.tmpl, self.tmpl)
        # [-2t, |t|^2, 1] . [q, 1, |q|^2]: the -2 is folded in here, so a frame is one copy.
        self._flat = np.concatenate(
            [-2.0 * self.tmpl, sqnorm[..., None], np.ones((self.L, self.T, 1))], axis=2
        ).reshape(self.L * self.T, self.D + 2)
        self._q_aug = np.ones(self.D + 2)
        # Positions past a template's end never count: +inf added to their normalized score.
        pos = np.arange(self.L)[:, None]
        self._pad_inf = np.where(pos < self.lengths[None, :], 0.0, np.inf)
        shape = (self.L, self.T)
        # Views made once (each slice or transpose made per frame costs as much as a small ufunc):
        # per row buffer (previous rows' left/up neighbours, the new row, its transpose).
        self._views = [(e[:-1], e[1:], e[1:].T) for e in (*self._ext, self._init)]
        self._suffix = np.empty((self.T, self.L))
        self._suffix_flat = self._suffix.reshape(-1)
        self._reduced = np.empty(2 * self.T)
        self._c = np.empty(shape)
        self._tmp = np.empty(shape)
        self._zeros = np.zeros(shape)  # np.maximum against an array: no scalar conversion per call
        # Running sums of the row's local costs with a 0 in front: [1:] is the inclusive cumsum,
        # [:-1] the exclusive one, both from one accumulate.
        self._cumsums = np.zeros((self.L + 1, self.T))
        self._cum, self._cum_excl = self._cumsums[1:], self._cumsums[:-1]
        self._diff = np.empty(self.tmpl.shape) if not self._expanded else None
        self._c_flat = self._c.reshape(-1)
        self._q_head = self._q_aug[: self.D]

    def reset(self) -> None:
        """Forget the query (a new onset)."""
        self.n = 0

    def _local_costs(self, q: np.ndarray) -> np.ndarray:
        c = self._c
        if self._expanded:
            # |t - q|^2 = [t, |t|^2, 1] . [-2q, 1, |q|^2]: one BLAS matvec, no (L, T, D) temporary.
            qa = self._q_aug
            self._q_head[:] = q
            qa[self.D + 1] = q.dot(q)
            np.dot(self._flat, qa, out=self._c_flat)
            np.maximum(c, self._zeros, out=c)
        else:
            np.subtract(self.tmpl, q, out=self._diff)
            np.einsum("ltd,ltd->lt", self._diff, self._diff, out=c)
        np.sqrt(c, out=c)
        return c

    def _push_jit(self, frame: np.ndarray) -> np.ndarray:
        q = self._q
        q[:] = frame
        prev = self._init if self.n == 0 else self._ext[self._cur]
        self._cur ^= 1
        self._kernel(self._tmpl_ldt, self.lengths, q, prev, self._ext[self._cur], self._jit_cost,
                     self._jit_left, self._jit_first, self.n, float(self.min_progress), self.scores)
        self._row = self._rows[self._cur]
        self.n += 1
        return self.scores

    def push(self, frame: np.ndarray) -> np.ndarray:
        """Add the query's next frame; (T,) scores of the query so far, in a reused buffer."""
        if self.method == "native":
            return self._push_native(frame)
        if self.method == "jit":
            return self._push_jit(frame)
        q = np.asarray(frame, dtype=np.float64)
        # Rows are stored with one sentinel position in front (index 0): +inf for real rows, 0
        # in the virtual row before the first frame, so D[0, 0] = 2 c_0 needs no special case.
        prev_left, prev_up, _ = self._views[2 if self.n == 0 else self._cur]
        self._cur ^= 1
        _, row, row_t = self._views[self._cur]
        if self.method == "scan":
            # a_j = min(D[i-1, j] + c_j, D[i-1, j-1] + 2 c_j) = c_j + min(D[i-1, j], D[i-1, j-1] + c_j);
            # row_j = C_j + min_{k<=j}(a_k - C_k), C = cumsum(c); a_k - C_k is
            # min(D[i-1, k], D[i-1, k-1] + c_k) - C_{k-1}, built in the row buffer itself.
            c = self._local_costs(q)
            np.add.accumulate(c, axis=0, out=self._cum)  # = cumsum, with less call overhead
            np.add(prev_left, c, out=row)
            np.minimum(prev_up, row, out=row)
            row -= self._cum_excl
            np.minimum.accumulate(row, axis=0, out=row)
            row += self._cum
        else:  # "loop": the C kernel's operations (dtw_loop.py), its scores bit for bit
            loop_row(self._loop, q, prev_left, prev_up, row)
        self._row = row
        self.n += 1
        return self._normalized_scores(row, row_t)

    def _normalized_scores(self, row: np.ndarray, row_t: np.ndarray) -> np.ndarray:
        """The numpy methods' scores from the new row (and its transpose): each template's best
        over the positions min_progress allows, normalized by path length, into self.scores."""
        recip = self._recip.get(self.n)
        if recip is None:
            col = 1.0 / (self._steps + self.n)
            recip = self._recip.setdefault(self.n, (col, col.T))
        if self.min_progress > 0:
            # best over positions need - 1 <= j < L_k of each template: one reduceat over the
            # position-contiguous copy (T, L); every other segment is the gap, skipped.
            key = (self.n, self.min_progress)
            idx = self._take.get(key)
            if idx is None:
                first = np.minimum(self.lengths, int(np.ceil(self.min_progress * self.n))) - 1
                bounds = np.empty(2 * self.T, dtype=np.intp)
                bounds[0::2] = self._cols * self.L + first
                bounds[1::2] = self._cols * self.L + self.lengths
                idx = self._take.setdefault(key, bounds[:-1] if bounds[-1] == self.T * self.L else bounds)
            np.multiply(row_t, recip[1], out=self._suffix)  # normalized, template-major
            red = self._reduced[: len(idx)]
            np.minimum.reduceat(self._suffix_flat, idx, out=red)
            self.scores[:] = red[0::2]
        else:
            norm = np.multiply(row, recip[0], out=self._tmp)
            norm += self._pad_inf
            np.minimum.reduce(norm, axis=0, out=self.scores)  # = np.min, less call overhead
        return self.scores

    def closed_scores(self) -> np.ndarray:
        """(T,) closed-end normalized scores of the query so far: the whole query against each
        whole template (a new array; not on the per-frame path)."""
        return self._row[self.lengths - 1, self._cols] / (self.lengths + self.n)

    def position(self, k: int) -> int:
        """Template k's position aligned to the query's newest frame (unconstrained open end)."""
        n_k = int(self.lengths[k])
        return int((self._row[:n_k, k] / (self._steps[:n_k, 0] + self.n)).argmin())


def dtw_rows(query: np.ndarray, template: np.ndarray) -> np.ndarray:
    """Reference: the plain full accumulated-cost matrix (n, L) of the same step pattern,
    computed cell by cell. For tests and as the definition the incremental version follows."""
    query = np.asarray(query, dtype=np.float64)
    template = np.asarray(template, dtype=np.float64)
    n, m = len(query), len(template)
    acc = np.full((n, m), np.inf)
    for i in range(n):
        for j in range(m):
            c = float(np.linalg.norm(query[i] - template[j]))
            if i == 0 and j == 0:
                acc[i, j] = 2.0 * c
                continue
            best = np.inf
            if i > 0:
                best = min(best, acc[i - 1, j] + c)
            if j > 0:
                best = min(best, acc[i, j - 1] + c)
            if i > 0 and j > 0:
                best = min(best, acc[i - 1, j - 1] + 2.0 * c)
            acc[i, j] = best
    return acc


def open_end_score(query: np.ndarray, template: np.ndarray, min_progress: float = 0.0) -> float:
    """Reference open-end normalized score of the whole query (plain full DTW)."""
    acc = dtw_rows(query, template)
    n, m = len(query), len(template)
    steps = np.arange(1, m + 1)
    scores = acc[-1] / (n + steps)
    scores[steps < min(m, int(np.ceil(min_progress * n)))] = np.inf
    return float(np.min(scores))


def dtw_distance(a: np.ndarray, b: np.ndarray) -> float:
    """Closed-end normalized DTW distance between two whole sequences (vectorized over rows;
    used offline to build templates and thresholds)."""
    dtw = IncrementalDTW([np.asarray(b, dtype=np.float64)], method="scan")
    for x in np.asarray(a, dtype=np.float64):
        dtw.push(x)
    return float(dtw._row[len(b) - 1, 0] / (len(a) + len(b)))
