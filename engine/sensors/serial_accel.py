"""SAMPLE payloads of protocol v1 to accelerations in g, one (sensors, 3) row per frame,
holding each sensor's last value of the boot for a frame that lacks it, and the check that a frame's
accelerations are ones a sensor can read at all."""

from __future__ import annotations

import struct
from collections.abc import Callable

import numpy as np

from engine.recording import MAX_ACCEL_G
from firmware_bridge import protocol

INT16_MAX_ABS = 32768  # the largest |count| an int16 holds (-32768)


def sample_width(flags: int) -> int:
    """Rows of the samples for a HELLO announcing these sensors: one per sensor, except that
    sensor B (the left hand, PROTOCOL.md) alone still takes the second row, the first (the right
    hand) holding still."""
    if flags & protocol.FLAGS_SENSORS == protocol.FLAG_SENSOR_B:
        return 2
    return protocol.sensor_count(flags)


class SampleAccel:
    """Converts SAMPLE frames with the scales and layout of the device's HELLO; counts each
    frame missing an announced sensor through `count("sensor_missing")`, and each carrying one
    the HELLO did not announce (its values dropped) through `count("sensor_unannounced")`."""

    def __init__(self, count: Callable[[str], None]) -> None:
        self.count = count
        self.last_row: np.ndarray | None = None  # the last SAMPLE's accel, (sensors, 3)
        self.announced: int | None = None  # the sensor flags the last HELLO naming any announced

    def take_hello(self, hello: protocol.Hello, same_boot: bool) -> bool:
        """Take a valid HELLO; True when it names other sensors than the HELLOs before it (none
        before the first that names any: a boot's HELLOs before its IMUs are found name none).
        A new boot holds nothing of the last one's readings: a sensor it lacks reads 0 g, as
        before any reading (a B-alone board's right hand after a reboot from A and B)."""
        if not same_boot:
            self.last_row = None
        if not hello.flags & protocol.FLAGS_SENSORS:
            return False
        was, self.announced = self.announced, hello.flags & protocol.FLAGS_SENSORS
        return was is not None and was != self.announced

    def rows(self, frames: list[protocol.Frame], hello: protocol.Hello,
             sensors: int) -> list[np.ndarray] | np.ndarray:
        """(sensors, 3) in g per frame: one numpy conversion for the whole poll when every frame
        has the layout the HELLO announced (the usual case), frame by frame otherwise."""
        flags = frames[0].flags & ~protocol.FLAG_OVERRUN
        want = hello.flags & protocol.FLAGS_SENSORS
        if (flags & protocol.FLAGS_SENSORS) == want and hello.sensors == sensors \
                and all((f.flags & ~protocol.FLAG_OVERRUN) == flags for f in frames):
            per = protocol.sample_values_per_sensor(flags)
            raw = np.frombuffer(b"".join([f.payload for f in frames]), dtype="<i2")
            acc = raw.reshape(len(frames), sensors, per)[:, :, :3] * (1.0 / hello.accel_lsb_per_g)
            self.last_row = acc[-1]  # for a later SAMPLE that lacks a sensor
            return acc
        return [self._accel(f, hello, sensors) for f in frames]

    @staticmethod
    def plausible(f: protocol.Frame, hello: protocol.Hello) -> bool:
        """False when an acceleration of the SAMPLE (any axis, any sensor; gyro aside) would be
        over MAX_ACCEL_G once scaled. PROTOCOL.md allows any accel_lsb_per_g from 1, and at 1 an
        int16 reads up to 32,767 g: no worn sensor does, and a recording reader refuses it.
        Compared in counts, before any conversion, so a dropped frame sets no held value."""
        limit = MAX_ACCEL_G * hello.accel_lsb_per_g
        if limit >= INT16_MAX_ABS:  # 33 counts per g or more (4096 usually): every count is fine
            return True
        per = protocol.sample_values_per_sensor(f.flags)
        counts = struct.unpack(f"<{len(f.payload) // 2}h", f.payload)
        return all(abs(c) <= limit for i, c in enumerate(counts) if i % per < 3)

    def _last(self, sensors: int) -> np.ndarray:
        """Every sensor's last accel, (sensors, 3); zeros before any."""
        last = self.last_row
        if last is None or last.shape[0] != sensors:
            return np.zeros((sensors, 3))
        return last

    def _accel(self, f: protocol.Frame, hello: protocol.Hello, sensors: int) -> np.ndarray:
        """(sensors, 3) in g; a sensor the HELLO announced but this SAMPLE lacks holds its last value."""
        per = protocol.sample_values_per_sensor(f.flags)
        raw = np.frombuffer(f.payload, dtype="<i2").reshape(-1, per)[:, :3] / hello.accel_lsb_per_g
        want = hello.flags & protocol.FLAGS_SENSORS
        have = f.flags & protocol.FLAGS_SENSORS
        if have == want and raw.shape[0] == sensors:
            out = raw  # (a HELLO that announced no sensor: the source drops its SAMPLEs)
        else:
            if want & ~have:
                self.count("sensor_missing")
            if have & ~want:  # not on the board, says its HELLO: nowhere to put it
                self.count("sensor_unannounced")
            out = self._last(sensors).copy()
            # raw holds the present sensors in order A then B; A is row 0, B the last row
            k = 0
            for s, row in ((protocol.FLAG_SENSOR_A, 0), (protocol.FLAG_SENSOR_B, sensors - 1)):
                if have & s:
                    if want & s:
                        out[row] = raw[k]
                    k += 1
        self.last_row = out
        return out
