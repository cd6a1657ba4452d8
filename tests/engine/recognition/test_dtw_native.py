"""The "native" (C, ctypes) method of IncrementalDTW: equal to the full reference DTW for every
prefix, bit for bit equal to the numba kernel and the numpy "loop" (auto's fallback), the same
recognizer events as the numpy scan on a synthesized session, built once and reused, and absent (numpy then) without a C compiler."""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from engine.recognition import DualBufferRecognizer, dtw, dtw_native
from engine.recognition.dtw import IncrementalDTW, open_end_score
from engine.recognition.dual_buffer import CLOSED_END

needs_native = pytest.mark.skipif(not dtw.native_available(), reason="no C compiler, or QUICKJAB_NO_NATIVE set")
finite = st.floats(-4.0, 4.0, allow_nan=False, width=64)
ASSETS = Path(__file__).resolve().parents[3] / "game" / "assets"


@pytest.fixture(autouse=True)
def _own_temporary_fallback(tmp_path_factory, monkeypatch):
    """Each test a temporary fallback cache of its own: a kernel an earlier run built in the
    machine's (a cache that could not be written then) was loaded from there, without a
    compiler and instead of the test's own cache."""
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path_factory.mktemp("tmp")))


@st.composite
def problems(draw):
    dim = 3 * draw(st.integers(1, 2))
    n_t = draw(st.integers(1, 4))
    templates = [draw(arrays(np.float64, (draw(st.integers(1, 9)), dim), elements=finite)) for _ in range(n_t)]
    query = draw(arrays(np.float64, (draw(st.integers(1, 10)), dim), elements=finite))
    progress = draw(st.sampled_from([0.0, 0.5, 1.0, 1.25, 2.0, CLOSED_END]))
    return templates, query, progress


@needs_native
@settings(max_examples=60, deadline=None)
@given(problems())
def test_native_equals_full_dtw_for_every_prefix(problem):
    templates, query, progress = problem
    d = IncrementalDTW(templates, method="native", min_progress=progress)
    assert d.method == "native" and d.n == 0
    for i in range(len(query)):
        scores = d.push(query[i])
        for k, t in enumerate(templates):
            assert scores[k] == pytest.approx(open_end_score(query[: i + 1], t, progress), rel=1e-9, abs=1e-9)


@needs_native
@pytest.mark.parametrize("n_templates", [1, 39, 300])
def test_native_is_the_jit_kernel_bit_for_bit(n_templates):
    rng = np.random.default_rng(n_templates)
    templates = [np.cumsum(rng.normal(0, 0.3, (int(rng.integers(3, 60)), 6)), axis=0) for _ in range(n_templates)]
    query = np.cumsum(rng.normal(0, 0.3, (70, 6)), axis=0)
    native = IncrementalDTW(templates, method="native", min_progress=1.25)
    other = (IncrementalDTW(templates, method="jit", min_progress=1.25) if dtw.jit_available() else
             IncrementalDTW(templates, method="scan", exact_costs=True, min_progress=1.25))
    loop = IncrementalDTW(templates, method="loop", min_progress=1.25)  # numpy, the kernel's operations
    for q in query:
        a, b = native.push(q), other.push(q)
        np.testing.assert_array_equal(loop.push(q), a)
        np.testing.assert_array_equal(loop._row, native._row)
        if other.method == "jit":
            assert np.array_equal(a, b)
        else:
            np.testing.assert_allclose(a, b, rtol=1e-12)
    np.testing.assert_array_equal(native.closed_scores(), other.closed_scores())


@needs_native
def test_recognizer_events_native_equal_loop_and_scan_on_a_synthesized_session():
    from engine.recognition import Templates
    from game.actions import load_library
    from tools.synth import synth_session

    templates = Templates.load(ASSETS / "templates.npz")
    signal, _ = synth_session(load_library(), 90.0, "experienced", np.random.default_rng(5))
    frames = signal.reshape(len(signal), -1)
    events = {}
    for method in ("native", "loop", "scan"):
        rec = DualBufferRecognizer(templates, dtw_method=method)
        assert rec.dtw.method == method
        events[method] = [e for f in frames for e in rec.push(f)]
    assert len(events["native"]) > 20
    assert events["loop"] == events["native"]  # the fallback's: every field, scores included
    assert [(e["event"], e.get("action"), e["frame"]) for e in events["native"]] == \
        [(e["event"], e.get("action"), e["frame"]) for e in events["scan"]]  # on this session


