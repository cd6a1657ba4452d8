"""Samples to 60 Hz frames: the exact k/60 grid, live == offline, irregular input rates, and a
replay of the phone recording through the loop and the live resampler."""

from __future__ import annotations

import numpy as np
import pytest

from engine.clock import VirtualClock
from engine.frames import FRAME_HZ, FrameResampler, recording_frames, resample
from engine.loop import FixedStepLoop
from engine.recording import Recording, read_recording, write_recording
from engine.sensors import Sample, open_source


def irregular(rate_hz: float, seconds: float, seed: int, sensors: int = 2):
    """Jittery timestamps around rate_hz and a smooth signal sampled at them."""
    rng = np.random.default_rng(seed)
    n = int(rate_hz * seconds)
    dt = rng.uniform(0.5, 1.5, n) / rate_hz
    t = 3.0 + np.concatenate([[0.0], np.cumsum(dt[:-1])])
    x = np.stack([np.sin(2 * np.pi * 1.3 * t + k) for k in range(3 * sensors)], axis=1)
    return t, x.reshape(n, sensors, 3)


@pytest.mark.parametrize("rate", [25, 100, 430])
def test_irregular_input_becomes_exact_60hz_frames(rate):
    t, x = irregular(rate, 4.0, seed=rate)
    grid, frames = resample(t, x)
    assert frames.shape == (len(grid), 6)
    assert len(grid) == int(np.floor((t[-1] - t[0]) * 60 + 1e-9)) + 1
    np.testing.assert_allclose(grid - t[0], np.arange(len(grid)) / 60, rtol=0, atol=1e-12)
    assert grid[0] == t[0] and grid[-1] <= t[-1]
    # a linear signal is reproduced exactly by linear interpolation
    lin_grid, lin = resample(t, np.column_stack([2 * t - 1, -t]))
    np.testing.assert_allclose(lin, np.column_stack([2 * lin_grid - 1, -lin_grid]), rtol=0, atol=1e-12)
    # a smooth one closely, and better the faster the input
    err = np.abs(frames - np.stack([np.sin(2 * np.pi * 1.3 * grid + k) for k in range(6)], axis=1)).max()
    assert err < {25: 0.06, 100: 0.01, 430: 0.001}[rate]


def test_hold_mode_and_duplicate_times():
    t = np.array([0.0, 0.01, 0.01, 0.05])
    x = np.array([[0.0], [1.0], [2.0], [3.0]])
    grid, held = resample(t, x, mode="hold")
    assert held[:, 0].tolist() == [0.0, 2.0, 2.0, 3.0][: len(grid)]
    grid, lin = resample(t, x)
    assert lin[1, 0] == pytest.approx(2.0 + (1 / 60 - 0.01) / 0.04)  # after the later duplicate
    with pytest.raises(ValueError):
        resample(t, x, mode="cubic")


def test_recording_frames_are_exactly_k_over_60_apart(shared_data):
    rec = read_recording(shared_data / "phone-boxing" / "train.csv")
    times, frames, labels = recording_frames(rec)
    k = np.arange(len(times))
    np.testing.assert_array_equal(times, k / FRAME_HZ)
    assert len(times) == int((rec.t[-1] - rec.t[0]) * 60) + 1
    assert frames.shape == (len(times), 3) and len(labels) == len(times)
    assert {"jab", "cross", "hook", "uppercut"} <= set(labels)


@pytest.mark.parametrize("seed", [0, 1])
def test_live_resampler_equals_offline_resample(seed):
    t, x = irregular(100, 5.0, seed)
    grid, offline = resample(t, x)
    rng = np.random.default_rng(seed)
    res = FrameResampler(sensors=2)
    i, live = 0, []
    for g in grid:
        # samples arrive in irregular bursts; every sample up to the one after g is in
        while i < len(t) and t[i] <= g + rng.uniform(0.02, 0.08):
            chunk = rng.integers(1, 4)
            res.push([Sample(float(tt), xx) for tt, xx in zip(t[i: i + chunk], x[i: i + chunk], strict=True)])
            i += chunk
        live.append(res.frame_at(float(g)).copy())
    np.testing.assert_array_equal(np.array(live), offline)


