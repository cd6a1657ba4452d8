"""A real X window (Xvfb) renders the same frame as the SDL dummy driver.

Both runs are `quickjab play` with a virtual clock and the same seed, so they simulate the same
steps; the test compares the two screenshots pixel by pixel. Skipped where Xvfb is absent
(CI installs it: .ci/setup-system).
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pygame
import pytest

sys.path.insert(0, str(Path(__file__).parent))
from game_graph import graph_path  # noqa: E402,F401 - the fixture

REPO = Path(__file__).resolve().parents[2]
XVFB = shutil.which("Xvfb")


def play(tmp: Path, out: Path, env_extra: dict[str, str], graph: str, headless: bool) -> None:
    env = {**os.environ, "XDG_DATA_HOME": str(tmp / "xdg"), "SDL_AUDIODRIVER": "dummy", **env_extra}
    cmd = [sys.executable, "-m", "tools.cli", "play", "--source", "keyboard://?seed=2", "--demo", "--seed", "2",
           "--frames", "40", "--size", "640x360", "--no-sound", "--graph", graph, "--screenshot", str(out)]
    cmd.append("--headless" if headless else "--virtual-clock")
    r = subprocess.run(cmd, cwd=REPO, env=env, capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr


@pytest.mark.skipif(XVFB is None, reason="Xvfb is not installed (apt-get install xvfb)")
def test_xvfb_window_renders_the_same_frame_as_the_dummy_driver(tmp_path, graph_path) -> None:  # noqa: F811 - the imported fixture
    # -displayfd: Xvfb picks a free display and writes its number to the pipe once it is ready
    read_fd, write_fd = os.pipe()
    server = subprocess.Popen([XVFB, "-displayfd", str(write_fd), "-screen", "0", "800x600x24", "-nolisten", "tcp"],
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, pass_fds=(write_fd,))
    os.close(write_fd)
    try:
        with os.fdopen(read_fd) as pipe:
            number = pipe.readline().strip()
        if not number:
            pytest.skip("Xvfb did not start")
        display = f":{number}"
        dummy, x11 = tmp_path / "dummy.png", tmp_path / "x11.png"
        play(tmp_path, dummy, {"SDL_VIDEODRIVER": "dummy"}, graph_path, headless=True)
        play(tmp_path, x11, {"SDL_VIDEODRIVER": "x11", "DISPLAY": display}, graph_path, headless=False)
    finally:
        server.terminate()
        server.wait(timeout=10)
    pygame.init()
    a = pygame.surfarray.array3d(pygame.image.load(str(dummy))).astype(int)
    b = pygame.surfarray.array3d(pygame.image.load(str(x11))).astype(int)
    assert a.shape == b.shape == (640, 360, 3)
    diff = np.abs(a - b).max(axis=2)
    # the same pixels: allow a sliver for blending rounding between surface formats
    assert (diff > 8).mean() < 0.002, f"{(diff > 8).mean():.4f} of the pixels differ"
    print(f"pixels differing: {(diff > 0).mean():.5f}")
    assert a.std() > 10  # and it is a real frame, not two blank ones
