"""The dual buffer's decision rules (paper IV-A to IV-C, and the ones beyond it: see
engine/recognition/dual_buffer.py): when a motion starts, switches, is rejected or called off,
and when it is over. Mixed into DualBufferRecognizer; they read its motion state."""

from __future__ import annotations

import math
from operator import mul, sub

import numpy as np

from engine.recognition.templates import activity

AUTO_MIN_MAIN = 3
AUTO_MAX_MAIN = 12
CLOSED_END = 1e9  # a min_progress that leaves only each template's last position
# The consumed-template end needs the motion to have lasted this fraction of the template.
COMPLETE_MIN_LENGTH = 0.6
COMPLETE_CALM = 0.3  # ... and the activity to have fallen below this fraction of the motion's peak
# A template is only accepted once the motion has been at least this strong relative to the
# template's own peak activity (a weak wiggle must not launch a punch just because its shape
# resembles the punch's gentle first frames; a real punch gets there within a few frames).
ENERGY_RATIO = 0.4
# ... of the template's peak over its first ENERGY_FRAMES frames from its onset (a third of a
# second: a punch's first phase). Against the template's whole peak, a full blow's slow wind-up
# held the start back by 6-12 frames. The bar is the gentlest of the action's templates: the
# best-matching template's own peak made it depend on which trial the shape happened to match,
# and a strong trial held softer punches back (docs/recognition.md, the constants' measurements).
# A motion that ends without ever reaching CALL_OFF_RATIO of the whole peak of its action's
# templates is called off: its start ends as `reject` (docs/formats.md), not `end`.
ENERGY_FRAMES = 20
# The open end's constraint while the hand moves: the motion's n frames must reach at least
# PROGRESS * n frames into a template. 1.25 (templates.MIN_PROGRESS, which the rejection
# thresholds are still learned with) held a full blow's slow start against a quick punch's
# template; 0.75 lets it sit earlier (figures: docs/recognition.md).
PROGRESS = 0.75
CALL_OFF_RATIO = 0.25
# A started motion that the null signal would end while it is still too short to be a punch
# (fewer than PAUSE_SHORT moving frames) or too weak (it would be called off) is a wind-up that
# paused, not the whole motion: its end waits up to PAUSE_FRAMES more quiet frames, and when the
# hand moves on within them the motion goes on (same DTW, a `switch` may correct the start).
# Ended there at once, the blow that followed started a second action and the early start
# stayed wrong or was called off (docs/recognition.md, the constants' measurements).
PAUSE_SHORT = 14
PAUSE_FRAMES = 20
# A first decision on a motion whose activity is still rising (this frame is its strongest so far)
# needs only RISING_RATIO of the template's early peak: a punch on its way gets there; a wiggle or
# a bounce that has already peaked needs ENERGY_RATIO. A full blow's slow first frames held its
# start 2-4 frames; a plain lower ENERGY_RATIO let more wiggles start (docs/recognition.md, the constants' measurements).
RISING_RATIO = 0.25
# No first decision while the hand has been under the gate for this many frames in a row: the
# motion is dying down (a twitch, the tail of a move the `complete` end split off); it waits, and
# is rejected if it ends (a twitch's false start; docs/recognition.md, the constants' measurements).
QUIET_DEFER = 2
# A motion that follows the previous one without the hand resting in between (`null_frames`
# quiet frames; the previous motion ended by `complete`, or the character finished and the
# discard ran out while the hand still moved) is likely that motion's return: its first decision
# also needs RETURN_RATIO of the previous motion's peak activity (discarded frames included), a
# bar that fades by RETURN_DECAY a frame so that a punch thrown soon after is held back briefly
# (without the decay, quick punches 17-30 frames apart were lost; docs/recognition.md).
RETURN_RATIO = 0.8
RETURN_DECAY = 0.95
# The discard (IV-C) does not run out at `discard_frames` while the hand still moves at
# DISCARD_HOLD_RATIO or more of the discarded motion's peak activity (a full blow's rest or its
# return, not a new punch), up to DISCARD_HOLD x `discard_frames` frames in all (the paper
# discards "up to 20 frames"; measured: see docs/recognition.md).
DISCARD_HOLD_RATIO = 0.5
DISCARD_HOLD = 1.5
# The other hand (two or more sensors, sixteenth round): the discard ignores the return of the
# hand that punched, not the other hand's punch (a left hook right after a right hook, 0.3-0.6 s
# apart on the two-glove recordings, was lost in the clip and the discard). A sensor carrying less
# than OTHER_HAND_SHARE of the discarded action's templates' activity, whose own activity (against
# the motion's onset gravity) passes the gate and OTHER_HAND_RATIO of the discarded motion's peak
# on the action's sensors, ends the discard; that frame is the next motion's onset. It also ends a
# decided motion that has run its course (`_ran_course`, nineteenth round), for a caller with no
# character to end the motion first.
OTHER_HAND_SHARE = 0.35
OTHER_HAND_RATIO = 0.5
# The handover (two or more sensors, twenty-seventh round): a decided motion that the `complete`
# rule ends while a character is playing its clip (the caller has called `character_finished()`
# before, and has not yet for this motion) goes into the discard the clip's end would have begun,
# not back to idle: a long clip (the game's hooks, 30-32 frames) outlasted the punch, and the
# punching hand's return, no longer discarded, started the punching hand's action again just as
# the other glove's punch came. Only for an action that has another hand (a sensor under
# OTHER_HAND_SHARE of its activity), so that the other hand's launch can end that discard: by the
# OTHER_HAND_* bars, or once that hand moves HANDOVER_OVER x as far (from the motion's onset
# gravity) as the punching hand does on this frame (a punch of the other hand thrown while this one
# landed, whose launch was already under way when the motion began, rarely reaches half of the
# punching hand's peak against that gravity).
HANDOVER_OVER = 1.5
# The moving hand (two or more sensors, eighteenth round): while one sensor has moved clearly the
# most since the onset (every other sensor's peak distance from its reading on the motion's first
# frame under MOVING_HAND_RATIO of its own), a decision in the buffers or at the end does not name
# an action that barely moves that sensor (under OTHER_HAND_SHARE of its templates' activity). The
# DTW sums both hands' features, and a bouncing boxer's other glove, whose tilt the templates also
# carry, named the wrong hand's punch in 19-23 % of the two-glove first decisions.
MOVING_HAND_RATIO = 0.7
UNCHANGED_FRAMES = 2
# A first decision needs the motion's peak of `linear` (||a| - |g||, summed over sensors: what a
# turn of the hand does not make) to reach TURN_RATIO x the action's templates' share of it (the
# least, over their first ENERGY_FRAMES frames, of peak linear / peak activity: TemplateSet
# `_turn_bar`) x the motion's peak activity. A guard change or a slow drift turns the sensor:
# its activity rises like a punch's first frames and started the wrong action 12-50 frames before
# the punch, which then ran into the punch or ended just before it (figures and costs:
# docs/recognition.md, thirteenth round). Trained templates only: adoption does not move it.
TURN_RATIO = 0.4
# A punch thrown straight after another with no rest between (a double): a punch launches the fist
# (the gravity-removed acceleration along some direction d: its strongest frame before the first
# reversal), then stops it (along -d, at RELAUNCH_RATIO or more of the launch's strength). When,
# after that stop, the hand accelerates along d again at RELAUNCH_RATIO or more of the launch, a
# new punch has started: a decided motion ends there (`complete`), a discard ends there, and this
# frame is the new motion's onset (the return rule still applies to it). Without it a double was
# one motion: the clip and the discard swallowed the second punch, and the punch after it started
# late (docs/recognition.md, thirteenth round, doubles). The hand's return (along -d, then stopped along +d) does not
# relaunch unless its stop is as hard and as prompt.
RELAUNCH_RATIO = 0.6
# ... within 60 degrees of the launch (cos >= RELAUNCH_COS), and within RELAUNCH_WITHIN frames of
# the stop (a double's second launch follows the first's stop at once; a gesture's later stroke
# that happens to point along its first one does not).
RELAUNCH_COS = 0.5
RELAUNCH_WITHIN = 10
# ... and a launch of at least RELAUNCH_MIN x the gate: a double is two hard punches far over the
# noise; a gentle motion whose acceleration turns round (a hook's sweep on a quiet synthesized
# player, whose onset jerk became its launch) is not split.
RELAUNCH_MIN = 3.0
# A stop is RELAUNCH_STOP frames in a row against the launch: a fist takes a few frames to stop;
# a buzz or a sensor's jitter flipping sign every frame is no stop.
RELAUNCH_STOP = 2
# A first decision needs the motion to have reached GATE_FLOOR x the gate: a motion that barely
# crosses the gate (the hand settling after a blow, a wiggle) is within reach of the sensor's noise,
# however well its shape fits a template's gentle first frames. A motion still rising may start
# under it (RISING_RATIO): the floor applied to it too held punches back (L fast -> slow per file
# first 79 -> 67 %, lag 100 -> 167 ms; docs/recognition.md, fifteenth round).
GATE_FLOOR = 1.3
# An adopted template (the player's own recent motion) gives a first decision over a trained one
# that fits under its threshold only when it scores ADOPTED_LEAD lower: an adopted motion is whole,
# wind-up included, and another kind's opening can look like that wind-up (docs/recognition.md,
# ninth and fourteenth rounds).
ADOPTED_LEAD = 0.4

