"""A rendered frame has both boxers and the HUD where they belong (pixels checked)."""

from __future__ import annotations

import numpy as np
import pygame
import pytest

from game.actions import load_library
from game.hud import OPPONENT_COLOR, PLAYER_COLOR, Hud, HudState, SourceSnapshot
from game.match import MatchSnapshot
from game.render import JOINT_NAMES, OPPONENT_LOOK, PLAYER_LOOK, Renderer
from game.skeleton import JOINTS, local_to_world

SIZE = (1280, 720)


@pytest.fixture(scope="module")
def lib():
    return load_library()


def colour_count(surf: pygame.Surface, rect: pygame.Rect, colour, tol: int = 40) -> int:
    rect = rect.clip(surf.get_rect())
    arr = pygame.surfarray.array3d(surf)[rect.left:rect.right, rect.top:rect.bottom].astype(int)
    return int((np.abs(arr - np.array(colour)).max(axis=2) <= tol).sum())


def scene(lib, player_action="guard", frame=0):
    player = local_to_world(lib[player_action].posture(frame), (0.0, -0.9, 0.0))
    opponent = local_to_world(lib["guard"].posture(0), (0.0, 0.9, np.pi))
    return player, opponent


def test_joint_order_matches_the_skeleton() -> None:
    assert tuple(JOINT_NAMES) == tuple(JOINTS)


def test_both_boxers_are_drawn_where_they_stand(lib) -> None:
    pygame.init()
    surf = pygame.Surface(SIZE)
    r = Renderer(SIZE)
    player, opponent = scene(lib, "straight_r", 10)
    r.draw(surf, [player, opponent])
    pbox, obox = r.screen_box(player), r.screen_box(opponent)
    assert surf.get_rect().contains(pbox) and surf.get_rect().contains(obox)
    # each boxer's trunks and gloves are inside its own box ...
    assert colour_count(surf, pbox, PLAYER_LOOK.trunks) > 300
    assert colour_count(surf, pbox, PLAYER_LOOK.gloves) > 100
    assert colour_count(surf, obox, OPPONENT_LOOK.trunks) > 150
    assert colour_count(surf, obox, OPPONENT_LOOK.gloves) > 60
    # ... and the opponent's blue is not in the far corners of the screen (no stray drawing)
    corner = pygame.Rect(0, 0, 200, 150)
    assert colour_count(surf, corner, OPPONENT_LOOK.trunks, tol=30) == 0
    # the ring canvas is in the middle of the floor, in front of the player
    canvas = surf.get_at((int(SIZE[0] * 0.5), int(SIZE[1] * 0.9)))[:3]
    assert min(canvas) > 140


def test_the_colours_come_from_the_boxers_not_the_ring(lib) -> None:
    pygame.init()
    empty, full = pygame.Surface(SIZE), pygame.Surface(SIZE)
    r = Renderer(SIZE)
    player, opponent = scene(lib)
    r.draw(empty, [])
    r.draw(full, [player, opponent])
    for body, look in ((player, PLAYER_LOOK), (opponent, OPPONENT_LOOK)):
        box = r.screen_box(body)
        # the ring has red ropes and a blue corner: what matters is what the boxer adds
        with_boxer = colour_count(full, box, look.trunks, tol=25)
        assert with_boxer > 150
        assert colour_count(empty, box, look.trunks, tol=25) < 0.3 * with_boxer


def test_health_bars_show_health_at_their_positions(lib) -> None:
    pygame.init()
    surf = pygame.Surface(SIZE)
    Renderer(SIZE).draw(surf, list(scene(lib)))
    st = HudState(match=MatchSnapshot(health=(75.0, 30.0)), shown_health=[75.0, 30.0])
    Hud().draw(surf, st)
    left, right = Hud.health_rects(SIZE)
    y = left.centery + left.height // 4  # below the highlight stripe
    # the player's bar: filled from the left to 75 %, empty beyond
    assert surf.get_at((left.left + 5, y))[:3] == PLAYER_COLOR
    assert surf.get_at((left.left + int(left.width * 0.7), y))[:3] == PLAYER_COLOR
    assert surf.get_at((left.left + int(left.width * 0.8), y))[:3] != PLAYER_COLOR
    # the CPU's bar drains towards the centre: filled on its right 30 %
    assert surf.get_at((right.right - 5, y))[:3] == OPPONENT_COLOR
    assert surf.get_at((right.right - int(right.width * 0.25), y))[:3] == OPPONENT_COLOR
    assert surf.get_at((right.right - int(right.width * 0.4), y))[:3] != OPPONENT_COLOR


