"""The HUD's text: a cache of rendered strings (never under the window's floor, game/hud_style.py) and
the drawing of text on panels of their own (key legends, lines under a banner, banners), which
notes, when a test asks, every text drawn, where, and in which panel."""

from __future__ import annotations

from collections.abc import Sequence

import pygame

from game.hud_style import MIN_TEXT_PX, SWITCH_COLOR, TEXT, min_text_px

# One font per size for the whole process, not per cache: pygame-ce keeps a font's file open
# while the font lives (and for good when the font outlives pygame.quit()), and every HUD and
# training screen made its own, one per size it drew at. A process that made many (the tests:
# fuzzed windows of many sizes, ~140 fonts a session) passed 1024 open files, where pyserial's
# select() on a serial port fails. Cleared at pygame.quit() (release_fonts, registered with it).
_FONTS: dict[int, pygame.font.Font] = {}


def release_fonts() -> None:
    """Close the fonts. Registered with pygame.quit(), which calls it before its font module
    goes: a font alive after that keeps its file open for the process's life, and cannot be
    drawn with."""
    _FONTS.clear()


def _font(size: int) -> pygame.font.Font:
    font = _FONTS.get(size)
    if font is None:
        if not _FONTS:  # the first since pygame started (again): its quit forgets them
            pygame.register_quit(release_fonts)
        font = _FONTS[size] = pygame.font.Font(None, size)
    return font


class TextCache:
    def __init__(self) -> None:
        self._cache: dict[tuple, pygame.Surface] = {}
        self._fits: dict[tuple, tuple[str, int]] = {}  # fit's answers, by text, size, width and floor
        self.floor = MIN_TEXT_PX  # the smallest size rendered: `for_window` sets it per window

    def for_window(self, height: int) -> float:
        """Set the floor for a window this tall (min_text_px); returns its type scale u."""
        u = height / 720.0
        self.floor = min_text_px(u)
        return u

    def font(self, size: int) -> pygame.font.Font:
        return _font(size)

    def render(self, text: str, size: int, color=TEXT, shadow: bool = True) -> pygame.Surface:
        """`text` in pygame's default font at `size` px, never under the floor."""
        size = max(self.floor, int(size))
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

    def width(self, text: str, size: int) -> int:
        """The width `render(text, size)` has (its shadow's 2 px included), without rendering it."""
        return self.font(max(self.floor, int(size))).size(text)[0] + 2

    def fit(self, text: str, size: int, width: int, smallest: int = 0, tail: int = 0) -> tuple[str, int]:
        """`text` at `size`, or smaller down to `smallest`, so it is at most `width` pixels wide
        (with its shadow); still too wide, its middle gives way to "...", sparing its last `tail`
        characters while that fits (a source line's state after its URL). Returns (text, size).
        Measured, not rendered (the candidates used to fill the render cache: 30 surfaces for one
        long URL, made again after each clear), and the answer kept for the next frame."""
        key = (text, size, width, smallest, self.floor, tail)
        done = self._fits.get(key)
        if done is not None:
            return done
        smallest = max(smallest, self.floor)
        while size > smallest and self.width(text, size) > width:
            size -= 1
        if self.width(text, size) > width:
            head, end = (text[: len(text) - tail], text[len(text) - tail:]) if 0 < tail < len(text) else (text, "")
            if end and self.width(f"{head[:1]}...{end}", size) > width:
                head, end = text, ""  # not even the spared end fits: the whole line gives way
            keep = len(head)
            while keep > 2 and self.width(f"{head[:keep // 2]}...{head[len(head) - keep // 2:]}{end}", size) > width:
                keep -= 2
            text = f"{head[:keep // 2]}...{head[len(head) - keep // 2:]}{end}"
        if len(self._fits) > 64:  # window resizes leave old widths behind
            self._fits.clear()
        done = self._fits[key] = (text, max(self.floor, size))
        return done


