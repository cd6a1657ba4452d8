"""`quickjab bench synth`: its table, and --json as the other benchmarks have it (one JSON object
on stdout, nothing else), with the table's figures (no timing asserted)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from tools.cli import main

REPO = Path(__file__).resolve().parents[2]
SMALL = ["--trials", "2", "--steps", "30", "--repeats", "2"]


def run_cli(args: list[str], tmp_path) -> subprocess.CompletedProcess:
    """In a process of its own: stdout is all of it (pygame's greeting would be there too)."""
    env = {"XDG_DATA_HOME": str(tmp_path), "PATH": "/usr/bin:/bin", "SDL_VIDEODRIVER": "dummy", "SDL_AUDIODRIVER": "dummy"}
    return subprocess.run([sys.executable, "-m", "tools.cli", "bench", "synth", *args], cwd=REPO,
                          capture_output=True, text=True, env=env, timeout=300)


def test_bench_synth_json_is_the_whole_of_stdout(tmp_path):
    r = run_cli([*SMALL, "--action", "straight_l", "--json"], tmp_path)
    assert r.returncode == 0, r.stderr
    fig = json.loads(r.stdout)
    assert fig["action"] == "straight_l" and fig["action_frames"] > 0
    assert (fig["trials"], fig["steps"], fig["repeats"]) == (2, 30, 2)
    assert set(fig["trial_ms"]) == set(fig["trial_faster_than_performing"]) == {"experienced", "novice"}
    for f in fig["trial_ms"].values():
        assert 0 < f["min"] <= f["median"]
    assert set(fig["step_us"]) == {"boxers", "physics", "hits"}
    for f in fig["step_us"].values():
        assert 0 < f["min"] <= f["median"]
    medians = sum(f["median"] for f in fig["step_us"].values())
    assert abs(fig["whole_step_us"] - medians) < 1e-6 * medians
    assert abs(fig["frame_share_percent"] - fig["whole_step_us"] / (1e6 / 60) * 100) < 1e-9 * fig["frame_share_percent"]
    s = fig["step_us"]
    assert abs(fig["motion_over_physics"] - (s["boxers"]["median"] + s["hits"]["median"]) / s["physics"]["median"]) < 1e-9


def test_bench_synth_table_and_a_bad_action(tmp_path):
    r = run_cli(SMALL, tmp_path)
    assert r.returncode == 0, r.stderr
    assert "one hook_r trial" in r.stdout and "whole step" in r.stdout and "motion layer / physics:" in r.stdout
    r = run_cli([*SMALL, "--action", "moonwalk", "--json"], tmp_path)
    assert r.returncode == 2 and r.stdout == "" and r.stderr.strip().splitlines() == ["quickjab bench: unknown action 'moonwalk'"]


def test_counts_out_of_range_are_one_line(capsys):
    """--trials 0 was a division by zero, --repeats 0 an empty min(): tracebacks."""
    for option, value, said in (("--trials", "0", "between 1 and 100000"), ("--steps", "-3", "between 1 and 1000000"),
                                ("--repeats", "0", "between 1 and 1000")):
        with pytest.raises(SystemExit) as exit_:
            main(["bench", "synth", option, value])
        err = capsys.readouterr().err.strip().splitlines()
        assert exit_.value.code == 2 and len(err) == 1, err
        assert err[0].startswith(f"quickjab bench synth: argument {option}: {value} is out of range: must be {said}"), err
