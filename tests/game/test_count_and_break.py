"""While nobody can box (the referee counts, the break between rounds) nothing done then acts
after it: a motion the player makes is over for the boxer there and then (as under the pause),
and a fist's touch spends no hand. A TKO winner who was down too is on their feet at the end."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).parent))
from fair_play import fist_on_head, throw, touch_next_steps, two_players  # noqa: E402

from game.match import COUNT, FIGHT  # noqa: E402


@pytest.fixture(autouse=True)
def own_data_dir(tmp_path, monkeypatch):
    """Never read (or write) the real user's trained templates."""
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "xdg"))


def _stop_boxing(s, why: str) -> None:
    """Boxer 2 floored (the referee counts), or the round's bell (the break)."""
    if why == "count":
        s.match.hit(1, 200.0)
        assert s.match.phase == COUNT
    else:
        s.match.clock_steps = 1
        s.loop.run(steps=1)
        assert s.match.phase == "break"


def _box_again(s) -> None:
    """The count or the break over on the next step."""
    m = s.match
    if m.phase == COUNT:
        m.count, m.count_steps = m.rise_count(1) - 1, m.hz - 1
    else:
        m.clock_steps = 1


@pytest.mark.parametrize("why", ["count", "break"])
def test_a_motion_made_while_nobody_can_box_does_nothing_after_it(why) -> None:
    """A left hook made during the count (or the break) was ignored, but its second half (the
    hand coming back) or a switch of it started a punch once the boxing went on."""
    s = two_players()
    s.loop.run(steps=60)  # the recognizers learn the resting gravity
    _stop_boxing(s, why)
    s.loop.run(steps=2)
    s.seats[0].source.press("hook_l")
    starts, actions = 0, set()
    for _ in range(240):
        s.loop.run(steps=1)
        new = sum(1 for seat, ev in s.events_log if seat == 0 and ev["event"] == "start")
        if s.match.phase != FIGHT and new > starts == 0:
            _box_again(s)  # on again just after the recognizer named the motion
        starts = new
        actions.add(s.boxers[0].controller.action)
    assert s.match.phase == FIGHT
    assert starts >= 1  # the recognizer saw the motion ...
    assert actions == {"guard"}  # ... and the boxer did nothing with it


@pytest.mark.parametrize("why", ["count", "break"])
def test_a_touch_while_nobody_can_box_spends_no_hand(why) -> None:
    """A fist on the head during the count (or the break) counted no blow but spent its hand:
    the punch was used up on a blow the referee did not count."""
    s = two_players()
    s.loop.run(steps=20)
    _stop_boxing(s, why)
    s.loop.run(steps=2)
    health, hits = list(s.match.health), list(s.match.hits)
    throw(s, 0)
    touch_next_steps(s, [fist_on_head(s, 0)])
    s.loop.run(steps=1)
    assert not s.boxers[0].hand_spent("r")
    assert s.match.health == health and s.match.hits == hits and len(s.blows_log) == 0


def test_a_tko_winner_floored_in_the_same_step_is_on_their_feet() -> None:
    """Player 1's third knockdown of the round (a TKO) in the step player 2 went down too: the
    winner lay on the canvas under "TKO - YOU WIN" (the KO winner has risen by the 10)."""
    s = two_players()
    s.loop.run(steps=20)
    s.match.round_knockdowns, s.match.knockdowns = [2, 0], [2, 0]
    s.match.health = [3.0, 3.0]
    throw(s, 0)
    throw(s, 1)
    touch_next_steps(s, [fist_on_head(s, 0), fist_on_head(s, 1)])
    s.loop.run(steps=1)
    m = s.match
    assert m.over and m.result == "TKO" and m.winner == 1 and m.knockdowns == [3, 1]
    s.loop.run(steps=60)
    assert m.downed == [0] and m.health[1] == 40.0  # up, as one who rises from the count
    assert [b.controller.action for b in s.boxers] == ["knockdown", "guard"]
