"""BVH motion capture: import (any hierarchy, any channel order), retarget onto our skeleton,
cut actions from it, and export played motion so Blender opens it.

Import runs forward kinematics over every frame at once: a joint's local transform is its
OFFSET plus any position channels, rotated by its rotation channels composed in the order they
are listed (BVH's convention: v_parent = R_ch1 R_ch2 R_ch3 v_child). A name table maps the
source's joints onto our 17 (Character Creator `CC_Base_*`, CMU/Motionbuilder and Mixamo
names). Retargeting scales the performer to our leg length, mirrors BVH's right-handed axes
into our frame (+x is the boxer's right), takes the root (x, z, yaw) from the pelvis and hips,
and re-imposes our bone lengths along the source's bone directions.

Export writes our skeleton: the pelvis carries position and rotation, every other joint
rotations (ZXY), computed from joint positions as the smallest rotation that points each bone
where it goes. Children of the pelvis and the chest hang from zero-length helper joints so
every bone can point independently and an export -> import round trip gives the positions
back.
"""

from __future__ import annotations

import io
import os
import warnings
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import TextIO

import numpy as np

from engine.clock import STEP_HZ
from engine.errors import InputError, not_a_regular_file
from game.actions import FPS, Action
from game.hits import Hit
from game.skeleton import (
    BONE_LENGTHS,
    BONES,
    JOINTS,
    PARENTS,
    impose_bone_lengths,
    joint_index,
    local_to_world,
    world_to_local,
)

# What a BVH file may hold; beyond these it is refused with a message, not resampled into
# gigabytes or exported as NaN poses.
MAX_FILE_BYTES = 256 * 2**20
MIN_FRAME_TIME, MAX_FRAME_TIME = 1e-4, 1.0  # 10 kHz to 1 Hz
MAX_DURATION_S = 4 * 3600.0
MAX_VALUE = 1e6  # |channel or offset value|: centimetres or degrees
MAX_JOINTS = 10_000  # a rig with fingers and a face has a few hundred
MAX_LINE_CHARS = 1 << 20  # a motion line of 300 joints is some 20 KB


class BVHError(InputError):
    """A BVH file that cannot be read; the message names the file and line."""


@dataclass
class BVHJoint:
    name: str
    parent: int
    offset: np.ndarray  # (3,)
    channels: list[str]
    end_site: np.ndarray | None = None


@dataclass
class BVH:
    joints: list[BVHJoint]
    motion: np.ndarray  # (frames, total channels)
    frame_time: float
    path: str = ""

    @property
    def frames(self) -> int:
        return len(self.motion)

    def index(self, name: str) -> int:
        for i, j in enumerate(self.joints):
            if j.name == name:
                return i
        raise KeyError(name)

    def global_positions(self) -> np.ndarray:
        """(frames, joints, 3) world positions of every joint, in the file's units and axes."""
        return forward_kinematics(self)[0]


# ------------------------------------------------------------------------------ reading


def read_bvh(path: str | os.PathLike, mappable: bool = False) -> BVH:
    """A BVH file. With `mappable`, a hierarchy without a joint for one of ours (map_joints) is
    refused before the motion is read: `bvh info` and `bvh cut` need every one."""
    path = Path(path)
    try:
        st = os.stat(path)
        if why := not_a_regular_file(st):
            raise BVHError(f"{path}: cannot read: {why}")
        if st.st_size > MAX_FILE_BYTES:
            raise BVHError(f"{path}: {st.st_size / 2**20:.0f} MiB is over the {MAX_FILE_BYTES // 2**20} MiB limit for a BVH file")
        with open(path, encoding="utf-8", errors="replace") as f:
            return _parse(f, str(path), mappable)
    except OSError as exc:
        raise BVHError(f"{path}: cannot read ({exc})") from None


def parse_bvh(text: str, name: str = "<bvh>", mappable: bool = False) -> BVH:
    return _parse(io.StringIO(text, newline=None), name, mappable)


