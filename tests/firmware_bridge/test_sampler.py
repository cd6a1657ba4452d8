"""The firmware's sampling loop on the host, with fake ticks, IMUs and a writer."""

from __future__ import annotations

import pytest

from firmware_bridge import protocol
from firmware_bridge.emulator import HostTicks
from firmware_bridge.firmware.sampler import Sampler


class FakeTicks:
    """MicroPython's ticks API over a counter the test moves; 30 bits like rp2."""

    def __init__(self, start=0, bits=30):
        self.now = start
        self.mask = (1 << bits) - 1
        self.half = 1 << (bits - 1)

    def ticks_us(self):
        return self.now & self.mask

    def ticks_add(self, t, d):
        return (t + d) & self.mask

    def ticks_diff(self, a, b):
        return ((a - b + self.half) & self.mask) - self.half

    def sleep_us(self, us):
        self.now += us


class FakeIMU:
    kind = protocol.IMU_MPU6050
    accel_lsb_per_g = 4096
    gyro_mlsb_per_dps = 65500

    def __init__(self, value, fail_at=()):
        self.value, self.fail_at, self.calls = value, set(fail_at), 0

    def read(self):
        self.calls += 1
        if self.calls in self.fail_at:
            raise OSError("i2c")
        return self.value + (1, 2, 3)


class Wire:
    def __init__(self, short_at=()):
        self.data, self.short_at, self.calls = bytearray(), set(short_at), 0

    def write(self, b):
        self.calls += 1
        if self.calls in self.short_at:
            self.data += b[:3]
            return 3
        self.data += b
        return len(b)


def run(sampler, steps):
    n = [0]

    def stop(_s):
        n[0] += 1
        return n[0] > steps

    sampler.run(stop)


def test_stream_decodes_with_hello_every_second_across_the_wrap():
    ticks = FakeTicks(start=(1 << 30) - 1_500_000)
    wire = Wire()
    s = Sampler([FakeIMU((0, 0, 4096)), FakeIMU((4096, 0, 0))], wire.write, ticks, rate_hz=200, boot_id=9)
    run(s, 800)  # 4 s at 200 Hz
    dec = protocol.Decoder()
    frames = dec.feed(bytes(wire.data))
    kinds = [f.msg_type for f in frames]
    assert kinds.count(protocol.SAMPLE) == 800 and kinds.count(protocol.HELLO) == 4
    assert dec.lost == 0 and dec.crc_errors == 0
    hello = protocol.Hello(frames[0])
    assert (hello.boot_id, hello.ts_bits, hello.rate_hz, hello.sensors) == (9, 30, 200, 2)
    samples = [f for f in frames if f.msg_type == protocol.SAMPLE]
    assert samples[0].values() == (0, 0, 4096, 4096, 0, 0)
    dt = [(b.t_us - a.t_us) & ((1 << 30) - 1) for a, b in zip(samples, samples[1:], strict=False)]
    assert set(dt) == {5000}  # no drift, wrap included


def test_short_write_drops_one_frame_and_flags_overrun():
    wire = Wire(short_at={5})
    s = Sampler([FakeIMU((1, 1, 1)), None], wire.write, FakeTicks(), rate_hz=100)
    run(s, 10)
    dec = protocol.Decoder()
    frames = dec.feed(bytes(wire.data))
    assert s.dropped == 1 and dec.lost == 1
    overrun = [f.seq for f in frames if f.flags & protocol.FLAG_OVERRUN]
    assert overrun == [5]  # the frame after the cut one (seq 4) says so


def test_read_error_leaves_the_sensor_out_and_says_so():
    wire = Wire()
    s = Sampler([FakeIMU((1, 1, 1)), FakeIMU((2, 2, 2), fail_at={3})], wire.write, FakeTicks())
    run(s, 5)
    frames = protocol.Decoder().feed(bytes(wire.data))
    texts = [f.payload for f in frames if f.msg_type == protocol.TEXT]
    assert texts == [b"read error on sensor B"]
    flags = [f.flags for f in frames if f.msg_type == protocol.SAMPLE]
    assert flags.count(protocol.FLAG_SENSOR_A) == 1 and s.read_errors == 1


def test_hello_request_sends_a_hello_before_the_next_sample():
    wire = Wire()
    s = Sampler([FakeIMU((1, 1, 1)), None], wire.write, FakeTicks())
    run(s, 3)
    s.request_hello()
    s.step(s.ticks.ticks_us())
    kinds = [f.msg_type for f in protocol.Decoder().feed(bytes(wire.data))]
    assert kinds == [protocol.HELLO] + [protocol.SAMPLE] * 3 + [protocol.HELLO, protocol.SAMPLE]


def test_gyro_flag_carries_gyro():
    wire = Wire()
    s = Sampler([FakeIMU((1, 2, 3)), None], wire.write, FakeTicks(), gyro=True)
    run(s, 1)
    f = [f for f in protocol.Decoder().feed(bytes(wire.data)) if f.msg_type == protocol.SAMPLE][0]
    assert f.flags & protocol.FLAG_GYRO and f.values() == (1, 2, 3, 1, 2, 3)