def test_without_a_compiler_there_is_no_native_kernel_and_auto_uses_numpy(monkeypatch, tmp_path):
    monkeypatch.setattr(dtw_native, "_loaded", [])
    monkeypatch.setenv(dtw_native.CACHE_ENV, str(tmp_path / "cache"))
    monkeypatch.setenv("CC", "/bin/false")  # a compiler that always fails
    monkeypatch.delenv(dtw_native.NO_NATIVE_ENV, raising=False)
    monkeypatch.delenv("QUICKJAB_NO_JIT", raising=False)
    assert dtw_native.push_row_native() is None and not dtw.native_available()
    assert IncrementalDTW([np.zeros((5, 3))] * 13).method == "loop"
    with pytest.raises(ValueError, match="C compiler"):
        IncrementalDTW([np.zeros((5, 3))], method="native")


@needs_native
def test_built_once_then_loaded_from_the_cache(monkeypatch, tmp_path):
    monkeypatch.setenv(dtw_native.CACHE_ENV, str(tmp_path))
    monkeypatch.setattr(dtw_native, "_loaded", [])
    assert dtw_native.push_row_native() is not None
    built = list(tmp_path.iterdir())
    assert built == [dtw_native.library_path()]  # nothing left behind but the library
    monkeypatch.setattr(dtw_native, "_loaded", [])
    monkeypatch.setenv("CC", "/bin/false")  # a rebuild would fail: it must load the cached one
    assert dtw_native.push_row_native() is not None
    monkeypatch.setattr(dtw_native, "_loaded", [])
    monkeypatch.setenv(dtw_native.NO_NATIVE_ENV, "1")
    assert dtw_native.push_row_native() is None


@pytest.mark.parametrize("method", ["native", "jit", "scan", "loop"])
def test_adding_and_removing_templates_scores_as_a_dtw_built_on_the_new_list(method):
    """The adaptation's path: update_templates / add_templates / remove_templates leave the DTW
    scoring exactly as one built from scratch on the same list (longer templates, capacity
    exhausted, removals, a reordering that falls back to padding afresh included)."""
    if (method == "native" and not dtw.native_available()) or (method == "jit" and not dtw.jit_available()):
        pytest.skip(f"{method} not available here")
    rng = np.random.default_rng(11)

    def make(n: int, longest: int = 40) -> list[np.ndarray]:
        return [np.cumsum(rng.normal(0, 0.3, (int(rng.integers(3, longest)), 6)), axis=0) for _ in range(n)]

    query = np.cumsum(rng.normal(0, 0.3, (30, 6)), axis=0)
    current = make(8)
    d = IncrementalDTW(current, method=method, min_progress=0.5)
    for step in range(24):
        for t in make(int(rng.integers(1, 3))):
            current.insert(int(rng.integers(0, len(current) + 1)), t)
        for _ in range(step % 3):
            del current[int(rng.integers(0, len(current)))]
        if step == 5:
            current.insert(0, make(1, 80)[0])  # longer than every template so far
        if step == 9:
            current.reverse()  # not an insertion or removal: padded afresh
        d.push(query[0])  # a query in progress is forgotten by the update
        d.update_templates(current)
        ref = IncrementalDTW(current, method=method, min_progress=0.5)
        assert d.n == 0 and d.T == ref.T and d.sources == current
        np.testing.assert_array_equal(d.lengths, ref.lengths)
        for f in query:
            np.testing.assert_array_equal(d.push(f), ref.push(f))
        np.testing.assert_array_equal(d.closed_scores(), ref.closed_scores())
        assert d.position(1) == ref.position(1)
    d.add_templates(make(2), at=[0, d.T])
    assert d.T == ref.T + 2
    d.remove_templates([0, d.T - 1])
    ref.reset()
    for f in query:
        np.testing.assert_array_equal(d.push(f), ref.push(f))
    with pytest.raises(ValueError):
        d.remove_templates(range(d.T))
    with pytest.raises(ValueError):
        d.add_templates([np.zeros((3, 5))])
