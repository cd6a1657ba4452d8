"""The action library: every clip starts and ends at the guard, keeps its bone lengths, and the
attacks and guards are where boxing puts them."""

from __future__ import annotations

import json

import numpy as np
import pytest

from game.actions import (
    ACTION_NAMES,
    REACTION_NAMES,
    ActionError,
    load_action,
    load_library,
    reaction_for,
)
from game.skeleton import (
    BONE_LENGTHS,
    JOINTS,
    bone_lengths,
    compose_root,
    joint_index,
    local_to_world,
)

LIB = load_library()
GUARD = LIB["guard"].posture(0)
FIST = {"l": joint_index("fist_l"), "r": joint_index("fist_r")}


def test_library_has_the_contract_actions():
    assert len(JOINTS) == 17
    for name in (*ACTION_NAMES, "guard", "knockdown", *REACTION_NAMES):
        assert name in LIB, name
    kinds = {n: LIB[n].kind for n in ACTION_NAMES}
    assert {kinds[n] for n in ACTION_NAMES[:6]} == {"attack"}
    assert {kinds[n] for n in ("parry_l", "parry_r", "block")} == {"defense"}
    assert {kinds[n] for n in ACTION_NAMES[9:]} == {"step"}


@pytest.mark.parametrize("name", sorted(LIB))
def test_every_action_starts_and_ends_at_the_guard(name):
    a = LIB[name]
    assert np.allclose(a.posture(0), GUARD, atol=1e-6)
    assert np.allclose(a.posture(a.frames - 1), GUARD, atol=1e-6)
    # and never stretches a bone, at integer or fractional frames
    for f in np.linspace(0, a.frames - 1, 37):
        assert np.allclose(bone_lengths(a.posture(f)), BONE_LENGTHS, atol=1e-6)
    # the feet stay on the ground, not in it (the ankle joint sits ~8 cm up at rest)
    assert a.table[:, [joint_index("ankle_l"), joint_index("ankle_r")], 1].min() > 0.02


def test_timings_are_boxing_timings():
    for n in ("straight_l", "straight_r"):
        assert 0.3 <= LIB[n].frames / 60 <= 0.42
    for n in ("hook_l", "hook_r", "uppercut_l", "uppercut_r"):
        assert 0.44 <= LIB[n].frames / 60 <= 0.56
    for n in ACTION_NAMES[9:]:
        assert 0.3 <= LIB[n].frames / 60 <= 0.4


@pytest.mark.parametrize("hand", ["l", "r"])
def test_straight_reaches_forward_with_its_own_hand(hand):
    a = LIB[f"straight_{hand}"]
    traj = a.hand_trajectory(hand)
    other = a.hand_trajectory("r" if hand == "l" else "l")
    gain = traj[:, 2].max() - traj[0, 2]
    assert gain > 0.4  # the punching fist travels forward ~half a metre
    assert other[:, 2].max() - other[0, 2] < 0.15  # the other one stays home
    peak = int(np.argmax(traj[:, 2]))
    w = a.attacks[0]
    assert w.hand == hand and w.start <= peak <= w.end
    # a straight goes straight: little sideways motion compared with its reach
    assert np.ptp(traj[:, 0]) < 0.5 * gain


def test_hooks_arc_sideways_and_uppercuts_rise():
    for hand, sign in (("l", 1.0), ("r", -1.0)):
        hook = LIB[f"hook_{hand}"].hand_trajectory(hand)
        w = LIB[f"hook_{hand}"].attacks[0]
        # the fist crosses towards the centre line during the window (l: +x, r: -x)
        assert sign * (hook[w.end, 0] - hook[w.start, 0]) > 0.1
        elbow = LIB[f"hook_{hand}"].table[:, joint_index(f"elbow_{hand}")]
        fist = LIB[f"hook_{hand}"].table[:, joint_index(f"fist_{hand}")]
        mid = (w.start + w.end) // 2
        assert elbow[mid, 1] > elbow[0, 1] + 0.2  # the elbow comes up...
        assert abs(elbow[mid, 1] - fist[mid, 1]) < 0.18  # ...about level with the fist
        up = LIB[f"uppercut_{hand}"]
        traj = up.hand_trajectory(hand)
        low = int(np.argmin(traj[:, 1]))
        w = up.attacks[0]
        assert traj[low, 1] < traj[0, 1] - 0.15  # drops below the guard first
        assert low < w.start and traj[w.end, 1] > traj[0, 1] + 0.05  # then rises above it