def test_host_ticks_wrap_like_micropython():
    # start 10 s before the wrap: a loaded machine cannot let the clock pass it between lines
    t = HostTicks(bits=30, start_us=(1 << 30) - 10_000_000)
    a = t.ticks_us()
    b = t.ticks_add(a, 20_000_000)
    assert b < a and t.ticks_diff(b, a) == 20_000_000 and t.ticks_diff(a, b) == -20_000_000


def test_a_read_error_long_after_the_last_one_is_still_reported():
    # At most one TEXT a second, timed by ticks_diff against the last TEXT: ticks_us wraps at
    # 2**30 us, so a read error 600 s after the previous one looked 474 s *earlier* than it and
    # went unreported, as did every other until 1074 s had passed
    ticks = FakeTicks()
    wire = Wire()
    imu_b = FakeIMU((2, 2, 2), fail_at={1, 6001})  # reads every 0.1 s: 600 s apart
    s = Sampler([FakeIMU((1, 1, 1)), imu_b], wire.write, ticks)
    for k in range(6002):
        s.step(ticks.ticks_add(0, 100_000 * k))
    texts = [f for f in protocol.Decoder().feed(bytes(wire.data)) if f.msg_type == protocol.TEXT]
    assert [f.payload for f in texts] == [b"read error on sensor B"] * 2
    assert s.read_errors == 2


def test_run_without_a_stop_function_survives_a_slow_tick():
    # run() (stop=None: sample for ever) read the host again after a tick that took over a period
    # (a long GC pause) by calling stop, None: TypeError, and the board stopped streaming
    class SlowTicks(FakeTicks):
        def ticks_us(self):
            self.now += 6000  # every look at the clock costs more than the 5 ms period
            return super().ticks_us()

    class Enough(Exception):
        pass

    class LastReads(FakeIMU):
        def read(self):
            if self.calls == 5:
                raise Enough  # ends the test's run (an OSError would be a read error)
            return super().read()

    wire = Wire()
    s = Sampler([LastReads((1, 1, 1)), None], wire.write, SlowTicks())
    try:
        s.run()
    except Enough:
        pass
    kinds = [f.msg_type for f in protocol.Decoder().feed(bytes(wire.data))]
    assert kinds == [protocol.HELLO] + [protocol.SAMPLE] * 5


def test_two_kinds_of_imu_go_out_in_the_hellos_scales():
    # board.find_imus takes the first two of 0x68, 0x69, 0x6A, 0x6B: an MPU-6050 (4096 counts
    # per g, 65.5 per dps) as A and an LSM6DS3 (4098, 57.143) as B. A HELLO has one set of
    # scales, A's, and B's counts went out unconverted: its accel read 0.05 % high and its gyro
    # (with gyro on) 13 % low
    from tests.engine.sensors.test_serial_hostile import _write_and_poll

    class LSM(FakeIMU):
        kind = protocol.IMU_LSM6DS3
        accel_lsb_per_g = 4098
        gyro_mlsb_per_dps = 57143

        def read(self):
            return (4098, -2049, 0, 5714, -28571, 0)  # 1 g, -0.5 g, 0; 100 dps, -500 dps, 0

    wire = Wire()
    s = Sampler([FakeIMU((0, 0, 4096)), LSM(())], wire.write, FakeTicks(), rate_hz=200, gyro=True)
    run(s, 5)
    src, got = _write_and_poll(bytes(wire.data), lambda src: src.stats.get("frames_ok", 0) == 6)  # HELLO, 5 SAMPLEs
    assert len(got) == 5 and src.hello.accel_lsb_per_g == 4096
    for sample in got:
        assert abs(sample.accel[1] - [1, -0.5, 0]).max() < 2e-4  # B in g with the HELLO's scale
    frames = protocol.Decoder().feed(bytes(wire.data))
    b_gyro = [f.values()[9:12] for f in frames if f.msg_type == protocol.SAMPLE]
    assert b_gyro == [(6550, -32749, 0)] * 5  # x 65500 / 57143: 100 and -499.99 dps at 65.5 per dps


@pytest.mark.parametrize("bits", [16, 20, 30])
def test_a_narrow_tick_counter_still_sends_a_hello_every_second_and_a_text_at_most_every_second(bits):
    # The HELLO was due when ticks_diff(now, last HELLO) reached 1 s: with a counter of 20 bits
    # or fewer half its period is under 1 s, ticks_diff never gets there, and after the first
    # HELLO none came again (PROTOCOL.md: every second). The TEXT spacing had the same flaw.
    ticks = FakeTicks(bits=bits)
    wire = Wire()
    s = Sampler([FakeIMU((1, 1, 1)), FakeIMU((2, 2, 2), fail_at=set(range(0, 640, 7)))], wire.write, ticks,
                ts_bits=bits)
    for k in range(640):  # 3.2 s at 200 Hz
        s.step(ticks.ticks_add(0, 5000 * k))
    frames = protocol.Decoder().feed(bytes(wire.data))
    hellos = [f for f in frames if f.msg_type == protocol.HELLO]
    texts = [f for f in frames if f.msg_type == protocol.TEXT]
    assert len(hellos) == 4  # at 0, 1, 2 and 3 s
    assert len(texts) == 4  # a read error every 35 ms, reported once a second
