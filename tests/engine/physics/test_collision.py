"""Capsule collision: closest points between segments, contacts with closing speed and
direction, and no interpenetration when two bodies walk into each other."""

from __future__ import annotations

import numpy as np
import pytest

from engine.physics import Contact, World
from engine.physics.collision import closest_params, segment_distance
from tests.engine.physics.humanoid import GUARD, STICKS, J, add_humanoid, place

DT = 1 / 60


def _brute_distance(p1, q1, p2, q2, n=401):
    u = np.linspace(0.0, 1.0, n)
    a = p1 + u[:, None] * (q1 - p1)
    b = p2 + u[:, None] * (q2 - p2)
    return np.sqrt(((a[:, None, :] - b[None, :, :]) ** 2).sum(-1)).min()


def test_segment_distance_matches_brute_force():
    rng = np.random.default_rng(0)
    p1, q1, p2, q2 = (rng.normal(size=(200, 3)) for _ in range(4))
    # special cases: parallel, collinear overlapping, a point, two points, crossing
    p1[0], q1[0], p2[0], q2[0] = (0, 0, 0), (1, 0, 0), (0.5, 1, 0), (2, 1, 0)
    p1[1], q1[1], p2[1], q2[1] = (0, 0, 0), (1, 0, 0), (0.5, 0, 0), (2, 0, 0)
    p1[2], q1[2], p2[2], q2[2] = (0, 0, 0), (1, 0, 0), (0.5, 0.3, 0), (0.5, 0.3, 0)
    p1[3], q1[3], p2[3], q2[3] = (0, 0, 0), (0, 0, 0), (0.5, 0.3, 0), (0.5, 0.3, 0)
    p1[4], q1[4], p2[4], q2[4] = (-1, 0, 0), (1, 0, 0), (0, -1, 0.2), (0, 1, 0.2)
    p1[5], q1[5], p2[5], q2[5] = (0, 0, 0), (0, 0, 0), (-1, 1, 0), (1, 1, 0)
    d = segment_distance(p1, q1, p2, q2)
    brute = np.array([_brute_distance(*(v[k] for v in (p1, q1, p2, q2))) for k in range(200)])
    assert np.all(d <= brute + 1e-12)  # never further than a sampled pair
    np.testing.assert_allclose(d, brute, atol=2e-3)
    s, t = closest_params(p1, q1, p2, q2)
    assert s.min() >= 0 and s.max() <= 1 and t.min() >= 0 and t.max() <= 1
    assert d[4] == pytest.approx(0.2) and d[3] == pytest.approx(np.hypot(0.5, 0.3))


def _ball(world: World, x, tag: str, radius: float = 0.2, mass: float = 1.0) -> int:
    return world.add_body([x], [mass], np.zeros((0, 2)), [[0, 0]], [radius], [tag])


def test_contact_reports_closing_speed_direction_and_tags():
    w = World(gravity=(0, 0, 0), ground_y=-10.0, damping=0.0)
    a = _ball(w, (-0.5, 1.0, 0.0), "fist_r")
    b = _ball(w, (0.5, 1.0, 0.0), "head")
    # velocities through the Verlet state: a at +2 m/s, b at -1 m/s along x
    w.x_prev[0] = w.x[0] - (2.0 * DT, 0.0, 0.0)
    w.x_prev[1] = w.x[1] - (-1.0 * DT, 0.0, 0.0)
    first = None
    for _ in range(30):
        contacts = w.step(DT)
        gap = np.linalg.norm(w.x[1] - w.x[0]) - 0.4
        assert gap >= -1e-9  # resolved within the step: never interpenetrating
        if contacts and first is None:
            first = contacts
    assert first is not None and len(first) == 1
    c = first[0]
    assert isinstance(c, Contact)
    assert (c.body_a, c.capsule_a, c.tag_a, c.body_b, c.capsule_b, c.tag_b) == (a, 0, "fist_r", b, 0, "head")
    assert c.rel_speed == pytest.approx(3.0, rel=1e-6)
    np.testing.assert_allclose(c.normal, (1.0, 0.0, 0.0), atol=1e-9)
    assert c.depth > 0
    assert -0.3 < c.point[0] < 0.3 and c.point[1] == pytest.approx(1.0)