def _parse(f: TextIO, name: str, mappable: bool) -> BVH:
    """Streams the file: the hierarchy line by line, then the motion straight into one array
    (the whole text split into lines and Python floats took 37 times the file's size)."""
    lines = enumerate(_lines(f, name))
    h = _Hierarchy(name)
    for i, line in lines:
        tok = line.split()
        if tok and not h.feed(tok, i):
            break  # MOTION
    else:
        i = None  # the file ended first
    if not h.joints:
        raise BVHError(f"{name}: no HIERARCHY joints")
    if i is None:
        raise BVHError(f"{name}: no MOTION section")
    if not all((np.abs(j.offset) <= MAX_VALUE).all() and (j.end_site is None or (np.abs(j.end_site) <= MAX_VALUE).all())
               for j in h.joints):
        raise BVHError(f"{name}: an OFFSET that is not a finite number up to {MAX_VALUE:g}")
    if mappable:
        map_joints(BVH(h.joints, np.empty((0, 0)), 1.0, name))
    frames, frame_time = _motion_header(lines, name)
    total = sum(len(j.channels) for j in h.joints)
    motion = _motion_values((line for _, line in lines), frames, total, name)
    return BVH(h.joints, motion, frame_time, name)


def _lines(f: TextIO, name: str) -> Iterator[str]:
    """The file's lines, refusing a huge one: splitting a line of 100 MB takes gigabytes."""
    while line := f.readline(MAX_LINE_CHARS + 1):
        if len(line) > MAX_LINE_CHARS:
            raise BVHError(f"{name}: a line of over {MAX_LINE_CHARS} characters")
        yield line


class _Hierarchy:
    """The HIERARCHY section read line by line: joints, their offsets and channels."""

    def __init__(self, name: str):
        self.name = name
        self.joints: list[BVHJoint] = []
        self.stack: list[int] = []
        self.pending: int | None = None  # joint whose '{' we expect
        self.in_end = False
        self.end_owner = -1

    def fail(self, msg: str, line: int) -> BVHError:
        return BVHError(f"{self.name}:{line + 1}: {msg}")

    def feed(self, tok: list[str], i: int) -> bool:
        """Take one non-empty line's tokens; False at MOTION (the hierarchy ends)."""
        key = tok[0].upper()
        if key == "HIERARCHY":
            pass
        elif key in ("ROOT", "JOINT"):
            self._joint(key, tok, i)
        elif key == "END":
            self.in_end, self.end_owner = True, self.stack[-1] if self.stack else -1
            if self.end_owner < 0:  # its OFFSET would go to joints[-1] or [-2]: none, or not its own
                raise self.fail("End Site outside a joint", i)
        elif key == "{":
            self._open(i)
        elif key == "}":
            if not self.stack:
                raise self.fail("unbalanced '}'", i)
            if self.stack.pop() == -2:
                self.in_end = False
        elif key == "OFFSET":
            self._offset(tok, i)
        elif key == "CHANNELS":
            self._channels(tok, i)
        elif key == "MOTION":
            return False
        else:
            raise self.fail(f"unexpected {tok[0]!r} in the hierarchy", i)
        return True

    def _joint(self, key: str, tok: list[str], i: int) -> None:
        if len(tok) < 2:
            raise self.fail(f"{key} without a name", i)
        if len(self.joints) >= MAX_JOINTS:  # 36 MB of 'JOINT b { }' lines took 1.4 GB
            raise self.fail(f"over {MAX_JOINTS} joints", i)
        parent = self.stack[-1] if self.stack else -1
        if key == "JOINT" and parent < 0:
            raise self.fail("JOINT outside a ROOT", i)
        self.joints.append(BVHJoint(" ".join(tok[1:]), parent, np.zeros(3), []))
        self.pending = len(self.joints) - 1

    def _open(self, i: int) -> None:
        if self.in_end:
            self.stack.append(-2)
        elif self.pending is not None:
            self.stack.append(self.pending)
            self.pending = None
        else:
            raise self.fail("unexpected '{'", i)

    def _offset(self, tok: list[str], i: int) -> None:
        try:
            off = np.array([float(v) for v in tok[1:4]])
        except ValueError:
            raise self.fail("OFFSET needs 3 numbers", i) from None
        if len(off) != 3:
            raise self.fail("OFFSET needs 3 numbers", i)
        if self.in_end:
            self.joints[self.end_owner].end_site = off
        elif self.stack:
            self.joints[self.stack[-1]].offset = off

    def _channels(self, tok: list[str], i: int) -> None:
        try:
            n = int(tok[1])
        except (IndexError, ValueError):
            raise self.fail("CHANNELS needs a count", i) from None
        chans = tok[2 : 2 + n]
        if len(chans) != n or not self.stack or self.stack[-1] < 0:
            raise self.fail("bad CHANNELS line", i)
        for c in chans:
            if c.lower() not in _CHANNELS:
                raise self.fail(f"unknown channel {c!r}", i)
        self.joints[self.stack[-1]].channels = [c.lower() for c in chans]


