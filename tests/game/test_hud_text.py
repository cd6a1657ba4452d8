"""game.hud_text.TextCache: fit measures its candidates instead of rendering them into the cache."""

from __future__ import annotations

import pygame

from game.hud_text import TextCache

LONG = "wiimote://00:1F:32:AB:CD:EF?profile=a-rather-long-profile-name&seed=12345  connected"


def test_fit_renders_nothing_into_the_cache_and_its_line_fits() -> None:
    # each candidate (every size down to the floor, then every shorter elision) was a rendered,
    # cached surface: ~30 for one URL at 800x480, all made again after each clear of the cache
    pygame.init()
    cache = TextCache()
    cache.for_window(480)
    line, size = cache.fit(LONG, 19, 300)
    assert len(cache._cache) == 0
    assert "..." in line and size == cache.floor
    assert cache.render(line, size).get_width() <= 300
    assert cache.width(line, size) == cache.render(line, size).get_width()
    # a line that fits is kept whole, at its size
    assert cache.fit("keyboard://  connected", 19, 300) == ("keyboard://  connected", 19)
