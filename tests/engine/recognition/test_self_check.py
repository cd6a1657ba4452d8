"""engine/recognition/self_check.py: each trained trial through the recognizer without its own
template, as `quickjab train` reports it."""

from __future__ import annotations

import numpy as np
import pytest

from engine.recognition import Templates
from engine.recognition.self_check import leave_one_out, said, without
from game.actions import load_library
from game.virtual_player import synthesize_action

LIB = load_library()


def trials_of(actions: list[str], n: int = 3, seed: int = 0) -> dict[str, list[np.ndarray]]:
    rng = np.random.default_rng(seed)
    return {a: [synthesize_action(LIB[a], "experienced", rng, rest_before=20, rest_after=20).reshape(-1, 6)
                for _ in range(n)] for a in actions}


def test_moves_thrown_apart_are_each_recognized_without_their_own_template():
    trials = trials_of(["straight_r", "hook_r", "uppercut_r"])
    check = leave_one_out(Templates.from_trials(trials), 0, trials)
    assert (check.trials, check.right, dict(check.taken_for)) == (9, 9, {})
    assert said(check) == ["each new trial against the rest (the game's recognizer, its own template left out): 9 of 9 recognized"]


def test_two_moves_thrown_alike_are_taken_for_each_other():
    trials = trials_of(["straight_r", "hook_r"])
    rng = np.random.default_rng(1)  # "hook_r" thrown as the straights, a little shaken
    trials["hook_r"] = [t + rng.normal(0, 0.01, t.shape) for t in trials["straight_r"]]
    check = leave_one_out(Templates.from_trials(trials), 0, trials)
    assert check.trials == 6 and check.right <= 3
    assert {a for a, _ in check.taken_for} <= {"straight_r", "hook_r"} and check.taken_for
    assert any(line.startswith("  hook_r: taken for straight_r") or line.startswith("  straight_r: taken for hook_r")
               for line in said(check)), said(check)


def test_only_the_new_trials_are_held_out_and_a_lone_one_is_not():
    base = trials_of(["straight_r", "hook_r"], seed=2)
    new = trials_of(["uppercut_r"], n=1, seed=3) | trials_of(["hook_l"], seed=4)
    templates = Templates.from_trials({**base, **new})
    check = leave_one_out(templates, 6, new)  # the new ones after the 6 of the base
    assert check.trials == 3  # uppercut_r's lone trial has no other of its kind to be matched with
    with pytest.raises(ValueError, match="template 5 is 'hook_r', not the trial's 'uppercut_r'"):
        leave_one_out(templates, 5, new)


def test_without_leaves_one_template_out_and_keeps_the_rest_as_they_are():
    templates = Templates.from_trials(trials_of(["straight_r", "hook_r"]))
    less = without(templates, 1)
    assert less.actions == ["straight_r", "straight_r", "hook_r", "hook_r", "hook_r"]
    assert np.array_equal(less.thresholds, np.delete(templates.thresholds, 1))
    assert less.signals[1] is templates.signals[2] and less.rest_noise == templates.rest_noise


def test_a_trial_is_scored_by_its_first_decided_motion():
    from engine.recognition.events import RecognizerEvent as Ev
    from engine.recognition.self_check import final_action

    first = [Ev("start", "block", 41), Ev("switch", "uppercut_r", 63), Ev("end", "uppercut_r", 76)]
    assert final_action(first + [Ev("start", "block", 86), Ev("end", "block", 112)]) == "uppercut_r"  # then the return
    assert final_action([Ev("start", "hook_r", 40), Ev("reject", "hook_r", 45, called_off=True)]) is None
    assert final_action([Ev("reject", None, 30), Ev("start", "jab", 50)]) == "jab"
    assert final_action([]) is None