def _motion_header(lines: Iterator[tuple[int, str]], name: str) -> tuple[int, float]:
    """'Frames:' and 'Frame Time:', the next lines of `lines` (numbered), checked."""
    frames = frame_time = None
    for i, line in lines:
        t = line.strip()
        try:
            if t.lower().startswith("frames:"):
                frames = int(t.split(":", 1)[1])
            elif t.lower().startswith("frame time:"):
                frame_time = float(t.split(":", 1)[1])
            elif t:
                raise BVHError(f"{name}:{i + 1}: expected 'Frames:' and 'Frame Time:'")
        except ValueError:
            raise BVHError(f"{name}:{i + 1}: {t[:40]!r} is not a number") from None
        if frames is not None and frame_time is not None:
            break
    if frames is None or frame_time is None:
        raise BVHError(f"{name}: missing 'Frames:'/'Frame Time:'")
    if frames < 1:
        raise BVHError(f"{name}: 'Frames: {frames}' (at least 1)")
    if not MIN_FRAME_TIME <= frame_time <= MAX_FRAME_TIME:  # also refuses nan
        raise BVHError(f"{name}: 'Frame Time: {frame_time}' (from {MIN_FRAME_TIME} to {MAX_FRAME_TIME} s)")
    if frames * frame_time > MAX_DURATION_S:
        raise BVHError(f"{name}: {frames * frame_time:.6g} s of motion, over the {MAX_DURATION_S / 3600:g} h limit")
    return frames, frame_time


