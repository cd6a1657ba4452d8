"""The heads-up display: health bars, round clock, knockdown count, the recognizer's view (action,
score, main and supplementary buffers filling, switch and reject marks), the input source and
its state and battery, key help, banners and overlays, and the F3 frame-budget overlay.

Everything it shows comes in a `HudState` the session fills each step; the HUD only draws.
Positions are fractions of the window so a resized window keeps the layout. Text surfaces are
cached: the same string in the same style is rendered once.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pygame

from engine.budget import FrameBudget
from engine.clock import STEP_HZ
from engine.sensors.source import REWIND, Source, SourceState, missing_in_short, missing_part
from game.hud_budget import BudgetOverlay

# the HUD's colours and layout (game/hud_style.py); importable from here as before
from game.hud_style import (  # noqa: F401
    BAR_BACK,
    BAR_LOSS,
    BUDGET_COLUMNS,
    BUDGET_HEADERS,
    CHART_BG,
    COUNT_X,
    DIM,
    HISTORY_FRAMES,
    KEY_TEXT,
    MARK_STEPS,
    MIN_TEXT_PX,
    OK_COLOR,
    OPPONENT_COLOR,
    PLAYER_COLOR,
    REJECT_COLOR,
    STAGE_COLORS,
    SWITCH_COLOR,
    TAIL_STEPS,
    TEXT,
    TEXT_EVERY,
    text_scale,
)
from game.hud_text import TextCache, TextLayer  # noqa: F401 (TextCache: importable from here as before)
from game.match import DOUBLE_KO, MatchSnapshot
from game.rules import MAX_HEALTH


@dataclass(frozen=True, slots=True)
class SourceSnapshot:
    """What the HUD shows of a source: the line under the health bars."""

    url: str = ""
    state: str = "connected"
    battery: float | None = None
    rewinds: bool = False  # it can play again from its start once it ended (REWIND: a replay)
    missing: str = ""  # a part it should have and has not (Source.missing: the Nunchuk)

    @classmethod
    def of(cls, source: Source, url: str | None = None, sensors: int | None = None) -> SourceSnapshot:
        """The source now; `url` to show another label (two players: "P1 wiimote://"); `sensors`,
        the count the game reads (a serial board that rebooted with fewer is missing some; one
        with more than the moves read is said too: its other hand does nothing, unsaid before)."""
        missing = missing_part(source, sensors)
        if not missing and sensors and source.state == SourceState.CONNECTED and source.sensors_known and source.sensors > sensors:
            missing = f"{source.sensors} sensors, your moves read {sensors}: the other hand does nothing (train them again)"
        return cls(source.url if url is None else url, source.state.value, source.battery,
                   REWIND in source.capabilities, missing)

    def line(self) -> str:
        """The HUD's line for it: URL, state and what is missing, in short ("connected, no
        Nunchuk": a long URL gives way in its middle, so the end stays)."""
        return f"{self.url}  {self.state}" + (f", {missing_in_short(self.missing)[0]}" if self.missing else "")

    def line_tail(self) -> int:
        """How many of `line()`'s last characters are its state: they stay whole while a long
        URL gives way (TextCache.fit's `tail`)."""
        return len(self.line()) - len(self.url)

    def plays_again(self) -> bool:
        """It ended and can play again (game.session.can_play_again, as the HUD sees it)."""
        return self.state == "ended" and self.rewinds

    def colour(self) -> tuple[int, int, int]:
        """Its dot: green connected and whole, amber (re)connecting or missing a part, red away."""
        if self.state == "connected":
            return SWITCH_COLOR if self.missing else OK_COLOR
        return SWITCH_COLOR if self.state in ("reconnecting", "connecting") else REJECT_COLOR


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
    rejected: bool = False  # the action shown is what a rejected motion matched best, not a recognition
    switch_age: int = MARK_STEPS
    switch_from: int = 0  # n_p: the clip frame the character continued from
    reject_age: int = MARK_STEPS
    end_age: int = TAIL_STEPS  # steps since the last `end`: a plain reject sooner is its return
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
            self.rejected = False
            if kind == "start":
                self.reject_age = MARK_STEPS  # a new motion: the last one's REJECT mark goes out
        if kind == "switch":
            self.switch_age = 0
            self.switch_from = int(event.get("from_frame", 0) or 0)
        elif kind == "end":
            self.end_age = 0
        elif kind == "reject" and not event.get("called_off") and self.end_age < TAIL_STEPS:
            pass  # the hand coming back from the motion that just ended: nothing the player tried
        elif kind == "reject":
            self.reject_age = 0
            self.rejected = True
            self.action = event.get("action", "") or "no match"
            self.score = event.get("score")

    def tick(self) -> None:
        """Advance timed marks by one step."""
        self.switch_age = min(MARK_STEPS, self.switch_age + 1)
        self.reject_age = min(MARK_STEPS, self.reject_age + 1)
        self.end_age = min(TAIL_STEPS, self.end_age + 1)
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


