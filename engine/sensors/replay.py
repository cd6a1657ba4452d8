"""`replay://file.csv?speed=1&loop=0`: plays a recording back in (scaled) real time, as samples
stamped on the host clock, so everything downstream sees what a live device would send."""

from __future__ import annotations

import math

import numpy as np

from engine.clock import STEP_DT
from engine.recording import Recording, read_recording
from engine.sensors.source import (
    REWIND,
    Clock,
    Sample,
    Source,
    SourceError,
    SourceState,
    file_path,
    parse_source_url,
    register_scheme,
    url_number,
    url_params_known,
)

MIN_SPEED, MAX_SPEED = 0.01, 1000.0  # replay speed factors
# Samples a second a looped replay may owe (speed included): a 430 Hz phone file at the top speed
# owes 430,000. A loop of samples a nanosecond apart owed a billion: every poll a hang.
MAX_LOOP_RATE = 1e6


def _stated_rate(text: str | None) -> float | None:
    """A recording's `rate_hz` metadata as a rate, or None when absent or not a positive number."""
    try:
        rate = float(text) if text is not None else None
    except ValueError:
        return None
    return rate if rate is not None and math.isfinite(rate) and 0 < rate <= 1e6 else None


class ReplaySource(Source):
    capabilities = frozenset({REWIND})  # played out, it can play again (the game's Enter)

    def __init__(self, rec: Recording, *, url: str = "", clock: Clock, speed: float = 1.0, loop: bool = False):
        if speed <= 0:
            raise SourceError(f"{url}: speed must be positive, not {speed}")
        super().__init__(url=url, sensors=rec.sensors, clock=clock, description=rec.meta.get("source", "replay"))
        self.rec = rec
        self.file_notes = list(rec.notes)  # a row left out of the file (read_recording): said by who opened it
        self.speed = speed
        self.loop = loop
        self._rel = rec.t - rec.t[0]
        period = float(np.median(np.diff(self._rel))) if len(rec) > 1 else STEP_DT
        self._length = float(self._rel[-1]) + period  # one loop's duration
        if loop and len(rec) * speed > MAX_LOOP_RATE * self._length:  # once through, at most the file's samples
            raise SourceError(f"{url}: looped at speed {speed:g}, its {len(rec)} samples every {self._length:.3g} s come at "
                              f"{len(rec) * speed / self._length:.3g} a second, over the {MAX_LOOP_RATE:g} a second a replay delivers")
        # the rate the file says its samples came at (docs/formats.md) when its times agree within
        # 1 %, else the median period's: times written to 6 decimals made a 60 Hz file's 59.9988
        # (and `record` wrote that); a stated rate its times contradict is not taken
        stated = _stated_rate(rec.meta.get("rate_hz"))
        self.rate_hz = stated if stated and abs(stated * period - 1.0) < 0.01 else (1.0 / period if period > 0 else None)
        self.rewind()

    def rewind(self) -> None:
        """Play from the first sample again, starting now: the recording read once is kept (the
        file is not parsed again), only the playback position goes back."""
        self._start = self.clock()
        self._next = 0  # index of the next sample, counted across loops
        self.state = SourceState.CONNECTED

    def poll(self) -> list[Sample]:
        if self.state is not SourceState.CONNECTED:
            return []
        elapsed = (self.clock() - self._start) * self.speed
        n = len(self._rel)
        out: list[Sample] = []
        while True:
            lap, i = divmod(self._next, n)
            if lap and not self.loop:
                self.state = SourceState.ENDED
                break
            rel = self._rel[i] + lap * self._length
            if rel > elapsed:
                break
            out.append(Sample(float(self._start + rel / self.speed), self.rec.accel[i]))
            self._next += 1
        return out

    def label_at(self, t: float) -> str:
        """Ground-truth label at host time t (for evaluation and the HUD)."""
        rel = ((t - self._start) * self.speed) % self._length if self.loop else (t - self._start) * self.speed
        i = int(np.clip(np.searchsorted(self._rel, rel, side="right") - 1, 0, len(self._rel) - 1))
        return self.rec.labels[i]


def open_replay(url: str, clock: Clock) -> ReplaySource:
    _, path, params = parse_source_url(url)
    if not path:
        raise SourceError(f"{url}: no file (expected replay://path/to/recording.csv)")
    url_params_known(url, params, ("speed", "loop"))
    speed = url_number(url, params, "speed", 1.0, MIN_SPEED, MAX_SPEED)
    loop = params.get("loop", "0").lower() in ("1", "true", "yes")
    return ReplaySource(read_recording(file_path(path)), url=url, clock=clock, speed=speed, loop=loop)


register_scheme("replay", open_replay)
