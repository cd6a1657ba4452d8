"""Templates: building methods, round-trip files, corrupt files, mirroring."""

from __future__ import annotations

import numpy as np
import pytest

from engine.errors import InputError
from engine.recognition import TemplateFileError, Templates
from engine.recognition.templates import (
    MAX_FILE_BYTES,
    MAX_TEMPLATES,
    average_eq1,
    dba,
    rest_gravity,
    trial_rest,
    trim_rest,
)

G = np.array([0.0, 0.0, 1.0, 0.0, -1.0, 0.0])


def trial(rng, axis=0, amp=3.0, n=24, lead=6):
    x = np.tile(G, (lead + n + 6, 1))
    x[lead : lead + n, axis] += amp * np.sin(np.linspace(0, 2 * np.pi, n)) + rng.normal(0, 0.02, n)
    return x


@pytest.fixture
def trials():
    rng = np.random.default_rng(0)
    return {"hook_r": [trial(rng, 0) for _ in range(3)], "straight_l": [trial(rng, 4) for _ in range(3)]}


@pytest.mark.parametrize("method", ["trials", "average", "dba"])
def test_methods_build_one_or_more_templates_per_action(trials, method):
    t = Templates.from_trials(trials, method=method)
    assert t.action_names == ["hook_r", "straight_l"]
    assert len(t) == (6 if method == "trials" else 2)
    assert t.dim == 6 and np.all(np.isfinite(t.thresholds)) and np.all(t.thresholds > 0)


def test_trim_keeps_the_motion_and_a_short_lead_in():
    rng = np.random.default_rng(1)
    x = trial(rng, lead=20)
    trimmed, onset = trim_rest(x)
    assert len(trimmed) < len(x) and 0 < onset <= 4
    assert np.abs(trimmed[onset:, 0]).max() == pytest.approx(np.abs(x[:, 0]).max())


def with_tail(x, n=20):
    """`x` cut with a long lead-in: the tail of the motion before it (the hand returning, turned
    30 degrees and shaking) comes first."""
    t = np.arange(n)
    tail = np.tile(G, (n, 1))
    tail[:, :3] = [0.0, np.sin(np.pi / 6), np.cos(np.pi / 6)]
    tail[:, 1] += 0.6 * np.exp(-t / 6) * np.sin(t / 2)  # gentler than the punch
    return np.vstack([tail, x])


def test_a_trial_cut_with_the_previous_motions_tail_keeps_its_rest():
    rng = np.random.default_rng(3)
    x = trial(rng, lead=15)
    g, rest = trial_rest(with_tail(x))
    np.testing.assert_allclose(g, G, atol=0.02)  # the rest before the punch, not the tail's first frames
    assert rest >= 20
    trimmed, onset = trim_rest(with_tail(x))
    clean, clean_onset = trim_rest(x)
    np.testing.assert_array_equal(trimmed[onset:], clean[clean_onset:])  # the same motion ...
    assert onset == clean_onset  # ... and lead-in: nothing of the tail
    built = Templates.from_trials({"hook_r": [with_tail(trial(rng, lead=15)) for _ in range(3)]})
    np.testing.assert_allclose(built.gravity, np.tile(G, (3, 1)), atol=0.02)


def test_the_onset_is_the_motion_after_the_last_rest_not_a_fidget_before_it():
    """A trial cut with a long lead holds a fidget that reaches a tenth of the punch's peak; a
    rest (REST_WINDOW quiet frames) separates them: the template starts at the punch. A wind-up
    whose pause is shorter than a rest stays part of the motion."""
    rng = np.random.default_rng(5)
    punch = trial(rng, lead=0)[:24]

    def with_lead(gap: int) -> np.ndarray:
        fidget = np.tile(G, (12, 1))
        fidget[:, 1] += 0.8 * np.sin(np.linspace(0, np.pi, 12))  # over a tenth of the punch's 3 g
        x = np.vstack([np.tile(G, (10, 1)), fidget, np.tile(G, (gap, 1)), punch, np.tile(G, (6, 1))])
        return x + rng.normal(0, 0.005, x.shape)  # every frame its own: found again below

    for gap, starts_at in ((12, 10 + 12 + 12), (4, 10)):  # a rest before the punch / a wind-up's pause
        x = with_lead(gap)
        trimmed, onset = trim_rest(x)
        at = int(np.flatnonzero(np.all(x == trimmed[onset], axis=1))[0])
        assert abs(at - starts_at) <= 2, (gap, at)


