"""The `quickjab` command: --version, --help on every subcommand, record, and bad files giving
one line naming file and line with exit code 2 and no traceback."""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from engine import __version__
from engine.recording import read_recording
from tools.cli import COMMAND_MODULES, build_parser, main

REPO = Path(__file__).resolve().parents[2]


def quickjab(*args: str, cwd: Path | None = None) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": str(REPO), "SDL_VIDEODRIVER": "dummy", "SDL_AUDIODRIVER": "dummy"}
    return subprocess.run([sys.executable, "-m", "tools.cli", *args], cwd=cwd or REPO, env=env,
                          capture_output=True, text=True, timeout=120)


def subcommand_paths(parser: argparse.ArgumentParser, prefix: tuple[str, ...] = ()) -> list[tuple[str, ...]]:
    """Every subcommand, nested ones too (bench loop, ...)."""
    out = []
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                out.append(prefix + (name,))
                out += subcommand_paths(sub, prefix + (name,))
    return out


def test_version():
    r = quickjab("--version")
    assert r.returncode == 0 and r.stdout.strip() == f"quickjab {__version__}"


def test_commands_of_this_issue_are_registered():
    paths = subcommand_paths(build_parser())
    for cmd in [("play",), ("record",), ("scope",), ("profile",), ("bench",), ("bench", "loop")]:
        assert cmd in paths
    assert {"game.play", "tools.record", "tools.scope", "tools.profile", "tools.bench"} <= set(COMMAND_MODULES)


def test_help_on_every_subcommand(capsys):
    paths = subcommand_paths(build_parser())
    assert paths
    for path in [()] + paths:
        with pytest.raises(SystemExit) as exit_:
            main([*path, "--help"])
        assert exit_.value.code == 0, path
        out = capsys.readouterr().out
        assert out.startswith("usage: quickjab") and (not path or path[-1] in out), path


def test_every_command_and_option_says_what_it_is(capsys):
    """The review: `recognize --help` had no description and no word on REC.csv or --templates;
    templates build, bvh info/cut/export, actions list/sheet/author and a few --seed neither."""
    def missing(parser: argparse.ArgumentParser, path: tuple[str, ...]) -> list[str]:
        out = []
        for action in parser._actions:
            if isinstance(action, argparse._SubParsersAction):
                for name, sub in action.choices.items():
                    out += [] if sub.description else [" ".join(path + (name,)) + ": no description"]
                    out += missing(sub, path + (name,))
            elif not isinstance(action, argparse._HelpAction) and not action.help:
                out.append(" ".join(path) + f" {'/'.join(action.option_strings) or action.dest}: no help")
        return out

    assert missing(build_parser(), ()) == []


def test_bench_help_gives_every_target_its_whole_summary():
    """`quickjab bench --help` showed each target's first docstring line: three ended
    mid-sentence ("recognition ... all templates in one", "startup ... (load")."""
    from tools.bench import TARGETS

    def subparsers(parser: argparse.ArgumentParser) -> argparse._SubParsersAction:
        return next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))

    targets = subparsers(subparsers(build_parser("bench")).choices["bench"])
    helps = {choice.dest: choice.help for choice in targets._choices_actions}
    assert set(helps) == set(TARGETS)
    assert all(text.endswith(".") for text in helps.values()), helps


@pytest.mark.parametrize("argv", [
    ["play", "--seed", "-1"],
    ["evaluate", "--folds", "1", "x.csv"],
    ["bench", "loop", "--no-such-option"],
    ["templates", "build"],
    ["bench", "graph", "--seed", "-1", "--graph", str(REPO / "game" / "assets" / "graph.npz")],  # was a numpy traceback
])
def test_a_bad_argument_is_one_line_and_exit_2(capsys, argv):
    with pytest.raises(SystemExit) as exit_:
        main(argv)
    assert exit_.value.code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("quickjab") and "usage" not in err, err


