"""Author the shipped action library: writes game/assets/actions/*.json.

Each action is a handful of key poses described like a boxing coach would (tools/pose_builder)
at frames of a 60 Hz clip, a root track for footwork, and its attack and guard windows. The
game only reads the JSON this writes (`quickjab actions author` regenerates it). Orthodox
stance: left foot and left hand lead.

Timings: straights 0.37-0.40 s, hooks and uppercuts 0.50-0.53 s, parries 0.3 s, block 0.5 s,
steps 0.35 s with 0.30 m of root motion.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from game.actions import Action, AttackWindow, GuardWindow, default_actions_dir
from game.skeleton import joint_index
from tools.pose_builder import GUARD, Pose

STEP = 0.30  # metres of root motion per step


def _action(name, kind, frames, keys, root=None, attacks=(), guards=(), loop=False, description=""):
    """keys: [(frame, Pose)]; root: [(frame, dx, dz, dyaw)] or None. Attack windows get their
    reach measured on the authored motion (max fist z within the window)."""
    key_frames = np.array([k for k, _ in keys])
    key_poses = np.array([p.joints() for _, p in keys])
    root_keys = np.array(root if root else [(0, 0, 0, 0), (frames - 1, 0, 0, 0)], dtype=np.float64)
    a = Action(name, kind, frames, key_frames, key_poses, root_keys, [], list(guards), loop, description)
    measured = []
    for hand, start, end, targets, damage in attacks:
        z = a.table[start : end + 1, joint_index(f"fist_{hand}"), 2]
        measured.append(AttackWindow(hand, start, end, tuple(targets), float(damage), float(z.max())))
    a.attacks = measured
    return a


def _in_clip_frame(pose: Pose, dx: float, dz: float, parts=("ankle_l", "ankle_r")) -> Pose:
    """A pose whose `parts` were given relative to the clip's start, re-expressed in the
    boxer's local frame when the root has moved by (dx, dz)."""
    kw = {}
    for part in parts:
        x, y, z = getattr(pose, part)
        kw[part] = (x - dx, y, z - dz)
    return pose.but(**kw)


def _smooth(t: float) -> float:
    t = min(max(t, 0.0), 1.0)
    return t * t * (3 - 2 * t)


# ---------------------------------------------------------------------------------- attacks


def straight_l() -> Action:
    g = GUARD
    reach = g.but(chest_yaw=44, hip_yaw=28, lean_fwd=8, pelvis=(0.0, 0.89, 0.03),
                  fist_l=(-0.02, 1.47, 0.85), elbow_l=(-0.6, -1.0, 0.0), head_yaw=-30)  # fmt: skip
    return _action("straight_l", "attack", 22, [
        (0, g),
        (3, g.but(chest_yaw=34, fist_l=(-0.08, 1.46, 0.46))),
        (7, reach),
        (10, reach.but(fist_l=(-0.03, 1.47, 0.78))),
        (15, g.but(chest_yaw=35, fist_l=(-0.09, 1.45, 0.47))),
        (21, g),
    ], attacks=[("l", 5, 10, ("head", "body"), 5.0)],
        description="jab: the lead (left) hand shoots straight from the guard and snaps back")  # fmt: skip


def straight_r() -> Action:
    g = GUARD
    full = g.but(hip_yaw=-2, chest_yaw=-28, lean_fwd=10, lean_side=-4, pelvis=(-0.02, 0.88, 0.06),
                 head_yaw=0, fist_r=(0.0, 1.46, 0.90), elbow_r=(0.6, -1.0, 0.0),
                 fist_l=(-0.11, 1.44, 0.27), ankle_r=(0.16, 0.11, -0.20), knee_r=(-0.4, 0.0, 1.0))  # fmt: skip
    return _action("straight_r", "attack", 24, [
        (0, g),
        (3, g.but(hip_yaw=28, chest_yaw=35, pelvis=(0.01, 0.89, -0.01), fist_r=(0.11, 1.42, 0.20))),
        (9, full),
        (12, full.but(fist_r=(0.01, 1.46, 0.82))),
        (17, g.but(hip_yaw=16, chest_yaw=12, head_yaw=-15, fist_r=(0.08, 1.43, 0.38))),
        (23, g),
    ], attacks=[("r", 6, 12, ("head", "body"), 9.0)],
        description="cross: the rear (right) hand straight, hips and shoulders turning through")  # fmt: skip


