"""The session end to end under the dummy video driver: a scripted headless match is
reproducible to the bit, keys posted to pygame make the player's boxer act through the real
recognizer, and a source that disconnects shows an overlay that clears on reconnect."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pygame
import pytest

from engine.clock import VirtualClock
from engine.sensors import SourceState, open_source
from game.session import Session, SessionConfig

sys.path.insert(0, str(Path(__file__).parent))
from game_graph import graph_path  # noqa: E402,F401 - the fixture

SIZE = (640, 360)


@pytest.fixture(autouse=True)
def own_data_dir(tmp_path, monkeypatch):
    """Never read (or write) the real user's trained templates."""
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "xdg"))


@pytest.fixture(autouse=True)
def _graph(graph_path):  # noqa: F811 - the imported fixture
    global GRAPH
    GRAPH = graph_path


GRAPH = ""


def make_session(url: str, seed: int = 0, render: bool = True, display: bool = False, demo: bool = False) -> Session:
    import game.keyboard_source  # noqa: F401 - registers keyboard://

    pygame.init()
    clock = VirtualClock()
    source = open_source(url, clock=clock.seconds)
    provider = None
    if display:
        pygame.display.set_mode(SIZE)
        provider = pygame.display.get_surface
    cfg = SessionConfig(seed=seed, size=SIZE, sound=False, render=render, graph=GRAPH, demo=demo)
    return Session(source, cfg, clock=clock, surface_provider=provider)


def test_scripted_match_is_reproducible() -> None:
    hashes, summaries = [], []
    for _ in range(2):
        # the attract mode's pilot: the graph picks the player's moves, the virtual player
        # performs them, the recognizer recognizes them; the CPU plays from the graph
        s = make_session("keyboard://?seed=5", seed=5, render=False, demo=True)
        s.loop.run(steps=3600)
        assert s.loop.step_index == 3600
        hashes.append(s.state_hash())
        summaries.append((len(s.events_log), len(s.blows_log), s.match.state()))
    assert hashes[0] == hashes[1]
    assert summaries[0] == summaries[1]
    # it was a match, not an idle ring: the recognizer started many actions, punches landed
    # and the round ran out
    starts = [e["action"] for e in s.events_log if e["event"] == "start"]
    assert len(starts) > 30 and len(set(starts)) >= 3
    assert {b[1] for b in s.blows_log} == {0, 1}  # both boxers landed blows
    assert min(s.match.health) < 100
    assert s.match.round > 1 or s.match.over or s.match.clock_steps < 30 * 60  # the clock ran


def test_the_state_hash_does_not_depend_on_how_run_is_split() -> None:
    """Low power renders every second step: `run(steps=7)` calls ended frames half way, and
    the held step then ran a frame later, when the keyboard source had more samples (the state
    hash changed with the split). Every step now sees the clock the whole run would."""
    import game.keyboard_source  # noqa: F401 - registers keyboard://

    hashes = []
    for chunks in ([600], [7] * 85 + [5]):
        pygame.init()
        clock = VirtualClock()
        source = open_source("keyboard://?seed=5", clock=clock.seconds)
        cfg = SessionConfig(seed=5, size=SIZE, sound=False, render=True, graph=GRAPH, demo=True, low_power=True)
        s = Session(source, cfg, clock=clock)
        for n in chunks:
            s.loop.run(steps=n)
        assert s.loop.step_index == 600
        hashes.append(s.state_hash())
    assert hashes[0] == hashes[1]


_KERNEL_RUN = """
import json
from engine import native
from tools.scripted_match import build_session
s = build_session(seed=0, render=False)
s.loop.run(steps=900)
print(json.dumps({"hash": s.state_hash(), "dtw": s.recognizer.dtw.method, "kernels": native.status()}))
"""


def _no_c_compiler() -> bool:
    from engine import native

    return native.compiler() is None


@pytest.mark.skipif(sys.platform == "win32", reason="the C kernels are POSIX only")
@pytest.mark.skipif(_no_c_compiler(), reason="no C compiler (cc, gcc, clang or $CC): both runs would be numpy's, "
                                              "compared with itself")
