"""Issue 17, the first hour of a new player: the traps of `train`, `play` and their screens."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from tools.cli import main

sys.path.insert(0, str(Path(__file__).parent))
from game_graph import graph_path, other_library_graph  # noqa: E402,F401 - the fixture

REPO = Path(__file__).resolve().parents[2]


def train(*args: str) -> int:
    return main(["train", "--headless", "--demo", "--source", "keyboard://?seed=3", "--size", "320x180", *args])


def test_training_one_move_then_another_keeps_both_and_the_defaults(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "xdg"))
    from engine.recognition import Templates
    from game.actions import ACTION_NAMES
    from game.userdata import SHIPPED_TEMPLATES, user_templates_path

    assert train("--actions", "straight_l") == 0
    first = Templates.load(user_templates_path())
    assert sorted(first.action_names) == sorted(ACTION_NAMES)
    assert train("--actions", "hook_r") == 0
    second = Templates.load(user_templates_path())
    assert sorted(second.action_names) == sorted(ACTION_NAMES)
    assert second.meta["trained"] == "hook_r,straight_l"
    # straight_l is still the one trained first, not the default's
    mine = [s for a, s in zip(first.actions, first.signals, strict=True) if a == "straight_l"]
    kept = [s for a, s in zip(second.actions, second.signals, strict=True) if a == "straight_l"]
    assert len(mine) == len(kept) and all(np.array_equal(a, b) for a, b in zip(mine, kept, strict=True))
    # an action neither run trained is the shipped set's
    if SHIPPED_TEMPLATES.exists():
        shipped = Templates.load(SHIPPED_TEMPLATES)
        ref = [s for a, s in zip(shipped.actions, shipped.signals, strict=True) if a == "block"]
        got = [s for a, s in zip(second.actions, second.signals, strict=True) if a == "block"]
        assert len(ref) == len(got) and all(np.array_equal(a, b) for a, b in zip(ref, got, strict=True))
    # a demo never asks the user to press keys
    assert "press" not in capsys.readouterr().err.lower()


def test_train_reset_goes_back_to_the_default_templates(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "xdg"))
    from game.session import templates_in_use
    from game.userdata import user_templates_path

    path = user_templates_path()
    path.parent.mkdir(parents=True)
    from game.session import synthesized_templates

    t = synthesized_templates(trials=1)
    t.meta.update({"source": "quickjab train", "trained": "straight_l"})
    t.save(path)
    assert templates_in_use().startswith("your templates (1 of 13 moves")
    assert main(["train", "--reset"]) == 0
    assert not path.exists()
    assert "default" in capsys.readouterr().err
    assert templates_in_use() == "default templates"


def test_train_reset_with_a_profile_removes_that_players_set_only(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "xdg"))
    from game.session import synthesized_templates
    from game.userdata import profile_templates_path, user_templates_path

    t = synthesized_templates(trials=1)
    for path in (user_templates_path(), profile_templates_path("ana")):
        path.parent.mkdir(parents=True, exist_ok=True)
        t.save(path)
    assert main(["train", "--reset", "--profile", "ana"]) == 0
    assert not profile_templates_path("ana").exists()
    assert user_templates_path().exists()  # the default player's set is not ana's
    assert str(profile_templates_path("ana")) in capsys.readouterr().err


def test_a_trained_set_keeps_the_rest_noise_of_its_trials(tmp_path, monkeypatch):
    """merge_templates keeps the new trials' rest noise: the automatic gate starts from the
    noise measured during training, not from its fallback."""
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "xdg"))
    from engine.recognition import Templates
    from game.userdata import user_templates_path

    assert train("--actions", "straight_l") == 0
    noise = Templates.load(user_templates_path()).rest_noise
    assert np.isfinite(noise) and 0 <= noise < 1.0


def test_play_says_which_templates_it_uses_on_screen_and_console(tmp_path, monkeypatch, capsys, graph_path):  # noqa: F811
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "xdg"))
    import pygame

    from game.session import synthesized_templates
    from game.userdata import user_templates_path

    shots = []
    for name in ("default", "mine"):
        shot = tmp_path / f"{name}.png"
        assert main(["play", "--headless", "--frames", "2", "--graph", graph_path, "--no-sound", "--source", "keyboard://",
                     "--screenshot", str(shot)]) == 0
        shots.append(pygame.surfarray.array3d(pygame.image.load(str(shot))).astype(int))
        if name == "default":
            t = synthesized_templates(trials=1)
            t.meta.update({"source": "quickjab train", "trained": "straight_l"})
            user_templates_path().parent.mkdir(parents=True, exist_ok=True)
            t.save(user_templates_path())
    err = capsys.readouterr().err
    assert "quickjab play: default templates" in err
    assert "your templates (1 of 13 moves; `quickjab train --reset` for the defaults)" in err
    # the line under the source's: its text differs between the two runs
    band = (slice(20, 700), slice(120, 150))
    assert (shots[0][band] != shots[1][band]).any()


def test_headless_play_without_frames_ends(tmp_path, graph_path, capsys):  # noqa: F811
    trace = tmp_path / "t.json"
    assert main(["play", "--headless", "--graph", graph_path, "--no-sound", "--source", "keyboard://",
                 "--size", "320x180", "--trace", str(trace)]) == 0
    from game.launch import HEADLESS_FRAMES

    frames = [e for e in json.loads(trace.read_text())["traceEvents"] if e.get("name") == "frame"]
    assert len(frames) == HEADLESS_FRAMES
    assert f"stopping after {HEADLESS_FRAMES} frames" in capsys.readouterr().err


@pytest.mark.parametrize("command", ["play", "train", "scope"])
def test_no_display_is_a_clear_error_not_an_invisible_window(command):
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY", "SDL_VIDEODRIVER")}
    env.update(PYTHONPATH=str(REPO), SDL_AUDIODRIVER="dummy")
    source = "demo://" if command == "scope" else "keyboard://"
    r = subprocess.run([sys.executable, "-m", "tools.cli", command, "--source", source, "--frames", "100000"],
                       cwd=REPO, env=env, capture_output=True, text=True, timeout=120)
    assert r.returncode == 2, r.stderr
    assert "no display" in r.stderr and "--headless" in r.stderr
    assert "Traceback" not in r.stderr
    # train's headless run goes on until its walk is over: --frames 600 stopped it in its first move
    assert ("--frames 600" in r.stderr) == (command != "train"), r.stderr


def test_training_traces_are_one_colour_per_hand():
    import pygame

    from game.actions import load_library
    from game.training import TRACE_COLOURS, Trainer, TrainingScreen

    pygame.init()
    screen = TrainingScreen(load_library(), Trainer(["straight_r"]), "keyboard://")
    t = np.arange(150)
    for k in t:
        screen.push_frame(np.array([np.sin(k / 7 + p) * 2 for p in range(6)]))
    surf = pygame.Surface((640, 300))
    rect = pygame.Rect(0, 0, 640, 300)
    screen._plot(surf, rect)
    a = pygame.surfarray.array3d(surf).reshape(-1, 3).astype(int)
    lit = a[a.max(axis=1) > 60]
    reddish = (lit[:, 0] > lit[:, 2] + 40)
    bluish = (lit[:, 2] > lit[:, 0] + 40)
    assert reddish.sum() > 500 and bluish.sum() > 500
    # nothing green or orange: every trace pixel is one hand's hue (or the grey mid line)
    greenish = (lit[:, 1] > lit[:, 0] + 30) & (lit[:, 1] > lit[:, 2] + 30)
    assert greenish.sum() == 0
    assert TRACE_COLOURS[0][0][0] > TRACE_COLOURS[0][0][2] and TRACE_COLOURS[1][0][2] > TRACE_COLOURS[1][0][0]


def test_training_keeps_the_usable_trials_and_says_what_it_dropped():
    """`train` builds the templates from every usable trial (keep="usable"), not 3 of 5, and
    tells the player how many of a move's trials it dropped."""
    from game.training import Trainer

    rng = np.random.default_rng(0)
    g = np.tile([0.0, 0.0, 1.0], (60, 1))

    def punch(axis: int, n: int = 24) -> np.ndarray:
        x = g.copy()
        x[20 : 20 + n, axis] += 3.0 * np.sin(np.linspace(0, np.pi, n))
        return x + rng.normal(0, 0.01, x.shape)

    cut_off = g.copy()
    cut_off[54:, 0] += 3.0 * np.sin(np.linspace(0, np.pi / 2, 6))  # the window closed on the way up
    trainer = Trainer(["jab", "upper"], recorded={"jab": [punch(0) for _ in range(4)] + [cut_off],
                                                  "upper": [punch(2) for _ in range(5)]})
    templates = trainer.templates()
    assert templates.actions.count("jab") == 4 and templates.actions.count("upper") == 5
    assert trainer.dropped == {"jab": (1, 5)}


