"""The virtual player's synthesis was rewritten for fewer numpy calls (a key press synthesizes
a whole motion inside the 60 Hz input stage). The readings must be the same bits as before:
the former code is kept here as the reference, and every action of both profiles is
synthesized both ways from the same random state."""

from __future__ import annotations

import numpy as np
import pytest

from game import virtual_player as vp
from game.actions import load_library


def smooth_tap_by_tap(x: np.ndarray, sigma: float) -> np.ndarray:
    if sigma <= 0:
        return x
    r = int(np.ceil(3 * sigma))
    k = np.exp(-0.5 * (np.arange(-r, r + 1) / sigma) ** 2)
    k /= k.sum()
    pad = np.concatenate([np.repeat(x[:1], r, 0), x, np.repeat(x[-1:], r, 0)])
    out = np.zeros_like(x)
    for i, w in enumerate(k):
        out += w * pad[i : i + len(x)]
    return out


def sensor_frames_before(forearm: np.ndarray, roll: np.ndarray) -> np.ndarray:
    y = forearm / np.maximum(np.linalg.norm(forearm, axis=-1, keepdims=True), 1e-9)
    up = np.array([0.0, 1.0, 0.0])
    z = up - y * (y @ up)[..., None]
    zn = np.linalg.norm(z, axis=-1, keepdims=True)
    z = np.where(zn > 1e-6, z / np.maximum(zn, 1e-9), np.array([0.0, 0.0, 1.0]))
    x = np.empty_like(y)
    x[..., 0] = y[..., 1] * z[..., 2] - y[..., 2] * z[..., 1]
    x[..., 1] = y[..., 2] * z[..., 0] - y[..., 0] * z[..., 2]
    x[..., 2] = y[..., 0] * z[..., 1] - y[..., 1] * z[..., 0]
    cr, sr = np.cos(roll)[None, :, None], np.sin(roll)[None, :, None]
    x, z = cr * x + sr * z, -sr * x + cr * z
    return np.stack([x, y, z], axis=-2)


def finish_before(signal: np.ndarray, noise_g: float, rng: np.random.Generator) -> np.ndarray:
    out = signal + rng.normal(0.0, noise_g, signal.shape)
    out = np.round(out / vp.QUANTUM_G) * vp.QUANTUM_G
    return np.clip(out, -vp.RANGE_G[None, :, None], vp.RANGE_G[None, :, None])


@pytest.mark.parametrize("n", [2, 9, 24, 61])
def test_smoothing_in_one_reduction_is_the_tap_by_tap_sum(n):
    rng = np.random.default_rng(n)
    for shape in [(n, 4, 3), (n, 2, 3), (n,)]:
        x = rng.normal(0.0, 1.0, shape) * rng.choice([1e-3, 1.0, 1e3], shape)
        for sigma in (0.0, 0.7, vp.SMOOTH_FRAMES, 4.0):
            np.testing.assert_array_equal(vp._smooth(x, sigma), smooth_tap_by_tap(x, sigma))


def test_sensor_frames_are_the_former_bits():
    rng = np.random.default_rng(1)
    forearm = rng.normal(0.0, 1.0, (500, 2, 3))
    forearm[::7, :, 0] = 0.0
    forearm[::11] = [0.0, 1.0, 0.0]  # along "up": the fallback z
    forearm[::13] = 0.0  # no direction at all
    roll = rng.uniform(-0.3, 0.3, 2)
    np.testing.assert_array_equal(vp.sensor_frames(forearm, roll), sensor_frames_before(forearm, roll))


@pytest.mark.parametrize("profile", list(vp.PROFILES))
def test_synthesized_actions_are_the_former_bits(profile, monkeypatch):
    lib = load_library()
    names = [n for n in sorted(lib) if n != "guard"]
    new = [vp.synthesize_action(lib[n], profile, np.random.default_rng(i), library=lib) for i, n in enumerate(names * 3)]
    new_rest = vp.synthesize_rest(60, lib["guard"], profile, np.random.default_rng(99))
    monkeypatch.setattr(vp, "_smooth", smooth_tap_by_tap)
    monkeypatch.setattr(vp, "sensor_frames", sensor_frames_before)
    monkeypatch.setattr(vp, "finish", finish_before)
    old = [vp.synthesize_action(lib[n], profile, np.random.default_rng(i), library=lib) for i, n in enumerate(names * 3)]
    for a, b in zip(new, old, strict=True):
        np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(new_rest, vp.synthesize_rest(60, lib["guard"], profile, np.random.default_rng(99)))
