"""Adaptation weighs an action with adopted templates against one without them by the trained
templates (Adaptation._usable): the one kind adopted must not take the other kinds' motions."""

from __future__ import annotations

import numpy as np

from engine.recognition import DualBufferRecognizer, Templates

G = np.array([0.0, 0.0, 1.0])


def move(ax: float, ay: float, n: int) -> np.ndarray:
    """An out-and-back acceleration along (ax, ay), gravity included."""
    x = np.tile(G, (n, 1))
    s = np.sin(np.linspace(0, 2 * np.pi, n))
    x[:, 0] += ax * s
    x[:, 1] += ay * s
    return x


def rest(n: int) -> np.ndarray:
    return np.tile(G, (n, 1))


def played(rec: DualBufferRecognizer, motions: list[np.ndarray], rng: np.random.Generator) -> list[str | None]:
    """Each motion between rests; the action each one was decided as in the end."""
    out = []
    for m in motions:
        events = []
        for f in np.vstack([rest(40), m + rng.normal(0, 0.02, m.shape), rest(40)]):
            events += rec.push(f)
        decided = [e["action"] for e in events if e["event"] in ("start", "switch")]
        out.append(decided[-1] if decided else None)
    return out


def quick_templates(rng: np.random.Generator) -> Templates:
    """Trained on quick punches: a straight one, and one with a little sideways."""
    def trials(ax: float, ay: float) -> list[np.ndarray]:
        return [np.vstack([rest(10), move(ax, ay, 16) + rng.normal(0, 0.02, (16, 3)), rest(10)]) for _ in range(3)]

    return Templates.from_trials({"a": trials(3.0, 0.0), "b": trials(2.5, 0.8)})


# Played as full blows: longer and twice as strong. Full a-blows fit a's quick templates clearly
# and are adopted; a full b-blow is nearer an adopted full a-blow than b's quick templates, and
# fits neither clearly enough to be adopted itself.
FULL_A, FULL_B = move(6.0, 0.0, 40), move(6.0, 0.6, 40)
SESSION = [FULL_A] * 4 + [FULL_B, FULL_A, FULL_B, FULL_A, FULL_B]


def test_the_kind_adopted_does_not_take_the_other_kinds_full_blows():
    rng = np.random.default_rng(0)
    templates = quick_templates(rng)
    rec = DualBufferRecognizer(templates, main=6, noise_g=0.5)
    got = played(rec, SESSION, rng)
    assert sorted(rec._adapted) == [templates.action_names.index("a")]  # only a was adopted
    assert got == ["a"] * 4 + ["b", "a", "b", "a", "b"]
    # without adaptation the same session is decided the same way
    assert played(DualBufferRecognizer(templates, main=6, noise_g=0.5, adapt=0), SESSION, rng) == got


def test_adopted_templates_are_left_out_only_against_an_action_without_them():
    rng = np.random.default_rng(1)
    rec = DualBufferRecognizer(quick_templates(rng), main=6, noise_g=0.5)
    played(rec, [FULL_A] * 3, rng)
    assert rec._is_adapted.any() and not rec._is_adapted[rec._tmpl_action == 1].any()
    a_trained = (rec._tmpl_action == 0) & ~rec._is_adapted
    scores = np.where(rec._is_adapted, 0.1, 1.0)  # the adopted ones fit best
    # a's trained templates fit worse than b's: a's adopted ones do not count
    scores[rec._tmpl_action == 1] = 0.5
    usable = rec._usable(scores)
    assert np.isinf(usable[rec._is_adapted]).all() and (usable[~rec._is_adapted] == scores[~rec._is_adapted]).all()
    # a's trained templates fit better than b's: everything counts
    scores[a_trained] = 0.4
    np.testing.assert_array_equal(rec._usable(scores), scores)
    # once b has adopted templates too, everything counts whatever the trained ones say
    rec._is_adapted[np.flatnonzero(rec._tmpl_action == 1)[0]] = True
    scores[a_trained] = 0.9
    np.testing.assert_array_equal(rec._usable(scores), scores)
