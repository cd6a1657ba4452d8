"""The automatic gate, the back-dated onset, the early start that a switch corrects or a
`reject` calls off, and the grip-invariant feature (issue: decisions within 100 ms of the true
onset, across sessions)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from engine.recognition import DualBufferRecognizer, Templates, gate, rules
from engine.recognition import dual_buffer as db
from engine.recognition.gate import percentile
from engine.recognition.templates import features, grip_features, representative_trials

G = np.array([0.0, 0.0, 1.0])


def rest(n: int, sigma: float = 0.0, rng: np.random.Generator | None = None) -> np.ndarray:
    x = np.tile(G, (n, 1))
    return x if sigma == 0 else x + (rng or np.random.default_rng(0)).normal(0.0, sigma, x.shape)


def bump(axis: int, amp: float, n: int = 24) -> np.ndarray:
    x = np.tile(G, (n, 1))
    x[:, axis] += amp * np.sin(np.linspace(0, np.pi, n))
    return x


def run(rec: DualBufferRecognizer, frames: np.ndarray) -> list[dict]:
    out = []
    for f in frames:
        out.extend(rec.push(f))
    return out


@pytest.fixture(scope="module")
def templates() -> Templates:
    rng = np.random.default_rng(0)
    trials = {
        name: [np.vstack([rest(30, 0.01, rng), bump(axis, 3.0) + rng.normal(0, 0.02, (24, 3)), rest(10, 0.01, rng)]) for _ in range(3)]
        for name, axis in (("jab", 0), ("upper", 2))
    }
    return Templates.from_trials(trials)


def test_templates_measure_the_rest_before_the_trials(templates, tmp_path):
    # 30 resting frames with 0.01 g noise per axis before every trial: a quiet sensor
    assert 0.005 < templates.rest_noise < 0.06
    path = tmp_path / "t.npz"
    templates.save(path)
    assert Templates.load(path).rest_noise == pytest.approx(templates.rest_noise)


def test_an_older_template_file_without_rest_noise_still_loads(templates, tmp_path):
    path, old = tmp_path / "new.npz", tmp_path / "old.npz"
    templates.save(path)
    with np.load(path, allow_pickle=False) as z:
        keys = {k: z[k] for k in z.files if k != "rest_noise"}
    with open(old, "wb") as f:
        np.savez_compressed(f, **keys)
    loaded = Templates.load(old)
    assert np.isnan(loaded.rest_noise) and len(loaded) == len(templates)
    assert DualBufferRecognizer(loaded).noise_g == db.AUTO_START_G  # the paper's gate until it has seen rest
    shipped = Templates.load(Path(__file__).resolve().parents[3] / "game" / "assets" / "templates.npz")
    assert np.isnan(shipped.rest_noise)  # synthesized trials hold no rest before the motion


@pytest.mark.parametrize("sigma", [0.01, 0.3])
def test_auto_gate_learns_the_resting_noise(templates, sigma):
    rng = np.random.default_rng(7)
    rec = DualBufferRecognizer(templates)  # noise_g="auto" is the default
    assert rec.auto_gate
    # two seconds of rest: the templates' quiet rest sets the first gate, so noisy frames may open
    # it before the gate has learned (a motion that matches nothing is rejected; never a start)
    first = run(rec, rest(120, sigma, rng))
    assert "start" not in [e["event"] for e in first]
    if sigma == 0.01:
        assert first == [] and rec.noise_g == db.AUTO_MIN_G  # a quiet sensor opens at a few tenths of a g
    else:
        # |a - g| of 0.3 g per axis reaches ~0.75 g at its 90th percentile: the gate sits above it
        assert 1.2 < rec.noise_g <= db.AUTO_MAX_G
    assert run(rec, rest(120, sigma, rng)) == []  # from then on the noise opens nothing
    if sigma == 0.3:  # where a fixed gate at the quiet level keeps opening on the noise alone
        fixed = DualBufferRecognizer(templates, noise_g=db.AUTO_MIN_G)
        events = run(fixed, rest(240, sigma, np.random.default_rng(7)))
        assert events or fixed.state == "active"
    # the same gentle punch (0.8 g) is a motion on the quiet sensor only
    rec.push(G + np.array([0.8, 0.0, 0.0]))
    assert (rec.state == "active") == (sigma == 0.01)


def test_auto_gate_is_frozen_after_the_first_motion(templates):
    rng = np.random.default_rng(3)
    rec = DualBufferRecognizer(templates)
    run(rec, rest(60, 0.01, rng))
    gate = rec.noise_g
    run(rec, bump(0, 3.0))
    run(rec, rest(200, 0.3, rng))  # the hand's returns between punches are not rest
    assert rec.noise_g == gate


@pytest.mark.parametrize("rests_now_and_then", [False, True])
def test_auto_gate_rises_when_the_hand_never_drops_under_it(templates, rests_now_and_then):
    # learnt at rest, frozen by the first motion, then a hand that sways 0.4-1.0 g away from
    # rest for BUSY_FRAMES + 10 frames (a boxer bouncing on the feet): the gate rises to AUTO_K x
    # the sway's BUSY_QUANTILE percentile; with one frame at rest every 500 frames it stays
    rng = np.random.default_rng(4)
    rec = DualBufferRecognizer(templates)
    run(rec, rest(60, 0.01, rng))
    run(rec, bump(0, 3.0))
    low = rec.noise_g
    n = gate.BUSY_FRAMES + 10
    sway = rest(n)
    sway[:, 1] += 0.7 + 0.3 * np.sin(np.arange(n) * 0.4)
    if rests_now_and_then:
        sway[::500] = G
    run(rec, sway)
    if rests_now_and_then:
        assert rec.noise_g == low
    else:
        act = np.abs(0.7 + 0.3 * np.sin(np.arange(gate.BUSY_FRAMES) * 0.4))
        assert low < 0.5 and rec.noise_g == pytest.approx(gate.AUTO_K * np.percentile(act, gate.BUSY_QUANTILE), rel=0.05)


def noisy_templates_with_a_wind_up(rng: np.random.Generator) -> tuple[Templates, np.ndarray]:
    """Templates trained on a noisy sensor (rest noise 0.15 g: a gate near 0.8 g) whose punches
    start with a gentle 0.5 g wind-up; and that wind-up."""
    wind_up = rest(20)
    wind_up[:, 0] += 0.5
    trials = {  # the sensor's noise on every frame, the wind-up's too
        name: [np.vstack([rest(30, 0.15, rng), wind_up + rng.normal(0.0, 0.15, wind_up.shape), bump(axis, 8.0), rest(10)]) for _ in range(3)]
        for name, axis in (("jab", 0), ("upper", 2))
    }
    return Templates.from_trials(trials), wind_up


def test_templates_are_cut_again_at_the_gate_learnt_from_the_rest():
    # Trained on a noisy sensor (a gate near 0.8 g), played on a quiet one (the gate learns 0.3 g):
    # the live motion's onset is at its gentle 0.5 g wind-up, so the templates must start there
    # too, as if the recognizer had been built at the learnt gate.
    rng = np.random.default_rng(5)
    noisy, wind_up = noisy_templates_with_a_wind_up(rng)
    rec = DualBufferRecognizer(noisy, main=6, adapt=0)
    assert rec.noise_g > 0.6
    built = rec.template_lengths.copy()
    run(rec, rest(120, 0.01, rng))
    assert rec.noise_g == db.AUTO_MIN_G
    events = run(rec, np.vstack([wind_up, bump(0, 8.0), rest(30)]))
    at_learnt_gate = DualBufferRecognizer(noisy, noise_g=db.AUTO_MIN_G, adapt=0).template_lengths
    assert list(rec.template_lengths) == list(at_learnt_gate)
    assert (rec.template_lengths >= built).all() and rec.template_lengths.sum() > built.sum()  # wind-up frames in
    assert [e["action"] for e in events if e["event"] == "start"] == ["jab"]


def test_a_recut_keeps_the_adopted_motions_and_cuts_the_trained_ones_as_at_that_gate():
    # A motion adopted (adaptation), then the gate moves (forced here: a session's gate freezes at
    # its first start) and the next onset recuts: the trained templates are those of a recognizer
    # built at the new gate, the adopted one is the live motion as it was adopted.
    rng = np.random.default_rng(6)
    noisy, _ = noisy_templates_with_a_wind_up(rng)
    rec = DualBufferRecognizer(noisy, main=6, adapt=3)
    run(rec, np.vstack([rest(120, 0.01, rng), bump(0, 8.0), rest(40)]))
    assert rec._is_adapted.sum() == 1  # the jab was adopted
    adopted = [src.copy() for src, a in zip(rec.dtw.sources, rec._is_adapted, strict=True) if a]
    rec.gate.noise_g = 0.9  # as if learnt again
    run(rec, np.vstack([bump(2, 8.0), rest(40)]))
    trained = [src for src, a in zip(rec.dtw.sources, rec._is_adapted, strict=True) if not a]
    at_gate = DualBufferRecognizer(noisy, noise_g=0.9, adapt=0).dtw.sources
    assert len(trained) == len(at_gate) and all(np.array_equal(a, b) for a, b in zip(trained, at_gate, strict=True))
    still = [src for src, a in zip(rec.dtw.sources, rec._is_adapted, strict=True) if a]
    assert any(np.array_equal(adopted[0], s) for s in still)
    at_first_gate = DualBufferRecognizer(noisy, noise_g=db.AUTO_MIN_G, adapt=0).dtw.sources
    assert any(len(a) != len(b) for a, b in zip(at_gate, at_first_gate, strict=True))  # the recut changed them


def test_start_counts_main_frames_from_where_the_motion_left_the_rest(templates, monkeypatch):
    # a slow rise: 0.1 g more each frame, so a 1.0 g gate opens 9 frames after 0.1 g
    ramp = np.tile(G, (30, 1))
    ramp[:, 0] += np.minimum(np.arange(1, 31) * 0.1, 3.0)
    frames = np.vstack([rest(20), ramp, bump(0, 3.0)[12:], rest(30)])
    events = run(DualBufferRecognizer(templates, noise_g=1.0, main=6), frames)
    start = next(e for e in events if e["event"] == "start")
    monkeypatch.setattr(gate, "ONSET_FRACTION", 10.0)  # no back-dating: the onset is the gate's frame
    plain = next(e for e in run(DualBufferRecognizer(templates, noise_g=1.0, main=6), frames) if e["event"] == "start")
    gate_open = plain["onset_frame"]
    assert gate_open >= 20 + 9  # the signal reaches 1 g 9 frames into the rise
    assert plain["frame"] == gate_open + 5
    # back-dated by up to BACKDATE_MAX frames, towards where the rise passed 0.3 g (20 + 2; the
    # gravity estimate has followed the slow rise a little, so a frame or so later)
    assert max(20 + 2, gate_open - db.BACKDATE_MAX) <= start["onset_frame"] <= gate_open - 5
    assert max(start["onset_frame"] + 5, gate_open) <= start["frame"] < plain["frame"]


def test_a_slow_rising_punch_starts_when_the_main_buffer_fills(templates, monkeypatch):
    # The jab three times slower than its templates: still rising when the main buffer fills, it
    # needs only RISING_RATIO of the templates' early peak and starts on that frame; the plain
    # energy bar (ENERGY_RATIO) held it 4 frames more.
    slow = np.vstack([rest(30), bump(0, 3.0, 72), rest(30)])
    start = next(e for e in run(DualBufferRecognizer(templates, noise_g=0.3, main=6), slow) if e["event"] == "start")
    assert start["action"] == "jab" and start["frame"] == start["onset_frame"] + 5
    monkeypatch.setattr(rules, "RISING_RATIO", db.ENERGY_RATIO)
    held = next(e for e in run(DualBufferRecognizer(templates, noise_g=0.3, main=6), slow) if e["event"] == "start")
    assert held["frame"] >= start["frame"] + 3


def test_a_flick_that_has_peaked_needs_the_whole_energy_bar(templates, monkeypatch):
    # Up to a third of the jab's peak in 3 frames, then falling: when the main buffer fills it is
    # no longer rising, so the lower bar does not apply and nothing starts. A plain bar as low as
    # RISING_RATIO starts a jab on it.
    flick = np.tile(G, (15, 1))
    flick[:3, 0] += np.sin(np.linspace(0, np.pi / 2, 3))
    flick[3:, 0] += np.cos(np.linspace(0, np.pi / 2, 12))
    frames = np.vstack([rest(30), flick, rest(30)])
    assert not [e for e in run(DualBufferRecognizer(templates, noise_g=0.3, main=6), frames) if e["event"] == "start"]
    monkeypatch.setattr(rules, "ENERGY_RATIO", db.RISING_RATIO)
    assert [e["action"] for e in run(DualBufferRecognizer(templates, noise_g=0.3, main=6), frames) if e["event"] == "start"] == ["jab"]


def test_the_energy_bar_is_the_gentlest_trial_of_the_action():
    # Two strong jab trials (3 g) and a gentle one (1.2 g): a 0.9 g jab that has already peaked
    # when the main buffer fills is as strong as the gentle trial allows (0.4 x 1.2 g) and starts;
    # against the strong trials' bar (0.4 x 3 g) nothing started.
    rng = np.random.default_rng(1)

    def trial(m: np.ndarray) -> np.ndarray:
        return np.vstack([rest(30, 0.01, rng), m + rng.normal(0, 0.02, m.shape), rest(10, 0.01, rng)])

    tm = Templates.from_trials({"jab": [trial(bump(0, 3.0)), trial(bump(0, 3.0)), trial(bump(0, 1.2))],
                                "upper": [trial(bump(2, 3.0)) for _ in range(3)]})
    rec = DualBufferRecognizer(tm, noise_g=0.3, adapt=0)
    jab = rec.action_names.index("jab")
    lo, hi = rec._action_starts[jab], rec._action_ends[jab]
    assert rec._action_bar[jab] == pytest.approx(rec._peak_act[lo:hi, 0].min()) == pytest.approx(1.2, abs=0.1)
    flick = np.tile(G, (15, 1))
    flick[:3, 0] += 0.9 * np.sin(np.linspace(0, np.pi / 2, 3))
    flick[3:, 0] += 0.9 * np.cos(np.linspace(0, np.pi / 2, 12))
    frames = np.vstack([rest(30), flick, rest(30)])
    assert [e["action"] for e in run(rec, frames) if e["event"] == "start"] == ["jab"]
    strong = DualBufferRecognizer(tm, noise_g=0.3, adapt=0)
    strong._action_bar = np.maximum.reduceat(strong._peak_act[:, 0], strong._action_starts)
    assert not [e for e in run(strong, frames) if e["event"] == "start"]


def test_a_wrong_early_start_is_switched_or_called_off():
    rng = np.random.default_rng(5)
    # "swing": a gentle 0.8 g wind-up over 20 frames, then a 4 g blow; "poke": a short 0.8 g
    # push and back on another axis.
    wind = np.tile(G, (20, 1))
    wind[:, 1] += 0.8 * np.sin(np.linspace(0, np.pi / 2, 20))
    blow = bump(1, 4.0)
    blow[:, 1] = np.maximum(blow[:, 1], 0.8 + G[1])
    swing = np.vstack([wind, blow])
    poke = bump(0, 0.8, 14)
    tm = Templates.from_trials({
        "swing": [np.vstack([rest(10), swing + rng.normal(0, 0.02, swing.shape), rest(10)]) for _ in range(3)],
        "poke": [np.vstack([rest(10), poke + rng.normal(0, 0.02, poke.shape), rest(10)]) for _ in range(3)],
    })
    # the wind-up alone, then the hand rests: it starts as a swing (its early frames match and are
    # as strong as the swing's own first frames), but never comes near the swing's blow: called off
    events = run(DualBufferRecognizer(tm, noise_g=0.3), np.vstack([rest(30), wind, wind[::-1], rest(30)]))
    kinds = [(e["event"], e["action"]) for e in events]
    assert kinds[0] == ("start", "swing")
    assert kinds[-1] == ("reject", "swing") and events[-1]["called_off"] is True
    assert "end" not in [k for k, _ in kinds]
    # the call-off ends the motion (the recognizer is idle): a character that aborts its clip
    # then (the game's young clip, PlayerController) owes it no `character_finished()`, which
    # would find nothing to end or discard
    rec = DualBufferRecognizer(tm, noise_g=0.3)
    for f in np.vstack([rest(30), wind, wind[::-1], rest(30)]):
        if any(e.get("called_off") for e in rec.push(f)):
            break
    else:
        raise AssertionError("not called off")
    assert rec.state == "idle"
    rec.character_finished()
    assert rec.state == "idle" and rec.push(G) == []
    # the whole swing: started and ended as a swing, never called off
    events = run(DualBufferRecognizer(tm, noise_g=0.3), np.vstack([rest(30), swing, rest(30)]))
    assert [(e["event"], e["action"]) for e in events if e["event"] in ("start", "end")] == [("start", "swing"), ("end", "swing")]
    assert not any(e.get("called_off") for e in events)


def test_a_wind_up_that_pauses_goes_on_as_one_motion(monkeypatch):
    # A swing's wind-up, the hand back under the gate for 10 frames (more than null_frames), then
    # the blow: one motion, started once on the wind-up and ended as a swing. Without the pause
    # rule the null signal called the wind-up off and the blow started a second action.
    rng = np.random.default_rng(5)
    wind = np.tile(G, (20, 1))
    wind[:, 1] += 0.8 * np.sin(np.linspace(0, np.pi / 2, 20))
    blow = bump(1, 4.0)
    blow[:, 1] = np.maximum(blow[:, 1], 0.8 + G[1])
    swing = np.vstack([wind, blow])
    poke = bump(0, 0.8, 14)
    tm = Templates.from_trials({
        "swing": [np.vstack([rest(10), swing + rng.normal(0, 0.02, swing.shape), rest(10)]) for _ in range(3)],
        "poke": [np.vstack([rest(10), poke + rng.normal(0, 0.02, poke.shape), rest(10)]) for _ in range(3)],
    })
    paused = np.vstack([rest(30), wind[:12], wind[:12][::-1], rest(10), bump(1, 4.0), rest(40)])
    events = run(DualBufferRecognizer(tm, noise_g=0.3, null_frames=6), paused)
    kinds = [(e["event"], e["action"]) for e in events if e["event"] != "switch"]
    assert kinds == [("start", "swing"), ("end", "swing")]
    assert events[0]["frame"] < 30 + 24  # started on the wind-up, before the pause
    # a pause longer than PAUSE_FRAMES ends the wind-up: called off, the blow starts anew
    longer = np.vstack([rest(30), wind[:12], wind[:12][::-1], rest(6 + db.PAUSE_FRAMES + 4), bump(1, 4.0), rest(40)])
    kinds = [(e["event"], e["action"]) for e in run(DualBufferRecognizer(tm, noise_g=0.3, null_frames=6), longer)]
    assert ("reject", "swing") in kinds and [k for k, _ in kinds].count("start") == 2
    # without the rule, the same paused swing was two motions
    monkeypatch.setattr(rules, "PAUSE_FRAMES", 0)
    kinds = [(e["event"], e["action"]) for e in run(DualBufferRecognizer(tm, noise_g=0.3, null_frames=6), paused)]
    assert [k for k, _ in kinds].count("start") == 2


def test_a_wrong_early_start_is_corrected_by_a_switch():
    # Both actions begin with the same x bump and differ afterwards (z vs y): the first decision
    # cannot tell them apart; when it guesses wrong, a switch with n_p corrects it.
    rng = np.random.default_rng(3)
    shared = bump(0, 2.5, 16)
    a = np.vstack([shared, bump(2, 3.0)])
    b = np.vstack([shared, bump(1, 3.0)])
    tm = Templates.from_trials({k: [np.vstack([rest(10), m + rng.normal(0, 0.02, m.shape), rest(10)]) for _ in range(3)]
                                for k, m in (("a", a), ("b", b))})
    for truth, motion in (("a", a), ("b", b)):
        events = run(DualBufferRecognizer(tm, noise_g=0.3), np.vstack([rest(30), motion, rest(30)]))
        decided = [e for e in events if e["event"] in ("start", "switch")]
        assert decided[0]["event"] == "start" and decided[-1]["action"] == truth
        if decided[0]["action"] != truth:
            assert decided[-1]["event"] == "switch" and decided[-1]["from_frame"] > 0


def rotation(axis: np.ndarray, angle: float) -> np.ndarray:
    axis = axis / np.linalg.norm(axis)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * k @ k


def test_grip_feature_is_unchanged_when_the_recording_is_rotated_at_rest():
    rng = np.random.default_rng(2)
    rec = np.vstack([rest(10, 0.01, rng), bump(0, 3.0) + bump(1, 1.0) - G, rest(10, 0.01, rng)])
    g = rec[:5].mean(axis=0)
    for angle in (0.3, 1.2, 2.5):
        r = rotation(rng.normal(size=3), angle)
        turned = rec @ r.T  # the same motion with the sensor held another way
        assert np.allclose(grip_features(turned, r @ g), grip_features(rec, g), atol=1e-12)
        assert np.allclose(features(turned, r @ g, "grip"), features(rec, g, "grip"), atol=1e-12)
        assert not np.allclose(features(turned, r @ g, "log"), features(rec, g, "log"), atol=1e-3)  # today's feature is not


def test_grip_templates_recognize_a_rotated_recording_the_same_way():
    rng = np.random.default_rng(4)
    trials = {
        name: [np.vstack([rest(30, 0.01, rng), bump(axis, 3.0) + rng.normal(0, 0.02, (24, 3)), rest(10, 0.01, rng)]) for _ in range(3)]
        for name, axis in (("jab", 0), ("upper", 2))
    }
    tm = Templates.from_trials(trials, feature="grip")
    stream = np.vstack([rest(40, 0.01, rng), bump(0, 3.0), rest(40, 0.01, rng), bump(2, 3.0), rest(40, 0.01, rng)])
    r = rotation(np.array([1.0, 2.0, 0.5]), 0.9)
    plain = run(DualBufferRecognizer(tm), stream)
    turned = run(DualBufferRecognizer(tm), stream @ r.T)
    strip = lambda evs: [(e["event"], e["action"], e["frame"]) for e in evs]  # noqa: E731
    assert strip(turned) == strip(plain)
    assert [a for k, a, _ in strip(plain) if k == "start"] == ["jab", "upper"]


def test_representative_trials_drop_the_cut_off_and_the_odd_one():
    rng = np.random.default_rng(6)
    good = [np.vstack([rest(10), bump(0, 3.0) + rng.normal(0, 0.05, (24, 3)), rest(10)]) for _ in range(3)]
    cut_off = np.vstack([rest(10), bump(0, 3.0)[:6]])  # the recording window closed early
    warm_up = np.vstack([rest(10), bump(1, 2.0, 40), rest(10)])  # a different motion
    kept = representative_trials([warm_up, good[0], cut_off, good[1], good[2]], keep=3)
    assert len(kept) == 3 and all(any(k is g or np.array_equal(k, g) for g in good) for k in kept)
    assert representative_trials(good[:2], keep=3) == good[:2]  # fewer than keep: all of them
    tm = Templates.from_trials({"jab": [warm_up, *good, cut_off]}, keep=3)
    assert len(tm) == 3


def test_the_gates_percentile_is_numpys_bit_for_bit():
    """gate.percentile replaces np.percentile (which imports numpy.ma mid-game); the auto gate
    must learn exactly what it learnt before."""
    rng = np.random.default_rng(11)
    for n in [*range(1, 40), 120, 600]:
        for scale in (1e-3, 1.0, 40.0):
            a = rng.random(n) * scale
            if n % 3 == 0:
                a = np.round(a, 1)  # ties
            for q in (0, 10, 25, 50, 90, 99.9, 100, float(rng.random() * 100)):
                assert percentile(a, q) == float(np.percentile(a, q)), (n, scale, q)
    a = rng.random(50)
    kept = a.copy()
    percentile(a, 90)
    assert np.array_equal(a, kept)  # the caller's buffer is left as it was


def test_a_first_punch_no_template_matches_does_not_raise_the_gate_over_the_rest():
    """Before any start, a rejected motion's frames count as resting noise (a gate set too low
    by quiet training trials). A real punch that matched nothing (here: thresholds of 0, or a
    move no template has) was learnt as rest too: the gate jumped to 2 g and every later punch
    stayed under it."""
    rng = np.random.default_rng(5)
    gentle = {name: [np.vstack([rest(30, 0.01, rng), bump(axis, 1.2) + rng.normal(0, 0.02, (24, 3)), rest(10, 0.01, rng)])
                     for _ in range(3)] for name, axis in (("jab", 0), ("upper", 2))}
    tm = Templates.from_trials(gentle)
    stream = np.vstack([rest(60, 0.01, rng), bump(1, 3.0, 30), rest(60, 0.01, rng)]  # an unknown, strong move first
                       + [np.vstack([bump(axis, 1.2), rest(60, 0.01, rng)]) for axis in (0, 2, 0, 2)])
    rec = DualBufferRecognizer(tm)
    events = run(rec, stream)
    assert [e["action"] for e in events if e["event"] == "start"] == ["jab", "upper", "jab", "upper"]
    assert rec.noise_g < 1.0
