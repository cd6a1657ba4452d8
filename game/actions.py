"""The action library: boxing clips loaded from JSON (game/assets/actions/*.json).

An action is data: keyframes of the 17 joint positions in the boxer's local frame, a root
track (dx, dz, dyaw) for footwork, the windows in which a fist is a weapon (AttackWindow) and
in which a guard covers the head or body (GuardWindow). Every clip starts and ends at the
guard posture (the paper's fat node), so any action can follow any other.

Playback: keyframes are joined by cubic Hermite (Catmull-Rom) curves with zero velocity at the
clip's ends, sampled once per 60 Hz frame at load time; `posture(f)` at a fractional frame
interpolates that table and re-imposes the bone lengths from the pelvis outwards (forward
kinematics along the interpolated bone directions), so limbs never stretch.
"""

from __future__ import annotations

import json
import os
import stat
import unicodedata
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path

import numpy as np

from engine.clock import STEP_HZ
from engine.errors import InputError
from game.skeleton import JOINTS, impose_bone_lengths, joint_index

ACTION_NAMES: tuple[str, ...] = (
    "straight_l", "straight_r", "uppercut_l", "uppercut_r", "hook_l", "hook_r",
    "parry_l", "parry_r", "block", "step_forward", "step_back", "step_left", "step_right",
)  # fmt: skip

KINDS = ("attack", "defense", "step", "reaction", "idle")
FPS = STEP_HZ  # clips hold one frame per step
MAX_FRAMES = 3600  # one minute: the longest shipped action is under 2 s
MAX_FILE_BYTES = 16 * 2**20  # an action file is ~10 KB
# Joint positions and root motion in metres: the shipped poses stay within 1.7 m of the root, a
# step moves it 0.3 m. Past these, a value is no pose but overflow waiting to happen (1e308 loaded,
# and the contact sheet's projection overflowed).
MAX_POSE_M = 10.0
MAX_ROOT_M = 100.0

# Hit reactions: hit_<where>_<side>_<strength>; side is where the blow comes FROM as seen by
# the boxer who is hit (a right hook from the opponent lands on the left: "left").
REACTION_WHERE = ("head", "body")
GUARD_KINDS = ("block", "parry")  # GuardWindow.kind
REACTION_SIDES = ("left", "right", "front")
REACTION_STRENGTHS = ("light", "heavy")
REACTION_NAMES: tuple[str, ...] = tuple(
    f"hit_{w}_{s}_{h}" for w in REACTION_WHERE for s in REACTION_SIDES for h in REACTION_STRENGTHS
)
HEAVY_HIT_SPEED = 5.0  # m/s closing speed from which a blow staggers rather than stings


NAME_MAX_CHARS = 64


class ActionError(InputError):
    """An action file that cannot be loaded; the message names the file."""


def name_problem(name: object) -> str | None:
    """Why `name` cannot name an action (None: it can): 1 to NAME_MAX_CHARS letters, digits
    and the marks that go with them (any script's: a player names actions in their own language;
    Hindi and Thai vowels are combining marks, as is the accent of a decomposed é), `_` and `-`,
    as every shipped name. A name is a label in recordings and templates, one of a
    comma-separated `--actions` list and the file name `actions author` writes, so no spaces,
    commas or slashes. The loader and `bvh cut --name` both ask it."""
    if not isinstance(name, str) or not name:
        return f"must be a non-empty string, not {name!r}"
    if len(name) > NAME_MAX_CHARS:
        return f"has {len(name)} characters, at most {NAME_MAX_CHARS}"
    if bad := sorted({ch for ch in name if not (ch.isalnum() or unicodedata.category(ch)[0] == "M" or ch in "_-")}):
        return f"{name!r} may hold only letters, digits, '_' and '-', not {''.join(bad)!r}"
    return None


@dataclass(frozen=True)
class AttackWindow:
    """Frames [start, end] in which `hand`'s fist is a weapon against `targets`."""

    hand: str  # "l" | "r"
    start: int
    end: int
    targets: tuple[str, ...]
    damage: float
    reach: float  # metres from the attacker's own root along +z at full extension

    def active(self, frame: float) -> bool:
        return self.start <= frame <= self.end


