"""`quickjab play` and `quickjab train` as a user runs them (headless)."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pygame
import pytest

import engine.sensors.source as source_mod
from engine.sensors import SourceError
from game.hud import SWITCH_COLOR
from tools.cli import main

sys.path.insert(0, str(Path(__file__).parent))
from game_graph import graph_path, other_library_graph  # noqa: E402,F401 - the fixture


def no_wiimote(url, clock):
    raise SourceError("no Wiimote found")


def test_play_without_a_wiimote_falls_back_to_the_keyboard_with_a_banner(tmp_path, monkeypatch, graph_path, capsys):  # noqa: F811
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "xdg"))
    monkeypatch.setitem(source_mod._factories, "wiimote", no_wiimote)
    shot, trace = tmp_path / "play.png", tmp_path / "trace.json"
    assert main(["play", "--headless", "--frames", "30", "--graph", graph_path, "--no-sound",
                 "--screenshot", str(shot), "--trace", str(trace)]) == 0
    # one console line says why and what now (two said it: the source's reason, then the game's)
    said = [line for line in capsys.readouterr().err.splitlines() if "keyboard" in line]
    assert said == ["quickjab play: no Wiimote found: playing from the keyboard"], said
    img = pygame.surfarray.array3d(pygame.image.load(str(shot))).astype(int)  # (w, h, 3)
    assert img.shape[:2] == (1280, 720)
    top_centre = img[400:880, 100:160]
    assert (np.abs(top_centre - np.array(SWITCH_COLOR)).max(axis=2) <= 10).sum() > 500  # the banner
    events = json.loads(trace.read_text())["traceEvents"]
    names = {e["name"] for e in events if e["ph"] == "X"}
    assert {"frame", "render", "input", "frames", "recognize", "player", "opponent", "physics", "hits", "match"} <= names
    assert sum(1 for e in events if e.get("name") == "frame") == 30


def test_bad_input_is_one_line_and_exit_2(tmp_path, capsys) -> None:
    assert main(["play", "--headless", "--size", "big"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--size" in err[0]
    assert main(["play", "--headless", "--source", "nosuch://x", "--frames", "1"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "nosuch" in err[0]
    assert main(["play", "--headless", "--graph", str(tmp_path / "missing.npz"), "--frames", "1", "--source", "keyboard://"]) == 2
    assert "missing.npz" in capsys.readouterr().err


def test_a_graph_from_another_action_library_is_one_line_before_the_match(tmp_path, capsys, graph_path) -> None:  # noqa: F811
    """`graph duel` refused it; `play` took it and its first look-up of the action the library
    lacks was a KeyError traceback in the middle of the match."""
    from game.interaction import GraphFileError
    from game.session import load_graph

    other = other_library_graph(graph_path, tmp_path / "other.npz")
    assert main(["play", "--headless", "--frames", "300", "--graph", other, "--source", "keyboard://", "--no-sound"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and other in err[0] and "different action library" in err[0], err
    with pytest.raises(GraphFileError, match="different action library"):
        load_graph(other)
    # graph duel says the same of it, from the same check
    assert main(["graph", "duel", "--graph", other, "--bouts", "1", "--seconds", "1"]) == 2
    said = capsys.readouterr().err.strip().splitlines()
    assert [line.split(": ", 1)[1] for line in said] == [line.split(": ", 1)[1] for line in err], said


def test_a_screenshot_or_trace_under_a_file_is_refused_before_the_match(tmp_path, capsys) -> None:
    # were a pygame.error traceback, an exit 2 after the match; a missing folder is made now,
    # as for every output, but not under a file
    (tmp_path / "no").write_text("x")
    for option in ("--screenshot", "--trace"):
        with pytest.raises(SystemExit) as exit_:
            main(["play", "--headless", "--frames", "5", "--source", "keyboard://", option, str(tmp_path / "no" / "d" / "s.png")])
        err = capsys.readouterr().err.strip().splitlines()
        assert exit_.value.code == 2 and len(err) == 1 and "is not a directory" in err[0], err


@pytest.mark.parametrize("where, says", [
    ("folder", "a directory"), ("corrupt.npz", "not a template file"), ("file.txt/t.npz", "not a directory"),
])
def test_a_templates_file_train_cannot_write_is_refused_before_the_session(tmp_path, monkeypatch, capsys, where, says) -> None:
    """A bad -o (or a bad own templates file) was found only when the trials were done, after
    minutes of a player's moves: all lost. --frames 2 ends the session long before that: the
    run used to exit 0 with "nothing saved"."""
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "xdg"))
    (tmp_path / "folder").mkdir()
    (tmp_path / "corrupt.npz").write_bytes(b"not a zip")
    (tmp_path / "file.txt").write_text("x")
    target = tmp_path / where
    assert main(["train", "--headless", "--demo", "--actions", "straight_r", "--frames", "2", "-o", str(target)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1].startswith(f"quickjab train: {target}") and says in err[-1], err


@pytest.mark.parametrize("argv", [
    ["play", "--headless", "--frames", "2", "--source", "keyboard://", "--screenshot", "/dev/full"],
    ["play", "--headless", "--frames", "2", "--source", "keyboard://", "--trace", "/dev/full"],
    ["train", "--headless", "--demo", "--frames", "2", "--screenshot", "/dev/full"],
])
def test_a_screenshot_or_trace_that_cannot_be_written_names_its_file(tmp_path, monkeypatch, capsys, argv) -> None:
    """/dev/full passes the folder check but takes nothing: pygame.error (a traceback) for the
    screenshot, "[Errno 28] No space left on device" naming no file for the trace, as a full
    disk would give."""
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "xdg"))
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1].startswith(f"quickjab {argv[0]}: /dev/full: cannot"), err


def test_training_saves_templates_that_play_then_uses(tmp_path, monkeypatch) -> None:
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "xdg"))
    assert main(["train", "--headless", "--demo", "--source", "keyboard://?seed=3",
                 "--actions", "straight_r,hook_l", "--size", "640x360"]) == 0
    saved = tmp_path / "xdg" / "quickjab" / "templates.npz"
    assert saved.exists()
    from game.session import load_templates

    templates = load_templates()
    # the two trained moves replace the defaults' two; the other 11 are kept (issue 17: training
    # one move used to leave a file of that move only, and every other move was rejected)
    from game.actions import ACTION_NAMES

    assert sorted(templates.action_names) == sorted(ACTION_NAMES)
    assert templates.meta.get("source") == "quickjab train"
    assert templates.meta.get("trained") == "hook_l,straight_r"
    # and the recognizer built on them recognizes the virtual player's hook_l
    from engine.recognition import DualBufferRecognizer
    from game.actions import load_library
    from game.virtual_player import synthesize_action

    rec = DualBufferRecognizer(templates)
    sig = synthesize_action(load_library()["hook_l"], "experienced", np.random.default_rng(9), rest_before=40, rest_after=30)
    events = [e for f in sig.reshape(len(sig), -1) for e in rec.push(f)]
    assert [e["action"] for e in events if e["event"] == "start"][:1] == ["hook_l"]


def test_train_demo_is_the_virtual_player_and_never_opens_a_wiimote(tmp_path, monkeypatch, capsys) -> None:
    # `train --demo`: the virtual player performs every move. It used to open wiimote:// first
    # (the keyboard only when no Wiimote answered), so with a Wiimote connected the demo trained
    # from the Wiimote, and without one it paid the probe (driver, HID enumeration) at start-up.
    from engine.sensors.demo import DemoSource

    opened = []

    def connected_wiimote(url, clock):
        opened.append(url)
        return DemoSource(url=url, clock=clock)  # a connected remote no virtual player drives

    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "xdg"))
    monkeypatch.setitem(source_mod._factories, "wiimote", connected_wiimote)
    assert main(["train", "--headless", "--demo", "--actions", "straight_r", "--size", "320x180"]) == 0
    assert opened == []
    assert "demo: the virtual player performs every move" in capsys.readouterr().err
    from engine.recognition import Templates

    saved = Templates.load(tmp_path / "xdg" / "quickjab" / "templates.npz")
    assert saved.meta.get("trained") == "straight_r"
    # the player's own device, named with --source, is still what a demo trains from
    assert main(["train", "--headless", "--demo", "--source", "wiimote://", "--actions", "straight_r",
                 "--size", "320x180", "--frames", "2", "-o", str(tmp_path / "w.npz")]) == 0
    # (opened on --headless's virtual clock, then again on the real one: a Wiimote is a live device)
    assert opened == ["wiimote://", "wiimote://"]
    assert "wiimote:// is a live device: --headless runs on the real clock" in capsys.readouterr().err


def test_headless_play_runs_a_live_device_found_by_default_on_the_real_clock(tmp_path, monkeypatch, capsys, graph_path):  # noqa: F811
    """`play --headless` without --source plays the first Wiimote found; the clock was chosen from
    the URL typed (none), so a connected remote ran on the virtual clock; `--demo` with a --source
    (which it never opens) ran on the real clock."""
    from engine.clock import RealClock, VirtualClock
    from engine.sensors.demo import DemoSource

    clocks = []

    def connected_wiimote(url, clock):
        clocks.append(type(clock.__self__))
        return DemoSource(url=url, clock=clock)

    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "xdg"))
    monkeypatch.setitem(source_mod._factories, "wiimote", connected_wiimote)
    assert main(["play", "--headless", "--frames", "3", "--size", "320x180", "--graph", str(graph_path)]) == 0
    assert clocks == [VirtualClock, RealClock]
    assert "wiimote:// is a live device" in capsys.readouterr().err
    assert main(["play", "--headless", "--demo", "--source", "serial:///dev/nonexistent-qj", "--frames", "3",
                 "--size", "320x180", "--graph", str(graph_path)]) == 0
    assert "live device" not in capsys.readouterr().err


def test_left_handed_play_mirrors_a_right_handed_set(tmp_path, monkeypatch) -> None:
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "xdg"))
    from game.session import load_templates

    right = load_templates()
    left = load_templates(left_handed=True)
    assert sorted(left.action_names) == sorted(right.action_names)
    i = right.actions.index("straight_r")
    j = left.actions.index("straight_l")
    a = right.signals[i].reshape(len(right.signals[i]), 2, 3)
    b = left.signals[j].reshape(len(left.signals[j]), 2, 3)
    assert np.allclose(b[:, 1, 1:], a[:, 0, 1:]) and np.allclose(b[:, 1, 0], -a[:, 0, 0])


def test_a_one_hand_recording_is_a_clear_error(tmp_path, monkeypatch, capsys, graph_path) -> None:  # noqa: F811
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "xdg"))
    rec = tmp_path / "one_hand.csv"
    rows = "\n".join(f"{k / 60:.4f},0.0,0.0,1.0" for k in range(120))
    rec.write_text(f"# rate_hz: 60\nt,rx,ry,rz\n{rows}\n")
    assert main(["play", "--headless", "--frames", "5", "--graph", graph_path, "--source", f"replay://{rec}"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "one_hand.csv" in err[0] and "sensor" in err[0]


def test_mirror_posture_swaps_sides() -> None:
    from game.actions import load_library
    from game.skeleton import joint_index
    from game.training import mirror_posture

    p = load_library()["straight_r"].posture(10)
    m = mirror_posture(p)
    assert np.allclose(m[joint_index("fist_l")], p[joint_index("fist_r")] * [-1, 1, 1])
    assert np.allclose(mirror_posture(m), p)


def test_play_draws_its_first_frame_before_the_loop_starts(tmp_path, monkeypatch, graph_path):  # noqa: F811
    """The first draw builds the ring's static layers (26 ms here, a frame being ~2.6 ms): done
    inside the loop's first frame, it dropped steps on a slow board; it is done before the loop."""
    from engine.loop import FixedStepLoop
    from game.render import Renderer

    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "xdg"))
    running, built_while = [False], []
    run, build = FixedStepLoop.run, Renderer._build_static

    def loop_run(self, *a, **k):
        running[0] = True
        return run(self, *a, **k)

    def build_static(self):
        built_while.append(running[0])
        return build(self)

    monkeypatch.setattr(FixedStepLoop, "run", loop_run)
    monkeypatch.setattr(Renderer, "_build_static", build_static)
    assert main(["play", "--demo", "--headless", "--frames", "5", "--graph", graph_path, "--no-sound"]) == 0
    assert built_while and built_while[0] is False


