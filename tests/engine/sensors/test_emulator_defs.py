"""The emulators' settings as data: WiimoteEmulatorDef and the serial board's EmulatorDef give
exactly the emulator their fields as keywords give."""

from __future__ import annotations

import dataclasses
import inspect

import numpy as np
import pytest

from engine.clock import VirtualClock
from engine.recording import Recording
from engine.sensors.wiimote.emulator import EmulatedWiimote, WiimoteEmulatorDef
from firmware_bridge.emulator import Emulator, EmulatorDef, synthetic_motion

STEP_NS = 16_666_667


def keyword_defaults(init, skip: tuple[str, ...]) -> dict[str, object]:
    params = inspect.signature(init).parameters
    return {n: p.default for n, p in params.items() if n not in skip and p.default is not inspect.Parameter.empty}


def recording() -> Recording:
    t = np.arange(0, 4, 1 / 60)
    a = np.empty((len(t), 2, 3))
    a[:, :, 0] = np.sin(3 * t)[:, None]
    a[:, :, 1] = 0.2
    a[:, :, 2] = 1.0 - 0.5 * np.cos(2 * t)[:, None]
    return Recording(t, a)


def reports(make) -> list[bytes]:
    vc = VirtualClock()
    emu = make(vc.seconds)
    emu.handle_output(bytes([0x12, 0x04, 0x35]))
    out = []
    for _ in range(180):
        vc.advance(STEP_NS)
        while (r := emu.take(vc.seconds())) is not None:
            out.append(bytes(r))
    return out


def test_wiimote_def_fields_are_the_emulator_keywords_with_their_defaults():
    assert WiimoteEmulatorDef().kwargs() == keyword_defaults(EmulatedWiimote.__init__, ("self", "rec", "clock", "events"))


def test_wiimote_from_def_sends_the_same_reports_as_the_keywords():
    rec = recording()
    tuned = {"drop": 0.2, "jitter_ms": 5.0, "seed": 3, "pad": 22}
    by_keywords = reports(lambda clock: EmulatedWiimote(rec, clock, **tuned))
    by_def = reports(lambda clock: EmulatedWiimote.from_def(rec, clock, WiimoteEmulatorDef(**tuned)))
    assert by_keywords == by_def and len(by_def) > 100
    assert reports(lambda clock: EmulatedWiimote.from_def(rec, clock)) == reports(lambda clock: EmulatedWiimote(rec, clock))
    assert by_def != reports(lambda clock: EmulatedWiimote.from_def(rec, clock))  # the settings do matter
    assert EmulatedWiimote.from_def(rec, lambda: 0.0, WiimoteEmulatorDef(**tuned)).definition == WiimoteEmulatorDef(**tuned)
    with pytest.raises(dataclasses.FrozenInstanceError):
        WiimoteEmulatorDef().drop = 0.5  # type: ignore[misc]


def test_serial_board_def_fields_are_the_emulator_keywords_with_their_defaults():
    kw = keyword_defaults(Emulator.__init__, ("self", "signal", "faults", "link", "on_port", "on_event"))
    assert dataclasses.asdict(EmulatorDef()) == kw


def test_serial_board_from_def_samples_the_same_as_the_keywords():
    signal = synthetic_motion(2, 0)
    made = [Emulator(signal, 2, rate_hz=100, seed=4, noise_g=0.01, ticks_start=1000),
            Emulator.from_def(signal, EmulatorDef(2, rate_hz=100, noise_g=0.01, ticks_start=1000, seed=4))]
    try:
        assert made[0].definition == made[1].definition == EmulatorDef(2, 100, 0.01, 30, 1000, 4)
        reads = []
        for emu in made:
            emu.elapsed = lambda: 1.25  # the same instant for both
            sampler = emu._sampler(0)
            reads.append([imu.read() for imu in sampler.imus] + [sampler.rate_hz, sampler.ts_mask, sampler.boot_id])
        assert reads[0] == reads[1]
    finally:
        for emu in made:
            emu.port.close()
    with pytest.raises(ValueError):
        EmulatorDef(sensors=3)


def test_serial_board_def_refuses_a_rate_the_hello_cannot_carry():
    # rate_hz is a u16 in the HELLO (PROTOCOL.md): 70000 was accepted, and the board's first
    # HELLO raised struct.error in the emulator's thread
    assert EmulatorDef(rate_hz=65535).rate_hz == 65535
    with pytest.raises(ValueError, match="rate_hz"):
        EmulatorDef(rate_hz=65536)


def test_serial_board_def_refuses_a_tick_counter_too_narrow_for_its_rate():
    # the sampler times its ticks by tick differences, right only under half the counter's period:
    # at ts_bits 8-13 and 200 Hz its loop ran ~30x too fast (10,422 frames in 1.5 s at 8 bits)
    assert EmulatorDef(rate_hz=200, ts_bits=15).ts_bits == 15
    for bits in (8, 13, 14):
        with pytest.raises(ValueError, match="too narrow"):
            EmulatorDef(rate_hz=200, ts_bits=bits)
    assert EmulatorDef(rate_hz=10, ts_bits=19).ts_bits == 19  # 0.26 s half-period, 0.1 s samples
