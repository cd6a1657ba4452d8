"""A recording cut mid-write (its last row without a line end, in a file `quickjab record` wrote)
has that row left out by read_recording, which notes it (Recording.notes, Source.file_notes). record,
one-player play, recognize and the trial readers said the note; train, two-player play, scope,
bridge emulate --replay and replays through wiimote-emu:// said nothing."""

from __future__ import annotations

from pathlib import Path

import pytest

from tools.cli import main

ROWS = "".join(f"{i / 100:.6f},0.1234,0.1234,1.1234,0.0,0.01,0.99,\n" for i in range(120))
HEADLESS = ["--headless", "--frames", "3"]


@pytest.fixture
def cut(tmp_path, monkeypatch) -> Path:
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "xdg"))
    path = tmp_path / "cut.csv"
    path.write_text("# rate_hz: 100\n# recorded_from: demo://\nt,rx,ry,rz,lx,ly,lz,label\n" + ROWS[:-4])  # cut in '0.99'
    return path


def said(capsys, argv: list[str]) -> list[str]:
    try:
        rc = main(argv)
    except SystemExit as exc:
        rc = exc.code
    err = capsys.readouterr().err
    assert rc == 0, err
    return [line for line in err.splitlines() if "the last row has no line end" in line]


def note(prefix: str, path: Path) -> list[str]:
    return [f"{prefix}{path}:123: the last row has no line end (the recording was cut mid-write): left out"]


def test_train_says_the_note(cut, capsys):
    assert said(capsys, ["train", *HEADLESS, "--source", f"replay://{cut}"]) == note("quickjab train: ", cut)


def test_two_player_play_says_which_player(cut, capsys):
    argv = ["play", *HEADLESS, "--players", "2", "--source", "keyboard://", "--source2", f"replay://{cut}"]
    assert said(capsys, argv) == note("quickjab play: player 2 (--source2): ", cut)


def test_scope_says_the_note(cut, capsys):
    assert said(capsys, ["scope", *HEADLESS, "--source", f"replay://{cut}"]) == note("quickjab scope: ", cut)


def test_wiimote_emu_carries_the_note(cut, capsys, tmp_path):
    assert said(capsys, ["play", *HEADLESS, "--source", f"wiimote-emu://{cut}"]) == note("quickjab play: ", cut)
    out = tmp_path / "out.csv"
    assert said(capsys, ["record", "--source", f"wiimote-emu://{cut}?seconds=0.3", "-o", str(out), "--seconds", "2"]) == note("quickjab record: ", cut)


def test_bridge_emulate_replay_says_the_note(cut, capsys):
    argv = ["bridge", "emulate", "--replay", str(cut), "--seconds", "0.2", "--quiet"]
    assert said(capsys, argv) == note("quickjab bridge: ", cut)


def test_the_trial_readers_say_the_note_as_their_command(cut, capsys, tmp_path):
    # they said it without the `quickjab <command>: ` every other command puts before it
    trials = tmp_path / "trials" / "jab"
    trials.mkdir(parents=True)
    (trials / "a.csv").write_text(cut.read_text())
    whole = cut.read_text() + "99,\n"  # the cut row made whole again, with its line end
    for name in ("b.csv", "c.csv"):
        (trials / name).write_text(whole)
    tpl = tmp_path / "t.npz"
    assert said(capsys, ["templates", "build", str(tmp_path / "trials"), "-o", str(tpl)]) == note("quickjab templates: ", trials / "a.csv")
    argv = ["evaluate", str(tmp_path / "trials"), "--templates", str(tpl), "--mains", "6"]
    assert said(capsys, argv) == note("quickjab evaluate: ", trials / "a.csv")
