"""The virtual player's sensor signals and the synth command."""

from __future__ import annotations

import numpy as np
import pytest

from engine.recording import read_recording
from game.actions import ACTION_NAMES, load_library
from game.virtual_player import PROFILES, QUANTUM_G, RANGE_G, synthesize_action, synthesize_rest
from tools.cli import main

LIB = load_library()


def test_a_trial_at_rest_reads_one_g():
    sig = synthesize_action(LIB["guard"], "experienced", np.random.default_rng(0), rest_before=30)
    mag = np.linalg.norm(sig[:30], axis=-1)
    assert np.allclose(mag.mean(axis=0), 1.0, atol=0.03)
    rest = synthesize_rest(60, LIB["guard"], "experienced", np.random.default_rng(1))
    assert np.allclose(np.linalg.norm(rest, axis=-1).mean(), 1.0, atol=0.03)


def test_readings_are_quantised_clipped_and_shaped():
    sig = synthesize_action(LIB["hook_r"], "experienced", np.random.default_rng(0), 5, 5)
    assert sig.ndim == 3 and sig.shape[1:] == (2, 3)
    assert np.allclose(sig / QUANTUM_G, np.round(sig / QUANTUM_G), atol=1e-6)
    assert np.all(np.abs(sig[:, 0]) <= RANGE_G[0] + 1e-9) and np.all(np.abs(sig[:, 1]) <= RANGE_G[1] + 1e-9)


@pytest.mark.parametrize("name", ["straight_r", "hook_r", "uppercut_r"])
def test_a_right_punch_peaks_at_a_few_g_on_the_wiimote_only(name):
    sig = synthesize_action(LIB[name], "experienced", np.random.default_rng(3))
    dev = np.linalg.norm(sig - sig[:1], axis=-1).max(axis=0)
    assert 1.0 < dev[0] < 7.5  # a few g on the punching hand
    assert dev[1] < 0.5 * dev[0]  # the guard hand moves much less


def test_profiles_vary_tempo_and_the_novice_is_sloppier():
    rng = np.random.default_rng(5)
    lens = {p: [len(synthesize_action(LIB["straight_r"], p, rng)) for _ in range(30)] for p in PROFILES}
    frames = LIB["straight_r"].frames
    assert frames * 0.85 <= min(lens["experienced"]) and max(lens["experienced"]) <= frames * 1.15
    assert np.std(lens["novice"]) > np.std(lens["experienced"])
    a = synthesize_action(LIB["jab" if "jab" in LIB else "straight_l"], "experienced", np.random.default_rng(1))
    b = synthesize_action(LIB["straight_l"], "experienced", np.random.default_rng(2))
    assert not np.array_equal(a, b)  # trials differ
    same = synthesize_action(LIB["straight_l"], "experienced", np.random.default_rng(1))
    assert np.array_equal(a, same)  # and are reproducible from a seed


def test_synth_trials_read_back(tmp_path):
    assert main(["synth", "--player", "experienced", "--trials", "2", "-o", str(tmp_path), "--seed", "4",
                 "--actions", "hook_r,step_back"]) == 0
    files = sorted(tmp_path.rglob("*.csv"))
    assert [f.relative_to(tmp_path).as_posix() for f in files] == [
        "hook_r/1.csv", "hook_r/2.csv", "step_back/1.csv", "step_back/2.csv"]
    rec = read_recording(files[0])
    assert rec.sensors == 2 and set(rec.labels) == {"hook_r"}
    assert np.allclose(np.diff(rec.t), 1 / 60, atol=1e-4)


def test_synth_session_is_labelled_with_rests(tmp_path):
    out = tmp_path / "rec.csv"
    assert main(["synth", "--session", "20", "-o", str(out), "--seed", "2", "--player", "novice"]) == 0
    rec = read_recording(out)
    assert len(rec) == 20 * 60
    labels = rec.labels
    assert "" in labels and set(labels) - {""} <= set(ACTION_NAMES)
    assert len(set(labels) - {""}) >= 3
    rest = np.array([lab == "" for lab in labels])
    assert np.allclose(np.linalg.norm(rec.accel[rest], axis=-1).mean(), 1.0, atol=0.05)


def test_synth_bad_input_is_one_line(capsys, tmp_path):
    assert main(["synth", "--trials", "1", "-o", str(tmp_path), "--actions", "haymaker"]) == 2
    assert "haymaker" in capsys.readouterr().err
    for empty in (",", ""):  # synthesized all 13, as if --actions had not been given
        assert main(["synth", "--trials", "1", "-o", str(tmp_path / "e"), "--actions", empty]) == 2
        assert "names no action" in capsys.readouterr().err and not (tmp_path / "e").exists()


def test_experienced_trials_are_told_apart_by_dtw():
    """The signals carry the action: nearest-template DTW (whole trials) on fresh experienced
    trials picks the right action for almost all of them."""
    dtw_ndim = pytest.importorskip("dtaidistance.dtw_ndim")
    from tools.synth import synth_trials

    templates = synth_trials(LIB, "experienced", 2, np.random.default_rng(10))
    tests = synth_trials(LIB, "experienced", 2, np.random.default_rng(11))
    right = total = 0
    for name, trials in tests.items():
        for t in trials:
            best = min(
                (dtw_ndim.distance(t, tr) / (len(t) + len(tr)), n)
                for n, trs in templates.items() for tr in trs
            )
            right += best[1] == name
            total += 1
    assert right / total >= 0.9


