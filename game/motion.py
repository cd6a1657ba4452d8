"""The player's motion graph: one fat node (the guard) and clip playback.

Every action leaves from and returns to the guard, so the graph has a single node and any
action can follow any other (paper section III, [2]). The recognizer's events drive it:
`start` plays an action from frame 0; `switch` plays the better-matching action from frame
n_p (`from_frame`, Fig. 4) because the player's hand is already n_p frames into that motion;
`end` lets the clip play out (the character completes its action); `reject` aborts a clip that
has only just started.

Jumps between postures (a switch, an interrupted clip) are hidden by offset blending: at the
jump the difference between what was shown and the new clip's posture is remembered and
faded out over `blend_frames` with a smoothstep, so the shown posture is continuous and the
new clip takes over within ~0.1 s. Bone lengths are re-imposed after blending.
"""

from __future__ import annotations

import numpy as np

from game.actions import Action
from game.skeleton import impose_bone_lengths, world_to_local

BLEND_FRAMES = 6
REJECT_ABORT_FRACTION = 0.35  # a rejected motion aborts the clip only while it is this young


class PlayerController:
    """Plays clips of `lib` one 60 Hz step at a time; see the module docstring."""

    def __init__(self, lib: dict[str, Action], blend_frames: int = BLEND_FRAMES):
        if "guard" not in lib:
            raise ValueError("the action library has no 'guard' clip")
        self.lib = lib
        self.blend_frames = max(int(blend_frames), 0)
        self.action = "guard"
        self.frame = 0.0
        self.output = lib["guard"].posture(0)
        self.root_delta = np.zeros(3)  # (dx, dz, dyaw) of the last step, local frame before it
        self.ignored_events = 0
        self._fresh = True
        self._offset: np.ndarray | None = None
        self._blend_step = 0
        self._finished = False
        self._from_event = False
        self.swing = 0  # counts the clips played; a switch keeps it (the same motion, relabelled)

    # ------------------------------------------------------------------ control
    @property
    def clip(self) -> Action:
        return self.lib[self.action]

    @property
    def idle(self) -> bool:
        return self.action == "guard"

    @property
    def phase(self) -> float:
        """How far through the current clip, 0..1 (the guard loop reads 0)."""
        return 0.0 if self.idle else float(self.frame) / max(self.clip.frames - 1, 1)

    def play(self, name: str, from_frame: float = 0, blend: bool = True) -> None:
        """Play `name` from `from_frame` (clamped into the clip), blending from what is shown."""
        if name not in self.lib:
            raise KeyError(f"no action {name!r} in the library")
        clip = self.lib[name]
        from_frame = min(max(float(from_frame), 0.0), clip.frames - 1.0)
        target = clip.posture(from_frame)
        if blend and self.blend_frames:
            self._offset = self.output - target
            self._blend_step = 0
        else:
            self._offset = None
        self.action, self.frame, self._fresh = name, from_frame, True
        self._from_event = False
        self.swing += 1

    def on_event(self, event: dict) -> None:
        """Apply one recognizer event (docs/formats.md keys)."""
        kind = event.get("event")
        name = event.get("action")
        if kind in ("start", "switch"):
            if name not in self.lib:
                self.ignored_events += 1
                return
            swing = self.swing
            self.play(name, event.get("from_frame", 0) if kind == "switch" else 0)
            if kind == "switch":  # the motion under way, better named: a hand it landed stays spent
                self.swing = swing
            self._from_event = True
        elif kind == "reject":
            # a started motion's reject is its call-off: the recognizer has ended it already, so
            # the aborted clip owes it no `character_finished()` (nothing left to end or discard)
            young = self.phase < REJECT_ABORT_FRACTION
            if self._from_event and not self.idle and young:
                self.play("guard")
        elif kind != "end":  # end: the character completes its clip
            self.ignored_events += 1

    # ------------------------------------------------------------------ playback
    def step(self) -> np.ndarray:
        """Advance one 60 Hz frame; the (17, 3) local reference posture to show."""
        self._finished = False
        clip = self.clip
        self.root_delta = np.zeros(3)
        if self._fresh:
            self._fresh = False
        else:
            f0 = self.frame
            f1 = f0 + 1.0
            if clip.loop:
                if f1 >= clip.frames - 1:
                    f1 -= clip.frames - 1
            elif f1 >= clip.frames - 1:
                f1 = clip.frames - 1.0
            if f1 > f0:  # no root motion across a loop's wrap or past a clip's last frame
                self.root_delta = _root_delta(clip, f0, f1)
            self.frame = f1
        posture = clip.posture(self.frame)
        if not clip.loop and self.frame >= clip.frames - 1:
            # back at the guard: the fat node; the guard loop continues seamlessly
            self._finished = True
            self.action, self.frame = "guard", 0.0
        if self._offset is not None:
            self._blend_step += 1
            t = min(self._blend_step / max(self.blend_frames, 1), 1.0)
            w = 1.0 - t * t * (3.0 - 2.0 * t)
            posture = impose_bone_lengths(posture + self._offset * w)
            if t >= 1.0:
                self._offset = None
        self.output = posture
        return posture

    def finished_action(self) -> bool:
        """True on the step a clip returned to the guard (tell the recognizer then)."""
        return self._finished


def _root_delta(clip: Action, f0: float, f1: float) -> np.ndarray:
    """Root motion between clip frames f0 and f1, in the boxer's local frame at f0."""
    a, b = clip.root_offset(f0), clip.root_offset(f1)
    d = b - a
    # clip-start frame -> local frame at f0: undo the yaw turned so far (the inverse of
    # compose_root's rotation, which places this delta back in the world)
    local = world_to_local(np.array([d[0], 0.0, d[1]]), (0.0, 0.0, a[2]))
    return np.array([local[0], local[2], d[2]])
