"""A contact sheet of the action library: key frames of every action drawn with pygame in a
three-quarter view, so a person can check that each action reads as what it claims to be.
`quickjab actions sheet -o docs/img/actions.png`."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from engine.errors import InputError
from game.actions import ACTION_NAMES, Action
from game.skeleton import BONES, JOINTS, compose_root, local_to_world

VIEW_YAW = np.radians(35.0)  # camera turned around the boxer: shows straights and hooks
CELL_W, CELL_H, SCALE = 130, 190, 95.0
TOP_H, TOP_SCALE = 78, 90.0  # the view from above under each frame: arcs vs. straight lines
LEFT_COLOUR, RIGHT_COLOUR, MID_COLOUR = (60, 120, 230), (220, 60, 50), (40, 40, 40)
HOT_CELL, COLD_CELL = (255, 236, 200), (238, 238, 232)
LEGEND_H = 30
MARGIN = 8  # pixels a figure keeps from its cell's edges


def key_frames(a: Action, n: int = 6) -> list[int]:
    """n frames that tell the action: evenly spaced, with the middle of each attack window."""
    frames = set(np.linspace(0, a.frames - 1, n).round().astype(int).tolist())
    for w in a.attacks:
        peak = (w.start + w.end) // 2
        frames.discard(min(frames, key=lambda f: abs(f - peak) if 0 < f < a.frames - 1 else 1e9))
        frames.add(peak)
    return sorted(frames)


def _project(p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    c, s = np.cos(VIEW_YAW), np.sin(VIEW_YAW)
    sx = c * p[..., 0] + s * p[..., 2]
    depth = -s * p[..., 0] + c * p[..., 2]
    sy = p[..., 1] + 0.12 * depth
    return np.stack([sx, sy], axis=-1), depth


def _colour(j: int) -> tuple[int, int, int]:
    name = JOINTS[j]
    return LEFT_COLOUR if name.endswith("_l") else RIGHT_COLOUR if name.endswith("_r") else MID_COLOUR


def fit(poses: list[np.ndarray], width: float, height: float) -> tuple[float, float]:
    """(scale, x centre in metres) so that every one of an action's figures fits a cell of
    width x height pixels: a knockdown lies as long as a boxer stands tall."""
    xy = [_project(p)[0] for p in poses]
    head_r = 0.11  # the head circle reaches past its joint
    both = np.concatenate(xy)
    span_x = float(np.ptp(both[:, 0])) + 2 * head_r  # all the frames, root motion included
    one_x = max(float(np.ptp(q[:, 0])) for q in xy) + 2 * head_r  # the widest single frame
    span_y = float(both[:, 1].max()) + head_r
    scale = min(SCALE, width / max(one_x, 1e-6), height / max(span_y, 1e-6))
    centre = 0.5 * float(both[:, 0].max() + both[:, 0].min()) if span_x * scale <= width else float("nan")
    return scale, centre


def draw_posture(surface, posture: np.ndarray, origin: tuple[float, float], scale: float = SCALE) -> None:
    import pygame

    xy, depth = _project(posture)
    pts = np.column_stack([origin[0] + xy[:, 0] * scale, origin[1] - xy[:, 1] * scale])
    # far bones first so near limbs overlap them
    order = np.argsort(-(depth[BONES[:, 0]] + depth[BONES[:, 1]]))
    for b in order:
        p, c = BONES[b]
        pygame.draw.line(surface, _colour(c), pts[p], pts[c], 3)
    head = JOINTS.index("head")
    pygame.draw.circle(surface, MID_COLOUR, pts[head], 0.11 * scale, 2)
    for name in ("fist_l", "fist_r"):
        j = JOINTS.index(name)
        pygame.draw.circle(surface, _colour(j), pts[j], 0.055 * scale)


def draw_top(surface, posture: np.ndarray, trail: np.ndarray, origin: tuple[float, float],
             scale: float = TOP_SCALE) -> None:
    """Seen from above (boxer facing up the page, +x to the right): shoulders, arms and the
    punching hands' paths so far, which tell a straight from a hook from a parry."""
    import pygame

    def pt(p):
        return (origin[0] + p[..., 0] * scale, origin[1] - p[..., 2] * scale)

    for hand, colour in (("l", LEFT_COLOUR), ("r", RIGHT_COLOUR)):
        path = trail[:, JOINTS.index(f"fist_{hand}")]
        if len(path) > 1:
            pygame.draw.lines(surface, tuple(int(c * 0.5 + 127) for c in colour), False,
                              [pt(q) for q in path], 2)  # fmt: skip
    sh_l, sh_r = JOINTS.index("shoulder_l"), JOINTS.index("shoulder_r")
    pygame.draw.line(surface, MID_COLOUR, pt(posture[sh_l]), pt(posture[sh_r]), 3)
    for side, colour in (("l", LEFT_COLOUR), ("r", RIGHT_COLOUR)):
        chain = [JOINTS.index(f"{j}_{side}") for j in ("shoulder", "elbow", "fist")]
        pygame.draw.lines(surface, colour, False, [pt(posture[j]) for j in chain], 3)
        pygame.draw.circle(surface, colour, pt(posture[chain[-1]]), 0.05 * scale)
    pygame.draw.circle(surface, MID_COLOUR, pt(posture[JOINTS.index("head")]), 0.09 * scale, 2)


