"""Building the Interaction Graph offline (Shum et al., I3D 2008, section 4):

1. **Sampling.** Many bouts run at once in the bout model with a mixed policy (uniformly
   random actions, and the greedy "attack when in reach" one); every decision (a boxer back
   at the guard) is recorded as a state seen by that boxer.
2. **Merging.** Samples in the same grid cell are one state (the grid steps are the merge
   threshold); a state's continuous features are the mean of its samples. The most visited
   cells (`candidate_factor` x `states`) are candidates.
3. **Edges and selection.** From every candidate, every choosable action is simulated in the
   bout model until the next decision of either boxer. Candidates that some other state's
   edge reaches are preferred (well connected), then the most visited; `states` are kept and
   their edges re-mapped to the nearest kept state. An edge carries the action, the reward,
   the steps it took, the state it ends in and whose turn that is. Expanding every action
   (not only the sampled ones) gives each state its full choice for the dynamic programming.
4. **Dynamic programming** (solve.py) gives one best action per state.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from .bout import ActionTable, BoutRules, Bouts, Rewards, greedy_choice, step
from .lookup import StateIndex
from .solve import solve
from .state import StateGrid, wrap_angle
from .table import GraphTable

# the 13 controllable actions (docs/interaction_graph.md)
CHOOSABLE = ["straight_l", "straight_r", "uppercut_l", "uppercut_r", "hook_l", "hook_r",
             "parry_l", "parry_r", "block", "step_forward", "step_back", "step_left", "step_right"]


@dataclass(frozen=True)
class BuildParams:
    seed: int = 0
    states: int = 60000
    bouts: int = 8192              # sampling bouts run at once
    bout_steps: int = 300          # steps per sampling bout before it restarts
    max_rounds: int = 12           # sampling rounds at most (each: `bouts` x `bout_steps`)
    sample_factor: float = 1.3     # sample until this many x `states` distinct cells exist
    greedy_share: float = 0.35     # share of sampled decisions taken by the greedy policy
    candidate_factor: float = 1.15  # cells expanded before keeping the best connected `states`
    opponent_max: float = 0.5      # 1: min-max; 0: the opponent's expectation (random)


def compile_table(lib: dict, rules: BoutRules) -> ActionTable:
    return ActionTable.from_library(lib, [n for n in CHOOSABLE if n in lib], rules)


def canonical_other(b: Bouts, who: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The other boxer's (action, frame) as a state stores it: READY when it chooses too."""
    t = b.table
    rows = np.arange(b.n)
    oth = 1 - who
    act = b.act[rows, oth].copy()
    frame = b.frame[rows, oth].copy()
    ready = frame >= t.frames[act] - 1
    act[ready] = t.wait
    frame[ready] = t.ready_frame
    return act, np.maximum(frame, 0)


def _new_bouts(t: ActionTable, n: int, rng: np.random.Generator, rules: BoutRules) -> Bouts:
    b = Bouts(t, n)
    b.place(rng.uniform(0.6, 2.2, n), rng.normal(0, 0.3, n), rng.normal(0, 0.3, n))
    b.hp[:] = rules.hp
    return b


def sample_states(t: ActionTable, grid: StateGrid, p: BuildParams, rules: BoutRules,
                  rewards: Rewards, rng: np.random.Generator, log=None):
    """Run sampling bouts; returns per-sample (key, d, bs, bo, act, frame) arrays."""
    cols: list[list[np.ndarray]] = [[] for _ in range(6)]
    seen: set[int] = set()
    total = 0
    rounds = 0
    for rounds in range(1, p.max_rounds + 1):
        b = _new_bouts(t, p.bouts, rng, rules)
        for _ in range(p.bout_steps):
            done = b.done()
            if done.any():
                # both choosing: a random one goes first, the second sees its choice
                first = rng.integers(0, 2, b.n)
                for who in (first, 1 - first):
                    rows = np.flatnonzero(done[np.arange(b.n), who])
                    if not len(rows):
                        continue
                    w = who[rows]
                    d, bs, bo = b.pose(w, rows)
                    act, frame = canonical_other(b, who)
                    act, frame = act[rows], frame[rows]
                    key = grid.key(d, bs, bo, act, frame)
                    for c, v in zip(cols, (key, d, bs, bo, act, frame), strict=True):
                        c.append(v)
                    choice = rng.choice(t.choices, len(rows))
                    greedy = rng.random(len(rows)) < p.greedy_share
                    for side in (0, 1):
                        g_rows = rows[greedy & (w == side)]
                        if len(g_rows):
                            choice[greedy & (w == side)] = greedy_choice(b, side, g_rows, rules)
                    for side in (0, 1):
                        m = w == side
                        if m.any():
                            b.start(rows[m], side, choice[m])
                    done[rows, w] = False
            step(b, rules, rewards)
        new = np.concatenate(cols[0][total:]) if len(cols[0]) > total else np.zeros(0, np.int64)
        total = len(cols[0])
        seen.update(np.unique(new).tolist())
        if log:
            log(f"sampling round {rounds}: {sum(len(k) for k in cols[0])} decisions, {len(seen)} cells")
        if len(seen) >= p.sample_factor * p.states:
            break
    out = [np.concatenate(c) for c in cols]
    return out, rounds