def hook_l() -> Action:
    g = GUARD
    impact = g.but(chest_yaw=-12, hip_yaw=4, lean_side=3, pelvis=(0.0, 0.88, 0.02), head_yaw=0,
                   fist_l=(0.0, 1.46, 0.56), elbow_l=(-1.0, 0.9, 0.0))  # fmt: skip
    return _action("hook_l", "attack", 30, [
        (0, g),
        (5, g.but(chest_yaw=42, hip_yaw=30, lean_side=-5, fist_l=(-0.32, 1.44, 0.30),
                  elbow_l=(-1.0, 0.3, 0.0))),
        (11, impact),
        (15, impact.but(chest_yaw=-22, fist_l=(0.13, 1.45, 0.44), elbow_l=(-1.0, 0.9, -0.3))),
        (22, g.but(chest_yaw=14, fist_l=(-0.08, 1.44, 0.33))),
        (29, g),
    ], attacks=[("l", 8, 14, ("head", "body"), 8.0)],
        description="lead hook: the left fist sweeps a horizontal arc, elbow up, body turning")  # fmt: skip


def hook_r() -> Action:
    g = GUARD
    impact = g.but(chest_yaw=-36, hip_yaw=-5, lean_fwd=6, lean_side=-3, pelvis=(-0.02, 0.88, 0.04),
                   head_yaw=10, fist_r=(0.0, 1.46, 0.58), elbow_r=(1.0, 0.9, 0.0),
                   fist_l=(-0.12, 1.44, 0.25), ankle_r=(0.16, 0.11, -0.20), knee_r=(-0.4, 0.0, 1.0))  # fmt: skip
    return _action("hook_r", "attack", 32, [
        (0, g),
        (5, g.but(chest_yaw=44, hip_yaw=32, fist_r=(0.32, 1.42, 0.10), elbow_r=(1.0, 0.3, 0.0))),
        (12, impact),
        (16, impact.but(chest_yaw=-46, fist_r=(-0.14, 1.45, 0.44), elbow_r=(1.0, 0.9, -0.3))),
        (24, g.but(chest_yaw=10, fist_r=(0.10, 1.42, 0.25))),
        (31, g),
    ], attacks=[("r", 9, 15, ("head", "body"), 11.0)],
        description="rear hook: the right fist arcs across, elbow up, hips and shoulders turning")  # fmt: skip


def uppercut_l() -> Action:
    g = GUARD
    impact = g.but(chest_yaw=8, hip_yaw=15, lean_fwd=4, lean_side=3, pelvis=(0.0, 0.91, 0.03),
                   head_yaw=-10, fist_l=(-0.02, 1.58, 0.54), elbow_l=(0.0, -1.0, 0.3))  # fmt: skip
    return _action("uppercut_l", "attack", 30, [
        (0, g),
        (5, g.but(pelvis=(-0.03, 0.83, 0.0), lean_side=-9, lean_fwd=10, chest_yaw=40,
                  fist_l=(-0.15, 1.10, 0.30), elbow_l=(-0.3, -1.0, -0.4))),
        (12, impact),
        (16, impact.but(fist_l=(0.0, 1.62, 0.46))),
        (23, g.but(chest_yaw=20, fist_l=(-0.08, 1.46, 0.33))),
        (29, g),
    ], attacks=[("l", 9, 15, ("head", "body"), 8.0)],
        description="lead uppercut: dip to the left, then the left fist rises from below")  # fmt: skip


