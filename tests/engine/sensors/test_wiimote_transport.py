"""The thin hidapi wrapper: backend choice, listing, non-blocking reads, padded writes,
errors as TransportError."""

from __future__ import annotations

import sys

import numpy as np
import pytest

from engine.clock import VirtualClock
from engine.recording import Recording
from engine.sensors.wiimote.emulator import EmulatedBus, EmulatedWiimote
from engine.sensors.wiimote.transport import (
    HidTransport,
    TransportError,
    hid_backend,
    kernel_driver,
    list_wiimotes,
)

REC = Recording(np.arange(0, 1, 1 / 60), np.zeros((60, 2, 3)))


def test_backend_prefers_hidraw_on_linux():
    mod = hid_backend()
    assert hasattr(mod, "enumerate") and hasattr(mod, "device")
    if sys.platform.startswith("linux"):
        assert mod.__name__ == "hidraw"
    assert isinstance(list_wiimotes(mod), list)  # the real backend answers without raising


def test_kernel_driver_lookup_is_quiet():
    assert kernel_driver(b"emu-1") is None
    assert kernel_driver("/dev/hidraw999") is None  # no such node: unknown, not an error


def test_list_excludes_non_wiimotes():
    vc = VirtualClock()
    plus = EmulatedWiimote(REC, vc.seconds, serial="a", product_id=0x0330)
    bus = EmulatedBus([EmulatedWiimote(REC, vc.seconds, serial="b"), plus])
    names = {w.model for w in list_wiimotes(bus)}
    assert names == {"RVL-CNT-01", "RVL-CNT-01-TR"}

    class ProBus(EmulatedBus):
        def enumerate(self, vendor_id=0, product_id=0):
            rows = super().enumerate(vendor_id, product_id)
            for r in rows:
                r["product_string"] = "Nintendo RVL-CNT-01-UC"  # a Wii U Pro Controller
            return rows

    assert list_wiimotes(ProBus([plus])) == []


def test_reads_writes_and_loss():
    vc = VirtualClock()
    emu = EmulatedWiimote(REC, vc.seconds, jitter_ms=0)
    t = HidTransport(EmulatedBus([emu]), emu.path, write_length=22)
    t.open()
    assert t.read() is None  # nothing waiting: returns at once
    t.write(bytes([0x15, 0x00]))
    assert emu.outputs[-1] == bytes([0x15, 0x00]) + bytes(20)  # padded to 22
    vc.advance(10_000_000)
    assert t.read()[0] == 0x20
    emu.unplug()
    with pytest.raises(TransportError):
        t.read()
    with pytest.raises(TransportError):
        t.write(bytes([0x15, 0x00]))
    t.close()
    t.close()
    with pytest.raises(TransportError):
        HidTransport(EmulatedBus([emu]), emu.path).open()
