"""Fuzzing the game's file readers (issue 16): BVH motion capture and the Interaction Graph.
A clean error (an InputError naming the file) or a valid result, never another exception."""

from __future__ import annotations

import io
import json
import zipfile
from datetime import timedelta
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from engine.errors import InputError
from game.bvh import BVHError, parse_bvh, read_bvh, retarget
from game.interaction.table import GraphFileError, GraphTable
from tools.cli import main

REPO = Path(__file__).resolve().parents[2]
GRAPH = REPO / "game" / "assets" / "graph.npz"
FUZZ = settings(max_examples=25, deadline=timedelta(seconds=20), derandomize=True,
                suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])

BVH_TEXT = """HIERARCHY
ROOT Hips
{
  OFFSET 0 0 0
  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
  JOINT Chest
  {
    OFFSET 0 5 0
    CHANNELS 3 Zrotation Xrotation Yrotation
    End Site
    {
      OFFSET 0 5 0
    }
  }
}
MOTION
Frames: 3
Frame Time: 0.0166667
0 90 0 0 0 0 0 0 0
0 91 0 10 0 0 5 0 0
0 92 0 20 0 0 10 0 0
"""
NASTY = st.sampled_from(["nan", "inf", "-5", "0", "1e9", "1e308", "1e-300", "abc", "", "{", "}", "\n",
                         "Frames: -5", "Frame Time: nan", "CHANNELS 100000000", "JOINT x", "End Site", ":"])


@FUZZ
@given(st.data())
def test_bvh_reader_gives_a_motion_or_a_clean_error(data):
    text = BVH_TEXT
    for _ in range(data.draw(st.integers(1, 4))):
        i = data.draw(st.integers(0, len(text)))
        j = data.draw(st.integers(i, min(len(text), i + 10)))
        text = text[:i] + data.draw(NASTY | st.text(max_size=6)) + text[j:]
    try:
        bvh = parse_bvh(text, "fuzz.bvh")
    except BVHError as exc:
        assert "\n" not in str(exc)
        return
    assert bvh.frames >= 1 and 0 < bvh.frame_time <= 1
    assert np.isfinite(bvh.motion).all()


@pytest.mark.parametrize("header, words", [
    ("Frames: abc\nFrame Time: 0.0166667", "not a number"),
    ("Frames: -5\nFrame Time: 0.0166667", "at least 1"),
    ("Frames: 3\nFrame Time: nan", "Frame Time"),
    ("Frames: 3\nFrame Time: inf", "Frame Time"),
    ("Frames: 3\nFrame Time: 1e9", "Frame Time"),
    ("Frames: 3\nFrame Time: 0", "Frame Time"),
])
def test_bad_bvh_headers_are_named(header, words):
    text = BVH_TEXT.replace("Frames: 3\nFrame Time: 0.0166667", header)
    with pytest.raises(BVHError, match=words):
        parse_bvh(text, "x.bvh")


def test_nan_pose_is_refused_not_exported():
    text = BVH_TEXT.replace("0 91 0 10", "0 nan 0 10")
    with pytest.raises(BVHError, match="finite"):
        parse_bvh(text, "x.bvh")


def test_bvh_motion_takes_the_memory_of_its_numbers_not_of_its_text(tmp_path, peak_memory):
    """A Python float per value took 37 times the file (8.7 GB for 234 MB)."""
    head, _ = BVH_TEXT.split("Frames:")
    rows = 50_000
    path = tmp_path / "long.bvh"
    path.write_text(head + f"Frames: {rows}\nFrame Time: 0.01\n"
                    + "".join(" ".join(f"{(i * k) % 90:.6f}" for k in range(9)) + "\n" for i in range(rows)))
    bvh, peak = peak_memory(lambda: read_bvh(path))
    assert bvh.motion.shape == (rows, 9) and bvh.motion[7, 2] == 14.0
    assert peak < 3 * path.stat().st_size, (peak, path.stat().st_size)  # numbers: 0.8 x the text