def result_title(result: str, winner: int | None, wins: tuple[str, str]) -> str:
    """The banner after the last bell: "KO - YOU WIN", "CPU WINS ON POINTS", "DRAW", "DOUBLE KO -
    DRAW" (not the match's own word for it, "points - YOU WIN"); `wins` says each side's win."""
    if winner is None:
        return f"{result.upper()} - DRAW" if result == DOUBLE_KO else "DRAW"
    if result in ("KO", "TKO"):
        return f"{result} - {wins[winner]}"
    return f"{wins[winner]} ON POINTS"


def knockdown_line(downed: tuple[int, ...]) -> str:
    """The line under the referee's count: "DOUBLE KNOCKDOWN" when both boxers are down."""
    return "DOUBLE KNOCKDOWN" if len(downed) == 2 else "KNOCKDOWN"


def lost_lines(state: str, rewinds: bool = False) -> tuple[str, str]:
    """The lost-source overlay's title and what happens next, for the source's state: one that
    ended (a replay played out) is not coming back, but one that `rewinds` plays again (the
    session's Enter rewinds it and starts a new match)."""
    if state == "ended" and rewinds:
        return "SOURCE ENDED", "Enter: play it again from the start   (close the window to quit)"
    if state == "ended":
        return "SOURCE ENDED", "nothing more to play: close the window to quit"
    return "CONTROLLER DISCONNECTED", "the match resumes when it is back"


