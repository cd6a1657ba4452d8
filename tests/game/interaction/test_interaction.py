"""The Interaction Graph: value iteration, the bout model, the build, the file, the look-up."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from game.interaction import (
    GraphFileError,
    GraphTable,
    InteractionGraph,
    OpponentController,
    Situation,
)
from game.interaction.bout import BoutRules, Bouts, Rewards, step
from game.interaction.build import BuildParams, build_graph, compile_table
from game.interaction.duel import duel
from game.interaction.solve import solve
from game.interaction.state import grid_distance2, relative_pose
from game.interaction.table import ESCAPE, join_small, split_small

sys.path.insert(0, str(Path(__file__).parent.parent))  # tests/game: hand_actions
from hand_actions import hand_library  # noqa: E402

SMALL = BuildParams(seed=3, states=400, bouts=64, bout_steps=300, max_rounds=1)
REPO = Path(__file__).resolve().parents[3]


@pytest.fixture(scope="module")
def lib():
    return hand_library()


@pytest.fixture(scope="module")
def small_table(lib):
    return build_graph(lib, SMALL)


@pytest.fixture(scope="module")
def small_graph(small_table, tmp_path_factory):
    path = tmp_path_factory.mktemp("g") / "graph.npz"
    small_table.save(path)
    return InteractionGraph.load(path)


# ---------------------------------------------------------------- value iteration

def _csr(edges):
    """edges: list per state of (dst, reward, steps, flip) -> solve() arguments."""
    ptr = np.cumsum([0] + [len(e) for e in edges])
    flat = [x for e in edges for x in e]
    dst, rew, steps, flip = (np.array(c) for c in zip(*flat, strict=True))
    return ptr, dst, rew.astype(float), 0.9 ** steps, flip.astype(bool)


def test_value_iteration_prefers_the_delayed_larger_reward():
    # 0 -a-> 1 (+1) -> 3 ;  0 -b-> 2 (0) -> 3 (+5) ; 3 absorbs with 0
    edges = [
        [(1, 1.0, 1, False), (2, 0.0, 1, False)],
        [(3, 0.0, 1, False)],
        [(3, 5.0, 1, False)],
        [(3, 0.0, 1, False)],
    ]
    sol = solve(*_csr(edges))
    assert sol.best_edge[0] == 1                      # b: 0.9 * 5 > 1
    np.testing.assert_allclose(sol.value, [4.5, 0.0, 5.0, 0.0], atol=1e-3)


def _turn_game():
    # state 0: ours. a -> 1 (the other's turn), b -> 2 (the other's turn); 3 absorbs.
    # In 1 the other can win 10 or lose 10; in 2 it gets 1 either way.
    return [
        [(1, 0.0, 0, True), (2, 0.0, 0, True)],
        [(3, 10.0, 0, True), (3, -10.0, 0, True)],
        [(3, 1.0, 0, True), (3, 1.0, 0, True)],
        [(3, 0.0, 1, False)],
    ]


def test_minmax_assumes_the_opponents_best_response():
    sol = solve(*_csr(_turn_game()), opponent_max=1.0)
    ptr = np.cumsum([0, 2])
    assert sol.best_edge[0] - ptr[0] == 1             # b: lose 1 rather than risk losing 10
    assert sol.value[0] == pytest.approx(-1.0)


def test_expectation_assumes_a_random_opponent():
    sol = solve(*_csr(_turn_game()), opponent_max=0.0)
    assert sol.best_edge[0] == 0                      # a: on average the other gets 0
    assert sol.value[0] == pytest.approx(0.0, abs=1e-6)


def test_solve_rejects_a_state_without_edges():
    with pytest.raises(ValueError):
        solve(np.array([0, 1, 1]), np.array([0]), np.zeros(1), np.ones(1), np.zeros(1, bool))


# ---------------------------------------------------------------- bout model

def _facing_pair(lib, distance):
    t = compile_table(lib, BoutRules())
    b = Bouts(t, 1)
    b.place(np.array([distance]), np.zeros(1), np.zeros(1))
    b.hp[:] = 100.0
    return t, b


def _play(b, t, a0, a1, steps):
    b.start(np.array([0]), 0, t.index(a0))
    b.start(np.array([0]), 1, t.index(a1))
    landed = np.zeros(2)
    for _ in range(steps):
        landed += step(b, BoutRules(), Rewards()).landed[0]
    return landed


def test_a_straight_in_reach_lands_and_interrupts(lib):
    t, b = _facing_pair(lib, 0.9)
    landed = _play(b, t, "straight_r", "guard", 12)
    assert landed.tolist() == [1.0, 0.0]
    assert b.hp[0, 1] == pytest.approx(92.0)
    assert t.names[b.act[0, 1]] == "hit_head"


def test_out_of_reach_misses_and_a_block_covers(lib):
    t, b = _facing_pair(lib, 1.5)
    assert _play(b, t, "straight_r", "guard", 20).sum() == 0
    t, b = _facing_pair(lib, 0.9)
    landed = _play(b, t, "straight_r", "block", 12)
    assert landed.sum() == 0
    assert b.hp[0, 1] == pytest.approx(100 - 0.2 * 8.0)      # chip damage only


def test_actions_take_their_frames_and_move_the_root(lib):
    t, b = _facing_pair(lib, 2.0)
    b.start(np.array([0]), 0, t.index("step_forward"))
    b.start(np.array([0]), 1, t.index("block"))
    n = 0
    while not b.done()[0, 0]:
        step(b, BoutRules(), Rewards())
        n += 1
    assert n == lib["step_forward"].frames
    d, _, _ = relative_pose(b.pos[0, 0], 0.0, b.pos[0, 1], 0.0)
    assert d == pytest.approx(1.7, abs=1e-6)


# ---------------------------------------------------------------- build, file

def test_build_is_deterministic_for_a_seed(lib, small_table):
    again = build_graph(lib, SMALL)
    for name in ("keys", "features", "best_action", "edge_dst", "edge_reward", "edge_flip"):
        np.testing.assert_array_equal(getattr(small_table, name), getattr(again, name))
    other = build_graph(lib, BuildParams(**{**SMALL.__dict__, "seed": 4}))
    assert not np.array_equal(other.keys, small_table.keys)


def test_build_has_every_action_from_every_state(small_table):
    t = small_table
    assert t.n_states == SMALL.states
    assert t.n_edges == t.n_states * t.n_choices
    assert (np.diff(t.edge_ptr) == t.n_choices).all()
    assert (np.diff(t.keys) > 0).all()
    assert set(np.unique(t.best_action)) <= set(range(t.n_choices))


def test_file_round_trips(small_table, tmp_path):
    path = tmp_path / "g.npz"
    small_table.save(path)
    back = GraphTable.load(path)
    assert back.action_names == small_table.action_names
    assert back.meta() == small_table.meta()
    for name in ("keys", "other_action", "other_frame", "visits", "best_action",
                 "value", "edge_ptr", "edge_dst", "edge_action", "edge_steps", "edge_flip",
                 "edge_reward", "fill_keys", "fill_state"):
        np.testing.assert_array_equal(np.asarray(getattr(back, name)),
                                      np.asarray(getattr(small_table, name)).astype(
                                          np.asarray(getattr(back, name)).dtype))
    # features are stored to 1/65536 of a cell, and each stays inside its own cell
    g = small_table.grid
    tol = np.array([g.distance_step, g.angle_step, g.angle_step]) / 65536
    assert (np.abs(back.features - small_table.features) <= tol).all()
    again = g.key(*back.features.T, back.other_action, back.other_frame)
    np.testing.assert_array_equal(again, small_table.keys)


def test_a_version_2_file_still_loads(small_table, tmp_path):
    t = small_table
    v2 = dict(meta=np.array(json.dumps({**t.meta(), "version": 2})),
              action_names=np.array(t.action_names), keys=t.keys, features=t.features,
              other_action=t.other_action.astype(np.int16),
              other_frame=t.other_frame.astype(np.int16), visits=t.visits,
              best_action=t.best_action.astype(np.int16), value=t.value,
              edge_ptr=t.edge_ptr.astype(np.int32), edge_dst=t.edge_dst.astype(np.int32),
              edge_action=t.edge_action, edge_steps=t.edge_steps, edge_flip=t.edge_flip,
              edge_reward=t.edge_reward, fill_key_steps=np.diff(t.fill_keys, prepend=0),
              fill_state=t.fill_state)
    np.savez_compressed(tmp_path / "v2.npz", **v2)
    back = GraphTable.load(tmp_path / "v2.npz")
    for name in ("keys", "features", "best_action", "edge_ptr", "edge_dst", "fill_keys",
                 "fill_state"):
        np.testing.assert_array_equal(np.asarray(getattr(back, name)),
                                      np.asarray(getattr(t, name)))
    np.savez_compressed(tmp_path / "v9.npz", **dict(v2, meta=np.array(
        json.dumps({**t.meta(), "version": 9}))))
    with pytest.raises(GraphFileError, match="version 9, this program reads 2, 3"):
        GraphTable.load(tmp_path / "v9.npz")


def test_escaped_steps_round_trip():
    x = np.array([0, 1, -1, 127, -127, 128, -128, 70000, -5, 2 ** 40], dtype=np.int64)
    small, big = split_small(x)
    assert small.dtype == np.int8 and len(big) == 4
    np.testing.assert_array_equal(join_small(small, big), x)
    assert join_small(small, big[:-1]) is None


def _corrupt_variants(small_table, tmp_path):
    good = tmp_path / "good.npz"
    small_table.save(good)
    raw = good.read_bytes()
    (tmp_path / "garbage.npz").write_bytes(b"not a graph at all" * 10)
    (tmp_path / "truncated.npz").write_bytes(raw[: len(raw) // 2])
    with np.load(good) as z:
        arrays = {k: z[k] for k in z.files}
    np.savez(tmp_path / "missing.npz",
             **{k: v for k, v in arrays.items() if k != "edge_dst_steps"})
    # the first destination (so, delta-coded, every one) moved past the last state
    steps, big = arrays["edge_dst_steps"].copy(), [int(x) for x in arrays["edge_dst_steps_big"]]
    first = big.pop(0) if steps[0] == ESCAPE else int(steps[0])
    steps[0] = ESCAPE
    big = np.array([first + len(arrays["key_steps"])] + big, dtype=np.int64)
    np.savez(tmp_path / "bad_dst.npz", **dict(arrays, edge_dst_steps=steps, edge_dst_steps_big=big))
    np.savez(tmp_path / "bad_escape.npz",
             **dict(arrays, edge_dst_steps_big=np.append(arrays["edge_dst_steps_big"], 1)))
    np.savez(tmp_path / "bad_meta.npz", **dict(arrays, meta=np.array("{")))
    meta = json.loads(str(arrays["meta"]))
    # `graph info` read build's keys with .get: a list was an AttributeError traceback
    np.savez(tmp_path / "build_list.npz", **dict(arrays, meta=np.array(json.dumps({**meta, "build": [1]}))))
    # the wait is an action of wait_frames frames: 10**12 asked the bout model for 568 TiB
    rules = {**meta["rules"], "wait_frames": 10**12}
    np.savez(tmp_path / "wait_huge.npz", **dict(arrays, meta=np.array(json.dumps({**meta, "rules": rules}))))
    return ["garbage", "truncated", "missing", "bad_dst", "bad_escape", "bad_meta", "build_list", "wait_huge"]


def test_a_corrupt_file_is_a_clear_error(small_table, tmp_path):
    for name in _corrupt_variants(small_table, tmp_path):
        path = tmp_path / f"{name}.npz"
        with pytest.raises(GraphFileError) as err:
            InteractionGraph.load(path)
        assert str(path) in str(err.value), name
    with pytest.raises(GraphFileError, match="no such"):
        InteractionGraph.load(tmp_path / "absent.npz")


def test_fill_keys_out_of_order_are_refused_in_any_dtype(small_table, tmp_path):
    # the fill's steps are checked in their stored dtype (no int64 copy at start-up); a uint64
    # step past 2**63 is negative as the decode reads it, and refused as before
    small_table.save(tmp_path / "good.npz")
    with np.load(tmp_path / "good.npz") as z:
        arrays = {k: z[k] for k in z.files}
    steps = arrays["fill_key_steps"].astype(np.uint64)
    for name, bad in (("zero", np.where(np.arange(len(steps)) == 1, 0, steps).astype(steps.dtype)),
                      ("wrapped", np.where(np.arange(len(steps)) == 1, np.uint64(2**63 + 1), steps))):
        np.savez(tmp_path / f"{name}.npz", **dict(arrays, fill_key_steps=bad))
        with pytest.raises(GraphFileError, match="keys not strictly ascending"):
            GraphTable.load(tmp_path / f"{name}.npz")
    np.savez(tmp_path / "u64.npz", **dict(arrays, fill_key_steps=steps))
    np.testing.assert_array_equal(GraphTable.load(tmp_path / "u64.npz").fill_keys, small_table.fill_keys)


def _saved_arrays(table, path) -> dict[str, np.ndarray]:
    table.save(path)
    with np.load(path) as z:
        return {k: z[k] for k in z.files}


def _escaped_first(small: np.ndarray, big: np.ndarray, add: int) -> tuple[np.ndarray, np.ndarray]:
    """An escaped pair (split_small) whose first value is `add` more than it was."""
    small, big = small.copy(), [int(x) for x in big]
    first = big.pop(0) if small[0] == ESCAPE else int(small[0])
    small[0] = ESCAPE
    return small, np.array([first + add] + big, dtype=np.int64)


@pytest.mark.parametrize("pos", [-5, 65536])
def test_a_feature_position_outside_its_cell_is_refused(small_table, tmp_path, pos):
    """feature_pos counts 1/65536 of its own cell: a negative or a whole cell's worth placed the
    state's features in another cell, and loaded."""
    arrays = _saved_arrays(small_table, tmp_path / "good.npz")
    feature_pos = arrays["feature_pos"].astype(np.int32)
    feature_pos[0, 0] = pos
    np.savez(tmp_path / "pos.npz", **dict(arrays, feature_pos=feature_pos))
    with pytest.raises(GraphFileError, match=r"pos.npz: .*feature_pos .* 0 to 65535"):
        GraphTable.load(tmp_path / "pos.npz")


