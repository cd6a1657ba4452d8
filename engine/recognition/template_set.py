"""The recognizer's template set: the trained templates sorted by action (per-action minima are
one reduceat), their bookkeeping (thresholds, early and window peak activity, lengths, each action's
energy bar), the DTW over them, and the in-place adoption of adapted templates. Mixed into
DualBufferRecognizer."""

from __future__ import annotations

import math

import numpy as np

from engine.recognition import rules
from engine.recognition.dtw import IncrementalDTW
from engine.recognition.rules import ENERGY_FRAMES, EXTEND_FACTOR, shaken_actions
from engine.recognition.templates import Templates, activity, features, linear, sensor_activity
from engine.recognition.tilt import tilted_copies


def _inserted(a: np.ndarray, i: int, value) -> np.ndarray:
    """np.insert(a, i, value, axis=0) for one row, in one concatenate (np.insert's own
    bookkeeping costs ~10x more on these short arrays)."""
    return np.concatenate((a[:i], np.array([value], dtype=a.dtype), a[i:]))


def hand_shares(templates: Templates, names: list[str]) -> np.ndarray:
    """(actions, sensors): each sensor's share of an action's activity, the mean over its
    templates of each sensor's summed |a - g| over the template's share of the total."""
    share = np.zeros((len(names), templates.dim // 3))
    index = {a: i for i, a in enumerate(names)}
    for s, g, action in zip(templates.signals, templates.gravity, templates.actions, strict=True):
        per_sensor = sensor_activity(s, g).sum(axis=0)
        share[index[action]] += per_sensor / max(float(per_sensor.sum()), 1e-12)
    return share / np.maximum(share.sum(axis=1, keepdims=True), 1e-12)


class TemplateSet:
    """Templates sorted by action, with the trained set kept for adaptation (`_adopt`)."""

    def _build_templates(self, templates: Templates, reject: bool, extend: bool, tilt_deg: float) -> None:
        """The templates and their tilted copies (tilt.py) sorted by action and their bookkeeping
        (thresholds, peaks, lengths, the action's energy bar), the DTW over them cut at the gate,
        and the trained set kept for adaptation."""
        given = templates
        templates, self._source = tilted_copies(given, tilt_deg)  # a copy's activity is its source's
        self._trained = templates  # with the copies (`self.templates` is the caller's set)
        # Templates sorted by action so per-action minima are one reduceat.
        names = templates.action_names
        index = {a: i for i, a in enumerate(names)}
        order = np.argsort([index[a] for a in templates.actions], kind="stable")
        self._order = order
        copies = self._source != np.arange(len(templates))
        self._base_copy = copies[order]  # the trained order's copies; adopted templates are none
        self._has_copies = bool(copies.any())
        self._is_copy, self._not_copy = self._base_copy, ~self._base_copy
        self._fit_bar: tuple[np.ndarray | None, np.ndarray | None] = (None, None)  # _first_usable's, per thresholds array
        self._cut_gate = self.gate.noise_g  # the gate the trained templates are cut at (see _recut)
        # each template's activity and features, whole: a cut is a slice of them (see _recut)
        acts = [activity(s, g) for s, g in zip(given.signals, given.gravity, strict=True)]
        self._whole = [
            (acts[k], features(s, g, self.feature)) for k, s, g in zip(self._source, templates.signals, templates.gravity, strict=True)
        ]
        self.action_names = names
        self._hands = templates.dim // 3
        self._hand_share = hand_shares(given, names)  # the copies' shares are their sources'
        self._barely = self._hand_share < rules.OTHER_HAND_SHARE  # (actions, sensors): the action barely moves it
        self._other_hands = self._barely.tolist()
        self._hand_mask: np.ndarray | None = None  # per template, for the sensor in _hand_mask_key (_moving_hand)
        self._hand_mask_key: tuple[np.ndarray, int] | None = None
        self._hand_ref: list[float] = []  # each sensor's reading on the motion's first frame (_track_hands)
        self._sensor_peak = [0.0] * self._hands  # and its peak distance from it since
        self._hand_g0: list[float] | None = None  # the decided motion's onset gravity (_other_hand)
        self._hand_peak = [0.0] * self._hands  # its peak activity per sensor so far
        self._hand_action = 0  # its action
        self._tmpl_action = np.array([index[templates.actions[k]] for k in order])
        self._action_starts = np.flatnonzero(np.r_[True, np.diff(self._tmpl_action) != 0])
        self._action_ends = np.r_[self._action_starts[1:], len(order)]
        self.thresholds = templates.thresholds[order] if reject else np.full(len(order), np.inf)
        starts = self._gate_starts(templates, order)
        cut = [self._whole[k][1][on:] for k, on in zip(order, starts, strict=True)]
        self._peak_act = np.array([self._peaks(self._whole[k][0][on:]) for k, on in zip(order, starts, strict=True)])  # (T, 2)
        self._action_bar = np.minimum.reduceat(self._peak_act[:, 0], self._action_starts)  # per action
        self._turn_bar = np.minimum.reduceat(self._template_lin_share(given, order, starts), self._action_starts)  # per action
        self.template_lengths = np.array([len(c) for c in cut])
        self._strokes = shaken_actions(given, self.action_names, self.gate.noise_g)  # a relaunch ends none of these
        self.dtw = IncrementalDTW(cut, method=self._dtw_method, min_progress=self.min_progress)
        self._stop_scores = np.empty(len(cut))  # the scores when the hand stopped (`_stopped`)
        # A decided motion that outlasts the supplementary buffer keeps its DTW growing (one
        # row a frame, as before) up to this many frames, for the rules that weigh the whole
        # motion (rules.EXTEND_FACTOR); bounded so a hand that never rests costs nothing.
        self._extend_to = int(EXTEND_FACTOR * max(self.window, int(self.template_lengths.max()))) if extend else 0
        self._base = (cut, self._tmpl_action.copy(), self.thresholds.copy(), self._peak_act.copy())
        self._base_starts = self._action_starts.copy()
        self._is_adapted = np.zeros(len(order), dtype=bool)
        self._adapted: dict[int, list[tuple[np.ndarray, tuple[float, float]]]] = {}  # (motion, (early, window) peaks)

    def _track_hands(self, xs: list[float]) -> None:
        """Each sensor's peak distance from its reading on the motion's first frame, for
        `_moving_hand`: how far each hand has moved, whatever the gravity estimate (a first guess
        taken mid-motion made a still hand look like the moving one). Plain floats: two or three
        sensors a frame."""
        if self._hands > 1:
            if self.count == 1:  # the motion's first frame (a back-dated one included)
                self._hand_ref = xs
                self._sensor_peak = [0.0] * self._hands
            ref = self._hand_ref
            dev = [math.dist(xs[i : i + 3], ref[i : i + 3]) for i in range(0, 3 * self._hands, 3)]
            self._sensor_peak = [max(p, d) for p, d in zip(self._sensor_peak, dev, strict=True)]

    def _moving_hand(self, scores: np.ndarray) -> np.ndarray:
        """`scores` with the templates of the actions that barely move the sensor that has moved
        clearly the most since the onset set to inf (MOVING_HAND_RATIO); as they are with
        one sensor, while no sensor leads clearly, or when it would leave no action or mask none."""
        if self._hands < 2:
            return scores
        peaks = self._sensor_peak
        m = max(range(self._hands), key=peaks.__getitem__)
        bar = rules.MOVING_HAND_RATIO * peaks[m]
        if any(p >= bar for i, p in enumerate(peaks) if i != m):
            return scores
        cached = self._hand_mask_key  # the template order changes only when one is adopted (a new array)
        if cached is None or cached[0] is not self._tmpl_action or cached[1] != m:
            barely = self._barely[:, m]
            self._hand_mask = barely[self._tmpl_action] if barely.any() and not barely.all() else None
            self._hand_mask_key = (self._tmpl_action, m)
        return scores if self._hand_mask is None else np.where(self._hand_mask, np.inf, scores)

    def _first_usable(self, scores: np.ndarray) -> np.ndarray:
        """The scores the first decision sees: the tilted copies left out while any other template
        fits under its threshold (tilt.py: where the trained templates fit, a copy would blur a
        resting tilt that tells the kinds apart). Takes the scores after `_moving_hand`: a template
        of an action it rules out fits nothing. Adopted templates have their own rule there
        (rules.ADOPTED_LEAD). A template of one trial has no threshold (inf), which every score is
        under: it fits where the loosest known threshold would take it (with `reject` off every
        threshold is inf, and the copies stay out of the first decision)."""
        if not self._has_copies:
            return scores
        if self._fit_bar[0] is not self.thresholds:  # thresholds are a new array whenever they change
            bar = self.thresholds
            if self.reject and np.isinf(bar).any() and np.isfinite(bar).any():
                bar = np.where(np.isinf(bar), bar[np.isfinite(bar)].max(), bar)
            self._fit_bar = (self.thresholds, bar)
        fits = scores <= self._fit_bar[1]
        fits &= self._not_copy
        return np.where(self._is_copy, np.inf, scores) if fits.any() else scores

    def _recut(self) -> None:
        """The trained templates cut again for the DTW at the gate now. A live motion starts where
        the gate opens, so the templates must start where the same gate opens on them: with
        noise_g="auto" the gate learnt from the player's rest differs from the one the templates
        were first cut at, and a template cut at a higher gate starts later in its motion than the
        live query (docs/recognition.md, fourteenth round). Called at an onset when the gate has
        changed since the last cut; adopted templates are live motions and stay as they are. What
        was sized at construction stays: `_extend_to` (from the templates' first-cut lengths) and
        the motion buffers sized by it: a motion's DTW still grows for at most that many frames."""
        order = self._order
        cut = [self._whole[k][1][on:] for k, on in zip(order, self._gate_starts(self._trained, order), strict=True)]
        # Only the DTW's cut: the energy and turn bars (and which actions are shakes) stay the
        # trained motions' own at the gate they were first cut at (bars following the gate down
        # let a wiggle at rest start: the phone-boxing stream's false starts 1 -> 2).
        self._base = (cut, *self._base[1:])
        self._cut_gate = self.gate.noise_g
        self._set_templates()

    def _gate_starts(self, templates: Templates, order: np.ndarray) -> list[int]:
        """Where the gate now opens on each template of `order` (`NoiseGate.start_on`), once per
        source: a tilted copy's activity and onset are its source's."""
        at: dict[int, int] = {}
        for k in order:
            src = int(self._source[k])
            if src not in at:
                at[src] = self.gate.start_on(templates, src, self._whole[src][0])
        return [at[int(self._source[k])] for k in order]

    def _template_lin_share(self, given: Templates, order: np.ndarray, starts: list[int]) -> np.ndarray:
        """(T,) each template's peak of `linear` over its peak activity, both over its first
        ENERGY_FRAMES frames from its onset (`starts`): how little of its early activity a turn of
        the hand explains (see rules.TURN_RATIO). A copy's is its source's (in `given`)."""
        out = []
        for k, on in zip(order, starts, strict=True):
            src = int(self._source[k])
            act = self._whole[src][0][on : on + ENERGY_FRAMES]
            lin = linear(given.signals[src], given.gravity[src])[on : on + ENERGY_FRAMES]
            out.append(float(lin.max() / act.max()) if len(act) and act.max() > 0 else 0.0)
        return np.array(out)

    def _peaks(self, act: np.ndarray) -> tuple[float, float]:
        """(early, window) peaks of an activity series from its onset."""
        if not len(act):
            return 0.0, 0.0
        return float(act[:ENERGY_FRAMES].max()), float(act[: self.window].max())

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
            self._is_copy = _inserted(self._is_copy, hi, False)
            self._not_copy = ~self._is_copy
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
        self._is_copy = np.r_[self._base_copy, np.zeros(len(extra), dtype=bool)][order]
        self._not_copy = ~self._is_copy
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
