"""`quickjab bench loop` prints sound figures (small sizes here; no timing assertions)."""

from __future__ import annotations

import json

import pytest

from tools.cli import main


def test_bench_loop_json(capsys):
    assert main(["bench", "loop", "--steps", "300", "--frames", "6", "--json"]) == 0
    fig = json.loads(capsys.readouterr().out)
    assert fig["loop_overhead_us_per_step"] > 0 and fig["bare_call_us_per_step"] > 0
    assert fig["overhead_ratio_vs_bare_call"] > 1  # the loop does more than a bare call
    late = fig["deadline_lateness_us"]
    assert late["frames"] == 6 and 0 <= late["median"] <= late["p99"] <= late["max"]


def test_bench_loop_table(capsys):
    assert main(["bench", "loop", "--steps", "200", "--frames", "3"]) == 0
    out = capsys.readouterr().out
    assert "loop overhead per step" in out and "lateness" in out


@pytest.mark.parametrize("argv, said", [
    (["bench", "loop", "--steps", "0"], "argument --steps: 0 is out of range: must be between 1 and 10000000"),
    (["bench", "loop", "--frames", "0"], "argument --frames: 0 is out of range: must be between 1 and 216000"),
])
def test_counts_out_of_range_are_one_line(capsys, argv, said):
    """--steps 0 was a division by zero, --frames 0 an IndexError: tracebacks."""
    with pytest.raises(SystemExit) as exit_:
        main(argv)
    err = capsys.readouterr().err.strip().splitlines()
    assert exit_.value.code == 2 and len(err) == 1, err
    assert err[0].startswith(f"quickjab {' '.join(argv[:2])}: {said}"), err
