"""The two-glove punchbuddy set (tools/glove_punches.py): punches found as bursts of one glove,
their onsets on that glove, the file names, and `quickjab evaluate --punchbuddy` on the real
recordings (../shared/data/punchbuddy; skipped when absent)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from engine.frames import recording_frames
from engine.recognition import rules
from engine.recording import Recording, read_recording, write_recording
from tools.evaluate_recognition import stream_onset
from tools.glove_punches import (
    GLOVE_GAP,
    GLOVE_NAME,
    evaluate_gloves,
    glove_bursts,
    glove_files,
    glove_intervals,
)

REPO = Path(__file__).resolve().parents[2]
PEAK = np.array([1.5, 2.5, 4.0, 2.5, 1.5])  # |a| - 1 g of a short punch: >= 1 g on 5 frames, > 3 g on its third


def resting(n: int, seed: int = 0) -> np.ndarray:
    """Two sensors at rest: 1 g along z with 0.02 g of noise."""
    x = np.tile([0.0, 0.0, 1.0, 0.0, 0.0, 1.0], (n, 1))
    return x + np.random.default_rng(seed).normal(0.0, 0.02, x.shape)


def wind_up(x: np.ndarray, sensor: int, at: int, k: int) -> None:
    """The k frames before `at` move away from the rest, 0.4 g on the first and more on every
    next (a ramp: a still stretch would be taken for the rest by `stream_onset`)."""
    x[at - k : at, 3 * sensor] += np.linspace(0.4, 1.0, k)


def punch(x: np.ndarray, sensor: int, at: int, profile: np.ndarray = PEAK) -> None:
    """The sensor's |a| raised by `profile` (g) from frame `at` on (along z, so |a| - 1 is it)."""
    x[at : at + len(profile), 3 * sensor + 2] = 1.0 + profile


def test_glove_bursts_are_the_punches_of_one_sensor_and_close_peaks_merge():
    x = resting(700)
    punch(x, 0, 0)  # at the very start: widening stops at frame 0
    punch(x, 0, 100)
    punch(x, 0, 200, np.array([1.2, 1.5, 2.0, 2.5, 3.5, 5.0, 3.5, 2.0, 1.5, 1.1]))  # a longer one
    punch(x, 0, 400)  # peak at 402 ...
    punch(x, 0, 415)  # ... and at 417: GLOVE_GAP frames apart, one burst
    punch(x, 0, 500)  # peak at 502 ...
    punch(x, 0, 516)  # ... and at 518: one frame further apart, two bursts
    punch(x, 0, 695)  # at the very end: widening stops at the last frame
    punch(x, 1, 300, np.array([0.5, 1.5, 2.5, 2.9, 2.5, 1.5, 0.5]))  # the other glove moves, under the peak bar
    assert 417 - 402 == GLOVE_GAP
    assert glove_bursts(x, 0) == [(0, 5), (100, 105), (200, 210), (400, 420), (500, 505), (516, 521), (695, 700)]
    assert glove_bursts(x, 1) == []
    y = x[:, [3, 4, 5, 0, 1, 2]]  # the same stream with the gloves swapped
    assert glove_bursts(y, 1) == glove_bursts(x, 0) and glove_bursts(y, 0) == []


def test_glove_intervals_onset_is_measured_on_the_punching_glove_alone():
    x = resting(400, seed=1)
    # the right glove (sensor 0) rests, starts to move at frame 190 (a wind-up), bursts at 200
    wind_up(x, 0, 200, 10)
    punch(x, 0, 200)
    # the left glove (sensor 1) is already moving from frame 160 on, under the burst bar
    x[160:230, 3] += 0.6 * np.sin(np.linspace(0, 3 * np.pi, 70))
    ivs, onsets, _ = glove_intervals(x, "hook_l", "straight_r")
    assert ivs == [("straight_r", 200, 205)]
    assert onsets == [190]
    # the same search on both gloves' readings would put it where the left glove started moving
    assert stream_onset(x, 200, 230) < 190


def test_glove_intervals_rest_is_searched_after_the_same_gloves_previous_burst():
    x = resting(300, seed=3)
    x[:115, 3:] = [0.0, 0.0, 1.0]  # the left glove perfectly still before its first punch ...
    punch(x, 1, 115)
    x[120:, 3] += 0.5  # ... and back in another guard after it (with noise)
    wind_up(x, 1, 150, 10)
    punch(x, 1, 150)
    punch(x, 0, 132)  # the right glove punches in between
    ivs, onsets, _ = glove_intervals(x, "hook_l", "hook_r")
    assert ivs == [("hook_l", 115, 120), ("hook_r", 132, 137), ("hook_l", 150, 155)]
    # the second left punch's rest is the new guard, after its glove's own previous burst: not the
    # stiller old guard before that burst (onset 115), and not cut short by the right glove's punch
    assert onsets[2] == 140
    left = x[:, 3:]
    assert stream_onset(left, 150, 180, 0) == 115 and stream_onset(left, 150, 180, 137) != 140