def test_separating_contact_has_negative_closing_speed():
    w = World(gravity=(0, 0, 0), ground_y=-10.0, damping=0.0)
    _ball(w, (0.0, 1.0, 0.0), "a")
    _ball(w, (0.0, 1.3, 0.0), "b")  # overlapping by 0.1, b moving up and away
    w.x_prev[1] = w.x[1] - (0.0, 0.5 * DT, 0.0)
    (c,) = w.step(DT)
    np.testing.assert_allclose(c.normal, (0.0, 1.0, 0.0), atol=1e-9)
    assert c.rel_speed == pytest.approx(-0.5, rel=1e-6)


def test_fist_hitting_a_capsule_side_reports_the_capsule_normal():
    w = World(gravity=(0, 0, 0), ground_y=-10.0, damping=0.0)
    # a long vertical "torso" capsule, heavy, and a fist coming at it along -z
    torso = w.add_body([[0.0, 1.0, 0.0], [0.0, 1.6, 0.0]], [30.0, 30.0], [[0, 1]], [[0, 1]], [0.15], ["torso"])
    fist = _ball(w, (0.0, 1.3, 0.5), "fist_l", radius=0.06)
    w.x_prev[2] = w.x[2] - (0.0, 0.0, -6.0 * DT)
    hits = []
    for _ in range(20):
        hits += [c for c in w.step(DT) if c.tag_b == "fist_l"]
    c = hits[0]
    assert (c.body_a, c.tag_a, c.body_b) == (torso, "torso", fist)
    np.testing.assert_allclose(c.normal, (0.0, 0.0, 1.0), atol=1e-6)  # torso -> fist
    assert c.rel_speed == pytest.approx(6.0, rel=0.01)
    # momentum: the light fist bounced off, the heavy torso barely moved
    assert abs(w.x[0:2, 2].mean()) < 0.05


@pytest.mark.parametrize(("solver", "iterations"), [("jacobi", 2), ("jacobi", 4), ("gauss_seidel", 4)])
def test_no_interpenetration_when_two_bodies_walk_into_each_other(solver, iterations):
    """Two humanoids whose reference postures walk into each other (their roots would end
    10 cm apart, the torsos 20 cm inside each other) at 0.6 m/s with a firm 5 Hz pull."""
    w = World(iterations=iterations, solver=solver)
    a = add_humanoid(w, 0.0, -1.0, 0.0)
    b = add_humanoid(w, 0.05, 1.0, np.pi)  # slightly off-centre, as in a real clinch
    p = w.pairs
    worst = np.inf
    n_contacts = 0
    for i in range(240):
        z = min(-1.0 + 0.6 * i * DT, -0.05)
        w.set_targets(a, place(GUARD, 0.0, z, 0.0), 5.0)
        w.set_targets(b, place(GUARD, 0.05, -z, np.pi), 5.0)
        n_contacts += len(w.step(DT))
        x = w.x
        gap = segment_distance(x[p.ia], x[p.ja], x[p.ib], x[p.jb]) - p.rsum
        worst = min(worst, gap.min())
    assert n_contacts > 50  # they did meet, for many steps
    assert worst >= -0.01  # never more than 1 cm inside each other
    # and they stand chest to chest, not through each other: the chests (torso radius 0.15)
    # are held about 30 cm apart although their targets are 10 cm apart
    chest_a = w.x[w.bodies[a].slice][J["chest"]]
    chest_b = w.x[w.bodies[b].slice][J["chest"]]
    assert chest_b[2] - chest_a[2] > 0.25


