"""The virtual player: what a Wiimote (right hand) and a Nunchuk (left hand) would read while a
person performs an action of the library.

From the clip's hand trajectories (root motion included, so steps move the hands too):
  acceleration = second derivative of position (60 Hz),
  reading      = acceleration - gravity, in g (a sensor at rest reads +1 g upwards),
rotated into a sensor frame that follows the forearm (y along elbow -> fist, z the part of
"up" across the forearm, x completing it; a small grip roll per trial), plus noise, quantised
to the Wiimote's ~1/26 g steps and clipped at each device's range.

A person holding controllers makes a smaller, smoother gesture than the boxer on screen:
GESTURE_SCALE shrinks the hand displacement from the guard and a short smoothing stands for
the arm's inertia, so a punch peaks at a few g as real Wiimote punches do.

Profiles vary tempo and amplitude per trial (experienced about +-10 %, novice +-30 %); the
novice also starts sloppily (a hesitant wobble, one hand late), mixes in part of a
neighbouring action and is noisier.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from engine.clock import STEP_HZ
from game.actions import Action
from game.skeleton import joint_index

FPS = float(STEP_HZ)
G = 9.81
QUANTUM_G = 1.0 / 26.0  # Wiimote ADC step: ~26 counts per g
RANGE_G = np.array([3.5, 2.0])  # clip: Wiimote (right, index 0), Nunchuk (left, index 1)
HANDS = ("r", "l")  # sensor index 0 = right hand (Wiimote), 1 = left (Nunchuk)
GESTURE_SCALE = 0.25  # a controller gesture vs. the boxer's full punch (which peaks at 12-28 g)
STEP_GESTURE_SCALE = 1.5  # a step: hands carried with the body and pushed the way it goes
SMOOTH_FRAMES = 2.5  # Gaussian sigma (frames) of the arm's low-pass

# the action a novice's motion drifts towards (similar shape, same hand)
NEIGHBOURS = {
    "straight_l": "hook_l", "straight_r": "hook_r", "hook_l": "straight_l", "hook_r": "straight_r",
    "uppercut_l": "straight_l", "uppercut_r": "straight_r", "parry_l": "block", "parry_r": "block",
    "block": "parry_r", "step_forward": "step_left", "step_back": "step_right",
    "step_left": "step_back", "step_right": "step_forward",
}  # fmt: skip


@dataclass(frozen=True)
class Profile:
    name: str
    tempo: float  # +- fraction of the clip's duration
    amplitude: float  # +- fraction of the hand displacement
    noise_g: float  # sensor noise sigma
    grip_roll_deg: float  # +- how the controller sits in the fist
    neighbour_mix: tuple[float, float]  # fraction of the neighbouring action mixed in
    sloppy_frames: tuple[int, int]  # hesitant wobble before the action starts
    hand_lag_frames: int  # the idle hand may lag by up to this


PROFILES: dict[str, Profile] = {
    "experienced": Profile("experienced", 0.10, 0.10, 0.015, 4.0, (0.0, 0.0), (0, 0), 0),
    "novice": Profile("novice", 0.30, 0.30, 0.05, 15.0, (0.10, 0.30), (3, 12), 4),
}


def _profile(profile: str | Profile) -> Profile:
    if isinstance(profile, Profile):
        return profile
    try:
        return PROFILES[profile]
    except KeyError:
        raise ValueError(f"unknown player profile {profile!r}; profiles: {', '.join(PROFILES)}") from None


_KERNELS: dict[float, np.ndarray] = {}


def _gauss(sigma: float) -> np.ndarray:
    k = _KERNELS.get(sigma)
    if k is None:
        r = int(np.ceil(3 * sigma))
        k = np.exp(-0.5 * (np.arange(-r, r + 1) / sigma) ** 2)
        k /= k.sum()
        k.flags.writeable = False
        _KERNELS[sigma] = k
    return k


def _smooth(x: np.ndarray, sigma: float) -> np.ndarray:
    """Gaussian smoothing along axis 0 with edge padding (rest stays rest). The taps are summed
    in order from 0.0, each output value as `out += w * shifted` tap by tap would, in one
    reduction over a (taps, n, ...) view of the padded signal (a key press synthesizes inside
    the 60 Hz input stage, and the tap-by-tap loop was 34 numpy calls)."""
    if sigma <= 0:
        return x
    k = _gauss(sigma)
    r = len(k) // 2
    pad = np.concatenate([np.repeat(x[:1], r, 0), x, np.repeat(x[-1:], r, 0)])
    shifted = np.lib.stride_tricks.as_strided(pad, (len(k), *x.shape), (pad.strides[0], *pad.strides), writeable=False)
    return np.add.reduce(k.reshape(-1, *[1] * x.ndim) * shifted, axis=0, initial=0.0)


# hand_motion depends on (action, n) only; the keyboard source synthesizes on a key press,
# inside the 60 Hz input stage, so the clip sampling (half a synthesis) is done once per
# (action, n). Entries hold the action itself so an id is never reused while cached.
_HAND_MOTION_CACHE: dict[tuple[int, int], tuple[Action, np.ndarray, np.ndarray]] = {}
_HAND_MOTION_CACHE_MAX = 1024


def hand_motion(action: Action, n: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Fists (n, 2, 3) and forearm directions (n, 2, 3), hands ordered (right, left), in the
    clip's starting frame (root motion applied), resampled to n frames (default: the clip's).
    The arrays are cached and read-only."""
    n = action.frames if n is None else max(int(n), 2)
    hit = _HAND_MOTION_CACHE.get((id(action), n))
    if hit is not None and hit[0] is action:
        return hit[1], hit[2]
    fists, elbows = _hand_motion(action, n)
    fists.flags.writeable = False
    elbows.flags.writeable = False
    if len(_HAND_MOTION_CACHE) >= _HAND_MOTION_CACHE_MAX:
        _HAND_MOTION_CACHE.clear()
    _HAND_MOTION_CACHE[(id(action), n)] = (action, fists, elbows)
    return fists, elbows


