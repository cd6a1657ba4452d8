"""`demo://?rate=100`: a synthetic two-hand source for trying things without a device.

Deterministic: sample k (at `start + k / rate` on the given clock) depends on k alone, so a
demo under a virtual clock is reproducible to the bit. Both hands rest with gravity on +z
and throw a punch in turn every 0.75 s (a 2.5 g windowed sine on x), with a slow sway and a
small high-frequency wobble standing in for sensor noise.
"""

from __future__ import annotations

import numpy as np

from engine.sensors.source import (
    Clock,
    Sample,
    Source,
    SourceError,
    SourceState,
    parse_source_url,
    register_scheme,
    url_number,
    url_params_known,
)

PUNCH_EVERY_S = 0.75
PUNCH_S = 0.3
PUNCH_G = 2.5
MIN_RATE_HZ = 1.0  # slower than any sensor (gloves send 25 Hz)
MAX_RATE_HZ = 10_000.0  # faster than any sensor; 1e9 made a poll build a billion samples


def demo_accel(t: np.ndarray) -> np.ndarray:
    """(n,) seconds since the start -> (n, 2, 3) accel in g for the right and left hands."""
    t = np.asarray(t, dtype=np.float64)
    out = np.zeros((len(t), 2, 3))
    out[:, :, 2] = 1.0  # gravity
    for hand, phase in ((0, 0.0), (1, 1.7)):
        out[:, hand, 0] += 0.08 * np.sin(2 * np.pi * 0.5 * t + phase)
        out[:, hand, 1] += 0.05 * np.sin(2 * np.pi * 0.31 * t + phase)
        out[:, hand, :] += 0.02 * np.sin(2 * np.pi * 23.0 * t[:, None] + phase + np.arange(3))
    # punches alternate hands: right on even slots, left on odd ones
    slot = np.floor(t / PUNCH_EVERY_S)
    u = (t - slot * PUNCH_EVERY_S) / PUNCH_S  # 0..1 during the punch
    active = u < 1.0
    wave = np.where(active, PUNCH_G * np.sin(2 * np.pi * u) * np.sin(np.pi * np.clip(u, 0, 1)), 0.0)
    hand = (slot % 2).astype(int)
    rows = np.arange(len(t))
    out[rows, hand, 0] += wave
    out[rows, hand, 2] -= 0.4 * wave * (hand == 0)  # a little lift on the right hand's punches
    return out


class DemoSource(Source):
    def __init__(self, *, url: str = "demo://", clock: Clock, rate_hz: float = 100.0):
        if not rate_hz > 0:
            raise SourceError(f"{url}: rate must be positive")
        super().__init__(url=url, sensors=2, clock=clock, description="demo: synthetic sine-wave punches")
        self.rate_hz = rate_hz
        self._start = clock()
        self._next = 0
        self.state = SourceState.CONNECTED

    def poll(self) -> list[Sample]:
        if self.state is not SourceState.CONNECTED:
            return []
        due = int(np.floor((self.clock() - self._start) * self.rate_hz + 1e-9)) + 1
        if due <= self._next:
            return []
        k = np.arange(self._next, due)
        self._next = due
        rel = k / self.rate_hz
        accel = demo_accel(rel)
        return [Sample(self._start + float(r), a) for r, a in zip(rel, accel, strict=True)]


def open_demo(url: str, clock: Clock) -> DemoSource:
    _, _, params = parse_source_url(url)
    url_params_known(url, params, ("rate",))
    rate = url_number(url, params, "rate", 100.0, MIN_RATE_HZ, MAX_RATE_HZ)
    return DemoSource(url=url, clock=clock, rate_hz=rate)


register_scheme("demo", open_demo)