@pytest.mark.parametrize("name, says", [("fill_state_offset", "the look-up fill points outside the states"),
                                        ("edge_dst_steps", "an edge points outside the states")])
def test_a_state_index_past_int32_is_refused_not_wrapped(small_table, tmp_path, name, says):
    """The decoded state indices are kept as int32: a wide value 2**32 past a state wrapped
    back onto that state, and the file loaded as if it were the good one."""
    arrays = _saved_arrays(small_table, tmp_path / "good.npz")
    small, big = _escaped_first(arrays[name], arrays[f"{name}_big"], 2**32)
    np.savez(tmp_path / "wide.npz", **dict(arrays, **{name: small, f"{name}_big": big}))
    with pytest.raises(GraphFileError, match=f"wide.npz: .*{says}"):
        GraphTable.load(tmp_path / "wide.npz")


def test_cli_reports_a_corrupt_file_in_one_line(tmp_path):
    path = tmp_path / "bad.npz"
    path.write_bytes(b"\x00" * 100)
    r = subprocess.run([sys.executable, "-m", "tools.cli", "graph", "info", str(path)],
                       cwd=REPO, capture_output=True, text=True)
    assert r.returncode == 2
    assert str(path) in r.stderr and len(r.stderr.strip().splitlines()) == 1


@pytest.mark.parametrize("name", ["feature_pos", "fill_state_offset", "edge_dst_steps"])
def test_cli_names_a_graph_whose_values_are_out_of_range(small_table, tmp_path, name):
    """`graph info` on a feature position outside its cell or a state index 2**32 past a state
    printed the graph and exited 0: now one line naming the file, exit 2, no traceback."""
    arrays = _saved_arrays(small_table, tmp_path / "good.npz")
    if name == "feature_pos":
        arrays[name] = -1 - arrays[name].astype(np.int32)
    else:
        arrays[name], arrays[f"{name}_big"] = _escaped_first(arrays[name], arrays[f"{name}_big"], 2**32)
    path = tmp_path / "bad.npz"
    np.savez(path, **arrays)
    r = subprocess.run([sys.executable, "-m", "tools.cli", "graph", "info", str(path)],
                       cwd=REPO, capture_output=True, text=True)
    assert r.returncode == 2 and "Traceback" not in r.stderr, r.stderr
    assert str(path) in r.stderr and len(r.stderr.strip().splitlines()) == 1, r.stderr