def select_states(samples, grid: StateGrid, n_states: int):
    """Merge samples by cell, keep the most visited cells (ties: smaller key, deterministic)."""
    key, d, bs, bo, act, frame = samples
    uniq, inv, visits = np.unique(key, return_inverse=True, return_counts=True)
    order = np.lexsort((uniq, -visits))[:n_states]
    keep = np.sort(order)                        # state ids follow key order
    cell_to_state = np.full(len(uniq), -1, dtype=np.int64)
    cell_to_state[keep] = np.arange(len(keep))
    sid = cell_to_state[inv]
    m = sid >= 0
    S = len(keep)
    cnt = np.bincount(sid[m], minlength=S).astype(float)
    centre = grid.cell_centres(uniq[keep])
    # mean of the samples, angles averaged as offsets from the cell centre (no wrap issue)
    feat = np.zeros((S, 3))
    feat[:, 0] = np.bincount(sid[m], weights=d[m], minlength=S) / cnt
    for j, ang in ((1, bs), (2, bo)):
        c_ang = centre[sid[m], j] * grid.angle_step - np.pi
        off = wrap_angle(ang[m] - c_ang)
        feat[:, j] = wrap_angle(centre[:, j] * grid.angle_step - np.pi
                                + np.bincount(sid[m], weights=off, minlength=S) / cnt)
    other_frame = np.rint(np.bincount(sid[m], weights=frame[m], minlength=S) / cnt).astype(np.int64)
    other_action = uniq[keep] // (grid.n_angle * grid.n_angle * grid.n_distance) // grid.n_phase
    return uniq[keep], feat, other_action, other_frame, visits[keep]


def expand_edges(t: ActionTable, feat, other_action, other_frame,
                 rules: BoutRules, rewards: Rewards):
    """Every choosable action from every state, simulated to the next decision. Returns per
    edge (grouped by source state, len(choices) each): the ending situation (d, bs, bo,
    other action, other frame), the action, reward, steps and whether it flips the turn."""
    S = len(feat)
    C = len(t.choices)
    E = S * C
    src = np.repeat(np.arange(S), C)
    action = np.tile(t.choices, S)
    b = Bouts(t, E)
    b.place(feat[src, 0], feat[src, 1], feat[src, 2])
    b.set_action(1, other_action[src], other_frame[src])
    b.hp[:] = np.inf
    b.start(np.arange(E), 0, action)
    reward = np.zeros(E)
    steps = np.zeros(E, dtype=np.int64)
    flip = np.zeros(E, dtype=bool)
    res = np.zeros((E, 5))       # d, bs, bo, act, frame of the ending state
    orig = np.arange(E)
    disc = 1.0
    gamma = rewards.discount
    k = 0
    while b.n:
        done = b.done()
        stop = done[:, 0] | done[:, 1]
        if stop.any():
            r = np.flatnonzero(stop)
            who = np.where(done[r, 1], 1, 0)          # the other first when both choose
            sub = b.select(r)
            d, bs, bo = sub.pose(who)
            act, frame = canonical_other(sub, who)
            res[orig[r]] = np.stack([d, bs, bo, act, frame], axis=1)
            flip[orig[r]] = who == 1
            steps[orig[r]] = k
            keep = np.flatnonzero(~stop)
            b = b.select(keep)
            orig = orig[keep]
            if not b.n:
                break
        sr = step(b, rules, rewards)
        reward[orig] += disc * (sr.gain[:, 0] - sr.gain[:, 1])
        disc *= gamma
        k += 1
        if k > 10 * int(t.frames.max()) + 100:
            raise RuntimeError("edge simulation did not reach a decision")
    return res, action, reward, steps, flip