def test_parries_move_a_hand_sideways_and_block_covers_the_head():
    for hand, sign in (("l", 1.0), ("r", -1.0)):
        a = LIB[f"parry_{hand}"]
        traj = a.hand_trajectory(hand)
        assert (sign * (traj[:, 0] - traj[0, 0])).max() > 0.15  # across the face, l: +x, r: -x
        assert a.guards and a.guards[0].kind == "parry"
    b = LIB["block"]
    mid = b.frames // 2
    head = b.posture(mid)[joint_index("head")]
    for hand in "lr":
        fist = b.posture(mid)[FIST[hand]]
        assert fist[1] > head[1] - 0.1 and fist[2] > head[2]  # gloves up, in front of the face
    assert b.guard_at(mid, "head").kind == "block"


def test_attack_windows_are_sane():
    for name in ACTION_NAMES[:6]:
        a = LIB[name]
        assert len(a.attacks) == 1
        w = a.attacks[0]
        assert 0 < w.start < w.end < a.frames - 1
        assert w.hand == name[-1]
        assert w.damage > 0 and set(w.targets) <= {"head", "body"}
        traj = a.hand_trajectory(w.hand)
        assert w.reach == pytest.approx(traj[w.start : w.end + 1, 2].max(), abs=2e-3)
        assert 0.4 < w.reach < 1.0
    assert LIB["straight_r"].attacks[0].reach > LIB["hook_r"].attacks[0].reach
    for name in ACTION_NAMES[6:]:
        assert not LIB[name].attacks


def test_steps_move_the_root_about_thirty_centimetres():
    expect = {"step_forward": (0, 1), "step_back": (0, -1), "step_left": (-1, 0), "step_right": (1, 0)}
    for name, (dx, dz) in expect.items():
        a = LIB[name]
        end = a.root_offset(a.frames - 1)
        assert 0.25 <= np.hypot(end[0], end[1]) <= 0.35
        assert np.sign(end[0]) == dx and np.sign(end[1]) == dz
        # the planted feet do not skate: a foot's world position moves monotonically
        world = np.array([local_to_world(a.posture(f), compose_root((0, 0, 0), a.root_offset(f)))
                          for f in range(a.frames)])
        for foot in ("ankle_l", "ankle_r"):
            travel = world[:, joint_index(foot), [0, 2]] @ np.array([dx, dz])
            assert np.all(np.diff(travel) > -0.01)


def test_reactions_and_knockdown():
    assert reaction_for("head", np.array([0.0, 0.0, -1.0]), 2.0) == "hit_head_front_light"
    assert reaction_for("body", np.array([1.0, 0.0, 0.1]), 8.0) == "hit_body_left_heavy"
    kd = LIB["knockdown"]
    lowest = kd.table[:, joint_index("head"), 1].min()
    assert lowest < 0.4  # actually goes down
    assert kd.frames > 90


def test_bad_action_file_names_itself(tmp_path):
    good = json.loads(open(LIB["straight_l"].source).read())
    bad = dict(good, keyframes=good["keyframes"][1:])
    path = tmp_path / "broken.json"
    path.write_text(json.dumps(bad))
    with pytest.raises(ActionError, match="broken.json"):
        load_action(path)
    path.write_text("{not json")
    with pytest.raises(ActionError, match="broken.json"):
        load_action(path)


def _with_first(good: dict, key: str, **change) -> dict:
    """`good` with the first item of its list `key` changed."""
    return dict(good, **{key: [dict(good[key][0], **change), *good[key][1:]]})


@pytest.mark.parametrize("change", [
    lambda g: [g], lambda g: 5, lambda g: None,  # the root is not an object: AttributeError
    lambda g: dict(g, frames=float("inf")),  # int(inf): OverflowError
    lambda g: _with_first(g, "keyframes", frame=float("inf")),
    lambda g: _with_first(g, "attacks", start=float("-inf")),
    lambda g: dict(g, guards=[{"start": float("inf"), "end": 1, "covers": ["head"], "kind": "block"}]),
    lambda g: dict(g, name=["hook_r"]), lambda g: dict(g, name={"a": 1}),  # unhashable in the library: TypeError
    lambda g: dict(g, name=5), lambda g: dict(g, name=""),
])
def test_an_action_file_of_the_wrong_shape_or_types_names_itself(tmp_path, change):
    """JSON's Infinity, a root that is not an object and a name that is not a string ended in a
    traceback (OverflowError, AttributeError, TypeError) instead of the file's one line."""
    good = json.loads(open(LIB["hook_r"].source).read())
    path = tmp_path / "odd.json"
    path.write_text(json.dumps(change(good)))  # Infinity as JSON's Python dialect writes it
    with pytest.raises(ActionError) as err:
        load_action(path)
    assert str(err.value).startswith(f"{path}: ") and "\n" not in str(err.value)


