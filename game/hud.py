"""The heads-up display: health bars, round clock, knockdown count, the recognizer's view (action,
score, main and supplementary buffers filling, switch and reject marks), the input source and
its state and battery, key help, banners and overlays, and the F3 frame-budget overlay.

Everything it shows comes in a `HudState` the session fills each step; the HUD only draws.
Positions are fractions of the window so a resized window keeps the layout. Text surfaces are
cached: the same string in the same style is rendered once.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field

import numpy as np
import pygame

from engine.budget import UNACCOUNTED, WAIT, FrameBudget
from engine.clock import STEP_HZ
from engine.sensors.source import Source
from game.match import MatchSnapshot
from game.rules import MAX_HEALTH

PLAYER_COLOR = (235, 64, 52)
OPPONENT_COLOR = (52, 120, 235)
BAR_BACK = (34, 30, 38)
BAR_LOSS = (250, 210, 90)  # the recently lost health, shown draining after the fill
TEXT = (242, 240, 232)
DIM = (170, 166, 160)
KEY_TEXT = (228, 225, 218)  # the key legend, on its dark panel
SWITCH_COLOR = (255, 200, 40)
REJECT_COLOR = (255, 70, 70)
OK_COLOR = (90, 220, 120)
STAGE_COLORS = [
    (102, 194, 165), (252, 141, 98), (141, 160, 203), (231, 138, 195), (166, 216, 84),
    (255, 217, 47), (229, 196, 148), (179, 179, 179), (120, 200, 240), (240, 120, 120),
]
MARK_STEPS = 45  # how long a switch / reject mark stays lit
CHART_BG = (30, 30, 36)
TEXT_EVERY = 10  # frames between refreshes of the F3 overlay's numbers
COUNT_X = 0.3  # the knockdown count's centre, as a fraction of the width
BUDGET_HEADERS = ("stage", "last ms", "p99 / budget ms", "overruns")
BUDGET_COLUMNS = (0, 110, 185, 320)  # their x in the F3 panel (720p pixels from the colour key)
HISTORY_FRAMES = 120  # the F3 overlay's chart: the last two seconds, a stacked column a frame


@dataclass(frozen=True, slots=True)
class SourceSnapshot:
    """What the HUD shows of a source: the line under the health bars."""

    url: str = ""
    state: str = "connected"
    battery: float | None = None

    @classmethod
    def of(cls, source: Source, url: str | None = None) -> SourceSnapshot:
        """The source now; `url` to show another label (two players: "P1 wiimote://")."""
        return cls(source.url if url is None else url, source.state.value, source.battery)


@dataclass
class HudState:
    """Everything the HUD draws. The match and the source come as typed snapshots the session
    takes once a step; the rest is the HUD's own (marks, messages, panels)."""

    match: MatchSnapshot = field(default_factory=MatchSnapshot)
    source: SourceSnapshot = field(default_factory=SourceSnapshot)
    shown_health: list[float] = field(default_factory=lambda: [MAX_HEALTH, MAX_HEALTH])  # drains after hits
    max_health: float = MAX_HEALTH
    names: tuple[str, str] = ("YOU", "CPU")
    # recognition
    action: str = ""
    score: float | None = None
    last_event: str = ""
    switch_age: int = MARK_STEPS
    switch_from: int = 0  # n_p: the clip frame the character continued from
    reject_age: int = MARK_STEPS
    main_fill: int = 0
    main_size: int = 6
    supp_fill: int = 0
    supp_size: int = 60
    # source
    keyboard_banner: bool = False
    templates: str = ""  # which template set the recognizer uses (session.templates_in_use)
    difficulty: str = ""  # the CPU's (game/difficulty.py), shown in the pause menu
    disconnected: bool = False
    keys: list[tuple[str, str]] = field(default_factory=list)
    mode: str = ""
    demo: bool = False
    show_budget: bool = False
    message: str = ""  # a transient centre message (round 2, fight!...)
    message_age: int = 0

    def mark(self, event: dict) -> None:
        """Note a recognizer event."""
        kind = event.get("event", "")
        self.last_event = kind
        if kind in ("start", "switch"):
            self.action = event.get("action", "")
            self.score = event.get("score")
        if kind == "switch":
            self.switch_age = 0
            self.switch_from = int(event.get("from_frame", 0) or 0)
        elif kind == "reject":
            self.reject_age = 0
            self.action = event.get("action", "") or "no match"
            self.score = event.get("score")

    def tick(self) -> None:
        """Advance timed marks by one step."""
        self.switch_age = min(MARK_STEPS, self.switch_age + 1)
        self.reject_age = min(MARK_STEPS, self.reject_age + 1)
        self.message_age += 1
        health = self.match.health
        for i in (0, 1):
            # the lost-health band drains at 40 health per second, after the fill
            if self.shown_health[i] > health[i]:
                self.shown_health[i] = max(health[i], self.shown_health[i] - 40.0 / STEP_HZ)
            else:
                self.shown_health[i] = health[i]