class Hud(TextLayer):
    def __init__(self) -> None:
        super().__init__()
        self.budget_overlay = BudgetOverlay()  # F3
        self.key_panel: pygame.Rect | None = None  # where the key legend was drawn last (tests)
        self.count_rect: pygame.Rect | None = None  # where the knockdown count was drawn last
        self.lost_box: pygame.Rect | None = None  # where the lost-controller box was drawn last
        self.key_line: pygame.Rect | None = None  # the "Esc pause  F3 budget..." line drawn last

    # layout helpers (fractions of the window, so resizes keep the layout)
    @staticmethod
    def health_rects(size: tuple[int, int]) -> tuple[pygame.Rect, pygame.Rect]:
        """Outer rectangles of the player's (left) and opponent's (right) health bars."""
        w, h = size
        bw, bh = int(w * 0.36), max(12, int(h * 0.035))
        y = int(h * 0.04)
        return pygame.Rect(int(w * 0.03), y, bw, bh), pygame.Rect(w - int(w * 0.03) - bw, y, bw, bh)

    def draw(self, surf: pygame.Surface, st: HudState, budget: FrameBudget | None = None) -> None:
        w, h = surf.get_size()
        u = self.text.for_window(h)  # type scale
        self.panels = {"screen": surf.get_rect()}
        self.panel = "screen"
        self._health(surf, st, u)
        self._clock(surf, st, u)
        self._source_banner(surf, st, u, self._source(surf, st, u))
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
        u = text_scale(u)
        box = pygame.Rect(0, 0, int(120 * u), int(78 * u))
        box.midtop = (w // 2, int(12 * u))
        pygame.draw.rect(surf, (12, 12, 18), box, border_radius=int(8 * u))
        pygame.draw.rect(surf, (90, 86, 96), box, 2, border_radius=int(8 * u))
        self.enter_panel("clock", box)
        label = "BREAK" if st.match.phase == "break" else f"ROUND {st.match.round}/{st.match.rounds}"
        self.blit(surf, label, int(22 * u), (w // 2, box.top + 6 * u), DIM, "midtop")
        col = REJECT_COLOR if st.match.phase == "fight" and secs <= 10 else TEXT
        self.blit(surf, f"{secs // 60}:{secs % 60:02d}", int(50 * u), (w // 2, box.top + 26 * u), col, "midtop")
        mode = "  ".join(m for m in (st.mode, "DEMO" if st.demo else "") if m)
        if mode:
            self.enter_panel("screen", None)
            self.blit(surf, mode, int(22 * u), (w // 2, box.bottom + 4 * u), SWITCH_COLOR, "midtop")
        self.enter_panel("screen", None)

    def clock_box(self, size: tuple[int, int], u: float) -> pygame.Rect:
        """The round clock's box (lines beside it stop short of it)."""
        t = text_scale(u)
        box = pygame.Rect(0, 0, int(120 * t), int(78 * t))
        box.midtop = (size[0] // 2, int(12 * t))
        return box

    def _source(self, surf: pygame.Surface, st: HudState, u: float) -> list[pygame.Rect]:
        left, _ = self.health_rects(surf.get_size())
        u0, u = u, text_scale(u)
        y = left.bottom + 32 * u
        pygame.draw.circle(surf, st.source.colour(), (int(left.left + 7 * u), int(y + 8 * u)), int(6 * u))
        # short of the round clock (its battery after it): a long URL gives way in its middle
        clock = self.clock_box(surf.get_size(), u0)  # level with it on small windows
        room = (clock.left if y < clock.bottom else surf.get_width()) - int(left.left + 18 * u) - int((56 if st.source.battery is not None else 8) * u)
        line, size = self.text.fit(st.source.line(), int(22 * u), room, tail=st.source.line_tail())
        lines = [r := self.blit(surf, line, size, (left.left + 18 * u, y), DIM)]
        if st.templates:
            line, size = self.text.fit(st.templates, int(18 * u), room)
            lines.append(self.blit(surf, line, size, (left.left + 18 * u, y + 22 * u), DIM))
        if st.source.battery is not None:
            bx, by = r.right + 12 * u, y + 2 * u
            body = pygame.Rect(int(bx), int(by), int(34 * u), int(14 * u))
            pygame.draw.rect(surf, DIM, body, 2)
            pygame.draw.rect(surf, DIM, (body.right, body.top + body.height // 4, int(3 * u), body.height // 2))
            b = max(0.0, min(1.0, st.source.battery))
            pygame.draw.rect(surf, OK_COLOR if b > 0.25 else REJECT_COLOR, (body.left + 3, body.top + 3, int((body.width - 6) * b), body.height - 6))
        return lines

    def _source_banner(self, surf: pygame.Surface, st: HudState, u: float, lines: list[pygame.Rect]) -> None:
        """One player: an amber strip under the clock (clear of the source `lines`) when the game plays from the keyboard
        for want of a Wiimote, or when the source misses a part (a Nunchuk that slipped out: nothing else says why)."""
        if st.keyboard_banner:
            self.strip(surf, "No Wiimote found: playing from the keyboard (keys below)", "keyboard banner", text_scale(u), lines)
        elif st.source.missing:
            self.strip(surf, st.source.missing[0].upper() + st.source.missing[1:], "missing banner", text_scale(u), lines)

    def _recognition(self, surf: pygame.Surface, st: HudState, u: float) -> None:
        _, h = surf.get_size()
        u = text_scale(u)
        panel = pygame.Rect(int(16 * u), h - int(170 * u), int(330 * u), int(118 * u))
        surf.blit(self._translucent(panel.size, (10, 10, 16, 170)), panel)
        self.enter_panel(f"recognition {len([p for p in self.panels if p.startswith('recognition')]) + 1}", panel, surf)
        x, y = panel.left + 12 * u, panel.top + 8 * u
        # a rejected motion keeps its name up (the closest action) under REJECTED: under
        # RECOGNIZED it read as recognized once the REJECT mark went out
        self.blit(surf, "REJECTED" if st.rejected else "RECOGNIZED", int(18 * u), (x, y), REJECT_COLOR if st.rejected else DIM)
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
        self.enter_panel("screen", None)

    def _mark(self, surf: pygame.Surface, text: str, color, topright, u: float) -> None:
        img = self.text.render(text, int(20 * u), (15, 15, 15), shadow=False)
        box = img.get_rect(topright=(int(topright[0]), int(topright[1]))).inflate(int(10 * u), int(4 * u))
        pygame.draw.rect(surf, color, box, border_radius=int(4 * u))
        self.put(surf, img, img.get_rect(center=box.center), text)

    def _keys(self, surf: pygame.Surface, st: HudState, u: float) -> None:
        w, h = surf.get_size()
        _, right = self.health_rects(surf.get_size())
        u = text_scale(u)
        self.key_line = self.blit(surf, "Esc pause   F3 budget   F11 fullscreen", int(20 * u), (right.right, right.bottom + 32 * u), DIM, "topright")
        if not st.keys:
            self.key_panel = None  # none drawn this frame
            return
        parts = [f"{k} {action_label(a)}" for k, a in st.keys]
        line = "   ".join(parts)
        size = int(19 * u)
        img = self.text.render(line, size, KEY_TEXT)
        lines = [line]
        if img.get_width() > w - 40:  # two lines on narrow windows
            half = (len(parts) + 1) // 2
            lines = ["   ".join(parts[:half]), "   ".join(parts[half:])]
            # a window narrow for its height (text scales with the height: 800x1040) smaller
            # still, so that the lines fit (their ends ran off both sides)
            size = self.text.fit(max(lines, key=lambda t: self.text.width(t, size)), size, w - 40)[1]
        self.key_panel = self.key_legend_panel(surf, lines, size, "midbottom", (w // 2, h - int(2 * u)), u)

    def key_legend_panel(self, surf: pygame.Surface, lines: list[str], size: int, anchor: str, pos, u: float) -> pygame.Rect:
        """Key legend lines on a dark panel of their own (the ring's ropes run behind the
        bottom of the screen), the panel's `anchor` point at `pos`; returns the panel."""
        line_h = int(20 * u)
        widest = max(self.text.render(t, size, KEY_TEXT).get_width() for t in lines)
        panel = pygame.Rect(0, 0, widest + int(24 * u), line_h * len(lines) + int(8 * u))
        setattr(panel, anchor, (int(pos[0]), int(pos[1])))
        surf.blit(self._translucent(panel.size, (8, 8, 12, 215)), panel)
        self.enter_panel(f"keys {len([p for p in self.panels if p.startswith('keys')]) + 1}", panel, surf)
        for n, text in enumerate(lines):
            self.blit(surf, text, size, (panel.centerx, panel.top + int(4 * u) + n * line_h), KEY_TEXT, "midtop")
        self.enter_panel("screen", None)
        return panel

    def _centre(self, surf: pygame.Surface, st: HudState, u: float) -> None:
        w, h = surf.get_size()
        big, mid = int(96 * u), int(40 * u)
        if st.match.phase == "over":
            title = result_title(st.match.result, st.match.winner, ("YOU WIN", "CPU WINS"))
            self._banner(surf, title, big, (w // 2, h * 0.42))
            if not st.demo and not st.disconnected:  # the lost-source box hides them; D does nothing there
                self.menu_line(surf, "Enter: a new match", mid, (w // 2, h * 0.42 + 60 * u), DIM, u)
                if st.difficulty:
                    self.menu_line(surf, f"D: difficulty {st.difficulty}", int(30 * u), (w // 2, h * 0.42 + 104 * u), DIM, u)
        elif st.match.phase == "count" and st.match.downed:
            # left of the ring's centre line: in the middle of the screen it sat over the far
            # corner post, white on white
            cx = w * COUNT_X
            self.count_rect = self._banner(surf, f"{st.match.count}", int(140 * u), (cx, h * 0.40), alpha=215)
            said, size = self.text.fit(knockdown_line(st.match.downed), mid, int(2 * cx))  # within the window
            self.blit(surf, said, size, (cx, h * 0.40 + 70 * u), SWITCH_COLOR, "midtop")
        elif st.match.paused and not st.disconnected:
            self._banner(surf, "PAUSED", big, (w // 2, h * 0.42))
            self.menu_line(surf, "Esc or Home to resume", mid, (w // 2, h * 0.42 + 56 * u), DIM, u)
            if st.difficulty:
                self.menu_line(surf, f"D: difficulty {st.difficulty}", mid, (w // 2, h * 0.42 + 100 * u), SWITCH_COLOR, u)
        elif st.message and st.message_age < 90:
            self._banner(surf, st.message, big, (w // 2, h * 0.42))

    def _disconnected(self, surf: pygame.Surface, st: HudState, u: float) -> None:
        w, h = surf.get_size()
        surf.blit(self._translucent((w, h), (10, 0, 0, 170)), (0, 0))
        box = pygame.Rect(0, 0, int(w * 0.6), int(150 * u))
        box.center = (w // 2, h // 2)
        self.lost_box = box
        pygame.draw.rect(surf, (120, 20, 24), box, border_radius=int(10 * u))
        pygame.draw.rect(surf, REJECT_COLOR, box, 3, border_radius=int(10 * u))
        self.enter_panel("lost", box)
        title, then = lost_lines(st.source.state, st.source.rewinds)
        line, size = self.text.fit(title, int(54 * u), box.width - int(24 * u))  # a window narrow for its height
        self.blit(surf, line, size, (w // 2, box.top + 22 * u), TEXT, "midtop")
        # the source on a line of its own, smaller if its URL is long (a two-player seat's
        # keyboard URL ran past both sides of the box), then what happens next
        line, size = self.text.fit(f"{st.source.url}: {st.source.state}", int(24 * u), box.width - int(24 * u))
        self.blit(surf, line, size, (w // 2, box.top + 80 * u), TEXT, "midtop")
        then, size = self.text.fit(then, int(24 * u), box.width - int(24 * u))
        self.blit(surf, then, size, (w // 2, box.top + 108 * u), TEXT, "midtop")
        self.enter_panel("screen", None)

    def _budget(self, surf: pygame.Surface, budget: FrameBudget, u: float) -> None:
        """The F3 overlay (game/hud_budget.py), clear of the panels drawn this frame under it."""
        below = [rect for name, rect in self.panels.items() if name.startswith(("recognition", "keys"))]
        above = [rect for name, rect in self.panels.items() if name.endswith(" banner")]  # the amber strip: it hid its end
        self.budget_overlay.draw(self, surf, budget, u, below, above + ([self.key_line] if self.key_line else []))

    # the overlay's chart and rows, under the names tests read
    @property
    def _chart(self) -> pygame.Surface | None:
        return self.budget_overlay.chart

    @property
    def _rows_text(self) -> list:
        return self.budget_overlay.rows_text