def _hand_motion(action: Action, n: int) -> tuple[np.ndarray, np.ndarray]:
    fs = np.linspace(0.0, action.frames - 1.0, n)
    postures, root = action.sample(fs)
    c, s = np.cos(root[:, 2]), np.sin(root[:, 2])
    fists, elbows = [], []
    for hand in HANDS:
        for out, joint in ((fists, f"fist_{hand}"), (elbows, f"elbow_{hand}")):
            p = postures[:, joint_index(joint)]
            # local -> clip-start frame: rotate by the root yaw, then translate
            wx = c * p[:, 0] + s * p[:, 2] + root[:, 0]
            wz = -s * p[:, 0] + c * p[:, 2] + root[:, 1]
            out.append(np.column_stack([wx, p[:, 1], wz]))
    return np.stack(fists, axis=1), np.stack(elbows, axis=1)


_ROLL1, _ROLL2 = np.array([1, 2, 0]), np.array([2, 0, 1])
_UP, _FORWARD = np.array([0.0, 1.0, 0.0]), np.array([0.0, 0.0, 1.0])


def sensor_frames(forearm: np.ndarray, roll: np.ndarray) -> np.ndarray:
    """(n, 2, 3, 3) rotation rows [x, y, z] of each sensor: y along the forearm, z the part of
    world up across it (rolled by `roll` radians per hand), x = y cross z."""
    # norms as np.linalg.norm takes them (sqrt of the reduced squares), without its checks
    y = forearm / np.maximum(np.sqrt(np.add.reduce(forearm * forearm, axis=-1, keepdims=True)), 1e-9)
    # y . up is y's vertical component (x 0 and z 0 add only a signed zero, which the
    # subtraction from up turns into the same +0.0)
    z = _UP - y * y[..., 1:2]
    zn = np.sqrt(np.add.reduce(z * z, axis=-1, keepdims=True))
    z = np.where(zn > 1e-6, z / np.maximum(zn, 1e-9), _FORWARD)
    # y cross z: np.cross's own products and differences (x0 = y1 z2 - y2 z1, ...), on the
    # components rolled by one and by two
    x = y[..., _ROLL1] * z[..., _ROLL2] - y[..., _ROLL2] * z[..., _ROLL1]
    cr, sr = np.cos(roll)[None, :, None], np.sin(roll)[None, :, None]
    rot = np.empty((*y.shape[:-1], 3, 3))
    rot[..., 0, :] = cr * x + sr * z
    rot[..., 1, :] = y
    rot[..., 2, :] = -sr * x + cr * z
    return rot


