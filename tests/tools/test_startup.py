"""Start-up (issue 14): what a command imports. Each check runs a fresh interpreter and looks at
sys.modules: `import engine.recognition`, `quickjab --help` and `quickjab play` never load numba
or matplotlib; `--help` and `import game` load none of the command modules or numpy; one
command loads its own module only; every command that draws nothing (recognize, templates
build, evaluate, record, devices, bridge, synth, actions list) loads no pygame, numba or
matplotlib, and the `--help` of every command and subcommand none of those nor the evaluation's
modules; `bench --help` and `bench startup` load no other benchmark's dependencies; `train
--demo` never probes for a Wiimote. `quickjab bench startup` prints its figures and verdicts."""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from tools.cli import COMMAND_MODULES, COMMANDS, build_parser, main

REPO = Path(__file__).resolve().parents[2]
HEAVY = ("numba", "matplotlib")
DRAWING = {"pygame", "numba", "matplotlib"}  # what only a command that draws (or plots) may load
# the evaluation's modules: `evaluate` and (trial_files) `templates build` only
EVALUATION = {"tools.evaluate_recognition", "tools.glove_punches", "tools.trial_files"}
# what the benchmarks measure (packages), each imported by its own target's run() only
BENCH_HEAVY = ("engine.recognition.", "engine.physics.", "engine.sensors.wiimote.", "firmware_bridge.",
               "dtaidistance.", "serial.", "game.")