def _pose_scaled(good: dict, k: float) -> dict:
    return _with_first(good, "keyframes", pose=[[k * v for v in p] for p in good["keyframes"][0]["pose"]])


@pytest.mark.parametrize("change", [
    lambda g: _pose_scaled(g, 1e307),  # 1e308 coordinates loaded; the contact sheet overflowed
    lambda g: _pose_scaled(g, 100.0),  # a joint 100 m from the root is no pose
    lambda g: dict(g, root=[[0, 1e6, 0, 0], [5, 0, 0, 0]]),
])
def test_an_action_whose_poses_lie_metres_away_is_refused(tmp_path, change):
    good = json.loads(open(LIB["hook_r"].source).read())
    path = tmp_path / "far.json"
    path.write_text(json.dumps(change(good)))
    with pytest.raises(ActionError, match="within") as err:
        load_action(path)
    assert str(err.value).startswith(f"{path}: ")
    path.write_text(json.dumps(_pose_scaled(good, 1.0)))  # the same file as shipped loads
    assert load_action(path).name == "hook_r"


def test_a_contact_sheet_over_a_folder_is_one_line(tmp_path, capsys):
    """pygame.image.save raised pygame.error (a traceback) for a folder or a file it cannot write."""
    from tools.cli import main

    for target in (tmp_path, tmp_path / "sheet.png"):
        if target != tmp_path:
            target.mkdir()
        with pytest.raises(SystemExit) as exit_:  # refused by -o's type, before the drawing
            main(["actions", "sheet", "-o", str(target)])
        err = capsys.readouterr().err.strip().splitlines()
        assert exit_.value.code == 2 and len(err) == 1, err
        assert err[0].startswith(f"quickjab actions sheet: argument -o/--output: {target} is a directory"), err


def test_contact_sheet_command_draws_every_action(tmp_path):
    import pygame

    from tools.cli import main

    out = tmp_path / "sheet.png"
    assert main(["actions", "sheet", "-o", str(out)]) == 0
    image = pygame.image.load(str(out))
    w, h = image.get_size()
    rows = (len(LIB) + 1) // 2
    assert w > 1000 and h > rows * 200  # one strip of key frames per action, two per row


@pytest.mark.parametrize(("name", "change", "says"), [
    ("hook_r", lambda g: _with_first(g, "attacks", damage=-5.0), "attack window"),
    ("hook_r", lambda g: _with_first(g, "attacks", targets=["elbow"]), "attack window"),
    ("hook_r", lambda g: _with_first(g, "attacks", targets=[]), "attack window"),
    ("block", lambda g: _with_first(g, "guards", kind="dodge"), "guard window"),
    ("block", lambda g: _with_first(g, "guards", covers=["knee"]), "guard window"),
    ("block", lambda g: _with_first(g, "guards", end=10_000), "guard window"),
    ("hook_r", lambda g: dict(g, fps=30), "fps must be 60"),
])
def test_an_action_the_referee_cannot_score_is_refused(tmp_path, name, change, says):
    """Found by a writer from the docs alone: negative damage, a target "elbow", a guard "dodge"
    covering a "knee", a guard past the clip's end and fps 30 all loaded (exit 0)."""
    good = json.loads(open(LIB[name].source).read())
    path = tmp_path / f"{name}.json"
    path.write_text(json.dumps(change(good)))
    with pytest.raises(ActionError, match=says) as err:
        load_action(path)
    assert str(err.value).startswith(f"{path}: ") and "\n" not in str(err.value)
    path.write_text(json.dumps(good))
    assert load_action(path).name == name


def test_two_files_of_one_action_name_are_refused_naming_both(tmp_path):
    """A copy of hook_r.json with other damage (zz_hook_r_v2.json) silently replaced the
    original: `actions list --dir` showed one hook_r, the copy's. Which file counts is not for
    the sort order to decide."""
    import shutil

    from game.actions import default_actions_dir

    folder = tmp_path / "actions"
    shutil.copytree(default_actions_dir(), folder)
    copy = json.loads((folder / "hook_r.json").read_text())
    (folder / "zz_hook_r_v2.json").write_text(json.dumps(_with_first(copy, "attacks", damage=99.0)))
    with pytest.raises(ActionError, match=r"zz_hook_r_v2.json: action 'hook_r' is also .*hook_r.json") as err:
        load_library(folder)
    assert "\n" not in str(err.value)
