"""Helpers for the fairness tests (same-step blows, pauses): sessions built headless under the
dummy video driver, and blows made to land in a chosen step through the real hits stage."""

from __future__ import annotations

import numpy as np
import pygame

from engine.clock import VirtualClock
from engine.physics.collision import Contact
from engine.sensors import open_source
from game.session import Session, SessionConfig
from game.two_player import TwoPlayerSession

SIZE = (640, 360)


def two_players(display: bool = False) -> TwoPlayerSession:
    """Two keyboard players (the split keyboard), no sound."""
    import game.keyboard_source  # noqa: F401 - registers keyboard://

    pygame.init()
    clock = VirtualClock()
    sources = [open_source(u, clock=clock.seconds) for u in ("keyboard://?seed=1&keys=left", "keyboard://?seed=2&keys=right")]
    provider = None
    if display:
        pygame.display.set_mode(SIZE)
        provider = pygame.display.get_surface
    cfg = SessionConfig(seed=0, size=SIZE, sound=False, render=display)
    return TwoPlayerSession(sources, cfg, clock=clock, surface_provider=provider)


def one_player(graph: str, display: bool = False) -> Session:
    """One keyboard player against the CPU (the graph given), no sound."""
    import game.keyboard_source  # noqa: F401 - registers keyboard://

    pygame.init()
    clock = VirtualClock()
    source = open_source("keyboard://?seed=3", clock=clock.seconds)
    provider = None
    if display:
        pygame.display.set_mode(SIZE)
        provider = pygame.display.get_surface
    cfg = SessionConfig(seed=0, size=SIZE, sound=False, render=display, graph=graph)
    return Session(source, cfg, clock=clock, surface_provider=provider)


def throw(session, who: int, action: str = "straight_r", frame: float = 8.0) -> None:
    """Boxer `who` in the middle of `action`, its fist live (inside the clip's attack window)."""
    ctrl = session.boxers[who].controller
    ctrl.play(action, from_frame=frame)
    assert ctrl.clip.attack_at(frame, action[-1]) is not None


def fist_on_head(session, attacker: int, hand: str = "r", speed: float = 5.0) -> Contact:
    """A contact as the physics reports it (body_a < body_b): `attacker`'s fist on the other's head."""
    a, d = session.boxers[attacker], session.boxers[1 - attacker]
    point = d.joint_positions()[4].copy()
    normal = np.asarray(point - a.joint_positions()[4], dtype=float)
    normal /= max(float(np.linalg.norm(normal)), 1e-9)
    fist, head = (a.body, f"fist_{hand}"), (d.body, "head")
    (body_a, tag_a), (body_b, tag_b) = sorted((fist, head))
    if body_a != a.body:
        normal = -normal  # the normal points from capsule a to capsule b
    return Contact(body_a, 0, tag_a, body_b, 0, tag_b, point, normal, speed)


def touch_next_steps(session, contacts: list[Contact], steps: int = 1) -> None:
    """The physics' next `steps` steps report `contacts` besides their own (a fist that reaches
    its target then; a touch that lasts is reported every step, as the physics does)."""
    real = session.world.step
    left = [steps]

    def step(dt: float) -> list:
        out = real(dt)
        left[0] -= 1
        if left[0] <= 0:
            session.world.step = real
        return out + list(contacts)

    session.world.step = step