def _budget_with(overruns: int, frames: int, period_ms: float = 1000 / 60):
    """A run of `frames` frames, the first `overruns` of them working 1.2 periods, the rest 0.3."""
    from engine.budget import FrameBudget

    budget = FrameBudget()
    budget.frame_period_ms = period_ms
    for i in range(frames):
        start = i * 100_000_000
        budget.begin_frame(start)
        budget.end_frame(start + int((1.2 if i < overruns else 0.3) * period_ms * 1e6), steps=1, dropped=0, wait_ns=0)
    return budget


def test_a_run_whose_frames_often_overran_points_at_low_power() -> None:
    from game.launch import slow_machine_hint

    assert slow_machine_hint(_budget_with(100, 600), low_power=False).startswith(
        "17 % of the frames took longer than 16.7 ms: this machine may play better with --low-power")
    assert "even in low power: a smaller window" in slow_machine_hint(_budget_with(100, 600, 1000 / 30), low_power=True)
    assert slow_machine_hint(_budget_with(30, 600), low_power=False) == ""  # 5 %: a hiccup, not the machine
    assert slow_machine_hint(_budget_with(100, 200), low_power=False) == ""  # too short a run to tell


def test_a_slow_low_power_run_is_pointed_at_a_window_that_draws_less_and_stays_readable() -> None:
    # the window named is the smallest whose text keeps its floor (800x450), not the 640x360
    # thumbnail; a window it would hardly shrink (a Pi's 800x480 screen) or a smaller one is not
    # told to take it
    from game.launch import slow_machine_hint

    slow = _budget_with(100, 600, 1000 / 30)
    for size in ((1280, 720), (1920, 1080), (960, 540), None):  # None: the window not known
        assert "a smaller window (--size 800x450) draws less" in slow_machine_hint(slow, low_power=True, size=size), size
    for size in ((800, 480), (800, 450), (640, 360)):
        hint = slow_machine_hint(slow, low_power=True, size=size)
        assert hint.startswith("17 % of the frames took longer than 33.3 ms even in low power") and "--size" not in hint, hint
        assert f"in a {size[0]}x{size[1]} window" in hint
    assert "--low-power" in slow_machine_hint(_budget_with(100, 600), low_power=False, size=(640, 360))


