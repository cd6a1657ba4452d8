"""Property tests: random bytes and report IDs into `decode_report` and into the driver's
state machine. Nothing raises; the counters count what came in."""

from __future__ import annotations

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from engine.clock import VirtualClock
from engine.recording import Recording
from engine.sensors import SourceState
from engine.sensors.wiimote import WiimoteSource, decode_report
from engine.sensors.wiimote import protocol as p
from engine.sensors.wiimote.emulator import EmulatedBus, EmulatedHidDevice, EmulatedWiimote

KNOWN_IDS = sorted(p.INPUT_REPORT_LENGTHS)
report_ids = st.one_of(st.sampled_from(KNOWN_IDS), st.integers(0, 255))
reports = st.builds(lambda rid, body: bytes([rid]) + body, report_ids, st.binary(max_size=30))


@given(st.one_of(st.binary(max_size=40), reports, st.lists(st.integers(-5, 300), max_size=30)))
def test_decode_report_never_raises(data):
    r = decode_report(data)
    assert isinstance(r.valid, bool)
    if r.valid:
        assert r.report_id in p.INPUT_REPORT_LENGTHS
        if r.accel is not None:
            assert all(0 <= v <= 1023 for v in r.accel)
        if r.size is not None:
            assert 1 <= r.size <= 16 and len(r.payload) == r.size
        if r.leds is not None:
            assert 0 <= r.leds <= 15


class InjectingDevice(EmulatedHidDevice):
    """The emulated device, with extra raw reports slipped in ahead of the real ones."""

    def read(self, max_length, timeout_ms=0):
        if self.bus.inject:
            data = list(self.bus.inject.pop(0))
            self.bus.delivered_invalid += not decode_report(data).valid
        else:
            data = super().read(max_length, timeout_ms)
        self.bus.delivered += bool(data)
        return data


class InjectingBus(EmulatedBus):
    def __init__(self, remotes):
        super().__init__(remotes)
        self.inject: list[bytes] = []
        self.delivered = 0  # reports handed to the driver
        self.delivered_invalid = 0

    def device(self):
        return InjectingDevice(self)


def _recording() -> Recording:
    t = np.arange(0, 2, 1 / 60)
    a = np.zeros((len(t), 2, 3))
    a[:, :, 2] = 1.0
    a[:, 0, 0] = np.sin(6 * t)
    return Recording(t, a)


REC = _recording()


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(st.tuples(st.integers(0, 40), st.lists(reports, max_size=6)), max_size=8))
def test_driver_survives_random_reports(bursts):
    vc = VirtualClock()
    bus = InjectingBus([EmulatedWiimote(REC, vc.seconds, jitter_ms=0)])
    src = WiimoteSource(clock=vc.seconds, backend=bus)
    schedule = dict(bursts)
    injected = 0
    real_reads = 0
    for step in range(45):
        vc.advance(16_666_667)
        for data in schedule.get(step, []):
            bus.inject.append(data)
            injected += 1
        before = sum(1 for s in bus.remotes[0].sent if s.read_at is not None)
        samples = src.poll()
        real_reads += sum(1 for s in bus.remotes[0].sent if s.read_at is not None) - before
        for s in samples:
            assert s.accel.shape == (2, 3)
    assert injected >= bus.delivered_invalid
    assert src.stats.get("malformed", 0) == bus.delivered_invalid
    assert src.stats.get("reports", 0) == bus.delivered >= real_reads
    assert src.stats.get("data_reports", 0) >= real_reads
    assert src.state in (SourceState.CONNECTED, SourceState.CONNECTING, SourceState.DISCONNECTED, SourceState.RECONNECTING)
    src.close()
