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


def test_a_source_lines_state_stays_whole_while_its_url_gives_way() -> None:
    """At 800x450 a long URL's line gave way in its middle, into its state ("...onnected, no
    Nunchuk"); the HUD spares the state after the URL while it fits."""
    pygame.init()
    cache = TextCache()
    cache.for_window(450)
    state = "  connected, no Nunchuk"
    line, size = cache.fit(LONG[: -len("  connected")] + state, 19, 300, tail=len(state))
    assert "..." in line and line.endswith(state) and line.startswith("wiimote://"), line
    assert cache.width(line, size) <= 300
    # room for no more than the state: the whole line gives way as before
    line, size = cache.fit("wiimote://x" + state, 19, cache.width(state, 19) // 2, tail=len(state))
    assert "..." in line and not line.endswith(state) and line.startswith("w")
