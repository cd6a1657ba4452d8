"""BVH import (the CMU clip), retargeting, cutting, export and the round trip."""

from __future__ import annotations

import json

import numpy as np
import pytest

from game.actions import load_library
from game.bvh import (
    BVHError,
    bvh_positions_ours,
    cut_action,
    forward_kinematics,
    map_joints,
    parse_bvh,
    played_positions,
    read_bvh,
    retarget,
    write_bvh,
)
from game.skeleton import BONE_LENGTHS, JOINTS, bone_lengths, joint_index
from tools.cli import main

LIB = load_library()
CMU = "mocap/cmu_02_05_punch_strike.bvh"


@pytest.fixture(scope="module")
def cmu(shared_data):
    return read_bvh(shared_data / CMU)


def test_cmu_clip_imports_with_rigid_limbs(cmu):
    assert cmu.frames == 927 and cmu.frame_time == pytest.approx(1 / 60, rel=1e-3)
    idx = map_joints(cmu)
    assert cmu.joints[idx[joint_index("fist_r")]].name == "CC_Base_R_Hand"
    pos = cmu.global_positions()[:, idx]
    lengths = bone_lengths(pos)
    # limbs that are one BVH bone each keep their length through all 927 frames (FK is right)
    for child in ("elbow_l", "fist_l", "elbow_r", "fist_r", "knee_l", "ankle_l", "knee_r", "ankle_r"):
        b = JOINTS.index(child) - 1  # BONES are ordered by child joint
        assert np.ptp(lengths[:, b]) / lengths[:, b].mean() < 0.01, child
    # a standing performer in centimetres: head well above the pelvis, feet near the floor
    assert 150 < pos[0, joint_index("head"), 1] < 190
    assert pos[:, joint_index("ankle_l"), 1].min() < 20


def test_retargeted_cmu_keeps_our_bone_lengths_within_one_percent(cmu):
    motion = retarget(cmu)
    assert motion.postures.shape == (927, 17, 3)
    assert np.abs(bone_lengths(motion.postures) / BONE_LENGTHS - 1).max() < 0.01
    # retargeting keeps the source's bone directions
    src = motion.source_positions
    for a, b in (("shoulder_r", "elbow_r"), ("knee_l", "ankle_l")):
        ia, ib = joint_index(a), joint_index(b)
        d_src = src[:, ib] - src[:, ia]
        # compare in world: rotate our local result back with the root yaw
        yaw = motion.roots[:, 2]
        loc = motion.postures[:, ib] - motion.postures[:, ia]
        wx = np.cos(yaw) * loc[:, 0] + np.sin(yaw) * loc[:, 2]
        wz = -np.sin(yaw) * loc[:, 0] + np.cos(yaw) * loc[:, 2]
        ours = np.column_stack([wx, loc[:, 1], wz])
        cos = np.sum(ours * d_src, axis=1) / np.linalg.norm(ours, axis=1) / np.linalg.norm(d_src, axis=1)
        assert cos.min() > 0.999
    # feet on the ground, pelvis at standing height
    assert 0.7 < motion.postures[0, joint_index("pelvis"), 1] < 1.1


def test_cut_action_from_the_cmu_clip_starts_and_ends_at_the_guard(cmu):
    motion = retarget(cmu)
    guard = LIB["guard"].posture(0)
    a = cut_action(motion, 100, 160, "cmu_punch", "attack", guard)
    assert a.frames == 61
    assert np.allclose(a.posture(0), guard, atol=1e-6) and np.allclose(a.posture(60), guard, atol=1e-6)
    assert np.allclose(a.root_offset(0), 0.0)
    mid = a.posture(30)
    assert np.abs(bone_lengths(mid) / BONE_LENGTHS - 1).max() < 1e-6
    with pytest.raises(Exception, match="outside"):
        cut_action(motion, 900, 2000, "x")


def test_export_import_round_trip(tmp_path):
    positions = played_positions(LIB, ["straight_l", "hook_r", "step_forward", "knockdown"])
    path = write_bvh(tmp_path / "played.bvh", positions, rest=LIB["guard"].posture(0))
    back = read_bvh(path)
    assert back.frames == len(positions)
    assert np.abs(bvh_positions_ours(back) - positions).max() < 1e-4
    assert back.joints[0].channels[:3] == ["xposition", "yposition", "zposition"]
    # root OFFSET zero, positions absolute: Blender (absolute) and the spec (added) agree
    assert np.all(back.joints[0].offset == 0.0)


