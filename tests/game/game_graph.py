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