def test_a_trial_that_starts_at_rest_keeps_its_first_frames_as_rest():
    x = trial(np.random.default_rng(4), lead=10)
    g, rest = trial_rest(x)
    assert rest == 0
    np.testing.assert_array_equal(g, rest_gravity(x))


def test_a_hold_inside_a_motion_is_not_its_rest():
    # a block: arms up, held still, and down again, cut without any rest before it
    up = np.linspace(0.0, 1.0, 10)[:, None] * np.array([0.0, 1.5, -0.5, 0.0, 1.5, -0.5])
    hold = np.tile(up[-1], (12, 1))
    down = up[::-1]
    x = G + np.vstack([up, hold, down]) + np.random.default_rng(5).normal(0, 0.01, (32, 6))
    g, rest = trial_rest(x)
    assert rest == 0
    np.testing.assert_array_equal(g, rest_gravity(x))


def test_averages_of_identical_trials_are_the_trial():
    x = np.cumsum(np.random.default_rng(2).normal(size=(15, 3)), axis=0)
    np.testing.assert_allclose(average_eq1([x, x, x]), x)
    np.testing.assert_allclose(dba([x, x]), x)


def test_round_trip_keeps_everything(tmp_path, trials):
    t = Templates.from_trials(trials, method="trials")
    t.meta["player"] = "ann"
    path = tmp_path / "ann.npz"
    t.save(path)
    u = Templates.load(path)
    assert u.actions == t.actions and u.method == t.method and u.feature == t.feature and u.meta == t.meta
    for a, b in zip(u.signals, t.signals, strict=True):
        np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(u.gravity, t.gravity)
    np.testing.assert_array_equal(u.onsets, t.onsets)
    np.testing.assert_array_equal(u.thresholds, t.thresholds)


@pytest.mark.parametrize("content", [b"", b"not a zip at all", b"PK\x03\x04garbage"])
def test_corrupt_file_is_a_clear_error_naming_it(tmp_path, content):
    path = tmp_path / "bad.npz"
    path.write_bytes(content)
    with pytest.raises(TemplateFileError) as err:
        Templates.load(path)
    assert isinstance(err.value, InputError) and "bad.npz" in str(err.value)


def test_wrong_npz_and_missing_file(tmp_path, trials):
    other = tmp_path / "other.npz"
    np.savez(other, x=np.zeros(3))
    with pytest.raises(TemplateFileError, match="other.npz"):
        Templates.load(other)
    t = Templates.from_trials(trials)
    path = tmp_path / "t.npz"
    t.save(path)
    data = dict(np.load(path))
    data["lengths"] = data["lengths"] + 1  # lengths no longer match the data
    with open(path, "wb") as f:
        np.savez(f, **data)
    with pytest.raises(TemplateFileError, match="t.npz"):
        Templates.load(path)
    with pytest.raises(TemplateFileError, match="missing.npz"):
        Templates.load(tmp_path / "missing.npz")


def test_mirror_swaps_hands_flips_x_and_names(trials):
    t = Templates.from_trials(trials)
    m = t.mirrored()
    assert m.actions == [a.replace("_r", "_x").replace("_l", "_r").replace("_x", "_l") for a in t.actions]
    s, ms = t.signals[0], m.signals[0]
    np.testing.assert_allclose(ms[:, 3], -s[:, 0])
    np.testing.assert_allclose(ms[:, 0:3] * [-1, 1, 1], s[:, 3:6])
    back = m.mirrored()
    np.testing.assert_allclose(back.signals[0], s)


def test_bad_trials_are_refused():
    with pytest.raises(ValueError):
        Templates.from_trials({"a": [np.zeros((10, 4))]})
    with pytest.raises(ValueError):
        Templates.from_trials({"a": [np.zeros((10, 3))], "b": [np.zeros((10, 6))]})