def _motion_values(lines: Iterator[str], frames: int, total: int, name: str) -> np.ndarray:
    """The first `frames` non-blank motion lines as a (frames, total) array, each a finite value
    up to MAX_VALUE. numpy's parser grows the array as rows come: memory is the numbers', not
    what `frames` announces."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # loadtxt's notes on skipped blank lines and on no data
        try:
            motion = np.loadtxt(lines, dtype=np.float64, comments=None, ndmin=2, max_rows=frames)
        except ValueError:  # a field that is not a number, or a row of another length
            raise BVHError(f"{name}: a motion line is not {total} numbers") from None
    if len(motion) < frames:
        raise BVHError(f"{name}: {frames} frames announced, {len(motion)} found")
    if motion.shape[1] != total:
        raise BVHError(f"{name}: motion lines need {total} values each")
    if not (motion.max() <= MAX_VALUE and motion.min() >= -MAX_VALUE):  # nan too; no copy made
        np.abs(motion, out=motion)  # refused: its values are not needed any more
        row = int(np.argmin((motion <= MAX_VALUE).all(axis=1)))
        raise BVHError(f"{name}: motion frame {row} has a value that is not a finite number up to {MAX_VALUE:g}")
    return motion


_CHANNELS = {"xposition", "yposition", "zposition", "xrotation", "yrotation", "zrotation"}


def _axis_rotation(axis: str, deg: np.ndarray) -> np.ndarray:
    a = np.radians(deg)
    c, s = np.cos(a), np.sin(a)
    o, z = np.ones_like(a), np.zeros_like(a)
    if axis == "x":
        m = [[o, z, z], [z, c, -s], [z, s, c]]
    elif axis == "y":
        m = [[c, z, s], [z, o, z], [-s, z, c]]
    else:
        m = [[c, -s, z], [s, c, z], [z, z, o]]
    return np.moveaxis(np.array(m), (0, 1), (-2, -1))


def forward_kinematics(bvh: BVH) -> tuple[np.ndarray, np.ndarray]:
    """World positions (frames, J, 3) and rotations (frames, J, 3, 3) of every joint."""
    n = bvh.frames
    pos = np.zeros((n, len(bvh.joints), 3))
    rot = np.zeros((n, len(bvh.joints), 3, 3))
    col = 0
    for j, joint in enumerate(bvh.joints):
        t = np.repeat(joint.offset[None], n, 0)
        r = np.repeat(np.eye(3)[None], n, 0)
        for ch in joint.channels:
            v = bvh.motion[:, col]
            col += 1
            if ch.endswith("position"):
                t[:, "xyz".index(ch[0])] += v
            else:
                r = r @ _axis_rotation(ch[0], v)
        if joint.parent < 0:
            pos[:, j], rot[:, j] = t, r
        else:
            p = joint.parent
            pos[:, j] = pos[:, p] + np.einsum("nij,nj->ni", rot[:, p], t)
            rot[:, j] = rot[:, p] @ r
    return pos, rot


# ------------------------------------------------------------------------------ retargeting

# our joint -> names it goes by in common BVH skeletons (first match wins)
NAME_TABLE: dict[str, tuple[str, ...]] = {
    "pelvis": ("CC_Base_Hip", "Hips", "hip", "mixamorig:Hips", "pelvis"),
    "spine": ("CC_Base_Spine01", "Spine", "LowerBack", "abdomen", "mixamorig:Spine", "spine"),
    "chest": ("CC_Base_Spine02", "Spine1", "chest", "mixamorig:Spine2", "Chest"),
    "neck": ("CC_Base_NeckTwist01", "Neck", "neck", "mixamorig:Neck"),
    "head": ("CC_Base_Head", "Head", "head", "mixamorig:Head"),
    "shoulder_l": ("CC_Base_L_Upperarm", "LeftArm", "lShldr", "mixamorig:LeftArm", "shoulder_l"),
    "elbow_l": ("CC_Base_L_Forearm", "LeftForeArm", "lForeArm", "mixamorig:LeftForeArm", "elbow_l"),
    "fist_l": ("CC_Base_L_Hand", "LeftHand", "lHand", "mixamorig:LeftHand", "fist_l"),
    "shoulder_r": ("CC_Base_R_Upperarm", "RightArm", "rShldr", "mixamorig:RightArm", "shoulder_r"),
    "elbow_r": ("CC_Base_R_Forearm", "RightForeArm", "rForeArm", "mixamorig:RightForeArm", "elbow_r"),
    "fist_r": ("CC_Base_R_Hand", "RightHand", "rHand", "mixamorig:RightHand", "fist_r"),
    "hip_l": ("CC_Base_L_Thigh", "LeftUpLeg", "lThigh", "mixamorig:LeftUpLeg", "hip_l"),
    "knee_l": ("CC_Base_L_Calf", "LeftLeg", "lShin", "mixamorig:LeftLeg", "knee_l"),
    "ankle_l": ("CC_Base_L_Foot", "LeftFoot", "lFoot", "mixamorig:LeftFoot", "ankle_l"),
    "hip_r": ("CC_Base_R_Thigh", "RightUpLeg", "rThigh", "mixamorig:RightUpLeg", "hip_r"),
    "knee_r": ("CC_Base_R_Calf", "RightLeg", "rShin", "mixamorig:RightLeg", "knee_r"),
    "ankle_r": ("CC_Base_R_Foot", "RightFoot", "rFoot", "mixamorig:RightFoot", "ankle_r"),
}


def map_joints(bvh: BVH, table: dict[str, tuple[str, ...]] = NAME_TABLE) -> list[int]:
    """For each of our JOINTS, the index of its BVH joint; BVHError lists what is missing."""
    names = {j.name: i for i, j in enumerate(bvh.joints)}
    lower = {j.name.lower(): i for i, j in enumerate(bvh.joints)}
    out, missing = [], []
    for ours in JOINTS:
        hit = next((names[n] for n in table[ours] if n in names), None)
        if hit is None:
            hit = next((lower[n.lower()] for n in table[ours] if n.lower() in lower), None)
        if hit is None:
            missing.append(ours)
        out.append(hit if hit is not None else -1)
    if missing:
        raise BVHError(f"{bvh.path}: no joint for {', '.join(missing)} (see game.bvh.NAME_TABLE)")
    return out


@dataclass
class Retargeted:
    """Motion on our skeleton: local postures (n, 17, 3) and world roots (n, 3) = (x, z, yaw),
    resampled to 60 Hz."""

    postures: np.ndarray
    roots: np.ndarray
    source_positions: np.ndarray  # (n, 17, 3) mapped source joints, metres, our axes, unscaled


def _units_to_metres(pos: np.ndarray) -> float:
    """Guess the unit of (n, 17, 3) mapped positions from the leg length: m, cm, inches, mm."""
    leg = np.linalg.norm(pos[0, joint_index("hip_l")] - pos[0, joint_index("knee_l")])
    leg += np.linalg.norm(pos[0, joint_index("knee_l")] - pos[0, joint_index("ankle_l")])
    for scale in (1.0, 0.01, 0.0254, 0.001):
        if 0.5 < leg * scale < 1.3:
            return scale
    return 1.0 / leg * 0.86


def roots_from_positions(p: np.ndarray) -> np.ndarray:
    """(n, 3) roots (x, z, yaw) from world joint positions in our axes: under the pelvis,
    facing the hips' forward (right x up)."""
    right = p[:, joint_index("hip_r")] - p[:, joint_index("hip_l")]
    right += p[:, joint_index("shoulder_r")] - p[:, joint_index("shoulder_l")]
    fwd = np.cross(right, np.array([0.0, 1.0, 0.0]))
    yaw = np.arctan2(fwd[:, 0], fwd[:, 2])
    pel = p[:, joint_index("pelvis")]
    return np.column_stack([pel[:, 0], pel[:, 2], np.unwrap(yaw)])