def test_glove_intervals_come_sorted_by_first_frame_left_first_on_a_tie():
    x = resting(900, seed=2)
    left = {100: 4, 300: 12, 500: 7}  # burst frame -> frames of wind-up before it
    right = {50: 9, 200: 3, 500: 15, 700: 6}
    for sensor, bursts in ((1, left), (0, right)):
        for at, k in bursts.items():
            wind_up(x, sensor, at, k)
            punch(x, sensor, at)
    ivs, onsets, _ = glove_intervals(x, "uppercut_l", "hook_r")
    assert ivs == [("hook_r", 50, 55), ("uppercut_l", 100, 105), ("hook_r", 200, 205), ("uppercut_l", 300, 305),
                   ("uppercut_l", 500, 505), ("hook_r", 500, 505), ("hook_r", 700, 705)]
    # each onset stays with its own interval through the sort: its own wind-up's first frame
    lead = {("uppercut_l", a): k for a, k in left.items()} | {("hook_r", a): k for a, k in right.items()}
    assert onsets == [a - lead[(action, a)] for action, a, _ in ivs]


def test_glove_files_maps_names_to_actions_and_skips_other_names(tmp_path):
    names = [
        "right-hook-50-amy-combo-lh-0.csv", "right-cross-20-amy-combo-lj-1.csv", "right-jab-10-bob-combo-lu-2.csv",
        "right-uppercut-5-bob-combo-lc-0.csv", "right-hook-100-amy-combo-lu-10.csv",
        # not the pattern:
        "left-hook-50-amy-combo-rh-0.csv", "right-hook-50-amy-combo-lx-0.csv", "right-hook-50-amy.csv",
        "right-swing-50-amy-combo-lh-0.csv", "right-hook-50-amy-combo-lh-0.txt", "notes.txt",
    ]
    for n in names:
        (tmp_path / n).write_text("")
    got = {p: [(f.name, left, right) for f, left, right in fs] for p, fs in glove_files(tmp_path).items()}
    assert got == {
        "amy": [("right-cross-20-amy-combo-lj-1.csv", "straight_l", "straight_r"),
                ("right-hook-100-amy-combo-lu-10.csv", "uppercut_l", "hook_r"),
                ("right-hook-50-amy-combo-lh-0.csv", "hook_l", "hook_r")],
        "bob": [("right-jab-10-bob-combo-lu-2.csv", "uppercut_l", "straight_r"),
                ("right-uppercut-5-bob-combo-lc-0.csv", "straight_l", "uppercut_r")],
    }
    assert glove_files(tmp_path / "nowhere") == {}


@pytest.fixture(scope="module")
def punchbuddy(shared_data) -> Path:
    root = shared_data / "punchbuddy"
    if not glove_files(root):
        pytest.skip(f"no punchbuddy recordings in {root}")
    return root


def test_real_files_burst_counts_are_within_10_percent_of_their_names(punchbuddy):
    for files in glove_files(punchbuddy).values():
        for f, left, right in files:
            count = int(GLOVE_NAME.fullmatch(f.name)["count"])
            _, frames, _ = recording_frames(read_recording(f))
            ivs, onsets, _ = glove_intervals(frames, left, right)
            for action in (left, right):
                n = sum(iv[0] == action for iv in ivs)
                assert abs(n - count) <= 0.1 * count, (f.name, action, n)
            assert len(onsets) == len(ivs) and all(a - 45 <= o <= a + 30 for o, (_, a, _) in zip(onsets, ivs, strict=True))


def quickjab(*args: str) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": str(REPO), "SDL_VIDEODRIVER": "dummy", "SDL_AUDIODRIVER": "dummy"}
    return subprocess.run([sys.executable, "-m", "tools.cli", *args], cwd=REPO, env=env,
                          capture_output=True, text=True, timeout=300)


def expected_rows(root: Path) -> dict[str, int]:
    """Row name -> punches tested, by the protocols' file rules (each test file's intervals counted)."""
    files = glove_files(root)
    n = {f: len(glove_intervals(recording_frames(read_recording(f))[1], left, right)[0])
         for fs in files.values() for f, left, right in fs}  # by path
    out = {}
    for person, fs in files.items():  # templates from one session, tested on the others it covers
        tested = sum(n[g[0]] for f in fs for g in fs if g is not f and set(g[1:]) <= set(f[1:]))
        if tested:
            out[f"punchbuddy {person} across sessions"] = tested
    for a, train in files.items():
        covered = {act for f in train for act in f[1:]}
        for b, tests in files.items():
            if a != b and any(set(g[1:]) <= covered for g in tests):
                out[f"punchbuddy {a} -> {b}"] = sum(n[g[0]] for g in tests if set(g[1:]) <= covered)
    return out


