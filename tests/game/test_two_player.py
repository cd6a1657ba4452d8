"""`play --players 2`: two people on two sources, two real recognizers, one match. Played
headless under the dummy video driver: a keyboard-vs-keyboard match to a decision is
reproducible to the bit, player 2's emulated Wiimote unplugged mid-round pauses the match for
both under an overlay that clears when it is back, and the CLI writes a screenshot."""

from __future__ import annotations

import math

import numpy as np
import pygame
import pytest

from engine.clock import VirtualClock
from engine.sensors import SourceState, open_source
from game.keyboard_source import KEYMAP_LEFT, KEYMAP_RIGHT
from game.match import Match
from game.session import PILOT_ATTACKS, SessionConfig
from game.two_player import TwoPlayerSession, source_urls

SIZE = (640, 360)


@pytest.fixture(autouse=True)
def own_data_dir(tmp_path, monkeypatch):
    """Never read (or write) the real user's trained templates."""
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "xdg"))


def make_session(urls: list[str], seed: int = 0, render: bool = True, display: bool = False,
                 demo: bool = False) -> TwoPlayerSession:
    import game.keyboard_source  # noqa: F401 - registers keyboard://

    pygame.init()
    clock = VirtualClock()
    sources = [open_source(u, clock=clock.seconds) for u in urls]
    provider = None
    if display:
        pygame.display.set_mode(SIZE)
        provider = pygame.display.get_surface
    cfg = SessionConfig(seed=seed, size=SIZE, sound=False, render=render, demo=demo)
    return TwoPlayerSession(sources, cfg, clock=clock, surface_provider=provider)


def key_event(name: str) -> pygame.event.Event:
    return pygame.event.Event(pygame.KEYDOWN, key=pygame.key.key_code(name), mod=0, unicode="", scancode=0)


def play_by_keys(s: TwoPlayerSession, rng: np.random.Generator, max_steps: int) -> None:
    """Two people at one keyboard: each presses a key of their own half now and then, stepping
    in when out of reach, else a punch, block or step (what they press is seeded)."""
    keys_of = [{a: k for k, a in km.items()} for km in (KEYMAP_LEFT, KEYMAP_RIGHT)]
    waits = [0, 0]
    while not s.match.over and s.loop.step_index < max_steps:
        a, b = s.boxers[0].root, s.boxers[1].root
        near = math.hypot(a[0] - b[0], a[1] - b[1]) < 1.0
        for i in (0, 1):
            busy = s.seats[i].source.busy or s.boxers[i].controller.action != "guard"
            if waits[i] > 0:
                waits[i] -= 1
            elif not busy and s.match.fighting:
                action = PILOT_ATTACKS[int(rng.integers(len(PILOT_ATTACKS)))] if near else "step_forward"
                pygame.event.post(key_event(keys_of[i][action]))
                waits[i] = int(rng.integers(8, 30))
        s.loop.run(steps=1)


def test_two_keyboard_players_box_to_a_decision_reproducibly() -> None:
    urls, _ = source_urls("keyboard://", "keyboard://", demo=False, seed=5)
    assert "keys=left" in urls[0] and "keys=right" in urls[1]  # one keyboard, split in two
    outcomes = []
    for _ in range(2):
        s = make_session(urls, seed=5, render=False, display=True)
        assert s.graph is None  # no Interaction Graph: both boxers are people
        assert s.seats[0].recognizer is not s.seats[1].recognizer
        s.match = Match(round_seconds=12)
        play_by_keys(s, np.random.default_rng(11), max_steps=3 * 12 * 60 + 2 * 3 * 60 + 600)
        assert s.match.over  # a decision: KO, TKO or the scorecards
        outcomes.append((s.state_hash(), s.match.state(), s.loop.step_index))
        # each half of the keyboard reached only its own player's source ...
        pressed = [set(seat.source.pressed) for seat in s.seats]
        assert pressed[0] and pressed[1]
        # ... each player's recognizer started actions for its own boxer, and both landed blows
        starts = [{ev["action"] for seat, ev in s.events_log if seat == i and ev["event"] == "start"} for i in (0, 1)]
        assert len(starts[0]) >= 3 and len(starts[1]) >= 3
        assert {blow[1] for blow in s.blows_log} == {0, 1}
        assert s.match.result in ("KO", "TKO", "points", "draw")
    assert outcomes[0] == outcomes[1]


