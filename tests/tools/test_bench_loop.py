"""`quickjab bench loop` prints sound figures (small sizes here; no timing assertions)."""

from __future__ import annotations

import json

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