def test_the_scripted_match_does_not_depend_on_the_c_kernels(tmp_path) -> None:
    """A process runs the C kernels when they built, numpy when they did not (no compiler, a
    failed build, QUICKJAB_NO_NATIVE=1): the match is the same to the bit either way. The DTW's
    numpy fallback was the scan, whose scores differed in the last bits; it is the kernel's
    own operations now (engine/recognition/dtw_loop.py)."""
    import json
    import os
    import subprocess

    from engine import native

    root = Path(__file__).resolve().parents[2]
    runs = []
    for extra in ({}, {native.NO_NATIVE_ENV: "1"}):
        env = {k: v for k, v in os.environ.items() if k not in (native.NO_NATIVE_ENV, native.NO_JIT_ENV)}
        env.update({native.CACHE_ENV: str(tmp_path / "cache"), "PYTHONPATH": str(root), **extra})
        out = subprocess.run([sys.executable, "-c", _KERNEL_RUN], cwd=root, env=env, capture_output=True,
                             text=True, timeout=300)
        assert out.returncode == 0, out.stderr
        runs.append(json.loads(out.stdout.strip().splitlines()[-1]))
    assert runs[1]["dtw"] == "loop" and all(v.startswith("numpy") for v in runs[1]["kernels"].values())
    assert runs[0]["dtw"] == "native", runs[0]["kernels"]  # a compiler is there: the kernels built
    assert runs[0]["hash"] == runs[1]["hash"]


def test_a_different_seed_plays_differently() -> None:
    a = make_session("keyboard://?seed=1", seed=1, render=False, demo=True)
    b = make_session("keyboard://?seed=2", seed=2, render=False, demo=True)
    a.loop.run(steps=300)
    b.loop.run(steps=300)
    assert a.state_hash() != b.state_hash()


def test_key_press_makes_the_boxer_act_through_the_recognizer() -> None:
    s = make_session("keyboard://?seed=3", display=True)
    s.loop.run(steps=30)  # the recognizer learns the resting gravity
    assert s.player.controller.action == "guard"
    seen = []
    original = s.player.controller.on_event

    def spy(ev):
        seen.append(ev)
        original(ev)

    s.player.controller.on_event = spy
    pygame.event.post(pygame.event.Event(pygame.KEYDOWN, key=pygame.K_p, mod=0, unicode="p", scancode=0))
    actions = []
    for _ in range(60):
        s.loop.run(steps=1)
        actions.append(s.player.controller.action)
    assert s.source.pressed == ["straight_r"]  # the key reached the keyboard source ...
    starts = [e for e in seen if e["event"] == "start"]
    assert starts and starts[0]["action"] == "straight_r"  # ... the recognizer decided it ...
    assert "straight_r" in actions  # ... and the boxer played it
    assert actions.index("straight_r") > 0  # not instantly: after the main buffer filled