@pytest.mark.parametrize("argv, prog", [
    (["play", "--low-pwer"], "quickjab play"),
    (["bench", "loop", "--no-such-option"], "quickjab bench loop"),
    (["graph", "info", "--graf"], "quickjab graph info"),
])
def test_an_unknown_option_is_named_by_the_command_given_it(capsys, argv, prog):
    """The review: `quickjab play --low-pwer` said `quickjab: unrecognized arguments ... (see
    quickjab --help)`, whose help lists the commands, not play's options."""
    with pytest.raises(SystemExit) as exit_:
        main(argv)
    assert exit_.value.code == 2
    assert capsys.readouterr().err == f"{prog}: unrecognized arguments: {argv[-1]} (see {prog} --help)\n"


@pytest.mark.parametrize("value", ["0", "0.5", "1"])
def test_graph_build_takes_every_opponent_max_its_help_names(value):
    """docs/interaction_graph.md: 1 = pure min-max, 0 = a random opponent (its expectation),
    blends between; 0 rebuilds that graph, so the parser must take it."""
    args = build_parser("graph").parse_args(["graph", "build", "-o", "g.npz", "--opponent-max", value])
    assert args.opponent_max == float(value)


@pytest.mark.parametrize("value", ["-0.1", "1.5", "nan"])
def test_graph_build_refuses_an_opponent_max_outside_0_to_1(capsys, value):
    with pytest.raises(SystemExit) as exit_:  # the parser alone: a value it took would not build a graph here
        build_parser("graph").parse_args(["graph", "build", "-o", "g.npz", "--opponent-max", value])
    assert exit_.value.code == 2
    assert "--opponent-max" in capsys.readouterr().err


def test_no_command_prints_help(capsys):
    assert main([]) == 0
    assert "COMMAND" in capsys.readouterr().out


def test_record_a_replay(tmp_path, shared_data):
    src = shared_data / "punchbuddy" / "right-hook-50-matt-combo-lh-4.csv"
    out = tmp_path / "out.csv"
    r = quickjab("record", "--source", f"replay://{src}?speed=400", "-o", str(out), "--label", "hook_r")
    assert r.returncode == 0, r.stderr
    rec, orig = read_recording(out), read_recording(src)
    assert len(rec) == len(orig) and rec.sensors == 2 and set(rec.labels) == {"hook_r"}
    assert rec.accel == pytest.approx(orig.accel, abs=1e-4)
    assert rec.t[-1] == pytest.approx((orig.t[-1] - orig.t[0]) / 400, abs=1e-4)  # replayed at 400x


BAD = {
    "missing_columns.csv": ("t,rx,ry\n0,1,2\n", 1),
    "text_in_numbers.csv": ("# rate_hz: 60\nt,rx,ry,rz\n0.00,1,2,3\n0.01,1,two,3\n", 4),
    "backwards.csv": ("t,rx,ry,rz\n0.00,1,2,3\n0.02,1,2,3\n0.01,1,2,3\n", 4),
}


@pytest.mark.parametrize("name", sorted(BAD))
def test_bad_files_give_one_line_exit_2_no_traceback(tmp_path, name):
    text, line = BAD[name]
    (tmp_path / name).write_text(text)
    r = quickjab("record", "--source", f"replay://{name}", "-o", "x.csv", cwd=tmp_path)
    assert r.returncode == 2
    assert "Traceback" not in r.stderr
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and f"{name}:{line}:" in lines[0], r.stderr
    assert not (tmp_path / "x.csv").exists()  # nothing written for a source that never opened


@pytest.mark.parametrize("args,words", [
    (("record", "--source", "nosuch://x", "-o", "x.csv"), "nosuch"),
    (("record", "--source", "replay://missing.csv", "-o", "x.csv"), "missing.csv"),
    (("profile", "missing.json"), "missing.json"),
    (("scope", "--headless", "--frames", "1", "--source", "replay://missing.csv"), "missing.csv"),
])
def test_bad_arguments_name_themselves(tmp_path, args, words):
    r = quickjab(*args, cwd=tmp_path)
    assert r.returncode == 2 and "Traceback" not in r.stderr
    assert len(r.stderr.strip().splitlines()) == 1 and words in r.stderr


