"""The scope under SDL's dummy driver: real pixels in the screenshot, state and rate shown,
reproducible headless runs, the Wiimote -> demo fallback."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import engine.sensors.source as source_mod
from engine.sensors import SourceError, SourceState
from engine.sensors.demo import DemoSource
from tools.cli import main
from tools.scope import AXIS_COLORS, STATE_COLORS, ScopeView, open_with_fallback

REPO = Path(__file__).resolve().parents[2]
VIEW = ScopeView()


def load_rgb(path: Path) -> np.ndarray:
    import pygame

    surf = pygame.image.load(str(path))
    return np.transpose(pygame.surfarray.array3d(surf), (1, 0, 2)).astype(int)  # (h, w, 3)


def count_color(img: np.ndarray, color: tuple[int, int, int], box: tuple[int, int, int, int], tol: int = 30) -> int:
    x0, y0, w, h = box
    region = img[y0: y0 + h, x0: x0 + w]
    return int((np.abs(region - np.array(color)).max(axis=2) <= tol).sum())


def status_box() -> tuple[int, int, int, int]:
    return (0, 0, VIEW.width, VIEW.status_h)


def scope_shot(tmp_path: Path, *args: str, frames: int = 150, name: str = "shot.png") -> np.ndarray:
    out = tmp_path / name
    assert main(["scope", "--headless", "--frames", str(frames), "--screenshot", str(out), *args]) == 0
    img = load_rgb(out)
    assert img.shape == (VIEW.height, VIEW.width, 3)
    return img


def test_scope_draws_every_axis_of_both_hands(tmp_path):
    img = scope_shot(tmp_path, "--source", "demo://")
    for hand in range(2):
        box = VIEW.panel_rect(hand)
        for color in AXIS_COLORS:
            assert count_color(img, color, box, tol=25) > 300, (hand, color)
    # the status line is drawn in the "connected" colour
    assert count_color(img, STATE_COLORS[SourceState.CONNECTED], status_box(), tol=10) > 50


def test_scope_with_a_one_hand_recording_leaves_the_left_panel_empty(tmp_path, shared_data):
    src = shared_data / "phone-boxing" / "train.csv"
    img = scope_shot(tmp_path, "--source", f"replay://{src}")
    right, left = VIEW.panel_rect(0), VIEW.panel_rect(1)
    assert all(count_color(img, c, right, tol=25) > 150 for c in AXIS_COLORS)
    assert all(count_color(img, c, left, tol=25) == 0 for c in AXIS_COLORS)


def test_scope_shows_an_ended_source(tmp_path):
    rec = tmp_path / "short.csv"
    rec.write_text("t,rx,ry,rz\n" + "".join(f"{i / 100:.2f},0,0,1\n" for i in range(20)))
    img = scope_shot(tmp_path, "--source", f"replay://{rec}", frames=60)
    assert count_color(img, STATE_COLORS[SourceState.ENDED], status_box(), tol=6) > 50
    assert count_color(img, STATE_COLORS[SourceState.CONNECTED], status_box(), tol=10) == 0


def test_scope_scrolls(tmp_path):
    a = scope_shot(tmp_path, frames=100, name="a.png")
    b = scope_shot(tmp_path, frames=130, name="b.png")
    box = VIEW.panel_rect(0)
    assert count_color(a, AXIS_COLORS[0], box) > 0 and (a != b).any()


def run_headless(*args: str) -> str:
    env = {**os.environ, "PYTHONPATH": str(REPO), "SDL_VIDEODRIVER": "dummy", "SDL_AUDIODRIVER": "dummy"}
    r = subprocess.run([sys.executable, "-m", "tools.cli", "scope", "--headless", *args],
                       cwd=REPO, env=env, capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    line = [x for x in r.stdout.splitlines() if x.startswith("state ")]
    assert len(line) == 1
    return line[0]


def test_two_headless_runs_give_the_same_state_hash():
    a = run_headless("--frames", "90", "--source", "demo://?rate=430")
    b = run_headless("--frames", "90", "--source", "demo://?rate=430")
    assert a == b
    assert run_headless("--frames", "91", "--source", "demo://?rate=430") != a


def no_wiimote(url, clock):
    raise SourceError("no Wiimote found")


def test_fallback_to_the_demo_source_with_a_banner(monkeypatch):
    monkeypatch.setitem(source_mod._factories, "wiimote", no_wiimote)
    src, banner = open_with_fallback("wiimote://", clock=lambda: 0.0)
    assert isinstance(src, DemoSource) and "No Wiimote" in banner


def test_fallback_when_the_device_is_disconnected(monkeypatch):
    closed = []

    class Gone(DemoSource):
        def close(self):
            closed.append(True)

    def factory(url, clock):
        s = Gone(url=url, clock=clock)
        s.state = SourceState.DISCONNECTED
        return s

    monkeypatch.setitem(source_mod._factories, "wiimote", factory)
    src, banner = open_with_fallback("wiimote://", clock=lambda: 0.0)
    assert src.url == "demo://" and banner and closed == [True]


def test_an_explicit_source_does_not_fall_back(monkeypatch):
    monkeypatch.setitem(source_mod._factories, "wiimote", no_wiimote)
    with pytest.raises(SourceError):
        open_with_fallback("wiimote://some/path", clock=lambda: 0.0)
    src, banner = open_with_fallback("demo://?rate=50", clock=lambda: 0.0)
    assert banner == "" and src.rate_hz == 50


# -- the first hour (issue 17): no silent zero-sample runs, readable labels, no clipping -----

def test_scope_on_a_missing_serial_port_exits_2_after_the_connect_timeout(tmp_path, capsys):
    rc = main(["scope", "--headless", "--source", f"serial://{tmp_path / 'no-port'}", "--connect-timeout", "0.5"])
    err = capsys.readouterr().err
    assert rc == 2
    assert "no device connected after 0.5 s" in err and "0 samples" not in err


def scope_with_labels(size: str, source: str = "demo://"):
    from engine.clock import VirtualClock
    from engine.sensors import open_source
    from tools.scope import Scope, ScopeView, run_scope  # noqa: F401

    w, h = (int(v) for v in size.split("x"))
    clock = VirtualClock()
    view = ScopeView(width=w, height=h, auto_range=True)
    scope = run_scope(open_source(source, clock=clock.seconds), clock=clock, frames=60, view=view)
    return scope, view


@pytest.mark.parametrize("size", ["960x600", "400x200", "1280x900"])
def test_scope_g_labels_stay_inside_their_panel_and_never_overlap(size):
    scope, view = scope_with_labels(size)
    rects = scope.label_rects
    assert len(rects) >= 4
    for i, (x, y, w, h) in enumerate(rects):
        inside = [hand for hand in range(2) if view.panel_rect(hand)[1] <= y and y + h <= sum(view.panel_rect(hand)[1::2])]
        assert inside, (x, y, w, h)
        for x2, y2, w2, h2 in rects[i + 1:]:
            assert y + h <= y2 or y2 + h2 <= y, ((x, y, w, h), (x2, y2, w2, h2))


READOUT_W = 200  # the right of a panel's top, where each axis's reading is written in its colour


def test_scope_autoscales_a_punch_beyond_4_g_and_range_fixes_the_scale(tmp_path):
    t = np.arange(0, 3, 1 / 100)
    accel = np.zeros((len(t), 2, 3))
    accel[:, :, 2] = 1.0
    accel[:, 0, 0] = 11.0 * np.sin(2 * np.pi * 1.5 * t)  # a phone punch: 11 g
    from engine.recording import Recording, write_recording

    rec = tmp_path / "punch.csv"
    write_recording(rec, Recording(t, accel))
    img = scope_shot(tmp_path, "--source", f"replay://{rec}?loop=1", frames=120)
    x0, y0, w, h = VIEW.panel_rect(0)
    rows = np.nonzero((np.abs(img[y0:y0 + h, x0:x0 + w - READOUT_W] - np.array(AXIS_COLORS[0])).max(axis=2) <= 25).any(axis=1))[0]
    # the x trace peaks inside the panel (16 g scale), not flattened against its edges
    assert rows.min() > 0.1 * h and rows.max() < 0.9 * h
    clipped = scope_shot(tmp_path, "--source", f"replay://{rec}?loop=1", "--range", "4", frames=120, name="c.png")
    rows = np.nonzero((np.abs(clipped[y0:y0 + h, x0:x0 + w - READOUT_W] - np.array(AXIS_COLORS[0])).max(axis=2) <= 25).any(axis=1))[0]
    assert rows.min() <= 2 and rows.max() >= h - 3


def test_a_long_status_line_stays_inside_the_window(tmp_path):
    long = tmp_path / ("a-very-long-directory-name-" * 4)
    long.mkdir()
    rec = long / "rec.csv"
    rec.write_text("t,rx,ry,rz\n" + "".join(f"{i / 100:.2f},0,0,1\n" for i in range(300)))
    out = tmp_path / "long.png"
    assert main(["scope", "--headless", "--frames", "30", "--screenshot", str(out), "--size", "480x400",
                 "--source", f"replay://{rec}"]) == 0
    img = load_rgb(out)
    color = STATE_COLORS[SourceState.CONNECTED]
    assert count_color(img, color, (0, 0, 480, 24), tol=10) > 50
    assert count_color(img, color, (472, 0, 8, 24), tol=10) == 0  # nothing drawn into the right margin


def test_headless_scope_of_a_live_device_runs_on_the_real_clock(tmp_path, capsys):
    """`scope --headless` on a serial device: the virtual clock ran 300 frames in well under a
    second and saw 79 of the device's samples ("0.0 samples/s"); a live device runs on the real
    clock, said in one line, and 90 frames (1.5 s) see about 300 samples at 200 Hz."""
    import subprocess
    import sys
    from pathlib import Path

    repo = Path(__file__).resolve().parents[2]
    link = tmp_path / "port"
    emu = subprocess.Popen([sys.executable, "-m", "tools.cli", "bridge", "emulate", "--seconds", "8", "--link", str(link),
                            "--quiet"], cwd=repo, stdout=subprocess.PIPE, text=True)
    try:
        assert emu.stdout.readline().startswith("port: ")
        assert main(["scope", "--headless", "--source", f"serial://{link}", "--frames", "90"]) == 0
    finally:
        emu.terminate()
        emu.wait(5)
    err = capsys.readouterr().err
    assert "is a live device: --headless runs on the real clock" in err
    import re

    samples = int(re.search(r"^scope: (\d+) samples", err, re.M).group(1))
    assert 200 <= samples <= 400, err


def test_each_hand_shows_its_readings_in_numbers(tmp_path):
    """The traces alone could not tell 0.9 g from 1.0 g, which is how a serial IMU's axes are
    found (firmware_bridge/README.md, `?axes=`): each hand's panel shows its axes' mean reading
    over the last quarter second, in numbers."""
    from engine.recording import Recording, write_recording

    t = np.arange(0, 3, 1 / 100)
    accel = np.tile([[0.02, 0.91, 0.41], [-0.5, 0.0, 0.87]], (len(t), 1, 1))
    rec = tmp_path / "guard.csv"
    write_recording(rec, Recording(t, accel))
    scope, _ = scope_with_labels("960x600", f"replay://{rec}?loop=1")
    np.testing.assert_allclose(scope.readouts[0], (0.02, 0.91, 0.41), atol=1e-3)
    np.testing.assert_allclose(scope.readouts[1], (-0.5, 0.0, 0.87), atol=1e-3)


def test_scope_says_a_wiimote_streams_without_its_nunchuk(tmp_path, monkeypatch):
    # the left panel's traces lie flat at 1 g: the state line says why
    from engine.clock import VirtualClock
    from engine.sensors import open_source
    from tools.scope import run_scope

    monkeypatch.setenv("SDL_VIDEODRIVER", "dummy")
    rec = tmp_path / "s.csv"
    assert main(["synth", "--session", "2", "--seed", "2", "-o", str(rec)]) == 0
    clock = VirtualClock()
    scope = run_scope(open_source(f"wiimote-emu://{rec}?nunchuk=0", clock=clock.seconds), clock=clock, frames=60)
    assert scope.status_line.startswith("connected, no Nunchuk: plug it in for left-hand moves"), scope.status_line
    clock = VirtualClock()
    whole = run_scope(open_source(f"wiimote-emu://{rec}", clock=clock.seconds), clock=clock, frames=60)
    assert whole.status_line.startswith("connected   "), whole.status_line


def test_headless_scope_ended_by_sigterm_writes_its_trace_and_exits_130(tmp_path, sigterm_when_running) -> None:
    """SDL turned SIGTERM into a quit event: the scope ended as a closed window, exit 0, and
    without its trace when one ended by Ctrl-C. Now it ends as `play` does: the trace written,
    exit 130."""
    from engine.trace import read_chrome_trace

    trace = tmp_path / "t.json"
    env = {**os.environ, "PYTHONPATH": str(REPO), "SDL_VIDEODRIVER": "dummy", "SDL_AUDIODRIVER": "dummy"}
    code, out, err = sigterm_when_running(["scope", "--headless", "--frames", "100000000", "--trace", str(trace)], env)
    assert code == 130, err
    assert "Traceback" not in err and "state " not in out, (out, err)
    assert any(ev.get("name") == "frame" for ev in read_chrome_trace(trace)["traceEvents"])
