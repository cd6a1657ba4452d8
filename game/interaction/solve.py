"""Value iteration over the Interaction Graph, vectorized over all edges.

States are seen by the boxer about to choose (see state.py), so one graph serves both boxers.
An edge (s, a) carries the chooser's reward r (its gain minus the other's), the discount
gamma**steps of the steps it lasts, the state s' it ends in and whether s' is seen by the
same boxer (flip=False: the chooser is back at the guard first) or by the other (flip=True).

Two value functions: V (our boxer chooses: the max over its edges) and U (the other chooses,
from the other's point of view: its best response, the max, for min-max; or its expectation,
the mean, when modelling a random opponent; `opponent_max` blends the two):

    Q_V(s, a) = r + g * ( V(s') if not flip else -U(s') )
    Q_U(s, a) = r + g * ( U(s') if not flip else -V(s') )
    V(s) = max_a Q_V(s, a)
    U(s) = w * max_a Q_U(s, a) + (1 - w) * mean_a Q_U(s, a)

With w = 1 this is min-max (V == U, a zero-sum game of alternating turns).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class Solution:
    value: np.ndarray        # (S,) V
    other_value: np.ndarray  # (S,) U
    best_edge: np.ndarray    # (S,) index into the edge arrays of the best action
    iterations: int
    residual: float


def solve(indptr: np.ndarray, dst: np.ndarray, reward: np.ndarray, discount: np.ndarray,
          flip: np.ndarray, opponent_max: float = 1.0, tol: float = 1e-4,
          max_iter: int = 2000) -> Solution:
    """Value iteration; every state needs at least one edge (edges grouped by source)."""
    indptr = np.asarray(indptr, dtype=np.int64)
    S = len(indptr) - 1
    counts = np.diff(indptr)
    if S == 0:
        raise ValueError("empty graph")
    if (counts <= 0).any():
        raise ValueError("every state needs at least one outgoing edge")
    starts = indptr[:-1]
    src = np.repeat(np.arange(S), counts)
    reward = np.asarray(reward, dtype=np.float64)
    discount = np.asarray(discount, dtype=np.float64)
    flip = np.asarray(flip, dtype=bool)
    dst = np.asarray(dst, dtype=np.int64)
    V = np.zeros(S)
    U = np.zeros(S)
    w = float(opponent_max)
    residual = np.inf
    it = 0
    while it < max_iter:
        it += 1
        Vd, Ud = V[dst], U[dst]
        qv = reward + discount * np.where(flip, -Ud, Vd)
        qu = reward + discount * np.where(flip, -Vd, Ud)
        V_new = np.maximum.reduceat(qv, starts)
        if w >= 1.0:
            U_new = np.maximum.reduceat(qu, starts)
        else:
            U_new = w * np.maximum.reduceat(qu, starts) + (1 - w) * np.add.reduceat(qu, starts) / counts
        residual = float(max(np.abs(V_new - V).max(), np.abs(U_new - U).max()))
        V, U = V_new, U_new
        if residual < tol:
            break
    qv = reward + discount * np.where(flip, -U[dst], V[dst])
    # the first edge of each state reaching its max (ties go to the earlier action)
    is_best = qv >= np.maximum.reduceat(qv, starts)[src]
    first = np.flatnonzero(is_best)
    _, pos = np.unique(src[first], return_index=True)
    best_edge = first[pos]
    return Solution(value=V, other_value=U, best_edge=best_edge, iterations=it, residual=residual)
