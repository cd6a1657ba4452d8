"""`python -m game`: the game's own commands (play, train) without the tools' ones, since game
never imports tools; errors are one line and exit 2, as with quickjab."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]


def run(*args: str) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": str(REPO), "SDL_VIDEODRIVER": "dummy", "SDL_AUDIODRIVER": "dummy"}
    return subprocess.run([sys.executable, "-m", "game", *args], cwd=REPO, env=env,
                          capture_output=True, text=True, timeout=120)


def test_python_m_game_offers_play_and_train_only():
    r = run("--help")
    commands = [line.split()[0] for line in r.stdout.splitlines() if line[:4] == "    " and line[4:5].isalpha()]
    assert r.returncode == 0 and commands == ["play", "train"], r.stdout
    assert run("record", "--help").returncode == 2  # a tools command is not here


def test_python_m_game_reports_bad_input_in_one_line():
    r = run("play", "--headless", "--frames", "5", "--source", "nosuch://x")
    assert r.returncode == 2 and "Traceback" not in r.stderr
    assert [line for line in r.stderr.splitlines() if line.startswith("quickjab play:")] == [
        "quickjab play: unknown source scheme 'nosuch' in 'nosuch://x'; known: demo, keyboard, replay, serial, wiimote, wiimote-emu"
    ]


@pytest.mark.parametrize("args", [("play", "--low-pwer"), ("play", "--difficulty", "x"), ("train", "--seed", "-1")])
def test_python_m_game_reports_a_bad_argument_in_one_line(args):
    """As quickjab's parser: one line naming the command, exit 2 (argparse's usage block before)."""
    r = run(*args)
    assert r.returncode == 2 and r.stderr.count("\n") == 1 and "usage" not in r.stderr, r.stderr
    assert r.stderr.startswith(f"python -m game {args[0]}: ") and r.stderr.endswith(f"(see python -m game {args[0]} --help)\n")


def test_one_owner_runs_a_command_for_both_command_lines(capsys, monkeypatch):
    """game.command.run_command is the error handling of `quickjab` and `python -m game`."""
    import argparse

    import game.__main__
    import game.command
    import tools.cli
    from engine.errors import InputError
    from game.command import run_command

    assert game.__main__.run_command is run_command
    # quickjab imports it when a command runs (after parsing: `quickjab --help` loads no game)
    ran = []
    monkeypatch.setattr(game.command, "run_command", lambda parser, args: ran.append(args.command) or 7)
    assert tools.cli.main(["devices"]) == 7 and ran == ["devices"]

    def raising(exc):
        def func(args):
            raise exc
        return argparse.Namespace(command="play", func=func)

    parser = argparse.ArgumentParser(prog="x")
    assert run_command(parser, raising(InputError("bad.csv: line 3: not a number"))) == 2
    assert run_command(parser, raising(FileNotFoundError(2, "No such file", "gone.npz"))) == 2
    assert run_command(parser, raising(KeyboardInterrupt())) == 130
    assert run_command(parser, argparse.Namespace(command="play", func=lambda args: None)) == 0
    assert capsys.readouterr().err.splitlines() == [
        "quickjab play: bad.csv: line 3: not a number",
        "quickjab play: [Errno 2] No such file: 'gone.npz'",
    ]
    with pytest.raises(ValueError):  # a bug is not input: its traceback shows
        run_command(parser, raising(ValueError("bug")))


def test_a_file_name_with_a_line_break_still_gives_one_line(capsys, tmp_path):
    """The message names the file as it is: a name holding a newline (legal on Linux) split the
    error into two lines, the second without `quickjab`; other breaks str.splitlines() counts
    (\\r, \\x0b, \\x1c, \\u2028...) likewise."""
    from tools.cli import main

    for name in ("new\nline.csv", "cr\rx.csv", "vt\x0bx.csv", "ls\u2028x.csv"):
        path = tmp_path / name
        path.write_text("x")
        assert main(["recognize", str(path), "--templates", str(REPO / "game" / "assets" / "templates.npz")]) == 2
        err = capsys.readouterr().err
        assert len(err.splitlines()) == 1 and err.startswith("quickjab recognize: ") and repr(name)[1:-1] in err, err
