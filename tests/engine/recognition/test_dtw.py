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


def test_auto_method_picks_loop_without_jit_or_native(monkeypatch):
    monkeypatch.setattr(dtw, "jit_available", lambda: False)  # with numba, auto is "jit" (test_dtw_jit)
    monkeypatch.setattr(dtw, "native_available", lambda: False)  # with a C compiler, "native"
    few = [np.zeros((5, 3))] * 13
    assert IncrementalDTW(few).method == "loop"  # the kernel's scores, bit for bit (below)
    assert IncrementalDTW(few * 40).method == "loop"


def kernel_scores(templates, query, progress):
    """Per query frame, the C kernel's scores and row, from its line-by-line Python original
    (dtw_kernel._push_row_py, run uncompiled): what "native" and "jit" compute."""
    from engine.recognition.dtw_kernel import _push_row_py
    from engine.recognition.dtw_templates import pad_templates

    tmpl, lengths = pad_templates(templates)
    ldt = np.ascontiguousarray(tmpl.transpose(0, 2, 1))
    L, T = tmpl.shape[:2]
    prev = np.full((L + 1, T), np.inf)
    prev[0] = 0.0
    out = []
    for n, q in enumerate(query):
        cur, scores = np.full((L + 1, T), np.inf), np.empty(T)
        _push_row_py(ldt, lengths, q, prev, cur, np.empty(T), np.empty(T), np.empty(T, dtype=np.int64),
                     n, progress, scores)
        out.append((scores, cur[1:]))
        prev = cur
    return out


@pytest.mark.parametrize("progress", [0.0, 0.75, 1e9])
def test_auto_without_a_compiler_scores_to_the_bit_as_the_c_kernel(monkeypatch, progress):
    """The numpy method auto falls back on (no compiler, a failed build, QUICKJAB_NO_NATIVE)
    gives the kernel's scores and rows bit for bit, so a run's events do not depend on whether
    the kernel was there. The scan it fell back on before cancels where a frame equals a
    template frame (a hand at rest): 1.4e-9 off in the scripted match (2e-7 relative)."""
    monkeypatch.setattr(dtw, "native_available", lambda: False)
    monkeypatch.setattr(dtw, "jit_available", lambda: False)
    rng = np.random.default_rng(3)
    rest = np.array([0.0, 0.1, 0.99, 0.05, -0.2, 0.97])
    templates = [np.vstack([np.repeat(rest[None], 4, 0), rng.normal(0, 1, (int(rng.integers(3, 30)), 6))])
                 for _ in range(40)]
    query = np.vstack([np.repeat(rest[None], 3, 0), templates[7][4:] + rng.normal(0, 0.01, (len(templates[7]) - 4, 6))])
    d = IncrementalDTW(templates, min_progress=progress)
    for q, (scores, row) in zip(query, kernel_scores(templates, query, progress), strict=True):
        np.testing.assert_array_equal(d.push(q), scores)
        np.testing.assert_array_equal(d._row, row)