def test_a_slow_run_ended_with_ctrl_c_still_says_it_was_slow(capsys) -> None:
    # a slideshow on a small board is often ended from the terminal: the hint was skipped then
    import argparse

    from game.launch import slow_hint_at_the_end

    args = argparse.Namespace(headless=False, virtual_clock=False, low_power=False)
    with pytest.raises(KeyboardInterrupt), slow_hint_at_the_end(args, _budget_with(100, 600)):
        raise KeyboardInterrupt
    assert "quickjab play: 17 % of the frames" in capsys.readouterr().err
    with slow_hint_at_the_end(args, _budget_with(100, 600)):
        pass
    assert "quickjab play: 17 % of the frames" in capsys.readouterr().err
    with pytest.raises(RuntimeError), slow_hint_at_the_end(args, _budget_with(100, 600)):
        raise RuntimeError("a bug")  # an error is the error's to say
    assert capsys.readouterr().err == ""


def test_play_on_a_board_without_a_c_compiler_says_so_in_one_line_and_plays(tmp_path) -> None:
    # the kernels fall back to numpy (engine/native.py); that was said by `quickjab bench` only
    import os
    import subprocess

    env = {k: v for k, v in os.environ.items() if k not in ("CC", "QUICKJAB_NO_NATIVE", "QUICKJAB_NO_JIT", "QUICKJAB_CACHE_DIR")}
    env.update(PATH=str(tmp_path / "no-bin"), XDG_CACHE_HOME=str(tmp_path / "cache"), TMPDIR=str(tmp_path),
               PYTHONPATH=str(Path(__file__).resolve().parents[2]), SDL_VIDEODRIVER="dummy", SDL_AUDIODRIVER="dummy")
    argv = [sys.executable, "-m", "tools.cli", "play", "--low-power", "--demo", "--headless", "--frames", "30"]
    for extra, said in (({}, True), ({"QUICKJAB_NO_NATIVE": "1"}, False)):  # asked for: not said
        r = subprocess.run(argv, env={**env, **extra}, capture_output=True, text=True, timeout=120)
        assert r.returncode == 0, r.stderr
        lines = [x for x in r.stderr.splitlines() if "C kernels" in x]
        if said:
            assert len(lines) == 1 and "numpy for contacts, dtw_push_row, stick_project (no C compiler" in lines[0], r.stderr
            assert lines[0].endswith("the game plays, more slowly (docs/performance.md)")
        else:
            assert lines == [], r.stderr