def test_retraining_one_move_compares_it_with_the_moves_kept(monkeypatch):
    """`train --actions jab`: a jab trial moved as the kept uppercut is dropped (the look-alike
    rule sees the base set's moves too; the odd-one rule, which would also drop it, is off)."""
    import engine.recognition.templates as template_module
    from engine.recognition import Templates
    from game.training import Trainer

    monkeypatch.setattr(template_module, "ODD_RATIO", np.inf)

    rng = np.random.default_rng(1)
    g = np.tile([0.0, 0.0, 1.0], (60, 1))

    def punch(axis: int, amp: float = 3.0) -> np.ndarray:
        x = g.copy()
        x[20:44, axis] += amp * np.sin(np.linspace(0, np.pi, 24))
        return x + rng.normal(0, 0.05, x.shape)

    look_alike = punch(2, 2.1)
    look_alike[20:44, 0] += 0.9 * np.sin(np.linspace(0, np.pi, 24))
    base = Templates.from_trials({"upper": [punch(2) for _ in range(4)]})
    recorded = {"jab": [punch(0), look_alike, punch(0), punch(0), punch(0)]}
    alone = Trainer(["jab"], recorded=recorded)
    assert alone.templates().actions.count("jab") == 5 and alone.dropped == {}  # nothing to look like
    trainer = Trainer(["jab"], recorded=recorded)
    templates = trainer.templates(base=base)
    assert trainer.dropped == {"jab": (1, 5)}
    assert templates.actions.count("jab") == 4 and templates.actions.count("upper") == 4


