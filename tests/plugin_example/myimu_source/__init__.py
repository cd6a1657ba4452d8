"""`myimu://?rate=50&sensors=1`: an example source package outside QuickJab's tree.

A stand-in for a user's own IMU: it delivers, on the given clock, one sample every 1/rate
seconds with every sensor at rest (gravity on +z, 1 g). Installed, its entry point in the
`quickjab.sources` group makes `open_source("myimu://...")` and `quickjab scope --source
myimu://` work without anything importing this package first.
"""

from __future__ import annotations

import numpy as np

from engine.sensors.source import Clock, Sample, Source, SourceState, parse_source_url, url_number


class MyImuSource(Source):
    def __init__(self, url: str, clock: Clock, rate_hz: float, sensors: int):
        super().__init__(url=url, sensors=sensors, clock=clock, description=f"myimu x{sensors} (example plugin)")
        self.rate_hz = rate_hz
        self._start = clock()
        self._sent = 0  # samples delivered so far
        self.state = SourceState.CONNECTED  # a real device would start CONNECTING

    def poll(self) -> list[Sample]:
        """The samples due by now; never waits (an empty list when none are)."""
        if self.state is not SourceState.CONNECTED:
            return []
        due = int((self.clock() - self._start) * self.rate_hz + 1e-9) + 1
        out = []
        for k in range(self._sent, due):
            accel = np.zeros((self.sensors, 3))
            accel[:, 2] = 1.0  # at rest: gravity only, in g
            out.append(Sample(self._start + k / self.rate_hz, accel))
        self._sent = max(self._sent, due)
        self.count("samples", len(out))
        return out

    def close(self) -> None:
        self.state = SourceState.DISCONNECTED  # a real device closes its port here


def open_myimu(url: str, clock: Clock) -> MyImuSource:
    """The entry point: `factory(url, clock) -> Source`. Bad parameters raise SourceError."""
    _, _, params = parse_source_url(url)
    rate = url_number(url, params, "rate", 50.0, 1.0, 2000.0)
    sensors = int(url_number(url, params, "sensors", 1, 1, 2, integer=True))
    return MyImuSource(url, clock, rate, sensors)