def test_bvh_info_refuses_a_hierarchy_it_cannot_map_before_reading_the_motion(tmp_path, capsys):
    path = tmp_path / "unmapped.bvh"  # motion that cannot be read: the hierarchy must say no first
    path.write_text(BVH_TEXT.replace("0 91 0 10", "not numbers"))
    for command in (["info", str(path)], ["cut", str(path), "--start", "0", "--end", "1", "--name", "x", "-o", str(tmp_path / "x.json")]):
        assert main(["bvh", *command]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and "no joint for spine" in err[0], err


@pytest.mark.parametrize("text, says", [
    ("HIERARCHY\nROOT a\n{\n" + "JOINT b\n{\n}\n" * 10_001 + "}\nMOTION\n", "over 10000 joints"),
    (BVH_TEXT.replace("OFFSET 0 5 0", "OFFSET 0 5 0 " + "0 " * 2**20, 1), "a line of over"),
    (BVH_TEXT.replace("0 91 0 10", "0 " * 2**20), "a line of over"),
    ("HIERARCHY\nEnd Site\n{\nOFFSET 0 0 0\n}\n", "End Site outside a joint"),  # was an IndexError
])
def test_too_many_joints_a_huge_line_or_a_stray_end_site_is_refused(text, says):
    with pytest.raises(BVHError, match=says):
        parse_bvh(text, "x.bvh")


def test_real_mocap_still_retargets(shared_data):
    from game.bvh import read_bvh

    for path in sorted((shared_data / "mocap").glob("*.bvh")):
        motion = retarget(read_bvh(path))
        assert np.isfinite(motion.postures).all() and len(motion.postures) > 10


# ------------------------------------------------------------------------------ the graph

@pytest.fixture(scope="module")
def graph_arrays() -> dict[str, np.ndarray]:
    with np.load(GRAPH, allow_pickle=False) as z:
        return {k: z[k] for k in z.files}


META_VALUES = st.sampled_from([float("nan"), float("inf"), -1, 0, 10**9, "x", None, [1], 0.5])
ARRAY_VALUES = st.sampled_from([np.nan, np.inf, -1, -129, 0, 2**31 - 1, 999, 1e30])


def _mutated(arrays: dict[str, np.ndarray], data: st.DataObject) -> dict[str, np.ndarray]:
    a = dict(arrays)
    meta = json.loads(str(a["meta"]))
    for _ in range(data.draw(st.integers(1, 3))):
        how = data.draw(st.sampled_from(["meta", "poke", "drop", "shape", "dtype"]))
        key = data.draw(st.sampled_from(sorted(k for k in a if k != "meta")))
        x = a[key]
        if how == "meta":
            section = data.draw(st.sampled_from(["grid", "rules", "rewards", "n_choices", "version", "format"]))
            if isinstance(meta.get(section), dict):
                meta[section][data.draw(st.sampled_from(sorted(meta[section])))] = data.draw(META_VALUES)
            else:
                meta[section] = data.draw(META_VALUES)
        elif how == "poke" and x.size and x.dtype.kind in "iufb":
            x = x.astype(np.float64) if data.draw(st.booleans()) else x.copy()
            v = data.draw(ARRAY_VALUES)
            try:
                x.flat[data.draw(st.integers(0, x.size - 1))] = v
            except (ValueError, OverflowError):
                pass
            a[key] = x
        elif how == "drop":
            a.pop(key)
        elif how == "shape" and x.ndim:
            a[key] = x[: data.draw(st.integers(0, max(0, len(x) - 1)))]
        elif how == "dtype":
            a[key] = x.astype(str) if x.size < 100_000 else x.astype(np.float32)
    a["meta"] = np.array(json.dumps(meta))
    return a


@FUZZ
@given(st.data())
def test_graph_loader_gives_a_table_or_a_clean_error(tmp_path_factory, graph_arrays, data):
    path = tmp_path_factory.mktemp("graph") / "g.npz"
    with open(path, "wb") as f:
        np.savez(f, **_mutated(graph_arrays, data))  # uncompressed: quicker to write and read
    try:
        g = GraphTable.load(path)
    except GraphFileError as exc:
        assert str(path) in str(exc) and "\n" not in str(exc)
        return
    # whatever loads is usable: ids in range, numbers finite
    assert np.isfinite(g.value).all() and np.isfinite(g.edge_reward).all() and np.isfinite(g.features).all()
    assert g.other_action.min() >= 0 and g.other_action.max() < len(g.action_names)
    assert g.edge_dst.min() >= 0 and g.edge_dst.max() < g.n_states
    assert 1 <= g.n_choices <= len(g.action_names)


def test_graph_npy_and_bomb_are_clean_errors(tmp_path, graph_arrays):
    npy = tmp_path / "g.npy"
    np.save(npy, graph_arrays["visits"])
    with pytest.raises(GraphFileError, match=r"\.npy"):
        GraphTable.load(npy)
    big = tmp_path / "big.npz"  # 600 MB of zeros, streamed: under 1 MB on disk
    header = np.lib.format.header_data_from_array_1_0(np.zeros(1))
    header["shape"] = (600 * 2**20 // 8,)
    buf = io.BytesIO()
    np.lib.format.write_array_header_1_0(buf, header)
    with zipfile.ZipFile(big, "w", zipfile.ZIP_DEFLATED, compresslevel=1) as z, \
            z.open("edge_reward.npy", "w", force_zip64=True) as f:
        f.write(buf.getvalue())
        for _ in range(150):
            f.write(bytes(4 * 2**20))
    with pytest.raises(GraphFileError, match="limit"):
        GraphTable.load(big)


def test_a_deeply_nested_meta_is_a_corrupt_file_not_a_recursion_error(tmp_path, graph_arrays):
    path = tmp_path / "deep.npz"
    with open(path, "wb") as f:
        np.savez(f, **{**graph_arrays, "meta": np.array("[" * 100_000)})
    with pytest.raises(GraphFileError, match="nested too deeply"):
        GraphTable.load(path)


def test_the_shipped_graph_loads():
    g = GraphTable.load(GRAPH)
    assert g.n_states > 1000 and issubclass(GraphFileError, InputError)