def test_live_resampler_holds_before_the_next_sample_and_is_none_before_the_first():
    res = FrameResampler(sensors=1)
    assert res.frame_at(0.0) is None
    res.push([Sample(0.0, np.array([[1.0, 2.0, 3.0]]))])
    assert res.frame_at(0.01).tolist() == [1.0, 2.0, 3.0]  # nothing later yet: hold
    res.push([Sample(0.02, np.array([[3.0, 2.0, 1.0]]))])
    assert res.frame_at(0.01).tolist() == pytest.approx([2.0, 2.0, 2.0])


def test_replay_of_the_phone_recording_through_loop_and_resampler(shared_data):
    """replay:// on a virtual clock, polled by a 60 Hz loop stage, resampled live: one frame
    per step at exactly k/60 s, equal to the offline frames of the same recording."""
    path = shared_data / "phone-boxing" / "train.csv"
    rec = read_recording(path)
    rel = rec.t - rec.t[0]
    lag_steps = int(np.ceil(np.diff(rel).max() * 60)) + 1  # wait for the sample after an instant
    clock = VirtualClock()
    source = open_source(f"replay://{path}", clock=clock.seconds)
    loop = FixedStepLoop(clock=clock, auto_freeze_gc=False)
    res = FrameResampler(sensors=1)
    times, frames = [], []

    def sense(step: int, dt: float) -> None:
        res.push(source.poll())
        k = step - lag_steps
        if k >= 0:
            times.append(loop.step_time(k))
            frames.append(res.frame_at(times[-1]).copy())

    loop.add_stage("sense", sense, budget_ms=1.0)
    n_frames = int(np.floor(rel[-1] * 60 + 1e-9)) + 1
    loop.run(steps=n_frames + lag_steps)
    assert loop.dropped_steps == 0
    times = np.array(times)
    np.testing.assert_array_equal(times, np.arange(n_frames) / 60)
    assert np.all(np.diff(times) == pytest.approx(1 / 60, abs=1e-12))
    _, offline = resample(rel, rec.accel)
    np.testing.assert_array_equal(np.array(frames), offline)


def test_a_last_sample_written_rounded_still_reaches_its_step(tmp_path):
    # docs/formats.md's example writes t to 4 decimals: 0.0333 is the step at 1/30 s. The grid
    # ended at floor(duration * 60 + 1e-9): the last sample of a 60 Hz file written rounded down
    # was lost (`synth --session 20` wrote 1200 frames and read back 1199)
    rec = Recording(np.array([0.0, 0.0167, 0.0333]), np.tile([0.0, 0.0, 1.0], (3, 1, 1)), ["", "", ""])
    assert len(recording_frames(rec)[1]) == 3
    exact = Recording(np.arange(1200) / 60.0, np.tile([0.0, 0.0, 1.0], (1200, 1, 1)), [""] * 1200)
    path = tmp_path / "s.csv"
    write_recording(path, exact)
    assert len(recording_frames(read_recording(path))[1]) == 1200
    short = Recording(np.array([0.0, 0.0167, 0.0320]), np.tile([0.0, 0.0, 1.0], (3, 1, 1)), ["", "", ""])
    assert len(recording_frames(short)[1]) == 2  # 0.0320 is not 1/30 s: no step made up


def test_recording_frames_at_a_phase_sit_that_fraction_of_a_step_later():
    # `quickjab evaluate --phases`: where the first sample falls between two steps is chance
    t = np.arange(101) / 100.0  # 1 s at 100 Hz, a ramp on every axis: linear interpolation is exact
    x = np.stack([t, 2 * t, 1 + 0 * t], axis=1)
    labels = ["a" if s < 0.5 else "b" for s in t]
    rec = Recording(t, x.reshape(-1, 1, 3), labels)
    times0, frames0, _ = recording_frames(rec)
    times, frames, got = recording_frames(rec, phase=0.5)
    np.testing.assert_allclose(times, (np.arange(len(times)) + 0.5) / 60, rtol=0, atol=1e-12)
    assert len(times) == 60 and len(times0) == 61  # the last step at 60.5/60 s is past the last sample
    np.testing.assert_allclose(frames[:, 0], times, atol=1e-12)
    np.testing.assert_allclose(frames[:, 1], 2 * times, atol=1e-12)
    assert not np.allclose(frames[:, 0], frames0[:60, 0])
    assert got == ["a" if s < 0.5 else "b" for s in np.floor(times * 100) / 100]
    np.testing.assert_array_equal(recording_frames(rec, phase=0.0)[1], resample(t, x)[1])
    with pytest.raises(ValueError, match="phase"):
        recording_frames(rec, phase=1.0)