def uppercut_r() -> Action:
    g = GUARD
    impact = g.but(chest_yaw=-22, hip_yaw=4, lean_fwd=6, lean_side=-3, pelvis=(-0.01, 0.91, 0.04),
                   head_yaw=5, fist_r=(0.03, 1.58, 0.56), elbow_r=(0.0, -1.0, 0.3),
                   ankle_r=(0.16, 0.11, -0.20))  # fmt: skip
    return _action("uppercut_r", "attack", 32, [
        (0, g),
        (5, g.but(pelvis=(0.03, 0.82, -0.01), lean_side=9, lean_fwd=10, chest_yaw=42, hip_yaw=30,
                  fist_r=(0.17, 1.08, 0.14), elbow_r=(0.3, -1.0, -0.4))),
        (13, impact),
        (17, impact.but(fist_r=(0.01, 1.62, 0.48))),
        (25, g.but(chest_yaw=18, fist_r=(0.10, 1.43, 0.25))),
        (31, g),
    ], attacks=[("r", 10, 16, ("head", "body"), 10.0)],
        description="rear uppercut: dip to the right, then the right fist drives upwards")  # fmt: skip


# ---------------------------------------------------------------------------------- defence


def parry_l() -> Action:
    g = GUARD
    out = g.but(chest_yaw=33, fist_l=(0.10, 1.47, 0.40), elbow_l=(-1.0, -0.7, 0.0))
    return _action("parry_l", "defense", 18, [
        (0, g), (5, out), (9, out.but(fist_l=(0.12, 1.45, 0.36))), (17, g),
    ], guards=[GuardWindow(2, 11, ("head",), "parry")],
        description="lead parry: the left glove slaps across the face to knock a punch aside")  # fmt: skip


def parry_r() -> Action:
    g = GUARD
    out = g.but(chest_yaw=24, fist_r=(-0.12, 1.47, 0.34), elbow_r=(1.0, -0.7, 0.0))
    return _action("parry_r", "defense", 18, [
        (0, g), (5, out), (9, out.but(fist_r=(-0.14, 1.45, 0.30))), (17, g),
    ], guards=[GuardWindow(2, 11, ("head",), "parry")],
        description="rear parry: the right glove slaps across to the left to deflect a jab")  # fmt: skip


def block() -> Action:
    g = GUARD
    shell = g.but(chest_yaw=18, lean_fwd=10, pelvis=(0.0, 0.86, 0.0), head_pitch=22, head_yaw=-15,
                  fist_l=(-0.08, 1.58, 0.28), fist_r=(0.08, 1.58, 0.25),
                  elbow_l=(-0.1, -1.0, 0.3), elbow_r=(0.1, -1.0, 0.3))  # fmt: skip
    return _action("block", "defense", 30, [
        (0, g), (5, shell), (24, shell), (29, g),
    ], guards=[GuardWindow(3, 26, ("head", "body"), "block")],
        description="block: both gloves up covering the head, elbows tucked over the ribs")  # fmt: skip


# ---------------------------------------------------------------------------------- footwork


def _step(name: str, direction: tuple[float, float], first: str, description: str) -> Action:
    """A step of STEP metres: the foot on the side of travel (`first`) moves, then the other
    follows, keeping the stance; the root glides along with a slight dip."""
    frames = 21
    dx, dz = direction[0] * STEP, direction[1] * STEP
    second = "ankle_r" if first == "ankle_l" else "ankle_l"
    start = {"ankle_l": np.array(GUARD.ankle_l), "ankle_r": np.array(GUARD.ankle_r)}
    move = np.array([dx, 0.0, dz])

    def foot(which: str, f: int, f0: int, f1: int) -> tuple:
        t = _smooth((f - f0) / (f1 - f0))
        p = start[which] + move * t
        p[1] += 0.07 * np.sin(np.pi * t)  # lifted mid-stride
        return tuple(p)

    keys = []
    for f in (0, 4, 7, 10, 13, 16, 20):
        root = _smooth(f / (frames - 1))
        dip = 0.02 * np.sin(np.pi * f / (frames - 1))
        pose = GUARD.but(pelvis=(0.0, 0.90 - dip, 0.0),
                         **{first: foot(first, f, 0, 10), second: foot(second, f, 7, 18)})  # fmt: skip
        keys.append((f, _in_clip_frame(pose, dx * root, dz * root)))
    return _action(name, "step", frames, keys, root=[(0, 0, 0, 0), (frames - 1, dx, dz, 0.0)],
                   description=description)  # fmt: skip


