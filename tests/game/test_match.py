"""Match rules: the round clock, knockdowns and the count, TKO, points, pause."""

from __future__ import annotations

from game.match import BREAK, COUNT, DOUBLE_KO, FIGHT, RISE_HEALTH, Match


def run(m: Match, steps: int) -> None:
    for _ in range(steps):
        m.step()


def test_three_rounds_then_points() -> None:
    m = Match()
    m.hit(1, 10.0)  # the player wins round 1 on damage
    run(m, 60 * 60)
    assert m.phase == BREAK and m.scores == [10, 9]
    run(m, 3 * 60)
    assert m.phase == FIGHT and m.round == 2 and m.seconds_left() == 60
    run(m, 60 * 60 + 3 * 60 + 60 * 60)
    assert m.over and m.result == "points" and m.winner == 0
    assert m.scores == [30, 29]
    kinds = [k for k, _ in m.drain_events()]
    assert kinds.count("bell") == 5  # end of 1, start of 2, end of 2, start of 3, end of 3


def test_even_rounds_are_a_draw() -> None:
    m = Match(round_seconds=1)
    run(m, 10_000)
    assert m.over and m.winner is None and m.result == "draw"


def test_knockdown_count_and_rise() -> None:
    m = Match()
    assert m.hit(1, 150.0)
    assert m.phase == COUNT and m.downed == [1] and m.health[1] == 0
    assert not m.hit(1, 10.0)  # no hitting a boxer who is down
    clock = m.clock_steps
    run(m, 3 * 60)  # first knockdown: up at 3
    assert m.phase == FIGHT and m.downed == [] and m.health[1] == 40.0
    assert m.clock_steps == clock  # the round clock stops during the count


def test_third_knockdown_in_a_round_is_a_tko() -> None:
    m = Match()
    for _ in range(2):
        m.hit(1, 200.0)
        run(m, 10 * 60)
        assert m.phase == FIGHT
    m.hit(1, 200.0)
    assert m.over and m.result == "TKO" and m.winner == 0


def test_counted_out_is_a_ko() -> None:
    m = Match()
    m.hit(0, 200.0)
    run(m, 3 * 60)  # up at 3
    run(m, 60 * 60)  # the round ends; the knockdown costs a point
    assert m.scores == [8, 10]
    run(m, 3 * 60)
    m.hit(0, 200.0)
    run(m, 6 * 60)  # up at 6
    assert m.phase == FIGHT
    m.hit(0, 200.0)
    run(m, 9 * 60)  # up at 9
    assert m.phase == FIGHT
    m.hit(0, 200.0)  # fourth: would rise at 12: out at 10 (a third in round 2 is also a TKO)
    assert m.over and m.winner == 1


def test_pause_stops_everything() -> None:
    m = Match()
    m.toggle_pause()
    before = m.state()
    run(m, 500)
    assert not m.hit(1, 10.0)
    assert m.state() == before
    m.toggle_pause()
    run(m, 60)
    assert m.seconds_left() == 59


def test_state_is_reproducible() -> None:
    def play() -> tuple:
        m = Match()
        for i in range(4000):
            if i % 97 == 0:
                m.hit(i % 2, 13.0)
            m.step()
        return m.state()

    assert play() == play()


def test_a_blow_of_no_finite_damage_does_not_count() -> None:
    # a NaN blow (a hit dict from outside the game, Session.apply_hit) knocked the boxer down
    # (max(0, health - nan) is 0) and left NaN in the round's damage, so the scorecards compared
    # NaN; an infinite one knocked down whatever the health. Neither counts now.
    for damage in (float("nan"), float("inf"), -float("inf")):
        m = Match()
        assert not m.hit(1, damage)
        assert m.phase == FIGHT and m.downed == [] and m.health == [100.0, 100.0]
        assert m.round_damage == [0.0, 0.0] and m.hits == [0, 0]


def trade(m: Match, damage: tuple[float, float], order: tuple[int, int] = (0, 1)) -> list[bool]:
    """Both boxers take a blow in one step (`damage[i]` on boxer i), landed in `order`."""
    counted = [m.land(i, damage[i]) for i in order]
    m.settle_knockdowns()
    return counted


def test_blows_of_one_step_all_count_whatever_their_order() -> None:
    states = []
    for order in ((0, 1), (1, 0)):
        m = Match()
        m.health = [3.0, 3.0]
        assert trade(m, (5.0, 4.0), order) == [True, True]
        assert m.knockdowns == [1, 1] and m.downed == [0, 1] and m.hits == [1, 1]
        assert [e for e in m.drain_events()] == [("knockdown", 0), ("knockdown", 1)]
        states.append(m.state())
    assert states[0] == states[1]


def test_a_double_knockdown_is_counted_for_both_each_rising_at_its_count() -> None:
    m = Match()
    m.knockdowns = [1, 0]  # boxer 0's second knockdown: up at 6; boxer 1's first: up at 3
    m.health = [2.0, 2.0]
    trade(m, (9.0, 9.0))
    run(m, 3 * 60)
    assert m.phase == COUNT and m.downed == [0] and m.health == [0.0, 40.0]
    assert not m.hit(0, 5.0)  # the one up waits: no blows while the other is counted
    run(m, 3 * 60)
    assert m.phase == FIGHT and m.downed == [] and m.health == [40.0, 40.0]
    assert [w for k, w in m.drain_events() if k == "rise"] == [1, 0]


def test_a_double_knockdown_that_ends_the_match_for_both_is_a_draw() -> None:
    m = Match()
    m.knockdowns = [3, 3]  # up at 12: both out at 10
    m.health = [1.0, 1.0]
    trade(m, (9.0, 9.0))
    run(m, 10 * 60 - 1)
    assert m.phase == COUNT
    run(m, 1)
    assert m.over and m.result == DOUBLE_KO and m.winner is None and m.downed == [0, 1]
    assert m.round_winners == [None]


def test_a_tko_with_the_other_boxer_down_too() -> None:
    m = Match()
    m.round_knockdowns, m.knockdowns = [2, 0], [2, 0]
    m.health = [1.0, 1.0]
    trade(m, (9.0, 9.0))  # boxer 0's third of the round; boxer 1 could rise at 3
    assert m.over and m.result == "TKO" and m.winner == 1
    assert m.downed == [0] and m.health == [0.0, RISE_HEALTH]  # the winner is up at once
    m = Match()
    m.round_knockdowns, m.knockdowns = [2, 0], [2, 3]
    m.health = [1.0, 1.0]
    trade(m, (9.0, 9.0))  # boxer 0 stopped, boxer 1 could not rise before 10 either
    assert m.over and m.result == DOUBLE_KO and m.winner is None