def test_the_kernels_line_names_one_reason_for_a_compiler_that_fails_every_kernel(tmp_path, monkeypatch) -> None:
    # a build that failed is remembered per kernel; the line names the failure once, not once a kernel
    from engine import native
    from game.launch import kernels_line

    for var in ("QUICKJAB_NO_NATIVE", "QUICKJAB_NO_JIT"):
        monkeypatch.delenv(var, raising=False)
    monkeypatch.setenv("QUICKJAB_CACHE_DIR", str(tmp_path))
    monkeypatch.setenv("CC", "/bin/false")
    monkeypatch.setattr(native, "_status", {})
    for _ in range(2):  # the build, then the remembered failure
        for stem in ("contacts", "dtw_push_row"):
            assert native.load_library(stem, f"int {stem}_x(void) {{ return 0; }}\n") is None
        line = kernels_line()
        assert line.startswith("C kernels: numpy for contacts, dtw_push_row (/bin/false exit 1") and line.count("/bin/false") == 1, line
    monkeypatch.setenv("QUICKJAB_NO_NATIVE", "1")
    assert kernels_line() == ""
    monkeypatch.setattr(native, "_status", {"contacts": "native: x.so"})
    monkeypatch.delenv("QUICKJAB_NO_NATIVE")
    assert kernels_line() == ""