def test_hud_keeps_its_layout_when_resized(lib) -> None:
    pygame.init()
    small = (800, 450)
    surf = pygame.Surface(small)
    Renderer(small).draw(surf, list(scene(lib)))
    Hud().draw(surf, HudState())
    left, right = Hud.health_rects(small)
    assert surf.get_at((left.left + 5, left.centery + 3))[:3] == PLAYER_COLOR
    assert surf.get_at((right.right - 5, right.centery + 3))[:3] == OPPONENT_COLOR


def test_disconnected_overlay_darkens_the_scene(lib) -> None:
    pygame.init()
    a, b = pygame.Surface(SIZE), pygame.Surface(SIZE)
    for surf, off in ((a, False), (b, True)):
        Renderer(SIZE).draw(surf, list(scene(lib)))
        Hud().draw(surf, HudState(disconnected=off, source=SourceSnapshot(state="disconnected" if off else "connected")))
    probe = (int(SIZE[0] * 0.5), int(SIZE[1] * 0.9))  # the canvas, outside the message box
    assert sum(b.get_at(probe)[:3]) < 0.5 * sum(a.get_at(probe)[:3])


def test_recognition_panel_shows_buffers_and_marks() -> None:
    from game.hud import OK_COLOR, REJECT_COLOR, SWITCH_COLOR

    pygame.init()
    panel = pygame.Rect(0, SIZE[1] - 180, 360, 180)

    def draw(**kw) -> pygame.Surface:
        surf = pygame.Surface(SIZE)
        surf.fill((0, 0, 0))
        Hud().draw(surf, HudState(**kw))
        return surf

    idle = draw()
    assert colour_count(idle, panel, OK_COLOR, tol=5) == 0
    assert colour_count(idle, panel, SWITCH_COLOR, tol=5) == 0
    st = HudState()
    st.mark({"event": "start", "action": "hook_r", "score": 0.3})
    st.mark({"event": "switch", "action": "uppercut_r", "from_frame": 6, "score": 0.2})
    assert st.action == "uppercut_r" and st.switch_from == 6
    busy = draw(main_fill=6, supp_fill=30, switch_age=0, reject_age=0, action="uppercut_r", score=0.2)
    assert colour_count(busy, panel, OK_COLOR, tol=5) > 6 * 150  # six lit main-buffer cells
    assert colour_count(busy, panel, SWITCH_COLOR, tol=5) > 300
    assert colour_count(busy, panel, REJECT_COLOR, tol=5) > 300
    for _ in range(60):
        st.tick()
    assert st.switch_age >= 45  # the mark goes out


def bluish(surf: pygame.Surface, rect: pygame.Rect) -> int:
    rect = rect.clip(surf.get_rect())
    a = pygame.surfarray.array3d(surf)[rect.left:rect.right, rect.top:rect.bottom].astype(int)
    return int(((a[..., 2] - a[..., 0] > 25) & (a[..., 2] - a[..., 1] > 10)).sum())  # blue over skin or red


