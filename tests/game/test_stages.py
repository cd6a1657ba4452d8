"""The session's stages are one table (game/stages.py): the loop runs them in its order, each
reads only what the set-up or an earlier stage provides, and the names are the session's own.
The HUD reads typed snapshots; source abilities are declared capabilities, not attributes."""

from __future__ import annotations

import dataclasses
import sys
from pathlib import Path

import pygame
import pytest

from engine.clock import VirtualClock
from engine.sensors import open_source
from engine.sensors.source import KEYS, PLAYABLE, Source, SourceState
from game.hud import SourceSnapshot
from game.match import MatchSnapshot
from game.session import Session, SessionConfig
from game.stages import SESSION_INPUTS, STAGES

sys.path.insert(0, str(Path(__file__).parent))
from game_graph import graph_path  # noqa: E402,F401 - the fixture

SIZE = (320, 180)


@pytest.fixture
def session(graph_path):  # noqa: F811 - the imported fixture
    import game.keyboard_source  # noqa: F401 - registers keyboard://

    pygame.init()
    clock = VirtualClock()
    source = open_source("keyboard://?seed=3", clock=clock.seconds)
    cfg = SessionConfig(seed=3, size=SIZE, sound=False, render=False, graph=graph_path, demo=True)
    return Session(source, cfg, clock=clock)


def test_every_stage_reads_what_is_there_before_it():
    provided = set(SESSION_INPUTS)
    for spec in STAGES:
        missing = set(spec.reads) - provided
        assert not missing, f"stage {spec.name} reads {missing} before anything writes it"
        provided |= set(spec.writes)
    assert len({s.name for s in STAGES}) == len(STAGES)


def test_the_loop_runs_the_table_and_the_names_are_the_sessions(session):
    names = [st.name for st in session.loop.budget.stages if st.name not in ("wait", "unaccounted")]
    assert names == [s.name for s in STAGES]
    assert {st.name: st.budget_ms for st in session.loop.budget.stages if st.name in names} == \
        {s.name: s.budget_ms for s in STAGES}
    for spec in STAGES:
        assert callable(getattr(session, f"_{spec.name}"))
        for attr in spec.reads + spec.writes:
            assert hasattr(session, attr), f"{spec.name}: the session has no {attr!r}"
    assert session.contacts == []  # set up before the physics stage first runs


def test_two_players_run_the_same_table():
    import game.keyboard_source  # noqa: F401
    from game.two_player import TwoPlayerSession, source_urls

    pygame.init()
    clock = VirtualClock()
    urls, _ = source_urls("keyboard://", "keyboard://", demo=False, seed=1)
    s = TwoPlayerSession([open_source(u, clock=clock.seconds) for u in urls],
                         SessionConfig(size=SIZE, sound=False, render=False), clock=clock)
    names = [st.name for st in s.loop.budget.stages if st.name not in ("wait", "unaccounted")]
    assert names == [sp.name for sp in STAGES]
    for spec in STAGES:
        for attr in spec.reads + spec.writes:
            assert hasattr(s, attr)
    s.loop.run(steps=5)
    assert isinstance(s.hud_state.match, MatchSnapshot)
    assert s.seats[1].hud.source.url.startswith("P2 ")


def test_the_hud_reads_a_typed_snapshot_of_the_match_and_the_source(session):
    session.loop.run(steps=120)
    st = session.hud_state
    assert st.match == session.match.snapshot() and isinstance(st.match, MatchSnapshot)
    assert st.source == SourceSnapshot.of(session.source)
    with pytest.raises(dataclasses.FrozenInstanceError):
        st.match.round = 2  # a snapshot, not the match


class _Remote(Source):
    """A source with a press_key method it does not declare: the game must not call it."""

    def __init__(self):
        super().__init__(url="remote://", sensors=2, state=SourceState.CONNECTED)
        self.pressed: list[str] = []

    def poll(self):
        return []

    def press_key(self, name):
        self.pressed.append(name)

    def press(self, action):
        self.pressed.append(action)


def test_abilities_are_declared_capabilities_not_attributes(graph_path):  # noqa: F811
    import game.keyboard_source as kb

    assert kb.KeyboardSource.capabilities == {PLAYABLE, KEYS} and Source.capabilities == frozenset()
    pygame.init()
    clock = VirtualClock()
    remote = _Remote()
    s = Session(remote, SessionConfig(size=SIZE, sound=False, render=False, graph=graph_path, demo=True), clock=clock)
    s.handle_event(pygame.event.Event(pygame.KEYDOWN, key=pygame.K_j))
    s.loop.run(steps=200)  # the demo pilot would press moves on a PLAYABLE source by now
    assert remote.pressed == [] and s.hud_state.keys == []
    # the same class declaring the abilities is driven by both
    remote.capabilities = frozenset({PLAYABLE, KEYS})
    remote.busy, remote.profile, remote.keymap = False, "experienced", {"j": "straight_l"}
    s.handle_event(pygame.event.Event(pygame.KEYDOWN, key=pygame.K_j))
    assert remote.pressed == ["j"]
