# A fake `machine` module: two MPU-6050 on I2C, for running the firmware (main.py, board.py,
# drivers, sampler) under the WebAssembly MicroPython. After 300 sample reads it raises Done,
# which ends main(); its stdout is the stream a board would send.
import struct


class Pin:
    OUT = 1

    def __init__(self, *a, **k):
        self.v = 0

    def value(self, v=None):
        if v is not None:
            self.v = v
        return self.v


class Done(Exception):
    pass


class I2C:
    reads_left = 300
    reads = 0  # sample reads so far, all buses
    empty_scans = 0  # scans that find nothing before the two sensors show up

    def __init__(self, *a, **k):
        self.n = {}  # reads per address

    def scan(self):
        if I2C.empty_scans > 0:
            I2C.empty_scans -= 1
            return []
        return [0x68, 0x69]

    def readfrom_mem(self, addr, reg, n):
        return bytes([0x68]) if reg == 0x75 else bytes(n)

    def writeto_mem(self, addr, reg, data):
        pass

    def readfrom_mem_into(self, addr, reg, buf):
        I2C.reads_left -= 1
        I2C.reads += 1
        if I2C.reads_left < 0:
            raise Done()
        n = self.n.get(addr, 0) + 1
        self.n[addr] = n
        buf[:] = struct.pack(">hhhhhhh", addr, n, 4096, 0, 1, 2, 3)