def test_training_over_a_set_for_other_sensors_says_the_old_moves_go(tmp_path, monkeypatch, capsys):
    """A saved one-sensor set and a two-sensor training (`train --actions X`): nothing of the old
    set fits, so only the moves trained now are kept; this used to happen without a word."""
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "xdg"))
    from engine.recognition import Templates
    from game.userdata import user_templates_path

    rng = np.random.default_rng(0)
    one = np.tile([0.0, 0.0, 1.0], (40, 1))
    one[10:30, 0] += 2.0 * np.sin(np.linspace(0, np.pi, 20))
    path = user_templates_path()
    path.parent.mkdir(parents=True, exist_ok=True)
    Templates.from_trials({"jab": [one + rng.normal(0, 0.01, one.shape) for _ in range(3)]}).save(path)
    assert train("--actions", "straight_r") == 0
    assert Templates.load(path).action_names == ["straight_r"]
    assert "were for 1 sensor(s), these trials have 2: only the moves trained now are kept" in capsys.readouterr().err


def test_train_reset_with_o_removes_only_a_template_file(tmp_path, monkeypatch, capsys):
    """`train --reset -o README.md` deleted the README: a file named with -o is removed only
    if it is a template set (a typo must not delete a recording or a document); a directory
    is one line, exit 2."""
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "xdg"))
    from game.session import synthesized_templates

    notes = tmp_path / "notes.txt"
    notes.write_text("the player's notes")
    assert main(["train", "--reset", "-o", str(notes)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and str(notes) in err[0] and "not removed" in err[0], err
    assert notes.read_text() == "the player's notes"
    assert main(["train", "--reset", "-o", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "directory" in err[0] and tmp_path.is_dir(), err
    mine = tmp_path / "mine.npz"
    synthesized_templates(trials=1).save(mine)
    assert main(["train", "--reset", "-o", str(mine)]) == 0
    assert not mine.exists()


def test_train_reset_removes_a_broken_set_in_the_data_directory(tmp_path, monkeypatch, capsys):
    """The player's own file is removed even when it no longer loads (what --reset is for),
    and a directory in its place is one line naming it, exit 2."""
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "xdg"))
    from game.userdata import profile_templates_path, user_templates_path

    path = user_templates_path()
    path.parent.mkdir(parents=True)
    path.write_bytes(b"PK\x03\x04 truncated")
    assert main(["train", "--reset"]) == 0 and not path.exists()
    capsys.readouterr()
    profile_templates_path("ana").mkdir(parents=True)
    assert main(["train", "--reset", "--profile", "ana"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and str(profile_templates_path("ana")) in err[0] and "directory" in err[0], err


def test_a_profile_with_templates_or_o_is_said_ignored(tmp_path, monkeypatch, capsys, graph_path):  # noqa: F811
    """`play --profile ana --templates X` played X and `train --profile ana -o X` saved to X
    without a word about ana (a typo in either went unseen): said, as --profile2 without
    --players 2 is."""
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "xdg"))
    from game.session import synthesized_templates

    mine = tmp_path / "mine.npz"
    synthesized_templates(trials=1).save(mine)
    assert main(["play", "--headless", "--frames", "1", "--graph", graph_path, "--no-sound", "--source", "keyboard://",
                 "--size", "320x180", "--templates", str(mine), "--profile", "ana"]) == 0
    assert "--profile ignored with --templates" in capsys.readouterr().err
    assert main(["train", "--reset", "--profile", "ana", "-o", str(tmp_path / "other.npz")]) == 0
    assert "--profile ignored with -o" in capsys.readouterr().err


def test_moves_whose_file_cannot_be_written_at_the_end_are_kept_elsewhere(tmp_path, monkeypatch, capsys):
    """The folder writable when train started, not when its trials were done (made read-only,
    removed, a full disk): the minutes of trials ended in "[Errno 2] No such file or directory"
    and were lost. They are saved in the temporary directory instead, said, exit 2."""
    import tempfile

    import game.training
    from engine.recognition import Templates

    blocked = tmp_path / "not-a-dir"
    blocked.write_text("")
    monkeypatch.setenv("XDG_DATA_HOME", str(blocked))  # its quickjab/ folder cannot be made
    monkeypatch.setattr(game.training, "_check_files", lambda args, output: None)  # as if it could at the start
    (tmp_path / "tmp").mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path / "tmp"))
    assert train("--actions", "block") == 2
    err = capsys.readouterr().err.strip().splitlines()
    kept = list((tmp_path / "tmp").glob("quickjab-templates-*.npz"))
    assert len(kept) == 1 and "block" in Templates.load(kept[0]).meta["trained"]
    assert str(blocked / "quickjab" / "templates.npz") in err[-1] and f"--templates {kept[0]}" in err[-1], err


