"""Gaps between the commands that a new user's walk through the docs found: an output in a
folder not made yet (some commands made it, the others refused), `actions sheet`'s default
file, `graph info --graph`, `bench recognition --json`, `profile ""`, options in `--help` only,
and profile names one file on macOS and Windows."""

from __future__ import annotations

import argparse
import json
import re
from pathlib import Path

import pytest

from tools.cli import build_parser, main

REPO = Path(__file__).resolve().parents[2]
TEMPLATES = REPO / "game" / "assets" / "templates.npz"
REC = "t,rx,ry,rz,lx,ly,lz,label\n" + "".join(  # still, with a labelled stretch for evaluate
    f"{i / 60:.6f},0.01,0.02,1.0,0.0,0.01,0.99,{'straight_l' if 20 <= i < 40 else ''}\n" for i in range(60))
TRACE = '{"traceEvents": [{"ph": "X", "name": "frame", "ts": 0, "dur": 9}, {"ph": "X", "name": "frame", "ts": 16667, "dur": 9}]}'


def _inputs(d: Path) -> dict[str, str]:
    (d / "rec.csv").write_text(REC)
    (d / "t.json").write_text(TRACE)
    return {"rec": str(d / "rec.csv"), "trace": str(d / "t.json"), "tpl": str(TEMPLATES)}


# every command that writes a file its user names, with that file (OUT) in folders not made yet
WRITERS = {
    "record -o": ["record", "--source", "demo://", "--seconds", "0.2", "-o", "OUT.csv"],
    "play --screenshot": ["play", "--headless", "--frames", "2", "--source", "keyboard://", "--screenshot", "OUT.png"],
    "play --trace": ["play", "--headless", "--frames", "2", "--source", "keyboard://", "--trace", "OUT.json"],
    "train --screenshot": ["train", "--headless", "--demo", "--frames", "2", "--screenshot", "OUT.png"],
    "scope --screenshot": ["scope", "--headless", "--frames", "2", "--screenshot", "OUT.png"],
    "scope --trace": ["scope", "--headless", "--frames", "2", "--trace", "OUT.json"],
    "profile --plot": ["profile", "{trace}", "--plot", "OUT.png"],
    "evaluate --plot": ["evaluate", "{rec}", "--templates", "{tpl}", "--mains", "6", "--plot", "OUT.png"],
    "recognize -o": ["recognize", "{rec}", "--templates", "{tpl}", "-o", "OUT.jsonl"],
    "bvh export -o": ["bvh", "export", "--play", "straight_l", "-o", "OUT.bvh"],
    "bvh export --opponent -o": ["bvh", "export", "--play", "straight_l", "--opponent", "guard", "-o", "OUT.bvh"],
    "synth -o": ["synth", "--session", "1", "-o", "OUT.csv"],
    "actions sheet -o": ["actions", "sheet", "-o", "OUT.png"],
    "graph build -o": ["graph", "build", "-o", "OUT.npz", "--states", "10", "--bouts", "2", "--quiet"],
    "bridge emulate --link": ["bridge", "emulate", "--seconds", "0.2", "--quiet", "--link", "OUT"],
}


@pytest.mark.parametrize("name", list(WRITERS))
def test_every_output_in_a_missing_folder_gets_its_folders_made(tmp_path, monkeypatch, capsys, name):
    """synth, templates build and train -o made a missing output folder; record -o, play and
    scope --screenshot / --trace, profile and evaluate --plot, recognize -o, bvh export -o and
    bridge emulate --link refused it ("no directory", or "cannot write" after the work)."""
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "xdg"))
    out = tmp_path / "new" / "deeper" / "out"
    argv = [a.format(**_inputs(tmp_path)).replace("OUT", str(out)) for a in WRITERS[name]]
    try:
        rc = main(argv)
    except SystemExit as exc:  # argparse's refusal
        rc = exc.code
    said = capsys.readouterr()
    assert rc == 0, said.err
    written = list(out.parent.iterdir())
    if name == "bridge emulate --link":  # the link goes with the port at the end: it was announced
        assert f"(link {out})" in said.out + said.err and not written
        return
    assert written and all(p.name.startswith("out") and p.is_file() for p in written), written