def readings(fists: np.ndarray, forearm: np.ndarray, roll: np.ndarray) -> np.ndarray:
    """Noise-free accelerometer readings (n, 2, 3) in g from hand positions at 60 Hz."""
    pad = np.concatenate([fists[:1], fists, fists[-1:]])
    acc = (pad[2:] - 2.0 * pad[1:-1] + pad[:-2]) * (FPS * FPS)
    specific = acc / G + _UP  # what an accelerometer feels: a - g
    rot = sensor_frames(forearm, roll)
    return np.einsum("nhij,nhj->nhi", rot, specific)


_LOW_G, _HIGH_G = -RANGE_G[None, :, None], RANGE_G[None, :, None]


def finish(signal: np.ndarray, noise_g: float, rng: np.random.Generator) -> np.ndarray:
    """Add sensor noise, quantise to the Wiimote's steps and clip at each device's range."""
    out = signal + rng.normal(0.0, noise_g, signal.shape)
    out = np.round(out / QUANTUM_G) * QUANTUM_G
    return np.minimum(np.maximum(out, _LOW_G), _HIGH_G)  # np.clip's values, without its wrapper


def performed_motion(action: Action, prof: Profile, rng: np.random.Generator,
                     library: dict[str, Action] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The hand positions and forearm directions of one performance (before the sensor)."""  # fmt: skip
    n = int(round(action.frames * rng.uniform(1.0 - prof.tempo, 1.0 + prof.tempo)))
    fists, elbows = hand_motion(action, n)
    rest_f, rest_e = fists[0].copy(), elbows[0].copy()
    neighbour = NEIGHBOURS.get(action.name)
    if library is not None and neighbour in library and prof.neighbour_mix[1] > 0:
        w = rng.uniform(*prof.neighbour_mix)
        nf, ne = hand_motion(library[neighbour], n)
        fists = (1.0 - w) * fists + w * (nf - nf[0] + rest_f)
        elbows = (1.0 - w) * elbows + w * (ne - ne[0] + rest_e)
    base = STEP_GESTURE_SCALE if action.kind == "step" else GESTURE_SCALE
    amp = base * rng.uniform(1.0 - prof.amplitude, 1.0 + prof.amplitude, size=(1, 2, 1))
    fists = rest_f + (fists - rest_f) * amp
    elbows = rest_e + (elbows - rest_e) * amp
    if prof.hand_lag_frames:
        lag = int(rng.integers(0, prof.hand_lag_frames + 1))
        h = int(rng.integers(0, 2))
        if lag:
            fists[:, h] = np.concatenate([np.repeat(fists[:1, h], lag, 0), fists[:-lag, h]])
            elbows[:, h] = np.concatenate([np.repeat(elbows[:1, h], lag, 0), elbows[:-lag, h]])
    if prof.sloppy_frames[1] > 0:
        k = int(rng.integers(prof.sloppy_frames[0], prof.sloppy_frames[1] + 1))
        wobble = np.sin(np.linspace(0.0, np.pi, k))[:, None, None] * rng.normal(0.0, 0.02, (1, 2, 3))
        fists = np.concatenate([rest_f + wobble, fists])
        elbows = np.concatenate([np.repeat(rest_e[None], k, 0), elbows])
    # both smoothed in one pass (the same arithmetic per element, half the numpy calls)
    both = _smooth(np.concatenate([fists, elbows], axis=1), SMOOTH_FRAMES)
    return both[:, :2], both[:, 2:]


def synthesize_action(
    action: Action,
    profile: str | Profile = "experienced",
    rng: np.random.Generator | None = None,
    rest_before: int = 0,
    rest_after: int = 0,
    library: dict[str, Action] | None = None,
) -> np.ndarray:
    """(n, 2, 3) readings in g of the Wiimote (right hand, index 0) and Nunchuk (left, index 1)
    at 60 Hz while `action` is performed, with `rest_before`/`rest_after` frames of the guard
    held still. `library` lets the novice mix in a neighbouring action (default: the shipped
    library)."""
    prof = _profile(profile)
    rng = rng if rng is not None else np.random.default_rng()
    if library is None and prof.neighbour_mix[1] > 0:
        from game.actions import load_library

        library = load_library()
    fists, elbows = performed_motion(action, prof, rng, library)
    if rest_before or rest_after:  # (a key press has neither: 6 numpy calls saved)
        fists = np.concatenate([np.repeat(fists[:1], rest_before, 0), fists, np.repeat(fists[-1:], rest_after, 0)])
        elbows = np.concatenate([np.repeat(elbows[:1], rest_before, 0), elbows, np.repeat(elbows[-1:], rest_after, 0)])
    roll = np.radians(rng.uniform(-prof.grip_roll_deg, prof.grip_roll_deg, 2))
    return finish(readings(fists, fists - elbows, roll), prof.noise_g, rng)


def synthesize_rest(frames: int, action: Action, profile: str | Profile = "experienced",
                    rng: np.random.Generator | None = None) -> np.ndarray:
    """(frames, 2, 3) readings of hands held at the start posture of `action` (the guard)."""  # fmt: skip
    prof = _profile(profile)
    rng = rng if rng is not None else np.random.default_rng()
    return finish(_rest_readings(action, max(frames, 0)), prof.noise_g, rng)


# The noise-free readings of hands at rest depend on (action, frames) only, and the keyboard
# source asks for the same rest chunk every second inside the 60 Hz input stage: computed once.
_REST_CACHE: dict[tuple[int, int], tuple[Action, np.ndarray]] = {}


def _rest_readings(action: Action, frames: int) -> np.ndarray:
    hit = _REST_CACHE.get((id(action), frames))
    if hit is not None and hit[0] is action:
        return hit[1]
    fists, elbows = hand_motion(action, 2)
    fists = np.repeat(fists[:1], frames, 0)
    elbows = np.repeat(elbows[:1], frames, 0)
    out = readings(fists, fists - elbows, np.zeros(2))
    out.flags.writeable = False
    if len(_REST_CACHE) >= _HAND_MOTION_CACHE_MAX:
        _REST_CACHE.clear()
    _REST_CACHE[(id(action), frames)] = (action, out)
    return out


class VirtualPlayerStream:
    """Frame-by-frame readings of a virtual player who rests at the guard until told to
    perform an action (for a keyboard-driven source): `perform(name)` queues the action's
    whole signal, `next_frame()` returns the next (2, 3) reading in g. Performing while an
    action is still under way starts the new one at once (as a player would)."""

    def __init__(self, lib: dict[str, Action], profile: str | Profile = "experienced",
                 rng: np.random.Generator | None = None, rest_chunk: int = 60):  # fmt: skip
        self.lib = lib
        self.profile = _profile(profile)
        self.rng = rng if rng is not None else np.random.default_rng()
        self._rest_chunk = max(int(rest_chunk), 1)
        self._queue = np.zeros((0, 2, 3))
        self._pos = 0
        self.performing: str | None = None  # the action whose signal is being played, if any

    def perform(self, name: str) -> int:
        """Start performing `name`; returns its length in frames."""
        if name not in self.lib:
            raise KeyError(f"no action {name!r} in the library")
        signal = synthesize_action(self.lib[name], self.profile, self.rng, library=self.lib)
        self._queue, self._pos, self.performing = signal, 0, name
        return len(signal)

    @property
    def waiting(self) -> bool:
        """A move performed whose first reading has not been given yet."""
        return self.performing is not None and self._pos == 0

    def rest_frame(self) -> np.ndarray:
        """A reading of the hands at rest, a waiting move left to wait (a paused match holds it)."""
        return synthesize_rest(1, self.lib["guard"], self.profile, self.rng)[0]

    def next_frame(self) -> np.ndarray:
        if self._pos >= len(self._queue):
            self._queue = synthesize_rest(self._rest_chunk, self.lib["guard"], self.profile, self.rng)
            self._pos, self.performing = 0, None
        frame = self._queue[self._pos]
        self._pos += 1
        return frame
