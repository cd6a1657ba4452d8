# ruff: noqa: UP031  (%-formatting: the same code must run on MicroPython)
# ST LSM6DS3 (and LSM6DS3TR-C / LSM6DSL / LSM6DSO, same registers for what is used here) over
# I2C at 0x6A (SA0 low) or 0x6B (SA0 high). Set to 208 Hz output, +-8 g (0.244 mg/LSB), the
# accel anti-aliasing filter at 100 Hz (fits 200 Hz sampling), +-500 dps (17.5 mdps/LSB).

import struct

WHO_AM_I = 0x0F
CTRL1_XL = 0x10
CTRL2_G = 0x11
CTRL3_C = 0x12
CTRL4_C = 0x13
OUTX_L_G = 0x22  # gyro x,y,z then accel x,y,z, little endian, 12 bytes
WHO_AM_I_OK = (0x69, 0x6A, 0x6C)


class LSM6DS3:
    kind = 2  # protocol.IMU_LSM6DS3
    accel_lsb_per_g = 4098  # 1 / 0.244 mg
    gyro_mlsb_per_dps = 57143  # 1 / 17.5 mdps

    def __init__(self, i2c, addr=0x6A):
        self.i2c = i2c
        self.addr = addr
        self.buf = bytearray(12)
        who = i2c.readfrom_mem(addr, WHO_AM_I, 1)[0]
        if who not in WHO_AM_I_OK:
            raise OSError("LSM6DS3 at 0x%02x answered WHO_AM_I 0x%02x" % (addr, who))
        w = i2c.writeto_mem
        w(addr, CTRL3_C, b"\x44")  # block data update, register auto-increment
        w(addr, CTRL4_C, b"\x80")  # XL_BW_SCAL_ODR: use the BW_XL bits below
        w(addr, CTRL1_XL, b"\x5e")  # 208 Hz, +-8 g, anti-aliasing 100 Hz
        w(addr, CTRL2_G, b"\x54")  # 208 Hz, +-500 dps

    def read(self):
        self.i2c.readfrom_mem_into(self.addr, OUTX_L_G, self.buf)
        gx, gy, gz, ax, ay, az = struct.unpack("<hhhhhh", self.buf)
        return (ax, ay, az, gx, gy, gz)
