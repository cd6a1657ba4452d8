"""Where issue 17 (the first hour) and issue 19 (two players) meet: `play --players 2` keeps
the first hour's fixes, and the two modes share their code rather than copy it."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from tools.cli import main

REPO = Path(__file__).resolve().parents[2]


@pytest.fixture(autouse=True)
def own_data_dir(tmp_path, monkeypatch):
    """Never read (or write) the real user's trained templates."""
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "xdg"))


def test_two_player_headless_without_frames_ends_and_names_the_templates(tmp_path, monkeypatch, capsys) -> None:
    import game.launch

    monkeypatch.setattr(game.launch, "HEADLESS_FRAMES", 40)  # the one-player default, shortened
    trace = tmp_path / "t.json"
    assert main(["play", "--players", "2", "--demo", "--headless", "--size", "320x180", "--trace", str(trace)]) == 0
    frames = [e for e in json.loads(trace.read_text())["traceEvents"] if e.get("name") == "frame"]
    assert len(frames) == 40
    err = capsys.readouterr().err
    assert "stopping after 40 frames" in err
    assert "quickjab play: P1 default templates" in err and "quickjab play: P2 default templates" in err


def test_two_player_without_a_display_is_a_clear_error() -> None:
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY", "SDL_VIDEODRIVER")}
    env.update(PYTHONPATH=str(REPO), SDL_AUDIODRIVER="dummy", XDG_DATA_HOME=os.environ["XDG_DATA_HOME"])
    r = subprocess.run([sys.executable, "-m", "tools.cli", "play", "--players", "2", "--source", "keyboard://",
                        "--source2", "keyboard://", "--frames", "100000"],
                       cwd=REPO, env=env, capture_output=True, text=True, timeout=120)
    assert r.returncode == 2, r.stderr
    assert "no display" in r.stderr and "--headless" in r.stderr
    assert "Traceback" not in r.stderr


def two_player_session(urls=("keyboard://?seed=1&keys=left", "keyboard://?seed=2&keys=right"), **cfg):
    import pygame

    import game.keyboard_source  # noqa: F401 - registers keyboard://
    from engine.clock import VirtualClock
    from engine.sensors import open_source
    from game.session import SessionConfig
    from game.two_player import TwoPlayerSession

    pygame.init()
    clock = VirtualClock()
    sources = [open_source(u, clock=clock.seconds) for u in urls]
    config = SessionConfig(size=(320, 180), sound=False, **{"render": False, **cfg})
    return TwoPlayerSession(sources, config, clock=clock)


def one_player_session(**cfg):
    import pygame

    import game.keyboard_source  # noqa: F401 - registers keyboard://
    from engine.clock import VirtualClock
    from engine.sensors import open_source
    from game.session import Session, SessionConfig

    pygame.init()
    clock = VirtualClock()
    source = open_source(cfg.pop("url", "keyboard://?seed=1"), clock=clock.seconds)
    return Session(source, SessionConfig(size=(320, 180), sound=False, render=False, **cfg), clock=clock)


def test_a_blow_does_the_same_damage_in_both_modes() -> None:
    """Issue 17 scaled every blow by BLOW_SCALE; the two-player copy of apply_hit did not."""
    from game.session import BLOCKED_SHARE, BLOW_SCALE, REFERENCE_SPEED

    hit = {"attacker": 0, "target": "head", "hand": "l", "speed": REFERENCE_SPEED, "damage": 10.0, "blocked": False,
           "direction": (0.0, 0.0, 1.0)}
    one, two = one_player_session(), two_player_session()
    for s in (one, two):
        s.apply_hit(5, dict(hit))
        s.apply_hit(6, {**hit, "attacker": 1, "blocked": True})
    assert two.match.health[1] == pytest.approx(100 - 10.0 * BLOW_SCALE)
    assert one.match.health[1] == two.match.health[1]  # the player's blow: no difficulty in it
    assert two.match.health[0] == pytest.approx(100 - 10.0 * BLOW_SCALE * BLOCKED_SHARE)  # no CPU handicap
    assert [b[1:] for b in two.blows_log] == [(0, "head", False, 6.0),
                                              (1, "head", True, round(10.0 * BLOW_SCALE * BLOCKED_SHARE, 4))]