def action_label(action: str) -> str:
    """An action as the HUD names it: "straight L", not "straight l" (which reads as "I")."""
    name = action.replace("_", " ")
    if name.endswith(" l") or name.endswith(" r"):
        name = name[:-1] + name[-1].upper()
    return name


class TextCache:
    def __init__(self) -> None:
        self._fonts: dict[int, pygame.font.Font] = {}
        self._cache: dict[tuple, pygame.Surface] = {}

    def font(self, size: int) -> pygame.font.Font:
        if size not in self._fonts:
            self._fonts[size] = pygame.font.Font(None, size)
        return self._fonts[size]

    def render(self, text: str, size: int, color=TEXT, shadow: bool = True) -> pygame.Surface:
        key = (text, size, color, shadow)
        surf = self._cache.get(key)
        if surf is None:
            if len(self._cache) > 512:
                self._cache.clear()
            font = self.font(size)
            fg = font.render(text, True, color)
            if shadow:
                surf = pygame.Surface((fg.get_width() + 2, fg.get_height() + 2), pygame.SRCALPHA)
                surf.blit(font.render(text, True, (0, 0, 0)), (2, 2))
                surf.blit(fg, (0, 0))
            else:
                surf = fg
            self._cache[key] = surf
        return surf


class Hud:
    def __init__(self) -> None:
        self.text = TextCache()
        self._p99: dict[str, float] = {}
        self._p99_frame = -10**9
        self._history: deque[np.ndarray] = deque(maxlen=HISTORY_FRAMES)  # per frame, ms per stage
        self._history_frame = -1
        self._chart: pygame.Surface | None = None  # the F3 chart, scrolled a column per frame
        self._fills: dict[tuple, pygame.Surface] = {}  # translucent backgrounds, by size and colour
        self._rows_text: list[str] = []
        self._text_frame = -10**9
        self.key_panel: pygame.Rect | None = None  # where the key legend was drawn last (tests)
        self.count_rect: pygame.Rect | None = None  # where the knockdown count was drawn last

    # layout helpers (fractions of the window, so resizes keep the layout)
    @staticmethod
    def health_rects(size: tuple[int, int]) -> tuple[pygame.Rect, pygame.Rect]:
        """Outer rectangles of the player's (left) and opponent's (right) health bars."""
        w, h = size
        bw, bh = int(w * 0.36), max(12, int(h * 0.035))
        y = int(h * 0.04)
        return pygame.Rect(int(w * 0.03), y, bw, bh), pygame.Rect(w - int(w * 0.03) - bw, y, bw, bh)

    def blit(self, surf: pygame.Surface, text: str, size: int, pos, color=TEXT, anchor: str = "topleft") -> pygame.Rect:
        img = self.text.render(text, size, color)
        rect = img.get_rect(**{anchor: (int(pos[0]), int(pos[1]))})
        surf.blit(img, rect)
        return rect

    def _translucent(self, size: tuple[int, int], rgba: tuple[int, int, int, int]) -> pygame.Surface:
        """A translucent background of this size and colour, made once (not once a frame)."""
        key = (tuple(size), rgba)
        bg = self._fills.get(key)
        if bg is None:
            if len(self._fills) > 64:  # window resizes leave old sizes behind
                self._fills.clear()
            bg = self._fills[key] = pygame.Surface(size, pygame.SRCALPHA)
            bg.fill(rgba)
        return bg

    def draw(self, surf: pygame.Surface, st: HudState, budget: FrameBudget | None = None) -> None:
        w, h = surf.get_size()
        u = h / 720.0  # type scale
        self._health(surf, st, u)
        self._clock(surf, st, u)
        self._source(surf, st, u)
        self._recognition(surf, st, u)
        self._keys(surf, st, u)
        self._centre(surf, st, u)
        if st.show_budget and budget is not None:
            self._budget(surf, budget, u)
        if st.disconnected:
            self._disconnected(surf, st, u)

    def _health(self, surf: pygame.Surface, st: HudState, u: float) -> None:
        rects = self.health_rects(surf.get_size())
        for i, (rect, color) in enumerate(zip(rects, (PLAYER_COLOR, OPPONENT_COLOR), strict=True)):
            pygame.draw.rect(surf, (0, 0, 0), rect.inflate(6, 6), border_radius=4)
            pygame.draw.rect(surf, BAR_BACK, rect)
            frac = max(0.0, min(1.0, st.match.health[i] / st.max_health))
            shown = max(frac, min(1.0, st.shown_health[i] / st.max_health))
            # the player's bar drains towards the centre of the screen (right), the CPU's to the left
            def part(f: float, rect: pygame.Rect = rect, i: int = i) -> pygame.Rect:
                wpx = int(rect.width * f)
                return pygame.Rect(rect.right - wpx if i == 1 else rect.left, rect.top, wpx, rect.height)
            pygame.draw.rect(surf, BAR_LOSS, part(shown))
            fill = part(frac)
            pygame.draw.rect(surf, color, fill)
            pygame.draw.rect(surf, tuple(min(255, c + 60) for c in color), (fill.left, fill.top, fill.width, max(2, rect.height // 4)))
            name_anchor = "topleft" if i == 0 else "topright"
            name_pos = (rect.left, rect.bottom + 4) if i == 0 else (rect.right, rect.bottom + 4)
            self.blit(surf, st.names[i], int(30 * u), name_pos, TEXT, name_anchor)
            # knockdown pips
            for k in range(st.match.knockdowns[i]):
                off = 70 * u + k * 18 * u
                cx = rect.left + off if i == 0 else rect.right - off
                pygame.draw.circle(surf, (255, 255, 255), (int(cx), int(rect.bottom + 14 * u)), int(6 * u))

    def _clock(self, surf: pygame.Surface, st: HudState, u: float) -> None:
        w, _ = surf.get_size()
        secs = max(0, int(np.ceil(st.match.seconds_left)))
        box = pygame.Rect(0, 0, int(120 * u), int(78 * u))
        box.midtop = (w // 2, int(12 * u))
        pygame.draw.rect(surf, (12, 12, 18), box, border_radius=int(8 * u))
        pygame.draw.rect(surf, (90, 86, 96), box, 2, border_radius=int(8 * u))
        label = "BREAK" if st.match.phase == "break" else f"ROUND {st.match.round}/{st.match.rounds}"
        self.blit(surf, label, int(22 * u), (w // 2, box.top + 6 * u), DIM, "midtop")
        col = REJECT_COLOR if st.match.phase == "fight" and secs <= 10 else TEXT
        self.blit(surf, f"{secs // 60}:{secs % 60:02d}", int(50 * u), (w // 2, box.top + 26 * u), col, "midtop")
        mode = "  ".join(m for m in (st.mode, "DEMO" if st.demo else "") if m)
        if mode:
            self.blit(surf, mode, int(22 * u), (w // 2, box.bottom + 4 * u), SWITCH_COLOR, "midtop")

    def _source(self, surf: pygame.Surface, st: HudState, u: float) -> None:
        left, _ = self.health_rects(surf.get_size())
        y = left.bottom + 32 * u
        state_col = OK_COLOR if st.source.state == "connected" else (SWITCH_COLOR if st.source.state in ("reconnecting", "connecting") else REJECT_COLOR)
        pygame.draw.circle(surf, state_col, (int(left.left + 7 * u), int(y + 8 * u)), int(6 * u))
        r = self.blit(surf, f"{st.source.url}  {st.source.state}", int(22 * u), (left.left + 18 * u, y), DIM)
        if st.templates:
            self.blit(surf, st.templates, int(18 * u), (left.left + 18 * u, y + 22 * u), DIM)
        if st.source.battery is not None:
            bx, by = r.right + 12 * u, y + 2 * u
            body = pygame.Rect(int(bx), int(by), int(34 * u), int(14 * u))
            pygame.draw.rect(surf, DIM, body, 2)
            pygame.draw.rect(surf, DIM, (body.right, body.top + body.height // 4, int(3 * u), body.height // 2))
            b = max(0.0, min(1.0, st.source.battery))
            pygame.draw.rect(surf, OK_COLOR if b > 0.25 else REJECT_COLOR, (body.left + 3, body.top + 3, int((body.width - 6) * b), body.height - 6))
        if st.keyboard_banner:
            w, _ = surf.get_size()
            msg = "No Wiimote found: playing from the keyboard (keys below)"
            img = self.text.render(msg, int(24 * u), (20, 20, 20), shadow=False)
            box = img.get_rect(midtop=(w // 2, int(118 * u))).inflate(int(24 * u), int(10 * u))
            pygame.draw.rect(surf, SWITCH_COLOR, box, border_radius=int(6 * u))
            surf.blit(img, img.get_rect(center=box.center))

    def _recognition(self, surf: pygame.Surface, st: HudState, u: float) -> None:
        _, h = surf.get_size()
        panel = pygame.Rect(int(16 * u), h - int(170 * u), int(330 * u), int(118 * u))
        surf.blit(self._translucent(panel.size, (10, 10, 16, 170)), panel)
        x, y = panel.left + 12 * u, panel.top + 8 * u
        self.blit(surf, "RECOGNIZED", int(18 * u), (x, y), DIM)
        name = action_label(st.action) if st.action else "-"
        r = self.blit(surf, name, int(34 * u), (x, y + 16 * u), TEXT)
        if st.score is not None:
            self.blit(surf, f"score {st.score:.2f}", int(22 * u), (r.right + 10 * u, y + 24 * u), DIM)
        # marks
        if st.switch_age < MARK_STEPS:
            self._mark(surf, f"SWITCH @{st.switch_from}", SWITCH_COLOR, (panel.right - 8 * u, panel.top + 8 * u), u)
        if st.reject_age < MARK_STEPS:
            self._mark(surf, "REJECT", REJECT_COLOR, (panel.right - 8 * u, panel.top + 34 * u), u)
        # main buffer: one cell per frame
        by = panel.top + 62 * u
        self.blit(surf, "main", int(18 * u), (x, by), DIM)
        cw = 22 * u
        for k in range(st.main_size):
            cell = pygame.Rect(int(x + 70 * u + k * (cw + 4 * u)), int(by), int(cw), int(12 * u))
            pygame.draw.rect(surf, OK_COLOR if k < st.main_fill else (60, 60, 70), cell)
        # supplementary buffer: a thin gauge
        sy = by + 22 * u
        self.blit(surf, "supp.", int(18 * u), (x, sy), DIM)
        gauge = pygame.Rect(int(x + 70 * u), int(sy), int(230 * u), int(12 * u))
        pygame.draw.rect(surf, (60, 60, 70), gauge)
        f = min(1.0, st.supp_fill / max(1, st.supp_size))
        pygame.draw.rect(surf, (120, 190, 255), (gauge.left, gauge.top, int(gauge.width * f), gauge.height))

    def _mark(self, surf: pygame.Surface, text: str, color, topright, u: float) -> None:
        img = self.text.render(text, int(20 * u), (15, 15, 15), shadow=False)
        box = img.get_rect(topright=(int(topright[0]), int(topright[1]))).inflate(int(10 * u), int(4 * u))
        pygame.draw.rect(surf, color, box, border_radius=int(4 * u))
        surf.blit(img, img.get_rect(center=box.center))

    def _keys(self, surf: pygame.Surface, st: HudState, u: float) -> None:
        w, h = surf.get_size()
        _, right = self.health_rects(surf.get_size())
        self.blit(surf, "Esc pause   F3 budget   F11 fullscreen", int(20 * u), (right.right, right.bottom + 32 * u), DIM, "topright")
        if not st.keys:
            return
        parts = [f"{k} {action_label(a)}" for k, a in st.keys]
        line = "   ".join(parts)
        size = int(19 * u)
        img = self.text.render(line, size, KEY_TEXT)
        lines = [line]
        if img.get_width() > w - 40:  # two lines on narrow windows
            half = (len(parts) + 1) // 2
            lines = ["   ".join(parts[:half]), "   ".join(parts[half:])]
        self.key_panel = self.key_legend_panel(surf, lines, size, "midbottom", (w // 2, h - int(2 * u)), u)

    def key_legend_panel(self, surf: pygame.Surface, lines: list[str], size: int, anchor: str, pos, u: float) -> pygame.Rect:
        """Key legend lines on a dark panel of their own (the ring's ropes run behind the
        bottom of the screen), the panel's `anchor` point at `pos`; returns the panel."""
        line_h = int(20 * u)
        widest = max(self.text.render(t, size, KEY_TEXT).get_width() for t in lines)
        panel = pygame.Rect(0, 0, widest + int(24 * u), line_h * len(lines) + int(8 * u))
        setattr(panel, anchor, (int(pos[0]), int(pos[1])))
        surf.blit(self._translucent(panel.size, (8, 8, 12, 215)), panel)
        for n, text in enumerate(lines):
            self.blit(surf, text, size, (panel.centerx, panel.top + int(4 * u) + n * line_h), KEY_TEXT, "midtop")
        return panel

    def _centre(self, surf: pygame.Surface, st: HudState, u: float) -> None:
        w, h = surf.get_size()
        big, mid = int(96 * u), int(40 * u)
        if st.match.phase == "over":
            if st.match.winner is None:
                title = "DRAW"
            else:
                title = f"{st.match.result} - {'YOU WIN' if st.match.winner == 0 else 'CPU WINS'}"
            self._banner(surf, title, big, (w // 2, h * 0.42))
            if not st.demo:
                self.blit(surf, "Enter: a new match", mid, (w // 2, h * 0.42 + 60 * u), DIM, "midtop")
                if st.difficulty:
                    self.blit(surf, f"D: difficulty {st.difficulty}", int(30 * u), (w // 2, h * 0.42 + 104 * u), DIM, "midtop")
        elif st.match.phase == "count" and st.match.down is not None:
            # left of the ring's centre line: in the middle of the screen it sat over the far
            # corner post, white on white
            cx = w * COUNT_X
            self.count_rect = self._banner(surf, f"{st.match.count}", int(140 * u), (cx, h * 0.40), alpha=215)
            self.blit(surf, "KNOCKDOWN", mid, (cx, h * 0.40 + 70 * u), SWITCH_COLOR, "midtop")
        elif st.match.paused and not st.disconnected:
            self._banner(surf, "PAUSED", big, (w // 2, h * 0.42))
            self.blit(surf, "Esc or Home to resume", mid, (w // 2, h * 0.42 + 56 * u), DIM, "midtop")
            if st.difficulty:
                self.blit(surf, f"D: difficulty {st.difficulty}", mid, (w // 2, h * 0.42 + 100 * u), SWITCH_COLOR, "midtop")
        elif st.message and st.message_age < 90:
            self._banner(surf, st.message, big, (w // 2, h * 0.42))

    def _banner(self, surf: pygame.Surface, text: str, size: int, center, alpha: int = 150) -> pygame.Rect:
        img = self.text.render(text, size, TEXT)
        box = img.get_rect(center=(int(center[0]), int(center[1]))).inflate(40, 16)
        surf.blit(self._translucent(box.size, (0, 0, 0, alpha)), box)
        surf.blit(img, img.get_rect(center=box.center))
        return box

    def _disconnected(self, surf: pygame.Surface, st: HudState, u: float) -> None:
        w, h = surf.get_size()
        surf.blit(self._translucent((w, h), (10, 0, 0, 170)), (0, 0))
        box = pygame.Rect(0, 0, int(w * 0.6), int(150 * u))
        box.center = (w // 2, h // 2)
        pygame.draw.rect(surf, (120, 20, 24), box, border_radius=int(10 * u))
        pygame.draw.rect(surf, REJECT_COLOR, box, 3, border_radius=int(10 * u))
        self.blit(surf, "CONTROLLER DISCONNECTED", int(54 * u), (w // 2, box.top + 22 * u), TEXT, "midtop")
        self.blit(surf, f"{st.source.url}: {st.source.state} - the match resumes when it is back",
                  int(24 * u), (w // 2, box.top + 88 * u), TEXT, "midtop")

    def _chart_column(self, x0: int, col_w: int, ms: np.ndarray, px_per_ms: float) -> None:
        """One frame's stacked column on the chart surface, at x0."""
        y0 = float(self._chart.get_height())
        for k, v in enumerate(ms):
            hpx = min(v * px_per_ms, y0)
            if hpx >= 0.5:
                pygame.draw.rect(self._chart, STAGE_COLORS[k % len(STAGE_COLORS)], (x0, int(y0 - hpx), col_w, int(np.ceil(hpx))))
                y0 -= hpx

    def _budget(self, surf: pygame.Surface, budget: FrameBudget, u: float) -> None:
        """A stacked bar per stage against the 16.7 ms line, and each stage's p99."""
        w, h = surf.get_size()
        chart_h = int(90 * u)
        panel = pygame.Rect(w - int(440 * u), int(130 * u), int(424 * u), int(80 * u + 20 * u * len(budget.stages)) + chart_h)
        surf.blit(self._translucent(panel.size, (0, 0, 0, 190)), panel)
        last = budget.last_frame_ms()
        names = [s.name for s in budget.stages if s.name not in (WAIT, UNACCOUNTED)] + [UNACCOUNTED]
        scale_ms = 2.0 * budget.frame_budget_ms  # the bar spans two frame budgets
        bar = pygame.Rect(panel.left + int(10 * u), panel.top + int(26 * u), panel.width - int(20 * u), int(18 * u))
        self.blit(surf, f"frame budget {budget.frame_budget_ms:.1f} ms   dropped {budget.dropped_steps}", int(18 * u), (panel.left + 10 * u, panel.top + 6 * u), TEXT)
        pygame.draw.rect(surf, (50, 50, 56), bar)
        x = float(bar.left)
        for k, name in enumerate(names):
            ms = last.get(name, 0.0)
            wpx = min(bar.width * ms / scale_ms, bar.right - x)  # an overrun stops at the bar's end
            if wpx >= 1:
                pygame.draw.rect(surf, STAGE_COLORS[k % len(STAGE_COLORS)], (int(x), bar.top, int(np.ceil(wpx)), bar.height))
            x += max(wpx, 0.0)
        line_x = bar.left + bar.width * budget.frame_budget_ms / scale_ms
        pygame.draw.line(surf, REJECT_COLOR, (line_x, bar.top - 4), (line_x, bar.bottom + 4), 2)
        stages = {s.name: s for s in budget.stages}
        if budget.frames - self._p99_frame >= 30:  # percentiles over the ring: twice a second
            self._p99_frame = budget.frames
            rows = budget.span_rows()  # once for all stages: each span_rows walks the whole ring
            ids, durs = budget.s_stage[rows], budget.s_dur[rows]
            for name in names:
                d = durs[(ids == budget.stage_id(name)) & (budget.s_depth[rows] == 0)]
                self._p99[name] = float(np.percentile(d, 99)) / 1e6 if len(d) else 0.0
        # history: a stacked column per frame against the same 16.7 ms line, newest on the right.
        # The chart keeps its own surface and scrolls it one column per frame, so a frame draws
        # one column, not 120 (drawing them all cost ~2 ms a frame: the overlay ate its budget)
        new = budget.frames != self._history_frame
        if new:
            self._history_frame = budget.frames
            self._history.append(np.array([last.get(n, 0.0) for n in names]))
        chart = pygame.Rect(bar.left, panel.bottom - chart_h - int(4 * u), bar.width, chart_h)
        col_w = max(1, chart.width // HISTORY_FRAMES)
        px_per_ms = chart.height / scale_ms
        if self._chart is None or self._chart.get_size() != chart.size:
            self._chart = pygame.Surface(chart.size)
            self._chart.fill(CHART_BG)
            for i, ms in enumerate(self._history):  # after a resize: redraw what is kept
                self._chart_column(chart.width - (len(self._history) - i) * col_w, col_w, ms, px_per_ms)
        elif new:
            self._chart.scroll(-col_w, 0)
            self._chart.fill(CHART_BG, (chart.width - col_w, 0, col_w, chart.height))
            self._chart_column(chart.width - col_w, col_w, self._history[-1], px_per_ms)
        surf.blit(self._chart, chart)
        line_y = chart.bottom - budget.frame_budget_ms * px_per_ms
        pygame.draw.line(surf, REJECT_COLOR, (chart.left, line_y), (chart.right, line_y), 1)
        if budget.frames - self._text_frame >= TEXT_EVERY or len(self._rows_text) != len(names):
            # the numbers change every frame; re-rendered 6 times a second they stay readable
            # and the text cache is not flooded with 60 new strings a second
            self._text_frame = budget.frames
            self._rows_text = []
            for name in names:
                st = stages[name]
                budget_txt = f" / {st.budget_ms:.2f}" if st.budget_ms else ""
                self._rows_text.append((name, f"{last.get(name, 0.0):.2f}", f"{self._p99.get(name, 0.0):.2f}{budget_txt}",
                                        str(st.overruns) if st.overruns else ""))
        # one column each, under a header: stage, last frame's ms, p99 / budget ms, overruns
        cols = [panel.left + 28 * u + x * u for x in BUDGET_COLUMNS]
        y = bar.bottom + 8 * u
        for x, head in zip(cols, BUDGET_HEADERS, strict=True):
            self.blit(surf, head, int(16 * u), (x, y + 2 * u), DIM)
        for k, row in enumerate(self._rows_text):
            y = bar.bottom + 28 * u + k * 20 * u
            pygame.draw.rect(surf, STAGE_COLORS[k % len(STAGE_COLORS)], (int(panel.left + 10 * u), int(y + 3 * u), int(12 * u), int(12 * u)))
            for x, text in zip(cols, row, strict=True):
                self.blit(surf, text, int(18 * u), (x, y), TEXT)