def test_the_near_boxer_is_translucent_where_it_hides_the_cpu(lib) -> None:
    """Issue 17: in a clinch the player's boxer, seen from behind, hid the CPU."""
    pygame.init()
    # the CPU straight behind the player along the camera's line of sight: fully hidden
    r = Renderer(SIZE)
    eye = r.camera.eye
    back = np.array([eye[0], 0.0, eye[2]]) / np.hypot(eye[0], eye[2])
    player = local_to_world(lib["guard"].posture(0), (float(back[0]) * 0.4, float(back[2]) * 0.4,
                                                      float(np.arctan2(-back[0], -back[2]))))
    opponent = local_to_world(lib["guard"].posture(0), (float(-back[0]) * 0.4, float(-back[2]) * 0.4,
                                                        float(np.arctan2(back[0], back[2]))))
    shown = pygame.Surface(SIZE)
    r.draw(shown, [player, opponent])
    opaque = Renderer(SIZE)
    opaque.see_through = False
    hidden = pygame.Surface(SIZE)
    opaque.draw(hidden, [player, opponent])
    box = r.screen_box(player)
    assert bluish(shown, box) > 2 * bluish(hidden, box) + 300
    # the player is still there, drawn over it (its red trunks, blended)
    assert colour_count(shown, box, PLAYER_LOOK.trunks, tol=90) > 200
    # apart: nothing changes
    far_apart = scene(lib)
    a, b = pygame.Surface(SIZE), pygame.Surface(SIZE)
    r.draw(a, list(far_apart))
    opaque.draw(b, list(far_apart))
    assert r._overlap(list(far_apart)) is None


def test_key_legend_sits_on_a_dark_panel_and_names_hands_in_capitals() -> None:
    """Issue 17: a rope crossed the key legend, and "straight l" read as "straight I"."""
    from game.hud import action_label
    from game.keyboard_source import key_help

    assert action_label("straight_l") == "straight L" and action_label("hook_r") == "hook R"
    assert action_label("step_left") == "step left" and action_label("block") == "block"
    pygame.init()
    for size in (SIZE, (640, 360)):
        surf = pygame.Surface(size)
        surf.fill((235, 235, 235))  # a bright scene (the canvas, a white rope) under the legend
        hud = Hud()
        hud.draw(surf, HudState(keys=key_help()))
        panel = hud.key_panel
        assert panel is not None and surf.get_rect().contains(panel)
        a = pygame.surfarray.array3d(surf)[panel.left:panel.right, panel.top:panel.bottom].astype(int).sum(axis=2) / 3
        assert np.median(a) < 70  # the panel hides what is behind it
        assert (a > 180).sum() > 200  # and the legend's text is bright on it


@pytest.mark.parametrize("size", [SIZE, (960, 540), (1600, 900)])
def test_knockdown_count_is_clear_of_the_corner_posts(size) -> None:
    """Issue 17: the count "2" sat over the far corner post."""
    from game.render import POST_HALF, POST_HEIGHT

    pygame.init()
    r = Renderer(size)
    surf = pygame.Surface(size)
    hud = Hud()
    hud.draw(surf, HudState(match=MatchSnapshot(phase="count", downed=(1,), count=2, knockdowns=(0, 2))))
    assert hud.count_rect is not None and surf.get_rect().contains(hud.count_rect)
    for x, z in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
        ends = np.array([[x * POST_HALF, 0.0, z * POST_HALF], [x * POST_HALF, POST_HEIGHT, z * POST_HALF]])
        xy, depth = r.camera.project(ends)
        half = 0.08 * float(r.camera.scale_at(depth.min()))
        post = pygame.Rect(int(xy[:, 0].min() - half), int(xy[:, 1].min()), int(2 * half + abs(xy[0, 0] - xy[1, 0])),
                           int(abs(xy[0, 1] - xy[1, 1])))
        assert not hud.count_rect.colliderect(post), (x, z, post, hud.count_rect)