def test_the_slow_machine_line_is_said_only_where_frames_keep_the_machines_pace(capsys) -> None:
    # under --headless or the virtual clock the frames run as fast as they can: their overruns
    # say nothing of the machine
    import argparse

    from game.launch import say_if_slow

    slow = _budget_with(100, 600)
    for headless, virtual, said in ((False, False, True), (True, False, False), (False, True, False)):
        say_if_slow(argparse.Namespace(headless=headless, virtual_clock=virtual, low_power=False), slow)
        err = capsys.readouterr().err
        assert ("quickjab play: 17 % of the frames" in err) == said, (headless, virtual, err)
    say_if_slow(argparse.Namespace(headless=False, virtual_clock=False, low_power=False), _budget_with(0, 600))
    assert capsys.readouterr().err == ""


@pytest.mark.parametrize("command", ["play", "train"])
@pytest.mark.parametrize("size", ["480x270", "320x240", "639x480", "1280x359"])
def test_a_window_under_640x360_is_said_in_one_line_and_opens(command, size, tmp_path, capsys) -> None:
    """Under 640x360 the HUD is hard to read (4 px capitals at 480x270 and 320x240, a REJECTED
    mark over the move's name, the training checklist off the window): said in one line; the
    window opens at that size all the same (a board's 480x320 screen has no larger one)."""
    shot = tmp_path / "shot.png"
    argv = [command, "--demo", "--size", size, "--screenshot", str(shot), "--frames", "2"]
    argv += ["--virtual-clock", "--no-sound"] if command == "play" else ["--actions", "straight_r", "-o", str(tmp_path / "t.npz")]
    assert main(argv) == 0
    err = capsys.readouterr().err.splitlines()
    said = [line for line in err if "--size" in line]
    assert said == [f"quickjab {command}: --size {size}: under 640x360 the text is hard to read and some of it runs "
                    "off the window"], err
    assert pygame.image.load(str(shot)).get_size() == tuple(int(v) for v in size.split("x"))


def test_the_smallest_window_plays_and_headless_frames_may_be_smaller(tmp_path, capsys) -> None:
    for size, options in (("640x360", ["--virtual-clock"]), ("320x240", ["--headless"])):
        shot = tmp_path / f"{size}.png"
        assert main(["play", "--demo", *options, "--frames", "2", "--no-sound", "--size", size, "--screenshot", str(shot)]) == 0
        assert pygame.image.load(str(shot)).get_size() == tuple(int(v) for v in size.split("x"))


def test_play_whose_terminal_closes_writes_its_files_and_exits_as_on_ctrl_c(tmp_path) -> None:
    """A terminal that really closes hangs up its line before the SIGHUP: every later line said to
    it failed with an I/O error, which cut the cleanup short after the screenshot (no trace, exit
    1). Now what cannot be said is not, and the files are written (exit 130)."""
    import os
    import pty
    import select
    import time

    from engine.trace import read_chrome_trace

    trace, shot = tmp_path / "run.json", tmp_path / "shot.png"
    env = {**os.environ, "PYTHONPATH": str(Path(__file__).resolve().parents[2]), "SDL_VIDEODRIVER": "dummy",
           "SDL_AUDIODRIVER": "dummy", "XDG_DATA_HOME": str(tmp_path / "data"), "XDG_CONFIG_HOME": str(tmp_path / "config")}
    argv = [sys.executable, "-m", "tools.cli", "play", "--headless", "--demo", "--frames", "10000000",
            "--trace", str(trace), "--screenshot", str(shot)]
    pid, master = pty.fork()  # the child's controlling terminal is the pty: closing it hangs up
    if pid == 0:
        os.execve(sys.executable, argv, env)
    said = b""
    try:
        while b"quickjab play:" not in said:  # the templates line: the loop is next
            ready, _, _ = select.select([master], [], [], 60)
            assert ready, said
            said += os.read(master, 4096)
        time.sleep(1.0)  # some frames for the trace
    finally:
        os.close(master)
    _, status = os.waitpid(pid, 0)
    assert os.waitstatus_to_exitcode(status) == 130, said
    assert shot.stat().st_size > 0
    assert any(ev.get("name") == "frame" for ev in read_chrome_trace(trace)["traceEvents"])


