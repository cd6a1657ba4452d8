"""The "jit" (numba) method of IncrementalDTW: equal to the full reference DTW for every prefix,
equal to the numpy scan, and the numpy fallback when numba is missing or disabled."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from engine.recognition import dtw, dtw_kernel
from engine.recognition.dtw import IncrementalDTW, dtw_rows, open_end_score
from engine.recognition.dual_buffer import CLOSED_END

ROOT = Path(__file__).resolve().parents[3]
needs_jit = pytest.mark.skipif(not dtw.jit_available(), reason="numba not importable or QUICKJAB_NO_JIT set")
finite = st.floats(-4.0, 4.0, allow_nan=False, width=64)


@st.composite
def problems(draw):
    dim = 3 * draw(st.integers(1, 2))
    n_t = draw(st.integers(1, 4))
    templates = [draw(arrays(np.float64, (draw(st.integers(1, 9)), dim), elements=finite)) for _ in range(n_t)]
    query = draw(arrays(np.float64, (draw(st.integers(1, 10)), dim), elements=finite))
    progress = draw(st.sampled_from([0.0, 0.5, 1.0, 1.25, 2.0, CLOSED_END]))
    return templates, query, progress


@needs_jit
@settings(max_examples=80, deadline=None)
@given(problems())
def test_jit_equals_full_dtw_for_every_prefix(problem):
    templates, query, progress = problem
    d = IncrementalDTW(templates, method="jit", min_progress=progress)
    assert d.method == "jit" and d.n == 0  # the warm-up push in __init__ left no trace
    for i in range(len(query)):
        scores = d.push(query[i]).copy()
        closed = d.closed_scores()
        for k, t in enumerate(templates):
            full = dtw_rows(query[: i + 1], t)
            np.testing.assert_allclose(d._row[: len(t), k], full[-1], rtol=1e-9, atol=1e-9)
            assert scores[k] == pytest.approx(open_end_score(query[: i + 1], t, progress), rel=1e-9, abs=1e-9)
            assert closed[k] == pytest.approx(full[-1, -1] / (i + 1 + len(t)), rel=1e-9, abs=1e-9)
            # closed end (CLOSED_END) is the whole template only
            assert open_end_score(query[: i + 1], t, CLOSED_END) == pytest.approx(closed[k], rel=1e-9, abs=1e-9)
            normalized = full[-1] / (i + 1 + np.arange(1, len(t) + 1))
            # the best position (ties broken by rounding, so compare the score there)
            assert normalized[d.position(k)] == pytest.approx(normalized.min(), rel=1e-9, abs=1e-9)


@needs_jit
@pytest.mark.parametrize("n_templates", [1, 13, 300])
def test_jit_equals_scan_on_random_data(n_templates):
    rng = np.random.default_rng(n_templates)
    templates = [np.cumsum(rng.normal(0, 0.3, (int(rng.integers(1, 60)), 6)), axis=0) for _ in range(n_templates)]
    query = np.cumsum(rng.normal(0, 0.3, (70, 6)), axis=0)
    scan = IncrementalDTW(templates, method="scan", exact_costs=True)
    jit = IncrementalDTW(templates, method="jit")
    for rep in range(2):  # and again after a reset (a new onset)
        for i, q in enumerate(query):
            # the recognizer changes min_progress from frame to frame (open end / closed end)
            scan.min_progress = jit.min_progress = (0.0, 1.25, CLOSED_END, 2)[(i + rep) % 4]
            np.testing.assert_allclose(jit.push(q), scan.push(q), rtol=1e-9, atol=0)
            np.testing.assert_allclose(jit._row, scan._row, rtol=1e-9, atol=0)
            np.testing.assert_allclose(jit.closed_scores(), scan.closed_scores(), rtol=1e-9, atol=0)
            assert [jit.position(k) for k in range(n_templates)] == [scan.position(k) for k in range(n_templates)]
        scan.reset()
        jit.reset()


@needs_jit
def test_jit_takes_any_frame_like_and_rejects_a_wrong_length():
    rng = np.random.default_rng(5)
    templates = [rng.normal(size=(8, 3)), rng.normal(size=(5, 3))]
    a, b = IncrementalDTW(templates, method="jit"), IncrementalDTW(templates, method="scan", exact_costs=True)
    for q in rng.normal(size=(4, 3)):
        np.testing.assert_allclose(a.push(q.astype(np.float32).tolist()), b.push(q.astype(np.float32)), rtol=1e-9)
    strided = rng.normal(size=(3, 2))[:, 0]  # a non-contiguous view
    np.testing.assert_allclose(a.push(strided), b.push(strided), rtol=1e-9)
    with pytest.raises(ValueError):
        a.push(np.zeros(4))


def test_auto_picks_native_else_jit_for_many_else_loop(monkeypatch):
    few = [np.zeros((5, 3))] * 13
    assert IncrementalDTW(few).method == ("native" if dtw.native_available() else "loop")
    monkeypatch.setattr(dtw, "native_available", lambda: False)
    assert IncrementalDTW(few).method == "loop"  # numba is not worth its start-up for 13
    many = few * (dtw.JIT_FROM_TEMPLATES // 13 + 1)
    assert IncrementalDTW(many).method == ("jit" if dtw.jit_available() else "loop")
    monkeypatch.setattr(dtw, "jit_available", lambda: False)
    assert IncrementalDTW(few).method == "loop"
    assert IncrementalDTW(few * 40).method == "loop"
    with pytest.raises(ValueError, match="numba"):
        IncrementalDTW(few, method="jit")


@pytest.mark.parametrize("hide", ["env", "import"])
def test_fallback_without_numba(monkeypatch, hide):
    """QUICKJAB_NO_JIT=1, or numba not importable: no kernel, auto uses numpy, results equal."""
    monkeypatch.setattr(dtw_kernel, "_compiled", [])
    monkeypatch.setattr(dtw, "native_available", lambda: False)  # the C kernel: test_dtw_native
    if hide == "env":
        monkeypatch.setenv(dtw_kernel.NO_JIT_ENV, "1")
    else:
        monkeypatch.delenv(dtw_kernel.NO_JIT_ENV, raising=False)
        monkeypatch.setitem(sys.modules, "numba", None)  # `import numba` raises ImportError
    assert dtw_kernel.push_row_kernel() is None and not dtw.jit_available()
    rng = np.random.default_rng(3)
    templates = [rng.normal(size=(int(rng.integers(2, 9)), 3)) for _ in range(4)]
    query = rng.normal(size=(6, 3))
    d = IncrementalDTW(templates, min_progress=1.25)
    assert d.method == "loop"  # the kernels' scores bit for bit (test_dtw.py)
    for i, q in enumerate(query):
        scores = d.push(q)
        for k, t in enumerate(templates):
            assert scores[k] == pytest.approx(open_end_score(query[: i + 1], t, 1.25), rel=1e-6, abs=1e-6)


def _run(code: str, **env: str) -> subprocess.CompletedProcess:
    full_env = {**os.environ, "PYTHONPATH": str(ROOT), **env}
    full_env.pop(dtw_kernel.NO_JIT_ENV, None)
    full_env.update(env)
    return subprocess.run([sys.executable, "-W", "error", "-c", textwrap.dedent(code)], cwd=ROOT, env=full_env,
                          capture_output=True, text=True, timeout=120)


def test_no_jit_env_var_in_a_fresh_process_runs_the_recognizer_on_numpy():
    code = """
        import numpy as np
        import sys
        from engine.recognition import DualBufferRecognizer, Templates
        from engine.recognition.dtw import jit_available
        rng = np.random.default_rng(0)
        g = np.array([0.0, 0.0, 1.0])
        bump = np.tile(g, (24, 1)); bump[:, 0] += 3.0 * np.sin(np.linspace(0, 2 * np.pi, 24))
        trials = [np.vstack([np.tile(g, (5, 1)), bump + rng.normal(0, 0.02, bump.shape), np.tile(g, (5, 1))]) for _ in range(3)]
        rec = DualBufferRecognizer(Templates.from_trials({"jab": trials}))
        events = [e for f in np.vstack([np.tile(g, (10, 1)), bump, np.tile(g, (20, 1))]) for e in rec.push(f)]
        assert not jit_available() and rec.dtw.method == "loop", rec.dtw.method
        assert "numba" not in sys.modules
        assert [e["event"] for e in events][:1] == ["start"] and events[0]["action"] == "jab", events
        print("ok")
    """
    r = _run(code, QUICKJAB_NO_JIT="1")
    assert r.returncode == 0 and r.stdout.strip() == "ok", r.stderr


@needs_jit
def test_unwritable_cache_compiles_without_caching_and_without_warnings():
    """No writable cache directory anywhere (e.g. installed read-only): numba refuses
    cache=True; the kernel is then compiled uncached, silently (-W error in the child)."""
    code = """
        import numpy as np
        from numba.core import caching

        def unwritable(self):
            raise PermissionError("read-only")

        caching._CacheLocator.ensure_cache_path = unwritable
        from engine.recognition import dtw_kernel
        from engine.recognition.dtw import IncrementalDTW, open_end_score
        kernel = dtw_kernel.push_row_kernel()
        assert kernel is not None and type(kernel._cache).__name__ == "NullCache", kernel._cache
        rng = np.random.default_rng(0)
        templates = [rng.normal(size=(7, 3)), rng.normal(size=(4, 3))]
        query = rng.normal(size=(5, 3))
        d = IncrementalDTW(templates, method="jit", min_progress=1.25)
        for i, q in enumerate(query):
            s = d.push(q)
        for k, t in enumerate(templates):
            assert abs(s[k] - open_end_score(query, t, 1.25)) < 1e-9
        print("ok")
    """
    r = _run(code)
    assert r.returncode == 0 and r.stdout.strip() == "ok", r.stderr
