"""Blows that land in the same simulation step all count before any knockdown is decided: the
order in which the physics reports the contacts (and so the boxers' order) decides nothing. Two
boxers floored in one step both go down and are both counted; when neither can go on the match
is a draw ("double KO"), shown as such."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

from game.match import COUNT, FIGHT

sys.path.insert(0, str(Path(__file__).parent))
from fair_play import fist_on_head, one_player, throw, touch_next_steps, two_players  # noqa: E402
from game_graph import graph_path  # noqa: E402,F401 - the fixture


@pytest.fixture(autouse=True)
def own_data_dir(tmp_path, monkeypatch):
    """Never read (or write) the real user's trained templates."""
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "xdg"))


def trade(s, health: float, reverse: bool = False) -> None:
    """Both boxers at `health`, both fists landing on the other's head in the next step."""
    s.loop.run(steps=20)
    s.match.health = [health, health]
    throw(s, 0)
    throw(s, 1)
    contacts = [fist_on_head(s, 0), fist_on_head(s, 1)]
    touch_next_steps(s, contacts[::-1] if reverse else contacts)
    s.loop.run(steps=1)


@pytest.mark.parametrize("reverse", [False, True])
def test_two_players_floored_in_one_step_both_go_down_and_are_counted(reverse) -> None:
    s = two_players()
    trade(s, 3.0, reverse)
    m = s.match
    assert [blow[1] for blow in s.blows_log] in ([0, 1], [1, 0])  # both blows counted
    assert m.hits == [1, 1] and m.health == [0.0, 0.0]
    assert m.knockdowns == [1, 1] and m.phase == COUNT and m.downed == [0, 1]
    assert [b.controller.action for b in s.boxers] == ["knockdown", "knockdown"]
    s.loop.run(steps=3 * 60)  # the first knockdown of each: both up at 3
    assert m.phase == FIGHT and m.downed == [] and m.health == [40.0, 40.0]


@pytest.mark.parametrize("reverse", [False, True])
def test_a_trade_with_the_cpu_floors_both(graph_path, reverse) -> None:  # noqa: F811
    s = one_player(graph_path)
    trade(s, 1.0, reverse)
    assert s.match.knockdowns == [1, 1] and s.match.downed == [0, 1]


def test_both_counted_out_in_one_step_is_a_drawn_double_ko() -> None:
    s = two_players(display=True)
    s.match.knockdowns = [3, 3]  # a fourth knockdown: up at 12, so out at 10
    trade(s, 3.0)
    m = s.match
    assert m.phase == COUNT and m.downed == [0, 1]
    s.loop.run(steps=10 * 60)
    assert m.over and m.winner is None and m.result == "double KO"
    assert m.round_winners == [None]
    s.view.hud.layout = []
    s.loop.run(steps=2)
    assert "DOUBLE KO - DRAW" in [text for text, _, _ in s.view.hud.layout]


def test_both_at_their_third_knockdown_of_the_round_is_a_drawn_double_ko() -> None:
    s = two_players()
    s.match.round_knockdowns = [2, 2]
    s.match.knockdowns = [2, 2]
    trade(s, 3.0)
    assert s.match.over and s.match.winner is None and s.match.result == "double KO"


def test_only_the_one_who_cannot_go_on_loses() -> None:
    s = two_players()
    s.match.knockdowns = [3, 0]  # player 1 would rise at 12: counted out; player 2 rises at 3
    trade(s, 3.0)
    m = s.match
    s.loop.run(steps=3 * 60)
    assert m.phase == COUNT and m.downed == [0] and m.health[1] == 40.0  # player 2 is up
    s.loop.run(steps=7 * 60)
    assert m.over and m.winner == 1 and m.result == "KO" and m.downed == [0]
