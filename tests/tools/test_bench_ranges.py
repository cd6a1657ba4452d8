"""The counts of the bench commands (`bench loop`, `frame`, `graph`, `physics`, `startup`,
`wiimote`, `serial`, `synth`, `recognition`) and of `bridge faults` are checked by argparse: one
line naming the option and its range, exit 2, before anything is imported or run (they were
checked inside the run, in words of their own). Each has an upper end too: `bench wiimote
--seconds 1e12` was a numpy memory error, `bench frame --steps` of a trillion one as well."""

from __future__ import annotations

import pytest

from tools.cli import main


@pytest.mark.parametrize("argv, said", [
    # bench loop's: --steps 0 was a division by zero, --frames 0 an IndexError (tracebacks)
    (["bench", "loop", "--steps", "0"], "argument --steps: 0 is out of range: must be between 1 and 10000000"),
    (["bench", "loop", "--frames", "0"], "argument --frames: 0 is out of range: must be between 1 and 216000"),
    (["bench", "frame", "--steps", "0"], "argument --steps: 0 is out of range: must be between 1 and 216000"),
    (["bench", "frame", "--steps", "1000000000000"], "argument --steps: 1000000000000 is out of range: must be between 1 and 216000"),
    (["bench", "frame", "--repeats", "-1"], "argument --repeats: -1 is out of range: must be between 1 and 100"),
    (["bench", "frame", "--repeats", "101"], "argument --repeats: 101 is out of range: must be between 1 and 100"),
    (["bench", "frame", "--realtime-seconds", "-0.5"], "argument --realtime-seconds: -0.5 is out of range: must be between 0 and 3600"),
    (["bench", "frame", "--realtime-seconds", "1e12"], "argument --realtime-seconds: 1e+12 is out of range: must be between 0 and 3600"),
    (["bench", "frame", "--seed", "-1"], "argument --seed: -1 is out of range: must be between 0 and"),
    (["bench", "frame", "--realtime-seconds", "nan"], "argument --realtime-seconds: expected a finite number, not 'nan'"),
    (["bench", "graph", "--states", "9"], "argument --states: 9 is out of range: must be between 10 and 1000000"),
    (["bench", "graph", "--states", "1000001"], "argument --states: 1000001 is out of range: must be between 10 and 1000000"),
    (["bench", "graph", "--lookups", "0"], "argument --lookups: 0 is out of range: must be between 1 and 1000000"),
    (["bench", "graph", "--lookups", "1000000000000"], "argument --lookups: 1000000000000 is out of range: must be between 1 and 1000000"),
    (["bench", "graph", "--loads", "0"], "argument --loads: 0 is out of range: must be between 1 and 1000"),
    (["bench", "graph", "--loads", "1001"], "argument --loads: 1001 is out of range: must be between 1 and 1000"),
    (["bench", "physics", "--steps", "0"], "argument --steps: 0 is out of range: must be between 1 and 100000"),
    (["bench", "physics", "--repeats", "0"], "argument --repeats: 0 is out of range: must be between 1 and 100"),
    (["bench", "physics", "--iterations", "0"], "argument --iterations: 0 is out of range: must be between 1 and 100"),
    (["bench", "physics", "--iterations", "100000000"], "argument --iterations: 100000000 is out of range: must be between 1 and 100"),
    (["bench", "physics", "--steps", "100001"], "argument --steps: 100001 is out of range: must be between 1 and 100000"),
    (["bench", "physics", "--repeats", "101"], "argument --repeats: 101 is out of range: must be between 1 and 100"),
    (["bench", "startup", "--runs", "0"], "argument --runs: 0 is out of range: must be between 1 and 1000"),
    (["bench", "startup", "--runs", "1001"], "argument --runs: 1001 is out of range: must be between 1 and 1000"),
    (["bench", "wiimote", "--seconds", "1e12"], "argument --seconds: 1e+12 is out of range: must be > 0 and <= 3600"),
    (["bench", "wiimote", "--seconds", "0"], "argument --seconds: 0 is out of range: must be > 0 and <= 3600"),
    (["bench", "wiimote", "--seconds", "inf"], "argument --seconds: expected a finite number, not 'inf'"),
    (["bench", "serial", "--seconds", "3601"], "argument --seconds: 3601 is out of range: must be > 0 and <= 3600"),
    (["bench", "serial", "--rate", "1001"], "argument --rate: 1001 is out of range: must be between 1 and 1000"),
    (["bench", "synth", "--trials", "100001"], "argument --trials: 100001 is out of range: must be between 1 and 100000"),
    (["bench", "recognition", "--repeat", "1001"], "argument --repeat: 1001 is out of range: must be between 1 and 1000"),
    (["bridge", "faults", "--corrupted", "-1"], "argument --corrupted: -1 is out of range: must be between 0 and 100000000"),
    (["bridge", "faults", "--frames", "-1"], "argument --frames: -1 is out of range: must be between 0 and 100000000"),
    (["bridge", "faults", "--events", "100000001"], "argument --events: 100000001 is out of range: must be between 0 and 100000000"),
    (["bridge", "faults", "--seed", "-1"], "argument --seed: -1 is out of range: must be between 0 and"),
])
def test_counts_out_of_range_are_argparse_errors(capsys, argv, said):
    with pytest.raises(SystemExit) as exit_:
        main(argv)
    err = capsys.readouterr().err.strip().splitlines()
    assert exit_.value.code == 2 and len(err) == 1, err
    assert err[0].startswith(f"quickjab {' '.join(argv[:2])}: {said}"), err


def test_a_bench_physics_run_over_its_budget_is_refused_before_it_runs(capsys):
    """Each bound alone allows a run of hours (100 iterations x 100000 steps x 100 repeats): the
    run's size is bounded too, one line and exit 2 before anything is built."""
    assert main(["bench", "physics", "--iterations", "100", "--steps", "100000", "--repeats", "1"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "over 1,000,000" in err, err


def test_a_bench_frame_run_over_its_budget_is_refused_before_it_runs(capsys):
    """--steps and --repeats each allow a long run, together 100 hour-long matches (every
    timed call kept): the run's size is bounded too, one line and exit 2 before anything runs."""
    assert main(["bench", "frame", "--steps", "216000", "--repeats", "4"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "over 648,000" in err, err