def test_a_looping_action_is_exported_once_round(tmp_path):
    """The guard loops: it never returns to the guard, so `bvh export --play guard` stepped it
    for ever, its frame list growing by some 30 MB a second."""
    import signal

    def hung(*_):
        raise TimeoutError("played_positions never finished a looping action")

    old = signal.signal(signal.SIGALRM, hung)
    signal.alarm(30)
    try:
        positions = played_positions(LIB, ["guard"], rest_frames=20)
        assert main(["bvh", "export", "--play", "straight_l,guard,hook_r", "-o", str(tmp_path / "g.bvh")]) == 0
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)
    assert len(positions) == 20 + LIB["guard"].frames + 20  # each action its own frames, a loop once round
    expected = sum(LIB[n].frames for n in ("straight_l", "guard", "hook_r")) + 40
    assert read_bvh(tmp_path / "g.bvh").frames == expected


def test_any_channel_order_is_honoured():
    # one bone along +y under a root rotated 90 degrees about z then x: order matters
    text = """HIERARCHY
ROOT a
{
  OFFSET 0 0 0
  CHANNELS 6 Xposition Yposition Zposition Xrotation Zrotation Yrotation
  JOINT b
  {
    OFFSET 0 1 0
    CHANNELS 3 Zrotation Xrotation Yrotation
    End Site
    {
      OFFSET 0 1 0
    }
  }
}
MOTION
Frames: 1
Frame Time: 0.0333333
0 0 0 90 90 0 0 0 0
"""
    pos, _ = forward_kinematics(parse_bvh(text))
    # R = Rx(90) Rz(90): (0,1,0) -Rz-> (-1,0,0) -Rx-> (-1,0,0)
    assert np.allclose(pos[0, 1], [-1.0, 0.0, 0.0], atol=1e-9)
    swapped = text.replace("Xrotation Zrotation Yrotation", "Zrotation Xrotation Yrotation")
    pos2, _ = forward_kinematics(parse_bvh(swapped))
    # R = Rz(90) Rx(90): (0,1,0) -Rx-> (0,0,1) -Rz-> (0,0,1)
    assert np.allclose(pos2[0, 1], [0.0, 0.0, 1.0], atol=1e-9)


def test_bad_bvh_names_itself(tmp_path):
    bad = tmp_path / "bad.bvh"
    bad.write_text("HIERARCHY\nROOT a\n{\n OFFSET 0 0\n}\n")
    with pytest.raises(BVHError, match="bad.bvh"):
        read_bvh(bad)
    assert main(["bvh", "info", str(bad)]) == 2


def test_bvh_commands(tmp_path, shared_data, capsys):
    out = tmp_path / "m.bvh"
    assert main(["bvh", "export", "--play", "straight_r,block", "-o", str(out)]) == 0
    assert read_bvh(out).frames > LIB["straight_r"].frames
    js = tmp_path / "cut.json"
    assert main(["bvh", "cut", str(shared_data / CMU), "--start", "200", "--end", "250",
                 "--name", "cmu_strike", "-o", str(js)]) == 0
    from game.actions import load_action

    assert load_action(js).frames == 51


def test_a_simulated_bout_exports_one_bvh_per_boxer(tmp_path):
    out = tmp_path / "bout.bvh"
    assert main(["bvh", "export", "--play", "straight_l,straight_r", "--opponent", "block", "-o", str(out)]) == 0
    a, b = read_bvh(tmp_path / "bout_boxer0.bvh"), read_bvh(tmp_path / "bout_boxer1.bvh")
    assert a.frames == b.frames > LIB["straight_l"].frames + LIB["straight_r"].frames
    pa, pb = bvh_positions_ours(a), bvh_positions_ours(b)
    # both in one world frame: boxer 0 at -z, boxer 1 at +z, facing each other
    assert pa[0, 0, 2] < 0 < pb[0, 0, 2]
    assert np.abs(bone_lengths(pa) / BONE_LENGTHS - 1).max() < 0.05  # simulated bodies keep their bones


@pytest.mark.parametrize("name", ["", "../../x", "a b", "x" * 5000, "a,b"])
def test_bvh_cut_refuses_a_name_the_action_loader_refuses(tmp_path, capsys, name):
    """The tester: `bvh cut --name ""` exited 0 with an action file the loader refused ("name must
    be a non-empty string"), and "../../x", "a b" or 5000 characters were taken. Refused by the
    parser with the loader's own rule (game.actions.name_problem), before the BVH is read."""
    out = tmp_path / "e.json"
    with pytest.raises(SystemExit) as exit_:
        main(["bvh", "cut", str(tmp_path / "m.bvh"), "--start", "0", "--end", "20", "--name", name, "-o", str(out)])
    assert exit_.value.code == 2 and not out.exists()
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "argument --name: the action name" in err, err


