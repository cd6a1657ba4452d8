# ruff: noqa: UP031  (%-formatting: the same code must run on MicroPython)
# QuickJab serial IMU bridge firmware (MicroPython; Raspberry Pi Pico first, ESP32 second).
# Streams one IMU per hand at 200 Hz as protocol v1 frames on USB serial. See README.md.

import sys
import time

import board
import micropython
import protocol
from sampler import Sampler

RATE_HZ = 200
TS_BITS = 30  # time.ticks_us() wraps at 2**30 on rp2 and esp32


def wait_for_imus(led, out, bus, bid):
    """Retry detection every second, saying so on the wire (TEXT) and with the LED."""
    seq = 0
    while True:
        imus, found = board.find_imus(bus)
        if imus[0] is not None or imus[1] is not None:
            return imus
        now = time.ticks_us()
        msg = "no IMU found; I2C scan: %s" % ",".join(["0x%02x" % a for a in found])
        out.write(protocol.encode_hello(seq, now & ((1 << TS_BITS) - 1), bid, RATE_HZ, 4096, 0,
                                        TS_BITS, protocol.IMU_UNKNOWN, 0))
        out.write(protocol.encode_text(seq + 1, now & ((1 << TS_BITS) - 1), msg))
        seq += 2
        for _ in range(10):
            led.show(time.ticks_us(), "no_imu")
            time.sleep_ms(100)


def main():
    led = board.Led()
    if board.safe_mode(led):
        return  # BOOTSEL held: stay at the REPL
    out = board.StdoutWriter()
    bid = board.boot_id()
    imus = wait_for_imus(led, out, board.i2c(), bid)
    sampler = Sampler(imus, out.write, time, rate_hz=RATE_HZ, boot_id=bid, ts_bits=TS_BITS)
    micropython.kbd_intr(-1)  # a stray 0x03 from the host must not stop streaming
    try:
        sampler.run(board.Watch(led))
    finally:
        micropython.kbd_intr(3)
        sys.stdout.write("\r\nstopped: %d frames, %d dropped, %d read errors\r\n" % (
            sampler.frames, sampler.dropped, sampler.read_errors))


main()
