"""PlayerController: the one-node motion graph, switches at n_p and blending (paper Fig. 4)."""

from __future__ import annotations

import numpy as np
import pytest

from game.actions import ACTION_NAMES, load_library
from game.motion import PlayerController
from game.skeleton import BONE_LENGTHS, bone_lengths

LIB = load_library()


def run(pc: PlayerController, steps: int) -> np.ndarray:
    return np.array([pc.step() for _ in range(steps)])


def peak_joint_speed(postures: np.ndarray) -> float:
    return float(np.linalg.norm(np.diff(postures, axis=0), axis=-1).max() * 60.0)


@pytest.mark.parametrize("name", ACTION_NAMES)
def test_a_started_action_plays_through_and_returns_to_the_guard(name):
    pc = PlayerController(LIB)
    run(pc, 3)
    pc.on_event({"event": "start", "action": name, "frame": 0, "t": 0.0, "score": 0.1})
    assert pc.action == name
    finished_at = None
    for i in range(LIB[name].frames + 5):
        pc.step()
        if pc.finished_action():
            finished_at = i
            break
    assert finished_at == LIB[name].frames - 1  # frames 0 .. frames-1, one per step
    assert pc.action == "guard" and pc.idle
    assert np.allclose(pc.output, LIB["guard"].posture(0), atol=1e-6)
    pc.step()
    assert not pc.finished_action()


def test_root_motion_of_a_step_adds_up():
    pc = PlayerController(LIB)
    pc.play("step_forward")
    total = np.zeros(3)
    for _ in range(LIB["step_forward"].frames):
        pc.step()
        total += pc.root_delta
    assert total == pytest.approx(LIB["step_forward"].root_offset(LIB["step_forward"].frames - 1), abs=1e-6)


@pytest.mark.parametrize(("a", "b"), [("straight_r", "hook_r"), ("straight_l", "hook_l")])
@pytest.mark.parametrize("n_p", [6, 8, 10])
def test_switching_at_n_p_is_smoother_than_restarting_the_clip(a, b, n_p):
    """Fig. 4: the recognizer switches from a straight to a hook once the hook matches better;
    continuing the hook from n_p moves the joints less violently than playing it from 0."""
    peaks = {}
    for from_frame in (n_p, 0):
        pc = PlayerController(LIB)
        pc.play(a)
        shown = list(run(pc, n_p))
        pc.on_event({"event": "switch", "action": b, "from_frame": from_frame})
        assert pc.action == b
        shown += list(run(pc, 12))
        peaks[from_frame] = peak_joint_speed(np.array(shown[n_p - 1 :]))
    assert peaks[n_p] < peaks[0]


def test_blending_keeps_postures_continuous_and_bones_rigid():
    pc = PlayerController(LIB)
    pc.play("hook_r")
    before = run(pc, 12)[-1]
    pc.play("block")  # an interruption with a big posture jump
    after = pc.step()
    jump = np.abs(LIB["block"].posture(0) - before).max()
    assert np.abs(after - before).max() < 0.25 * jump
    shown = run(pc, 10)
    assert np.allclose(bone_lengths(shown), BONE_LENGTHS, atol=1e-6)
    assert np.allclose(shown[-1], LIB["block"].posture(10), atol=1e-6)  # blend is over


def test_reject_aborts_a_young_clip_and_end_lets_it_finish():
    pc = PlayerController(LIB)
    pc.on_event({"event": "start", "action": "hook_l"})
    run(pc, 3)
    pc.on_event({"event": "reject"})
    assert pc.idle
    pc.on_event({"event": "start", "action": "hook_l"})
    run(pc, 3)
    pc.on_event({"event": "end", "action": "hook_l"})
    assert pc.action == "hook_l"
    pc.on_event({"event": "start", "action": "no_such_move"})
    assert pc.action == "hook_l" and pc.ignored_events == 1