def render_sheet(lib: dict[str, Action], names: list[str] | None = None, per_row: int = 2):
    """A pygame Surface with one strip of key frames per action."""
    import pygame

    pygame.font.init()
    if names is None:
        names = [*ACTION_NAMES, "guard", *sorted(n for n in lib if n.startswith("hit_")), "knockdown"]
        names += sorted(n for n in lib if n not in names)  # cut or authored actions of other names
    names = [n for n in names if n in lib]
    cols = max(len(key_frames(lib[n])) for n in names)
    strip_w = cols * CELL_W + 10
    rows = (len(names) + per_row - 1) // per_row
    row_h = CELL_H + TOP_H + 22
    sheet = pygame.Surface((per_row * strip_w, LEGEND_H + rows * row_h))
    sheet.fill((250, 250, 245))
    font = pygame.font.Font(None, 20)
    small = pygame.font.Font(None, 16)
    draw_legend(sheet, font)
    for i, name in enumerate(names):
        a = lib[name]
        x0, y0 = (i % per_row) * strip_w, LEGEND_H + (i // per_row) * row_h
        frames = key_frames(a)
        poses = [local_to_world(a.posture(f), compose_root((0.0, 0.0, 0.0), a.root_offset(f))) for f in frames]
        scale, centre = fit(poses, CELL_W - 2 * MARGIN, CELL_H - 24)
        sheet.blit(font.render(f"{name}  ({a.frames} f = {a.frames / 60:.2f} s)", True, (0, 0, 0)), (x0 + 4, y0 + 2))
        for k, (f, pose) in enumerate(zip(frames, poses, strict=True)):
            cx = x0 + k * CELL_W
            cell = pygame.Rect(cx + 2, y0 + 18, CELL_W - 4, CELL_H + TOP_H - 2)
            hot = a.attack_at(f) is not None or a.guard_at(f) is not None
            pygame.draw.rect(sheet, HOT_CELL if hot else COLD_CELL, cell)
            ground = y0 + CELL_H + 4
            pygame.draw.line(sheet, (160, 160, 150), (cx + 6, ground), (cx + CELL_W - 6, ground), 1)
            # root motion shown as displacement of the whole figure (around the action's centre;
            # frame by frame when the whole action would not fit)
            xs = _project(pose)[0][:, 0]
            mid = centre if np.isfinite(centre) else 0.5 * float(xs.max() + xs.min())
            sheet.set_clip(cell)  # nothing spills into the neighbouring cells
            draw_posture(sheet, pose, (cx + CELL_W * 0.5 - mid * scale, ground), scale)
            local = a.table[: f + 1] if f > 0 else a.table[:1]
            draw_top(sheet, a.posture(f), local, (cx + CELL_W * 0.5, ground + TOP_H - 12))
            sheet.set_clip(None)
            sheet.blit(small.render(f"f{f}", True, (90, 90, 90)), (cx + 5, y0 + 20))
    return sheet


def draw_legend(sheet, font) -> None:
    """What the colours mean, in a band over the strips."""
    import pygame

    x, y = 8, 7
    items = [("left arm / leg", LEFT_COLOUR, "line"), ("right arm / leg", RIGHT_COLOUR, "line"),
             ("attack or guard window active", HOT_CELL, "box"), ("outside the windows", COLD_CELL, "box")]
    for text, colour, kind in items:
        if kind == "line":
            pygame.draw.line(sheet, colour, (x, y + 7), (x + 22, y + 7), 4)
        else:
            pygame.draw.rect(sheet, colour, (x, y, 22, 15))
            pygame.draw.rect(sheet, (160, 160, 150), (x, y, 22, 15), 1)
        img = font.render(text, True, (0, 0, 0))
        sheet.blit(img, (x + 28, y + 1))
        x += 28 + img.get_width() + 22
    note = font.render("top: side view, f = clip frame at 60 Hz;  bottom: seen from above, with the fists' paths", True, (70, 70, 70))
    sheet.blit(note, (x, y + 1))


def write_sheet(lib: dict[str, Action], path: str | os.PathLike) -> Path:

    os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
    path = Path(path)
    if path.is_dir():  # said before the drawing
        raise InputError(f"{path}: a directory, not a file name for the sheet")
    path.parent.mkdir(parents=True, exist_ok=True)
    from game.launch import save_image

    save_image(render_sheet(lib), path, "the sheet")  # a file it cannot write whole: an InputError naming it
    return path
