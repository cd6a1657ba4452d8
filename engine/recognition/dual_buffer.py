"""The dual buffer framework (paper IV-A to IV-C) around the incremental DTW.

Per 60 Hz frame (`push`):
- Noise gate (IV-A): a frame is valid when the sum over sensors of |a - g| reaches `noise_g`,
  g being each sensor's gravity, estimated while the sensor is still (and followed slowly
  while the gate is closed; re-estimated from steady readings when a wrong guess, e.g. from
  a first frame taken mid-motion, would otherwise hold the gate open forever).
  `noise_g="auto"` (the default; the paper's 1.0 g is `noise_g=1.0`) learns the gate from the
  sensor's resting noise before the first motion (AUTO_*), a quiet sensor opening at a few
  tenths of a g, a noisy one higher.
- Onset: the first valid frame, back-dated to where the motion left the rest (the frames just
  before it at ONSET_FRACTION of the gate, at most BACKDATE_MAX); from then on every frame
  counts, valid or not, so the main buffer fills `main` frames after the hand started moving.
- Main buffer: when it holds `main` frames, the best template gives the first decision: a
  `start` event. `main="auto"` decides as early as 3 frames when the best action leads the
  runner-up clearly, and waits up to 12 frames when it does not.
- Supplementary buffer (IV-B): up to `supplementary` frames from the onset the DTW keeps
  growing and the decision is refined; a better action (by `switch_margin`) gives a `switch`
  with `from_frame` = n_p, the clip frames the character has already played. The new action
  must be under its rejection threshold unless the current one no longer fits under its own.
- Scoring: while the hand moves the motion may be partial, so a template scores by its best
  prefix (open end, the query's end at least `min_progress` * n frames into it); once the hand
  is quiet, or its reading has stopped changing, the motion has probably ended and the whole
  template must match (closed end).
- Rejection: a decision needs the best template's score under its threshold (learned from the
  spread of the training trials) and the motion to have reached ENERGY_RATIO of the template's
  peak activity over its first ENERGY_FRAMES frames (a wiggle is not a punch; a first decision
  while the activity is still rising needs RISING_RATIO of it). If not, nothing
  starts; the decision may still come later in the supplementary buffer, else the motion is
  `reject`ed when the buffer is full, and that motion ends there (the next frame above the gate
  is a new onset, whether or not the hand came to rest). A started motion that ends without ever reaching
  CALL_OFF_RATIO of its action's peak is called off: `reject` with `called_off`, no `end`.
  A first decision also needs the motion's peak of ||a| - |g|| to reach TURN_RATIO of the
  action's templates' share of it (their gentlest, over their first ENERGY_FRAMES) times the
  motion's peak activity: a turn of the hand (a guard change, a drift) moves the reading away
  from gravity without changing its magnitude, and it starts nothing; the punch after it does.
- Null signal (IV-C): `null_frames` quiet frames in a row `end` the motion; a started motion still
  too short or too weak to be over waits up to PAUSE_FRAMES more quiet frames (a wind-up's pause).
- Return rule: a motion that follows the previous one without the hand resting in between
  (after a `complete` end or a discard that ran out) starts only once it reaches RETURN_RATIO of
  that motion's peak activity, a bar that fades by RETURN_DECAY a frame (probably the return).
- Beyond the paper: the motion also ends (`reason: "complete"`) once the current action's
  template has been matched past `complete_fraction` of its length and the hand has calmed
  down, so punches thrown back to back without a rest start one action each even when no
  character calls `character_finished()`. `complete_fraction=0` keeps the paper's rules.
- Beyond the paper: a decided motion that outlasts the supplementary buffer keeps its DTW
  growing (bounded), for the rules that weigh the whole motion (the `complete` end, the end of
  a motion that outlasted its action, adaptation); the decision itself is the buffer's, as in
  the paper. `extend=False` turns this off.
- Beyond the paper: adaptation to the player. A motion whose whole fits its final action's
  templates better by ADAPT_MARGIN than any other action's (and under the threshold) joins that
  action's templates; the `adapt` (3) most recent per action are kept beside the trained ones,
  across `reset()`, until `forget_adaptation()`. `adapt=0` turns it off. The adopted templates take part in switches and
  the final decision; the first decision takes an adopted template only when no trained one
  fits under its threshold, or when it scores ADOPTED_LEAD lower than the best trained one.
- Relaunch (a double): just after a punch's stop, the hand launching along that punch's launch
  again (RELAUNCH_*) ends the decided motion (`complete`) or the discard; that frame is the next
  motion's onset. Not for actions whose own templates relaunch (a shake). A first decision needs
  GATE_FLOOR x the gate.
- After `character_finished()` (IV-C) frames are discarded until a null signal or until
  `discard_frames` frames have passed, so the hand's return does not launch a new action; past
  `discard_frames`, only once the hand has calmed under DISCARD_HOLD_RATIO of the discarded
  motion's peak activity (at most DISCARD_HOLD x `discard_frames` frames). With two or more
  sensors, the other hand's punch is not that return: a sensor the discarded action barely
  moves that moves past the gate and OTHER_HAND_RATIO of the discarded motion's own peak ends
  the discard (OTHER_HAND_*), and that frame is the next motion's onset (a combo). Beyond the
  paper, the same launch ends a decided motion (`complete`) that has run, since its start, the
  rest of its best template past the main buffer (`_ran_course`): without a character nothing
  else ended a motion the boxer never rested from, and the other hand's punch was lost. And a
  decided motion that the `complete` rule ends while a character still plays its clip goes into
  that discard (HANDOVER_OVER), for an action that has another hand: the punching hand's return
  started that hand's action again just as the other hand's punch came (the game's long hooks).
- Beyond the paper: a decided motion that has lasted as long as its action's longest template, and
  at least `supplementary` frames, ends there (`complete`) whether or not the hand has rested:
  without a character calling `character_finished()` a hand that never rests held one motion open
  for seconds, and every punch thrown in it was lost (`_outlasted`).
- Beyond the paper: with two or more sensors, while one sensor has moved clearly the most since the
  onset (the others' peaks under MOVING_HAND_RATIO of its), no decision (first, switch or final)
  names an action that barely moves it (under OTHER_HAND_SHARE of its templates' activity): the
  DTW weighs both hands' readings alike, and the other hand's tilt could name its action.

Events are dicts with the keys of docs/formats.md ("event", "action", "frame", "t" when the caller
passes it, "from_frame" on switches, "score"), plus estimates of the motion's speed (m/s),
direction (unit vector at the peak speed, in the frame of the sensor that reached it) and peak
gravity-removed acceleration (g).
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from engine.recognition.adaptation import ADAPT_MARGIN, ADAPT_PER_ACTION, Adaptation
from engine.recognition.config import (
    SETTINGS,
    RecognizerConfig,
    RecognizerConfigError,
    check_settings,
    config_or_defaults,
)
from engine.recognition.events import RecognizerEvent
from engine.recognition.features import FrameFeatures
from engine.recognition.gate import (
    AUTO_MAX_G,
    AUTO_MIN_G,
    AUTO_START_G,
    BACKDATE_MAX,
    NoiseGate,
)
from engine.recognition.motion_end import MotionEnd
from engine.recognition.rules import (
    ACTIVE,
    AUTO_MAX_MAIN,
    CLOSED_END,
    DISCARD,
    DISCARD_HOLD,
    DISCARD_HOLD_RATIO,
    ENERGY_RATIO,
    IDLE,
    PAUSE_FRAMES,
    PROGRESS,
    RETURN_DECAY,
    RETURN_RATIO,
    RISING_RATIO,
    UNCHANGED_FRAMES,
    DecisionRules,
)
from engine.recognition.speed import SpeedEstimate
from engine.recognition.template_set import TemplateSet
from engine.recognition.templates import Templates, activity, linear
from engine.recognition.tilt import TILT_DEG

# re-exported: the names tests and tools read from here
__all__ = [
    "ADAPT_MARGIN", "AUTO_MAX_G", "AUTO_MIN_G", "AUTO_START_G", "BACKDATE_MAX", "CLOSED_END",
    "ENERGY_RATIO", "PAUSE_FRAMES", "RETURN_RATIO", "RISING_RATIO", "DualBufferRecognizer",
]


def _check_keywords(settings: dict[str, object]) -> None:
    """The keywords checked as RecognizerConfig checks its fields (numpy scalars as the numbers
    they hold), so `DualBufferRecognizer(t, **kw)` and `from_config` refuse the same values; a
    ValueError naming the setting."""
    try:
        check_settings({k: v.item() if isinstance(v, np.generic) else v for k, v in settings.items()}, "DualBufferRecognizer")
    except RecognizerConfigError as exc:
        raise ValueError(str(exc)) from None


class DualBufferRecognizer(TemplateSet, DecisionRules, MotionEnd, Adaptation):
    """Frames in, action events out (the module docstring's rules). Owns a gate, features and a speed
    estimate; the rules, template set and adaptation are mixins over its one motion state."""

    def __init__(
        self,
        templates: Templates,
        main: int | str = 6,
        supplementary: int = 60,
        noise_g: float | str = "auto",
        null_frames: int = 6,
        discard_frames: int = 20,
        *,
        switch_margin: float = 0.05,
        auto_lead: float = 0.25,
        reject: bool = True,
        dtw_method: str = "auto",
        min_progress: float = PROGRESS,
        complete_fraction: float = 0.9,
        complete_frames: int = 2,
        closed_after: int = 1,
        extend: bool = True,
        adapt: int = ADAPT_PER_ACTION,
        tilt_deg: float = TILT_DEG,
    ):
        if not isinstance(templates, Templates):
            raise TypeError("templates must be a Templates")
        _check_keywords({k: v for k, v in locals().items() if k in SETTINGS})
        self.gate = NoiseGate(noise_g, templates)  # gravity and the gate (IV-A)
        self.templates = templates
        self.main = main
        self.supplementary = int(supplementary)
        self.null_frames = int(null_frames)
        self.discard_frames = int(discard_frames)
        self.switch_margin = float(switch_margin)
        self.auto_lead = float(auto_lead)
        self.reject = bool(reject)
        self.complete_fraction = float(complete_fraction)
        self.complete_frames = int(complete_frames)
        self.closed_after = int(closed_after) if closed_after > 0 else 1 << 30
        self.dim, self.feature = templates.dim, templates.feature
        self.frame_features = FrameFeatures(self.feature, self.dim)  # owns its buffer
        self.speed = SpeedEstimate(self.dim)  # the motion estimates on start and switch events
        self.min_progress = float(min_progress)
        self.window = max(self.supplementary, AUTO_MAX_MAIN if main == "auto" else int(main))
        self.adapt = max(0, int(adapt))  # recent whole motions per action that join the templates (`_adapt`)
        self._dtw_method = dtw_method
        self._build_templates(templates, reject, extend, float(tilt_deg))
        self._motion = np.empty((max(self.window, self._extend_to), self.dim))  # features since the onset
        self._acts = np.empty(len(self._motion))  # the gate's activity since the onset
        self._recent = np.empty((BACKDATE_MAX, self.dim))  # the last idle frames (ring), for back-dating
        self._moved = False  # a motion has started (a `start`) since the recognizer was built
        self._has_character = False  # the caller has called `character_finished()` (HANDOVER_OVER)
        self._handover = False  # the discard began at a `complete` end, not at the clip's end
        self.reset()

    @classmethod
    def from_config(cls, templates: Templates, config: RecognizerConfig | Mapping[str, object] | None = None) -> DualBufferRecognizer:
        """The recognizer `config` describes (None: the defaults; a mapping: settings over them)."""
        return cls(templates, **config_or_defaults(config).kwargs())

    # -- state -------------------------------------------------------------------------------
    def reset(self) -> None:
        """Back to idle, forgetting gravity and any motion in progress."""
        self.state = IDLE
        self.frame = -1
        self.dropped_frames = 0  # frames with a NaN or inf reading: counted and dropped (push)
        self._t: float | None = None
        self.gate.reset()
        self._queued: list[RecognizerEvent] = []
        self._n_recent = 0
        self._after_peak = 0.0  # the previous motion's peak (fading) while the hand has not rested since
        self._idle_quiet = 0  # quiet idle frames in a row
        self._begin_motion_state()

    def _begin_motion_state(self) -> None:
        self.count = 0  # frames in the buffer since the onset
        self.quiet = 0
        self.action: int | None = None  # index into action_names of the current decision
        self.onset_frame = -1
        self.start_frame = -1
        self.pending = False  # past the first decision point with nothing good enough yet
        self.discarded = 0
        self._g0 = None
        self.speed.reset()
        self._peak_act_seen = 0.0
        self._peak_lin = 0.0  # the motion's peak of the gate's `_lin` (see TURN_RATIO)
        self._done = 0
        self._was_closed = False
        self._stopped, self._stop_n = False, 0  # the hand stopped (closed-end scores kept), at query frame n

    @property
    def noise_g(self) -> float:
        """The gate now (g): as given, or learnt from the resting noise when "auto"."""
        return self.gate.noise_g

    @property
    def auto_gate(self) -> bool:
        return self.gate.auto

    @property
    def gravity(self) -> np.ndarray | None:
        """Each sensor's gravity as the gate estimates it (None before the first frame)."""
        return self.gate.gravity

    @property
    def current_action(self) -> str | None:
        return None if self.action is None else self.action_names[self.action]

    def character_finished(self) -> None:
        """The character's clip of the current action ended (IV-C): the rest of this motion
        (the hand coming back) is discarded until a null signal or `discard_frames` frames."""
        self._has_character = True
        if self.state != ACTIVE or self.action is None:
            return
        self._queued.append(self._event("end", self.action_names[self.action], None, reason="character_finished"))
        self._after_peak = self._peak_act_seen
        self._begin_motion_state()
        self.state = DISCARD
        self._handover = False

    # -- the per-frame step ------------------------------------------------------------------
    def push(self, frame: np.ndarray, t: float | None = None) -> list[RecognizerEvent]:
        """Feed one 60 Hz frame of shape (D,); returns the events it decided (often none)."""
        x = np.asarray(frame, dtype=np.float64).reshape(-1)
        if x.shape[0] != self.dim:
            raise ValueError(f"frame has {x.shape[0]} values, the templates have D = {self.dim}")
        self.frame += 1
        self._t = t if t is None or abs(t) < 1e300 else None  # NaN or inf: no time (it is not JSON)
        events, self._queued = self._queued, []
        if not np.isfinite(x).all():  # the method: no fromnumeric wrapper (~1 us a frame)
            self.dropped_frames += 1  # a malformed frame is counted and dropped, not a crash
            return events
        valid = self.gate.step(x, self.state == ACTIVE, self.count >= self.window)
        self._xs, self._act, self._lin = self.gate.xs, self.gate.act, self.gate.lin
        self._relaunch(valid, events)  # a double or the other hand's punch: this frame is an onset
        if self.state == DISCARD:
            self.discarded += 1
            self.quiet = 0 if valid else self.quiet + 1
            self._after_peak = 0.0 if self.quiet >= self.null_frames else max(self._after_peak, self._act)
            ran_out = self.discarded >= self.discard_frames and (
                self._act < DISCARD_HOLD_RATIO * self._after_peak or self.discarded >= DISCARD_HOLD * self.discard_frames
            )
            if self.quiet >= self.null_frames or ran_out:
                self._begin_motion_state()
                self.state = IDLE
            return events
        if self.state == IDLE:
            if not valid:
                self._recent[self._n_recent % BACKDATE_MAX] = x
                self._n_recent += 1
                self._idle_quiet += 1
                self._after_peak *= RETURN_DECAY
                if self._idle_quiet >= self.null_frames:
                    self._after_peak = 0.0
                if self.gate.auto and not self._moved:
                    self.gate.learn(self._act)
                return events
            if not self._open_motion(events):
                return events
        self._step_active(x, valid, events)
        return events

    def _open_motion(self, events: list[RecognizerEvent]) -> bool:
        """A motion starts from the frames before this one already on their way (ONSET_FRACTION),
        replayed oldest first against the current gravity (it follows a slow rise a little); False
        when the motion ended in them (a window shorter than the back-dated frames)."""
        self.state = ACTIVE
        self._idle_quiet = 0
        if self.gate.noise_g != self._cut_gate:
            self._recut()  # the gate learnt since the templates were cut
        self.dtw.reset()
        self._g0 = self.gate.gravity.copy()
        self._g0_list = self._g0.tolist()
        m = min(self._n_recent, BACKDATE_MAX)
        recent = self._recent[(self._n_recent - m + np.arange(m)) % BACKDATE_MAX]
        back = self.gate.backdate(activity(recent, self._g0)) if m else 0
        self.onset_frame = self.frame - back
        xs, act, lin = self._xs, self._act, self._lin
        for r in recent[m - back :]:
            self._xs = r.tolist()
            self._act, self._lin = float(activity(r[None], self._g0)[0]), float(linear(r[None], self._g0)[0])
            self._step_active(r, True, events, backdated=True)
            if self.state != ACTIVE:
                break
        self._xs, self._act, self._lin = xs, act, lin
        self._n_recent = 0
        return self.state == ACTIVE

    def _step_active(self, x: np.ndarray, valid: bool, events: list[RecognizerEvent], backdated: bool = False) -> None:
        self.count += 1
        self.quiet = 0 if valid else self.quiet + 1
        self._peak_act_seen = max(self._peak_act_seen, self._act)
        self._peak_lin = max(self._peak_lin, self._lin)
        self._after_peak *= RETURN_DECAY
        self.speed.track(self._xs, self._g0_list)
        self._track_hands(self._xs)
        complete = False
        in_window = self.count <= self.window
        if in_window or (self.action is not None and self.count <= self._extend_to):
            # While the hand moves, the motion may be partial: open end (the query's end may sit
            # anywhere past min_progress * n in a template). Once it is quiet the motion has
            # probably ended, and the whole template must be matched (closed end); so too once
            # the reading has stopped changing.
            closed = not backdated and (self.gate.unchanged >= UNCHANGED_FRAMES or (not valid and self.quiet >= self.closed_after))
            self.dtw.min_progress = CLOSED_END if closed else self.min_progress
            f = self.frame_features.of(x, self._g0)
            self._acts[self.dtw.n] = self._act
            self._motion[self.dtw.n] = f
            scores = self.dtw.push(f)
            if closed and not self._was_closed:
                # the hand has just stopped: the whole motion so far against whole templates
                self._stop_scores[:] = scores
                self._stop_n = self.dtw.n
                self._stopped = True
            self._was_closed = closed
            if in_window:
                usable = self._first_usable(self._moving_hand(scores)) if self.action is None else self._moving_hand(self._usable(scores))
                self._decide(usable, events)
                complete = self._complete(usable)
        if self.quiet >= self.null_frames and not complete and self._paused():
            return  # a wind-up's pause: the blow may follow
        # A motion rejected at the end of its window ends there, and a decided one that outlasted its
        # action (`_outlasted`), at rest or not: a hand that never rests held it open for seconds.
        rejected = self.action is None and self.count > self.window
        complete = complete or self._outlasted()
        if self.quiet >= self.null_frames or complete or rejected:
            self._end_motion(complete, events)

    def _event(self, kind: str, action: str | None, score: float | None, **flags) -> RecognizerEvent:
        """The event decided now; a start or switch carries the motion estimate and onset so far."""
        return RecognizerEvent.decided(kind, action, self.frame, self._t, score, self.speed, self.onset_frame, **flags)
