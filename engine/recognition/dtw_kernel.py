"""The incremental DTW's per-frame step as one compiled (numba) call: IncrementalDTW's "jit" method.

Why compiled: at a few dozen templates the numpy formulations spend most of a frame in call
overhead (~13 calls of ~1 us on 60 x 13 blocks); one compiled loop nest does the local costs,
the row recurrence, the normalization and the per-template minimum in a single call, and at
hundreds of templates its inner loop over templates is vectorized (SIMD) by LLVM.

`push_row_kernel()` is None when numba cannot be imported (no wheels, e.g. 32-bit ARM boards)
or when QUICKJAB_NO_JIT=1 is set; IncrementalDTW then uses its numpy methods.

Compiled code is cached on disk (cache=True) so later processes skip the ~0.5 s compile. When no
cache directory is writable (an installed, read-only tree and no writable user cache) numba
refuses cache=True when the function is decorated; we then compile without caching instead.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable

NO_JIT_ENV = "QUICKJAB_NO_JIT"


def _jit_disabled() -> bool:
    return os.environ.get(NO_JIT_ENV, "").strip() not in ("", "0")


def _push_row_py(tmpl, lengths, q, prev, cur, cost, left, first, n, min_progress, scores):  # pragma: no cover - compiled
    """One query frame (query index n, 0-based) against every template.

    tmpl: (L, D, T) templates, position-major, each position's D values contiguous across
    templates (the innermost loops run over templates: contiguous, vectorized).
    prev, cur: (L + 1, T) accumulated-cost rows with one sentinel position in front (index 0):
    prev is the previous row (or, for n == 0, the virtual row: 0 at the sentinel, +inf after);
    cur's sentinel stays +inf. cur[1:] gets D[n, :] for all positions, including the padding
    past a template's end (computed but never counted, as in the numpy methods).
    cost, left (float) and first (int64): (T,) scratch.
    scores: (T,) out, each template's best normalized score over positions
    first_k <= j < L_k, first_k = min(L_k, ceil(min_progress * (n + 1))) - 1.
    """
    L, D, T = tmpl.shape
    frames = n + 1
    need = min_progress * frames
    for k in range(T):
        length = lengths[k]
        first[k] = length - 1 if need >= length else int(math.ceil(need)) - 1
        scores[k] = math.inf
        left[k] = math.inf  # D[n, j - 1] for j = 0: the sentinel
    for j in range(L):
        # local costs |t - q| at position j for every template: direct subtract-square-sum
        for k in range(T):
            cost[k] = 0.0
        for d in range(D):
            qd = q[d]
            for k in range(T):
                diff = tmpl[j, d, k] - qd
                cost[k] += diff * diff
        # symmetric2: D[n, j] = min(D[n-1, j] + c, D[n-1, j-1] + 2c, D[n, j-1] + c), divided by
        # the path weight n + j + 2. D[n, j-1] is read from `left`, not from cur[j]: with cur
        # read and written in one loop LLVM cannot prove the row offset (T) is safe and does
        # not vectorize (measured 2.3x slower at 1000 templates).
        inv = 1.0 / (j + 1 + frames)
        for k in range(T):
            c = math.sqrt(cost[k])
            up = prev[j + 1, k] + c
            diag = prev[j, k] + 2.0 * c
            best = up if up < diag else diag
            side = left[k] + c
            v = best if best < side else side
            cur[j + 1, k] = v
            left[k] = v
            s = v * inv
            if j >= first[k] and j < lengths[k] and s < scores[k]:
                scores[k] = s


_compiled: list[Callable | None] = []  # filled on the first call of push_row_kernel()


def push_row_kernel() -> Callable | None:
    """The compiled kernel, or None without numba. numba is imported on first use only (it
    adds ~0.3 s to a process's start, which CLI commands that never recognize need not pay)."""
    if not _compiled:
        _compiled.append(_compile())
    return _compiled[0]


def _compile() -> Callable | None:
    if _jit_disabled():
        return None
    try:
        import numba
    except (ImportError, OSError):  # no wheels (or no llvmlite library) here: numpy serves
        return None
    try:
        return numba.njit(cache=True, nogil=True)(_push_row_py)
    except RuntimeError:
        # "cannot cache function ...: no locator available": neither the source's __pycache__
        # nor a user cache directory is writable (e.g. installed read-only): compile per process.
        return numba.njit(cache=False, nogil=True)(_push_row_py)
