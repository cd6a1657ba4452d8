"""The incremental DTW equals the plain full DTW for every prefix, for both numpy row methods
(the numba "jit" method: test_dtw_jit.py)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from engine.recognition import dtw
from engine.recognition.dtw import IncrementalDTW, dtw_distance, dtw_rows, open_end_score

finite = st.floats(-4.0, 4.0, allow_nan=False, width=64)


@st.composite
def problems(draw):
    dim = 3 * draw(st.integers(1, 2))
    n_t = draw(st.integers(1, 4))
    templates = [draw(arrays(np.float64, (draw(st.integers(1, 9)), dim), elements=finite)) for _ in range(n_t)]
    query = draw(arrays(np.float64, (draw(st.integers(1, 10)), dim), elements=finite))
    progress = draw(st.sampled_from([0.0, 1.0, 2.0]))
    return templates, query, progress


@settings(max_examples=60, deadline=None)
@given(problems(), st.sampled_from(["scan", "loop"]))
def test_incremental_equals_full_dtw_for_every_prefix(problem, method):
    templates, query, progress = problem
    dtw = IncrementalDTW(templates, method=method, min_progress=progress, exact_costs=True)
    for i in range(len(query)):
        scores = dtw.push(query[i]).copy()
        for k, t in enumerate(templates):
            full = dtw_rows(query[: i + 1], t)
            # the accumulated row itself, not only the score
            np.testing.assert_allclose(dtw._row[: len(t), k], full[-1], rtol=1e-9, atol=1e-9)
            assert scores[k] == pytest.approx(open_end_score(query[: i + 1], t, progress), rel=1e-9, abs=1e-9)


@pytest.mark.parametrize("progress", [0.0, 1.25])
def test_fast_costs_and_both_methods_match_the_exact_path(progress):
    rng = np.random.default_rng(1)
    templates = [rng.normal(size=(int(rng.integers(5, 40)), 6)) for _ in range(300)]
    query = rng.normal(size=(30, 6))
    exact = IncrementalDTW(templates, method="scan", min_progress=progress, exact_costs=True)
    fast = [IncrementalDTW(templates, method=m, min_progress=progress) for m in ("scan", "loop")]
    for q in query:
        ref = exact.push(q).copy()
        for f in fast:
            np.testing.assert_allclose(f.push(q), ref, rtol=1e-6, atol=1e-6)


def test_identical_sequences_score_zero_and_distance_is_symmetric():
    rng = np.random.default_rng(2)
    a, b = rng.normal(size=(12, 3)), rng.normal(size=(9, 3))
    dtw = IncrementalDTW([a])
    for x in a:
        score = dtw.push(x)[0]
    assert score == pytest.approx(0.0, abs=1e-6)
    assert dtw_distance(a, b) == pytest.approx(dtw_distance(b, a))
    assert dtw_distance(a, b) > 0


def test_auto_method_picks_loop_for_many_templates_without_jit(monkeypatch):
    monkeypatch.setattr(dtw, "jit_available", lambda: False)  # with numba, auto is "jit" (test_dtw_jit)
    monkeypatch.setattr(dtw, "native_available", lambda: False)  # with a C compiler, "native"
    few = [np.zeros((5, 3))] * 13
    assert IncrementalDTW(few).method == "scan"
    assert IncrementalDTW(few * 40).method == "loop"