@pytest.mark.parametrize("signame", ["SIGTERM", "SIGHUP"])
def test_play_ended_by_sigterm_or_sighup_writes_its_trace_as_ctrl_c_does(tmp_path, signame) -> None:
    """`kill`, a service manager, `timeout` (SIGTERM) or a closed terminal (SIGHUP) ended play on
    the spot, or as a closed window where SDL caught SIGTERM: no trace, or an exit status that
    said nothing of the interruption. Now it is Ctrl-C's end: the trace written, exit 130."""
    import os
    import signal
    import subprocess
    import time

    from engine.trace import read_chrome_trace

    trace = tmp_path / "run.json"
    env = {**os.environ, "PYTHONPATH": str(Path(__file__).resolve().parents[2]), "SDL_VIDEODRIVER": "dummy",
           "SDL_AUDIODRIVER": "dummy", "XDG_DATA_HOME": str(tmp_path / "data"), "XDG_CONFIG_HOME": str(tmp_path / "config")}
    argv = [sys.executable, "-m", "tools.cli", "play", "--headless", "--demo", "--frames", "10000000", "--trace", str(trace)]
    proc = subprocess.Popen(argv, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    try:
        said = proc.stderr.readline()  # the templates line: the window is open, the loop next
        assert said.startswith("quickjab play:"), said
        time.sleep(1.0)  # some frames for the trace
        proc.send_signal(getattr(signal, signame))
        err = said + proc.communicate(timeout=60)[1]
    finally:
        proc.kill()
        proc.wait()
    assert proc.returncode == 130, err
    assert "Traceback" not in err and f"quickjab play: wrote {trace}" in err
    assert any(ev.get("name") == "frame" for ev in read_chrome_trace(trace)["traceEvents"])


@pytest.mark.parametrize("where", ["__init__", "render"])
def test_play_ended_while_the_match_loads_writes_its_trace_as_in_the_loop(tmp_path, monkeypatch, capsys, where) -> None:
    """Ctrl-C (or SIGTERM, SIGHUP: the same KeyboardInterrupt) after the window opened and before
    the loop ran (the session built, its first frame drawn: seconds on a slow board) wrote no
    trace and no screenshot, where one in the loop writes both. Now the files are written with
    what there is, a trace of no frames said so, and the exit is 130 as in the loop."""
    from game.session import Session

    def interrupted(self, *a, **k):
        raise KeyboardInterrupt

    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "xdg"))
    monkeypatch.setattr(Session, where, interrupted)
    trace, shot = tmp_path / "t.json", tmp_path / "s.png"
    assert main(["play", "--demo", "--headless", "--no-sound", "--trace", str(trace), "--screenshot", str(shot)]) == 130
    err = capsys.readouterr().err
    assert f"quickjab play: wrote {shot}" in err
    assert f"quickjab play: wrote {trace} (no frames: ended before the first)" in err
    data = json.loads(trace.read_text())
    assert data["otherData"]["frames_total"] == 0 and all(ev["ph"] == "M" for ev in data["traceEvents"])
    assert pygame.image.load(str(shot)).get_size() == (1280, 720)


def test_train_says_a_backslash_in_minus_o_is_no_folder_here(tmp_path, monkeypatch, capsys) -> None:
    """`train -o 'C:\\Users\\me\\t.npz'` on Linux or macOS saved one file of that literal name in
    the current folder, unsaid: a backslash is a character of a name there. Said in one line
    (a name it is, so it is not refused)."""
    import os

    if os.sep == "\\" or os.altsep == "\\":
        pytest.skip("a folder separator on this system")
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "xdg"))
    monkeypatch.chdir(tmp_path)
    name = "C:\\Users\\me\\t.npz"
    main(["train", "--headless", "--demo", "--actions", "straight_r", "--frames", "2", "-o", name])
    err = capsys.readouterr().err.strip().splitlines()
    assert (f"quickjab train: -o {name}: a backslash is not a folder separator on this system: "
            f"this names one file, {name}, in {tmp_path}") in err, err
