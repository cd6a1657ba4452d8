"""`quickjab bench recognition` runs end to end and prints its columns and the targets line
(no timing asserted)."""

from __future__ import annotations

import re

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