def retarget(bvh: BVH, table: dict[str, tuple[str, ...]] = NAME_TABLE) -> Retargeted:
    idx = map_joints(bvh, table)
    pos = bvh.global_positions()[:, idx]
    pos = pos * _units_to_metres(pos)
    pos[..., 0] *= -1.0  # BVH is right-handed with the performer's left at +x; ours has +x right
    source = pos.copy()
    # performer scaled to our leg length, feet on the ground
    ours = BONE_LENGTHS[[_bone("knee_l"), _bone("ankle_l")]].sum()
    theirs = np.median(
        np.linalg.norm(pos[:, joint_index("hip_l")] - pos[:, joint_index("knee_l")], axis=-1)
        + np.linalg.norm(pos[:, joint_index("knee_l")] - pos[:, joint_index("ankle_l")], axis=-1)
    )
    if not theirs > 1e-9 or not np.isfinite(theirs):
        raise BVHError(f"{bvh.path}: the legs have no length (every OFFSET zero?)")
    pos = pos * (ours / theirs)
    # resample to 60 Hz
    src_t = np.arange(bvh.frames) * bvh.frame_time
    n = max(int(np.floor(src_t[-1] * FPS)) + 1, 1)
    t = np.arange(n) / FPS
    flat = pos.reshape(bvh.frames, -1)
    pos = np.stack([np.interp(t, src_t, flat[:, k]) for k in range(flat.shape[1])], axis=1).reshape(n, 17, 3)
    roots = roots_from_positions(pos)
    local = np.stack([world_to_local(p, tuple(r)) for p, r in zip(pos, roots, strict=True)])
    # ankle joints sit ~8 cm up: put the lower foot of the first frame there
    lift = 0.08 - local[0, [joint_index("ankle_l"), joint_index("ankle_r")], 1].min()
    local[..., 1] += lift
    if not (np.isfinite(local).all() and np.isfinite(roots).all()):
        raise BVHError(f"{bvh.path}: retargeting gives non-finite positions (a degenerate skeleton?)")
    return Retargeted(impose_bone_lengths(local), roots, source)


def _bone(child: str) -> int:
    return int(np.nonzero(BONES[:, 1] == joint_index(child))[0][0])


