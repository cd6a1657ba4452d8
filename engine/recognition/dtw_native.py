"""The incremental DTW's per-frame step in C, loaded with ctypes: IncrementalDTW's "native" method.

Why: the numba kernel (dtw_kernel.py) is fast but importing numba and loading its cached code
costs ~0.6 s and ~110 MB on every start, more than the whole game on a 1 GB board (issue 14).
The same loop nest in C is ~40 lines, built once with the system's C compiler into a small
shared library in the user's cache directory, and afterwards costs a dlopen (~1 ms, <1 MB).

The arithmetic is the numba kernel's, operation for operation (no fused multiply-add:
-ffp-contract=off; sqrt correctly rounded), so "native" and "jit" give the same scores bit for
bit, and so does the numpy "loop" method (dtw_loop.py: the same operations in the same order),
which `method="auto"` runs where this kernel cannot be had. The numpy scan sums in another order
and expands its local costs: its scores differ in the last bits (1.5e-14 on noisy queries, but
up to 1.4e-9 in the scripted match, where rest frames equal template frames and the expansion
cancels), so it is run only when named.

`push_row_native()` is None when there is no C compiler (cc, or $CC) and no library built
earlier (a failed build is remembered: engine/native.py), or when QUICKJAB_NO_NATIVE=1 (or QUICKJAB_NO_JIT=1: no compiled kernel at all) is set;
IncrementalDTW then uses numba for hundreds of templates, else numpy.
"""

from __future__ import annotations

import ctypes
from collections.abc import Callable
from pathlib import Path

from engine import native
from engine.native import CACHE_ENV, NO_NATIVE_ENV  # noqa: F401 - the switches, named here too

SOURCE = r"""
#include <math.h>
/* One query frame (index n, 0-based) against every template; see dtw_kernel._push_row_py,
   which this follows line by line. tmpl: (L, D, S); prev, cur: (L + 1, S) with a sentinel row;
   only the first T of the S (row stride) columns are templates: spare columns let a template
   be added without reallocating. */
void push_row(const double *restrict tmpl, const long long *restrict lengths,
              const double *restrict q, const double *restrict prev, double *restrict cur,
              double *restrict cost, double *restrict left, long long *restrict first,
              long long L, long long D, long long T, long long S, long long n, double min_progress,
              double *restrict scores)
{
    long long frames = n + 1;
    double need = min_progress * (double)frames;
    for (long long k = 0; k < T; k++) {
        long long length = lengths[k];
        first[k] = need >= (double)length ? length - 1 : (long long)ceil(need) - 1;
        scores[k] = INFINITY;
        left[k] = INFINITY;
    }
    for (long long j = 0; j < L; j++) {
        for (long long k = 0; k < T; k++) cost[k] = 0.0;
        for (long long d = 0; d < D; d++) {
            const double qd = q[d];
            const double *row = tmpl + (j * D + d) * S;
            for (long long k = 0; k < T; k++) {
                double diff = row[k] - qd;
                cost[k] += diff * diff;
            }
        }
        const double inv = 1.0 / (double)(j + 1 + frames);
        const double *up_row = prev + (j + 1) * S, *diag_row = prev + j * S;
        double *out = cur + (j + 1) * S;
        for (long long k = 0; k < T; k++) {
            double c = sqrt(cost[k]);
            double up = up_row[k] + c;
            double diag = diag_row[k] + 2.0 * c;
            double best = up < diag ? up : diag;
            double side = left[k] + c;
            double v = best < side ? best : side;
            out[k] = v;
            left[k] = v;
            double s = v * inv;
            /* a select on `&` (no branch, no conditional store): the loop vectorizes */
            int keep = (j >= first[k]) & (j < lengths[k]) & (s < scores[k]);
            scores[k] = keep ? s : scores[k];
        }
    }
}
"""

_loaded: list[Callable | None] = []


def library_path() -> Path:
    """Where this kernel's built library is (or would be) kept."""
    return native.library_path("dtw_push_row", SOURCE)


def _load() -> Callable | None:
    lib = native.load_library("dtw_push_row", SOURCE, ("push_row",))  # None: missing symbol too
    if lib is None:
        return None
    fn = lib.push_row
    p, i64 = ctypes.c_void_p, ctypes.c_longlong
    fn.argtypes = [p, p, p, p, p, p, p, p, i64, i64, i64, i64, i64, ctypes.c_double, p]
    fn.restype = None
    return fn


def push_row_native() -> Callable | None:
    """The C kernel (a ctypes function taking array addresses), or None when it cannot be had.
    Built on the first call in a machine's life (docs/performance.md), loaded from the cache afterwards."""
    if not _loaded:
        _loaded.append(_load())
    return _loaded[0]
