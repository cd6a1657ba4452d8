"""Sounds synthesized with numpy at start-up: a punch whoosh, a hit thud, a blocked knock and the
ring bell. No files. Where there is no audio device (CI, a headless run) the mixer is not
opened and `play` does nothing: the game never fails for want of a sound card."""

from __future__ import annotations

import numpy as np
import pygame

RATE = 22050


def _env(n: int, attack: float, decay: float) -> np.ndarray:
    t = np.arange(n) / RATE
    a = np.minimum(1.0, t / max(attack, 1e-4))
    return a * np.exp(-t / decay)


def synth_punch(rng: np.random.Generator) -> np.ndarray:
    """A short whoosh: band-limited noise with a rising then falling envelope."""
    n = int(0.18 * RATE)
    noise = rng.standard_normal(n)
    # a crude band-pass: difference of two moving averages
    k1, k2 = 4, 40
    lo = np.convolve(noise, np.ones(k1) / k1, mode="same")
    lo2 = np.convolve(noise, np.ones(k2) / k2, mode="same")
    t = np.arange(n) / n
    return (lo - lo2) * np.sin(np.pi * t) ** 2 * 0.6


def synth_hit(rng: np.random.Generator, heavy: bool = True) -> np.ndarray:
    """A thud: a low sine sweeping down plus a noisy slap."""
    n = int(0.25 * RATE)
    t = np.arange(n) / RATE
    f = (110.0 if heavy else 170.0) * np.exp(-t * 6)
    body = np.sin(2 * np.pi * np.cumsum(f) / RATE) * _env(n, 0.002, 0.07)
    slap = rng.standard_normal(n) * _env(n, 0.0005, 0.012)
    return 0.9 * body + 0.5 * slap


def synth_block(rng: np.random.Generator) -> np.ndarray:
    n = int(0.12 * RATE)
    t = np.arange(n) / RATE
    return 0.5 * np.sin(2 * np.pi * 420 * t) * _env(n, 0.001, 0.02) + 0.2 * rng.standard_normal(n) * _env(n, 0.0005, 0.008)


def synth_bell() -> np.ndarray:
    """The ring bell: inharmonic partials with long decays, struck three times."""
    n = int(1.6 * RATE)
    t = np.arange(n) / RATE
    partials = ((1.0, 1.0, 0.9), (2.76, 0.5, 0.6), (5.4, 0.25, 0.35), (8.93, 0.12, 0.2))
    ding = sum(a * np.sin(2 * np.pi * 880 * r * t) * np.exp(-t / d) for r, a, d in partials)
    out = np.zeros(n)
    for k in range(3):
        off = int(k * 0.22 * RATE)
        out[off:] += ding[: n - off]
    return out * 0.25


def to_int16(x: np.ndarray) -> np.ndarray:
    peak = float(np.max(np.abs(x))) or 1.0
    return (x / max(peak, 1.0) * 32000).astype(np.int16)


class Sounds:
    """The game's sounds; silent (not failing) when no mixer can be opened."""

    def __init__(self, enabled: bool = True, seed: int = 0):
        self.enabled = False
        self._sounds: dict[str, pygame.mixer.Sound] = {}
        self.waves: dict[str, np.ndarray] = {}
        if not enabled:
            return  # nothing synthesized (~3 ms, 0.4 MB) for a match without sound
        rng = np.random.default_rng(seed)
        self.waves = {
            "punch": synth_punch(rng),
            "hit": synth_hit(rng, heavy=True),
            "hit_light": synth_hit(rng, heavy=False),
            "block": synth_block(rng),
            "bell": synth_bell(),
        }
        try:
            if not pygame.mixer.get_init():
                pygame.mixer.init(frequency=RATE, size=-16, channels=1, buffer=512)
            freq, _, channels = pygame.mixer.get_init()
        except pygame.error:
            return  # no audio device: stay silent
        for name, wave in self.waves.items():
            data = to_int16(wave)
            if freq != RATE:  # the device chose its own rate: resample linearly
                m = int(len(data) * freq / RATE)
                data = np.interp(np.linspace(0, len(data) - 1, m), np.arange(len(data)), data).astype(np.int16)
            if channels > 1:
                data = np.repeat(data[:, None], channels, axis=1)
            self._sounds[name] = pygame.sndarray.make_sound(np.ascontiguousarray(data))
        self.enabled = True

    def play(self, name: str, volume: float = 1.0) -> None:
        snd = self._sounds.get(name)
        if snd is not None:
            snd.set_volume(max(0.0, min(1.0, volume)))
            snd.play()
