"""Recognizer settings as data, from the player's side: saved with the templates by `train`,
set in the user's config file and on `play`'s command line, in that order of precedence
(command line > config file > saved with the templates > defaults)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
from pathlib import Path

import pygame
import pytest

from engine.clock import VirtualClock
from engine.errors import InputError
from engine.recognition import RecognizerConfig
from game.user_config import config_path, read_config, recognizer_settings
from tools.cli import main

sys.path.insert(0, str(Path(__file__).parent))
from game_graph import graph_path  # noqa: E402,F401 - the fixture

REPO = Path(__file__).resolve().parents[2]


@pytest.fixture(autouse=True)
def own_dirs(tmp_path, monkeypatch):
    """Never read or write the real user's templates or config file."""
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "xdg"))
    monkeypatch.setenv("XDG_CONFIG_HOME", str(tmp_path / "config"))


def write_config(text: str) -> Path:
    path = config_path()
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text, encoding="utf-8")
    return path


def test_no_config_file_sets_nothing():
    assert not config_path().exists() and read_config() == {} and recognizer_settings() == {}


def test_config_file_then_command_line():
    path = write_config('[recognizer]\nnoise_g = 0.5\nmain = "auto"\nreject = false\n')
    assert path == Path(str(config_path())) and path.parts[-2:] == ("quickjab", "config.toml")
    assert recognizer_settings() == {"noise_g": 0.5, "main": "auto", "reject": False}
    assert recognizer_settings(["noise_g=0.7", "adapt=0"]) == {"noise_g": 0.7, "main": "auto", "reject": False, "adapt": 0}


@pytest.mark.parametrize("text, says", [
    ("[recognizer\nnoise_g = 0.5\n", "not a valid TOML file"),
    ("[recognizer]\nnoise = 0.5\n", "[recognizer]: unknown recognizer setting 'noise'"),
    ('[recognizer]\nnoise_g = "loud"\n', "recognizer setting noise_g must be a number"),
    ("[recognizer]\nmain = 6.5\n", "recognizer setting main must be an integer"),
    ("noise_g = 0.5\n", "unknown setting or table 'noise_g'"),
    ("[recogniser]\nnoise_g = 0.5\n", "unknown setting or table 'recogniser'"),
    ("recognizer = 3\n", "'recognizer' must be a table"),
    # nested past the parser's recursion limit (tomllib recurses per level): RecursionError
    ("[recognizer]\nnoise_g = " + "[" * 100_000 + "]" * 100_000 + "\n", "not a valid TOML file"),
    ("[recognizer]\nnoise_g = " + "{a = " * 50_000 + "1" + "}" * 50_000 + "\n", "not a valid TOML file"),
    # an integer of over 4300 digits: tomllib's int() raised a plain ValueError (a traceback)
    ("[recognizer]\nmain = " + "1" * 5000 + "\n", "not a valid TOML file (an integer of over 4300 digits"),
    ("\ufeff[recognizer]\nnoise_g = 0.5\n", "not a valid TOML file"),  # a byte-order mark: TOML has none
])
def test_a_bad_config_file_names_itself_in_one_line(text, says):
    path = write_config(text)
    with pytest.raises(InputError) as err:
        recognizer_settings()
    assert str(err.value).startswith(str(path)) and says in str(err.value) and "\n" not in str(err.value)


def test_a_config_file_that_is_not_text_or_not_a_file():
    path = config_path()
    path.parent.mkdir(parents=True)
    path.write_bytes(b"\xff\xfe[rec")
    with pytest.raises(InputError, match="not a valid TOML file"):
        read_config()
    path.unlink()
    path.mkdir()
    with pytest.raises(InputError, match="cannot read the config file"):
        read_config()


@pytest.mark.parametrize("target", ["config.toml", "elsewhere.toml"])
def test_a_config_link_that_loops_or_dangles_is_refused_not_ignored(target):
    """Path.exists() is False for both, and the settings were silently the defaults."""
    path = config_path()
    path.parent.mkdir(parents=True)
    path.symlink_to(target)  # itself: a loop; a file that is not there: dangling
    with pytest.raises(InputError, match=f"{path}: cannot read the config file"):
        read_config()


def test_a_fifo_config_file_is_refused_without_opening_it():
    path = config_path()
    path.parent.mkdir(parents=True)
    os.mkfifo(path)  # size 0, and opening it blocks until a writer comes

    def hung(*_):
        raise TimeoutError("read_config opened the FIFO and waited")

    old = signal.signal(signal.SIGALRM, hung)
    signal.alarm(5)
    try:
        with pytest.raises(InputError, match="cannot read the config file: .*pipe"):
            read_config()
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)


def test_play_with_a_bad_config_file_exits_2_with_one_line_and_no_traceback(tmp_path):
    path = write_config("[recognizer]\nnoise_g = true\n")
    env = {"PYTHONPATH": str(REPO), "XDG_CONFIG_HOME": str(tmp_path / "config"), "XDG_DATA_HOME": str(tmp_path / "xdg"),
           "SDL_VIDEODRIVER": "dummy", "SDL_AUDIODRIVER": "dummy", "PATH": "/usr/bin:/bin"}
    r = subprocess.run([sys.executable, "-m", "tools.cli", "play", "--headless", "--frames", "1", "--source", "keyboard://"],
                       cwd=REPO, env=env, capture_output=True, text=True, timeout=120)
    err = r.stderr.strip().splitlines()
    assert r.returncode == 2 and len(err) == 1, r.stderr
    assert str(path) in err[0] and "noise_g" in err[0] and "Traceback" not in r.stderr


