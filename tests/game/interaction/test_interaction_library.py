"""The Interaction Graph against the real action library and the shipped graph."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from game.actions import ACTION_NAMES, load_library
from game.interaction import DEFAULT_GRAPH, InteractionGraph, Situation
from game.interaction.bout import BoutRules, Bouts, Rewards, step
from game.interaction.build import BuildParams, build_graph, compile_table
from game.interaction.duel import duel

REPO = Path(__file__).resolve().parents[3]


@pytest.fixture(scope="module")
def lib():
    return load_library()


@pytest.fixture(scope="module")
def shipped():
    return InteractionGraph.load(DEFAULT_GRAPH)


def test_table_compiles_the_library(lib):
    t = compile_table(lib, BoutRules())
    assert t.names[:13] == list(ACTION_NAMES) and t.names[13] == "guard"
    assert "knockdown" not in t.names
    assert all(lib[n].kind == "reaction" for n in t.names[14:])
    # hits pick the reaction of the part, the side the blow comes from and its strength
    w = t.window[t.index("hook_r")].max()
    assert t.names[t.win_react[w]] == "hit_head_left_heavy"
    w = t.window[t.index("straight_l")].max()
    assert t.names[t.win_react[w]] == "hit_head_front_light"


def test_a_parry_turns_a_straight_into_chip_damage(lib):
    t = compile_table(lib, BoutRules())
    b = Bouts(t, 2)
    b.place(np.array([0.8, 0.8]), np.zeros(2), np.zeros(2))
    b.hp[:] = 100.0
    b.start(np.array([0, 1]), 0, t.index("straight_r"))
    b.start(np.array([0]), 1, t.index("parry_l"))
    b.start(np.array([1]), 1, t.index("step_left"))
    for _ in range(14):
        step(b, BoutRules(), Rewards())
    assert b.hp[0, 1] == pytest.approx(100.0 - 0.2 * 9.0)   # parried: the referee's fifth
    assert b.hp[1, 1] == pytest.approx(100.0 - 9.0)      # stepping: hit clean


def test_small_build_with_the_library_is_deterministic(lib):
    p = BuildParams(seed=5, states=300, bouts=64, bout_steps=200, max_rounds=1)
    a, b = build_graph(lib, p), build_graph(lib, p)
    np.testing.assert_array_equal(a.keys, b.keys)
    np.testing.assert_array_equal(a.best_action, b.best_action)
    np.testing.assert_array_equal(a.edge_dst, b.edge_dst)


def test_shipped_graph_matches_the_library(lib, shipped):
    table = compile_table(lib, shipped.table.rules)
    assert shipped.names == table.names
    assert shipped.table.build["library"] == table.fingerprint(), \
        "the action library changed: rebuild with quickjab graph build -o game/assets/graph.npz"
    assert shipped.n_states >= 55560 and shipped.n_edges >= 107167
    assert DEFAULT_GRAPH.stat().st_size < 8_000_000


def test_shipped_graph_fill_holds_every_state_cell(shipped):
    idx = shipped.index
    pos = np.searchsorted(idx.fill_keys, idx.keys)
    np.testing.assert_array_equal(idx.fill_keys[pos], idx.keys)
    np.testing.assert_array_equal(idx.fill_state[pos], np.arange(idx.n))


def test_shipped_graph_answers_with_an_action(shipped):
    s = Situation(0.9, 0.0, 0.0, np.pi, "guard", 0.0, "straight_r", 3.0)
    assert shipped.best_action(s) in (*ACTION_NAMES, "guard")


def test_shipped_graph_beats_random_and_greedy_in_a_short_duel(lib, shipped):
    for opp in ("random", "greedy"):
        r = duel(shipped, lib, opp, bouts=20, seconds=30.0, seed=7)
        assert r.wins > r.losses and r.hits_landed > r.hits_received, r.as_dict()


def test_cli_duel_runs(tmp_path):
    r = subprocess.run([sys.executable, "-m", "tools.cli", "graph", "duel", "--bouts", "4",
                        "--seconds", "5", "--json"], cwd=REPO, capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    import json
    out = json.loads(r.stdout)
    assert [d["opponent"] for d in out] == ["random", "greedy"]
    assert all(d["wins"] + d["losses"] + d["draws"] == 4 for d in out)


def test_cli_build_writes_a_loadable_graph(tmp_path):
    out = tmp_path / "g.npz"
    r = subprocess.run([sys.executable, "-m", "tools.cli", "graph", "build", "-o", str(out),
                        "--states", "200", "--bouts", "64", "--quiet"],
                       cwd=REPO, capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    g = InteractionGraph.load(out)
    assert g.n_states == 200 and g.table.build["seed"] == 0


def test_opponent_controller_drives_the_motion_controller(lib, shipped):
    from game.interaction import OpponentController
    from game.motion import PlayerController

    pc = PlayerController(lib)
    oc = OpponentController(shipped, lib, controller=pc)
    # the other stands at the guard just inside straight range, facing us
    s = Situation(0.95, 0.0, 0.0, np.pi, "guard", 0.0, "guard", 0.0)
    chosen, steps = [], 0
    while len(chosen) < 3 and steps < 400:
        c = oc.decide(s)
        if c is not None:
            chosen.append(c)
            # it acts only from the guard: right after choosing an action it is busy
            if c != "guard":
                assert pc.action == c
                pc.step()
                assert oc.decide(s) is None
        pc.step()
        steps += 1
    assert len(chosen) == 3 and all(c in (*ACTION_NAMES, "guard") for c in chosen)
    assert any(lib[c].kind == "attack" for c in chosen if c != "guard"), chosen


def test_bench_graph_on_the_shipped_graph_agrees_with_brute_force():
    r = subprocess.run([sys.executable, "-m", "tools.cli", "bench", "graph", "--graph", str(DEFAULT_GRAPH),
                        "--lookups", "300", "--loads", "1", "--json"],
                       cwd=REPO, capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    import json
    fig = json.loads(r.stdout)
    assert fig["states"] == 60000 and fig["agreement_with_brute_force"] == 1.0
    assert fig["lookup_us"] > 0 and fig["brute_force_us"] > 0 and fig["load_s_median"] > 0


def test_duel_refuses_a_graph_built_from_another_library(lib, tmp_path):
    sys.path.insert(0, str(Path(__file__).parent.parent))  # tests/game: hand_actions
    from hand_actions import hand_library
    other = build_graph(hand_library(), BuildParams(seed=1, states=100, bouts=32, bout_steps=100, max_rounds=1))
    with pytest.raises(ValueError, match="rebuild"):
        duel(InteractionGraph(other), lib, "random", bouts=2, seconds=1.0)
