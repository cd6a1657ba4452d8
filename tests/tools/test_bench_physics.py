"""`quickjab bench physics` runs end to end and reports its figures (no timing asserted)."""

from __future__ import annotations

import json

import pytest

from tools.cli import main


def test_bench_physics_json(capsys):
    assert main(["bench", "physics", "--steps", "5", "--repeats", "1", "--json"]) == 0
    fig = json.loads(capsys.readouterr().out)
    assert fig["particles"] == 34 and fig["iterations"] == 4
    for name in ("apart", "clinch", "apart_gauss_seidel", "clinch_gauss_seidel"):
        assert fig["step_us"][name]["min"] > 0
    assert fig["step_us"]["apart"]["contacts_per_step"] == 0
    assert fig["step_us"]["clinch"]["contacts_per_step"] > 0  # the clinch does touch
    assert fig["peer_pure_python_step_us"]["min"] > 0
    assert set(fig["relaxation"]) == {"jacobi", "gauss_seidel", "pure_python"}


def test_bench_physics_table(capsys):
    assert main(["bench", "physics", "--steps", "5", "--repeats", "1"]) == 0
    out = capsys.readouterr().out
    assert "World.step" in out and "pure-Python" in out


def test_bench_physics_rejects_zero_steps():
    with pytest.raises(SystemExit) as exit_:  # argparse's range, as every bench count (test_bench_ranges.py)
        main(["bench", "physics", "--steps", "0"])
    assert exit_.value.code == 2
