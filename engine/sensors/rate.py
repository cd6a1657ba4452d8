"""Measured sample rate of a live source, from the samples' own timestamps."""

from __future__ import annotations

from collections import deque

from engine.sensors.source import Sample


class RateMeter:
    """Samples per second over the last `window_s` seconds of sample time."""

    def __init__(self, window_s: float = 1.0):
        self.window_s = window_s
        self._times: deque[float] = deque()
        self.total = 0

    def add(self, samples: list[Sample]) -> None:
        times = self._times
        for s in samples:
            times.append(s.t)
        self.total += len(samples)
        if times:
            cutoff = times[-1] - self.window_s
            while times and times[0] < cutoff:
                times.popleft()

    def rate_hz(self, now: float | None = None) -> float:
        """Samples per second in the window; 0 when fewer than two samples, or when `now` is
        given and the last sample is older than the window (the source went quiet)."""
        times = self._times
        if len(times) < 2 or (now is not None and now - times[-1] > self.window_s):
            return 0.0
        span = times[-1] - times[0]
        return (len(times) - 1) / span if span > 0 else 0.0
