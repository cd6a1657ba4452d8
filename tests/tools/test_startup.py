"""Start-up (issue 14): what a command imports. Each check runs a fresh interpreter and looks at
sys.modules: `import engine.recognition`, `quickjab --help` and `quickjab play` never load numba
or matplotlib; `--help` and `import game` load none of the command modules or numpy; one
command loads its own module only. `quickjab bench startup` prints its figures and verdicts."""

from __future__ import annotations

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


def test_a_command_imports_its_module_only():
    mods = loaded_after("""
        from tools.cli import main
        assert main(["bench", "startup", "--runs", "0"]) == 2  # a clear error before any run
    """)
    assert "tools.bench" in mods and "tools.bench_startup" in mods
    assert not mods & (set(COMMAND_MODULES) - {"tools.bench"})
    assert not top_level(mods) & set(HEAVY)


def test_play_loads_no_numba_or_matplotlib():
    mods = loaded_after("""
        from tools.cli import main
        assert main(["play", "--demo", "--headless", "--frames", "2", "--no-sound"]) == 0
    """)
    assert {"game.play", "game.session", "engine.recognition.dual_buffer"} <= mods
    assert not top_level(mods) & set(HEAVY)
    assert not mods & (set(COMMAND_MODULES) - {"game.play"})


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