@pytest.mark.parametrize("name", ["../../x", "a b", "x" * 65])
def test_the_action_loader_refuses_the_names_bvh_cut_refuses(tmp_path, name):
    from game.actions import ActionError, load_action

    path = tmp_path / "odd.json"
    path.write_text(json.dumps(dict(json.loads(open(LIB["hook_r"].source).read()), name=name)))
    with pytest.raises(ActionError, match="name"):
        load_action(path)


def test_bvh_cut_moves_an_existing_file_aside(tmp_path, capsys):
    """The tester: `bvh cut ... -o cut.json` replaced whatever was there (an action someone made).
    Moved aside, to cut.json.old (not one more action of a folder the loader reads: two files
    of one action there stop the whole library), said in one line."""
    bvh = tmp_path / "m.bvh"
    assert main(["bvh", "export", "--play", "straight_r", "-o", str(bvh)]) == 0
    out = tmp_path / "cut.json"
    out.write_text('{"my": "action"}\n')
    capsys.readouterr()
    argv = ["bvh", "cut", str(bvh), "--start", "0", "--end", "20", "--name", "x", "-o", str(out)]
    assert main(argv) == 0
    assert capsys.readouterr().err == f"{out} was not empty: moved to {tmp_path / 'cut.json.old'}\n"
    assert (tmp_path / "cut.json.old").read_text() == '{"my": "action"}\n'
    from game.actions import load_action

    assert load_action(out).name == "x"
    assert main(argv) == 0 and capsys.readouterr().err == ""  # the same action again: nothing to keep
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cut.json", "cut.json.old", "m.bvh"]


def test_a_cut_over_an_action_of_a_library_folder_keeps_the_library_loading(tmp_path):
    """Re-cutting an action into a copy of the library (its file moved aside) left two files of
    one action there, and the library refused to load ("one file per action")."""
    import shutil
    from pathlib import Path

    lib = tmp_path / "actions"
    shutil.copytree(Path(LIB["hook_r"].source).parent, lib)
    bvh = tmp_path / "m.bvh"
    assert main(["bvh", "export", "--play", "straight_r", "-o", str(bvh)]) == 0
    argv = ["bvh", "cut", str(bvh), "--start", "0", "--end", "20", "--name", "straight_l", "-o", str(lib / "straight_l.json")]
    assert main(argv) == 0 and (lib / "straight_l.json.old").is_file()
    assert load_library(lib)["straight_l"].frames == 21


def test_a_bout_cut_at_the_cap_is_said(tmp_path, capsys, monkeypatch):
    """The tester: `bvh export --play hook_r x3000 --opponent hook_r x3000` silently stopped at the
    2-minute cap. Said in one line: what was asked, what was written (the cap made 1 s here)."""
    import game.bvh
    import tools.bvh_cmd

    monkeypatch.setattr(game.bvh, "MAX_BOUT_S", 1)
    monkeypatch.setattr(tools.bvh_cmd, "MAX_BOUT_S", 1)
    script = ",".join(["hook_r"] * 30)
    assert main(["bvh", "export", "--play", script, "--opponent", script, "-o", str(tmp_path / "bout.bvh")]) == 0
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "cut at the 1 s cap: asked for 30 and 30 actions" in err, err
    frames = read_bvh(tmp_path / "bout_boxer0.bvh").frames
    assert f"wrote {frames / 60:.1f} s" in err


def test_a_bout_under_the_cap_says_nothing_of_it(tmp_path, capsys):
    assert main(["bvh", "export", "--play", "hook_r", "--opponent", "block", "-o", str(tmp_path / "b.bvh")]) == 0
    assert capsys.readouterr().err == ""


def test_an_action_named_in_another_script_loads(tmp_path):
    # letters and digits of any script, `_` and `-`: a player names actions in their language
    from game.actions import load_action, name_problem

    path = tmp_path / "hook.json"
    path.write_text(json.dumps(dict(json.loads(open(LIB["hook_r"].source).read()), name="хук_2")), encoding="utf-8")
    assert load_action(path).name == "хук_2" and name_problem("хук 2") is not None
    for word in ("मुक्का", "ต่อย", "ضَرْبَة", "cafe\u0301"):  # vowels and accents that are combining marks
        assert name_problem(word) is None, word