def test_a_file_of_more_templates_than_a_player_could_train_is_refused(tmp_path, trials):
    """A million 3-frame templates deflate to 0.5 MB, within the size limit: loaded, they took
    1.7 GB and 47 s to replay 2 s through. The count is checked before any is built."""
    path = tmp_path / "many.npz"
    Templates.from_trials(trials).save(path)
    data = dict(np.load(path))
    n = MAX_TEMPLATES + 1
    data.update(actions=np.array(["jab_r"] * n), lengths=np.full(n, 3), signals=np.tile(data["signals"][:1], (3 * n, 1)),
                gravity=np.tile(data["gravity"][:1], (n, 1)), onsets=np.zeros(n, np.int64), thresholds=np.ones(n))
    with open(path, "wb") as f:
        np.savez_compressed(f, **data)
    with pytest.raises(TemplateFileError, match=f"many.npz: .*{n} templates, at most {MAX_TEMPLATES}"):
        Templates.load(path)
    data.update(actions=data["actions"][:-1], lengths=data["lengths"][:-1], signals=data["signals"][:-3],
                gravity=data["gravity"][:-1], onsets=data["onsets"][:-1], thresholds=data["thresholds"][:-1])
    with open(path, "wb") as f:
        np.savez_compressed(f, **data)
    assert len(Templates.load(path)) == MAX_TEMPLATES


