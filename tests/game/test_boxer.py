"""Boxers in the physics world: following the reference, root motion, collisions and hits."""

from __future__ import annotations

import math

import numpy as np
import pytest

from engine.physics import World
from game.actions import load_library
from game.boxer import Boxer, hits_from_contacts
from game.skeleton import joint_index

LIB = load_library()
DT = 1 / 60


def ring(gap: float):
    w = World()
    a = Boxer(w, LIB, x=0.0, z=-gap / 2, yaw=0.0)
    b = Boxer(w, LIB, x=0.0, z=gap / 2, yaw=math.pi)
    return w, a, b


def run(w, a, b, steps: int) -> list[dict]:
    hits = []
    for _ in range(steps):
        a.step(DT)
        b.step(DT)
        hits += hits_from_contacts(w.step(DT), [a, b])
    return hits


def test_the_body_follows_the_guard_and_stands():
    w, a, b = ring(1.0)
    assert run(w, a, b, 60) == []  # two guards a metre apart do not touch
    err = np.abs(a.joint_positions() - a.reference).max()
    assert err < 0.05
    assert a.joint_positions()[joint_index("head"), 1] > 1.4


@pytest.mark.parametrize("punch", ["straight_r", "straight_l"])
def test_a_straight_that_reaches_the_head_reports_one_hit_with_its_speed(punch):
    w, a, b = ring(0.85)
    run(w, a, b, 20)
    a.controller.play(punch)
    hits = run(w, a, b, 40)
    assert len(hits) == 1
    h = hits[0]
    assert h["attacker"] == 0 and h["target"] == "head" and h["hand"] == punch[-1]
    assert h["speed"] > 1.0 and not h["blocked"]
    assert h["direction"][2] > 0.5  # travelling from A (at -z) towards B (at +z)
    # B's head was actually knocked: it moved away from A
    assert b.joint_positions()[joint_index("head"), 2] > b.reference[joint_index("head"), 2] - 0.5


def test_no_hit_outside_the_attack_window_or_out_of_reach():
    w, a, b = ring(1.3)
    run(w, a, b, 10)
    a.controller.play("straight_r")
    assert run(w, a, b, 40) == []
    w, a, b = ring(0.85)
    run(w, a, b, 10)
    a.controller.play("parry_r")  # a hand moves but it is no punch
    assert run(w, a, b, 30) == []


def test_a_blocking_opponent_turns_the_hit_into_a_blocked_one():
    w, a, b = ring(0.85)
    run(w, a, b, 10)
    b.controller.play("block")
    run(w, a, b, 4)
    a.controller.play("straight_r")
    hits = run(w, a, b, 30)
    assert hits and all(h["blocked"] for h in hits)


def test_reaction_follows_a_hit():
    w, a, b = ring(0.85)
    run(w, a, b, 10)
    a.controller.play("straight_l")
    hits = run(w, a, b, 30)
    name = b.react(hits[0])
    assert name.startswith("hit_head_front") and b.controller.action == name


def test_step_forward_moves_the_root_and_walking_into_each_other_does_not_interpenetrate():
    w, a, b = ring(1.2)
    a.controller.play("step_forward")
    run(w, a, b, LIB["step_forward"].frames + 5)
    assert a.root[1] == pytest.approx(-0.6 + 0.3, abs=0.03)
    # both keep stepping in: the torsos meet, are held apart, and the roots give way
    for _ in range(6):
        a.controller.play("step_forward")
        b.controller.play("step_forward")
        for _ in range(LIB["step_forward"].frames):
            a.step(DT)
            b.step(DT)
            w.step(DT)
            pa, pb = a.joint_positions(), b.joint_positions()
            chest = joint_index("chest")
            d = np.linalg.norm((pa[chest] - pb[chest])[[0, 2]])
            assert d > 0.15 + 0.15 - 0.01  # torso capsules (r = 0.15) never overlap
    # the roots gave way instead of driving the references through the other boxer
    assert b.root[1] > a.root[1]
    for boxer in (a, b):
        assert np.linalg.norm((boxer.joint_positions()[0] - boxer.reference[0])[[0, 2]]) < 0.15


@pytest.mark.parametrize(("a_name", "b_name"), [("straight_r", "hook_r"), ("straight_l", "hook_l")])
def test_switching_at_n_p_is_smoother_on_the_simulated_body(a_name, b_name):
    """Fig. 4 measured on the particle body, not only on the reference postures."""
    n_p = 8
    peaks = {}
    for from_frame in (n_p, 0):
        w = World()
        boxer = Boxer(w, LIB, z=0.0)
        for _ in range(20):
            boxer.step(DT)
            w.step(DT)
        boxer.controller.play(a_name)
        xs = []
        for i in range(n_p + 20):
            if i == n_p:
                boxer.controller.on_event({"event": "switch", "action": b_name, "from_frame": from_frame})
            boxer.step(DT)
            w.step(DT)
            xs.append(boxer.joint_positions().copy())
        speed = np.linalg.norm(np.diff(np.array(xs), axis=0), axis=-1) * 60.0
        peaks[from_frame] = speed[n_p - 1 :].max()
    assert peaks[n_p] < peaks[0]


def test_a_switch_during_a_landed_punch_does_not_land_it_again():
    """A switch is the recognizer's better label for the motion under way, not a new punch: with
    the fist still on the head, each switch (straight_r <-> hook_r, both in their attack window
    at from_frame 10) cleared the spent hand and landed the same swing again, a blow a step; a
    new start still lands."""
    w, a, b = ring(0.85)
    run(w, a, b, 20)
    a.controller.on_event({"event": "start", "action": "straight_r"})
    hits = []
    while not hits and a.controller.action == "straight_r":
        hits += run(w, a, b, 1)
    assert len(hits) == 1
    for i in range(10):
        a.controller.on_event({"event": "switch", "action": ("hook_r", "straight_r")[i % 2], "from_frame": 10})
        hits += run(w, a, b, 1)
    assert len(hits) == 1
    run(w, a, b, 60)
    a.controller.on_event({"event": "start", "action": "straight_r"})
    assert len(run(w, a, b, 40)) == 1


def test_keep_inside_holds_the_root_on_plain_floats_to_the_same_bits(monkeypatch):
    # four times a 60 Hz step: np.clip on a Python float cost ~2 us each (a small board: ~10x)
    w, a, _ = ring(1.0)
    limit = 2.4
    cases = [0.3, -0.0, 0.0, 2.4, -2.4, 7.5, -7.5, math.inf, -math.inf, math.nan, 5e-324, np.float64(3.1)]
    expected = [(float(np.clip(v, -limit, limit)), float(np.clip(-v, -limit, limit))) for v in cases]

    def no_numpy(*args, **kwargs):
        raise AssertionError("np.clip on the 60 Hz path")

    def same(x: float, y: float) -> bool:
        return (math.isnan(x) and math.isnan(y)) or (x == y and math.copysign(1, x) == math.copysign(1, y))

    monkeypatch.setattr(np, "clip", no_numpy)
    for v, want in zip(cases, expected, strict=True):
        a._root = (v, -v, 0.25)
        a.keep_inside(limit)
        assert all(type(x) is float for x in a._root[:2]) and a._root[2] == 0.25
        assert same(a._root[0], want[0]) and same(a._root[1], want[1]), (v, a._root, want)
