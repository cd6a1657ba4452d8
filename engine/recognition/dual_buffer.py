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
  `reject`ed when the buffer is full. A started motion that ends without ever reaching
  CALL_OFF_RATIO of its action's peak is called off: `reject` with `called_off`, no `end`.
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
  growing (bounded); at its end the whole motion is scored against whole templates, and a
  clearly better action becomes the final decision: a `switch` flagged `whole_motion` just
  before `end` (the game has usually finished the clip by then; what it sees within
  `supplementary` frames follows the paper). `extend=False` turns this off.
- Beyond the paper: adaptation to the player. A motion whose whole fits its final action's
  templates better by ADAPT_MARGIN than any other action's (and under the threshold) joins that
  action's templates; the `adapt` (3) most recent per action are kept beside the trained ones,
  across `reset()`, until `forget_adaptation()`. `adapt=0` turns it off. uWave (day-1
  templates, days 2-7): final 89.9 -> 94.1 %. The adopted templates take part in switches and
  the final decision; the first decision takes an adopted template only when no trained one
  fits under its threshold.
- After `character_finished()` (IV-C) frames are discarded until a null signal or until
  `discard_frames` frames have passed, so the hand's return does not launch a new action; past
  `discard_frames`, only once the hand has calmed under DISCARD_HOLD_RATIO of the discarded
  motion's peak activity (at most DISCARD_HOLD x `discard_frames` frames).

