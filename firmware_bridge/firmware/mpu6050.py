# ruff: noqa: UP031  (%-formatting: the same code must run on MicroPython)
# InvenSense MPU-6050 over I2C at 0x68 (AD0 low) or 0x69 (AD0 high): two on one bus, one
# per hand. Set to +-8 g (4096 LSB/g), +-500 dps (65.5 LSB/dps), the digital low-pass filter
# at DLPF_CFG=2 (accel 94 Hz, gyro 98 Hz: under the 100 Hz Nyquist limit of 200 Hz sampling)
# and an internal sample rate of 1 kHz / (1 + 4) = 200 Hz.

import struct

PWR_MGMT_1 = 0x6B
SMPLRT_DIV = 0x19
CONFIG = 0x1A
GYRO_CONFIG = 0x1B
ACCEL_CONFIG = 0x1C
ACCEL_XOUT_H = 0x3B
WHO_AM_I = 0x75
# genuine parts answer 0x68; common clones (MPU-6500 family, counterfeits) answer these
WHO_AM_I_OK = (0x68, 0x70, 0x71, 0x72, 0x73, 0x98)


class MPU6050:
    kind = 1  # protocol.IMU_MPU6050
    accel_lsb_per_g = 4096
    gyro_mlsb_per_dps = 65500

    def __init__(self, i2c, addr=0x68):
        self.i2c = i2c
        self.addr = addr
        self.buf = bytearray(14)  # read into this: no allocation per sample
        who = i2c.readfrom_mem(addr, WHO_AM_I, 1)[0]
        if who not in WHO_AM_I_OK:
            raise OSError("MPU-6050 at 0x%02x answered WHO_AM_I 0x%02x" % (addr, who))
        w = i2c.writeto_mem
        w(addr, PWR_MGMT_1, b"\x80")  # reset
        _sleep_ms(100)
        w(addr, PWR_MGMT_1, b"\x01")  # wake, clock from the X gyro PLL (more stable than 8 MHz RC)
        w(addr, SMPLRT_DIV, b"\x04")
        w(addr, CONFIG, b"\x02")
        w(addr, GYRO_CONFIG, b"\x08")
        w(addr, ACCEL_CONFIG, b"\x10")

    def read(self):
        """(ax, ay, az, gx, gy, gz) raw int16: one 14-byte burst read (accel, temp, gyro)."""
        self.i2c.readfrom_mem_into(self.addr, ACCEL_XOUT_H, self.buf)
        ax, ay, az, _temp, gx, gy, gz = struct.unpack(">hhhhhhh", self.buf)
        return (ax, ay, az, gx, gy, gz)


def _sleep_ms(ms):
    import time

    if hasattr(time, "sleep_ms"):
        time.sleep_ms(ms)
    else:
        time.sleep(ms / 1000)
