"""A pause freezes the match: the boxers' clips, the physics and the CPU's timers stand still,
a punch under way is not spent by a touch under the pause (it lands after it), and a motion the
player makes under the pause does nothing, during it or after it."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).parent))
from fair_play import fist_on_head, one_player, throw, touch_next_steps, two_players  # noqa: E402
from game_graph import graph_path  # noqa: E402,F401 - the fixture


@pytest.fixture(autouse=True)
def own_data_dir(tmp_path, monkeypatch):
    """Never read (or write) the real user's trained templates."""
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "xdg"))


def test_a_punch_under_way_is_held_by_the_pause_and_lands_after_it(graph_path) -> None:  # noqa: F811
    s = one_player(graph_path)
    s.loop.run(steps=20)
    throw(s, 0)
    s.toggle_pause()  # Esc, or the Wiimote's Home
    still = s.world.x.copy()
    # the fist on the CPU's head for as long as it stays there (a touch is reported every step)
    touch_next_steps(s, [fist_on_head(s, 0)], steps=90)
    s.loop.run(steps=60)
    ctrl = s.player.controller
    assert (ctrl.action, ctrl.frame) == ("straight_r", 8.0)  # the clip stands still ...
    assert np.array_equal(s.world.x, still)  # ... and so do the bodies
    assert not s.player.hand_spent("r") and s.match.health[1] == 100.0 and len(s.blows_log) == 0
    s.toggle_pause()
    s.loop.run(steps=1)
    assert s.match.health[1] < 100.0 and [blow[1] for blow in s.blows_log] == [0]  # it lands now


def test_the_cpu_rests_and_moves_no_further_under_the_pause(graph_path) -> None:  # noqa: F811
    s = one_player(graph_path)
    s.loop.run(steps=20)
    s.opponent.controller.play("hook_l", from_frame=3)
    s._cpu_rest = 45  # steps it waits at the guard after this move
    s.toggle_pause()
    s.loop.run(steps=120)
    cpu = s.opponent.controller
    assert (cpu.action, cpu.frame, s._cpu_rest) == ("hook_l", 3.0, 45)
    s.toggle_pause()
    s.loop.run(steps=2)
    assert cpu.action == "hook_l" and cpu.frame == 4.0  # on from where it stood


def test_a_motion_made_under_the_pause_does_nothing_after_it() -> None:
    """A left hook made under the pause (the virtual player's Wiimote readings: keys do nothing
    then) was ignored, but its second half, the hand coming back, started a hook after the
    resume: the character never played the first, so nothing discarded the return."""
    from engine.sensors.source import PLAYABLE

    s = two_players()
    s.seats[0].source.capabilities = frozenset({PLAYABLE})  # a controller's readings: no keys (hold_keys)
    s.loop.run(steps=60)  # the recognizers learn the resting gravity
    s.toggle_pause()
    s.seats[0].source.press("hook_l")
    starts, actions = 0, set()
    for _ in range(240):
        s.loop.run(steps=1)
        new = sum(1 for seat, ev in s.events_log if seat == 0 and ev["event"] == "start")
        if s.match.paused and new > starts == 0:
            s.toggle_pause()  # resumed just after the recognizer named the motion
        starts = new
        actions.add(s.boxers[0].controller.action)
    assert starts >= 1  # the recognizer saw the motion ...
    assert actions == {"guard"}  # ... and the boxer did nothing with it


def test_a_hit_flash_stands_still_with_the_picture_under_the_pause() -> None:
    """The pause is a still picture of the ring: a flash mid-way stays as it was (frozen with the
    bodies it lit, not fading over them), and fades on after the resume."""
    s = two_players()
    s.loop.run(steps=20)
    s.renderer.add_flash(s.boxers[1].joint_positions()[4])
    s.loop.run(steps=5)
    s.toggle_pause()
    s.loop.run(steps=60)
    assert [f.age for f in s.renderer.flashes] == [5]
    s.toggle_pause()
    s.loop.run(steps=1)
    assert [f.age for f in s.renderer.flashes] == [6]


@pytest.mark.parametrize("players", [1, 2])
def test_a_key_pressed_just_before_esc_plays_after_the_resume(players, graph_path) -> None:  # noqa: F811
    """A key and Esc in one step's events: the key was pressed, but its move, performed from
    the next reading on, was all made under the pause, which finished it for the boxer: lost."""
    import pygame

    s = one_player(graph_path) if players == 1 else two_players()
    s.loop.run(steps=60)  # the recognizer learns the resting gravity
    for key in (pygame.K_q, pygame.K_ESCAPE):
        pygame.event.post(pygame.event.Event(pygame.KEYDOWN, key=key, mod=0, unicode="", scancode=0))
    s.loop.run(steps=120)
    assert s.match.paused and s.boxers[0].controller.action == "guard"
    s.toggle_pause()
    actions = set()
    for _ in range(60):
        s.loop.run(steps=1)
        actions.add(s.boxers[0].controller.action)
    assert "straight_l" in actions  # the move waited for the resume
