# ruff: noqa: UP031  (%-formatting: the same code must run on MicroPython)
# The firmware's sampling loop, shared by the board (main.py) and the host emulator
# (firmware_bridge/emulator.py), which runs this same code against a simulated IMU on a pty.
# MicroPython and CPython alike: no f-strings, no typing, time comes from an injected `ticks`
# object (MicroPython's time module on the board, a host clock in the emulator).

try:
    from firmware_bridge import protocol  # CPython: the package
except ImportError:
    import protocol  # the board: protocol.py copied next to this file

HELLO_EVERY_US = 1000000
TEXT_EVERY_US = 1000000  # at most one error line per second, so a broken sensor cannot flood


# The scales a HELLO announces before any IMU is found (the drivers' settings: +-8 g, +-500 dps),
# so that every HELLO carries real scales (PROTOCOL.md), even the "no IMU yet" ones.
DEFAULT_ACCEL_LSB_PER_G = 4096
DEFAULT_GYRO_MLSB_PER_DPS = 65500


def _rescale(values, scale):
    """(ax, ay, az, gx, gy, gz) counts times num / den, rounded half away from zero in integers
    (no floating point on the board's hot path); encode_sample clamps them to int16."""
    out = []
    for i in range(len(values)):
        num, den = (scale[0], scale[1]) if i < 3 else (scale[2], scale[3])
        v = values[i] * num
        out.append((v + den // 2) // den if v >= 0 else -((den // 2 - v) // den))
    return tuple(out)


class Sampler:
    """Reads one IMU per hand at `rate_hz` and writes one SAMPLE frame per reading, a HELLO at
    start and every second, and TEXT lines for read errors. Every frame of a boot, whatever its
    type and whoever sends it (main.py's wait for IMUs too), goes through `_send`, so one
    sequence counter counts them all.

    imus: [imu_a, imu_b]; either may be None (absent). A driver has read() -> (ax, ay, az, gx,
    gy, gz) raw ints, and accel_lsb_per_g, gyro_mlsb_per_dps, kind.
    write: write(bytes) -> number written (or None); it must never block. A short write drops
    the rest of that frame (the next frame's leading 0x00 resynchronises the host) and sets the
    overrun flag on the next SAMPLE.
    """

    def __init__(self, imus, write, ticks, rate_hz=200, boot_id=0, ts_bits=30, gyro=False):
        self.write = write
        self.ticks = ticks
        self.rate_hz = rate_hz
        self.period_us = 1000000 // rate_hz
        self.boot_id = boot_id
        # t_us is a u32 on the wire: a wider tick counter (the emulator allows 62 bits) goes out
        # as its low 32 bits, and the HELLO says so (ts_bits 8..32, PROTOCOL.md)
        self.ts_bits = ts_bits if ts_bits < 32 else 32
        self.ts_mask = (1 << self.ts_bits) - 1
        self.gyro = gyro
        self.seq = 0
        self.overrun = False
        self.frames = 0  # frames fully written
        self.dropped = 0  # frames cut short or not written at all
        self.read_errors = 0
        self.late = 0  # deadlines missed by more than one period
        # how long ago the last HELLO and TEXT went (us; None: a HELLO is due / no TEXT to space
        # from), added up from tick to tick (`_age`)
        self._hello_age = None
        self._text_age = None
        self._looked = None  # the ticks when the ages were last brought up to date
        self.set_imus(imus)

    def set_imus(self, imus):
        """Use these IMUs from now on (main.py: once detection finds them) and announce them
        with a HELLO before the next SAMPLE."""
        self.imus = imus
        ref = imus[0] if imus[0] is not None else imus[1]
        self.accel_lsb_per_g = ref.accel_lsb_per_g if ref is not None else DEFAULT_ACCEL_LSB_PER_G
        self.gyro_mlsb_per_dps = ref.gyro_mlsb_per_dps if ref is not None else DEFAULT_GYRO_MLSB_PER_DPS
        self.imu_kind = ref.kind if ref is not None else protocol.IMU_UNKNOWN
        # a HELLO carries one set of scales, A's: B of another kind (an MPU-6050 beside an
        # LSM6DS3) has its counts converted to them, (accel num, den, gyro num, den)
        b = imus[1]
        self._b_scale = None
        if ref is not None and b is not None and (b.accel_lsb_per_g != self.accel_lsb_per_g
                                                  or b.gyro_mlsb_per_dps != self.gyro_mlsb_per_dps):
            self._b_scale = (self.accel_lsb_per_g, b.accel_lsb_per_g, self.gyro_mlsb_per_dps, b.gyro_mlsb_per_dps)
        self._hello_age = None

    def _send(self, frame):
        self.seq = (self.seq + 1) & protocol.SEQ_MASK
        try:
            n = self.write(frame)
        except OSError:
            n = 0
        if n is None or n >= len(frame):
            self.frames += 1
            return True
        self.dropped += 1
        self.overrun = True
        return False

    def present_flags(self):
        f = 0
        if self.imus[0] is not None:
            f |= protocol.FLAG_SENSOR_A
        if self.imus[1] is not None:
            f |= protocol.FLAG_SENSOR_B
        if self.gyro:
            f |= protocol.FLAG_GYRO
        return f

    def _age(self, now):
        """Bring the HELLO's and the TEXT's ages up to `now`. The difference of two tick counts
        is right only under half the counter's period (0.5 s at 20 bits, 537 s at 30), so the
        ages add up the small steps between looks instead of comparing with a time long past."""
        if self._looked is not None:
            dt = self.ticks.ticks_diff(now, self._looked)
            if dt > 0:
                if self._hello_age is not None:
                    self._hello_age += dt
                if self._text_age is not None:
                    self._text_age += dt
                    if self._text_age >= TEXT_EVERY_US:
                        self._text_age = None  # the next TEXT may go (and the age stays a small int)
        self._looked = now

    def send_hello(self, now):
        self._age(now)
        self._hello_age = 0
        return self._send(protocol.encode_hello(
            self.seq, now & self.ts_mask, self.boot_id, self.rate_hz, self.accel_lsb_per_g,
            self.gyro_mlsb_per_dps, self.ts_bits, self.imu_kind, self.present_flags()))

    def request_hello(self):
        """The host asked (protocol.HELLO_REQUEST): send a HELLO before the next SAMPLE."""
        self._hello_age = None

    def send_text(self, now, text):
        self._age(now)
        if self._text_age is not None:  # at most one a second
            return False
        self._text_age = 0
        return self._send(protocol.encode_text(self.seq, now & self.ts_mask, text))

    def step(self, now):
        """One reading of every IMU and its frame; a HELLO first when one is due."""
        self._age(now)
        if self._hello_age is None or self._hello_age >= HELLO_EVERY_US:
            self.send_hello(now)
        readings = [None, None]
        for i in (0, 1):
            imu = self.imus[i]
            if imu is None:
                continue
            try:
                readings[i] = imu.read()
            except OSError:  # an I2C error: this sensor is left out of this sample
                self.read_errors += 1
                self.send_text(now, "read error on sensor %s" % "AB"[i])
        a, b = readings
        if a is None and b is None:
            return False
        if b is not None and self._b_scale is not None:
            b = _rescale(b, self._b_scale)
        g = self.gyro
        frame = protocol.encode_sample(
            self.seq, now & self.ts_mask,
            None if a is None else a[:3], None if b is None else b[:3],
            a[3:6] if g and a is not None else None, b[3:6] if g and b is not None else None,
            self.overrun)
        self.overrun = False
        return self._send(frame)

    def run(self, stop=None):
        """Sample at rate_hz on deadlines computed from ticks_add (no drift) until stop(self)
        returns true. A deadline missed by more than a period is skipped, not caught up.

        stop(self) is called once per tick (again after a stall), after the tick's time is taken
        and before its frame is built; that is where the board and the emulator read host bytes,
        so a HELLO request that arrived before the SAMPLE's time stamp is answered before that
        SAMPLE (PROTOCOL.md, "Host to device"). A SAMPLE stamped earlier than the request may
        still go first: it was made before the request arrived."""
        t = self.ticks
        deadline = t.ticks_us()
        while True:
            now = t.ticks_us()
            wait = t.ticks_diff(deadline, now)
            if wait > 0:
                t.sleep_us(wait)
                now = t.ticks_us()
            if stop is not None and stop(self):
                break
            later = t.ticks_us()
            if t.ticks_diff(later, now) > self.period_us:
                # stop() hung (a stall): stamp the reading when it is really made, and read the
                # host again, so no request that came before the stamp waits behind this SAMPLE
                now = later
                if stop is not None and stop(self):
                    break
            self.step(now)
            deadline = t.ticks_add(deadline, self.period_us)
            if t.ticks_diff(t.ticks_us(), deadline) > self.period_us:
                self.late += 1
                deadline = t.ticks_us()