def test_straight_to_the_head_is_reported_with_its_speed():
    """A's right fist driven at B's head (a straight; B's guard dropped) gives a fist_r/head
    contact, closing at punch speed along +z (A faces +z), and the head is pushed, not
    entered."""
    w = World()
    a = add_humanoid(w, 0.0, -0.3, 0.0)
    b = add_humanoid(w, 0.0, 0.3, np.pi)
    dropped = GUARD.copy()
    for j in ("fist_l", "fist_r", "elbow_l", "elbow_r"):
        dropped[J[j]] += (0.0, -0.3, -0.1)
    pose_b = place(dropped, 0.0, 0.3, np.pi)
    for _ in range(30):
        w.set_targets(a, place(GUARD, 0.0, -0.3, 0.0), 8.0)
        w.set_targets(b, pose_b, 8.0)
        w.step(DT)
    head_b = w.x[w.bodies[b].slice][J["head"]].copy()
    guard_a = place(GUARD, 0.0, -0.3, 0.0)
    shoulder = guard_a[J["shoulder_r"]]
    aim = (head_b - shoulder) / np.linalg.norm(head_b - shoulder)
    hits = []
    stretch = 0.0
    for i in range(20):
        # the arm's targets swing from the guard to straight at B's head in 6 frames
        u = min(i / 6.0, 1.0)
        pose = guard_a.copy()
        pose[J["elbow_r"]] = (1 - u) * guard_a[J["elbow_r"]] + u * (shoulder + 0.3 * aim)
        pose[J["fist_r"]] = (1 - u) * guard_a[J["fist_r"]] + u * (shoulder + 0.62 * aim)
        w.set_targets(a, pose, 8.0)
        w.set_targets(b, pose_b, 8.0)
        hits += [c for c in w.step(DT) if c.tag_a == "fist_r" and c.tag_b == "head"]
        xa = w.x[w.bodies[a].slice]
        lengths = np.linalg.norm(xa[STICKS[:, 1]] - xa[STICKS[:, 0]], axis=1)
        stretch = max(stretch, np.max(np.abs(lengths / w.bodies[a].rest_lengths - 1.0)))
    assert hits, "the straight never touched the head"
    # the arm is pulled 3 cm past its reach into a head that stops it: bones give a little
    assert stretch < 0.08
    first = hits[0]
    assert (first.body_a, first.body_b) == (a, b)
    assert first.rel_speed > 2.0  # m/s: a punch, not a brush
    assert first.normal[2] > 0.6 and first.normal @ aim > 0.8  # from A's fist into B's head
    x = w.x
    p = w.pairs
    assert (segment_distance(x[p.ia], x[p.ja], x[p.ib], x[p.jb]) - p.rsum).min() > -0.01
    assert w.x[w.bodies[b].slice][J["head"], 2] > head_b[2] + 0.01  # the head was knocked back


def test_one_step_separates_random_overlapping_capsules():
    rng = np.random.default_rng(3)
    for _ in range(50):
        w = World(gravity=(0, 0, 0), ground_y=-10.0, damping=0.0)
        for _ in range(2):
            p = rng.normal(0.0, 0.15, (2, 3))
            w.add_body(p, rng.uniform(0.5, 5.0, 2), [[0, 1]], [[0, 1]], [rng.uniform(0.05, 0.2)], ["c"])
        pairs = w.pairs
        x = w.x
        before = segment_distance(x[pairs.ia], x[pairs.ja], x[pairs.ib], x[pairs.jb]) - pairs.rsum
        contacts = w.step(DT)
        after = segment_distance(x[pairs.ia], x[pairs.ja], x[pairs.ib], x[pairs.jb]) - pairs.rsum
        assert len(contacts) == int(before[0] < 0)
        assert after[0] >= -0.002


def test_fast_fist_that_passes_the_head_centre_in_one_step_is_turned_back():
    """At 15 m/s a fist moves 25 cm a step: from just outside the head to past its centre.
    The contact still points from the fist into the head, closing, and the fist ends on the
    side it came from."""
    w = World(gravity=(0, 0, 0), ground_y=-10.0, damping=0.0, max_speed=20.0)
    head = _ball(w, (0.0, 1.6, 0.0), "head", radius=0.11, mass=5.0)
    fist = _ball(w, (0.0, 1.6, -1.0), "fist_r", radius=0.06, mass=1.0)
    assert w.step(DT) == []  # a step apart: the world has seen them not touching
    w.x[1] = (0.0, 1.6, -0.18)  # 1 cm outside the head
    w.x_prev[1] = w.x[1] - (0.0, 0.0, 15.0 * DT)  # moving +z at 15 m/s: next at z = +0.07
    (c,) = w.step(DT)
    assert (c.body_a, c.tag_a, c.body_b, c.tag_b) == (head, "head", fist, "fist_r")
    np.testing.assert_allclose(c.normal, (0.0, 0.0, -1.0), atol=1e-9)  # head -> fist: back along -z
    assert c.rel_speed == pytest.approx(15.0, rel=1e-6)
    assert w.x[1, 2] < w.x[0, 2] - 0.17 + 0.002  # the fist is in front of the head, not behind it


