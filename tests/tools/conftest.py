"""Fixtures for tests that run a whole Session: an Interaction Graph to play against (the
shipped one when present, else a small one built once per test session, ~1 s)."""

from __future__ import annotations

from pathlib import Path

import pytest


@pytest.fixture(scope="session")
def match_graph(tmp_path_factory) -> Path | None:
    """None (the shipped game/assets/graph.npz) when it loads, else the path of a small graph."""
    from game.interaction import InteractionGraph
    from game.interaction.build import BuildParams, build_graph

    try:
        InteractionGraph.load()
        return None
    except Exception:  # absent or from another build of the format: build a small one
        from game.actions import load_library

        path = tmp_path_factory.mktemp("graph") / "graph.npz"
        build_graph(load_library(), BuildParams(seed=3, states=400, bouts=64, bout_steps=300, max_rounds=1)).save(path)
        return path


@pytest.fixture(autouse=True)
def _own_data_dir(tmp_path, monkeypatch):
    """Never read (or write) the real user's trained templates."""
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "xdg"))
