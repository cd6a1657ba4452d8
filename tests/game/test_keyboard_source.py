"""keyboard:// as a sensor: samples on the source's clock, motions synthesized by the virtual
player on key presses, states instead of exceptions; and the synthesized sounds."""

from __future__ import annotations

import numpy as np
import pytest

import game  # noqa: F401 - the package registers keyboard://
from engine.clock import VirtualClock
from engine.sensors import SourceError, SourceState, open_source, registered_schemes
from game.keyboard_source import KEYMAP, key_help


def test_the_game_package_registers_the_scheme() -> None:
    assert "keyboard" in registered_schemes()


def test_samples_follow_the_clock_at_60_hz_and_a_press_moves_the_hands() -> None:
    clock = VirtualClock()
    src = open_source("keyboard://?seed=1", clock=clock.seconds)
    assert src.state == SourceState.CONNECTED and src.sensors == 2
    rest = []
    for _ in range(30):
        clock.advance(16_666_667)
        rest += src.poll()
    assert 29 <= len(rest) <= 31
    t = np.array([s.t for s in rest])
    assert np.allclose(np.diff(t), 1 / 60)
    quiet = np.array([s.accel for s in rest])
    assert quiet.shape[1:] == (2, 3)
    assert np.allclose(np.linalg.norm(quiet, axis=2), 1.0, atol=0.15)  # hands at rest: gravity
    assert src.press_key("p") == "straight_r" and src.busy
    moving = []
    for _ in range(40):
        clock.advance(16_666_667)
        moving += src.poll()
    peak = np.abs(np.array([s.accel for s in moving]) - quiet.mean(axis=0)).max()
    assert peak > 0.8  # a punch, not noise
    assert src.press_key("x") is None  # not an action key


def test_disconnect_is_a_state_not_an_exception() -> None:
    clock = VirtualClock()
    src = open_source("keyboard://", clock=clock.seconds)
    src.disconnect()
    clock.advance(100_000_000)
    assert src.poll() == [] and src.state == SourceState.DISCONNECTED
    src.reconnect()
    clock.advance(100_000_000)
    assert len(src.poll()) >= 1


def test_bad_urls_name_themselves() -> None:
    with pytest.raises(SourceError, match="seed"):
        open_source("keyboard://?seed=abc")
    with pytest.raises(SourceError, match="profile"):
        open_source("keyboard://?profile=pro")
    with pytest.raises(SourceError, match=r"keyboard://\?sead=3: unknown parameter\(s\) sead \(known: profile, seed, auto, keys\)"):
        open_source("keyboard://?sead=3")  # a typo: it played seed 0 with no word said


def test_every_action_has_a_key() -> None:
    from game.actions import ACTION_NAMES

    assert sorted(KEYMAP.values()) == sorted(ACTION_NAMES)
    assert len(key_help()) == 13


def test_sounds_are_synthesized_and_silent_without_a_device() -> None:
    from game.sound import Sounds, to_int16

    s = Sounds(enabled=True)  # the dummy audio driver, or no mixer at all: never an error
    assert set(s.waves) == {"punch", "hit", "hit_light", "block", "bell"}
    assert len(s.waves["bell"]) > len(s.waves["hit"]) > 0
    for w in s.waves.values():
        pcm = to_int16(w)
        assert pcm.dtype == np.int16 and np.abs(pcm).max() > 1000
    s.play("bell")
    Sounds(enabled=False).play("hit")