@pytest.mark.parametrize("name", ["record -o", "play --trace", "scope --screenshot", "profile --plot", "bridge emulate --link",
                                  "graph build -o"])
def test_an_output_under_a_file_is_one_line_before_the_work(tmp_path, monkeypatch, capsys, name):
    """What cannot be made (a file where a folder would go) is still said at once, in one line,
    before a device is opened or a match played: refused with the arguments, the command never run."""
    import game.command

    def no_work(*args, **kwargs):
        raise AssertionError(f"{name}: the command ran before its output was refused")

    monkeypatch.setattr(game.command, "run_command", no_work)  # what runs a parsed command (tools/cli.py)
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "xdg"))
    (tmp_path / "plain").write_text("x")
    out = tmp_path / "plain" / "sub" / "out"
    argv = [a.format(**_inputs(tmp_path)).replace("OUT", str(out)) for a in WRITERS[name]]
    with pytest.raises(SystemExit) as exit_:
        main(argv)
    err = capsys.readouterr().err.strip().splitlines()
    assert exit_.value.code == 2 and len(err) == 1, err
    assert f"{tmp_path / 'plain'} is not a directory" in err[0] and "connected" not in err[0], err


def test_actions_sheet_writes_its_default_file_in_the_current_folder(tmp_path, monkeypatch, capsys):
    """The default was docs/img/actions.png under wherever the command ran: run elsewhere than
    the repository, it made docs/img/ there. Now actions.png here, as templates build's
    templates.npz; the repository's figure is `-o docs/img/actions.png`, as docs/motion.md says."""
    monkeypatch.chdir(tmp_path)
    assert main(["actions", "sheet"]) == 0
    assert (tmp_path / "actions.png").stat().st_size > 0
    assert not (tmp_path / "docs").exists()
    assert "wrote actions.png" in capsys.readouterr().out