def test_two_player_session_has_what_the_inherited_methods_read() -> None:
    """TwoPlayerSession(Session) never ran Session.__init__: the pause menu's D
    (cycle_difficulty) and the round bookkeeping met missing attributes."""
    import pygame

    one, two = one_player_session(), two_player_session(difficulty="adaptive")
    assert set(vars(one)) <= set(vars(two)), sorted(set(vars(one)) - set(vars(two)))
    two.match.toggle_pause()
    two.cycle_difficulty()  # the pause menu's D: nothing to set, no CPU, and no error
    two.handle_event(pygame.event.Event(pygame.KEYDOWN, key=pygame.K_d, mod=0, unicode="d", scancode=0))
    assert two.hud_state.difficulty == ""  # the pause menu offers no difficulty: two people box
    two.match.toggle_pause()
    two.match.round_winners.append(0)  # a round decided: the one-player bookkeeping is safe
    two.loop.run(steps=2)


def test_the_side_on_view_draws_neither_boxer_see_through(monkeypatch) -> None:
    """Side-on, "near" is arbitrary: issue 17's translucent near boxer is the one-player view's."""
    import numpy as np
    import pygame

    from game.render import Renderer
    from game.render_two_player import SideOnLowPowerRenderer, SideOnRenderer

    pygame.init()
    assert Renderer.see_through  # the one-player view keeps it
    s = two_player_session()
    bodies = [j.copy() for j in s.curr_joints]
    bodies[1][:, 0] += 0.05  # nearly on top of each other: the one-player view would blend
    for cls in (SideOnRenderer, SideOnLowPowerRenderer):
        r = cls((320, 180))
        assert r.see_through is False
        monkeypatch.setattr(r, "_overlap", lambda b: pytest.fail("side-on drew a see-through boxer"))
        r.draw(pygame.Surface((320, 180)), bodies)
    assert np.isfinite(bodies[0]).all()


def test_shifted_primitives_stay_plain_float_pairs() -> None:
    """The see-through pass moved capsules and spheres by list - ndarray: numpy per limb."""
    from game.render import _shifted

    capsule = _shifted(0, ([10.0, 20.0], (30.0, 40.0), 3.0, 2.0, (1, 2, 3)), (4.0, 5.0))
    assert capsule == ((6.0, 15.0), (26.0, 35.0), 3.0, 2.0, (1, 2, 3))
    assert all(type(p) is tuple and all(type(v) is float for v in p) for p in capsule[:2])
    sphere = _shifted(1, ([10.0, 20.0], 3.0, (1, 2, 3)), (4.0, 5.0))
    assert sphere == ((6.0, 15.0), 3.0, (1, 2, 3)) and type(sphere[0]) is tuple


@pytest.mark.parametrize("size", [(1280, 720), (640, 360)])
def test_two_player_key_legends_sit_on_dark_panels_with_hand_labels(size) -> None:
    """Issue 17's readable legend (a dark panel, "L"/"R") for each of the two keyboard players."""
    import numpy as np
    import pygame

    from game.hud import HudState
    from game.hud_two_player import TwoPlayerHud, compact_keys
    from game.keyboard_source import KEYMAP_LEFT, KEYMAP_RIGHT, key_help

    lines = compact_keys(key_help(KEYMAP_LEFT))
    assert lines[0].startswith("L hand: Q straight") and lines[1].startswith("R hand: A straight")
    assert "_l" not in " ".join(lines) and " l/" not in " ".join(lines)
    pygame.init()
    surf = pygame.Surface(size)
    surf.fill((235, 235, 235))  # a bright scene (the canvas, a white rope) under the legends
    one, two = HudState(keys=key_help(KEYMAP_LEFT)), HudState(keys=key_help(KEYMAP_RIGHT))
    hud = TwoPlayerHud(two)
    hud.draw(surf, one)
    assert len(hud.key_panels) == 2
    left, right = hud.key_panels
    assert left.right < right.left and left.centerx < size[0] // 2 < right.centerx
    px = pygame.surfarray.array3d(surf).astype(int).sum(axis=2) / 3
    for panel in hud.key_panels:
        assert surf.get_rect().contains(panel)
        a = px[panel.left:panel.right, panel.top:panel.bottom]
        assert np.median(a) < 70  # the panel hides what is behind it
        assert (a > 180).sum() > 100  # and the legend's text is bright on it
    # the recognition panels sit above the legends, not under them
    w, h = size
    above = px[left.left + 4:left.right - 4, left.top - int(12 * h / 720):left.top - 2]
    assert np.median(above) < 90


