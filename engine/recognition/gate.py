"""The noise gate (paper IV-A): gravity tracking, the gate itself, the "auto" gate learnt from the
resting noise, and the back-dating of an onset. DualBufferRecognizer owns one (`self.gate`)."""

from __future__ import annotations

import math

import numpy as np

from engine.recognition.templates import Templates, activity

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
# ratcheted the gate up to its cap (most phone punches were lost). Kept across reset().
AUTO_K = 2.0
AUTO_QUANTILE = 90
AUTO_MIN_G = 0.3
AUTO_MAX_G = 2.0
AUTO_START_G = 1.0
AUTO_FRAMES = 120
AUTO_MIN_FRAMES = 30
AUTO_EVERY = 10
# One exception to the freeze (sixteenth round): a hand that has not once dropped under the gate
# for BUSY_FRAMES frames (10 s) moves all the time (a boxer bouncing on the feet, after standing
# still while the gate was learnt), so the gate is under the player's floor of motion and no
# motion ever ends by the null signal. It is raised to AUTO_K x the BUSY_QUANTILE percentile of
# those frames' activity (within the AUTO bounds, never lowered).
BUSY_FRAMES = 600
BUSY_QUANTILE = 25


def percentile(values: np.ndarray, q: float) -> float:
    """`np.percentile(values, q)` (its default linear method), bit for bit, for finite values.
    numpy's own calls np.unique, which imports numpy.ma (1.3 MB, 7 ms here) the first time: on
    the auto gate's first learning, inside a game frame."""
    a = np.array(values, dtype=np.float64)  # partitioned in place
    n = len(a)
    v = (n - 1) * (q / 100)
    if v >= n - 1:
        return float(a.max())
    lo = max(math.floor(v), 0)
    a.partition((lo, lo + 1))
    x, y = a[lo], a[lo + 1]
    t = v - lo
    d = y - x
    return float(y - d * (1 - t)) if t >= 0.5 else float(x + d * t)