def test_keys_of_each_half_drive_only_their_own_boxer() -> None:
    s = make_session(["keyboard://?seed=1&keys=left", "keyboard://?seed=2&keys=right"], display=True)
    s.loop.run(steps=30)  # the recognizers learn the resting gravity
    pygame.event.post(key_event("q"))  # player 1's left straight
    actions = [[], []]
    for _ in range(70):
        s.loop.run(steps=1)
        for i in (0, 1):
            actions[i].append(s.boxers[i].controller.action)
    assert s.seats[0].source.pressed == ["straight_l"] and s.seats[1].source.pressed == []
    assert "straight_l" in actions[0] and set(actions[1]) <= {"guard"}
    pygame.event.post(key_event("p"))  # player 2's right straight
    for _ in range(70):
        s.loop.run(steps=1)
        actions[1].append(s.boxers[1].controller.action)
    assert s.seats[1].source.pressed == ["straight_r"]
    assert "straight_r" in actions[1]
    assert s.seats[0].source.pressed == ["straight_l"]


def test_player_two_unplugged_mid_round_pauses_both_and_resumes(tmp_path) -> None:
    from tools.cli import main

    rec = tmp_path / "p2.csv"
    assert main(["synth", "--session", "8", "--seed", "2", "-o", str(rec)]) == 0
    # player 2 on an emulated Wiimote + Nunchuk that is unplugged 3 s in and back at 5 s
    s = make_session(["keyboard://?seed=4&keys=left", f"wiimote-emu://{rec}?unplug_at=3&replug_at=5"], display=True)
    surf = pygame.display.get_surface()
    probe = (SIZE[0] // 2, int(SIZE[1] * 0.80))  # the canvas, where no HUD panel is
    s.loop.run(steps=2 * 60)
    assert [seat.source.state for seat in s.seats] == [SourceState.CONNECTED] * 2
    assert s.seats[1].hud.source.battery is not None  # the remote's battery is shown
    bright = sum(surf.get_at(probe)[:3])
    assert s.match.fighting
    s.loop.run(steps=int(1.5 * 60))  # 3.5 s: unplugged
    assert s.seats[1].source.state != SourceState.CONNECTED
    assert s.seats[1].hud.disconnected and not s.seats[0].hud.disconnected
    assert s.seats[1].hud.source.state != "connected" and s.seats[0].hud.source.state == "connected"
    assert s.match.paused  # for both players
    assert sum(surf.get_at(probe)[:3]) < 0.5 * bright  # the overlay
    clock, p1_events = s.match.clock_steps, s.events_log.total
    pygame.event.post(key_event("q"))  # player 1 cannot box on while player 2 is away
    s.loop.run(steps=60)
    assert s.match.clock_steps == clock and s.seats[0].source.pressed == []
    s.loop.run(steps=3 * 60)  # 7.5 s: back
    assert [seat.source.state for seat in s.seats] == [SourceState.CONNECTED] * 2
    assert not s.seats[1].hud.disconnected and not s.match.paused
    assert s.match.clock_steps < clock  # the round clock runs again
    assert sum(surf.get_at(probe)[:3]) > 0.7 * bright
    assert s.events_log.total >= p1_events


def test_enter_plays_a_played_out_replay_again_with_two_players(tmp_path) -> None:
    """Player 1's replay played out: the match paused for good under SOURCE ENDED. Enter, which
    the overlay offers, rewinds it and starts a new match (player 2's half of the keyboard is
    not pressed by it)."""
    from tools.cli import main

    rec = tmp_path / "p1.csv"
    assert main(["synth", "--session", "1", "--seed", "2", "-o", str(rec)]) == 0
    s = make_session([f"replay://{rec}", "keyboard://?seed=5&keys=right"], display=True)
    s.loop.run(frames=90)
    assert s.seats[0].source.state == SourceState.ENDED and s.match.paused
    s.view.hud.layout = []
    s.redraw()  # the overlay's picture: paused, the frame would hold the last one
    s.loop.run(frames=1)
    said = [text for text, _, panel in s.view.hud.layout if panel == "lost"]
    assert "SOURCE ENDED" in said and any(t.startswith("Enter: play it again") for t in said), said
    resets = []
    for seat in s.seats:
        seat.recognizer.reset = lambda reset=seat.recognizer.reset, i=seat.index: (resets.append(i), reset())[-1]
    s.match.health[1] = 40.0
    pygame.event.post(key_event("return"))
    s.loop.run(frames=20)
    assert s.seats[0].source.state == SourceState.CONNECTED and not s.source_lost()
    assert s.match.fighting and s.match.health == [100.0, 100.0]  # a new match
    assert set(resets) == {0, 1} and s.seats[1].source.pressed == []
    s.loop.run(frames=70)
    assert s.seats[0].source.state == SourceState.ENDED and s.match.paused  # played out again


def test_enter_plays_both_replays_again_from_their_start(tmp_path) -> None:
    """Two replays of different lengths: Enter under the shorter one's SOURCE ENDED rewound only
    that one, and the new match went on with the other replay from where it was."""
    from tools.cli import main

    for name, secs in (("p1.csv", "1"), ("p2.csv", "4")):
        assert main(["synth", "--session", secs, "--seed", "2", "-o", str(tmp_path / name)]) == 0
    s = make_session([f"replay://{tmp_path / 'p1.csv'}", f"replay://{tmp_path / 'p2.csv'}"], display=True)
    s.loop.run(frames=90)
    assert [seat.source.state for seat in s.seats] == [SourceState.ENDED, SourceState.CONNECTED]
    p2 = s.seats[1].source
    delivered = []
    poll = p2.poll
    p2.poll = lambda: (lambda got: (delivered.extend(got), got)[1])(poll())
    pygame.event.post(key_event("return"))
    s.loop.run(frames=1)
    assert s.match.fighting and not s.source_lost()
    first = p2.rec.accel[0]
    assert delivered and np.array_equal(delivered[0].accel, first)  # player 2's replay from its start too
    s.loop.run(frames=70)
    assert p2.state == SourceState.CONNECTED  # 1.2 s into its 4 s: it started again


def test_enter_under_a_replays_end_waits_for_the_other_seat(tmp_path) -> None:
    """Player 1's replay played out while player 2's controller was away: Enter rewound the replay
    into a new match paused for player 2, where it played out unseen (player 2 back, SOURCE ENDED
    again); and under player 2's box, which does not offer Enter, Enter reset the match. Now the
    overlay shows the seat the match waits for, Enter does nothing until it is back, then plays
    the replay again."""
    from tools.cli import main

    rec = tmp_path / "p1.csv"
    assert main(["synth", "--session", "1", "--seed", "2", "-o", str(rec)]) == 0
    s = make_session([f"replay://{rec}", "keyboard://?seed=5&keys=right"], display=True)
    s.loop.run(frames=90)
    s.seats[1].source.disconnect()
    s.view.hud.layout = []
    s.redraw()  # the overlay's picture: paused, the frame would hold the last one
    s.loop.run(frames=1)
    assert [seat.source.state for seat in s.seats] == [SourceState.ENDED, SourceState.DISCONNECTED]
    said = [text for text, _, panel in s.view.hud.layout if panel == "lost"]
    assert "CONTROLLER DISCONNECTED" in said and not any(t.startswith("Enter") for t in said), said
    match = s.match
    pygame.event.post(key_event("return"))
    s.loop.run(frames=3)
    assert s.match is match and s.seats[0].source.state == SourceState.ENDED  # not rewound unseen
    s.seats[1].source.reconnect()
    s.view.hud.layout = []
    s.redraw()  # the overlay's picture: paused, the frame would hold the last one
    s.loop.run(frames=1)
    said = [text for text, _, panel in s.view.hud.layout if panel == "lost"]
    assert "SOURCE ENDED" in said and any(t.startswith("Enter: play it again") for t in said), said
    pygame.event.post(key_event("return"))
    s.loop.run(frames=20)
    assert s.match is not match and s.match.fighting and not s.source_lost()


def test_enter_after_the_last_bell_waits_for_a_seat_that_is_away(tmp_path) -> None:
    """The match over, player 1's replay played out and player 2's controller away: Enter (which
    player 2's box does not offer) rewound the replay into a new match paused for player 2, where
    it played out unseen (player 2 back: SOURCE ENDED again). Now Enter waits for player 2, then
    plays the replay again."""
    from tools.cli import main

    rec = tmp_path / "p1.csv"
    assert main(["synth", "--session", "1", "--seed", "2", "-o", str(rec)]) == 0
    s = make_session([f"replay://{rec}", "keyboard://?seed=5&keys=right"], display=True)
    s.loop.run(frames=10)
    s.match._finish(0, "KO")  # the last bell
    s.loop.run(frames=90)
    s.seats[1].source.disconnect()
    s.loop.run(frames=1)
    assert s.match.over and [seat.source.state for seat in s.seats] == [SourceState.ENDED, SourceState.DISCONNECTED]
    match = s.match
    pygame.event.post(key_event("return"))
    s.loop.run(frames=3)
    assert s.match is match and s.seats[0].source.state == SourceState.ENDED  # not rewound unseen
    s.seats[1].source.reconnect()
    s.loop.run(frames=1)
    pygame.event.post(key_event("return"))
    s.loop.run(frames=20)
    assert s.match is not match and s.match.fighting and not s.source_lost()


def test_the_result_screen_offers_no_menu_under_a_lost_seats_box(tmp_path) -> None:
    """After the last bell the result screen says "Enter: a new match"; once a seat's source is
    away its box says what comes next instead, and the menu line is not drawn under it."""
    from tools.cli import main

    rec = tmp_path / "p1.csv"
    assert main(["synth", "--session", "1", "--seed", "2", "-o", str(rec)]) == 0
    s = make_session([f"replay://{rec}", "keyboard://?seed=5&keys=right"], display=True)
    s.loop.run(frames=10)
    s.match._finish(0, "KO")  # a knockout now: the result screen
    s.view.hud.layout = []
    s.redraw()  # the overlay's picture: paused, the frame would hold the last one
    s.loop.run(frames=1)
    assert "Enter: a new match" in [text for text, _, _ in s.view.hud.layout]  # the control
    s.loop.run(frames=90)
    assert s.seats[0].source.state == SourceState.ENDED
    s.view.hud.layout = []
    s.redraw()  # the overlay's picture: paused, the frame would hold the last one
    s.loop.run(frames=1)
    said = [text for text, _, _ in s.view.hud.layout]
    assert "SOURCE ENDED" in said and "Enter: a new match" not in said, said


def test_player_twos_missing_nunchuk_is_said_on_their_source_line(tmp_path) -> None:
    """With two players the middle under the clock is the shared key line: a seat's missing part
    is said on its own source line, in amber, not in a strip."""
    from game.hud_style import SWITCH_COLOR, text_scale
    from tools.cli import main

    rec = tmp_path / "p2.csv"
    assert main(["synth", "--session", "4", "--seed", "2", "-o", str(rec)]) == 0
    s = make_session(["keyboard://?seed=4&keys=left", f"wiimote-emu://{rec}?nunchuk_out_at=1&nunchuk_in_at=3"], display=True)
    s.loop.run(steps=2 * 60)
    hud = s.view.hud
    hud.layout = []
    s.loop.run(frames=1)
    (line,) = [rect for text, rect, _ in hud.layout if text.endswith("  connected, no Nunchuk")]
    u = text_scale(hud.text.for_window(SIZE[1]))  # the dot sits 11 u left of the line, 8 u down
    dot = pygame.display.get_surface().get_at((int(line.left - 11 * u), int(line.top + 8 * u)))
    assert tuple(dot)[:3] == SWITCH_COLOR and "missing banner" not in hud.panels
    assert s.seats[0].hud.source.missing == "" and s.match.fighting


def test_a_serial_board_back_with_fewer_sensors_is_missing_the_others() -> None:
    from engine.sensors.source import Source, SourceState
    from game.hud import SourceSnapshot

    board = Source(url="serial:///dev/ttyACM0", sensors=1, state=SourceState.CONNECTED)
    assert SourceSnapshot.of(board, sensors=2).missing.startswith("1 of 2 sensors")
    assert SourceSnapshot.of(board, sensors=1).missing == "" and SourceSnapshot.of(board).missing == ""
    board.state = SourceState.RECONNECTING  # its sensors are not known again yet
    assert SourceSnapshot.of(board, sensors=2).missing == ""


def test_a_board_with_more_sensors_than_the_moves_read_is_said() -> None:
    """One-hand moves with a two-IMU board: the left hand did nothing, and nothing said why."""
    from engine.sensors.source import Source, SourceState
    from game.hud import SourceSnapshot

    board = Source(url="serial:///dev/ttyACM0", sensors=2, state=SourceState.CONNECTED)
    snap = SourceSnapshot.of(board, sensors=1)
    assert snap.missing.startswith("2 sensors, your moves read 1: the other hand does nothing")
    assert snap.line().endswith("connected, 2 sensors, your moves read 1") and snap.colour() != SourceSnapshot().colour()
    board.sensors_known = False  # a serial board before its HELLO: 2 is a guess
    assert SourceSnapshot.of(board, sensors=1).missing == ""
    board.sensors_known, board.state = True, SourceState.RECONNECTING
    assert SourceSnapshot.of(board, sensors=1).missing == ""


def test_either_players_home_button_pauses_both_once_per_press() -> None:
    s = make_session(["keyboard://?seed=4&keys=left", "keyboard://?seed=5&keys=right"], render=False)
    s.loop.run(steps=10)
    assert s.match.fighting and not s.match.paused
    s.seats[1].source.buttons = 0x0080  # player 2's Home down: pause (once, not every step it is held)
    s.loop.run(steps=10)
    assert s.match.paused
    s.seats[1].source.buttons = 0
    s.seats[0].source.buttons = 0x0080  # player 1's Home resumes
    s.loop.run(steps=10)
    assert not s.match.paused


def test_demo_renders_two_panels_side_on(tmp_path) -> None:
    from tools.cli import main

    out = tmp_path / "two.png"
    assert main(["play", "--players", "2", "--demo", "--headless", "--frames", "240", "--size", "640x360",
                 "--seed", "2", "--screenshot", str(out)]) == 0
    img = pygame.surfarray.array3d(pygame.image.load(str(out))).astype(int)
    w, h = SIZE
    # both recognition panels: dark translucent boxes at the bottom left and bottom right
    left, right = img[16:150, h - 80:h - 30], img[w - 150:w - 16, h - 80:h - 30]
    assert left.mean() < 90 and right.mean() < 90
    # both boxers' trunks (red, blue) are on screen, red left of blue: side-on, neither hidden
    red = (img[..., 0] > 150) & (img[..., 1] < 70) & (img[..., 2] < 70)
    blue = (img[..., 2] > 150) & (img[..., 0] < 80) & (img[..., 1] < 140)
    body = np.zeros_like(red)
    body[:, 70:h - 90] = True  # between the HUD's bars and panels
    xr, xb = np.nonzero(red & body)[0], np.nonzero(blue & body)[0]
    assert len(xr) > 100 and len(xb) > 100
    assert np.median(xr) < np.median(xb)


def test_profiles_keep_their_own_templates(tmp_path) -> None:
    from engine.errors import InputError
    from game.two_player import seat_templates
    from game.userdata import profile_templates_path, user_templates_path

    assert profile_templates_path(None) == user_templates_path()  # the default keeps today's file
    assert profile_templates_path("default") == user_templates_path()
    assert profile_templates_path("ana") != profile_templates_path("ben") != user_templates_path()
    with pytest.raises(InputError):
        profile_templates_path("../etc")
    path, note = seat_templates("ana", None)
    assert path is None and "ana" in note  # untrained: the default set, and it says so
    from game.session import synthesized_templates

    profile_templates_path("ana").parent.mkdir(parents=True)
    synthesized_templates(seed=4).save(profile_templates_path("ana"))
    assert seat_templates("ana", None) == (profile_templates_path("ana"), None)


def test_default_sources_are_two_wiimotes_else_the_keyboard_halves() -> None:
    from engine.errors import InputError

    urls, notes = source_urls(None, None, demo=False, seed=0, wiimotes=lambda: ["/dev/hidraw3", "/dev/hidraw5"])
    assert urls == ["wiimote:///dev/hidraw3?player=1", "wiimote:///dev/hidraw5?player=2"] and not notes
    urls, notes = source_urls(None, None, demo=False, seed=0, wiimotes=lambda: ["/dev/hidraw3"])
    assert urls[0] == "wiimote:///dev/hidraw3?player=1" and urls[1].startswith("keyboard://") and notes
    urls, _ = source_urls("serial:///dev/ttyACM0", "keyboard://", demo=False, seed=0)
    assert urls == ["serial:///dev/ttyACM0", "keyboard://?seed=1"]  # a lone keyboard player keeps it all
    with pytest.raises(InputError):
        source_urls("serial:///dev/ttyACM0", "serial:///dev/ttyACM0", demo=False, seed=0)
    with pytest.raises(InputError, match="only one Wiimote"):  # not the same remote twice
        source_urls("wiimote://", "wiimote://", demo=False, seed=0, wiimotes=lambda: ["/dev/hidraw3"])


def test_train_profile_saves_beside_the_default_set_and_play_uses_it(tmp_path, capsys) -> None:
    from game.userdata import profile_templates_path, user_templates_path
    from tools.cli import main

    assert main(["train", "--headless", "--demo", "--source", "keyboard://?seed=3", "--actions", "straight_r",
                 "--size", "640x360", "--profile", "ana"]) == 0
    assert profile_templates_path("ana").exists() and not user_templates_path().exists()
    s = make_session(["keyboard://?seed=1", "keyboard://?seed=2"], render=False)
    assert len(s.seats[0].templates) > 1  # without profiles: the default (shipped) set
    from game.two_player import seat_templates

    pygame.init()
    clock = VirtualClock()
    sources = [open_source(u, clock=clock.seconds) for u in ("keyboard://?seed=1", "keyboard://?seed=2")]
    s = TwoPlayerSession(sources, SessionConfig(size=SIZE, sound=False, render=False), clock=clock,
                         templates=(None, seat_templates("ana", None)[0]))
    # player 2 plays with ana's set: her straight_r, the default set for the moves she did not train
    assert s.seats[1].templates.meta.get("trained") == "straight_r"
    assert s.seats[0].templates.meta.get("trained") != "straight_r"
    assert len(s.seats[0].templates) > 1


def test_two_player_bad_input_is_one_line_and_exit_2(capsys) -> None:
    from tools.cli import main

    assert main(["play", "--players", "2", "--headless", "--frames", "1", "--source", "replay://x.csv",
                 "--source2", "replay://x.csv"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "same device" in err[0]
    assert main(["play", "--players", "2", "--headless", "--frames", "1", "--source", "keyboard://",
                 "--source2", "keyboard://", "--profile", "../../etc"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--profile" in err[0]
    assert main(["play", "--players", "2", "--headless", "--frames", "1", "--source", "keyboard://?keys=middle",
                 "--source2", "keyboard://"]) == 2
    assert "keys must be one of" in capsys.readouterr().err


def test_a_one_hand_source_for_two_hand_moves_says_how_to_train_for_it(tmp_path, capsys) -> None:
    from tools.cli import main

    one = tmp_path / "one.csv"
    one.write_text("t,rx,ry,rz\n" + "".join(f"{i / 60:.5f},0,0,1\n" for i in range(60)))
    assert main(["play", "--players", "2", "--headless", "--frames", "1", "--source", "keyboard://",
                 "--source2", f"replay://{one}"]) == 2
    (err,) = capsys.readouterr().err.strip().splitlines()
    assert "the source has 1 sensor(s), player 2's templates need 2" in err
    assert err.endswith(f"quickjab train --source replay://{one} --profile NAME, then --profile2 NAME")


def test_the_side_on_camera_keeps_player_one_on_the_left_from_every_side() -> None:
    from game.camera import SIDE_ON_HEADINGS, side_on_camera, side_on_heading

    for deg in range(0, 360, 15):
        phi = math.radians(deg)
        d = np.array([math.sin(phi), math.cos(phi)])
        p1, p2 = -0.6 * d, 0.6 * d
        k = side_on_heading(p1, p2)
        assert 0 <= k < SIDE_ON_HEADINGS
        cam = side_on_camera((1280, 720), k)
        xy, _ = cam.project(np.array([[p1[0], 1.0, p1[1]], [p2[0], 1.0, p2[1]]]))
        assert xy[0, 0] < xy[1, 0] - 150  # side by side, player 1 on the left
    # hysteresis: a line 30 degrees round from view 0 keeps it; 35 degrees cuts to view 1
    line = lambda deg: (np.zeros(2), np.array([math.sin(math.radians(deg)), math.cos(math.radians(deg))]))  # noqa: E731
    assert side_on_heading(*line(30), current=0) == 0
    assert side_on_heading(*line(35), current=0) == 1
    assert side_on_heading(*line(30)) == 1  # without a current view: the nearest


def test_player_two_profile_errors_and_notes_name_profile2(capsys) -> None:
    from tools.cli import main

    assert main(["play", "--players", "2", "--headless", "--frames", "1", "--source", "keyboard://",
                 "--source2", "keyboard://", "--profile2", "../x"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--profile2 '../x'" in err[0]
    assert main(["play", "--players", "2", "--headless", "--frames", "1", "--size", "320x180", "--source", "keyboard://",
                 "--source2", "keyboard://", "--profile2", "nobody"]) == 0
    note = [line for line in capsys.readouterr().err.splitlines() if "nobody" in line]
    assert len(note) == 1 and "player 2" in note[0]


def test_a_source_that_does_not_open_says_which_player(capsys, tmp_path) -> None:
    from tools.cli import main

    missing = tmp_path / "missing.csv"
    for option, url in (("--source2", f"replay://{missing}"), ("--source2", "bogus://x"), ("--source", f"wiimote-emu://{missing}")):
        other = "--source" if option == "--source2" else "--source2"
        assert main(["play", "--players", "2", "--headless", "--frames", "1", other, "keyboard://", option, url]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        player = 2 if option == "--source2" else 1
        assert len(err) == 1 and f"player {player} ({option})" in err[0], err


def test_the_same_device_spelled_two_ways_is_refused(tmp_path) -> None:
    from engine.errors import InputError

    port = tmp_path / "ttyACM0"
    port.touch()
    (tmp_path / "link").symlink_to(port)
    for a, b in ((f"serial://{port}", f"serial://{port}?baud=230400"),  # another speed, the same port
                 (f"serial://{tmp_path / 'link'}", f"serial://{port}"),  # a link to it (bridge emulate --link)
                 ("wiimote:///dev/hidraw3", "wiimote:///dev/hidraw3?player=2")):
        with pytest.raises(InputError, match="same device"):
            source_urls(a, b, demo=False, seed=0)
    other = tmp_path / "ttyACM1"
    urls, _ = source_urls(f"serial://{port}", f"serial://{other}", demo=False, seed=0)
    assert urls == [f"serial://{port}", f"serial://{other}"]


def test_source_wiimote_without_source2_and_no_wiimote_is_no_traceback() -> None:
    # `play --players 2 --source wiimote://` with no remote paired: an AttributeError on the
    # missing --source2 before; now player 2 takes the keyboard and opening wiimote:// says why
    urls, notes = source_urls("wiimote://", None, demo=False, seed=0, wiimotes=lambda: [])
    assert urls[0] == "wiimote://" and urls[1].startswith("keyboard://") and "player 2" in notes[0]
    urls, _ = source_urls(None, "wiimote://", demo=False, seed=0, wiimotes=lambda: [])
    assert urls[0].startswith("keyboard://") and urls[1] == "wiimote://"