@dataclass(frozen=True)
class GuardWindow:
    """Frames [start, end] in which the boxer covers `covers` ("head", "body")."""

    start: int
    end: int
    covers: tuple[str, ...]
    kind: str  # "block" | "parry"

    def active(self, frame: float) -> bool:
        return self.start <= frame <= self.end


@dataclass
class Action:
    """One clip. `table` holds the posture at every integer frame (frames, 17, 3)."""

    name: str
    kind: str
    frames: int
    key_frames: np.ndarray  # (K,) int
    key_poses: np.ndarray  # (K, 17, 3)
    root_keys: np.ndarray  # (R, 4): frame, dx, dz, dyaw
    attacks: list[AttackWindow] = field(default_factory=list)
    guards: list[GuardWindow] = field(default_factory=list)
    loop: bool = False
    description: str = ""
    source: str = ""

    def __post_init__(self) -> None:
        # the curves sampled at every integer frame, once: playback interpolates these tables
        self.table, self.root_table = self.sample(np.arange(self.frames, dtype=np.float64))

    def _lerp(self, table: np.ndarray, f: float) -> np.ndarray:
        f = min(max(float(f), 0.0), self.frames - 1.0)
        i = int(f)
        if i >= self.frames - 1:
            return table[-1].copy()
        t = f - i
        return table[i] * (1.0 - t) + table[i + 1] * t

    def posture(self, f: float) -> np.ndarray:
        """(17, 3) local joint positions at clip frame f (clamped to the clip)."""
        p = self._lerp(self.table, f)
        if float(f) != int(f):
            p = impose_bone_lengths(p)
        return p

    def root_offset(self, f: float) -> np.ndarray:
        """(3,) cumulative (dx, dz, dyaw) by frame f, in the local frame at the clip's start."""
        return self._lerp(self.root_table, f)

    def sample(self, fs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Postures (n, 17, 3) and root offsets (n, 3) at many fractional frames at once,
        straight from the keyframe curves (smooth to the second derivative within segments,
        which the virtual player's accelerations need)."""
        fs = np.clip(np.asarray(fs, dtype=np.float64), 0.0, self.frames - 1.0)
        postures = impose_bone_lengths(_hermite(self.key_frames, self.key_poses, fs))
        if len(self.root_keys) == 0:
            return postures, np.zeros((len(fs), 3))
        return postures, _hermite(self.root_keys[:, 0], self.root_keys[:, 1:], fs)

    def hand_trajectory(self, hand: str) -> np.ndarray:
        """(frames, 3) local fist positions ('l' or 'r')."""
        return self.table[:, joint_index(f"fist_{hand}")].copy()

    def attack_at(self, frame: float, hand: str | None = None) -> AttackWindow | None:
        for w in self.attacks:
            if w.active(frame) and (hand is None or w.hand == hand):
                return w
        return None

    def guard_at(self, frame: float, target: str | None = None) -> GuardWindow | None:
        for g in self.guards:
            if g.active(frame) and (target is None or target in g.covers):
                return g
        return None

    def to_json(self) -> dict:
        return {
            "name": self.name,
            "kind": self.kind,
            "frames": self.frames,
            "fps": FPS,
            "loop": self.loop,
            "description": self.description,
            "joints": list(JOINTS),
            "keyframes": [
                {"frame": int(k), "pose": np.round(p, 4).tolist()}
                for k, p in zip(self.key_frames, self.key_poses, strict=True)
            ],
            "root": np.round(self.root_keys, 4).tolist(),
            "attacks": [
                {"hand": w.hand, "start": w.start, "end": w.end, "targets": list(w.targets),
                 "damage": w.damage, "reach": round(w.reach, 3)}
                for w in self.attacks
            ],  # fmt: skip
            "guards": [
                {"start": g.start, "end": g.end, "covers": list(g.covers), "kind": g.kind}
                for g in self.guards
            ],
        }


def _hermite(keys: np.ndarray, values: np.ndarray, at: np.ndarray) -> np.ndarray:
    """Cubic Hermite through (keys, values) with Catmull-Rom tangents, zero at both ends (the
    clip leaves and returns to the guard at rest). keys must increase."""
    keys = np.asarray(keys, dtype=np.float64)
    values = np.asarray(values, dtype=np.float64)
    if len(keys) == 1:
        return np.repeat(values[:1], len(at), axis=0)
    tangents = np.zeros_like(values)
    if len(keys) > 2:
        span = (keys[2:] - keys[:-2]).reshape((-1,) + (1,) * (values.ndim - 1))
        tangents[1:-1] = (values[2:] - values[:-2]) / span
    seg = np.clip(np.searchsorted(keys, at, side="right") - 1, 0, len(keys) - 2)
    k0, k1 = keys[seg], keys[seg + 1]
    h = k1 - k0
    t = np.clip((at - k0) / h, 0.0, 1.0)
    shape = (-1,) + (1,) * (values.ndim - 1)
    t, h = t.reshape(shape), h.reshape(shape)
    t2, t3 = t * t, t * t * t
    h00, h10 = 2 * t3 - 3 * t2 + 1, t3 - 2 * t2 + t
    h01, h11 = -2 * t3 + 3 * t2, t3 - t2
    return (
        h00 * values[seg] + h10 * h * tangents[seg] + h01 * values[seg + 1] + h11 * h * tangents[seg + 1]
    )


def action_from_json(data: dict, source: str = "") -> Action:
    """Build an Action from its JSON object; raises ActionError naming `source` when malformed."""
    if not isinstance(data, dict):
        raise ActionError(f"{source or '?'}: not an action (expected a JSON object, not {type(data).__name__})")
    where = source or data.get("name", "?")
    try:
        if why := name_problem(data["name"]):
            raise ActionError(f"{where}: name {why}")
        joints = data.get("joints", list(JOINTS))
        if list(joints) != list(JOINTS):
            raise ActionError(f"{where}: joints must be {', '.join(JOINTS)}")
        kind = data["kind"]
        if kind not in KINDS:
            raise ActionError(f"{where}: kind {kind!r} is not one of {', '.join(KINDS)}")
        frames = int(data["frames"])
        keys = data["keyframes"]
        key_frames = np.array([int(k["frame"]) for k in keys])
        key_poses = np.array([k["pose"] for k in keys], dtype=np.float64)
        if key_poses.shape[1:] != (len(JOINTS), 3) or not np.all(np.isfinite(key_poses)):
            raise ActionError(f"{where}: every keyframe pose must be {len(JOINTS)} finite [x, y, z]")
        if frames > MAX_FRAMES:
            raise ActionError(f"{where}: {frames} frames, at most {MAX_FRAMES}")
        if frames < 2 or key_frames[0] != 0 or key_frames[-1] != frames - 1 or np.any(np.diff(key_frames) <= 0):
            raise ActionError(f"{where}: keyframes must increase from frame 0 to frames-1 ({frames - 1})")
        root = np.array(data.get("root", []), dtype=np.float64).reshape(-1, 4)
        attacks = [
            AttackWindow(a["hand"], int(a["start"]), int(a["end"]), tuple(a["targets"]),
                         float(a["damage"]), float(a["reach"]))
            for a in data.get("attacks", [])
        ]  # fmt: skip
        guards = [
            GuardWindow(int(g["start"]), int(g["end"]), tuple(g["covers"]), g["kind"])
            for g in data.get("guards", [])
        ]
        if not (np.isfinite(root).all() and all(np.isfinite([w.damage, w.reach]).all() for w in attacks)):
            raise ActionError(f"{where}: root keys, damage and reach must be finite numbers")
        if np.abs(key_poses).max() > MAX_POSE_M or (len(root) and np.abs(root[:, 1:]).max() > MAX_ROOT_M):
            raise ActionError(f"{where}: poses must lie within {MAX_POSE_M:g} m and root keys within {MAX_ROOT_M:g} m")
        if data.get("fps", FPS) != FPS:
            raise ActionError(f"{where}: fps must be {FPS} (clips play one frame a step), not {data['fps']!r}")
        _check_windows(where, attacks, guards, frames)
        return Action(
            name=data["name"], kind=kind, frames=frames, key_frames=key_frames,
            key_poses=key_poses, root_keys=root, attacks=attacks, guards=guards,
            loop=bool(data.get("loop", False)), description=data.get("description", ""),
            source=source,
        )  # fmt: skip
    except ActionError:
        raise
    except (KeyError, TypeError, ValueError, IndexError, OverflowError) as exc:  # OverflowError: int(Infinity)
        raise ActionError(f"{where}: malformed action ({type(exc).__name__}: {exc})") from None


def _check_windows(where: str, attacks: list[AttackWindow], guards: list[GuardWindow], frames: int) -> None:
    """Attack and guard windows the referee can score: inside the clip, on a head or a body, a
    block or a parry, no negative damage or reach; else an ActionError naming `where`."""
    for w in attacks:
        if w.hand not in ("l", "r") or not 0 <= w.start <= w.end < frames or w.damage < 0 or w.reach < 0 \
                or not w.targets or not set(w.targets) <= set(REACTION_WHERE):
            raise ActionError(f"{where}: bad attack window {w} (hand l or r, frames inside the clip, "
                              f"targets of {', '.join(REACTION_WHERE)}, damage and reach >= 0)")
    for g in guards:
        if g.kind not in GUARD_KINDS or not 0 <= g.start <= g.end < frames or not g.covers \
                or not set(g.covers) <= set(REACTION_WHERE):
            raise ActionError(f"{where}: bad guard window {g} (kind {' or '.join(GUARD_KINDS)}, frames inside "
                              f"the clip, covers of {', '.join(REACTION_WHERE)})")


def load_action(path: str | Path) -> Action:
    path = Path(path)
    try:
        st = os.stat(path)
        if not stat.S_ISREG(st.st_mode) or st.st_size > MAX_FILE_BYTES:
            raise ActionError(f"{path}: cannot read action (not a regular file of at most {MAX_FILE_BYTES // 2**20} MiB)")
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError, RecursionError, ValueError) as exc:
        raise ActionError(f"{path}: cannot read action ({type(exc).__name__}: {exc})") from None
    return action_from_json(data, str(path))


def default_actions_dir() -> Path:
    return Path(str(resources.files("game") / "assets" / "actions"))


_CACHE: dict[str, dict[str, Action]] = {}


def load_library(directory: str | Path | None = None) -> dict[str, Action]:
    """Every action under `directory` (default: the shipped game/assets/actions), by name.
    The shipped library is parsed once per process; callers get their own dict."""
    directory = Path(directory) if directory is not None else default_actions_dir()
    key = str(directory.resolve())
    if key not in _CACHE:
        files = sorted(directory.glob("*.json"))
        if not files:
            raise ActionError(f"{directory}: no action files (*.json)")
        lib = {}
        for f in files:
            a = load_action(f)
            if a.name in lib:  # the later file in name order replaced the other one, unsaid
                raise ActionError(f"{f}: action {a.name!r} is also {lib[a.name].source}; one file per action")
            lib[a.name] = a
        missing = [n for n in (*ACTION_NAMES, "guard") if n not in lib]
        if missing:
            raise ActionError(f"{directory}: missing action(s) {', '.join(missing)}")
        _CACHE[key] = lib
    return dict(_CACHE[key])


def reaction_name(target: str, side: str, heavy: bool) -> str:
    """The hit reaction for a blow on `target` ("head"|"body") coming from `side`
    ("left"|"right"|"front"), light or heavy."""
    return f"hit_{target}_{side}_{'heavy' if heavy else 'light'}"


def reaction_for(target: str, direction_local: np.ndarray, speed: float) -> str:
    """Pick the reaction for a hit: `direction_local` is the blow's direction of travel in the
    hit boxer's local frame (a blow travelling towards -z came from the front; one travelling
    towards +x, the boxer's right, came from the left)."""
    d = np.asarray(direction_local, dtype=np.float64)
    if abs(d[0]) > abs(d[2]) * 0.8:
        side = "left" if d[0] > 0 else "right"
    else:
        side = "front"
    return reaction_name(target if target in REACTION_WHERE else "body", side, speed >= HEAVY_HIT_SPEED)