Events are dicts with the keys of docs/formats.md ("event", "action", "frame", "t" when the caller
passes it, "from_frame" on switches, "score"), plus estimates of the motion's speed (m/s),
direction (unit vector in the first sensor's frame) and peak acceleration (g).
"""

from __future__ import annotations

import math

import numpy as np

from engine.clock import STEP_HZ
from engine.recognition.config import RecognizerConfig
from engine.recognition.dtw import IncrementalDTW
from engine.recognition.templates import (
    LOG_SCALE_G,
    Templates,
    activity,
    features,
    grip_features,
)

G = 9.81
AUTO_MIN_MAIN = 3
AUTO_MAX_MAIN = 12
STILL_DELTA_G = 0.03  # a sensor is still when it changes less than this per frame ...
STILL_FRAMES = 3  # ... for this many frames in a row, reading about 1 g
STILL_NORM_TOL = 0.2
GRAVITY_FOLLOW = 0.05  # how fast g follows the signal while the gate is closed
# Recovery from a wrong gravity (e.g. learnt from a first frame taken mid-motion, when the noise
# is too strong for the STILL_DELTA_G test): a sensor whose every reading stays within
# STEADY_G of its running mean (EMA, STEADY_ALPHA) for RECOVER_FRAMES frames in a row is not
# moving, whatever the gate says, so its gravity becomes that mean. Only once the motion's
# buffers are full (its decision is made; a slow, gentle gesture must not be cut short while it
# is being recognized) or outside a motion.
STEADY_ALPHA = 0.125
STEADY_G = 0.2
RECOVER_FRAMES = 30
# A template is only accepted once the motion has been at least this strong relative to the
# template's own peak activity (a weak wiggle must not launch a punch just because its shape
# resembles the punch's gentle first frames; a real punch gets there within a few frames).
CLOSED_END = 1e9  # a min_progress that leaves only each template's last position
# The consumed-template end needs the motion to have lasted this fraction of the template.
COMPLETE_MIN_LENGTH = 0.6
COMPLETE_CALM = 0.3  # ... and the activity to have fallen below this fraction of the motion's peak
ENERGY_RATIO = 0.4
# ... of the template's peak over its first ENERGY_FRAMES frames from its onset (a third of a
# second: a punch's first phase). Against the template's whole peak, a full blow's slow wind-up
# held the start back by 6-12 frames (phone-punches fast -> slow, median lag 233 -> 83 ms).
# The bar is the gentlest of the action's templates (ninth round): the best-matching template's
# own peak made it depend on which trial the shape happened to match, and a strong trial held
# softer punches back (phone-boxing lag 158 -> 125 ms, uWave 94.68 -> 94.92 %).
# A motion that ends without ever reaching CALL_OFF_RATIO of the whole peak of its action's
# templates is called off: its start ends as `reject` (docs/formats.md), not `end`.
ENERGY_FRAMES = 20
# The open end's constraint while the hand moves: the motion's n frames must reach at least
# PROGRESS * n frames into a template. 1.25 (templates.MIN_PROGRESS, which the rejection
# thresholds are still learned with) held a full blow's slow start against a quick punch's
# template; 0.75 lets it sit earlier. phone-punches finals 93.1 / 93.9 / 94.7 / 91.7 ->
# 100 / 95.5 / 98.2 / 91.7 %, uWave and the synthesized players unchanged (recog2 measured
# 1.0 / 1.5 against 1.25 on uWave with the 1.0 g gate; both lost).
PROGRESS = 0.75
CALL_OFF_RATIO = 0.25
# A started motion that the null signal would end while it is still too short to be a punch
# (fewer than PAUSE_SHORT moving frames) or too weak (it would be called off) is a wind-up that
# paused, not the whole motion: its end waits up to PAUSE_FRAMES more quiet frames, and when the
# hand moves on within them the motion goes on (same DTW, a `switch` may correct the start).
# Ended there at once, the blow that followed started a second action and the early start
# stayed wrong or was called off (phone-punches right slow -> fast first decision 71.7 -> 86.7 %).
PAUSE_SHORT = 14
PAUSE_FRAMES = 20
# A first decision on a motion whose activity is still rising (this frame is its strongest so far)
# needs only RISING_RATIO of the template's early peak: a punch on its way gets there; a wiggle or
# a bounce that has already peaked needs ENERGY_RATIO. A full blow's slow first frames held its
# start 2-4 frames (phone-punches median lag L fast -> slow 150 -> 92 ms, R 150 -> 100 ms, with
# the pause rule above to keep the finals; a plain ENERGY_RATIO 0.25 cost two more false starts
# on phone-boxing than this).
RISING_RATIO = 0.25
# No first decision while the hand has been under the gate for this many frames in a row: the
# motion is dying down (a twitch, the tail of a move the `complete` end split off); it waits, and
# is rejected if it ends. Synthesized session 6 -> 0 false starts, phone-punches right slow ->
# fast final 91.7 -> 93.3 %, the rest unchanged.
QUIET_DEFER = 2
# A motion that follows the previous one without the hand resting in between (`null_frames`
# quiet frames; the previous motion ended by `complete`, or the character finished and the
# discard ran out while the hand still moved) is likely that motion's return: its first decision
# also needs RETURN_RATIO of the previous motion's peak activity (discarded frames included), a
# bar that fades by RETURN_DECAY a frame so that a punch thrown soon after is held back briefly.
# phone-boxing false starts 2 -> 1, extra starts 6 -> 2 (no character 11 -> 2), type 71.2 ->
# 74.2 %; phone-punches right slow -> fast extra starts 72 -> 63, left slow -> fast lag 67 -> 75 ms;
# uWave and the synthesized players unchanged. No decay: quick punches 17-30 frames apart lost.
RETURN_RATIO = 0.8
RETURN_DECAY = 0.95
# The discard (IV-C) does not run out at `discard_frames` while the hand still moves at
# DISCARD_HOLD_RATIO or more of the discarded motion's peak activity (a full blow's rest or its
# return, not a new punch), up to DISCARD_HOLD x `discard_frames` frames in all (the paper
# discards "up to 20 frames"; measured: see docs/recognition.md).
DISCARD_HOLD_RATIO = 0.5
DISCARD_HOLD = 1.5
# The onset is back-dated from the frame the gate opens to where the motion left the rest: the
# run of frames just before it whose activity reaches ONSET_FRACTION of the gate, at most
# BACKDATE_MAX frames (templates are cut by the same rule). The gate decides THAT a motion
# happens (a noisy sensor needs a high one); the back-dated onset says WHEN it began, so the main
# buffer fills `main` frames after the hand started moving, not after it got strong.
ONSET_FRACTION = 0.3
BACKDATE_MAX = 8
# noise_g="auto" (the default): the gate is AUTO_K x the resting noise, the AUTO_QUANTILE
# percentile of the gate's activity at rest, within [AUTO_MIN_G, AUTO_MAX_G]. The rest: the
# idle frames before the recognizer's first motion (at least AUTO_MIN_FRAMES of them, the last
# AUTO_FRAMES kept, refreshed every AUTO_EVERY frames); until then the rest before the training
# trials' motions (Templates.rest_noise), else AUTO_START_G (the paper's gate). Frozen from the
# first motion on: the idle between punches holds the hand's returns, and learning from them
# ratcheted the gate up to its cap (phone-punches recall 100 -> 36 %). Kept across reset().
AUTO_K = 2.0
AUTO_QUANTILE = 90
AUTO_MIN_G = 0.3
AUTO_MAX_G = 2.0
AUTO_START_G = 1.0
AUTO_FRAMES = 120
AUTO_MIN_FRAMES = 30
AUTO_EVERY = 10
# A hand whose reading has stopped changing (STILL_DELTA_G per frame) for this many frames has
# finished its motion even when it rests in a new orientation (the gate, measured against the
# gravity before the onset, stays open): score whole templates (closed end) from then on.
UNCHANGED_FRAMES = 2

# A decided motion that outlasts the supplementary buffer keeps its DTW growing up to
# EXTEND_FACTOR x max(window, longest template) frames; at its end a different action whose whole
# template fits the whole motion better by LATE_SWITCH_MARGIN becomes the final decision (a
# noticeable change, so a wider margin than a switch inside the buffer). uWave users 1-6: final
# 89.0 -> 89.9 % (the long gestures the 60-frame buffer cannot see to their end).
EXTEND_FACTOR = 2.0
LATE_SWITCH_MARGIN = 0.1
# Template adaptation (`_adapt`): a whole motion that fits its action better than any other
# action's template by this margin joins that action's templates; this many are kept per action.
ADAPT_MARGIN = 0.4
ADAPT_PER_ACTION = 3

IDLE, ACTIVE, DISCARD = "idle", "active", "discard"


def _inserted(a: np.ndarray, i: int, value) -> np.ndarray:
    """np.insert(a, i, value, axis=0) for one row, in one concatenate (np.insert's own
    bookkeeping costs ~10x more on these short arrays)."""
    return np.concatenate((a[:i], np.array([value], dtype=a.dtype), a[i:]))


class DualBufferRecognizer:
    """Frames in, action events out. See the module docstring for the rules."""

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
    ):
        if not isinstance(templates, Templates):
            raise TypeError("templates must be a Templates")
        if main != "auto" and (not isinstance(main, (int, np.integer)) or main < 1):
            raise ValueError(f"main must be a positive int or 'auto', not {main!r}")
        self.auto_gate = noise_g == "auto"
        if self.auto_gate:
            noise_g = self._auto_gate(templates.rest_noise) if np.isfinite(templates.rest_noise) else AUTO_START_G
        elif not isinstance(noise_g, (int, float, np.integer, np.floating)):
            raise ValueError(f"noise_g must be a number of g or 'auto', not {noise_g!r}")
        if supplementary < 1 or null_frames < 1 or discard_frames < 0 or noise_g < 0:
            raise ValueError("supplementary and null_frames must be >= 1, discard_frames and noise_g >= 0")
        self.templates = templates
        self.main = main
        self.supplementary = int(supplementary)
        self.noise_g = float(noise_g)
        self.null_frames = int(null_frames)
        self.discard_frames = int(discard_frames)
        self.switch_margin = float(switch_margin)
        self.auto_lead = float(auto_lead)
        self.reject = bool(reject)
        self.complete_fraction = float(complete_fraction)
        self.complete_frames = int(complete_frames)
        self.closed_after = int(closed_after) if closed_after > 0 else 1 << 30
        self.dim = templates.dim
        self.feature = templates.feature
        self._feat = np.empty(self.dim)
        self._stop_scores = np.empty(len(templates.actions))

        # Templates sorted by action so per-action minima are one reduceat.
        names = templates.action_names
        index = {a: i for i, a in enumerate(names)}
        order = np.argsort([index[a] for a in templates.actions], kind="stable")
        self.action_names = names
        self._tmpl_action = np.array([index[templates.actions[k]] for k in order])
        self._action_starts = np.flatnonzero(np.r_[True, np.diff(self._tmpl_action) != 0])
        self._action_ends = np.r_[self._action_starts[1:], len(order)]
        self.thresholds = templates.thresholds[order] if reject else np.full(len(order), np.inf)
        self.window = max(self.supplementary, AUTO_MAX_MAIN if main == "auto" else int(main))
        cut = [self._cut_at_gate(templates, k) for k in order]
        self._peak_act = self._template_peaks(templates, order)  # (T, 2): early and window peaks
        self._action_bar = np.minimum.reduceat(self._peak_act[:, 0], self._action_starts)  # per action
        self.template_lengths = np.array([len(c) for c in cut])
        self.min_progress = float(min_progress)
        self.dtw = IncrementalDTW(cut, method=dtw_method, min_progress=min_progress)
        # A decided motion that outlasts the supplementary buffer keeps its DTW growing (one
        # row a frame, as before) up to this many frames, for a final decision over the whole
        # motion at its end (`_late_switch`); bounded so a hand that never rests costs nothing.
        self._extend_to = int(EXTEND_FACTOR * max(self.window, int(self.template_lengths.max()))) if extend else 0
        # Adaptation to the player (see `_adapt`): the trained templates stay; up to `adapt`
        # recent, confidently recognized whole motions per action join them.
        self.adapt = max(0, int(adapt))
        self._dtw_method = dtw_method
        self._base = (cut, self._tmpl_action.copy(), self.thresholds.copy(), self._peak_act.copy())
        self._base_starts = self._action_starts.copy()
        self._is_adapted = np.zeros(len(order), dtype=bool)
        self._adapted: dict[int, list[tuple[np.ndarray, tuple[float, float]]]] = {}  # (motion, (early, window) peaks)
        self._motion = np.empty((max(self.window, self._extend_to), self.dim))  # features since the onset
        self._acts = np.empty(len(self._motion))  # the gate's activity since the onset
        self._recent = np.empty((BACKDATE_MAX, self.dim))  # the last idle frames (ring), for back-dating
        self._idle_acts = np.empty(AUTO_FRAMES)  # the gate's activity on the last idle frames (ring), for "auto"
        self._n_idle = 0
        self._moved = False  # a motion has started (a `start`) since the recognizer was built
        self.reset()

    @classmethod
    def from_config(cls, templates: Templates, config: RecognizerConfig | None = None) -> DualBufferRecognizer:
        """The recognizer `config` describes (engine/recognition/config.py; None: the defaults),
        the same as passing its fields as keywords."""
        return cls(templates, **(config or RecognizerConfig()).kwargs())

    def _gate_start(self, templates: Templates, k: int) -> int:
        """Where this recognizer's onset would be on template k: the start of the run of
        above-gate frames that holds the template's trimmed onset (earlier wiggles separated by
        quiet frames are not the motion); the first above-gate frame after the onset when the
        onset itself is gentler than the gate; the onset when the gate never opens. Then
        back-dated as `push` does (`_backdate`)."""
        act = activity(templates.signals[k], templates.gravity[k])
        on = int(templates.onsets[k])
        if act[on] < self.noise_g:
            later = np.flatnonzero(act[on:] >= self.noise_g)
            if not len(later):
                return on
            on += int(later[0])
        while on > 0 and act[on - 1] >= self.noise_g:
            on -= 1
        return on - self._backdate(act[max(0, on - BACKDATE_MAX) : on])

    @staticmethod
    def _auto_gate(noise: float) -> float:
        return float(min(max(AUTO_K * noise, AUTO_MIN_G), AUTO_MAX_G))

    def _learn_gate(self, act: float) -> None:
        """noise_g="auto": one more resting frame's activity; now and then the gate from them."""
        self._idle_acts[self._n_idle % AUTO_FRAMES] = act
        self._n_idle += 1
        if self._n_idle >= AUTO_MIN_FRAMES and self._n_idle % AUTO_EVERY == 0:
            self.noise_g = self._auto_gate(float(np.percentile(self._idle_acts[: min(self._n_idle, AUTO_FRAMES)], AUTO_QUANTILE)))

    def _backdate(self, before: np.ndarray) -> int:
        """How many of the frames just before the gate opened (activity `before`, oldest first)
        belong to the motion: the run at the end whose activity reaches ONSET_FRACTION of the gate."""
        low = np.flatnonzero(before < ONSET_FRACTION * self.noise_g)
        return len(before) - (int(low[-1]) + 1 if len(low) else 0)

    def _template_peaks(self, templates: Templates, order: np.ndarray) -> np.ndarray:
        """(T, 2) each template's peak activity from its onset over its first ENERGY_FRAMES frames
        (the energy rule of a start) and over `window` frames (a motion that never gets near it
        is called off)."""
        return np.array([
            self._peaks(activity(templates.signals[k], templates.gravity[k])[self._gate_start(templates, k) :]) for k in order
        ])

    def _peaks(self, act: np.ndarray) -> tuple[float, float]:
        """(early, window) peaks of an activity series from its onset."""
        if not len(act):
            return 0.0, 0.0
        return float(act[:ENERGY_FRAMES].max()), float(act[: self.window].max())

    def _cut_at_gate(self, templates: Templates, k: int) -> np.ndarray:
        """Template k from its gate onset, in the recognizer's feature space."""
        sig, g = templates.signals[k], templates.gravity[k]
        return features(sig[self._gate_start(templates, k) :], g, self.feature)

    # -- state -------------------------------------------------------------------------------
    def reset(self) -> None:
        """Back to idle, forgetting gravity and any motion in progress."""
        self.state = IDLE
        self.frame = -1
        self._t: float | None = None
        self.gravity: np.ndarray | None = None
        self._last: list[float] | None = None  # the previous frame, plain floats (see _gate)
        self._still = 0
        self._mean: list[float] = []
        self._steady = 0
        self._unchanged = 0
        self._queued: list[dict] = []
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
        self._velocity = [0.0] * self.dim
        self._peak_speed = 0.0
        self._peak_dir = [0.0, 0.0, 0.0]
        self._peak_g = 0.0
        self._peak_act_seen = 0.0
        self._done = 0
        self._extended = False  # the DTW ran past the supplementary buffer (a long motion)
        self._was_closed = False
        self._stopped = False
        self._stop_n = 0

    @property
    def current_action(self) -> str | None:
        return None if self.action is None else self.action_names[self.action]

    def character_finished(self) -> None:
        """The character's clip of the current action ended (IV-C): the rest of this motion
        (the hand coming back) is discarded until a null signal or `discard_frames` frames."""
        if self.state != ACTIVE or self.action is None:
            return
        self._queued.append(self._event("end", self.action_names[self.action], None, reason="character_finished"))
        self._after_peak = self._peak_act_seen
        self._begin_motion_state()
        self.state = DISCARD

    # -- the per-frame step ------------------------------------------------------------------
    def push(self, frame: np.ndarray, t: float | None = None) -> list[dict]:
        """Feed one 60 Hz frame of shape (D,); returns the events it decided (often none)."""
        x = np.asarray(frame, dtype=np.float64).reshape(-1)
        if x.shape[0] != self.dim:
            raise ValueError(f"frame has {x.shape[0]} values, the templates have D = {self.dim}")
        self.frame += 1
        self._t = t
        events, self._queued = self._queued, []
        if not np.isfinite(x).all():  # the method: no fromnumeric wrapper (~1 us a frame)
            return events  # a malformed frame is dropped, not a crash
        valid = self._gate(x)
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
                if self.auto_gate and not self._moved:
                    self._learn_gate(self._act)
                return events
            self.state = ACTIVE
            self._idle_quiet = 0
            self.dtw.reset()
            self._g0 = self.gravity.copy()
            self._g0_list = self._g0.tolist()
            # The frames just before the gate opened that were already on their way (see
            # ONSET_FRACTION) start the motion: replayed now, oldest first. (Measured against the
            # gravity from before them instead of the current one, which follows a slow rise a
            # little: phone-punches finals 1-5 points lower, so not kept.)
            m = min(self._n_recent, BACKDATE_MAX)
            recent = self._recent[(self._n_recent - m + np.arange(m)) % BACKDATE_MAX]
            back = self._backdate(activity(recent, self._g0)) if m else 0
            self.onset_frame = self.frame - back
            xs, act = self._xs, self._act
            for r in recent[m - back :]:
                self._xs = r.tolist()
                self._act = float(activity(r[None], self._g0)[0])
                self._step_active(r, True, events, backdated=True)
            self._xs, self._act = xs, act
            self._n_recent = 0
        self._step_active(x, valid, events)
        return events

    def _gate(self, x: np.ndarray) -> bool:
        """Update the gravity estimate and say whether this frame is valid (above the gate).
        Plain floats: with 1-4 sensors that is cheaper than a dozen tiny numpy calls.

        Gravity: the first frame is only a guess (it may be mid-motion); it snaps to the reading after
        STILL_FRAMES still frames, follows slowly while the gate is closed, and is re-estimated
        from the running mean after RECOVER_FRAMES steady frames (a wrong guess cannot hold the
        gate open forever)."""
        xs = x.tolist()
        if self.gravity is None:
            self.gravity = x.copy()
            self._last = list(xs)
            self._mean = list(xs)
        g, last, mean = self.gravity.tolist(), self._last, self._mean
        still_now, unchanged_now, steady_now, act = True, True, True, 0.0
        a = STEADY_ALPHA
        for k in range(0, len(xs), 3):
            ax, ay, az = xs[k], xs[k + 1], xs[k + 2]
            dx, dy, dz = ax - last[k], ay - last[k + 1], az - last[k + 2]
            if dx * dx + dy * dy + dz * dz >= STILL_DELTA_G**2:
                still_now = unchanged_now = False
            elif abs(math.sqrt(ax * ax + ay * ay + az * az) - 1.0) >= STILL_NORM_TOL:
                still_now = False
            mx, my, mz = mean[k] + a * (ax - mean[k]), mean[k + 1] + a * (ay - mean[k + 1]), mean[k + 2] + a * (az - mean[k + 2])
            mean[k], mean[k + 1], mean[k + 2] = mx, my, mz
            ex, ey, ez = ax - mx, ay - my, az - mz
            if ex * ex + ey * ey + ez * ez >= STEADY_G**2:
                steady_now = False
            gx, gy, gz = ax - g[k], ay - g[k + 1], az - g[k + 2]
            act += math.sqrt(gx * gx + gy * gy + gz * gz)
        self._last = self._xs = xs
        self._still = self._still + 1 if still_now else 0
        self._unchanged = self._unchanged + 1 if unchanged_now else 0
        self._steady = self._steady + 1 if steady_now else 0
        if self._still >= STILL_FRAMES:
            self.gravity[:] = x
            act = 0.0
        elif self._steady >= RECOVER_FRAMES and act >= self.noise_g and (self.state != ACTIVE or self.count >= self.window):
            self.gravity[:] = mean
            act = 0.0
        valid = act >= self.noise_g
        self._act = act
        if not valid and self.state != ACTIVE:
            self.gravity += GRAVITY_FOLLOW * (x - self.gravity)
        return valid

    def _step_active(self, x: np.ndarray, valid: bool, events: list[dict], backdated: bool = False) -> None:
        if self.auto_gate and not self._moved and self.action is None and self.count >= self.window:
            # Nothing has ever started and this motion was rejected (or outlasted the buffer
            # undecided): the sensor's noise crossing a gate set too low (e.g. from quieter
            # training trials) holds the gate open, so these frames count as rest too.
            self._learn_gate(self._act)
        self.count += 1
        self.quiet = 0 if valid else self.quiet + 1
        self._peak_act_seen = max(self._peak_act_seen, self._act)
        self._after_peak *= RETURN_DECAY
        self._track_speed()
        complete = False
        in_window = self.count <= self.window
        if in_window or (self.action is not None and self.count <= self._extend_to):
            # While the hand moves, the motion may be partial: open end (the query's end may sit
            # anywhere past min_progress * n in a template). Once it is quiet the motion has
            # probably ended, and the whole template must be matched (closed end); so too once
            # the reading has stopped changing.
            closed = not backdated and (self._unchanged >= UNCHANGED_FRAMES or (not valid and self.quiet >= self.closed_after))
            self.dtw.min_progress = CLOSED_END if closed else self.min_progress
            f = self._features(x)
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
                self._decide(scores, events)
                complete = self._complete(scores)
            else:
                self._extended = True
        if self.quiet >= self.null_frames and not complete and self._paused():
            return  # a wind-up's pause: the blow may follow
        if self.quiet >= self.null_frames or complete:
            if self.action is not None and self._called_off():
                events.append(self._event("reject", self.action_names[self.action], None, called_off=True))
            elif self.action is not None:
                if self._extended:
                    self._late_switch(self._stop_scores if self._stopped else self.dtw.scores, events)
                if self.adapt and self.count <= max(self.window, self._extend_to):
                    self._adapt()
                events.append(self._event("end", self.action_names[self.action], None, reason="complete" if complete else None))
            elif self.pending:
                events.append(self._event("reject", None, None))
            if self.action is None and self.auto_gate and not self._moved:
                for a in self._acts[: min(self.dtw.n, self.window)]:  # as above: it was rest
                    self._learn_gate(float(a))
            self._after_peak = self._peak_act_seen if complete else 0.0
            self._begin_motion_state()
            self.state = IDLE

    def _paused(self) -> bool:
        """A started motion under the null signal that is too short or too weak to be over yet
        waits up to PAUSE_FRAMES more quiet frames for the hand to go on (see PAUSE_SHORT)."""
        if self.action is None or self.quiet >= self.null_frames + PAUSE_FRAMES:
            return False
        return self.count - self.quiet < PAUSE_SHORT or self._called_off()

    def _called_off(self) -> bool:
        """A started motion that ended without ever reaching CALL_OFF_RATIO of the peak of any of
        its action's templates was no such action (a wiggle the early start took for one)."""
        if not self.reject:
            return False
        lo, hi = self._action_starts[self.action], self._action_ends[self.action]
        return self._peak_act_seen < CALL_OFF_RATIO * float(self._peak_act[lo:hi, 1].min())

    def _adapt(self) -> None:
        """A player drifts from the trials the templates came from (uWave: day-1 templates, days
        2-7 tested). When a motion ends whose whole, up to where the hand stopped, fits its final
        action's template better by ADAPT_MARGIN than any other action's, it becomes one of that
        action's templates; the `adapt` most recent ones per action are kept beside the trained
        ones (the uWave paper's template adaptation, driven by confident decisions instead of
        the user's feedback). Motions ended by `character_finished()` are partial: never used."""
        n = self._stop_n if self._stopped else self.dtw.n
        if n < 2:
            return
        scores = self._stop_scores if self._stopped else self.dtw.closed_scores()
        lo, hi = int(self._action_starts[self.action]), int(self._action_ends[self.action])  # its templates
        k = lo + int(np.argmin(scores[lo:hi]))
        best, other = float(scores[k]), float(min(scores[:lo].min(initial=np.inf), scores[hi:].min(initial=np.inf)))
        if not best < (1.0 - ADAPT_MARGIN) * other or best > self.thresholds[k]:
            return
        self._adopt(self._motion[:n].copy(), self._peaks(self._acts[:n]))

    def _adopt(self, motion: np.ndarray, peak: tuple[float, float]) -> None:
        """The current action's newest adapted template: in place of its oldest once `adapt`
        are kept, else added at the end of the action's templates. The bookkeeping arrays are
        edited where they change, the DTW moves a column or two (`replace_template`): what
        `_set_templates` would build from scratch, at ~1/10 of its cost (on the step a motion ends)."""
        a = self.action
        kept = self._adapted.setdefault(a, [])
        kept.append((motion, peak))
        lo, hi = int(self._action_starts[a]), int(self._action_ends[a])
        first = hi - (len(kept) - 1)  # where the action's adapted templates start
        if len(kept) <= self.adapt:  # one more template: after the action's others
            b = int(self._base_starts[a])  # its trained templates' thresholds: [b, b + first - lo)
            loosest = self._base[2][b : b + first - lo].max()
            self._tmpl_action = _inserted(self._tmpl_action, hi, a)
            self._action_starts[a + 1 :] += 1
            self._action_ends[a:] += 1
            self.thresholds = _inserted(self.thresholds, hi, loosest)
            self._peak_act = _inserted(self._peak_act, hi, peak)
            self.template_lengths = _inserted(self.template_lengths, hi, len(motion))
            self._is_adapted = _inserted(self._is_adapted, hi, True)
            self.dtw.add_templates([motion], at=[hi])
            self._stop_scores = np.empty(self.dtw.T)
        elif len(kept) == self.adapt + 1 and first < hi:  # the oldest adapted one makes room
            del kept[0]
            self._peak_act[first : hi - 1] = self._peak_act[first + 1 : hi]
            self._peak_act[hi - 1] = peak
            self.template_lengths[first : hi - 1] = self.template_lengths[first + 1 : hi]
            self.template_lengths[hi - 1] = len(motion)
            self.dtw.replace_template(first, motion, hi - 1)
        else:  # `adapt` lowered since: rebuilt from the kept lists
            del kept[: -self.adapt]
            self._set_templates()
            return
        # the action's energy bar: its gentlest template, the adopted one included (as `_set_templates`)
        self._action_bar[a] = self._peak_act[self._action_starts[a] : self._action_ends[a], 0].min()

    def _set_templates(self) -> None:
        """The DTW over the trained templates plus the adapted ones, sorted by action. An adapted
        template takes its action's loosest trained threshold."""
        cut, acts, thr, peaks = self._base
        extra = [(motion, a, peak) for a, kept in self._adapted.items() for motion, peak in kept]
        new_acts = np.array([a for _, a, _ in extra], dtype=acts.dtype)
        loosest = np.maximum.reduceat(thr, self._base_starts)  # per action (trained sorted by action)
        acts = np.concatenate([acts, new_acts])
        thr = np.concatenate([thr, loosest[new_acts]])
        peaks = np.concatenate([peaks, [peak for _, _, peak in extra]]) if extra else peaks
        cut = [*cut, *(motion for motion, _, _ in extra)]
        order = np.argsort(acts, kind="stable")
        self._is_adapted = order >= len(self._base[1])
        self._tmpl_action = acts[order]
        self._action_starts = np.flatnonzero(np.r_[True, np.diff(self._tmpl_action) != 0])
        self._action_ends = np.r_[self._action_starts[1:], len(order)]
        self.thresholds = thr[order]
        self._peak_act = peaks[order]
        self._action_bar = np.minimum.reduceat(self._peak_act[:, 0], self._action_starts)
        cut = [cut[k] for k in order]
        self.template_lengths = np.array([len(c) for c in cut])
        self.dtw.update_templates(cut)  # the adopted one added, a dropped one removed: no rebuild
        self._stop_scores = np.empty(len(cut))

    def forget_adaptation(self) -> None:
        """Back to the trained templates only (a new player)."""
        if self._adapted:
            self._adapted = {}
            self._set_templates()

    def _decide(self, scores: np.ndarray, events: list[dict]) -> None:
        best = int(np.argmin(scores))
        if self.action is None and self._is_adapted[best]:
            # The first decision comes from the trained templates while one of them fits under
            # its threshold: an adopted motion is whole, wind-up included, and the next punch's
            # wind-up of another kind matched it (a full uppercut adopted, the following jabs
            # started as uppercuts: mixed right fast -> slow first 80.7 % without adaptation,
            # 57.9 % with it). A player drifted beyond every trained template still starts
            # from the adopted ones; switches and the final decision use them all.
            trained = np.where(self._is_adapted, np.inf, scores)
            k = int(np.argmin(trained))
            if trained[k] <= self.thresholds[k]:
                best = k
        best_action = int(self._tmpl_action[best])
        best_score = float(scores[best])
        bar = self._action_bar[best_action]
        strong = not self.reject or self._peak_act_seen >= ENERGY_RATIO * bar
        if not strong and self.action is None:
            # still rising (this frame is the motion's strongest so far): RISING_RATIO will do
            strong = self._peak_act_seen >= RISING_RATIO * bar and self._act >= self._peak_act_seen
        ok = strong and best_score <= self.thresholds[best]
        if self.action is None:
            ok = ok and (not self.reject or self._peak_act_seen >= RETURN_RATIO * self._after_peak)
            if not self.pending and not self._first_decision_due(scores):
                return
            if self.quiet >= QUIET_DEFER and self.count < self.window:
                self.pending = True  # the motion is dying down: wait, it may have been a twitch
                return
            if ok:
                self._moved = True
                self.action = best_action
                self.start_frame = self.frame
                events.append(self._event("start", self.action_names[best_action], best_score, late=self.pending))
                self.pending = False
            elif self.count >= self.window:
                events.append(self._event("reject", self.action_names[best_action], best_score))
                self.pending = False
                self.count = self.window + 1  # decided: no more DTW for this motion
            else:
                self.pending = True
            return
        # A switch needs the motion to be strong enough for the new template. It needs the new
        # template's rejection threshold only while the current action still fits under its
        # own: once the current decision no longer fits either (the player's style has drifted
        # from the training trials: uWave days 2-7 against day-1 templates), the better match
        # is the better answer (uWave 85.3 -> 88.7 %); while it fits, no flicker to a misfit.
        if best_action == self.action or not strong:
            return
        if self._beats_current(scores, best_score, ok, self.switch_margin):
            self.action = best_action
            events.append(
                self._event("switch", self.action_names[best_action], best_score, from_frame=self.frame - self.start_frame)
            )

    def _late_switch(self, scores: np.ndarray, events: list[dict]) -> None:
        """A motion longer than the supplementary buffer: its DTW kept growing past it, so at
        the end the whole motion (up to where the hand stopped) is scored against whole
        templates. A different action that is now better by LATE_SWITCH_MARGIN (with the same
        threshold rules as a switch) becomes the final decision: a `switch` flagged
        `whole_motion` (from_frame = n_p, frames since the start, as for any switch) before `end`."""
        best = int(np.argmin(scores))
        best_action = int(self._tmpl_action[best])
        if best_action == self.action:
            return
        best_score = float(scores[best])
        if self._beats_current(scores, best_score, best_score <= self.thresholds[best], LATE_SWITCH_MARGIN):
            self.action = best_action
            events.append(
                self._event(
                    "switch", self.action_names[best_action], best_score, from_frame=self.frame - self.start_frame, whole_motion=True
                )
            )

    def _beats_current(self, scores: np.ndarray, best_score: float, ok: bool, margin: float) -> bool:
        """A switch's test (in the buffer and at the end): the best template, `ok` if under its
        threshold, beats the current action's best template by `margin`; a best template over
        its threshold only counts once the current action no longer fits under its own."""
        k = self._current_best(scores)
        current = float(scores[k])
        if not ok and current <= self.thresholds[k]:
            return False
        return best_score < current * (1.0 - margin)

    def _complete(self, scores: np.ndarray) -> bool:
        """True when the current action's best template has been matched to its end for
        `complete_frames` frames in a row: the motion is over even if the hand never rests
        (punches thrown back to back), so the next rise is a new onset."""
        if self.complete_fraction <= 0 or self.action is None:
            return False
        k = self._current_best(scores)
        if self.count < COMPLETE_MIN_LENGTH * self.template_lengths[k] or self._act > COMPLETE_CALM * self._peak_act_seen:
            # too early (an alignment can jump to a template's end at the start), or the
            # hand is still moving hard: not over yet
            self._done = 0
            return False
        pos = self.dtw.position(k)
        self._done = self._done + 1 if pos + 1 >= self.complete_fraction * self.template_lengths[k] else 0
        if self._done < self.complete_frames:
            return False
        # ... and the motion so far, taken as whole, fits this template at least as well as
        # any other action's whole template (a long gesture pausing after a stretch that
        # looks like a shorter action's whole is not over; uWave +0.2, novice +0.4 points,
        # phone recall unchanged; requiring a margin here costs phone recall).
        closed = self.dtw.closed_scores()
        return bool(closed[k] <= np.min(np.where(self._tmpl_action == self.action, np.inf, closed)))

    def _current_best(self, scores: np.ndarray) -> int:
        """The current action's best-scoring template (templates are sorted by action)."""
        lo, hi = self._action_starts[self.action], self._action_ends[self.action]
        return int(lo + scores[lo:hi].argmin())

    def _first_decision_due(self, scores: np.ndarray) -> bool:
        if self.main != "auto":
            return self.count >= self.main
        if self.count < AUTO_MIN_MAIN:
            return False
        if self.count >= AUTO_MAX_MAIN or len(self.action_names) < 2:
            return True
        per_action = np.minimum.reduceat(scores, self._action_starts)
        first, second = np.partition(per_action, 1)[:2]
        return second > 0 and (second - first) / second >= self.auto_lead

    def _track_speed(self) -> None:
        """Integrate the gravity-removed acceleration since the onset: a rough hand velocity,
        enough to tell a hard punch from a soft one (the paper's future work). Plain floats."""
        xs, g0, v = self._xs, self._g0_list, self._velocity
        k_dt = G / STEP_HZ
        for k in range(0, len(xs), 3):
            dx, dy, dz = xs[k] - g0[k], xs[k + 1] - g0[k + 1], xs[k + 2] - g0[k + 2]
            self._peak_g = max(self._peak_g, math.sqrt(dx * dx + dy * dy + dz * dz))
            v[k] += dx * k_dt
            v[k + 1] += dy * k_dt
            v[k + 2] += dz * k_dt
            sp = math.sqrt(v[k] * v[k] + v[k + 1] * v[k + 1] + v[k + 2] * v[k + 2])
            if sp > self._peak_speed:
                self._peak_speed = sp
                self._peak_dir = [v[k] / sp, v[k + 1] / sp, v[k + 2] / sp]

    def _features(self, x: np.ndarray) -> np.ndarray:
        """templates.features() for one frame, into a reused buffer (same values)."""
        out = self._feat
        if self.feature == "log":
            np.abs(x, out=out)
            out *= 1.0 / LOG_SCALE_G
            np.log1p(out, out=out)
            np.copysign(out, x, out=out)
        elif self.feature == "dynamic":
            np.subtract(x, self._g0, out=out)
        elif self.feature == "grip":
            out[:] = grip_features(x[None], self._g0)[0]
        else:
            out[:] = x
        return out

    def _event(self, kind: str, action: str | None, score: float | None, **extra) -> dict:
        ev: dict = {"event": kind, "action": action, "frame": self.frame}
        if self._t is not None:
            ev["t"] = round(float(self._t), 4)
        if "from_frame" in extra:
            ev["from_frame"] = int(extra.pop("from_frame"))
        if score is not None:
            ev["score"] = round(score, 5)
        if kind in ("start", "switch"):
            ev["speed"] = round(self._peak_speed, 3)
            ev["direction"] = [round(v, 3) for v in self._peak_dir]
            ev["peak_g"] = round(self._peak_g, 3)
            ev["onset_frame"] = self.onset_frame
        ev.update({k: v for k, v in extra.items() if v})
        return ev