def test_budget_overlay_has_a_header_over_its_columns() -> None:
    """Issue 17: the F3 overlay's first column (the stage names) had no header."""
    from engine.clock import VirtualClock
    from engine.loop import FixedStepLoop
    from game.hud import BUDGET_HEADERS

    assert BUDGET_HEADERS[0] == "stage"
    pygame.init()
    loop = FixedStepLoop(VirtualClock())
    loop.add_stage("physics", lambda s, dt: None, 3.0)
    loop.set_render(lambda a: None, 8.0)
    loop.run(frames=5)
    drawn = {}
    for headers in (BUDGET_HEADERS, ("", "", "", "")):
        import game.hud_budget as hud_mod  # the F3 overlay draws its headers

        old = hud_mod.BUDGET_HEADERS
        hud_mod.BUDGET_HEADERS = headers
        try:
            surf = pygame.Surface(SIZE)
            hud = Hud()
            hud.draw(surf, HudState(show_budget=True), loop.budget)
            drawn[headers[0]] = pygame.surfarray.array3d(surf).astype(int)
        finally:
            hud_mod.BUDGET_HEADERS = old
    # the header row sits between the stacked bar and the first stage row, left in the panel
    band = (slice(SIZE[0] - 440, SIZE[0] - 300), slice(178, 200))
    assert (drawn["stage"][band] != drawn[""][band]).any(axis=2).sum() > 30


def test_budget_overlay_lists_stages_not_the_spans_inside_them() -> None:
    """docs/engine.md's `with loop.span("physics.collide")` inside a stage gave the F3 overlay a
    row of its own that always read 0.00 ms last and 0.00 p99 (the overlay reads stage runs,
    depth 0, only), however long the span took."""
    from engine.clock import VirtualClock
    from engine.loop import FixedStepLoop

    pygame.init()
    loop = FixedStepLoop(VirtualClock(), auto_freeze_gc=False)

    def physics(step: int, dt: float) -> None:
        with loop.span("physics.collide"):
            sum(range(2000))

    loop.add_stage("physics", physics, 3.0)
    loop.set_render(lambda a: None, 8.0)
    loop.run(frames=5)
    hud = Hud()
    hud.draw(pygame.Surface(SIZE), HudState(show_budget=True), loop.budget)
    assert [row[0] for row in hud._rows_text] == ["physics", "render", "unaccounted"]


@pytest.mark.parametrize("render_hz, period", [(60, "16.7"), (30, "33.3")])
def test_budget_overlay_measures_a_frame_against_its_period(render_hz, period, monkeypatch) -> None:
    """Low power renders every other step: a frame holds two steps' stages, so its line is the
    33.3 ms a frame has, not one step's 16.7 ms (frames within their period looked over it)."""
    from engine.clock import VirtualClock
    from engine.loop import FixedStepLoop

    pygame.init()
    loop = FixedStepLoop(VirtualClock(), render_hz=render_hz)
    loop.add_stage("physics", lambda s, dt: None, 3.0)
    loop.set_render(lambda a: None, 8.0)
    loop.run(frames=5)
    said = []
    hud = Hud()
    real = hud.blit
    monkeypatch.setattr(hud, "blit", lambda surf, text, *a, **k: (said.append(text), real(surf, text, *a, **k))[1])
    hud.draw(pygame.Surface(SIZE), HudState(show_budget=True), loop.budget)
    assert any(t.startswith(f"frame budget {period} ms") for t in said), said[:3]


def test_the_facing_vector_is_np_cross_to_the_bit_without_calling_it(monkeypatch) -> None:
    # each boxer's eyes, every frame in both renderers: np.cross cost ~15 us a call
    from game.render import facing

    rng = np.random.default_rng(3)
    rights = [np.array((x, 0.0, z)) for x, z in rng.normal(size=(200, 2))]
    rights += [np.array(v) for v in ((0.0, 0.0, 1.0), (-0.0, 0.0, -1.0), (1.0, 0.0, 0.0), (-1.0, 0.0, -0.0), (-0.0, 0.0, 0.0))]
    for r in rights:
        assert facing(r).tobytes() == np.cross(r, (0.0, 1.0, 0.0)).tobytes(), r
    scene = Renderer((320, 180))
    pose = load_library()["guard"].posture(0)
    bodies = [local_to_world(pose, (0.0, -0.9, 0.0)), local_to_world(pose, (0.0, 0.9, np.pi))]

    def no_cross(*args, **kwargs):
        raise AssertionError("np.cross in a frame")

    monkeypatch.setattr(np, "cross", no_cross)
    scene.draw(pygame.Surface((320, 180)), bodies)
