# ruff: noqa: UP031  (%-formatting: the same code must run on MicroPython)
# Board glue for the firmware: I2C pins, the LED and its codes, the non-blocking stdout writer,
# the stdin stop word, IMU detection. MicroPython only (the emulator replaces all of this).

import os
import select
import sys
import time

import machine
import protocol
from lsm6ds3 import LSM6DS3
from mpu6050 import MPU6050

STOP_WORD = b"!stop!"  # typed to the port, ends streaming (Ctrl-C is disabled while streaming)
# and a single protocol.HELLO_REQUEST byte ('?') asks for a HELLO at once

# (I2C id, SDA, SCL, LED pin) per port; LED None where the board has none we know of
PINS = {
    "rp2": (0, 4, 5, "LED"),  # Raspberry Pi Pico / Pico W: GP4 = SDA, GP5 = SCL, pins 6 and 7
    "esp32": (0, 21, 22, 2),  # ESP32 DevKit: GPIO21 = SDA, GPIO22 = SCL, blue LED on GPIO2
}


def i2c():
    bus, sda, scl, _ = PINS.get(sys.platform, (0, 4, 5, None))
    return machine.I2C(bus, sda=machine.Pin(sda), scl=machine.Pin(scl), freq=400000)


def find_imus(bus):
    """[sensor A, sensor B]: two MPU-6050 at 0x68/0x69, or LSM6DS3 at 0x6A/0x6B; the first two
    found in address order, the lower A (right hand). A lone IMU is A whatever its address (a
    one-IMU board is a right hand), so a two-IMU board whose A fails at boot streams B as A: its
    HELLO then announces one sensor. Missing ones are None."""
    found = bus.scan()
    imus = []
    for addr in (0x68, 0x69, 0x6A, 0x6B):
        if addr in found and len(imus) < 2:
            try:
                imus.append(MPU6050(bus, addr) if addr < 0x6A else LSM6DS3(bus, addr))
            except OSError:
                pass
    while len(imus) < 2:
        imus.append(None)
    return imus, found


def boot_id():
    try:
        b = os.urandom(4)
        return b[0] | (b[1] << 8) | (b[2] << 16) | (b[3] << 24)
    except (AttributeError, NotImplementedError):
        return time.ticks_us() ^ (time.ticks_cpu() << 7)


def safe_mode(led, window_ms=1000):
    """BOOTSEL pressed during the first second after boot (Pico; the LED is on meanwhile)
    leaves the board at the REPL for mpremote instead of streaming."""
    try:
        import rp2

        pressed = rp2.bootsel_button
    except (ImportError, AttributeError):
        return False
    led.set(True)
    start = time.ticks_ms()
    try:
        while time.ticks_diff(time.ticks_ms(), start) < window_ms:
            if pressed():
                return True
            time.sleep_ms(20)
        return False
    finally:
        led.set(False)


class Led:
    """LED codes (README): heartbeat 1 Hz = streaming both sensors; double flash each second =
    streaming one sensor; fast 5 Hz blink = no IMU found; steady on = host not reading
    (output dropped in the last second)."""

    def __init__(self):
        pin = PINS.get(sys.platform, (0, 0, 0, None))[3]
        self.pin = machine.Pin(pin, machine.Pin.OUT) if pin is not None else None

    def set(self, on):
        if self.pin is not None:
            self.pin.value(1 if on else 0)

    def show(self, now_us, code):
        if self.pin is None:
            return
        ms = (now_us // 1000) % 1000
        if code == "overrun":
            on = True
        elif code == "no_imu":
            on = ms % 200 < 100
        elif code == "one":
            on = ms < 80 or 160 <= ms < 240
        else:
            on = ms < 500
        self.pin.value(1 if on else 0)


class StdoutWriter:
    """sys.stdout.buffer.write (never print: it turns LF into CRLF), guarded by a zero-timeout
    poll so an unread USB port drops frames instead of blocking the sampling loop."""

    def __init__(self):
        self.out = sys.stdout.buffer
        self.poll = select.poll()
        self.poll.register(sys.stdout, select.POLLOUT)

    def write(self, data):
        if not self.poll.poll(0):
            return 0
        n = self.out.write(data)
        return len(data) if n is None else n


class Watch:
    """Called by Sampler.run once per tick, before the tick's frame is built: host bytes every
    tick (a '?' is answered with a HELLO before the next SAMPLE; the stop word ends streaming),
    the LED code every 50 ms."""

    def __init__(self, led, stdin=None, poller=None):
        self.led = led
        self.stdin = stdin if stdin is not None else sys.stdin
        self.poll = poller if poller is not None else select.poll()
        self.poll.register(self.stdin, select.POLLIN)
        self.tail = b""
        self.next_led = time.ticks_us()
        self.dropped_seen = 0
        self.overrun_until = None  # ticks_us until which the LED says "overrun"; None: it does not

    def __call__(self, sampler):
        now = time.ticks_us()
        if time.ticks_diff(now, self.next_led) >= 0:
            self.next_led = time.ticks_add(now, 50000)
            self.show_led(sampler, now)
        return self.read_host(sampler)

    def show_led(self, sampler, now):
        if sampler.dropped != self.dropped_seen:
            self.dropped_seen = sampler.dropped
            self.overrun_until = time.ticks_add(now, 1000000)
        # forgotten once past: ticks_diff with a time over half the counter's period ago (537 s on
        # rp2 and esp32) wraps and would say it is still ahead
        if self.overrun_until is not None and time.ticks_diff(self.overrun_until, now) <= 0:
            self.overrun_until = None
        if self.overrun_until is not None:
            code = "overrun"
        elif sampler.imus[0] is None or sampler.imus[1] is None:
            code = "one"
        else:
            code = "both"
        self.led.show(now, code)

    def read_host(self, sampler):
        """What the host sent since the last tick; True on the stop word."""
        for _ in range(16):  # bounded: the 200 Hz loop comes first
            if not self.poll.poll(0):
                break
            b = self.stdin.buffer.read(1)
            if not b:  # readable but empty: the port's closed end, nothing to act on
                break
            if b == protocol.HELLO_REQUEST:
                sampler.request_hello()
            self.tail = (self.tail + b)[-len(STOP_WORD):]
            if self.tail == STOP_WORD:
                return True
        return False