def test_a_lasting_touch_is_new_only_on_its_first_step():
    w = World(gravity=(0, 0, 0), ground_y=-10.0, damping=0.0)
    _ball(w, (0.0, 1.0, 0.0), "a", mass=1e6)  # a wall
    _ball(w, (0.6, 1.0, 0.0), "b")
    w.step(DT)
    flags = []
    for i in range(40):
        # b pressed against a for 20 steps, then pulled away, then pressed again
        w.set_targets(1, [[0.2 if (i < 20 or i >= 30) else 0.8, 1.0, 0.0]], 6.0)
        flags += [c.new for c in w.step(DT)]
    assert flags.count(True) == 2 and len(flags) > 10  # two touches, each new once
    assert flags[0] is True and flags[1] is False


def test_fast_fist_from_close_range_is_turned_back_too():
    """The same from 3 cm away (already within the contact margin, a jab from a clinch)."""
    w = World(gravity=(0, 0, 0), ground_y=-10.0, damping=0.0, max_speed=20.0)
    _ball(w, (0.0, 1.6, 0.0), "head", radius=0.11, mass=5.0)
    _ball(w, (0.0, 1.6, -0.20), "fist_r", radius=0.06, mass=1.0)  # 3 cm outside the head
    assert w.step(DT) == []
    w.x_prev[1] = w.x[1] - (0.0, 0.0, 15.0 * DT)  # next at z = +0.05, past the centre
    (c,) = w.step(DT)
    np.testing.assert_allclose(c.normal, (0.0, 0.0, -1.0), atol=1e-9)
    assert c.rel_speed == pytest.approx(15.0, rel=1e-6)
    assert w.x[1, 2] < w.x[0, 2] - 0.17 + 0.002


def test_the_c_narrow_phase_and_contact_projection_are_numpys_bit_for_bit():
    """engine/physics/collision.py's C kernels follow the numpy code operation for operation:
    random capsule pairs (crossing, parallel, point-like) give the same broad-phase candidates,
    the same s, t, normals, depths,
    and projecting their contact set moves the particles to the same bits."""
    from engine.physics import collision

    if collision.kernels() is None:
        pytest.skip("no C compiler here (numpy runs)")
    rng = np.random.default_rng(9)
    n = 40
    caps = rng.integers(0, n, (24, 2))
    caps[:4, 1] = caps[:4, 0]  # spheres
    radii = rng.uniform(0.02, 0.3, len(caps))
    body = np.repeat([0, 1], len(caps) // 2)
    ca, cb = np.meshgrid(np.arange(len(caps)), np.arange(len(caps)), indexing="ij")
    keep = body[ca.ravel()] < body[cb.ravel()]
    inv_mass = rng.uniform(0.3, 2.0, n)
    pairs = collision.CapsulePairs(ca.ravel()[keep], cb.ravel()[keep], caps, radii, inv_mass, n)
    for trial in range(20):
        x = rng.normal(0.0, 0.4, (n, 3))
        if trial % 4 == 0:
            x[caps[5, 1]] = x[caps[5, 0]] + (x[caps[17, 1]] - x[caps[17, 0]])  # parallel segments
        for margin in (0.0, 0.05, 0.3):
            assert np.array_equal(pairs.candidates(x, margin), pairs.candidates_numpy(x, margin))
        idx = rng.choice(len(pairs), 30, replace=False)
        c_out, np_out = pairs.narrow(x, idx), pairs.narrow_numpy(x, idx)
        for a, b in zip(c_out, np_out, strict=True):
            assert np.array_equal(a, b)
        s, t, normal, _ = c_out
        cset = pairs.contact_set(idx, s, t, normal)
        assert cset._c is not None
        a, b = x.copy(), x.copy()
        for _ in range(3):
            cset.project(a)
            cset.project_numpy(b)
        assert np.array_equal(a, b) and not np.array_equal(a, x)
