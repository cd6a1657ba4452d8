"""The two-player HUD: the one-player HUD's parts, with a panel per player.

Player 1 keeps the one-player places (health bar, source line and recognition panel on the
left); player 2 gets the mirror image on the right. Two keyboard players see their half of the
keyboard under their own panel. The disconnected overlay names the player whose controller
was lost; the result names the winner (P1 / P2).
"""

from __future__ import annotations

import pygame

from engine.budget import FrameBudget
from game.hud import DIM, OK_COLOR, REJECT_COLOR, TEXT, Hud, HudState, result_title
from game.hud_style import text_scale

PANEL_W, PANEL_MARGIN = 330, 16  # the recognition panel's width and margin (game.hud, at 720 p)
LEGEND_LIFT = 20  # the recognition panel moves up this much (720 p) over a three-line key legend


def compact_keys(keys: list[tuple[str, str]]) -> list[str]:
    """A player's key legend in three short lines (the one-player legend's one line is too
    wide for half a screen): each hand's punches and parry, "L"/"R" for the hand (a lower-case
    "l" reads as "I"), then the block and the footwork."""
    by_action = {a: k for k, a in keys}
    lines = []
    for hand in ("L", "R"):
        moves = [f"{by_action[f'{base}_{hand.lower()}']} {base}" for base in ("straight", "hook", "uppercut", "parry")
                 if f"{base}_{hand.lower()}" in by_action]
        if moves:
            lines.append(f"{hand} hand: " + "  ".join(moves))
    moves = [f"{by_action['block']} block"] if "block" in by_action else []
    steps = [f"{d} {by_action[f'step_{name}']}" for d, name in (("fwd", "forward"), ("back", "back"), ("left", "left"),
                                                                 ("right", "right")) if f"step_{name}" in by_action]
    if steps:
        moves.append("step " + "  ".join(steps))
    if moves:
        lines.append("   ".join(moves))
    return lines


class TwoPlayerHud(Hud):
    """`draw(surf, st, budget)` as the one-player Hud; `second` is player 2's HudState (its
    recognition and source fields; the match fields come from `st`, player 1's)."""

    def __init__(self, second: HudState) -> None:
        super().__init__()
        self.second = second
        self.key_panels: list[pygame.Rect] = []  # where the players' key legends were drawn last (tests)

    def draw(self, surf: pygame.Surface, st: HudState, budget: FrameBudget | None = None) -> None:
        w, h = surf.get_size()
        u = self.text.for_window(h)
        t = text_scale(u)  # the panels that hold small text (game/hud_style.py)
        two = self.second
        self.panels = {"screen": surf.get_rect()}
        self.panel = "screen"
        self._health(surf, st, u)
        self._clock(surf, st, u)
        self._source(surf, st, u)
        self._source_right(surf, two, u)
        # each recognition panel lifted over its player's key legend (when they have one): the
        # one-player drawing on a shorter surface
        lift = [int(LEGEND_LIFT * t) if s.keys else 0 for s in (st, two)]
        self._recognition(surf.subsurface(pygame.Rect(0, 0, w, h - lift[0])), st, u)
        # player 2's panel: the same drawing on a strip of the screen's right edge, so the
        # panel sits mirrored at the bottom right
        strip_w = min(w, int((PANEL_W + 2 * PANEL_MARGIN) * t))
        self._recognition(surf.subsurface(pygame.Rect(w - strip_w, 0, strip_w, h - lift[1])), two, u)
        self._legends(surf, st, two, u)
        self._centre_two(surf, st, u)
        if st.show_budget and budget is not None:
            self._budget(surf, budget, u)
        # the box of a seat whose source is away, before a played-out replay's (whose Enter
        # does nothing until that seat is back: game.session.enter_starts_match)
        lost = [s for s in (st, two) if s.disconnected]
        if lost:
            waits = [s for s in lost if not s.source.plays_again()]
            self._disconnected(surf, (waits or lost)[0], u)

    def _source_right(self, surf: pygame.Surface, st: HudState, u: float) -> None:
        """Player 2's source, state and battery under the right health bar, right-aligned."""
        _, right = self.health_rects(surf.get_size())
        u0, u = u, text_scale(u)
        y = right.bottom + 32 * u
        x = right.right
        if st.source.battery is not None:
            body = pygame.Rect(0, int(y + 2 * u), int(34 * u), int(14 * u))
            body.right = int(x - 3 * u)
            pygame.draw.rect(surf, DIM, body, 2)
            pygame.draw.rect(surf, DIM, (body.right, body.top + body.height // 4, int(3 * u), body.height // 2))
            b = max(0.0, min(1.0, st.source.battery))
            pygame.draw.rect(surf, OK_COLOR if b > 0.25 else REJECT_COLOR,
                             (body.left + 3, body.top + 3, int((body.width - 6) * b), body.height - 6))
            x = body.left - 12 * u
        # short of the round clock: a long URL gives way in its middle
        clock = self.clock_box(surf.get_size(), u0)  # level with it (small windows), its dot just clear of it
        room = int(x - 18 * u) - (clock.right if y < clock.bottom else 0)
        line, size = self.text.fit(st.source.line(), int(22 * u), room, tail=st.source.line_tail())
        r = self.blit(surf, line, size, (x, y), DIM, "topright")
        if st.templates:
            line, size = self.text.fit(st.templates, int(18 * u), room)
            self.blit(surf, line, size, (right.right, y + 22 * u), DIM, "topright")
        pygame.draw.circle(surf, st.source.colour(), (int(r.left - 11 * u), int(y + 8 * u)), int(6 * u))

    def _legends(self, surf: pygame.Surface, one: HudState, two: HudState, u: float) -> None:
        """Each keyboard player's keys under their own panel, on the one-player legend's dark
        panel; the shared keys in the middle."""
        w, h = surf.get_size()
        u = text_scale(u)
        self.key_panels = []
        for st, x, anchor in ((one, PANEL_MARGIN * u, "bottomleft"), (two, w - PANEL_MARGIN * u, "bottomright")):
            if st.keys:
                self.key_panels.append(self.key_legend_panel(surf, compact_keys(st.keys), int(19 * u), anchor,
                                                             (x, h - 2 * u), u))
        # the shared keys under the round clock (the bottom corners are the players')
        self.key_line = self.blit(surf, "Esc pause  F3 budget  F11 fullscreen", int(18 * u), (w // 2, 118 * u), DIM, "midtop")

    def _centre_two(self, surf: pygame.Surface, st: HudState, u: float) -> None:
        if st.match.phase != "over":
            if not (st.match.paused and self.second.disconnected):  # the overlay says why, not PAUSED
                self._centre(surf, st, u)
            return
        w, h = surf.get_size()
        title = result_title(st.match.result, st.match.winner, (f"{st.names[0]} WINS", f"{st.names[1]} WINS"))
        self._banner(surf, title, int(96 * u), (w // 2, h * 0.42))
        if not st.demo and not (st.disconnected or self.second.disconnected):  # the lost box says what next
            self.menu_line(surf, "Enter: a new match", int(40 * u), (w // 2, h * 0.42 + 60 * u), TEXT, u)
