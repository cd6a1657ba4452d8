"""The IMU drivers and board detection against fake I2C register maps (CPython; the same files
compile with mpy-cross in test_micropython.py)."""

from __future__ import annotations

import struct
import sys
import types
from pathlib import Path

import pytest

FIRMWARE = Path(__file__).resolve().parents[2] / "firmware_bridge" / "firmware"


class FakeBus:
    """Register files per address; records writes."""

    def __init__(self, devices: dict[int, dict[int, int]]):
        self.regs = devices
        self.writes: list[tuple[int, int, bytes]] = []

    def scan(self):
        return sorted(self.regs)

    def readfrom_mem(self, addr, reg, n):
        if addr not in self.regs:
            raise OSError(19)
        return bytes(self.regs[addr].get(reg + i, 0) for i in range(n))

    def readfrom_mem_into(self, addr, reg, buf):
        buf[:] = self.readfrom_mem(addr, reg, len(buf))

    def writeto_mem(self, addr, reg, data):
        self.writes.append((addr, reg, bytes(data)))
        for i, b in enumerate(data):
            self.regs[addr][reg + i] = b


@pytest.fixture
def firmware_path(monkeypatch):
    monkeypatch.syspath_prepend(str(FIRMWARE.parent))  # protocol.py, as copied next to the others
    monkeypatch.syspath_prepend(str(FIRMWARE))
    machine = types.ModuleType("machine")
    machine.Pin = type("Pin", (), {"OUT": 1, "__init__": lambda self, *a, **k: None, "value": lambda self, v=None: None})
    monkeypatch.setitem(sys.modules, "machine", machine)
    yield
    for name in ("mpu6050", "lsm6ds3", "board", "protocol"):
        sys.modules.pop(name, None)


def mpu_regs(who=0x68, accel=(100, -200, 4096), gyro=(1, 2, 3)):
    regs = {0x75: who}
    data = struct.pack(">hhhhhhh", *accel, 0, *gyro)
    for i, b in enumerate(data):
        regs[0x3B + i] = b
    return regs


def test_mpu6050_configures_8g_200hz_dlpf_and_reads(firmware_path):
    from mpu6050 import MPU6050

    bus = FakeBus({0x69: mpu_regs()})
    imu = MPU6050(bus, 0x69)
    cfg = {reg: data for _, reg, data in bus.writes}
    assert cfg[0x1C] == b"\x10"  # ACCEL_CONFIG: +-8 g
    assert cfg[0x1A] == b"\x02"  # DLPF 94 Hz
    assert cfg[0x19] == b"\x04"  # 1 kHz / 5 = 200 Hz
    assert cfg[0x6B] == b"\x01"  # awake, PLL clock
    assert imu.read() == (100, -200, 4096, 1, 2, 3)
    assert imu.accel_lsb_per_g == 4096


def test_mpu6050_rejects_a_wrong_chip(firmware_path):
    from mpu6050 import MPU6050

    with pytest.raises(OSError, match="WHO_AM_I 0x12"):
        MPU6050(FakeBus({0x68: {0x75: 0x12}}), 0x68)


def test_lsm6ds3_configures_and_reads_little_endian(firmware_path):
    from lsm6ds3 import LSM6DS3

    regs = {0x0F: 0x69}
    for i, b in enumerate(struct.pack("<hhhhhh", 7, 8, 9, -1, 2, 4098)):
        regs[0x22 + i] = b
    bus = FakeBus({0x6A: regs})
    imu = LSM6DS3(bus, 0x6A)
    cfg = {reg: data for _, reg, data in bus.writes}
    assert cfg[0x10] == b"\x5e"  # 208 Hz, +-8 g, 100 Hz anti-aliasing
    assert imu.read() == (-1, 2, 4098, 7, 8, 9)


def test_board_finds_two_mpus_a_is_the_lower_address(firmware_path):
    import board

    bus = FakeBus({0x68: mpu_regs(accel=(1, 1, 1)), 0x69: mpu_regs(accel=(2, 2, 2))})
    (a, b), found = board.find_imus(bus)
    assert found == [0x68, 0x69] and a.addr == 0x68 and b.addr == 0x69
    (a, b), _ = board.find_imus(FakeBus({0x69: mpu_regs()}))
    assert a.addr == 0x69 and b is None
    (a, b), _ = board.find_imus(FakeBus({}))
    assert a is None and b is None