# A decided motion that outlasts the supplementary buffer keeps its DTW growing up to
# EXTEND_FACTOR x max(window, longest template) frames, for the rules that weigh the whole motion
# (the `complete` end's whole fit, `_outlasted`, `_ran_course`, adaptation). It no longer changes
# the decision at the end (the twenty-eighth round: the late whole-motion switch named another
# kind on the motions no character cuts short; docs/recognition.md).
EXTEND_FACTOR = 2.0

IDLE, ACTIVE, DISCARD = "idle", "active", "discard"


class LaunchTracker:
    """A motion's launch, stop and relaunch (see RELAUNCH_RATIO), one gravity-removed acceleration
    (all sensors' axes together, plain floats) a frame."""

    def __init__(self) -> None:
        self.launch: list[float] | None = None  # the strongest acceleration before the first stop
        self.norm = 0.0
        self.stopped_at: int | None = None  # frames counted by `step`, at the last stop
        self.stop_run = 0  # stopping frames in a row
        self.n = 0
        self.action: int | None = None  # the motion's decided action (kept through its discard)

    def step(self, a: list[float] | None, valid: bool = True) -> bool:
        """True when this frame launches the hand along the launch again just after a stop. Only
        frames over the gate (`valid`) launch, stop or relaunch: a launch taken from the motion's
        first faint frames would make any wobble a stop. `a` is only read when `valid`."""
        self.n += 1
        if not valid:
            return False
        if self.stopped_at is not None and self.n - self.stopped_at > RELAUNCH_WITHIN:
            return False  # the punch's own stop passed without a new launch: no double
        # sum over map(mul): the generator's sums, the same products added in the same order
        norm = sum(map(mul, a, a)) ** 0.5
        if self.launch is None or self.norm <= 0:
            self.launch, self.norm = a, norm
            return False
        proj = sum(map(mul, a, self.launch)) / self.norm
        if proj <= -RELAUNCH_RATIO * self.norm:
            self.stop_run += 1
            if self.stop_run >= RELAUNCH_STOP:
                self.stopped_at = self.n  # (its last frame: the stop lasts several)
            return False
        self.stop_run = 0
        if self.stopped_at is None:
            if norm > self.norm:
                self.launch, self.norm = a, norm
            return False
        return self.n - self.stopped_at <= RELAUNCH_WITHIN and norm >= RELAUNCH_RATIO * self.norm and proj >= RELAUNCH_COS * norm