@pytest.mark.parametrize("users", ["x", ",", "auto", "0"])
def test_evaluate_users_are_refused_in_their_own_words(capsys, users):
    """`--users x` was refused as a main buffer: "expected a positive int or 'auto'"; users take no 'auto'."""
    with pytest.raises(SystemExit) as exit_:
        main(["evaluate", "--uwave", "u", "--users", users])
    assert exit_.value.code == 2
    assert capsys.readouterr().err == (f"quickjab evaluate: argument --users: expected user numbers such as 1-6 or 1,3, "
                                       f"not {users!r} (see quickjab evaluate --help)\n")


def test_unwritable_output_is_one_line(tmp_path, shared_data):
    src = shared_data / "punchbuddy" / "right-hook-50-matt-combo-lh-4.csv"
    (tmp_path / "no").write_text("a file where a folder would be made")
    r = quickjab("record", "--source", f"replay://{src}?speed=100", "-o", str(tmp_path / "no" / "dir" / "x.csv"))
    assert r.returncode == 2 and "Traceback" not in r.stderr and "x.csv" in r.stderr


GOOD_REC = "t,rx,ry,rz,lx,ly,lz,label\n" + "".join(f"{i / 60:.6f},0.01,0.02,1.0,0.0,0.01,0.99,\n" for i in range(60))


def _exit_code(argv: list[str]) -> int:
    """main's exit code, whether it returns it or argparse exits with it (an option's type)."""
    try:
        return main(argv)
    except SystemExit as exc:
        return exc.code


def _same_file_cases(d: Path) -> dict[str, tuple[list[str], Path]]:
    """name -> (argv whose output is one of its inputs, that input)."""
    rec, trial = d / "rec.csv", d / "trials" / "jab" / "1.csv"
    rec.write_text(GOOD_REC)
    trial.parent.mkdir(parents=True)
    trial.write_text(GOOD_REC.replace(",\n", ",jab\n"))
    tpl = d / "t.npz"
    tpl.write_bytes((REPO / "game" / "assets" / "templates.npz").read_bytes())
    bvh = d / "m.bvh"
    bvh.write_text("HIERARCHY\n")  # never read: refused before
    trace = d / "trace"
    trace.write_text('{"traceEvents": []}')
    named_as_plot = d / "trace.svg"  # a trace given a plot's name: --plot writes that very file
    named_as_plot.write_text('{"traceEvents": []}')
    return {
        "recognize-recording": (["recognize", str(rec), "--templates", str(tpl), "-o", str(rec)], rec),
        "recognize-templates": (["recognize", str(rec), "--templates", str(tpl), "-o", str(tpl)], tpl),
        "build-trial": (["templates", "build", str(d / "trials"), "-o", str(trial)], trial),
        "bvh-cut": (["bvh", "cut", str(bvh), "--start", "0", "--end", "1", "--name", "x", "-o", str(bvh)], bvh),
        "record-replay": (["record", "--source", f"replay://{rec}", "--seconds", "0.2", "-o", str(rec)], rec),
        "record-replay-link": (["record", "--source", f"replay://{d / 'link.csv'}", "--seconds", "0.2", "-o", str(rec)], rec),
        "profile-plot": (["profile", str(named_as_plot), "--plot", str(named_as_plot)], named_as_plot),
        "play-screenshot": (["play", "--headless", "--frames", "2", "--templates", str(tpl), "--screenshot", str(tpl)], tpl),
        "scope-trace": (["scope", "--headless", "--frames", "2", "--source", f"replay://{rec}", "--trace", str(rec)], rec),
        "train-screenshot": (["train", "--headless", "--demo", "--frames", "2", "-o", str(tpl), "--screenshot", str(tpl)], tpl),
    }


@pytest.mark.parametrize("name", ["recognize-recording", "recognize-templates", "build-trial", "bvh-cut", "record-replay",
                                  "record-replay-link", "profile-plot", "play-screenshot", "scope-trace", "train-screenshot"])