def test_disconnect_shows_overlay_and_reconnect_clears_it() -> None:
    s = make_session("keyboard://?seed=4", display=True)
    surf = pygame.display.get_surface()
    probe = (SIZE[0] // 2, int(SIZE[1] * 0.93))
    s.loop.run(frames=5)
    bright = sum(surf.get_at(probe)[:3])
    clock_before = s.match.clock_steps
    s.source.disconnect()
    s.loop.run(frames=5)
    assert s.hud_state.disconnected and s.source.state == SourceState.DISCONNECTED
    assert sum(surf.get_at(probe)[:3]) < 0.5 * bright
    assert s.match.paused and s.match.clock_steps == clock_before  # the clock waits
    s.source.reconnect()
    s.loop.run(frames=5)
    assert not s.hud_state.disconnected and not s.match.paused
    assert sum(surf.get_at(probe)[:3]) == pytest.approx(bright, abs=30)
    assert s.match.clock_steps < clock_before


def escape() -> pygame.event.Event:
    return pygame.event.Event(pygame.KEYDOWN, key=pygame.K_ESCAPE, mod=0, unicode="", scancode=0)


def test_escape_while_the_controller_is_lost_keeps_the_match_paused() -> None:
    """Esc toggled the pause under the lost-controller overlay: the round clock ran and the CPU
    boxed on while the overlay still said the match waits for the controller."""
    s = make_session("keyboard://?seed=4", display=True)
    surf = pygame.display.get_surface()
    probe = (SIZE[0] // 2, int(SIZE[1] * 0.93))
    s.loop.run(frames=5)
    bright = sum(surf.get_at(probe)[:3])
    s.source.disconnect()
    s.loop.run(frames=5)
    clock_before = s.match.clock_steps
    for _ in range(2):  # once, and again: neither resumes it
        pygame.event.post(escape())
        s.loop.run(frames=30)
        assert s.match.paused and s.match.clock_steps == clock_before
        assert s.hud_state.disconnected and sum(surf.get_at(probe)[:3]) < 0.5 * bright  # the overlay stays
    s.source.reconnect()
    s.loop.run(frames=5)
    assert not s.hud_state.disconnected and not s.match.paused  # back: it resumes by itself
    assert s.match.clock_steps < clock_before


def test_a_replay_that_plays_out_pauses_the_match_and_says_so(tmp_path, capsys) -> None:
    """A replay's source ends: the match went on as if the player stood still, the round clock
    running and the CPU boxing; now it pauses for good under an overlay that says the source ended."""
    from tools.cli import main

    rec = tmp_path / "short.csv"
    assert main(["synth", "--session", "1", "--seed", "2", "-o", str(rec)]) == 0
    s = make_session(f"replay://{rec}", display=True)
    surf = pygame.display.get_surface()
    probe = (SIZE[0] // 2, int(SIZE[1] * 0.93))
    s.loop.run(frames=30)
    assert s.source.state == SourceState.CONNECTED and s.match.fighting
    bright = sum(surf.get_at(probe)[:3])
    s.view.hud.layout = []
    s.loop.run(frames=60)  # 1.5 s: played out
    assert s.source.state == SourceState.ENDED
    assert s.match.paused and s.hud_state.disconnected
    clock = s.match.clock_steps
    pygame.event.post(escape())  # nothing to resume with
    s.loop.run(frames=60)
    assert s.match.paused and s.match.clock_steps == clock
    assert sum(surf.get_at(probe)[:3]) < 0.5 * bright  # the overlay
    said = {text for text, _, panel in s.view.hud.layout if panel == "lost"}
    assert "SOURCE ENDED" in said and any(t.startswith("replay://") and t.endswith(": ended") for t in said), said
    assert capsys.readouterr().err.count("the source ended (Enter in the window plays it again)") == 1  # once


def key(code: int) -> pygame.event.Event:
    return pygame.event.Event(pygame.KEYDOWN, key=code, mod=0, unicode="", scancode=0)


def played_out_replay(tmp_path) -> Session:
    """A one-player session on a 1 s replay, run until it has played out (SOURCE ENDED)."""
    from tools.cli import main

    rec = tmp_path / "short.csv"
    assert main(["synth", "--session", "1", "--seed", "2", "-o", str(rec)]) == 0
    s = make_session(f"replay://{rec}", display=True)
    s.loop.run(frames=90)
    assert s.source.state == SourceState.ENDED and s.match.paused and s.source_lost()
    return s


def test_enter_under_source_ended_plays_the_replay_again_in_a_new_match(tmp_path, capsys) -> None:
    """A replay that played out paused the match for good: playing it again meant restarting
    the program. Enter, offered on the SOURCE ENDED overlay, rewinds it and starts a new match."""
    s = played_out_replay(tmp_path)
    surf = pygame.display.get_surface()
    probe = (SIZE[0] // 2, int(SIZE[1] * 0.93))
    dark = sum(surf.get_at(probe)[:3])  # under the overlay
    s.view.hud.layout = []
    s.redraw()  # the overlay's picture: paused, the frame would hold the last one
    s.loop.run(frames=1)
    said = [text for text, _, panel in s.view.hud.layout if panel == "lost"]
    assert "SOURCE ENDED" in said and any(t.startswith("Enter: play it again") for t in said), said
    resets = []
    reset = s.recognizer.reset
    s.recognizer.reset = lambda: (resets.append(s.loop.step_index), reset())[-1]
    s.match.health[0] = 40.0  # this match's state: the new match's is fresh
    pygame.event.post(key(pygame.K_RETURN))
    s.loop.run(frames=20)
    assert s.source.state == SourceState.CONNECTED and not s.source_lost()
    assert s.match.fighting and s.match.round == 1 and s.match.health == [100.0, 100.0]
    assert resets  # the recognizer learns the (rewound) recording's gravity afresh
    assert sum(surf.get_at(probe)[:3]) > 2 * dark + 30  # the overlay is gone
    s.loop.run(frames=70)  # played out again: paused again, and the console says so again
    assert s.source.state == SourceState.ENDED and s.match.paused
    assert capsys.readouterr().err.count("the source ended") == 2


def test_d_does_nothing_under_the_lost_source_overlays(tmp_path) -> None:
    """D (the pause menu's next difficulty) changed the CPU's difficulty under the lost-controller
    and SOURCE ENDED overlays, where no pause menu shows it; the pause menu's D still works."""
    s = make_session("keyboard://?seed=4", display=True)
    start = s.difficulty.name
    s.loop.run(frames=5)
    s.source.disconnect()
    for phase in ("fight", "over"):  # paused under the overlay, and after the last bell
        s.match.phase = phase
        s.view.hud.layout = []
        pygame.event.post(key(pygame.K_d))
        s.loop.run(frames=3)
        assert s.source_lost() and s.difficulty.name == start and s.hud_state.difficulty == start
        assert not any(text.startswith("D: ") for text, _, _ in s.view.hud.layout)  # nothing offers it
    ended = played_out_replay(tmp_path)
    pygame.event.post(key(pygame.K_d))
    ended.loop.run(frames=3)
    assert ended.difficulty.name == start
    # the controller back and the match paused by Esc: the menu offers D, and D acts
    s.match.phase = "fight"
    s.source.reconnect()
    s.loop.run(frames=3)
    pygame.event.post(escape())
    s.loop.run(frames=3)
    s.view.hud.layout = []
    pygame.event.post(key(pygame.K_d))
    s.loop.run(frames=3)
    assert s.match.paused and s.difficulty.name != start
    assert f"D: difficulty {s.difficulty.label}" in [text for text, _, _ in s.view.hud.layout]

def test_rumble_on_the_player_when_hit() -> None:
    s = make_session("keyboard://?seed=6", render=False)
    calls = []
    s.source.rumble = calls.append
    hit = {"attacker": 1, "target": "head", "hand": "r", "speed": 5.0, "direction": np.array([0, 0, -1.0]),
           "blocked": False, "damage": 9.0}
    s.apply_hit(0, hit)
    assert calls and s.match.health[0] < 100
    assert s.player.controller.action.startswith("hit_head")  # the reaction plays
    s.apply_hit(1, {**hit, "attacker": 0})
    assert len(calls) == 1  # the CPU being hit does not rumble the player's controller


def test_escape_pauses_and_f3_shows_the_budget_overlay() -> None:
    s = make_session("keyboard://?seed=8", display=True)
    surf = pygame.display.get_surface()
    s.loop.run(frames=3)
    before = pygame.surfarray.array3d(surf).copy()
    pygame.event.post(pygame.event.Event(pygame.KEYDOWN, key=pygame.K_F3, mod=0, unicode="", scancode=0))
    s.loop.run(frames=2)
    assert s.hud_state.show_budget
    panel = pygame.Rect(SIZE[0] - 215, 70, 200, 120)  # the overlay's corner of the screen
    after = pygame.surfarray.array3d(surf)
    region = (slice(panel.left, panel.right), slice(panel.top, panel.bottom))
    assert np.abs(after[region].astype(int) - before[region].astype(int)).mean() > 10
    pygame.event.post(pygame.event.Event(pygame.KEYDOWN, key=pygame.K_ESCAPE, mod=0, unicode="", scancode=0))
    s.loop.run(frames=2)
    assert s.match.paused
    clock = s.match.clock_steps
    s.loop.run(frames=30)
    assert s.match.clock_steps == clock
    pygame.event.post(pygame.event.Event(pygame.KEYDOWN, key=pygame.K_ESCAPE, mod=0, unicode="", scancode=0))
    s.loop.run(frames=30)
    assert not s.match.paused and s.match.clock_steps < clock


def test_a_replayed_recording_drives_the_player_through_the_wiimote_emulator(tmp_path) -> None:
    from collections import Counter

    from engine.recording import read_recording
    from tools.cli import main

    rec = tmp_path / "session.csv"
    assert main(["synth", "--session", "8", "--seed", "2", "-o", str(rec)]) == 0
    labels = [x for x in dict.fromkeys(read_recording(rec).labels) if x]
    s = make_session(f"wiimote-emu://{rec}", render=False)
    s.loop.run(steps=8 * 60 + 60)
    starts = [e["action"] for e in s.events_log if e["event"] == "start"]
    assert s.hud_state.source.battery is not None  # the emulated remote reports its battery
    assert s.hud_state.source.state == "connected"
    # most of the performed actions were recognized, in order
    hits = Counter(starts) & Counter(labels)
    assert sum(hits.values()) >= 0.6 * len(labels)


def test_a_nunchuk_that_slips_out_is_shown_until_it_is_back(tmp_path) -> None:
    """The remote streams on without its Nunchuk (the left hand reads a still 1 g) and the match
    goes on: an amber strip under the clock and the source line say what is missing."""
    from game.hud_style import SWITCH_COLOR
    from tools.cli import main

    rec = tmp_path / "session.csv"
    assert main(["synth", "--session", "4", "--seed", "2", "-o", str(rec)]) == 0
    s = make_session(f"wiimote-emu://{rec}?nunchuk_out_at=1.5&nunchuk_in_at=3", display=True)
    surf, hud = pygame.display.get_surface(), s.view.hud

    def frame() -> tuple[set[str], pygame.Rect | None]:
        hud.layout = []
        s.loop.run(frames=1)
        return {text for text, _, _ in hud.layout}, hud.panels.get("missing banner")

    s.loop.run(steps=60)
    said, banner = frame()
    assert banner is None and not any("Nunchuk" in t for t in said)
    s.loop.run(steps=60)  # 2 s: out
    said, banner = frame()
    assert "No Nunchuk: plug it in for left-hand moves" in said, said
    assert any(t.endswith("  connected, no Nunchuk") for t in said), said  # the source line
    assert tuple(surf.get_at((banner.left + 4, banner.centery)))[:3] == SWITCH_COLOR
    assert s.match.fighting  # it does not pause the match: the right hand boxes on
    s.loop.run(steps=90)  # 3.5 s: back
    said, banner = frame()
    assert banner is None and not any("Nunchuk" in t for t in said)


def test_rounds_start_from_the_corners_and_the_attract_mode_starts_over() -> None:
    from game.match import Match

    s = make_session("keyboard://?seed=9", render=False, demo=True)
    s.match = Match(round_seconds=2)
    s.loop.run(steps=2 * 60 + 3 * 60 + 5)  # round 1, the break, the bell of round 2
    assert s.match.round == 2
    assert s.player.root[:2] == pytest.approx((0.0, -0.55), abs=0.05)
    assert s.opponent.root[:2] == pytest.approx((0.0, 0.55), abs=0.05)
    s.loop.run(steps=2 * 60 * 2 + 3 * 60 + 60)
    assert s.match.over
    s.loop.run(steps=8 * 60 + 2)
    assert not s.match.over and s.match.round == 1 and s.match.health == [100.0, 100.0]


class HeldRemote:
    """A test double of a Wiimote: rest readings at 60 Hz, buttons, battery, rumble calls."""

    def __init__(self, clock):
        from engine.sensors import Source

        class _Remote(Source):
            def poll(inner):
                now = clock.seconds()
                out = []
                while inner.next_t <= now:
                    out.append(Sample(inner.next_t, np.array([[0.0, 1.0, 0.0], [0.0, 1.0, 0.0]])))
                    inner.next_t += 1 / 60
                return out

            def rumble(inner, ms):
                inner.rumbles.append(ms)

        from engine.sensors import Sample

        self.source = _Remote(url="wiimote-test://", sensors=2, state=SourceState.CONNECTED, battery=0.55)
        self.source.next_t = 0.0
        self.source.buttons = 0
        self.source.rumbles = []


def test_home_button_pauses_and_the_battery_shows() -> None:
    pygame.init()
    clock = VirtualClock()
    remote = HeldRemote(clock).source
    s = Session(remote, SessionConfig(size=SIZE, sound=False, render=False, graph=GRAPH), clock=clock)
    s.loop.run(steps=10)
    assert s.hud_state.source.battery == 0.55 and s.hud_state.source.url == "wiimote-test://"
    remote.buttons = 0x0080  # Home down: pause (once, not every step it is held)
    s.loop.run(steps=10)
    assert s.match.paused
    remote.buttons = 0
    s.loop.run(steps=2)
    remote.buttons = 0x0080
    s.loop.run(steps=2)
    assert not s.match.paused


def test_home_while_the_controller_is_lost_keeps_the_match_paused() -> None:
    """Home toggles the pause as Esc does; under the lost-controller overlay it must not resume the
    match either (both go through Session.toggle_pause)."""
    pygame.init()
    clock = VirtualClock()
    remote = HeldRemote(clock).source
    s = Session(remote, SessionConfig(size=SIZE, sound=False, render=False, graph=GRAPH), clock=clock)
    s.loop.run(steps=10)
    remote.state = SourceState.RECONNECTING
    s.loop.run(steps=5)
    assert s.match.paused and s.hud_state.disconnected
    clock_before = s.match.clock_steps
    remote.buttons = 0x0080  # Home down (a press), while the controller is away
    s.loop.run(steps=5)
    remote.buttons = 0
    s.loop.run(steps=30)
    assert s.match.paused and s.match.clock_steps == clock_before
    remote.state = SourceState.CONNECTED
    s.loop.run(steps=5)
    assert not s.match.paused  # back: it resumes by itself


def test_a_profiles_trained_set_is_said_as_the_players_own_with_its_moves(tmp_path):
    """`play --profile ana` said "templates ana.npz": not that the set is ana's own, nor how
    many moves were trained (docs/game.md: "yours, with how many moves you trained")."""
    from game.session import synthesized_templates, templates_in_use
    from game.userdata import profile_templates_path

    path = profile_templates_path("ana")
    path.parent.mkdir(parents=True)
    t = synthesized_templates(trials=1)
    t.meta.update({"source": "quickjab train", "trained": "hook_l,hook_r"})
    t.save(path)
    said = templates_in_use(path)
    assert said.startswith("your templates (ana: 2 of 13 moves") and "--profile ana" in said, said
    other = tmp_path / "built.npz"
    synthesized_templates(trials=1).save(other)  # `--templates FILE` of another origin: its name
    assert templates_in_use(other) == "templates built.npz"


def test_a_new_match_mid_round_does_not_count_the_cpus_lead_as_the_players_blows() -> None:
    """Enter under SOURCE ENDED starts a new match mid-round: the fresh match's lead (0) after
    the CPU's lead in the abandoned round read to the player's form as blows the player landed
    (PlayerForm.observe: a fall of the lead), so the CPU pressed a player who had landed nothing."""
    s = make_session("keyboard://?seed=4", render=False)
    s.match.round_damage[1] = 30.0  # the CPU leads the round by 30; the player landed nothing
    s.loop.run(steps=2)
    assert s.difficulty.form.landed == 0.0
    s.new_match()
    s.loop.run(steps=2)
    assert s.difficulty.form.landed == 0.0


def test_a_paused_match_redraws_its_picture_ten_times_a_second_and_after_a_key() -> None:
    """A paused match drew every frame (half a core at 1280x720 under a software display, as much
    as the match); its picture is held now: drawn on the pause's first frame, PAUSED_REDRAW_HZ
    times a second after it, and on the frame after any event; every frame while boxing, and
    while the F3 overlay is up (its figures are of the frames drawn)."""
    from game.ring import PAUSED_REDRAW_HZ

    s = make_session("keyboard://?seed=4", display=True)
    every = round(s.loop.render_hz / PAUSED_REDRAW_HZ)
    assert every == 6
    drawn = []
    draw = s.view.draw
    s.view.draw = lambda *a: (drawn.append(s.loop.frame_index), draw(*a))[-1]
    s.loop.run(frames=10)
    assert len(drawn) == 10  # boxing: every frame
    pygame.event.post(key(pygame.K_ESCAPE))
    drawn.clear()
    start = s.loop.frame_index
    s.loop.run(frames=32)
    assert s.match.paused
    assert drawn == [start + k for k in range(0, 32, every)], drawn  # the first at once
    drawn.clear()
    # the paused frames 33 and 34 are not due (31, 37 are): the key's frame is drawn all the same
    level = s.difficulty.name
    pygame.event.post(key(pygame.K_d))  # the pause menu's next difficulty: shown at once
    s.loop.run(frames=2)
    assert drawn == [s.loop.frame_index - 2] and s.difficulty.name != level
    pygame.event.post(key(pygame.K_F3))
    drawn.clear()
    s.loop.run(frames=4)
    assert s.hud_state.show_budget and len(drawn) == 4  # the overlay's figures: every frame
    pygame.event.post(key(pygame.K_F3))
    pygame.event.post(key(pygame.K_ESCAPE))
    drawn.clear()
    s.loop.run(frames=5)
    assert not s.match.paused and len(drawn) == 5