class TextLayer:
    """Text and translucent panels on a surface; the HUD's drawing builds on it."""

    def __init__(self) -> None:
        self.text = TextCache()
        self._fills: dict[tuple, pygame.Surface] = {}  # translucent backgrounds, by size and colour
        # tests: a list to collect every text drawn (text, rectangle, the panel it belongs to);
        # `panels` holds the panels' rectangles ("screen" for text drawn straight on the ring)
        self.layout: list[tuple[str, pygame.Rect, str]] | None = None
        self.panels: dict[str, pygame.Rect] = {}
        self.panel = "screen"

    def blit(self, surf: pygame.Surface, text: str, size: int, pos, color=TEXT, anchor: str = "topleft") -> pygame.Rect:
        img = self.text.render(text, size, color)
        rect = img.get_rect(**{anchor: (int(pos[0]), int(pos[1]))})
        return self.put(surf, img, rect, text)

    def put(self, surf: pygame.Surface, img: pygame.Surface, rect: pygame.Rect, text: str) -> pygame.Rect:
        """A rendered text blitted at `rect`, noted in `layout` when tests collect it (on the
        screen, where a subsurface was drawn on)."""
        surf.blit(img, rect)
        if self.layout is not None:
            self.layout.append((text, rect.move(surf.get_abs_offset()), self.panel))
        return rect

    def enter_panel(self, name: str, rect: pygame.Rect | None, surf: pygame.Surface | None = None) -> None:
        """Texts drawn from now on belong to panel `name` (`rect` on `surf`; None: the screen)."""
        self.panel = name
        if rect is not None:
            self.panels[name] = rect.move(surf.get_abs_offset()) if surf is not None else rect

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

    def menu_line(self, surf: pygame.Surface, text: str, size: int, midtop, color, u: float) -> pygame.Rect:
        """A line under a banner (Enter: a new match, D: difficulty...) on a dark ground of its
        own: drawn straight on the ring, its grey was the canvas's grey (contrast 1.0)."""
        img = self.text.render(text, size, color)
        ground = img.get_rect(midtop=(int(midtop[0]), int(midtop[1]))).inflate(int(16 * u), int(6 * u))
        surf.blit(self._translucent(ground.size, (8, 8, 12, 200)), ground)
        self.enter_panel(f"menu {text}", ground)
        rect = self.blit(surf, text, size, midtop, color, "midtop")
        self.enter_panel("screen", None)
        return rect

    def strip(self, surf: pygame.Surface, msg: str, name: str, u: float, clear: Sequence[pygame.Rect] = ()) -> None:
        """A line on an amber strip under the round clock, its panel `name` (a notice the
        player must not miss: no Wiimote found, a Nunchuk missing); under `clear` (the source's
        lines) where it would cover them (windows narrow for their height: 640x720, 800x600)."""
        w = surf.get_width()
        msg, size = self.text.fit(msg, int(24 * u), w - int(24 * u) - 2)  # a window narrow for its height
        img = self.text.render(msg, size, (20, 20, 20), shadow=False)
        box = img.get_rect(midtop=(w // 2, int(118 * u))).inflate(int(24 * u), int(10 * u))
        if covered := [r.bottom for r in clear if box.colliderect(r)]:
            box.top = max(covered) + int(4 * u)
        pygame.draw.rect(surf, SWITCH_COLOR, box, border_radius=int(6 * u))
        self.enter_panel(name, box)
        self.put(surf, img, img.get_rect(center=box.center), msg)
        self.enter_panel("screen", None)

    def _banner(self, surf: pygame.Surface, text: str, size: int, center, alpha: int = 150) -> pygame.Rect:
        # its size follows the window's height: smaller on a window narrow for it (640x720: the
        # result ran off both sides)
        text, size = self.text.fit(text, size, surf.get_width() - 40)
        img = self.text.render(text, size, TEXT)
        box = img.get_rect(center=(int(center[0]), int(center[1]))).inflate(40, 16)
        surf.blit(self._translucent(box.size, (0, 0, 0, alpha)), box)
        self.enter_panel(f"banner {text}", box)
        self.put(surf, img, img.get_rect(center=box.center), text)
        self.enter_panel("screen", None)
        return box
