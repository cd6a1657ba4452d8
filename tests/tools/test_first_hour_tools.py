"""Issue 17, the first hour with the tools: evaluate --plot without matplotlib, bvh cut into a
new folder, a cut action on the contact sheet, plots that read (sizes, legends off the bars)."""

from __future__ import annotations

import json
import sys

import numpy as np
import pytest

from tools.cli import main


def test_evaluate_plot_without_matplotlib_is_one_line_and_exit_2(tmp_path, monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "matplotlib", None)  # import matplotlib -> ImportError
    rc = main(["evaluate", "--plot", str(tmp_path / "f.png"), str(tmp_path / "whatever.csv")])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2
    assert len(err) == 1 and "--plot needs matplotlib" in err[0]
    from engine.errors import InputError
    from tools.evaluate_recognition import plot

    with pytest.raises(InputError, match="matplotlib"):
        plot({"a": []}, str(tmp_path / "f.png"))


def rows(n: int = 12) -> list[dict]:
    out = []
    for m in range(1, n + 1):
        ok = min(1.0, 0.5 + m / 20)
        out.append({"main": m, "acceptable": ok, "unnoticeable switch": 0.0, "noticeable switch": (1 - ok) / 2,
                    "unacceptable": (1 - ok) / 2, "first_correct": ok * 0.9})
    return out


def test_evaluate_plot_is_large_and_its_legend_covers_no_bar(tmp_path):
    import pygame

    from tools.evaluate_recognition import GROUPS, plot

    data = [{**{g: r.get(g, 0.0) for g in GROUPS}, "main": r["main"], "first_correct": r["first_correct"]} for r in rows()]
    png = tmp_path / "fig.png"
    layout = plot({"uWave": data, "phone": data}, str(png))
    w, h = pygame.image.load(str(png)).get_size()
    assert (w, h) == layout["size"] and w >= 1200 and h >= 450  # was 336x256 per panel
    lx0, ly0, lx1, ly1 = layout["legend"]
    for ax0, ay0, ax1, ay1 in layout["axes"]:
        assert ax1 - ax0 >= 450 and ay1 - ay0 >= 280
        assert lx1 <= ax0 or lx0 >= ax1 or ly1 <= ay0 or ly0 >= ay1  # the legend is outside every panel


def test_bvh_cut_creates_the_output_folder_and_the_sheet_shows_the_cut_action(tmp_path, capsys):
    import pygame

    bvh = tmp_path / "m.bvh"
    assert main(["bvh", "export", "--play", "straight_r,block", "-o", str(bvh)]) == 0
    js = tmp_path / "new" / "deeper" / "my_jab.json"
    assert main(["bvh", "cut", str(bvh), "--start", "2", "--end", "20", "--name", "my_jab", "-o", str(js)]) == 0
    assert json.loads(js.read_text())["name"] == "my_jab"
    base, more = tmp_path / "base.png", tmp_path / "more.png"
    assert main(["actions", "sheet", "-o", str(base)]) == 0
    assert main(["actions", "sheet", "--add", str(js.parent), "-o", str(more)]) == 0
    from game.actions import load_action, load_library
    from tools.contact_sheet import render_sheet  # noqa: F401

    lib = load_library()
    h0, h1 = pygame.image.load(str(base)).get_height(), pygame.image.load(str(more)).get_height()
    assert (len(lib) % 2 == 0 and h1 > h0) or (len(lib) % 2 == 1 and h1 == h0)
    assert load_action(js).name == "my_jab"


def test_contact_sheet_has_a_legend_and_keeps_the_knockdown_in_its_cells():
    import pygame

    from game.actions import load_library
    from game.skeleton import compose_root, local_to_world
    from tools.contact_sheet import (
        CELL_W,
        HOT_CELL,
        LEFT_COLOUR,
        LEGEND_H,
        MARGIN,
        RIGHT_COLOUR,
        _project,
        fit,
        key_frames,
        render_sheet,
    )

    lib = load_library()
    sheet = render_sheet(lib)
    band = np.transpose(pygame.surfarray.array3d(sheet.subsurface((0, 0, sheet.get_width(), LEGEND_H))), (1, 0, 2)).astype(int)
    for colour in (LEFT_COLOUR, RIGHT_COLOUR, HOT_CELL):
        assert (np.abs(band - np.array(colour)).max(axis=2) <= 4).sum() > 40, colour
    a = lib["knockdown"]
    poses = [local_to_world(a.posture(f), compose_root((0.0, 0.0, 0.0), a.root_offset(f))) for f in key_frames(a)]
    scale, centre = fit(poses, CELL_W - 2 * MARGIN, 160)
    for p in poses:
        xs = _project(p)[0][:, 0]
        mid = centre if np.isfinite(centre) else 0.5 * (xs.max() + xs.min())
        assert (xs.max() - mid) * scale <= CELL_W / 2 and (mid - xs.min()) * scale <= CELL_W / 2
