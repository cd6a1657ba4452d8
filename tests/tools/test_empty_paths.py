"""An empty path is refused by every command that takes one, in one line naming the command and
the argument, exit 2, before any work: Path("") is ".", so `recognize ""` said the current folder
was no recording, `templates build ""` read the current folder as trials and `graph info ""`
showed the shipped graph as if it had been named."""

from __future__ import annotations

import pytest

from tools.cli import main

# (command line with the empty path, how the error names the argument)
EMPTY = {
    "play --templates": (["play", "--headless", "--frames", "1", "--templates", ""], "--templates"),
    "play --graph": (["play", "--headless", "--frames", "1", "--graph", ""], "--graph"),
    "play --screenshot": (["play", "--headless", "--frames", "1", "--screenshot", ""], "--screenshot"),
    "play --trace": (["play", "--headless", "--frames", "1", "--trace", ""], "--trace"),
    "train -o": (["train", "--headless", "--demo", "--frames", "1", "-o", ""], "-o/--output"),
    "train --screenshot": (["train", "--headless", "--demo", "--frames", "1", "--screenshot", ""], "--screenshot"),
    "record -o": (["record", "--source", "demo://", "--seconds", "0.1", "-o", ""], "-o/--output"),
    "devices PATH": (["devices", ""], "PATH"),
    "scope --screenshot": (["scope", "--headless", "--frames", "1", "--screenshot", ""], "--screenshot"),
    "scope --trace": (["scope", "--headless", "--frames", "1", "--trace", ""], "--trace"),
    "profile TRACE": (["profile", ""], "TRACE.json"),
    "profile --plot": (["profile", "t.json", "--plot", ""], "--plot"),
    "bench graph --graph": (["bench", "graph", "--graph", ""], "--graph"),
    "bench frame --templates": (["bench", "frame", "--templates", ""], "--templates"),
    "bench frame --graph": (["bench", "frame", "--graph", ""], "--graph"),
    "synth -o": (["synth", "--session", "1", "-o", ""], "-o/--output"),
    "soak --graph": (["soak", "--graph", ""], "--graph"),
    "soak --templates": (["soak", "--templates", ""], "--templates"),
    "bvh info": (["bvh", "info", ""], "FILE.bvh"),
    "bvh cut FILE": (["bvh", "cut", "", "--start", "0", "--end", "1", "--name", "x", "-o", "x.json"], "FILE.bvh"),
    "bvh cut -o": (["bvh", "cut", "x.bvh", "--start", "0", "--end", "1", "--name", "x", "-o", ""], "-o/--output"),
    "bvh export -o": (["bvh", "export", "--play", "straight_l", "-o", ""], "-o/--output"),
    "actions list --dir": (["actions", "list", "--dir", ""], "--dir"),
    "actions sheet -o": (["actions", "sheet", "-o", ""], "-o/--output"),
    "actions sheet --dir": (["actions", "sheet", "--dir", ""], "--dir"),
    "actions sheet --add": (["actions", "sheet", "--add", ""], "--add"),
    "actions author -o": (["actions", "author", "-o", ""], "-o/--output"),
    "graph build -o": (["graph", "build", "-o", ""], "-o/--output"),
    "graph info": (["graph", "info", ""], "graph"),
    "graph info --graph": (["graph", "info", "--graph", ""], "--graph"),
    "graph duel --graph": (["graph", "duel", "--graph", ""], "--graph"),
    "bridge emulate --replay": (["bridge", "emulate", "--seconds", "0.1", "--replay", ""], "--replay"),
    "bridge emulate --link": (["bridge", "emulate", "--seconds", "0.1", "--link", ""], "--link"),
    "templates build": (["templates", "build", ""], "TRIALS_DIR|REC.csv"),
    "templates build -o": (["templates", "build", "trials", "-o", ""], "-o/--output"),
    "recognize": (["recognize", "", "--templates", "t.npz"], "REC.csv"),
    "recognize --templates": (["recognize", "r.csv", "--templates", ""], "--templates"),
    "recognize -o": (["recognize", "r.csv", "--templates", "t.npz", "-o", ""], "-o/--output"),
    "evaluate": (["evaluate", ""], "INPUT"),
    "evaluate, a second input": (["evaluate", "a.csv", ""], "INPUT"),
    "evaluate --templates": (["evaluate", "a.csv", "--templates", ""], "--templates"),
    "evaluate --train": (["evaluate", "a.csv", "--train", ""], "--train"),
    "evaluate --uwave": (["evaluate", "--uwave", ""], "--uwave"),
    "evaluate --phone-punches": (["evaluate", "--phone-punches", ""], "--phone-punches"),
    "evaluate --punchbuddy": (["evaluate", "--punchbuddy", ""], "--punchbuddy"),
    "evaluate --plot": (["evaluate", "a.csv", "--plot", ""], "--plot"),
}


@pytest.mark.parametrize("name", list(EMPTY))
def test_an_empty_path_is_one_line_naming_the_command_and_the_argument(tmp_path, monkeypatch, capsys, name):
    monkeypatch.chdir(tmp_path)  # nothing a refused command might still write lands in the repository
    argv, argument = EMPTY[name]
    with pytest.raises(SystemExit) as exit_:
        main(argv)
    said = capsys.readouterr()
    err = said.err.strip().splitlines()
    assert exit_.value.code == 2 and said.out == "" and len(err) == 1, (said.out, err)
    command = " ".join(argv[:2] if argv[0] in ("bench", "bvh", "actions", "graph", "bridge", "templates") else argv[:1])
    assert err[0].startswith(f"quickjab {command}: argument {argument}: the path is empty"), err
    assert list(tmp_path.iterdir()) == []