def test_the_largest_seed_plays_two_players_and_duels(capsys) -> None:
    """Seat and duel seeds were seed + i: past SEED_MAX, a keyboard URL the source refused."""
    from engine.arguments import SEED_MAX
    from engine.sensors import SourceError, open_source
    from game.two_player import source_urls
    from tools.virtual_duel import duel_jobs

    assert main(["play", "--players", "2", "--demo", "--headless", "--frames", "2", "--size", "320x180",
                 "--seed", str(SEED_MAX)]) == 0
    urls, _ = source_urls("keyboard://", "keyboard://", demo=False, seed=SEED_MAX)
    assert f"seed={SEED_MAX}" in urls[0] and "seed=0" in urls[1]
    assert [job[2] for job in duel_jobs(["normal"], ["novice", "experienced"], 2, SEED_MAX)] == [SEED_MAX, 0] * 2
    import game.keyboard_source  # noqa: F401 - registers keyboard://

    with pytest.raises(SourceError) as err:
        open_source(f"keyboard://?seed={SEED_MAX + 1}")
    assert f"from 0 to {SEED_MAX}" in str(err.value) and "e+" not in str(err.value)  # the bound as an integer


def test_the_one_player_legend_shows_the_keys_the_source_answers() -> None:
    """`keyboard://?keys=left` answers only the left half; the legend showed the whole keyboard."""
    from game.keyboard_source import KEYMAP, KEYMAP_LEFT, key_help

    assert one_player_session(url="keyboard://?seed=1&keys=left").hud_state.keys == key_help(KEYMAP_LEFT)
    assert one_player_session(url="keyboard://?seed=1").hud_state.keys == key_help(KEYMAP)


def test_player_two_options_in_a_one_player_match_are_noted(capsys) -> None:
    """The review: `play --source2 URL --profile2 NAME` without `--players 2` dropped both unsaid."""
    assert main(["play", "--demo", "--headless", "--frames", "1", "--size", "320x180",
                 "--source2", "keyboard://", "--profile2", "ben"]) == 0
    notes = [line for line in capsys.readouterr().err.splitlines() if "ignored" in line]
    assert notes == ["quickjab play: --source2 and --profile2 ignored without --players 2: they are player 2's"]
    assert main(["play", "--demo", "--headless", "--frames", "1", "--size", "320x180"]) == 0
    assert "ignored" not in capsys.readouterr().err  # not given: nothing to say


def test_two_player_options_for_the_cpu_are_noted_and_one_keyboard_half_twice_is_an_error(capsys) -> None:
    assert main(["play", "--players", "2", "--demo", "--headless", "--frames", "1", "--size", "320x180",
                 "--difficulty", "hard", "--graph", "no-such.npz"]) == 0
    notes = [line for line in capsys.readouterr().err.splitlines() if "ignored" in line]
    assert len(notes) == 1 and "--difficulty" in notes[0] and "--graph" in notes[0]
    assert main(["play", "--players", "2", "--demo", "--headless", "--frames", "1", "--size", "320x180"]) == 0
    assert "ignored" not in capsys.readouterr().err  # not given: nothing to say
    for a, b in (("left", "left"), ("right", "right"), ("all", "left")):
        assert main(["play", "--players", "2", "--headless", "--frames", "1", "--source", f"keyboard://?keys={a}",
                     "--source2", f"keyboard://?keys={b}"]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and f"keys={a}" in err[0] and "their own half" in err[0], err
    assert main(["play", "--players", "2", "--headless", "--frames", "1", "--size", "320x180",
                 "--source", "keyboard://?keys=right", "--source2", "keyboard://?keys=left"]) == 0  # swapped is fine
