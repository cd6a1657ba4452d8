"""`quickjab bench recognition` runs end to end and prints its columns and the targets line
(no timing asserted)."""

from __future__ import annotations

import re

import pytest

from engine.recognition import dtw
from tools.cli import main


def test_bench_recognition_table_and_targets(capsys):
    assert main(["bench", "recognition", "--sizes", "13", "--repeat", "1", "--buffer", "8"]) == 0
    out = capsys.readouterr().out
    header = next(line for line in out.splitlines() if line.lstrip().startswith("templates"))
    assert [c.strip() for c in header.split("|")][:7] == ["templates", "scan us", "loop us", "jit us", "auto", "push us", "native us"]
    row = next(line for line in out.splitlines() if line.lstrip().startswith("13 |"))
    assert row.split("|")[4].strip() == dtw.auto_method(13)
    # every target of issue 3 at 13 templates gets a yes/NO verdict
    assert re.search(r"targets: 13 templates: \w+ <= 30 us (yes|NO), >= 10x (yes|NO), push <= 30 us (yes|NO)", out)


def test_bench_recognition_sweep_lists_every_method(capsys):
    assert main(["bench", "recognition", "--sizes", "3", "--repeat", "1", "--buffer", "4", "--sweep"]) == 0
    out = capsys.readouterr().out
    sweep = out.split("us per frame)")[1].strip().splitlines()
    assert len(sweep) == 7 and all("scan" in line and "loop" in line for line in sweep)
    assert all(("jit" in line) == dtw.jit_available() for line in sweep)
    assert all(("native" in line) == dtw.native_available() for line in sweep)


def test_bench_recognition_per_action_sizes_give_push_verdicts(capsys):
    assert main(["bench", "recognition", "--sizes", "2x3", "--repeat", "1", "--buffer", "4"]) == 0
    out = capsys.readouterr().out
    assert any(line.lstrip().startswith("2x3 |") for line in out.splitlines())
    assert main(["bench", "recognition", "--sizes", "13x3", "--repeat", "1", "--buffer", "4"]) == 0
    assert re.search(r"13x3: push <= 40 us (yes|NO), push >= 10x (yes|NO)", capsys.readouterr().out)
    assert main(["bench", "recognition", "--sizes", "many"]) == 2


def test_a_figure_not_measured_is_a_dash_not_nan():
    from tools.bench_recognition import _cell

    assert _cell(float("nan"), 8) == "       -" and _cell(12.345, 8) == "    12.3"


@pytest.mark.parametrize("option, value, said", [
    ("--dim", "0", "0 is out of range: must be between 3 and 60"),
    ("--dim", "-1", "-1 is out of range"),
    ("--dim", "4", "4 is not a multiple of 3 (3 values per sensor)"),
    ("--dim", "61", "61 is out of range"),
    ("--buffer", "0", "0 is out of range: must be between 1 and 6000"),
    ("--buffer", "-2", "-2 is out of range"),
    ("--repeat", "0", "0 is out of range: must be between 1 and 1000"),
    ("--repeat", "-1", "-1 is out of range"),
    ("--repeat", "x", "expected an integer, not 'x'"),
])
def test_out_of_range_numbers_are_one_line(capsys, option, value, said):
    """--dim 0 or 4 and --buffer 0 were tracebacks (the templates, a division by zero), --repeat 0
    printed inf for every figure."""
    with pytest.raises(SystemExit) as exit_:
        main(["bench", "recognition", "--sizes", "3", option, value])
    err = capsys.readouterr().err.strip().splitlines()
    assert exit_.value.code == 2 and len(err) == 1, err
    assert err[0].startswith(f"quickjab bench recognition: argument {option}: {said}"), err


@pytest.mark.parametrize("sizes", ["0", "-2", "2x0", "0x3", "10001", "5000x3"])
def test_sizes_without_templates_or_too_many_are_one_line(capsys, sizes):
    assert main(["bench", "recognition", "--sizes", sizes]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--sizes" in err[0] and "from 1 to 10000 templates" in err[0], err


def test_the_limits_are_the_recognizers():
    from engine.recognition import config, templates
    from tools import bench_recognition

    assert bench_recognition.MAX_FRAMES == config.MAX_FRAMES
    assert bench_recognition.MAX_TEMPLATES == templates.MAX_TEMPLATES


def test_a_dim_of_several_sensors_runs(capsys):
    assert main(["bench", "recognition", "--sizes", "2", "--repeat", "1", "--buffer", "2", "--dim", "9", "--json"]) == 0
    assert '"dim": 9' in capsys.readouterr().out