def steps() -> list[Action]:
    return [
        _step("step_forward", (0, 1), "ankle_l", "step forward: lead foot reaches, rear foot follows"),
        _step("step_back", (0, -1), "ankle_r", "step back: rear foot pushes back, lead foot follows"),
        _step("step_left", (-1, 0), "ankle_l", "step left: left foot steps out, right foot follows"),
        _step("step_right", (1, 0), "ankle_r", "step right: right foot steps out, left foot follows"),
    ]


# ---------------------------------------------------------------------------------- idle, hits


def guard() -> Action:
    g = GUARD
    low = g.but(pelvis=(0.0, 0.885, 0.0), fist_l=(-0.10, 1.43, 0.34), fist_r=(0.10, 1.41, 0.17))
    return _action("guard", "idle", 60, [(0, g), (30, low), (59, g)], loop=True,
                   description="the guard: orthodox stance, hands up, bouncing lightly")  # fmt: skip


def _reaction(name: str, frames: int, peak: Pose, hold: Pose, root=(0.0, 0.0), description="") -> Action:
    g = GUARD
    peak_f, hold_f = max(3, frames // 6), frames // 2
    dx, dz = root
    rk = [(0, 0, 0, 0), (hold_f, dx, dz, 0), (frames - 1, dx, dz, 0)]
    keys = [(0, g), (peak_f, peak), (hold_f, hold), (frames - 1, g)]
    # feet stay where they were while the root is pushed: express them in the moving frame
    fixed = []
    for f, p in keys:
        frac = _smooth(f / hold_f) if f <= hold_f else 1.0
        fixed.append((f, p if f in (0, frames - 1) else _in_clip_frame(p, dx * frac * 0.5, dz * frac * 0.5)))
    return _action(name, "reaction", frames, fixed, root=rk, description=description)


def reactions() -> list[Action]:
    g = GUARD
    out = []
    for heavy in (False, True):
        k = 2.0 if heavy else 1.0
        frames = 36 if heavy else 20
        strength = "heavy" if heavy else "light"
        low_hands = dict(fist_l=(-0.16, 1.36 - 0.04 * k, 0.28), fist_r=(0.16, 1.34 - 0.04 * k, 0.12))
        # head, from the front: snaps back
        peak = g.but(lean_fwd=-9 * k, head_pitch=-16 * k, pelvis=(0.0, 0.90 - 0.02 * k, -0.03 * k), **low_hands)
        out.append(_reaction(f"hit_head_front_{strength}", frames, peak, peak.but(lean_fwd=-4 * k, head_pitch=-6 * k),
                             root=(0.0, -0.07 * k), description=f"{strength} blow to the face: the head snaps back"))  # fmt: skip
        # head, from the left: pushed and turned to the right
        peak = g.but(lean_side=9 * k, chest_yaw=30 + 10 * k, head_yaw=-25 + 30 * k, **low_hands)
        out.append(_reaction(f"hit_head_left_{strength}", frames, peak, peak.but(lean_side=4 * k),
                             root=(0.06 * k, 0.0), description=f"{strength} blow from the left: head turned away to the right"))  # fmt: skip
        peak = g.but(lean_side=-9 * k, chest_yaw=30 - 12 * k, head_yaw=-25 - 30 * k, **low_hands)
        out.append(_reaction(f"hit_head_right_{strength}", frames, peak, peak.but(lean_side=-4 * k),
                             root=(-0.06 * k, 0.0), description=f"{strength} blow from the right: head turned away to the left"))  # fmt: skip
        # body: doubles over the blow, hands come down
        body_hands = dict(fist_l=(-0.13, 1.22 - 0.04 * k, 0.22), fist_r=(0.13, 1.20 - 0.04 * k, 0.14))
        peak = g.but(lean_fwd=12 * k, head_pitch=14 * k, pelvis=(0.0, 0.89 - 0.03 * k, -0.04 * k), **body_hands)
        out.append(_reaction(f"hit_body_front_{strength}", frames, peak, peak.but(lean_fwd=8 * k),
                             root=(0.0, -0.05 * k), description=f"{strength} blow to the body: doubles over"))  # fmt: skip
        peak = g.but(lean_fwd=8 * k, lean_side=-8 * k, pelvis=(0.0, 0.89 - 0.02 * k, 0.0),
                     fist_l=(-0.20, 1.12, 0.10), fist_r=(0.12, 1.36, 0.15))  # fmt: skip
        out.append(_reaction(f"hit_body_left_{strength}", frames, peak, peak.but(lean_side=-5 * k),
                             root=(0.05 * k, 0.0), description=f"{strength} blow to the left ribs: folds over them"))  # fmt: skip
        peak = g.but(lean_fwd=8 * k, lean_side=8 * k, pelvis=(0.0, 0.89 - 0.02 * k, 0.0),
                     fist_r=(0.20, 1.10, 0.02), fist_l=(-0.12, 1.38, 0.28))  # fmt: skip
        out.append(_reaction(f"hit_body_right_{strength}", frames, peak, peak.but(lean_side=5 * k),
                             root=(-0.05 * k, 0.0), description=f"{strength} blow to the right ribs: folds over them"))  # fmt: skip
    return out


def knockdown() -> Action:
    """Falls on his back, lies there, sits up, gets up to the guard (2.5 s)."""
    g = GUARD
    parts = ("pelvis", "fist_l", "fist_r", "ankle_l", "ankle_r")
    # poses given relative to the clip start; the root ends 0.30 m back
    root_at = {0: 0.0, 8: -0.08, 20: -0.2, 26: -0.27, 32: -0.3, 44: -0.3, 95: -0.3, 112: -0.3, 127: -0.3, 139: -0.3, 149: -0.3}
    world: dict[int, Pose] = {
        0: g.but(pelvis=(0.0, 0.90, 0.0)),
        8: g.but(lean_fwd=-22, head_pitch=-30, pelvis=(0.0, 0.84, -0.10),
                 fist_l=(-0.32, 1.20, 0.05), fist_r=(0.32, 1.18, -0.05)),
        20: g.but(lean_fwd=-55, head_pitch=-20, hip_yaw=10, chest_yaw=10, pelvis=(0.0, 0.50, -0.32),
                  fist_l=(-0.45, 0.95, -0.40), fist_r=(0.45, 0.95, -0.45),
                  elbow_l=(-1, 0, 0), elbow_r=(1, 0, 0), knee_l=(0, 1, 1), knee_r=(0, 1, 1)),
        32: g.but(lean_fwd=-88, head_pitch=0, head_yaw=0, hip_yaw=0, chest_yaw=0, lean_side=0,
                  pelvis=(0.0, 0.13, -0.55), ankle_l=(-0.18, 0.08, 0.28), ankle_r=(0.18, 0.08, 0.24),
                  fist_l=(-0.60, 0.10, -0.85), fist_r=(0.60, 0.10, -0.85),
                  elbow_l=(-1, 0, 0), elbow_r=(1, 0, 0), knee_l=(0, 1, 0), knee_r=(0, 1, 0)),
    }
    world[26] = g.but(lean_fwd=-75, head_pitch=-10, head_yaw=0, hip_yaw=5, chest_yaw=5,
                      pelvis=(0.0, 0.27, -0.46), ankle_l=(-0.17, 0.08, 0.12), ankle_r=(0.18, 0.08, 0.06),
                      fist_l=(-0.55, 0.45, -0.75), fist_r=(0.55, 0.45, -0.78),
                      elbow_l=(-1, 0, 0), elbow_r=(1, 0, 0), knee_l=(0, 1, 0.5), knee_r=(0, 1, 0.5))  # fmt: skip
    world[44] = world[32].but(fist_l=(-0.58, 0.10, -0.80))
    world[95] = world[32].but(lean_fwd=-84, fist_l=(-0.40, 0.10, -0.45), fist_r=(0.40, 0.10, -0.45))
    world[112] = g.but(lean_fwd=-5, head_pitch=10, head_yaw=0, hip_yaw=0, chest_yaw=0,
                       pelvis=(0.0, 0.14, -0.55), ankle_l=(-0.18, 0.08, -0.10), ankle_r=(0.18, 0.08, -0.12),
                       fist_l=(-0.20, 0.55, -0.25), fist_r=(0.20, 0.55, -0.25),
                       knee_l=(0, 1, 0.5), knee_r=(0, 1, 0.5))  # fmt: skip
    world[127] = g.but(lean_fwd=35, head_pitch=0, pelvis=(0.0, 0.55, -0.35), ankle_l=(-0.15, 0.08, -0.08),
                       ankle_r=(0.17, 0.13, -0.40), fist_l=(-0.18, 0.85, -0.05), fist_r=(0.18, 0.85, -0.12),
                       knee_l=(0, 0.5, 1), knee_r=(0, 0.2, 1))  # fmt: skip
    world[139] = g.but(lean_fwd=14, pelvis=(0.0, 0.82, -0.31), ankle_l=(-0.15, 0.08, -0.08),
                       ankle_r=(0.17, 0.08, -0.52), fist_l=(-0.12, 1.30, 0.0), fist_r=(0.12, 1.28, -0.12))  # fmt: skip
    world[149] = g
    keys = []
    for f, p in sorted(world.items()):
        if f in (0, 149):
            keys.append((f, g))
        else:
            keys.append((f, _in_clip_frame(p, 0.0, root_at[f], parts)))
    root = [(f, 0.0, dz, 0.0) for f, dz in sorted(root_at.items())]
    return _action("knockdown", "reaction", 150, keys, root=root,
                   description="knockdown: falls on his back, lies, sits up and gets back to the guard")  # fmt: skip


def build_library() -> list[Action]:
    return [
        straight_l(), straight_r(), uppercut_l(), uppercut_r(), hook_l(), hook_r(),
        parry_l(), parry_r(), block(), *steps(), guard(), *reactions(), knockdown(),
    ]  # fmt: skip


def write_library(directory: str | Path | None = None, kept: list[Path] | None = None) -> list[Path]:
    """Write every action's JSON to `directory` (default: the shipped game/assets/actions);
    the files written. With `kept`, a file there that holds anything else than what would be
    written (an action someone edited) is left as it is and added to `kept`, not replaced."""
    directory = Path(directory) if directory is not None else default_actions_dir()
    directory.mkdir(parents=True, exist_ok=True)
    written = []
    for a in build_library():
        path = directory / f"{a.name}.json"
        text = json.dumps(a.to_json(), indent=1) + "\n"
        if kept is not None and _differs(path, text):
            kept.append(path)
            continue
        path.write_text(text, encoding="utf-8")
        written.append(path)
    return written


def _differs(path: Path, text: str) -> bool:
    """Whether a file at `path` holds anything other than `text` (not there, or empty: no)."""
    try:
        return path.stat().st_size > 0 and path.read_bytes() != text.encode("utf-8")
    except FileNotFoundError:
        return False


if __name__ == "__main__":
    for p in write_library():
        print(p)