def map_edges(index: StateIndex, res: np.ndarray) -> np.ndarray:
    """The state each edge ends in: the nearest state of its ending situation."""
    return index.nearest_many(res[:, 0], res[:, 1], res[:, 2], res[:, 3].astype(np.int64),
                              res[:, 4].astype(np.int64))


def prefer_connected(keys, visits, dst, C: int, n: int) -> np.ndarray:
    """Indices of the `n` candidates to keep: first those some other state's edge reaches
    (well connected), then by visits (often visited), then by key (deterministic)."""
    src = np.arange(len(dst)) // C
    indeg = np.bincount(dst[dst != src], minlength=len(keys))
    order = np.lexsort((keys, -visits.astype(np.int64), (indeg == 0)))
    return np.sort(order[:n])


def build_graph(lib: dict, params: BuildParams | None = None, rules: BoutRules | None = None,
                rewards: Rewards | None = None, grid: StateGrid | None = None,
                log=None) -> GraphTable:
    """Sample, merge, expand and solve; returns the table ready to save."""
    params = params or BuildParams()
    rules = rules or BoutRules()
    rewards = rewards or Rewards()
    grid = grid or StateGrid()
    t0 = time.perf_counter()
    rng = np.random.default_rng(params.seed)
    t = compile_table(lib, rules)
    samples, rounds = sample_states(t, grid, params, rules, rewards, rng, log)
    t1 = time.perf_counter()
    # candidates: the most visited cells, a few more than wanted
    n_cand = int(math.ceil(params.candidate_factor * params.states))
    keys, feat, oact, oframe, visits = select_states(samples, grid, n_cand)
    res, action, reward, steps, flip = expand_edges(t, feat, oact, oframe, rules, rewards)
    C = len(t.choices)
    dst = map_edges(StateIndex(grid, keys, ready_action=t.wait), res)
    keep = prefer_connected(keys, visits, dst, C, params.states)
    if log:
        log(f"kept {len(keep)} states of {len(keys)} candidates ({len(np.unique(samples[0]))} cells)")
    keys, feat, oact, oframe, visits = keys[keep], feat[keep], oact[keep], oframe[keep], visits[keep]
    rows = (keep[:, None] * C + np.arange(C)[None, :]).ravel()
    res, action, reward, steps, flip = res[rows], action[rows], reward[rows], steps[rows], flip[rows]
    index = StateIndex(grid, keys, ready_action=t.wait)
    dst = map_edges(index, res)
    indptr = np.arange(len(keys) + 1) * C
    t2 = time.perf_counter()
    sol = solve(indptr, dst, reward, rewards.discount ** steps, flip, opponent_max=params.opponent_max)
    t3 = time.perf_counter()
    unreached = int(len(keys) - len(np.unique(dst)))
    info = {
        "library": t.fingerprint(), "seed": params.seed, "states_requested": params.states, "sampling_bouts": params.bouts,
        "bout_steps": params.bout_steps, "sampling_rounds": rounds,
        "samples": int(len(samples[0])), "cells_sampled": int(len(np.unique(samples[0]))),
        "candidates": int(n_cand), "greedy_share": params.greedy_share, "opponent_max": params.opponent_max,
        "states_unreached": unreached, "vi_iterations": sol.iterations,
        "vi_residual": sol.residual,
        "seconds": {"sampling": round(t1 - t0, 2), "edges": round(t2 - t1, 2),
                    "solve": round(t3 - t2, 2), "total": round(t3 - t0, 2)},
    }
    return GraphTable(
        action_names=list(t.names), n_choices=len(t.choices), keys=keys,
        features=feat, other_action=oact, other_frame=oframe,
        visits=visits, best_action=action[sol.best_edge], value=sol.value.astype(np.float32),
        edge_ptr=indptr, edge_dst=dst, edge_action=action, edge_steps=steps,
        edge_flip=flip, edge_reward=reward.astype(np.float32),
        fill_keys=index.fill_keys, fill_state=index.fill_state,
        grid=grid, rules=rules, rewards=rewards, build=info)
