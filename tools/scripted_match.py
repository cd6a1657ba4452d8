"""A scripted headless match for benchmarks and the soak: the real Session (every stage, the
real recognizer, physics, Interaction Graph opponent, match rules, renderer to an offscreen
surface) on a VirtualClock, the player's boxer driven by the virtual player through
`keyboard://?auto=1` (the attract mode) with a fixed seed, no sound, SDL's dummy drivers.

Templates: the file given, else the shipped game/assets/templates.npz, else the virtual
player's synthesized set (seed 0), never the user's own trained set (figures must not depend
on who ran `quickjab train` on this machine).
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path


def headless_env() -> None:
    """SDL's dummy video and audio drivers (before pygame initialises), and no pygame banner
    on stdout (it would corrupt --json output)."""
    os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")
    os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
    os.environ.setdefault("SDL_AUDIODRIVER", "dummy")


_SYNTH_CACHE: dict[int, Path] = {}


def default_templates() -> Path:
    """The shipped templates, else the synthesized set saved once per process to a temp file."""
    from game.userdata import SHIPPED_TEMPLATES

    if SHIPPED_TEMPLATES.exists():
        return SHIPPED_TEMPLATES
    if 0 not in _SYNTH_CACHE:
        from game.session import synthesized_templates

        path = Path(tempfile.mkdtemp(prefix="quickjab-bench-")) / "templates.npz"
        synthesized_templates(seed=0).save(path)
        _SYNTH_CACHE[0] = path
    return _SYNTH_CACHE[0]


def build_session(seed: int = 0, low_power: bool = False, render: bool = True,
                  size: tuple[int, int] = (1280, 720), templates: str | Path | None = None,
                  graph: str | Path | None = None, clock=None):
    """A Session on a VirtualClock (or the clock given) playing the virtual player against the
    graph opponent. Returns the session; `session.loop.run(steps=N)` plays."""
    headless_env()
    import pygame

    import game.keyboard_source  # noqa: F401 - registers keyboard://
    from engine.clock import VirtualClock
    from engine.sensors import open_source
    from game.session import Session, SessionConfig

    pygame.init()
    clock = clock if clock is not None else VirtualClock()
    from game.launch import DEMO_SOURCE

    source = open_source(f"{DEMO_SOURCE}&seed={seed}", clock=clock.seconds)
    cfg = SessionConfig(seed=seed, size=size, low_power=low_power, demo=True, sound=False, render=render,
                        templates=templates if templates is not None else default_templates(), graph=graph)
    return Session(source, cfg, clock=clock)


def build_two_player_session(seed: int = 0, low_power: bool = False, render: bool = True,
                             size: tuple[int, int] = (1280, 720), templates: str | Path | None = None, clock=None):
    """A two-player match (game.two_player) on a VirtualClock (or the clock given): two keyboard
    sources, each a virtual player pressing moves on its half of the keyboard (the demo's
    pilots), two real recognizers with the same templates. `session.loop.run(steps=N)` plays."""
    headless_env()
    import pygame

    import game.keyboard_source  # noqa: F401 - registers keyboard://
    from engine.clock import VirtualClock
    from engine.sensors import open_source
    from game.session import SessionConfig
    from game.two_player import TwoPlayerSession, source_urls

    pygame.init()
    clock = clock if clock is not None else VirtualClock()
    urls, _ = source_urls(None, None, demo=True, seed=seed)
    sources = [open_source(u, clock=clock.seconds) for u in urls]
    tmpl = templates if templates is not None else default_templates()
    cfg = SessionConfig(seed=seed, size=size, low_power=low_power, demo=True, sound=False, render=render)
    return TwoPlayerSession(sources, cfg, clock=clock, templates=(tmpl, tmpl))