def test_evaluate_punchbuddy_prints_one_row_per_protocol(punchbuddy):
    r = quickjab("evaluate", "--punchbuddy", str(punchbuddy), "--mains", "6", "--json")
    assert r.returncode == 0, r.stderr
    rows = [json.loads(line) for line in r.stdout.splitlines()]
    expected = expected_rows(punchbuddy)
    assert set(expected) >= {"punchbuddy matt across sessions", "punchbuddy egor -> matt", "punchbuddy matt -> egor"}
    assert {row["set"]: row["n"] for row in rows} == expected
    assert len(rows) == len(expected) and all(row["main"] == 6 and "false_starts" in row for row in rows)


def test_glove_bursts_widened_into_each_other_are_one_punch():
    # two peaks 20 frames apart (more than GLOVE_GAP), the frames between them 1.5 g off: both
    # widen over the same frames, so they are one punch, not the same interval twice
    x = resting(100)
    punch(x, 0, 30)
    x[35:52, 2] = 2.5
    punch(x, 0, 50)
    assert glove_bursts(x, 0) == [(30, 55)]


def amy_session(folder: Path, n: int, punches: bool = True, sensors: int = 2) -> None:
    x = resting(600)
    if punches:
        for at in range(50, 550, 100):
            punch(x, 0, at)
            punch(x, 1, at + 50)
    write_recording(folder / f"right-hook-5-amy-combo-lh-{n}.csv", Recording(np.arange(600) / 60.0, x.reshape(600, 2, 3)[:, :sensors]))


@pytest.mark.parametrize("make", ["missing", "empty", "other files", "one session", "no punches to test", "one glove"])
def test_evaluate_punchbuddy_without_recordings_names_the_folder(tmp_path, make):
    folder = tmp_path / "no-gloves-here"
    if make != "missing":
        folder.mkdir()
    if make == "other files":
        (folder / "left_jab_fast.csv").write_text("t,rx,ry,rz\n0,0,0,1\n")
    if make in ("one session", "no punches to test", "one glove"):  # a file to learn from ...
        amy_session(folder, 0)
    if make == "no punches to test":  # ... and one with no punch to test on
        amy_session(folder, 1, punches=False)
    if make == "one glove":  # ... and one from a single glove
        amy_session(folder, 1, sensors=1)
    r = quickjab("evaluate", "--punchbuddy", str(folder), "--mains", "6")
    assert r.returncode == 2
    assert "no-gloves-here" in r.stderr and "Traceback" not in r.stderr
    assert r.stdout == ""
    if make == "one glove":
        assert "right-hook-5-amy-combo-lh-1.csv: 1 sensor(s)" in r.stderr


def test_real_gloves_first_decisions_name_the_moving_hand(punchbuddy, monkeypatch):
    """Each file holds one kind per hand, so a wrong first decision names the wrong hand: the
    moving-hand rule (rules.MOVING_HAND_RATIO) takes 10 points of them back within a person
    (matt: 73.5 -> 83.5 %) and keeps the final decision within a point (89.7 -> 89.1 %)."""
    def row(name: str) -> dict:
        return evaluate_gloves(punchbuddy, [6])[name][0].row()

    name = "punchbuddy matt across sessions"
    on = row(name)
    monkeypatch.setattr(rules, "MOVING_HAND_RATIO", 0.0)
    off = row(name)
    assert on["first_correct"] >= off["first_correct"] + 0.05
    assert on["final_correct"] >= off["final_correct"] - 0.01


def _without_a_character_rule_on_and_off(punchbuddy, monkeypatch, person: str, rule: str) -> tuple[dict, dict]:
    """`person`'s across-sessions row with no character (--clip-frames 0), with the recognizer's
    `rule` (a method saying whether it applies) as it is, then turned off."""
    from engine.recognition import DualBufferRecognizer

    def row() -> dict:
        return evaluate_gloves(punchbuddy, [6], clip_frames=0)[f"punchbuddy {person} across sessions"][0].row()

    on = row()
    monkeypatch.setattr(DualBufferRecognizer, rule, lambda self: False)
    return on, row()


def test_real_gloves_without_a_character_start_as_many_punches(punchbuddy, monkeypatch):
    """With no character calling character_finished() (--clip-frames 0, as `quickjab recognize`
    replays), a bouncing boxer's decided motion never came to rest and held every punch after it:
    egor's punches started 62.7 %. Ending a motion that has outlasted its action's templates
    (`_outlasted`) starts 88.9 % of them."""
    on, off = _without_a_character_rule_on_and_off(punchbuddy, monkeypatch, "egor", "_outlasted")
    assert on["started"] >= off["started"] + 0.15 and on["final_correct"] >= off["final_correct"] + 0.15


def test_real_gloves_without_a_character_keep_the_other_hands_punch(punchbuddy, monkeypatch):
    """Without a character, matt's decided motion (his gloves never rest) held on over the other
    hand's next punch, which started mid-way or not at all: final 57.4 %. Once the motion has run
    its best template's course, the other hand's launch ends it as it ends the discard
    (`_ran_course`): final 88.9 %."""
    on, off = _without_a_character_rule_on_and_off(punchbuddy, monkeypatch, "matt", "_ran_course")
    assert on["first_correct"] >= off["first_correct"] + 0.15 and on["final_correct"] >= off["final_correct"] + 0.2
