"""IncrementalDTW's "loop" method: the C kernel's arithmetic (dtw_native.py, dtw_kernel.py), operation
for operation, in numpy, so that its scores are the "native" and "jit" scores bit for bit.

Why: `method="auto"` runs the C kernel where it can be built and numpy where it cannot (no
compiler, a failed or raced build, QUICKJAB_NO_NATIVE=1). The "scan" method sums in another order
and takes its local costs as |t|^2 - 2 t.q + |q|^2, which cancels where a frame nearly equals a
template frame (a hand at rest): its scores differed from the kernel's by up to 1.4e-9 (2e-7
relative) in the scripted match, and a recognizer deciding on near-ties would then decide
differently depending on whether a compiler was there. This method follows the kernel:
- local costs: per template position, sum over d of (t_d - q_d)^2 in d order from 0, then sqrt;
- best = min(D[i-1, j] + c, D[i-1, j-1] + 2c), then along the row D[i, j] = min(best, D[i, j-1] + c),
  position by position (a vectorized step across templates each);
- the scores: the row times 1 / (j + 1 + n), the minimum over the positions min_progress allows.
min is exact and +, *, / and sqrt are correctly rounded, so the same operations on the same values
give the same bits, whatever SIMD path numpy or the compiler takes (frames are finite: the
recognizer drops a non-finite one).
"""

from __future__ import annotations

import numpy as np


def loop_buffers(tmpl: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """What `loop_row` reuses, from the (L, T, D) padded templates: the templates as (D, L, T)
    (one dimension's values contiguous), a scratch of that shape, and (L, T) costs and bests."""
    dlt = np.ascontiguousarray(tmpl.transpose(2, 0, 1))
    L, T = tmpl.shape[:2]
    return dlt, np.empty_like(dlt), np.empty((L, T)), np.empty((L, T))


def loop_row(bufs: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray], q: np.ndarray,
             prev_diag: np.ndarray, prev_up: np.ndarray, row: np.ndarray) -> None:
    """The next accumulated-cost row into `row` (L, T) from the previous one's (L, T) views
    `prev_diag` (D[i-1, j-1]) and `prev_up` (D[i-1, j]), for query frame q (D,)."""
    dlt, sq, c, best = bufs
    np.subtract(dlt, q[:, None, None], out=sq)
    np.multiply(sq, sq, out=sq)
    c[:] = sq[0]  # the kernel's 0.0 + sq[0]: the same value
    for d in range(1, len(sq)):
        np.add(c, sq[d], out=c)
    np.sqrt(c, out=c)
    np.multiply(c, 2.0, out=best)
    np.add(prev_diag, best, out=best)
    np.add(prev_up, c, out=row)  # the row as scratch: up + c
    np.minimum(row, best, out=best)
    row[0] = best[0]  # D[i, -1] is the +inf sentinel
    for j in range(1, len(row)):
        np.add(row[j - 1], c[j], out=row[j])
        np.minimum(best[j], row[j], out=row[j])
