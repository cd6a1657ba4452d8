"""Match rules: the round clock, knockdowns and the count, TKO, points, pause."""

from __future__ import annotations

from game.match import BREAK, COUNT, FIGHT, Match


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
    assert m.phase == COUNT and m.down == 1 and m.health[1] == 0
    assert not m.hit(1, 10.0)  # no hitting a boxer who is down
    clock = m.clock_steps
    run(m, 3 * 60)  # first knockdown: up at 3
    assert m.phase == FIGHT and m.down is None and m.health[1] == 40.0
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
        assert m.phase == FIGHT and m.down is None and m.health == [100.0, 100.0]
        assert m.round_damage == [0.0, 0.0] and m.hits == [0, 0]