def test_play_refuses_a_bad_recognizer_option(capsys):
    for bad, says in [("gate=0.5", "unknown recognizer setting 'gate'"), ("noise_g", "expected NAME=VALUE"),
                      ("main=0", "main must be an integer from 1")]:
        assert main(["play", "--headless", "--frames", "1", "--source", "keyboard://", "--recognizer", bad]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and says in err[0], err


def session_recognizer(settings: dict, templates: Path | None, graph):
    import game.keyboard_source  # noqa: F401 - registers keyboard://
    from engine.sensors import open_source
    from game.session import Session, SessionConfig

    pygame.init()
    clock = VirtualClock()
    source = open_source("keyboard://?seed=1", clock=clock.seconds)
    cfg = SessionConfig(size=(320, 180), sound=False, render=False, graph=graph, templates=templates, recognizer=settings)
    return Session(source, cfg, clock=clock).recognizer


def test_precedence_command_line_over_config_file_over_templates_over_defaults(tmp_path, graph_path):  # noqa: F811
    from game.session import synthesized_templates

    t = synthesized_templates(trials=1)
    t.recognizer = {"noise_g": 0.4, "supplementary": 50, "null_frames": 9}
    saved = tmp_path / "mine.npz"
    t.save(saved)
    write_config("[recognizer]\nnoise_g = 0.6\nsupplementary = 40\n")
    rec = session_recognizer(recognizer_settings(["noise_g=0.8"]), saved, graph_path)
    defaults = RecognizerConfig()
    assert rec.noise_g == 0.8  # command line over all
    assert rec.supplementary == 40  # config file over the templates
    assert rec.null_frames == 9  # the templates over the defaults
    assert rec.discard_frames == defaults.discard_frames and rec.main == defaults.main  # nobody set these
    assert not rec.auto_gate
    # nothing set anywhere: the defaults, exactly
    (config_path()).unlink()
    rec = session_recognizer(recognizer_settings(), None, graph_path)
    assert (rec.auto_gate, rec.main, rec.supplementary, rec.null_frames) == (True, 6, 60, 6)


def test_train_saves_the_settings_and_keeps_those_already_saved(tmp_path, graph_path):  # noqa: F811
    from engine.recognition import Templates

    out = tmp_path / "mine.npz"
    base = ["train", "--headless", "--demo", "--source", "keyboard://?seed=3", "--size", "320x180", "-o", str(out)]
    assert main([*base, "--actions", "straight_r", "--recognizer", "noise_g=0.5",
                 "--recognizer", "main=auto"]) == 0
    assert Templates.load(out).recognizer == {"noise_g": 0.5, "main": "auto"}
    assert main([*base, "--actions", "hook_l", "--recognizer", "noise_g=0.7"]) == 0
    assert Templates.load(out).recognizer == {"noise_g": 0.7, "main": "auto"}  # main kept, the gate re-tuned
    # and play decides with them
    rec = session_recognizer(recognizer_settings(), out, graph_path)
    assert (rec.noise_g, rec.main) == (0.7, "auto")


def test_two_players_each_over_their_own_templates_settings(tmp_path):
    import game.keyboard_source  # noqa: F401 - registers keyboard://
    from engine.sensors import open_source
    from game.session import SessionConfig, synthesized_templates
    from game.two_player import TwoPlayerSession

    t = synthesized_templates(trials=1)
    t.recognizer = {"null_frames": 9, "noise_g": 0.4}
    saved = tmp_path / "ann.npz"
    t.save(saved)
    pygame.init()
    clock = VirtualClock()
    sources = [open_source(u, clock=clock.seconds) for u in ("keyboard://?seed=1", "keyboard://?seed=2")]
    cfg = SessionConfig(size=(320, 180), sound=False, render=False, recognizer={"noise_g": 0.9})
    s = TwoPlayerSession(sources, cfg, clock=clock, templates=(saved, None))
    ann, other = (seat.recognizer for seat in s.seats)
    assert (ann.noise_g, ann.null_frames) == (0.9, 9)  # the shared command line over her saved gate
    assert (other.noise_g, other.null_frames) == (0.9, 6)


def test_a_config_file_saved_with_a_byte_order_mark_says_so():
    """Notepad's "UTF-8 with BOM": refused (TOML has no byte-order mark) as "Invalid statement
    (at line 1, column 1)", a line that shows nothing wrong: the mark is named, and the fix."""
    path = config_path()
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(b"\xef\xbb\xbf[recognizer]\r\nnoise_g = 0.5\r\n")
    with pytest.raises(InputError) as exc:
        read_config()
    assert str(exc.value) == f"{path}: not a valid TOML file (it starts with a byte-order mark: save it as UTF-8 without BOM)"