def test_an_output_that_is_an_input_is_refused_before_it_is_written(tmp_path, capsys, monkeypatch, name):
    """`recognize rec.csv -o rec.csv` emptied the recording, `templates build trials -o
    trials/jab/1.csv` wrote the templates over a trial, `bvh cut a.bvh -o a.bvh` replaced the
    capture with JSON, `record --source replay://a.csv -o a.csv` cut it to its first seconds:
    each exited 0. Now: one line naming both, exit 2, the input as it was. (A screenshot, trace
    or plot over an input of another kind is refused by its kind first, before the command runs.)"""
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "xdg"))
    argv, victim = _same_file_cases(tmp_path)[name]
    (tmp_path / "link.csv").symlink_to(tmp_path / "rec.csv")
    before = victim.read_bytes()
    assert _exit_code(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    said = "is the input" if name in ("recognize-recording", "recognize-templates", "build-trial", "bvh-cut",
                                      "record-replay", "record-replay-link") else "is there and is not"
    assert err[-1].startswith("quickjab") and said in err[-1] and str(victim) in err[-1], err
    assert victim.read_bytes() == before


@pytest.mark.parametrize("argv", [
    ["record", "--source", "demo://?rate=100", "--seconds", "0.8", "-o", "/dev/full"],
    ["templates", "build", "{trials}", "-o", "/dev/full"],
    ["bvh", "export", "--play", "straight_l", "-o", "/dev/full"],
    ["recognize", "{punch}", "--templates", str(REPO / "game" / "assets" / "templates.npz"), "-o", "/dev/full"],
])
def test_a_full_disk_names_the_file_it_could_not_write(tmp_path, capsys, argv):
    """/dev/full is a disk with no room: ENOSPC names no file, and the line was only
    "[Errno 28] No space left on device"."""
    trial = tmp_path / "trials" / "jab" / "1.csv"
    trial.parent.mkdir(parents=True)
    trial.write_text(GOOD_REC.replace(",\n", ",jab\n"))
    punch = tmp_path / "punch.csv"  # a punch: the recognizer has events to write
    punch.write_text("t,rx,ry,rz,lx,ly,lz\n" + "".join(f"{i / 60:.5f},{3 * np.sin(i / 5):.3f},0,1,0,0,1\n" for i in range(60)))
    assert main([a.format(trials=tmp_path / "trials", punch=punch) for a in argv]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1].startswith(f"quickjab {argv[0]}: /dev/full") and "No space left" in err[-1], err


def _file_size_limit() -> None:  # the child: files over 8 KB cannot be written, as on a full disk
    import resource
    import signal

    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # a write past the limit fails with EFBIG instead
    resource.setrlimit(resource.RLIMIT_FSIZE, (8192, 8192))


@pytest.mark.parametrize("argv", [
    ["play", "--headless", "--frames", "2", "--source", "keyboard://", "--screenshot", "{out}.png"],
    ["scope", "--headless", "--frames", "2", "--screenshot", "{out}.png"],
    ["actions", "sheet", "-o", "{out}.png"],
    ["profile", "{trace}", "--plot", "{out}.png"],
])
def test_an_image_that_cannot_be_written_whole_is_an_error_naming_it(tmp_path, argv):
    """pygame.image.save ignores a failed write: on a full disk play, scope and the contact
    sheet said "wrote" and left a truncated PNG (exit 0); matplotlib's error named no file."""
    trace = tmp_path / "t.json"
    trace.write_text('{"traceEvents": [{"ph": "X", "name": "frame", "ts": 0, "dur": 9}]}')
    out = tmp_path / "out"
    env = {**os.environ, "PYTHONPATH": str(REPO), "SDL_VIDEODRIVER": "dummy", "SDL_AUDIODRIVER": "dummy",
           "XDG_DATA_HOME": str(tmp_path / "xdg")}
    r = subprocess.run([sys.executable, "-m", "tools.cli", *(a.format(out=out, trace=trace) for a in argv)], cwd=REPO,
                       env=env, capture_output=True, text=True, timeout=120, preexec_fn=_file_size_limit)
    last = r.stderr.strip().splitlines()[-1]
    assert r.returncode == 2 and "Traceback" not in r.stderr and last.startswith(f"quickjab {argv[0]}: {out}.png"), r.stderr


def test_a_reader_that_goes_away_ends_the_command_quietly(tmp_path):
    # `quickjab recognize ... | head -1`: the pipe closes after the first event, and the command
    # printed "[Errno 32] Broken pipe" and exited 2, as for a bad file. Now it ends quietly, with
    # the status a shell gives a command that SIGPIPE ended
    from engine.recognition import Templates
    from tests.engine.recognition.test_dual_buffer import bump, rest

    rng = np.random.default_rng(0)
    trials = {a: [np.vstack([rest(10), bump(k, 3.0), rest(10)]) + rng.normal(0, 0.02, (44, 3)) for _ in range(3)]
              for k, a in enumerate(("jab", "hook"))}
    Templates.from_trials(trials).save(tmp_path / "t.npz")
    frames = np.vstack([np.vstack([rest(30), bump(k % 2, 3.0)]) for k in range(800)])  # ~200 KB of events: past a pipe's 64 KiB
    rows = "\n".join(f"{i / 60:.4f},{x:.3f},{y:.3f},{z:.3f}" for i, (x, y, z) in enumerate(frames))
    (tmp_path / "rec.csv").write_text("t,rx,ry,rz\n" + rows + "\n")
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    cmd = [sys.executable, "-m", "tools.cli", "recognize", str(tmp_path / "rec.csv"), "--templates", str(tmp_path / "t.npz")]
    proc = subprocess.Popen(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    assert proc.stdout.readline()  # one event, then the reader goes away
    proc.stdout.close()
    _, err = proc.communicate(timeout=120)
    assert err.decode() == "" and proc.returncode == 141


@pytest.mark.parametrize("argv", [
    ["play", "--headless", "--frames", "2", "--size=--"],
    ["play", "--headless", "--frames", "2", "--templates=--"],
    ["play", "--headless", "--frames", "2", "--source=--"],
    ["play", "--headless", "--frames", "2", "--trace=--"],
    ["play", "--headless", "--frames", "2", "--recognizer=--"],
    ["synth", "--session", "2", "-o=--"],
    ["synth", "--session", "2", "-o--"],
    ["bvh", "export", "-o", "out.bvh", "--play=--"],
    ["graph", "info", "--graph=--"],
    ["profile", "trace.json", "--plot=--"],
])
def test_an_option_given_the_value_double_dash_is_refused(capsys, argv):
    """The tester: argparse turns the value `--` into [] without calling `type=`: `play
    --size=--` ended in AttributeError 'list' object has no attribute 'lower', `play --trace=--`
    and `graph info --graph=--` ignored the option. Refused by the parser, as one line, exit 2."""
    with pytest.raises(SystemExit) as exit_:
        main(argv)
    assert exit_.value.code == 2
    err = capsys.readouterr().err
    option = argv[-1].split("=")[0] if "=" in argv[-1] else argv[-1][:2]
    assert err.count("\n") == 1 and f"argument {option}" in err and "expected a value, got '--'" in err, err


def test_actions_author_leaves_an_edited_action_of_its_folder(tmp_path, capsys):
    """The tester: `actions author -o MYDIR` wrote over a hook_r.json someone had edited there.
    Files that hold what would be written are written again; one that differs is left and named
    in one line (moved aside in the folder, it would be a second hook_r the library refuses)."""
    assert main(["actions", "author", "-o", str(tmp_path)]) == 0
    capsys.readouterr()
    edited = tmp_path / "hook_r.json"
    edited.write_text(edited.read_text().replace('"kind": "attack"', '"kind": "defense"'))
    mine = edited.read_text()
    (tmp_path / "guard.json").unlink()
    assert main(["actions", "author", "-o", str(tmp_path)]) == 0
    out, err = capsys.readouterr()
    assert edited.read_text() == mine and (tmp_path / "guard.json").exists()
    assert err.count("\n") == 1 and "hook_r.json" in err and "left 1 file" in err, err
    assert out.startswith("wrote 26 action files")


@pytest.mark.parametrize("argv, written", [
    (["synth", "--templates", "-o", "{out}"], "cut.json"),
    (["templates", "build", "{trials}", "-o", "{out}"], "cut.json"),
    (["recognize", "{rec}", "--templates", str(REPO / "game" / "assets" / "templates.npz"), "-o", "{out}"], "cut.json"),
    (["play", "--headless", "--frames", "2", "--screenshot", "{out}"], "cut.json"),
    (["play", "--headless", "--frames", "2", "--trace", "{out}"], "cut.json"),
    (["scope", "--headless", "--frames", "2", "--trace", "{out}"], "cut.json"),
    (["actions", "sheet", "-o", "{out}"], "cut.json"),
    (["profile", "{trace}", "--plot", "{out}"], "cut.json"),
    (["graph", "build", "--quiet", "-o", "{out}"], "cut.json"),
    (["bvh", "export", "--play", "hook_r", "-o", "{out}"], "cut.json"),
    (["bvh", "export", "--play", "hook_r", "--opponent", "block", "-o", "{out}"], "cut_boxer1.json"),
])
def test_a_derived_output_is_not_written_over_a_file_of_another_kind(tmp_path, capsys, argv, written):
    """The tester: `synth --templates -o cut.json` wrote an .npz over an action JSON, `bvh export`
    and `graph build` replaced any file. An earlier output of the kind is replaced (their job);
    a file plainly of another kind (by its first bytes) is refused in one line, before the work.
    So are `templates build`, `recognize -o`, screenshots, traces, the contact sheet and plots,
    which replaced any file (a recording given by mistake was lost)."""
    inputs = tmp_path / "in"
    _same_file_cases(inputs.mkdir() or inputs)  # a recording, trials and a trace to read
    theirs = tmp_path / written
    theirs.write_text('{"name": "x"}\n')
    argv = [a.format(out=tmp_path / "cut.json", trials=inputs / "trials", rec=inputs / "rec.csv", trace=inputs / "trace")
            for a in argv]
    assert _exit_code(argv) == 2 and theirs.read_text() == '{"name": "x"}\n'
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "is not " in err and str(theirs) in err, err
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted([written, "in"])


def test_a_derived_output_replaces_an_earlier_one_of_its_kind(tmp_path):
    import zipfile

    from engine.npz_files import is_npz_head
    from game.bvh import is_bvh_head

    out = tmp_path / "out.bvh"
    assert main(["bvh", "export", "--play", "hook_r", "-o", str(out)]) == 0
    assert main(["bvh", "export", "--play", "block", "-o", str(out)]) == 0  # its own kind: replaced
    np.savez(tmp_path / "a.npz", x=np.zeros(2))
    zipfile.ZipFile(tmp_path / "empty.zip", "w").close()
    assert is_npz_head((tmp_path / "a.npz").read_bytes()[:64]) and is_npz_head((tmp_path / "empty.zip").read_bytes())
    assert is_bvh_head(out.read_bytes()[:64]) and is_bvh_head(b"\xef\xbb\xbf  hierarchy\n")
    assert not is_npz_head(b'{"name": "x"}') and not is_bvh_head(b'{"name": "x"}')
    from engine.file_kinds import is_events_head, is_image_head, is_plot_head, is_trace_head

    rec, action, bvh = GOOD_REC.encode()[:64], b'{"name": "jab_l", "kind": "attack"}', b"HIERARCHY\nROOT Hips\n"
    for other in (rec, action, bvh, b"PK\x03\x04" + bytes(60)):  # a recording, an action, a BVH, an .npz
        assert not any(is_kind(other) for is_kind in (is_image_head, is_plot_head, is_trace_head, is_events_head))
    assert is_trace_head(b'\xef\xbb\xbf {\n "traceEvents": [') and is_trace_head(b"[]") and not is_trace_head(b'{"event"')
    assert is_events_head(b'{"event": "start"') and not is_events_head(b'{"traceEvents": []}')


@pytest.mark.parametrize("argv, out", [
    (["play", "--headless", "--frames", "2", "--screenshot", "{out}"], "shot.png"),
    (["play", "--headless", "--frames", "2", "--screenshot", "{out}"], "shot.jpg"),
    (["play", "--headless", "--frames", "2", "--screenshot", "{out}"], "shot.bmp"),
    (["play", "--headless", "--frames", "2", "--screenshot", "{out}"], "shot"),  # pygame: TGA
    (["play", "--headless", "--frames", "2", "--trace", "{out}"], "trace.json"),
    (["recognize", "{rec}", "--templates", str(REPO / "game" / "assets" / "templates.npz"), "-o", "{out}"], "ev.jsonl"),
])
def test_a_screenshot_trace_events_or_plot_replaces_an_earlier_one(tmp_path, capsys, argv, out):
    """What each command writes is of the kind its check lets it replace: run twice, the second
    run replaces the first one's file (a check too strict would refuse the command's own output)."""
    inputs = tmp_path / "in"
    _same_file_cases(inputs.mkdir() or inputs)
    if "--plot" in argv:
        pytest.importorskip("matplotlib")
        assert main(["play", "--headless", "--frames", "5", "--trace", str(inputs / "trace")]) == 0  # a loop's trace
    swing = [2.5 * np.sin(np.pi * i / 20) if 60 <= i < 80 else 0.01 for i in range(140)]  # events to write
    (inputs / "rec.csv").write_text("t,rx,ry,rz,lx,ly,lz,label\n" + "".join(
        f"{i / 60:.6f},{x:.4f},0.02,1.0,0.0,0.01,0.99,\n" for i, x in enumerate(swing)))
    argv = [a.format(out=tmp_path / out, rec=inputs / "rec.csv", trace=inputs / "trace") for a in argv]
    for _ in range(2):
        assert main(argv) == 0, capsys.readouterr().err
        assert (tmp_path / out).stat().st_size > 0


def test_a_plot_replaces_an_earlier_one_in_every_format_matplotlib_writes(tmp_path, capsys):
    """The kind check lets each format's own earlier file be replaced (svgz is gzip, avif an ISO
    media file, raw and rgba bare pixels were refused at first); pgf needs LaTeX: left out."""
    pytest.importorskip("matplotlib")
    from matplotlib.backend_bases import FigureCanvasBase

    trace = tmp_path / "t.json"
    assert main(["play", "--headless", "--frames", "5", "--trace", str(trace)]) == 0
    formats = sorted(set(FigureCanvasBase.get_supported_filetypes()) - {"pgf"})
    assert {"png", "svg", "svgz", "pdf", "eps", "raw", "rgba"} <= set(formats)
    for fmt in formats:
        out = tmp_path / f"plot.{fmt}"
        for _ in range(2):
            assert main(["profile", str(trace), "--plot", str(out)]) == 0, (fmt, capsys.readouterr().err)
        assert out.stat().st_size > 0


def test_raw_pixels_replace_only_raw_pixels_and_pgf_without_latex_is_said_first(tmp_path, capsys):
    """.raw and .rgba plots have no head of their own: they replaced anything (a recording named
    rec.raw); a .pgf plot without LaTeX failed after the work."""
    import shutil

    pytest.importorskip("matplotlib")
    from engine.file_kinds import is_pixels_head

    assert is_pixels_head(b"\xff" * 64) and is_pixels_head(b"\x00\xff\x10\x80" * 16)
    assert not any(is_pixels_head(h) for h in (GOOD_REC.encode()[:64], b'{"traceEvents": [', b"PK\x03\x04" + bytes(60),
                                               "é".encode() * 32, b"t,x\n0,\xc3"))  # a character cut by the head's end
    trace = tmp_path / "t.json"
    assert main(["play", "--headless", "--frames", "5", "--trace", str(trace)]) == 0
    rec = tmp_path / "rec.raw"
    rec.write_text(GOOD_REC)
    assert _exit_code(["profile", str(trace), "--plot", str(rec)]) == 2 and rec.read_text() == GOOD_REC
    assert "is there and is not raw pixels" in capsys.readouterr().err
    from matplotlib import rcParams

    if shutil.which(rcParams["pgf.texsystem"]) is None:
        assert _exit_code(["profile", str(trace), "--plot", str(tmp_path / "p.pgf")]) == 2
        assert "needs" in capsys.readouterr().err and not (tmp_path / "p.pgf").exists()