def relaunches(signal: np.ndarray, gravity: np.ndarray, gate: float) -> bool:
    """Whether a (template) signal launches again after a stop: a motion of several strokes (a
    shake, a zig-zag), which a relaunch does not end."""
    tracker = LaunchTracker()
    a = np.asarray(signal, dtype=np.float64) - np.asarray(gravity, dtype=np.float64)
    valid = activity(signal, gravity) >= gate
    return any(tracker.step(row, bool(v)) for row, v in zip(a.tolist(), valid, strict=True))


class DecisionRules:
    """The first decision, switches in and after the buffer, the complete end, the pause and
    the call-off (DualBufferRecognizer's state: `action`, `count`, `quiet`, the templates)."""

    def _relaunch(self, valid: bool, events: list[dict]) -> None:
        """A double (`_double`) or, with two or more sensors, the other hand's punch in the discard
        (`_other_hand`) ends the previous motion: this frame is the next motion's onset."""
        self._double(valid, events)
        if self._hands > 1:
            self._other_hand(events)

    def _double(self, valid: bool, events: list[dict]) -> None:
        """A double (see RELAUNCH_RATIO): just after the punch's stop, the hand launches along the
        punch's launch again. The decided motion ends there (`complete`) or the discard does, and
        the state goes back to idle so that this frame is the next motion's onset. Idle: a fresh
        tracker at the onset, which that frame launches."""
        if self.state == IDLE:
            if valid:  # the onset: against the gravity the motion is about to take as its rest
                self._launch = LaunchTracker()
                self._launch.step(self._gravity_removed(self.gate.gravity.tolist()), valid)
            return
        if self.state == ACTIVE and self.action is not None:
            self._launch.action = self.action  # kept through the discard
        action = self._launch.action
        if not (
            self._launch.step(self._gravity_removed(self._g0_list) if valid else None, valid)
            and self._launch.norm >= RELAUNCH_MIN * self.gate.noise_g
            and action is not None
            and not self._strokes[action]
            and (self.state == DISCARD or self.action is not None)
        ):
            return
        if self.state == ACTIVE:
            self._end_complete(events)
        self._begin_motion_state()
        self.state = IDLE
        self._n_recent = 0  # no back-dating into the previous motion
        self._launch = LaunchTracker()
        self._launch.step(self._gravity_removed(self._g0_list) if valid else None, valid)

    def _other_hand(self, events: list) -> None:
        """Each sensor's peak activity over the decided motion (from the frame after its start,
        against its onset gravity) and, in the discard that follows it or once the motion has run
        its course (`_ran_course`), the other hand's launch (OTHER_HAND_*): the discard or the
        motion (`complete`) ends and the state goes back to idle, so that this frame is the next
        onset. (A clip that ends on the start frame itself leaves nothing tracked: the rule is off
        for that motion.) Plain floats: two or three sensors a frame, where numpy's per-call cost
        is most of the work."""
        if self.state == ACTIVE and self.action is not None:
            if self._hand_g0 is None:
                self._hand_g0 = list(self._g0_list)
                self._hand_peak = [0.0] * self._hands
            self._hand_action = self.action
        elif self.state != DISCARD or self._hand_g0 is None:
            self._hand_g0 = None
            return
        xs, g0 = self._xs, self._hand_g0
        dev = [math.dist(xs[i : i + 3], g0[i : i + 3]) for i in range(0, 3 * self._hands, 3)]
        other = self._other_hands[self._hand_action]
        own_peak = max((p for p, o in zip(self._hand_peak, other, strict=True) if not o), default=0.0)  # before this frame
        self._hand_peak = [max(p, d) for p, d in zip(self._hand_peak, dev, strict=True)]
        if own_peak <= 0.0:
            return
        launch = max((d for d, o in zip(dev, other, strict=True) if o), default=0.0)
        strong = launch >= OTHER_HAND_RATIO * own_peak and launch >= self.gate.noise_g
        if self._handover and self.state == DISCARD and not strong and launch >= self.gate.noise_g:
            strong = launch >= HANDOVER_OVER * max((d for d, o in zip(dev, other, strict=True) if not o), default=0.0)
        if strong and (self.state == DISCARD or self._ran_course()):  # (the DTW's scores read only then)
            if self.state == ACTIVE:
                self._end_complete(events)
            self._begin_motion_state()
            self.state = IDLE  # (nothing to back-date: no idle frame since the discarded motion)
            self._hand_g0 = None

    def _ran_course(self) -> bool:
        """A decided motion that has run, since its start, the rest of its best template past the
        main buffer: where a character's clip would be ending. Without a character (a caller that
        only pushes frames) the other hand's punch then ends the motion as it ends the discard."""
        if self.state != ACTIVE or self.action is None:
            return False
        main = AUTO_MIN_MAIN if self.main == "auto" else self.main
        return self.frame - self.start_frame >= int(self.template_lengths[self._current_best(self.dtw.scores)]) - main

    def _end_complete(self, events: list) -> None:
        """The decided motion ends here (`complete`), as at any end: adapted to, then its end."""
        if self.adapt and self.count <= max(self.window, self._extend_to):
            self._adapt()
        events.append(self._event("end", self.action_names[self.action], None, reason="complete"))
        self._after_peak = self._peak_act_seen

    def _gravity_removed(self, g: list[float]) -> list[float]:
        """This frame's acceleration less gravity `g`, all sensors' axes together (plain floats)."""
        return list(map(sub, self._xs, g))

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

    def _decide(self, scores: np.ndarray, events: list) -> None:
        best = int(scores.argmin())  # the method: no fromnumeric wrapper
        if self.action is None and self._is_adapted[best]:
            # The first decision comes from the trained templates while one of them fits under
            # its threshold, unless the adopted one is clearly better (see ADOPTED_LEAD): a
            # player drifted from the trials starts from the own recent motions; switches and the
            # final decision use them all.
            trained = np.where(self._is_adapted, np.inf, scores)
            k = int(np.argmin(trained))
            if trained[k] <= self.thresholds[k] and scores[best] > trained[k] * (1.0 - ADOPTED_LEAD):
                best = k
        best_action = int(self._tmpl_action[best])
        best_score = float(scores[best])
        bar = self._action_bar[best_action]
        strong = not self.reject or self._peak_act_seen >= ENERGY_RATIO * bar
        if self.reject and self.action is None and self._peak_act_seen < GATE_FLOOR * self.gate.noise_g:
            strong = False  # barely over the gate: see GATE_FLOOR
        if not strong and self.action is None:
            # still rising (this frame is the motion's strongest so far): RISING_RATIO will do
            strong = self._peak_act_seen >= RISING_RATIO * bar and self._act >= self._peak_act_seen
        ok = strong and best_score <= self.thresholds[best]
        if self.action is None:
            ok = ok and (not self.reject or self._peak_act_seen >= RETURN_RATIO * self._after_peak)
            ok = ok and (not self.reject or self._peak_lin >= TURN_RATIO * self._turn_bar[best_action] * self._peak_act_seen)
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
        # is the better answer; while it fits, no flicker to a misfit.
        if best_action == self.action or not strong:
            return
        if self._beats_current(scores, best_score, ok, self.switch_margin):
            self.action = best_action
            events.append(
                self._event("switch", self.action_names[best_action], best_score, from_frame=self.frame - self.start_frame)
            )

    def _beats_current(self, scores: np.ndarray, best_score: float, ok: bool, margin: float) -> bool:
        """A switch's test: the best template, `ok` if under its
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
        # looks like a shorter action's whole is not over; requiring a margin here costs
        # phone recall).
        closed = self._usable(self.dtw.closed_scores())  # as the decisions weigh adopted templates
        return bool(closed[k] <= np.min(np.where(self._tmpl_action == self.action, np.inf, closed)))

    def _outlasted(self) -> bool:
        """A decided motion longer than the supplementary buffer and than every template of its
        action: over, at rest or not (eighteenth round). The character's clip ends a motion in the
        game; without one (`quickjab recognize`, a caller that only pushes frames) a hand that
        never rests held one motion open for seconds and lost every punch thrown in it."""
        if self.action is None or self.count <= self.window:
            return False
        lo, hi = self._action_starts[self.action], self._action_ends[self.action]
        return self.count > int(self.template_lengths[lo:hi].max())

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
        # a second action at inf (left out by `_moving_hand`, or none of its templates fitting)
        # gives no lead to measure: not yet (as inf / inf was, without its RuntimeWarning)
        return bool(np.isfinite(second)) and second > 0 and (second - first) / second >= self.auto_lead


def shaken_actions(templates, names: list[str], gate: float) -> list[bool]:
    """Per action: do most of its templates launch again after a stop (a shake, a zig-zag: several
    strokes, not one punch)? A relaunch does not end such an action's motion."""
    shaken = [relaunches(s[o:], g, gate) for s, g, o in zip(templates.signals, templates.gravity, templates.onsets, strict=True)]
    return [2 * sum(k for k, a in zip(shaken, templates.actions, strict=True) if a == name) > templates.actions.count(name) for name in names]
