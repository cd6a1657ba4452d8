"""The Interaction Graph the game tests play against: the shipped table, else a small one built
once per test run (~3 s)."""

from __future__ import annotations

import pytest


@pytest.fixture(scope="session")
def graph_path(tmp_path_factory) -> str:
    from game.interaction import DEFAULT_GRAPH

    if DEFAULT_GRAPH.exists():
        return str(DEFAULT_GRAPH)
    from tools.cli import main

    out = tmp_path_factory.mktemp("graph") / "graph.npz"
    assert main(["graph", "build", "-o", str(out), "--states", "3000", "--bouts", "256", "--quiet"]) == 0
    return str(out)


def other_library_graph(graph: str, out) -> str:
    """`graph` as if built from another action library: its first action renamed "zzz" (a name
    the game's library lacks) and chosen in every state."""
    import numpy as np

    with np.load(graph, allow_pickle=False) as f:
        arrays = dict(f)
    names = arrays["action_names"].astype("U32")
    names[0] = "zzz"
    arrays["action_names"] = names
    arrays["best_action"] = np.zeros_like(arrays["best_action"])
    np.savez_compressed(out, **arrays)
    return str(out)
