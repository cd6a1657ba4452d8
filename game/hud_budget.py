"""The F3 overlay: the last frame's stages as a stacked bar against the frame's period (the
16.7 ms line; 33.3 ms in low power), a chart of the last HISTORY_FRAMES frames, and per stage
its last ms, p99 against its budget and overruns.
Drawn by the HUD (game/hud.py) with its text and backgrounds."""

from __future__ import annotations

from collections import deque
from collections.abc import Sequence

import numpy as np
import pygame

from engine.budget import UNACCOUNTED, WAIT, FrameBudget
from game.hud_style import (
    BUDGET_COLUMNS,
    BUDGET_HEADERS,
    CHART_BG,
    DIM,
    HISTORY_FRAMES,
    REJECT_COLOR,
    STAGE_COLORS,
    TEXT,
    TEXT_EVERY,
    text_scale,
)


class BudgetOverlay:
    def __init__(self) -> None:
        self.p99: dict[str, float] = {}
        self.p99_frame = -10**9
        self.history: deque[np.ndarray] = deque(maxlen=HISTORY_FRAMES)  # per frame, ms per stage
        self.history_frame = -1
        self.chart: pygame.Surface | None = None  # the chart, scrolled a column per frame
        self.rows_text: list = []
        self.text_frame = -10**9
        self.rows_shown = 0  # the stages listed last frame: fewer than all where the room ran out

    def draw(self, hud, surf: pygame.Surface, budget: FrameBudget, u: float,
             below: Sequence[pygame.Rect] = (), above: Sequence[pygame.Rect] = ()) -> None:
        """A stacked bar per stage against the frame's period (the 16.7 ms line; 33.3 ms in low
        power, where a frame holds two steps), and each stage's p99; clear of the panels `below`
        (the HUD's, drawn this frame: key legends, player 2's recognition panel) and under the
        lines `above` it (two players' shared key line under the clock)."""
        w, h = surf.get_size()
        chart_h = int(90 * u)
        t = text_scale(u)  # the text and its rows stop shrinking (game/hud_style.py); the chart does not
        # u follows the window's height: on a window narrow for it (640x1080) the 440 u panel was
        # wider than the window, so there it is as wide as the window allows
        t = min(t, (w - 16) / 440)
        # the stages the loop runs, not the spans inside them (those never run at depth 0)
        names = [s.name for s in budget.stages if s.name not in (WAIT, UNACCOUNTED) and not s.nested] + [UNACCOUNTED]
        # below the clock and the mode line under it (LOW POWER, DEMO), whose text stops shrinking
        # with the window: at 800x480 the panel's top (130 u) ran over "LOW POWER  DEMO"
        top = max(int(130 * u), hud.clock_box((w, h), u).bottom + int(30 * t))
        panel = pygame.Rect(w - int(440 * t), top, int(424 * t), int(80 * t + 20 * t * (len(names) + 1)) + chart_h)
        # under a line above that reaches into its columns: with two players the shared "Esc pause
        # F3 budget F11 fullscreen" line under the clock ran under its title from 640x360 to 960x540
        panel.top = max([top] + [r.bottom + int(4 * t) for r in above if r.right > panel.left and r.left < panel.right])
        chart_h, self.rows_shown = give_way(panel, chart_h, len(names), below, t)
        # (a row's room under the last row is the chart's margin: without a chart, none)
        panel.height = int(80 * t + 20 * t * (self.rows_shown + (1 if chart_h else 0))) + chart_h
        surf.blit(hud._translucent(panel.size, (0, 0, 0, 190)), panel)
        hud.enter_panel("budget", panel)
        u = t
        last = budget.last_frame_ms()
        scale_ms = 2.0 * budget.frame_period_ms  # the bar spans two frame periods
        bar = pygame.Rect(panel.left + int(10 * u), panel.top + int(26 * u), panel.width - int(20 * u), int(18 * u))
        busiest = f"   busiest {self.rows_shown} of {len(names)}" if self.rows_shown < len(names) else ""
        hud.blit(surf, f"frame budget {budget.frame_period_ms:.1f} ms   dropped {budget.dropped_steps}{busiest}", int(18 * u), (panel.left + 10 * u, panel.top + 6 * u), TEXT)
        self._bar(surf, bar, names, last, budget, scale_ms)
        self._update_p99(budget, names)
        chart = pygame.Rect(bar.left, panel.bottom - chart_h - int(4 * u), bar.width, chart_h)
        self._chart(surf, chart, names, last, budget, scale_ms)
        self._rows(hud, surf, panel, bar, names, last, budget, u)
        hud.enter_panel("screen", None)

    @staticmethod
    def _bar(surf: pygame.Surface, bar: pygame.Rect, names: list[str], last: dict, budget: FrameBudget, scale_ms: float) -> None:
        pygame.draw.rect(surf, (50, 50, 56), bar)
        x = float(bar.left)
        for k, name in enumerate(names):
            ms = last.get(name, 0.0)
            wpx = min(bar.width * ms / scale_ms, bar.right - x)  # an overrun stops at the bar's end
            if wpx >= 1:
                pygame.draw.rect(surf, STAGE_COLORS[k % len(STAGE_COLORS)], (int(x), bar.top, int(np.ceil(wpx)), bar.height))
            x += max(wpx, 0.0)
        line_x = bar.left + bar.width * budget.frame_period_ms / scale_ms
        pygame.draw.line(surf, REJECT_COLOR, (line_x, bar.top - 4), (line_x, bar.bottom + 4), 2)

    def _update_p99(self, budget: FrameBudget, names: list[str]) -> None:
        if budget.frames - self.p99_frame >= 30:  # percentiles over the ring: twice a second
            self.p99_frame = budget.frames
            rows = budget.span_rows()  # once for all stages: each span_rows walks the whole ring
            ids, durs = budget.s_stage[rows], budget.s_dur[rows]
            for name in names:
                d = durs[(ids == budget.stage_id(name)) & (budget.s_depth[rows] == 0)]
                self.p99[name] = float(np.percentile(d, 99)) / 1e6 if len(d) else 0.0

    def _chart(self, surf: pygame.Surface, chart: pygame.Rect, names: list[str], last: dict,
               budget: FrameBudget, scale_ms: float) -> None:
        # history: a stacked column per frame against the same period line, newest on the right.
        # The chart keeps its own surface and scrolls it one column per frame, so a frame draws
        # one column, not 120 (drawing them all cost ~2 ms a frame: the overlay ate its budget)
        new = budget.frames != self.history_frame
        if new:
            self.history_frame = budget.frames
            self.history.append(np.array([last.get(n, 0.0) for n in names]))
        if chart.height < 1:  # no room for it this frame: its history is still kept
            self.chart = None
            return
        col_w = max(1, chart.width // HISTORY_FRAMES)
        px_per_ms = chart.height / scale_ms
        if self.chart is None or self.chart.get_size() != chart.size:
            self.chart = pygame.Surface(chart.size)
            self.chart.fill(CHART_BG)
            for i, ms in enumerate(self.history):  # after a resize: redraw what is kept
                self._chart_column(chart.width - (len(self.history) - i) * col_w, col_w, ms, px_per_ms)
        elif new:
            self.chart.scroll(-col_w, 0)
            self.chart.fill(CHART_BG, (chart.width - col_w, 0, col_w, chart.height))
            self._chart_column(chart.width - col_w, col_w, self.history[-1], px_per_ms)
        surf.blit(self.chart, chart)
        line_y = chart.bottom - budget.frame_period_ms * px_per_ms
        pygame.draw.line(surf, REJECT_COLOR, (chart.left, line_y), (chart.right, line_y), 1)

    def _chart_column(self, x0: int, col_w: int, ms: np.ndarray, px_per_ms: float) -> None:
        """One frame's stacked column on the chart surface, at x0."""
        y0 = float(self.chart.get_height())
        for k, v in enumerate(ms):
            hpx = min(v * px_per_ms, y0)
            if hpx >= 0.5:
                pygame.draw.rect(self.chart, STAGE_COLORS[k % len(STAGE_COLORS)], (x0, int(y0 - hpx), col_w, int(np.ceil(hpx))))
                y0 -= hpx

    def _rows(self, hud, surf: pygame.Surface, panel: pygame.Rect, bar: pygame.Rect, names: list[str],
              last: dict, budget: FrameBudget, u: float) -> None:
        stages = {s.name: s for s in budget.stages}
        if budget.frames - self.text_frame >= TEXT_EVERY or len(self.rows_text) != len(names):
            # the numbers change every frame; re-rendered 6 times a second they stay readable
            # and the text cache is not flooded with 60 new strings a second
            self.text_frame = budget.frames
            self.rows_text = []
            for name in names:
                st = stages[name]
                budget_txt = f" / {st.budget_ms:.2f}" if st.budget_ms else ""
                self.rows_text.append((name, f"{last.get(name, 0.0):.2f}", f"{self.p99.get(name, 0.0):.2f}{budget_txt}",
                                       str(st.overruns) if st.overruns else ""))
        # one column each, under a header: stage, last frame's ms, p99 / budget ms, overruns
        cols = [panel.left + 28 * u + x * u for x in BUDGET_COLUMNS]
        y = bar.bottom + 8 * u
        for x, head in zip(cols, BUDGET_HEADERS, strict=True):
            hud.blit(surf, head, int(16 * u), (x, y + 2 * u), DIM)
        for j, k in enumerate(self._busiest(names, stages, budget.frame_period_ms)):
            row = self.rows_text[k]
            y = bar.bottom + 28 * u + j * 20 * u
            pygame.draw.rect(surf, STAGE_COLORS[k % len(STAGE_COLORS)], (int(panel.left + 10 * u), int(y + 3 * u), int(12 * u), int(12 * u)))
            for x, text in zip(cols, row, strict=True):
                hud.blit(surf, text, int(18 * u), (x, y), TEXT)

    def _busiest(self, names: list[str], stages: dict, period: float) -> list[int]:
        """The rows shown, in the stages' order: all of them, else the stages nearest their
        budget (p99 against it; a stage without one against the frame's `period`)."""
        if self.rows_shown >= len(names):
            return list(range(len(names)))

        def load(k: int) -> float:
            return self.p99.get(names[k], 0.0) / (stages[names[k]].budget_ms or period)
        return sorted(sorted(range(len(names)), key=load, reverse=True)[:self.rows_shown])


def give_way(panel: pygame.Rect, chart_h: int, rows: int, below: Sequence[pygame.Rect], t: float) -> tuple[int, int]:
    """The chart's height and the number of stage rows that keep `panel` clear of the panels
    under it (at 800x450 it ran over the key legend, and with two players over player 2's
    recognition panel and legend): the chart gives way first, down to 24 t, then altogether;
    then the rows of the least loaded stages (never under 1)."""
    under = [r.top for r in below if r.left < panel.right and r.right > panel.left and r.bottom > panel.top]
    room = min(under, default=panel.bottom + int(4 * t)) - int(4 * t) - panel.top
    over = panel.height - room
    if over <= 0:
        return chart_h, rows
    if chart_h - over >= int(24 * t):
        return chart_h - over, rows
    return 0, max(1, min(rows, int((room - 80 * t) // (20 * t))))