class NoiseGate:
    """Gravity per sensor and whether a frame is above the gate (`noise_g`, learnt when "auto").
    After each `step`: `xs` (the frame, plain floats), `act` (the gate's activity, sum over sensors
    of |a - g|) and `lin` (sum of ||a| - |g||, what a turn of the hand does not make)."""

    def __init__(self, noise_g: float | str, templates: Templates):
        """The gate to start with: `noise_g` as given, or for "auto" the one from the training
        trials' rest (Templates.rest_noise), else AUTO_START_G."""
        self.auto = noise_g == "auto"
        if self.auto:
            noise_g = self.auto_gate(templates.rest_noise) if np.isfinite(templates.rest_noise) else AUTO_START_G
        elif not isinstance(noise_g, (int, float, np.integer, np.floating)):
            raise ValueError(f"noise_g must be a number of g or 'auto', not {noise_g!r}")
        self.noise_g = float(noise_g)
        self._idle_acts = np.empty(AUTO_FRAMES)  # the activity on the last idle frames (ring), for "auto"
        self._n_idle = 0
        self._busy_acts = np.empty(BUSY_FRAMES)  # the activity on the last frames (ring), see BUSY_FRAMES
        self.reset()

    def reset(self) -> None:
        """Forget gravity (the learnt gate is kept: see AUTO_*)."""
        self.gravity: np.ndarray | None = None
        self._last: list[float] | None = None  # the previous frame, plain floats
        self._mean: list[float] = []
        self._still = 0
        self._steady = 0
        self.unchanged = 0  # frames in a row whose reading has not changed (UNCHANGED_FRAMES)
        self._busy = 0  # frames in a row over the gate
        self.xs: list[float] = []
        self.act = 0.0
        self.lin = 0.0

    @staticmethod
    def auto_gate(noise: float) -> float:
        return float(min(max(AUTO_K * noise, AUTO_MIN_G), AUTO_MAX_G))

    def start_on(self, templates: Templates, k: int, act: np.ndarray | None = None) -> int:
        """Where this gate's onset would be on template k: the start of the run of
        above-gate frames that holds the template's trimmed onset (earlier wiggles separated by
        quiet frames are not the motion); the first above-gate frame after the onset when the
        onset itself is gentler than the gate; the onset when the gate never opens. Then
        back-dated as the recognizer does (`backdate`). `act`: the template's activity, if known."""
        if act is None:
            act = activity(templates.signals[k], templates.gravity[k])
        on = int(templates.onsets[k])
        if act[on] < self.noise_g:
            later = np.flatnonzero(act[on:] >= self.noise_g)
            if not len(later):
                return on
            on += int(later[0])
        while on > 0 and act[on - 1] >= self.noise_g:
            on -= 1
        return on - self.backdate(act[max(0, on - BACKDATE_MAX) : on])

    def learn(self, act: float) -> None:
        """noise_g="auto": one more resting frame's activity; now and then the gate from them."""
        self._idle_acts[self._n_idle % AUTO_FRAMES] = act
        self._n_idle += 1
        if self._n_idle >= AUTO_MIN_FRAMES and self._n_idle % AUTO_EVERY == 0:
            self.noise_g = self.auto_gate(percentile(self._idle_acts[: min(self._n_idle, AUTO_FRAMES)], AUTO_QUANTILE))

    def backdate(self, before: np.ndarray) -> int:
        """How many of the frames just before the gate opened (activity `before`, oldest first)
        belong to the motion: the run at the end whose activity reaches ONSET_FRACTION of the gate."""
        low = np.flatnonzero(before < ONSET_FRACTION * self.noise_g)
        return len(before) - (int(low[-1]) + 1 if len(low) else 0)

    def step(self, x: np.ndarray, in_motion: bool, decided: bool) -> bool:
        """Update the gravity estimate and say whether this frame is valid (above the gate);
        `in_motion`: a motion is being recognized, `decided`: its buffers are full.
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
        still_now, unchanged_now, steady_now, act, lin = True, True, True, 0.0, 0.0
        a, still_d2, steady2 = STEADY_ALPHA, STILL_DELTA_G**2, STEADY_G**2  # (globals: read once)
        for k in range(0, len(xs), 3):
            ax, ay, az = xs[k], xs[k + 1], xs[k + 2]
            dx, dy, dz = ax - last[k], ay - last[k + 1], az - last[k + 2]
            size = math.sqrt(ax * ax + ay * ay + az * az)
            if dx * dx + dy * dy + dz * dz >= still_d2:
                still_now = unchanged_now = False
            elif abs(size - 1.0) >= STILL_NORM_TOL:
                still_now = False
            mx, my, mz = mean[k] + a * (ax - mean[k]), mean[k + 1] + a * (ay - mean[k + 1]), mean[k + 2] + a * (az - mean[k + 2])
            mean[k], mean[k + 1], mean[k + 2] = mx, my, mz
            ex, ey, ez = ax - mx, ay - my, az - mz
            if ex * ex + ey * ey + ez * ez >= steady2:
                steady_now = False
            gx, gy, gz = ax - g[k], ay - g[k + 1], az - g[k + 2]
            act += math.sqrt(gx * gx + gy * gy + gz * gz)
            # how far the reading's magnitude is from gravity's (a turn of the hand keeps it)
            lin += abs(size - math.sqrt(g[k] * g[k] + g[k + 1] * g[k + 1] + g[k + 2] * g[k + 2]))
        self._last = self.xs = xs
        self._still = self._still + 1 if still_now else 0
        self.unchanged = self.unchanged + 1 if unchanged_now else 0
        self._steady = self._steady + 1 if steady_now else 0
        if self._still >= STILL_FRAMES:
            self.gravity[:] = x
            act = lin = 0.0
        elif self._steady >= RECOVER_FRAMES and act >= self.noise_g and (not in_motion or decided):
            self.gravity[:] = mean
            act = lin = 0.0
        valid = act >= self.noise_g
        if self.auto:
            self._busy_acts[self._busy % BUSY_FRAMES] = act
            self._busy = self._busy + 1 if valid else 0
            if self._busy >= BUSY_FRAMES:
                self.noise_g = max(self.noise_g, self.auto_gate(percentile(self._busy_acts, BUSY_QUANTILE)))
                self._busy = 0
        self.act = act
        self.lin = lin
        if not valid and not in_motion:
            self.gravity += GRAVITY_FOLLOW * (x - self.gravity)
        return valid