def cut_action(
    motion: Retargeted,
    start: int,
    end: int,
    name: str,
    kind: str = "attack",
    guard: np.ndarray | None = None,
    blend_frames: int = 8,
    key_every: int = 2,
) -> Action:
    """An Action from 60 Hz frames [start, end] of retargeted motion. Its root track is the
    motion of the root relative to the cut's first frame; with `guard`, the first and last
    `blend_frames` are blended into the guard so the action leaves and returns to the fat node."""
    if not 0 <= start < end < len(motion.postures):
        raise InputError(f"frame range {start}..{end} is empty or outside the motion (0..{len(motion.postures) - 1})")
    post = motion.postures[start : end + 1].copy()
    frames = len(post)
    if guard is not None:
        b = min(blend_frames, frames // 2)
        w = np.ones(frames)
        ramp = np.linspace(0.0, 1.0, b + 1)[1:]
        ramp = ramp * ramp * (3 - 2 * ramp)
        w[:b] = np.concatenate([[0.0], ramp[:-1]])[:b]
        w[frames - b :] = w[:b][::-1]
        post = impose_bone_lengths(guard[None] * (1 - w[:, None, None]) + post * w[:, None, None])
    r0 = motion.roots[start]
    roots = motion.roots[start : end + 1]
    d = roots[:, :2] - r0[:2]
    c, s = np.cos(r0[2]), np.sin(r0[2])
    rel = np.column_stack([c * d[:, 0] - s * d[:, 1], s * d[:, 0] + c * d[:, 1], roots[:, 2] - r0[2]])
    keys = sorted(set(range(0, frames, key_every)) | {frames - 1})
    return Action(name, kind, frames, np.array(keys), post[keys],
                  np.column_stack([np.array(keys, float), rel[keys]]), source="bvh")  # fmt: skip


# ------------------------------------------------------------------------------ writing

_HELPERS = {"pelvis": ("spine", "hip_l", "hip_r"), "chest": ("neck", "shoulder_l", "shoulder_r")}
EXPORT_ORDER = "ZXY"


def _export_hierarchy(rest: np.ndarray) -> list[tuple[str, int, np.ndarray, int | None]]:
    """(name, parent index in this list, offset, our joint index or None for helpers)."""
    out: list[tuple[str, int, np.ndarray, int | None]] = []
    where: dict[int, int] = {}

    def add(j: int, parent: int) -> None:
        name = JOINTS[j]
        # the root's OFFSET is zero and its position channels absolute: readers that add the
        # channels to the offset (the spec) and readers that take them as absolute (Blender)
        # then agree
        off = rest[j] - rest[PARENTS[j]] if PARENTS[j] >= 0 else np.zeros(3)
        if PARENTS[j] >= 0 and JOINTS[PARENTS[j]] in _HELPERS:
            out.append((f"{JOINTS[PARENTS[j]]}_to_{name}", parent, np.zeros(3), None))
            parent = len(out) - 1
        out.append((name, parent, off, j))
        where[j] = len(out) - 1
        for c in range(len(JOINTS)):
            if PARENTS[c] == j:
                add(c, where[j])

    add(0, -1)
    return out


def _swing(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(n, 3, 3) smallest rotations taking unit vectors a (3,) onto b (n, 3)."""
    a = a / np.linalg.norm(a)
    b = b / np.maximum(np.linalg.norm(b, axis=-1, keepdims=True), 1e-12)
    v = np.cross(a, b)
    c = b @ a
    k = np.zeros((len(b), 3, 3))
    k[:, 0, 1], k[:, 0, 2], k[:, 1, 2] = -v[:, 2], v[:, 1], -v[:, 0]
    k[:, 1, 0], k[:, 2, 0], k[:, 2, 1] = v[:, 2], -v[:, 1], v[:, 0]
    denom = np.where(1.0 + c > 1e-9, 1.0 / (1.0 + c), 0.0)
    r = np.eye(3)[None] + k + (k @ k) * denom[:, None, None]
    flip = 1.0 + c <= 1e-9  # opposite: half turn about any perpendicular
    if np.any(flip):
        perp = np.cross(a, [1.0, 0.0, 0.0])
        if np.linalg.norm(perp) < 1e-6:
            perp = np.cross(a, [0.0, 1.0, 0.0])
        perp /= np.linalg.norm(perp)
        r[flip] = 2.0 * np.outer(perp, perp) - np.eye(3)
    return r


def _euler_zxy(r: np.ndarray) -> np.ndarray:
    """(n, 3) degrees (z, x, y) with R = Rz Rx Ry."""
    x = np.arcsin(np.clip(r[:, 2, 1], -1.0, 1.0))
    z = np.arctan2(-r[:, 0, 1], r[:, 1, 1])
    y = np.arctan2(-r[:, 2, 0], r[:, 2, 2])
    return np.degrees(np.column_stack([z, x, y]))


def _to_bvh_axes(p: np.ndarray) -> np.ndarray:
    """Ours (+x right) -> BVH's right-handed axes (+x the performer's left); also the inverse."""
    q = np.array(p, dtype=np.float64, copy=True)
    q[..., 0] *= -1.0
    return q


def write_bvh(path: str | os.PathLike, positions: np.ndarray, fps: float = FPS, rest: np.ndarray | None = None) -> Path:
    """Write WORLD joint positions (n, 17, 3) in metres as a BVH (centimetres, Y up) with our
    skeleton; `rest` (17, 3) is the rest pose for the offsets (default: the first frame)."""
    pos = _to_bvh_axes(np.asarray(positions, dtype=np.float64)) * 100.0
    n = len(pos)
    rest_pose = _to_bvh_axes(np.asarray(rest if rest is not None else positions[0])) * 100.0
    hier = _export_hierarchy(rest_pose)
    children: dict[int, list[int]] = {i: [] for i in range(len(hier))}
    for i, (_, parent, _, _) in enumerate(hier):
        if parent >= 0:
            children[parent].append(i)
    local = _export_rotations(pos, hier, children)
    lines = ["HIERARCHY"]
    _emit_joint(lines, hier, children, 0, 0)
    cols = [pos[:, 0]]
    for i in range(len(hier)):
        cols.append(_euler_zxy(local[i]))
    data = np.concatenate(cols, axis=1)
    lines += ["MOTION", f"Frames: {n}", f"Frame Time: {1.0 / fps:.6f}"]
    lines += [" ".join(f"{v:.6f}" for v in row) for row in data]
    path = Path(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)  # `bvh export -o new/x.bvh`: made, as every output's folder
        path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    except OSError as exc:  # a full disk: ENOSPC names no file
        raise BVHError(f"{path}: cannot write ({exc.strerror or exc})") from None
    return path


def _export_rotations(pos: np.ndarray, hier: list, children: dict[int, list[int]]) -> np.ndarray:
    """(joints, n, 3, 3) local rotations that pose the export skeleton on `pos`."""
    n = len(pos)
    glob = np.zeros((len(hier), n, 3, 3))
    local = np.zeros((len(hier), n, 3, 3))
    for i, (_, parent, _, _) in enumerate(hier):
        pr = glob[parent] if parent >= 0 else np.repeat(np.eye(3)[None], n, 0)
        kids = children[i]
        if len(kids) == 1:
            local[i] = _aim_at_child(pos, hier, children, i, pr)
        elif len(kids) > 1:
            local[i] = _orient_by_children(pos, hier, children, i, pr)
        else:
            local[i] = np.repeat(np.eye(3)[None], n, 0)
        glob[i] = pr @ local[i]
    return local


def _aim_at_child(pos: np.ndarray, hier: list, children: dict[int, list[int]], i: int, pr: np.ndarray) -> np.ndarray:
    """The swing that points joint i's only bone at its child's position."""
    _, parent, _, j = hier[i]
    kid = children[i][0]
    kj = hier[kid][3]
    if kj is None:  # a helper hangs below: aim at the pelvis/chest's child through it
        kj = hier[children[kid][0]][3]
        off = hier[children[kid][0]][2]
    else:
        off = hier[kid][2]
    me = j if j is not None else hier[parent][3]
    want = np.einsum("nji,nj->ni", pr, pos[:, kj] - pos[:, me])
    return _swing(off, want)


def _orient_by_children(pos: np.ndarray, hier: list, children: dict[int, list[int]], i: int,
                        pr: np.ndarray) -> np.ndarray:
    """The pelvis / chest itself: orient by its children (Kabsch), helpers do the rest."""
    n = len(pos)
    j = hier[i][3]
    offs, wants = [], []
    for kid in children[i]:
        g = children[kid][0]
        offs.append(hier[g][2])
        wants.append(np.einsum("nji,nj->ni", pr, pos[:, hier[g][3]] - pos[:, j]))
    a = np.array(offs)
    b = np.stack(wants, axis=1)
    h = np.einsum("ki,nkj->nij", a, b)
    u, _, vt = np.linalg.svd(h)
    d = np.sign(np.linalg.det(np.swapaxes(vt, 1, 2) @ np.swapaxes(u, 1, 2)))
    fix = np.repeat(np.eye(3)[None], n, 0)
    fix[:, 2, 2] = d
    return np.swapaxes(vt, 1, 2) @ fix @ np.swapaxes(u, 1, 2)


def _emit_joint(lines: list[str], hier: list, children: dict[int, list[int]], i: int, depth: int) -> None:
    """Joint i and its subtree as HIERARCHY lines."""
    order_names = " ".join(f"{a}rotation" for a in EXPORT_ORDER)
    name, parent, off, _ = hier[i]
    pad = "  " * depth
    lines.append(f"{pad}{'ROOT' if parent < 0 else 'JOINT'} {name}")
    lines.append(f"{pad}{{")
    lines.append(f"{pad}  OFFSET {off[0]:.6f} {off[1]:.6f} {off[2]:.6f}")
    if parent < 0:
        lines.append(f"{pad}  CHANNELS 6 Xposition Yposition Zposition {order_names}")
    else:
        lines.append(f"{pad}  CHANNELS 3 {order_names}")
    if children[i]:
        for c in children[i]:
            _emit_joint(lines, hier, children, c, depth + 1)
    else:
        lines.append(f"{pad}  End Site")
        lines.append(f"{pad}  {{")
        lines.append(f"{pad}    OFFSET 0.000000 5.000000 0.000000")
        lines.append(f"{pad}  }}")
    lines.append(f"{pad}}}")


def played_positions(lib: dict[str, Action], names: list[str], root=(0.0, 0.0, 0.0),
                     rest_frames: int = 20) -> np.ndarray:
    """WORLD joint positions (n, 17, 3) of a PlayerController playing `names` one after another
    (each from the guard), root motion applied: what `quickjab bvh export` writes. Each action
    plays its frames; a looping one (the guard), which never returns to the guard, once round."""  # fmt: skip
    from game.motion import PlayerController
    from game.skeleton import compose_root

    pc = PlayerController(lib)
    out = []
    root = tuple(root)
    for _ in range(rest_frames):
        out.append(local_to_world(pc.step(), root))
    for name in names:
        pc.play(name)
        clip, steps = lib[name], 0
        while True:
            posture = pc.step()
            root = compose_root(root, pc.root_delta)
            out.append(local_to_world(posture, root))
            steps += 1
            if pc.finished_action() or (clip.loop and steps >= clip.frames):
                break
    for _ in range(rest_frames):
        out.append(local_to_world(pc.step(), root))
    return np.array(out)


def bvh_positions_ours(bvh: BVH) -> np.ndarray:
    """World positions (n, 17, 3) in metres and our axes of a BVH written by write_bvh."""
    idx = [bvh.index(name) for name in JOINTS]
    return _to_bvh_axes(bvh.global_positions()[:, idx]) / 100.0


class BVHRecorder:
    """Collects the boxers' WORLD joint positions every step of a match and writes one BVH per
    boxer (`match.bvh` -> `match_boxer0.bvh`, `match_boxer1.bvh`; one boxer: `match.bvh`), all
    in the same world frame, so Blender imports them side by side."""

    def __init__(self, fps: float = FPS):
        self.fps = fps
        self.frames: list[np.ndarray] = []
        self.unplayed: tuple[int, ...] = ()  # a bout cut at MAX_BOUT_S: the actions of each boxer never begun

    def add(self, positions_per_boxer: list[np.ndarray]) -> None:
        self.frames.append(np.array([np.asarray(p, dtype=np.float64) for p in positions_per_boxer]))

    def write(self, path: str | os.PathLike, rest: np.ndarray | None = None) -> list[Path]:
        if not self.frames:
            raise InputError(f"{path}: nothing recorded")
        data = np.array(self.frames)  # (n, boxers, 17, 3)
        return [write_bvh(p, data[:, i], self.fps, rest) for i, p in enumerate(boxer_paths(path, data.shape[1]))]


def boxer_paths(path: str | os.PathLike, boxers: int) -> list[Path]:
    """The files BVHRecorder.write writes for `boxers` boxers: `path` itself for one, else
    <stem>_boxer0.bvh, <stem>_boxer1.bvh, ... beside it."""
    path = Path(path)
    if boxers == 1:
        return [path]
    return [path.with_name(f"{path.stem}_boxer{i}{path.suffix or '.bvh'}") for i in range(boxers)]


def is_bvh_head(head: bytes) -> bool:
    """Whether a file's first bytes are a BVH's (its first word HIERARCHY): what a BVH output
    may replace (engine.errors.refuse_other_kind)."""
    return head.removeprefix(b"\xef\xbb\xbf").lstrip().upper().startswith(b"HIERARCHY")


MAX_BOUT_S = 120  # simulate_bout stops a script longer than this (its BVHRecorder's unplayed says what was left)


def simulate_bout(lib: dict[str, Action], player: list[str], opponent: list[str], gap: float = 0.85,
                  rest_frames: int = 20) -> tuple[BVHRecorder, list[Hit]]:
    """Two Boxers in a physics world, `gap` metres apart, each playing its list of actions
    back to back (hits make the struck boxer react); returns the recording and the hits."""  # fmt: skip
    import math

    from engine.physics import World
    from game.boxer import Boxer, hits_from_contacts

    world = World()
    boxers = [Boxer(world, lib, z=-gap / 2, yaw=0.0), Boxer(world, lib, z=gap / 2, yaw=math.pi)]
    queues = [list(player), list(opponent)]
    rec = BVHRecorder()
    hits_all: list[Hit] = []
    idle = 0
    dt = 1.0 / FPS
    while idle < rest_frames or any(queues) or not all(b.controller.idle for b in boxers):
        for b, q in zip(boxers, queues, strict=True):
            if b.controller.idle and q and idle >= rest_frames:
                b.controller.play(q.pop(0))
        for b in boxers:
            b.step(dt)
        hits = hits_from_contacts(world.step(dt), boxers)
        for h in hits:
            if not h.blocked:
                boxers[1 - h.attacker].react(h)
        hits_all += hits
        rec.add([b.joint_positions() for b in boxers])
        idle += 1
        if len(rec.frames) > STEP_HZ * MAX_BOUT_S:  # a runaway script: stop after two minutes
            rec.unplayed = tuple(len(q) for q in queues)  # said by the caller (bvh export)
            break
    for _ in range(rest_frames):
        for b in boxers:
            b.step(dt)
        world.step(dt)
        rec.add([b.joint_positions() for b in boxers])
    return rec, hits_all