def test_graph_info_takes_the_graph_as_graph_duel_does(tmp_path, capsys):
    graph = REPO / "game" / "assets" / "graph.npz"
    assert main(["graph", "info", "--graph", str(graph), "--json"]) == 0
    by_option = json.loads(capsys.readouterr().out)
    assert main(["graph", "info", str(graph), "--json"]) == 0  # the positional as before
    assert json.loads(capsys.readouterr().out) == by_option and by_option["states"] > 0
    assert main(["graph", "info", "--graph", str(graph)]) == 0
    assert capsys.readouterr().out.startswith(f"{graph}: ")
    assert main(["graph", "info", str(graph), "--graph", str(graph)]) == 0  # the same file twice: fine
    capsys.readouterr()
    assert main(["graph", "info", str(graph), "--graph", str(tmp_path / "other.npz")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("quickjab graph: ") and "--graph" in err[0] and "other.npz" in err[0], err


def test_bench_recognition_json(capsys):
    """The other benchmarks have --json (one JSON object on stdout, nothing else); this one had none."""
    assert main(["bench", "recognition", "--sizes", "3,2x3", "--repeat", "1", "--buffer", "4", "--json"]) == 0
    fig = json.loads(capsys.readouterr().out)  # the whole of stdout is the JSON
    assert fig["buffer_frames"] == 4 and fig["dim"] == 6
    assert [s["size"] for s in fig["sizes"]] == ["3", "2x3"]
    first = fig["sizes"][0]
    assert first["templates"] == 3 and first["per_action"] == 1 and first["push_us"] > 0
    assert first["auto"] in ("scan", "loop", "jit", "native") and first[f"{first['auto']}_us"] > 0
    assert fig["sizes"][1]["templates"] == 6 and fig["sizes"][1]["per_action"] == 3
    assert "sweep_us" not in fig  # only with --sweep
    assert main(["bench", "recognition", "--sizes", "13", "--repeat", "1", "--buffer", "4", "--json"]) == 0
    fig = json.loads(capsys.readouterr().out)
    assert set(fig["targets"]) == {"13 templates"}
    assert all(isinstance(v, bool) for v in fig["targets"]["13 templates"].values())


def test_profile_of_an_empty_path_says_it_is_empty(capsys):
    """Refused by argparse now, as every command's empty path is (tests/tools/test_empty_paths.py)."""
    with pytest.raises(SystemExit) as exit_:
        main(["profile", ""])
    assert exit_.value.code == 2
    assert capsys.readouterr().err == "quickjab profile: argument TRACE.json: the path is empty (see quickjab profile --help)\n"


DOCS = [REPO / "README.md", *sorted((REPO / "docs").glob("*.md")), *sorted((REPO / "firmware_bridge").glob("*.md"))]


def _options(parser: argparse.ArgumentParser, prefix: tuple[str, ...] = ()):
    """(command words, option strings) of every option of every (sub)command."""
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                yield from _options(sub, (*prefix, name))
        elif action.option_strings and not isinstance(action, (argparse._HelpAction, argparse._VersionAction)):
            yield prefix, action.option_strings


def test_every_option_of_every_command_is_in_the_docs():
    """Options that were in `--help` only (bench recognition --dim, soak --render-every, graph
    build --bouts, ...): each is named in a section of the docs that names its command too."""
    sections = [s for f in DOCS for s in re.split(r"(?m)^#+ ", f.read_text(encoding="utf-8"))]
    missing = []
    for words, strings in _options(build_parser()):
        command = re.compile(r"(?<![\w-])" + re.escape(" ".join(words)) + r"(?![\w-])")
        option = re.compile(r"(?<![\w-])(" + "|".join(map(re.escape, strings)) + r")(?![\w-])")
        if not any(command.search(s) and option.search(s) for s in sections):
            missing.append(f"{' '.join(words)} {strings[-1]}")
    assert not missing, missing


@pytest.mark.parametrize("name", ["con", "NUL", "Com1", "lpt9", "aux", "prn"])
def test_a_windows_device_name_is_no_profile(tmp_path, monkeypatch, capsys, name):
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "xdg"))
    for argv in (["train", "--reset", "--profile", name],
                 ["play", "--headless", "--frames", "1", "--source", "keyboard://", "--profile", name]):
        assert main(argv) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and f"--profile {name!r}" in err[0] and "reserved" in err[0], err


def test_a_new_profile_differing_only_in_case_from_one_saved_is_refused(tmp_path, monkeypatch, capsys):
    """`--profile Ana` beside a saved ana.npz is that very file on macOS and Windows: train would
    replace ana's moves (and --reset delete them), play would load them."""
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "xdg"))
    from game.session import synthesized_templates
    from game.userdata import profile_templates_path

    ana = profile_templates_path("ana")
    ana.parent.mkdir(parents=True)
    synthesized_templates(trials=1).save(ana)
    for argv in (["train", "--reset", "--profile", "Ana"],
                 ["train", "--headless", "--demo", "--frames", "2", "--profile", "ANA"],
                 ["play", "--headless", "--frames", "1", "--source", "keyboard://", "--profile", "Ana"],
                 ["play", "--headless", "--frames", "1", "--players", "2", "--source", "keyboard://",
                  "--source2", "keyboard://", "--profile2", "aNa"]):
        assert main(argv) == 2, argv
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and "'ana'" in err[0] and "case" in err[0], (argv, err)
    assert ana.exists() and [p.name for p in ana.parent.iterdir()] == ["ana.npz"]
    # the saved profile by its own name keeps working, and so does another name
    assert main(["play", "--headless", "--frames", "1", "--source", "keyboard://", "--profile", "ana"]) == 0
    assert main(["play", "--headless", "--frames", "1", "--source", "keyboard://", "--profile", "ben"]) == 0
    assert main(["train", "--reset", "--profile", "ana"]) == 0
    assert not ana.exists()
