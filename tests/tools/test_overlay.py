"""The F3 overlay's chart scrolls one column per frame: after a few frames the newest frames'
stacked columns are on the right of the chart, the rest is background; a resize redraws it."""

from __future__ import annotations

import numpy as np
import pygame

from game.hud import CHART_BG, HISTORY_FRAMES
from tools.scripted_match import build_session


def drawn_columns(chart: pygame.Surface) -> np.ndarray:
    px = pygame.surfarray.array3d(chart)  # (w, h, 3)
    return np.flatnonzero(np.any(np.any(px != np.array(CHART_BG), axis=-1), axis=1))


def test_chart_scrolls_a_column_per_frame(match_graph) -> None:
    s = build_session(seed=1, size=(1280, 720), graph=match_graph)
    s.hud_state.show_budget = True
    s.loop.run(frames=10)
    chart = s.hud._chart
    col_w = max(1, chart.get_width() // HISTORY_FRAMES)
    cols = drawn_columns(chart)
    # ten frames drawn: only the rightmost ten columns hold stage colours (the render stage is
    # several ms, so every frame's column is visible)
    assert cols.min() >= chart.get_width() - 10 * col_w
    assert len(set(cols // col_w)) >= 9
    s.loop.run(frames=20)
    assert drawn_columns(s.hud._chart).min() < chart.get_width() - 20 * col_w
    # one line of numbers per stage
    assert len(s.hud._rows_text) == len([st for st in s.loop.budget.stages if st.name != "wait"])
    # a new window size rebuilds the chart from the kept history
    s.hud.draw(pygame.Surface((640, 360)), s.hud_state, s.loop.budget)
    small = s.hud._chart
    assert small.get_size() != chart.get_size() and len(drawn_columns(small)) > 0