def loaded_after(code: str) -> set[str]:
    """The modules in sys.modules after running `code` in a fresh interpreter."""
    env = {**os.environ, "PYTHONPATH": str(REPO), "SDL_VIDEODRIVER": "dummy", "SDL_AUDIODRIVER": "dummy"}
    env.pop("QUICKJAB_NO_JIT", None)
    script = textwrap.dedent(code) + "\nimport sys, json\nprint('MODULES' + json.dumps(sorted(sys.modules)))\n"
    r = subprocess.run([sys.executable, "-c", script], cwd=REPO, env=env, capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    line = next(x for x in r.stdout.splitlines() if x.startswith("MODULES"))
    return set(json.loads(line[len("MODULES"):]))


def top_level(modules: set[str]) -> set[str]:
    return {m.split(".")[0] for m in modules}


def run_in_fresh(argv: list[str], code: int = 0) -> set[str]:
    """The modules a fresh interpreter has loaded after `quickjab ARGV` returned `code`."""
    return loaded_after(f"""
        from tools.cli import main
        code = main({argv!r})
        assert code == {code}, code
    """)


def bench_heavy(modules: set[str]) -> set[str]:
    """The modules of BENCH_HEAVY's packages among `modules`; `game` and game.command run every
    command (tools/cli.py), so they are not counted."""
    return {m for m in modules if (m + ".").startswith(BENCH_HEAVY)} - {"game", "game.command"}


def test_import_engine_recognition_loads_no_numba_or_matplotlib():
    mods = loaded_after("import engine.recognition\nfrom engine.recognition import dtw\ndtw.IncrementalDTW([__import__('numpy').zeros((4, 3))] * 13)")
    assert "engine.recognition.dual_buffer" in mods  # the check is not vacuous
    assert not top_level(mods) & set(HEAVY)


def test_help_loads_no_command_module_no_numpy_no_numba():
    mods = loaded_after("""
        from tools.cli import main
        try:
            main(["--help"])
        except SystemExit as exc:
            assert exc.code == 0
    """)
    assert "tools.cli" in mods
    assert not top_level(mods) & {*HEAVY, "numpy", "pygame"}
    assert not mods & set(COMMAND_MODULES)
    assert not mods & {"game", "engine.sensors.source"}  # keyboard://'s registration: for a command only


def test_a_command_imports_its_module_only():
    mods = loaded_after("""
        from tools.cli import main
        try:
            main(["bench", "startup", "--runs", "0"])  # argparse's range: a clear error before any run
        except SystemExit as exc:
            assert exc.code == 2, exc.code
        else:
            raise AssertionError("--runs 0 ran")
    """)
    assert "tools.bench" in mods and "tools.bench_startup" in mods
    assert not mods & (set(COMMAND_MODULES) - {"tools.bench"})
    assert not top_level(mods) & DRAWING
    assert not bench_heavy(mods)  # the other targets' dependencies: imported by their run() only


def test_play_loads_no_numba_or_matplotlib():
    mods = loaded_after("""
        from tools.cli import main
        assert main(["play", "--demo", "--headless", "--frames", "2", "--no-sound"]) == 0
    """)
    assert {"game.play", "game.session", "engine.recognition.dual_buffer"} <= mods
    assert not top_level(mods) & set(HEAVY)
    assert not mods & (set(COMMAND_MODULES) - {"game.play"})


def test_play_never_loads_numpy_ma():
    """np.unique and np.percentile import numpy.ma (1.3 MB, 7 ms) on first use: at start-up (the
    graph's phase bins), then inside a game frame (the auto gate's first learning, 30 frames in).
    The game does without both."""
    mods = loaded_after("""
        from tools.cli import main
        assert main(["play", "--demo", "--headless", "--frames", "240", "--no-sound"]) == 0
    """)
    assert "engine.recognition.gate" in mods and "numpy.ma" not in mods


def test_the_auto_gate_never_loads_numpy_ma():
    """Both of the gate's percentiles, the resting noise's (`learn`) and a hand that never rests
    (BUSY_FRAMES over the gate), run without numpy.ma."""
    mods = loaded_after("""
        import types
        import numpy as np
        from engine.recognition.gate import BUSY_FRAMES, NoiseGate
        gate = NoiseGate("auto", types.SimpleNamespace(rest_noise=0.3))
        for k in range(200):
            gate.learn(0.1 + 0.01 * (k % 7))
        learnt = gate.noise_g
        for k in range(10):
            gate.step(np.array([0.0, 0.0, 1.0]), False, False)  # at rest: the gravity
        for k in range(2 * BUSY_FRAMES):  # then never under the gate
            gate.step(np.array([0.8 + 0.4 * np.sin(k / 3), 0.5 * np.cos(k / 5), 1.0]), False, False)
        assert gate.noise_g > learnt, (learnt, gate.noise_g)  # the busy rule raised it
    """)
    assert "numpy.ma" not in mods


def test_train_demo_opens_the_virtual_player_without_looking_for_a_wiimote():
    mods = run_in_fresh(["train", "--demo", "--headless", "--frames", "1", "--actions", "straight_r"])
    assert {"game.training", "game.keyboard_source"} <= mods
    assert not {m for m in mods if m.startswith("engine.sensors.wiimote")}  # no driver, no HID enumeration
    assert not top_level(mods) & set(HEAVY)


def test_devices_lists_wiimotes_without_numpy_or_the_driver():
    # the transport (hidapi enumeration) and the protocol's ids only: the driver, which turns
    # reports into samples with numpy, loads when a wiimote:// source is opened
    mods = run_in_fresh(["devices", "--json"])
    assert {"engine.sensors.wiimote.transport", "serial.tools.list_ports"} <= mods
    assert "numpy" not in top_level(mods)
    assert "engine.sensors.wiimote.driver" not in mods


def test_the_game_opens_the_audio_device_only_for_sound_and_never_the_joystick():
    # pygame.init() opened both for every match (an audio thread mixing silence with --no-sound)
    loaded_after("""
        import pygame
        opened = []

        def spy(module, name):
            real = getattr(module, name)
            setattr(module, name, lambda *a, **k: (opened.append(name if module is pygame else module.__name__), real(*a, **k))[1])

        spy(pygame, "init"), spy(pygame.mixer, "init"), spy(pygame.joystick, "init")
        from tools.cli import main
        assert main(["play", "--demo", "--headless", "--frames", "2"]) == 0
        assert main(["play", "--demo", "--virtual-clock", "--frames", "2", "--no-sound"]) == 0
        assert main(["train", "--demo", "--headless", "--frames", "1", "--actions", "straight_r"]) == 0
        assert opened == [], opened
        assert main(["play", "--demo", "--virtual-clock", "--frames", "2"]) == 0  # with sound
        assert opened == ["pygame.mixer"], opened
    """)


@pytest.fixture(scope="module")
def recognition_files(tmp_path_factory) -> dict[str, Path]:
    """Two actions' trials, their templates and a labelled recording of both (1 sensor)."""
    import numpy as np

    from engine.recording import Recording, write_recording

    root = tmp_path_factory.mktemp("startup")
    g, rng = np.array([0.0, 0.0, 1.0]), np.random.default_rng(0)

    def bump(axis: int) -> np.ndarray:
        x = np.tile(g, (24, 1))
        x[:, axis] += 3.0 * np.sin(np.linspace(0, 2 * np.pi, 24))
        return x

    def write(path: Path, frames: np.ndarray, labels: list[str]) -> None:
        write_recording(path, Recording(np.arange(len(frames)) / 60.0, frames.reshape(-1, 1, 3), labels))

    for action, axis in (("jab", 0), ("upper", 2)):
        (root / "trials" / action).mkdir(parents=True)
        for k in range(3):
            x = np.vstack([np.tile(g, (8, 1)), bump(axis) + rng.normal(0, 0.03, (24, 3)), np.tile(g, (8, 1))])
            write(root / "trials" / action / f"{k}.csv", x, [action] * len(x))
    frames = np.vstack([np.tile(g, (20, 1)), bump(2), np.tile(g, (30, 1)), bump(0), np.tile(g, (30, 1))])
    write(root / "rec.csv", frames, [""] * 20 + ["upper"] * 24 + [""] * 30 + ["jab"] * 24 + [""] * 30)
    assert main(["templates", "build", str(root / "trials"), "-o", str(root / "t.npz")]) == 0
    (root / "empty").mkdir()
    return {"trials": root / "trials", "recording": root / "rec.csv", "templates": root / "t.npz",
            "empty": root / "empty", "out": root}


# Commands that draw nothing, each with {its modules that show it ran} and the evaluation's
# modules it may load; files named by key from recognition_files.
QUIET_COMMANDS = {
    "recognize": (["recognize", "--templates", "{templates}", "{recording}", "-o", "{out}/events.jsonl"], 0,
                  {"engine.recognition.dual_buffer"}, set()),
    "templates build": (["templates", "build", "{trials}", "-o", "{out}/built.npz"], 0,
                        {"engine.recognition.templates"}, {"tools.trial_files"}),
    "evaluate": (["evaluate", "--templates", "{templates}", "{trials}", "{recording}", "--mains", "6"], 0,
                 {"tools.evaluate_recognition"}, {"tools.evaluate_recognition", "tools.trial_files"}),
    "evaluate --punchbuddy": (["evaluate", "--punchbuddy", "{empty}"], 2,  # none there: one line, exit 2
                              {"tools.glove_punches"}, EVALUATION),
    "record": (["record", "--source", "replay://{recording}", "-o", "{out}/recorded.csv", "--seconds", "0.2"], 0,
               {"engine.sensors.replay"}, set()),
    "devices": (["devices", "--json"], 0, {"engine.sensors.wiimote.transport"}, set()),
    "bridge faults": (["bridge", "faults", "--random-mb", "0.01", "--corrupted", "100", "--frames", "300",
                       "--events", "10"], 0, {"firmware_bridge.faults"}, set()),
    "synth": (["synth", "--trials", "1", "--actions", "straight_r", "-o", "{out}/synth"], 0,
              {"game.virtual_player"}, set()),
    "actions list": (["actions", "list"], 0, {"game.actions"}, set()),
}


@pytest.mark.parametrize("name", QUIET_COMMANDS)
def test_a_command_that_draws_nothing_loads_no_pygame_numba_or_matplotlib(name, recognition_files):
    argv, code, ran, evaluation = QUIET_COMMANDS[name]
    files = {k: str(v) for k, v in recognition_files.items()}
    mods = run_in_fresh([a.format(**files) for a in argv], code)
    assert ran <= mods  # the check is not vacuous: the command did its work
    assert not top_level(mods) & DRAWING
    assert mods & EVALUATION == evaluation


def help_paths(command: str) -> list[list[str]]:
    """[command], then every subcommand under it (`templates build`, `bench startup`, ...)."""
    def walk(parser, path):
        yield path
        for action in parser._actions:
            if isinstance(action, argparse._SubParsersAction):
                for name, sub in action.choices.items():
                    yield from walk(sub, [*path, name])

    top = next(a for a in build_parser(command)._actions if isinstance(a, argparse._SubParsersAction))
    return list(walk(top.choices[command], [command]))


def test_help_paths_reach_the_subcommands():
    assert help_paths("templates") == [["templates"], ["templates", "build"]]
    assert ["bench", "startup"] in help_paths("bench") and ["graph", "duel"] in help_paths("graph")


@pytest.mark.parametrize("module", COMMAND_MODULES)
def test_help_of_every_command_and_subcommand_loads_nothing_it_does_not_need(module):
    # one interpreter per command module, which then prints every --help of its commands:
    # whatever any of them loads is in sys.modules at the end
    paths = [p for command, (m, _) in COMMANDS.items() if m == module for p in help_paths(command)]
    mods = loaded_after(f"""
        from tools.cli import main
        for path in {paths!r}:
            try:
                main([*path, "--help"])
            except SystemExit as exc:
                assert exc.code == 0, path
    """)
    assert module in mods
    assert not top_level(mods) & DRAWING
    assert not mods & EVALUATION
    if module == "tools.bench":  # every target's --help, not only `bench --help`
        assert {f"tools.bench_{name}" for name in ("frame", "recognition", "serial", "startup")} <= mods
        assert not bench_heavy(mods)


def test_command_table_matches_what_the_modules_register():
    parser = build_parser()
    sub = next(a for a in parser._actions if a.dest == "command")
    assert list(sub.choices) == list(COMMANDS)
    helps = {a.dest: a.help for a in sub._choices_actions}
    assert helps == {name: help_line for name, (_, help_line) in COMMANDS.items()}


def test_a_mistyped_command_lists_the_commands(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["plya"])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert "invalid choice: 'plya'" in err and "'play'" in err and "'evaluate'" in err


@pytest.mark.slow
def test_bench_startup_prints_figures_and_verdicts(capsys):
    assert main(["bench", "startup", "--runs", "1", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["play"]["wall_min_s"] > 0 and out["import_numpy_pygame"]["rss_max_mb"] > 10
    assert out["play"]["rss_max_mb"] > out["import_numpy_pygame"]["rss_max_mb"]
    assert set(out["targets"]) == {"ratio_median_le_3", "rss_le_120mb"}
    assert set(out["kernels"]) == {"contacts", "stick_project", "dtw_push_row"}  # native or numpy, and why