def test_a_file_of_more_signal_than_memory_allows_is_refused_before_it_is_read(tmp_path, trials):
    """13 templates of 400,000 frames (250 MB of signal, 2.5 MB deflated) took 1.4 GB in
    recognize, 5.6 x their size: the limit on what a file declares is 64 MiB (the shipped set is
    under 1 MB)."""
    path = tmp_path / "long.npz"
    Templates.from_trials(trials).save(path)
    data = dict(np.load(path))
    data["signals"] = np.zeros((MAX_FILE_BYTES // 48 + 1, 6))
    with open(path, "wb") as f:
        np.savez_compressed(f, **data)
    with pytest.raises(TemplateFileError, match="long.npz: .*over the 64 MiB limit"):
        Templates.load(path)


def _rewritten(path, **changes):
    data = dict(np.load(path))
    data.update(changes)
    with open(path, "wb") as f:
        np.savez_compressed(f, **data)


def test_complex_signals_are_refused_not_cast(tmp_path, trials, recwarn):
    """astype(float64) dropped the imaginary part with a ComplexWarning (two lines on stderr
    before the command went on as if the file were fine)."""
    path = tmp_path / "complex.npz"
    Templates.from_trials(trials).save(path)
    _rewritten(path, signals=np.load(path)["signals"] + 1j)
    with pytest.raises(TemplateFileError, match="complex.npz: .*signals must hold real numbers, not complex128"):
        Templates.load(path)
    assert not [w for w in recwarn if issubclass(w.category, np.exceptions.ComplexWarning)]


def test_signals_of_no_columns_are_refused_at_load(tmp_path, trials):
    """Signals (frames, 0) and gravity (T, 0) loaded as templates of D = 0, refused only later
    by the command that compared them with a sensor (play's message did not name the file)."""
    path = tmp_path / "d0.npz"
    t = Templates.from_trials(trials)
    t.save(path)
    _rewritten(path, signals=np.zeros((sum(len(s) for s in t.signals), 0)), gravity=np.zeros((len(t), 0)))
    with pytest.raises(TemplateFileError, match=r"d0.npz: .*no values per frame \(D = 0\)"):
        Templates.load(path)


def test_fractional_onsets_are_refused_not_truncated(tmp_path, trials):
    """An onset of 2.7 was read as frame 2. A whole number stored as a float (2.0) is the same
    onset and still loads: the format gives no type for onsets."""
    path = tmp_path / "onsets.npz"
    t = Templates.from_trials(trials)
    t.save(path)
    _rewritten(path, onsets=t.onsets.astype(np.float64))
    np.testing.assert_array_equal(Templates.load(path).onsets, t.onsets)
    _rewritten(path, onsets=t.onsets + 0.7)
    with pytest.raises(TemplateFileError, match=r"onsets.npz: .*onset \d+\.7 is not a whole frame"):
        Templates.load(path)
    _rewritten(path, onsets=t.onsets.astype(str))  # read as numbers by the int64 cast
    with pytest.raises(TemplateFileError, match=r"onsets.npz: .*onsets must hold numbers"):
        Templates.load(path)


@pytest.mark.parametrize(("change", "says"), [
    ({"format": np.array(b"quickjab-templates")}, "bytes"),
    ({"method": np.array(b"trials")}, "method must hold unicode strings"),
    ({"version": np.array(1.5)}, "version must be the integer 1"),
    ({"version": np.array("1")}, "version must be the integer 1"),
    ({"actions": np.array([["a", "b"]])}, "one name per template"),
    ({"meta_values": np.array(["x", "y", "z"])}, "pairs"),
    ({"lengths": np.zeros(0, dtype=int), "signals": np.zeros((0, 6)), "actions": np.zeros(0, dtype="U1"),
      "gravity": np.zeros((0, 6)), "onsets": np.zeros(0, dtype=int), "thresholds": np.zeros(0)}, "no templates"),
    ({"version": None}, "no 'version' array"),
])
def test_a_template_file_out_of_its_format_says_what_is_wrong(tmp_path, trials, change, says):
    """Found by a writer from docs/formats.md alone: bytes strings read as "no format marker",
    versions 1.5 and "1" loaded, and a missing key, unpaired notes or no templates at all gave
    Python's own words ("'version'", "zip() argument 2 is shorter...", "zero-size array...")."""
    good = tmp_path / "good.npz"
    Templates.from_trials(trials).save(good)
    with np.load(good, allow_pickle=False) as z:
        arrays = {k: z[k] for k in z.files}
    for k, v in change.items():
        if v is None:
            del arrays[k]
        else:
            arrays[k] = v
    bad = tmp_path / "bad.npz"
    np.savez(bad, **arrays)
    with pytest.raises(TemplateFileError, match=says) as info:
        Templates.load(bad)
    assert str(bad) in str(info.value)


def test_template_lengths_that_only_add_up_past_int64_are_refused(tmp_path, trials):
    """Four lengths of 2**62 frames and more sum, wrapped in int64, to the file's frame count:
    they passed the check, the signal split into empty templates, and `recognize` ended in a
    traceback (reshape of size 0). No template is longer than the signal data."""
    good = tmp_path / "good.npz"
    Templates.from_trials(trials).save(good)
    with np.load(good, allow_pickle=False) as z:
        arrays = {k: z[k] for k in z.files}
    n = len(arrays["signals"])
    arrays.update(lengths=np.array([2**62, 2**62, 2**62, 2**62 + n], dtype=np.int64), actions=np.array(["a", "b", "c", "d"]),
                  gravity=arrays["gravity"][:1].repeat(4, axis=0), onsets=np.zeros(4, np.int64), thresholds=np.ones(4))
    bad = tmp_path / "wrapped.npz"
    np.savez(bad, **arrays)
    with pytest.raises(TemplateFileError, match="wrapped.npz: .*signal lengths do not match the signal data"):
        Templates.load(bad)


@pytest.mark.parametrize("failure", [OSError(28, "No space left on device"), KeyboardInterrupt()])
def test_a_save_that_fails_halfway_keeps_the_file_it_was_replacing(tmp_path, trials, monkeypatch, failure):
    """`quickjab train` saves the player's templates over their previous set: a full disk or a
    Ctrl-C while writing truncated that set (open(path, "wb") first) and left half a file."""
    path = tmp_path / "mine.npz"
    Templates.from_trials(trials, method="trials").save(path)
    before = path.read_bytes()
    real = np.savez_compressed

    def fails_halfway(f, **arrays):
        real(f, **arrays)
        f.truncate(len(before) // 2)
        raise failure

    monkeypatch.setattr(np, "savez_compressed", fails_halfway)
    with pytest.raises((TemplateFileError, KeyboardInterrupt)):
        Templates.from_trials({"hook_r": trials["hook_r"]}, method="trials").save(path)
    assert path.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["mine.npz"]  # no half-written file left