def test_a_broken_cached_graph_is_built_again(tmp_path, monkeypatch, capsys):
    """Without the shipped graph, `play` builds one into graph-small.npz once; a broken cached
    file (a copy cut short, a disk error) was an error on every start, never rebuilt: it is a
    cache, built again."""
    import game.interaction
    from game.session import load_graph
    from game.userdata import data_dir

    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "xdg"))
    monkeypatch.setattr(game.interaction, "DEFAULT_GRAPH", tmp_path / "no-graph.npz")
    cached = data_dir() / "graph-small.npz"
    cached.parent.mkdir(parents=True)
    cached.write_bytes(b"PK\x03\x04 cut short")
    assert load_graph() is not None
    assert "building it again" in capsys.readouterr().err
    assert load_graph() is not None and "building" not in capsys.readouterr().err


def test_a_cached_graph_from_another_action_library_is_built_again(tmp_path, monkeypatch, capsys):
    """The cache is checked against the library as a given graph is (a stale one crashed the
    match at its first look-up of an action the library lacks): it is built again."""
    import game.interaction
    from game.session import load_graph
    from game.userdata import data_dir

    if not game.interaction.DEFAULT_GRAPH.exists():
        pytest.skip("no shipped graph to alter")
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "xdg"))
    cached = data_dir() / "graph-small.npz"
    cached.parent.mkdir(parents=True)
    other_library_graph(str(game.interaction.DEFAULT_GRAPH), cached)
    monkeypatch.setattr(game.interaction, "DEFAULT_GRAPH", tmp_path / "no-graph.npz")
    assert "zzz" not in load_graph().names
    assert "different action library" in capsys.readouterr().err