def test_cli_info_json(small_table, tmp_path):
    path = tmp_path / "g.npz"
    small_table.save(path)
    r = subprocess.run([sys.executable, "-m", "tools.cli", "graph", "info", str(path), "--json"],
                       cwd=REPO, capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    info = json.loads(r.stdout)
    assert info["states"] == small_table.n_states and info["edges"] == small_table.n_edges
    assert info["file_bytes"] == path.stat().st_size and info["build"]["seed"] == SMALL.seed


# ---------------------------------------------------------------- look-up, run time

def test_lookup_maps_a_live_situation_to_its_nearest_state(small_graph):
    g = small_graph
    rng = np.random.default_rng(0)
    t = g.table
    # live situations name the other's action; an idle other ("guard") is always READY, so
    # states of an other in the middle of a wait are not reachable by name
    live = np.flatnonzero(t.other_action != g.wait_id)
    for i in range(300):
        sid = int(rng.choice(live))
        d, bs, bo = (float(x) for x in t.features[sid])
        if i % 2:      # a live situation near, not at, a sampled one
            d, bs, bo = abs(d + rng.normal(0, 0.1)), bs + rng.normal(0, 0.3), bo + rng.normal(0, 0.3)
        a = int(t.other_action[sid])
        s = Situation(d, bs, bo, 0.0, "guard", 0.0, g.names[a], float(t.other_frame[sid]))
        got = g.state_of(s)
        aid, frame = g.other_code(s.other_action, s.other_phase)
        peer = g.index.brute_force(d, bs, bo, aid, frame)
        # the same state, or one exactly as near (a situation on a cell border)
        q = g.table.grid.cell_centres(np.array([g.table.grid.key(d, bs, bo, aid, frame)]))[0]
        near = [grid_distance2(g.index.centres[k], q, g.table.grid.n_angle) for k in (got, peer)]
        assert got == peer or near[0] == pytest.approx(near[1])
        assert g.table.other_action[got] == g.table.other_action[peer]
        if i % 2 == 0:
            assert got == sid          # a sampled state's own features map to it
        assert g.best_action(s) == g.names[t.best_action[got]]


def test_every_sampled_cell_is_in_the_fill_as_its_own_state(small_graph):
    # what lets `nearest` keep no dict of the state keys: the fill answers a sampled cell too
    from game.interaction.lookup import neighbour_fill

    idx = small_graph.index
    for keys, state in ((idx.fill_keys, idx.fill_state), neighbour_fill(idx.grid, idx.keys, radius=0)):
        pos = np.searchsorted(keys, idx.keys)
        np.testing.assert_array_equal(keys[pos], idx.keys)
        np.testing.assert_array_equal(state[pos], np.arange(idx.n))
    t = small_graph.table
    for i in range(0, idx.n, max(1, idx.n // 200)):  # a state's own situation finds it
        assert idx.nearest(*t.features[i], int(t.other_action[i]), int(t.other_frame[i])) == i


def test_scalar_and_vectorized_lookup_agree(small_graph):
    g = small_graph
    rng = np.random.default_rng(1)
    n = 500
    d = rng.uniform(0, 4.5, n)
    bs, bo = rng.uniform(-math.pi, math.pi, (2, n))
    act = g.table.other_action[rng.integers(0, g.n_states, n)]
    frame = rng.integers(0, 30, n)
    many = g.index.nearest_many(d, bs, bo, act, frame)
    one = [g.index.nearest(d[i], bs[i], bo[i], int(act[i]), int(frame[i])) for i in range(n)]
    np.testing.assert_array_equal(many, one)


def test_fill_and_scan_agree_with_brute_force(small_graph):
    g = small_graph
    rng = np.random.default_rng(2)
    n = 400
    d = rng.uniform(0, 4.5, n)
    bs, bo = rng.uniform(-math.pi, math.pi, (2, n))
    act = rng.integers(0, len(g.names), n)
    frame = rng.integers(0, 30, n)
    many = g.index.nearest_many(d, bs, bo, act, frame)
    peer = [g.index.brute_force(d[i], bs[i], bo[i], int(act[i]), int(frame[i])) for i in range(n)]
    np.testing.assert_array_equal(many, peer)


def test_a_broken_situation_means_wait(small_graph):
    for bad in (math.nan, math.inf):
        assert small_graph.best_action(Situation(bad, 0.0, 0.0, 0.0, "guard", 0, "guard", 0)) == "guard"
        assert small_graph.best_action(Situation(1.0, bad, 0.0, 0.0, "guard", 0, "jab", bad)) == "guard"


def test_idle_other_is_ready(small_graph):
    g = small_graph
    assert g.other_code("guard", 3.0) == (g.wait_id, g.table.rules.wait_frames - 1)
    assert g.other_code("no_such_action", 3.0)[0] == g.wait_id


class FakeController:
    def __init__(self):
        self.action, self.played = "guard", []

    def play(self, name, from_frame=0):
        self.action = name
        self.played.append(name)


def test_opponent_acts_only_at_the_guard(small_graph, lib):
    fc = FakeController()
    oc = OpponentController(small_graph, lib, controller=fc)
    s = Situation(0.9, 0.0, 0.0, math.pi, "guard", 0.0, "guard", 0.0)
    first = oc.decide(s)
    assert first == small_graph.best_action(s)
    fc.action = "straight_r"
    assert oc.decide(s) is None
    fc.action = "guard"
    assert oc.decide(s) is not None or first == "guard"


def test_duel_counts_are_consistent(small_graph, lib):
    r = duel(small_graph, lib, "greedy", bouts=6, seconds=5.0, seed=0)
    assert r.wins + r.losses + r.draws == 6
    assert r.hits_landed >= 0 and r.damage_dealt >= 0
    again = duel(small_graph, lib, "greedy", bouts=6, seconds=5.0, seed=0)
    assert again.as_dict() == r.as_dict()


@pytest.mark.parametrize("build, says", [
    (None, ["library not recorded", "time not recorded", "residual not recorded"]),  # no build at all
    ({}, ["seed not recorded", "not recorded samples", "residual not recorded"]),  # TypeError formatting None
    ({"seconds": "x"}, ["time x s"]),  # AttributeError: .get on a string
    ({"seconds": {"total": [1]}, "vi_residual": "small", "seed": "a\nb"}, ["time [1] s", "residual small", "seed a\\nb"]),
])
def test_cli_info_prints_what_build_metadata_it_has(small_table, tmp_path, capsys, build, says):
    """The loader takes `build` as optional and reads none of its fields: `graph info` tracebacked
    on a missing or odd one; now it prints what there is and "not recorded" for the rest."""
    from tools.cli import main

    arrays = _saved_arrays(small_table, tmp_path / "good.npz")
    meta = json.loads(str(arrays["meta"]))
    meta.pop("build")
    if build is not None:
        meta["build"] = build
    path = tmp_path / "g.npz"
    np.savez(path, **dict(arrays, meta=np.array(json.dumps(meta))))
    assert main(["graph", "info", str(path)]) == 0
    out = capsys.readouterr().out
    assert len(out.splitlines()) == 6, out
    for text in says:
        assert text in out, out
    assert main(["graph", "info", str(path), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["build"] == (build or {})