def test_stream_rests_then_performs_on_demand():
    from game.virtual_player import VirtualPlayerStream

    vp = VirtualPlayerStream(LIB, "experienced", np.random.default_rng(0))
    rest = np.array([vp.next_frame() for _ in range(30)])
    assert vp.performing is None
    assert np.allclose(np.linalg.norm(rest, axis=-1).mean(), 1.0, atol=0.03)
    n = vp.perform("straight_r")
    assert vp.performing == "straight_r"
    sig = np.array([vp.next_frame() for _ in range(n)])
    assert np.linalg.norm(sig[:, 0] - rest[0, 0], axis=-1).max() > 1.0  # the Wiimote hand punches
    vp.next_frame()
    assert vp.performing is None


def test_shipped_templates_are_rebuilt_by_the_synth_command(tmp_path):
    """game/assets/templates.npz comes from `quickjab synth --templates` (seed 0, 3 experienced
    trials per action): rebuilding gives the same templates, so a change to the actions or the
    virtual player that would leave the shipped file stale fails here."""
    pytest.importorskip("engine.recognition")
    from pathlib import Path

    shipped = Path(__file__).resolve().parents[2] / "game" / "assets" / "templates.npz"
    if not shipped.exists():
        pytest.skip("no shipped templates in this tree")
    out = tmp_path / "t.npz"
    assert main(["synth", "--templates", "-o", str(out)]) == 0
    with np.load(out, allow_pickle=False) as a, np.load(shipped, allow_pickle=False) as b:
        # optional keys added since the shipped file was written; these trials hold no rest
        newer = set(a.files) - set(b.files)
        assert newer <= {"rest_noise"} and all(np.isnan(a[k]) for k in newer)
        assert set(b.files) <= set(a.files)
        for k in b.files:
            if a[k].dtype.kind == "f":
                assert np.allclose(a[k], b[k], rtol=0, atol=1e-9, equal_nan=True), k
            else:
                assert np.array_equal(a[k], b[k]), k


def test_the_sensor_frame_is_left_handed_x_to_the_wearers_left():
    """engine/sensors/axes.py and the serial docs rest on this: with y (the forearm) pointing
    forward and z up, the game's sensor x points to the wearer's left (the world's -x: x right,
    y up, z forward), so a right-handed IMU chip maps onto it by a mirror (`?axes=-x,y,z`)."""
    from game.virtual_player import sensor_frames

    rot = sensor_frames(np.array([[[0.0, 0.0, 1.0], [0.0, 0.0, 1.0]]]), np.zeros(2))
    np.testing.assert_allclose(rot[0, 0], [[-1, 0, 0], [0, 0, 1], [0, 1, 0]], atol=1e-12)


def test_synth_moves_a_trial_of_its_folder_aside_and_says_so(tmp_path, capsys):
    """The tester: `synth --trials 2 --actions hook_r -o DIR` replaced a player's DIR/hook_r/1.csv
    without a word. Moved aside (to 1.csv.old: `templates build` reads every *.csv of the folder
    as a trial) and said in one line; a file that holds just what would be written (a second run
    of the same seed) stays, and is not copied."""
    mine = tmp_path / "hook_r" / "1.csv"
    mine.parent.mkdir()
    mine.write_text("my own trial\n")
    argv = ["synth", "--trials", "2", "--actions", "hook_r", "--seed", "1", "-o", str(tmp_path)]
    assert main(argv) == 0
    err = capsys.readouterr().err
    assert (tmp_path / "hook_r" / "1.csv.old").read_text() == "my own trial\n"
    assert err.count("\n") == 1 and str(mine) in err and "1.csv.old" in err, err
    assert read_recording(mine).labels[0] == "hook_r"
    assert main(argv) == 0 and capsys.readouterr().err == ""  # the same bytes again: nothing moved
    assert sorted(p.name for p in (tmp_path / "hook_r").iterdir()) == ["1.csv", "1.csv.old", "2.csv"]
    assert sorted(p.name for p in (tmp_path / "hook_r").glob("*.csv")) == ["1.csv", "2.csv"]  # the trials read


def test_synth_session_moves_an_existing_recording_aside(tmp_path, capsys):
    out = tmp_path / "rec.csv"
    out.write_text("a take of mine\n")
    (tmp_path / "rec-old.csv").write_text("an older one\n")
    assert main(["synth", "--session", "2", "-o", str(out)]) == 0
    assert capsys.readouterr().err == f"{out} was not empty: moved to {tmp_path / 'rec-old-2.csv'}\n"
    assert (tmp_path / "rec-old-2.csv").read_text() == "a take of mine\n"
    assert (tmp_path / "rec-old.csv").read_text() == "an older one\n"
    assert len(read_recording(out)) == 120
