"""Distance constraints: signs (stretched pulls together, compressed pushes apart), mass
weighting, inequality limits, and convergence of both vectorized solvers."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from engine.physics import World
from engine.physics.constraints import DistanceConstraints, edge_colouring
from tests.engine.physics.humanoid import (
    GUARD,
    LIMIT_PAIRS,
    MASSES,
    STICKS,
    add_humanoid,
    limit_ranges,
)

SOLVERS = ["jacobi", "gauss_seidel"]


def _pair(solver: str, lo: float, hi: float, masses=(1.0, 1.0)) -> DistanceConstraints:
    return DistanceConstraints(np.array([[0, 1]]), np.array([lo]), np.array([hi]),
                               1.0 / np.asarray(masses), solver)


@pytest.mark.parametrize("solver", SOLVERS)
def test_stretched_stick_pulls_its_ends_together(solver):
    c = _pair(solver, 1.0, 1.0)
    x = np.array([[0.0, 0.0, 0.0], [1.5, 0.0, 0.0]])
    before = x.copy()
    c.relax(x)
    assert x[0, 0] > before[0, 0]  # left end moved right, towards the other
    assert x[1, 0] < before[1, 0]  # right end moved left
    assert np.linalg.norm(x[1] - x[0]) < 1.5


@pytest.mark.parametrize("solver", SOLVERS)
def test_compressed_stick_pushes_its_ends_apart(solver):
    c = _pair(solver, 1.0, 1.0)
    x = np.array([[0.0, 0.0, 0.0], [0.0, 0.6, 0.0]])
    c.relax(x)
    assert x[0, 1] < 0.0 and x[1, 1] > 0.6
    assert np.linalg.norm(x[1] - x[0]) > 0.6


def test_gauss_seidel_restores_a_lone_stick_exactly_and_heavier_end_moves_less():
    c = _pair("gauss_seidel", 1.0, 1.0, masses=(4.0, 1.0))
    x = np.array([[0.0, 0.0, 0.0], [2.0, 0.0, 0.0]])
    c.relax(x)
    assert np.linalg.norm(x[1] - x[0]) == pytest.approx(1.0)
    moved0, moved1 = abs(x[0, 0]), abs(x[1, 0] - 2.0)
    assert moved0 == pytest.approx(0.2) and moved1 == pytest.approx(0.8)  # split 1:4 by inverse mass
    # the centre of mass did not move
    assert (4.0 * x[0, 0] + 1.0 * x[1, 0]) / 5.0 == pytest.approx(2.0 / 5.0)


@pytest.mark.parametrize("solver", SOLVERS)
def test_limit_acts_only_outside_its_range(solver):
    c = _pair(solver, 0.5, 1.0)
    inside = np.array([[0.0, 0.0, 0.0], [0.8, 0.0, 0.0]])
    x = inside.copy()
    c.relax(x)
    np.testing.assert_array_equal(x, inside)
    too_close = np.array([[0.0, 0.0, 0.0], [0.2, 0.0, 0.0]])
    c.relax(too_close)
    assert too_close[1, 0] - too_close[0, 0] > 0.2
    too_far = np.array([[0.0, 0.0, 0.0], [1.6, 0.0, 0.0]])
    c.relax(too_far)
    assert too_far[1, 0] - too_far[0, 0] < 1.6


def _humanoid_constraints(solver: str) -> DistanceConstraints:
    rest = np.linalg.norm(GUARD[STICKS[:, 1]] - GUARD[STICKS[:, 0]], axis=1)
    rng = limit_ranges()
    return DistanceConstraints(np.concatenate([STICKS, LIMIT_PAIRS]), np.concatenate([rest, rng[:, 0]]),
                               np.concatenate([rest, rng[:, 1]]), 1.0 / MASSES, solver)


@pytest.mark.parametrize("solver", SOLVERS)
def test_relaxation_converges_on_the_humanoid(solver):
    c = _humanoid_constraints(solver)
    x = GUARD + np.random.default_rng(1).normal(0.0, 0.03, GUARD.shape)
    start = c.errors(x).max()
    errs = []
    for _ in range(60):
        c.relax(x)
        errs.append(c.errors(x).max())
    assert errs[3] < 0.8 * start
    assert errs[-1] < 0.05 * start  # 60 iterations: a 3 cm scramble back within 1.5 mm
    assert np.sqrt(np.mean(c.errors(x) ** 2)) < 0.01 * start


def test_relaxation_conserves_momentum():
    """Mass-weighted corrections with the same scale at both ends: the centre of mass stays."""
    for solver in SOLVERS:
        c = _humanoid_constraints(solver)
        x = GUARD + np.random.default_rng(2).normal(0.0, 0.05, GUARD.shape)
        com = MASSES @ x / MASSES.sum()
        for _ in range(10):
            c.relax(x)
        np.testing.assert_allclose(MASSES @ x / MASSES.sum(), com, atol=1e-12)


def test_edge_colouring_is_proper():
    colours = edge_colouring(STICKS)
    for col in np.unique(colours):
        ends = STICKS[colours == col].ravel()
        assert len(ends) == len(np.unique(ends))  # no particle twice in one batch
    degree = np.bincount(STICKS.ravel()).max()
    assert colours.max() + 1 <= 2 * degree - 1  # greedy bound


@pytest.mark.parametrize("solver", SOLVERS)
def test_body_at_rest_under_gravity_keeps_its_bones(solver):
    w = World(iterations=4, solver=solver)
    bid = add_humanoid(w)
    w.set_targets(bid, GUARD, 5.0)
    for _ in range(120):
        w.step(1 / 60)
    rest = w.bodies[bid].rest_lengths
    x = w.x[w.bodies[bid].slice]
    lengths = np.linalg.norm(x[STICKS[:, 1]] - x[STICKS[:, 0]], axis=1)
    assert np.max(np.abs(lengths - rest) / rest) < 0.02
    assert np.abs(x - GUARD).max() < 0.05  # gravity sag only

_coord = st.floats(-2.0, 2.0, allow_nan=False)


@settings(max_examples=200, deadline=None)
@given(a=st.tuples(_coord, _coord, _coord), b=st.tuples(_coord, _coord, _coord),
       m=st.tuples(st.floats(0.1, 20.0), st.floats(0.1, 20.0)), rest=st.floats(0.05, 3.0),
       solver=st.sampled_from(SOLVERS))
def test_any_stick_moves_its_ends_the_right_way(a, b, m, rest, solver):
    x = np.array([a, b], dtype=float)
    length = np.linalg.norm(x[1] - x[0])
    if length < 1e-3 or abs(length - rest) < 1e-6:
        return
    c = _pair(solver, rest, rest, masses=m)
    new = x.copy()
    c.relax(new)
    towards = x[1] - x[0]  # from end 0 to end 1
    moved0, moved1 = new[0] - x[0], new[1] - x[1]
    sign = 1.0 if length > rest else -1.0  # stretched: together; compressed: apart
    assert sign * (moved0 @ towards) >= -1e-12
    assert sign * (moved1 @ -towards) >= -1e-12
    assert abs(np.linalg.norm(new[1] - new[0]) - rest) < abs(length - rest)
    # the centre of mass stays where it was
    np.testing.assert_allclose(m[0] * new[0] + m[1] * new[1], m[0] * x[0] + m[1] * x[1], atol=1e-9)


def test_the_c_projection_is_numpys_bit_for_bit():
    """engine/native.py's stick projection does numpy's operations in numpy's order: the
    same positions after many iterations, stretched, compressed and in-range sticks mixed."""
    from engine.physics import constraints

    if constraints.project_kernel() is None:
        pytest.skip("no C compiler here (numpy runs)")
    rng = np.random.default_rng(4)
    n = 34
    pairs = np.array([(i, j) for i in range(n) for j in range(i + 1, n) if rng.random() < 0.08])
    rest = rng.uniform(0.05, 0.6, len(pairs))
    lo, hi = rest * rng.choice([1.0, 0.7], len(pairs)), rest * rng.choice([1.0, 1.3], len(pairs))
    inv_mass = rng.uniform(0.2, 3.0, n)
    c = constraints.DistanceConstraints(pairs, lo, hi, inv_mass)
    assert all(b.kernel is not None for b in c.batches)
    x0 = rng.normal(0.0, 0.5, (n, 3))
    a, b = x0.copy(), x0.copy()
    for _ in range(50):
        for batch in c.batches:
            batch.project(a)
            batch.project_numpy(b)
    assert np.array_equal(a, b) and not np.array_equal(a, x0)
