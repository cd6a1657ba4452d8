# ruff: noqa: UP031  (%-formatting: the same code must run on MicroPython)
# QuickJab serial IMU bridge firmware (MicroPython; Raspberry Pi Pico first, ESP32 second).
# Streams one IMU per hand at 200 Hz as protocol v1 frames on USB serial. See README.md.

import sys
import time

import board
import micropython
from sampler import Sampler

RATE_HZ = 200
TS_BITS = 30  # time.ticks_us() wraps at 2**30 on rp2 and esp32


def wait_for_imus(led, sampler, bus):
    """Retry detection every second, saying so on the wire (HELLO and TEXT) and with the LED.
    The sampler sends those frames, so they share its sequence counter with everything the boot
    sends later (PROTOCOL.md: seq counts every frame of every type)."""
    ticks = sampler.ticks
    while True:
        imus, found = board.find_imus(bus)
        if imus[0] is not None or imus[1] is not None:
            return imus
        now = ticks.ticks_us()
        sampler.send_hello(now)  # no sensor flags yet; the drivers' scales
        sampler.send_text(now, "no IMU found; I2C scan: %s" % ",".join(["0x%02x" % a for a in found]))
        for _ in range(10):
            led.show(ticks.ticks_us(), "no_imu")
            time.sleep_ms(100)


def main():
    led = board.Led()
    if board.safe_mode(led):
        return  # BOOTSEL held: stay at the REPL
    out = board.StdoutWriter()
    sampler = Sampler([None, None], out.write, time, rate_hz=RATE_HZ, boot_id=board.boot_id(), ts_bits=TS_BITS)
    sampler.set_imus(wait_for_imus(led, sampler, board.i2c()))  # and a HELLO before the first SAMPLE
    micropython.kbd_intr(-1)  # a stray 0x03 from the host must not stop streaming
    try:
        sampler.run(board.Watch(led))
    finally:
        micropython.kbd_intr(3)
        sys.stdout.write("\r\nstopped: %d frames, %d dropped, %d read errors\r\n" % (
            sampler.frames, sampler.dropped, sampler.read_errors))


main()
