"""`quickjab play` on a serial board that reboots with one sensor fewer (an IMU that fails at
boot): the game keeps running (the frames stage raised a broadcast error before)."""

from __future__ import annotations

import os
import sys
import threading
import tty
from collections.abc import Callable
from pathlib import Path

from firmware_bridge import protocol
from tools.cli import main

sys.path.insert(0, str(Path(__file__).parent))
from game_graph import graph_path  # noqa: E402,F401 - the fixture


def test_play_survives_a_reboot_to_one_sensor(tmp_path, monkeypatch, capsys, graph_path):  # noqa: F811
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "xdg"))
    master, slave = os.openpty()
    tty.setraw(slave)

    def board():
        os.read(master, 1)  # the host opened the port and asked for a HELLO (its open flushed before)
        two = protocol.encode_hello(0, 0, 1, 200, 4096, 65500, 30, protocol.IMU_MPU6050, 3) + b"".join(
            protocol.encode_sample(i, 5000 * i, (0, 0, 4096), (0, 4096, 0)) for i in range(1, 40))
        one = protocol.encode_hello(0, 0, 2, 200, 4096, 65500, 30, protocol.IMU_MPU6050, protocol.FLAG_SENSOR_A) + b"".join(
            protocol.encode_sample(i, 5000 * i, (4096, 0, 0)) for i in range(1, 40))
        os.write(master, two + one)

    th = threading.Thread(target=board, daemon=True)
    th.start()
    try:
        rc = main(["play", "--headless", "--frames", "40", "--graph", graph_path, "--no-sound",
                   "--source", f"serial://{os.ttyname(slave)}"])
    finally:
        th.join(5)
        os.close(master)
        os.close(slave)
    assert rc == 0, capsys.readouterr().err


def test_the_hud_says_the_board_came_back_with_one_sensor_fewer(graph_path):  # noqa: F811
    """The other hand's readings hold still after such a reboot: the source line and the amber
    strip under the clock say so (Session passes the sensors it reads to the snapshot)."""
    import pygame

    from engine.clock import VirtualClock
    from engine.sensors import open_source
    from game.session import Session, SessionConfig

    master, slave = os.openpty()
    tty.setraw(slave)
    try:
        pygame.init()
        pygame.display.set_mode((640, 360))
        clock = VirtualClock()
        cfg = SessionConfig(seed=0, size=(640, 360), sound=False, render=True, graph=graph_path)
        s = Session(open_source(f"serial://{os.ttyname(slave)}", clock=clock.seconds), cfg, clock=clock,
                    surface_provider=pygame.display.get_surface)
        os.write(master, protocol.encode_hello(0, 0, 1, 200, 4096, 65500, 30, protocol.IMU_MPU6050, 3) + b"".join(
            protocol.encode_sample(i, 5000 * i, (0, 0, 4096), (0, 4096, 0)) for i in range(1, 40)))
        s.loop.run(steps=10)
        assert s.hud_state.source.missing == ""
        os.write(master, protocol.encode_hello(0, 0, 2, 200, 4096, 65500, 30, protocol.IMU_MPU6050, protocol.FLAG_SENSOR_A)
                 + b"".join(protocol.encode_sample(i, 5000 * i, (4096, 0, 0)) for i in range(1, 40)))
        s.loop.run(steps=10)
        hud = s.view.hud
        hud.layout = []
        s.loop.run(frames=1)
        said = [text for text, _, _ in hud.layout]
        assert any(t.endswith("  connected, 1 of 2 sensors") for t in said), said
        assert "1 of 2 sensors: the other hand holds still" in said and "missing banner" in hud.panels
    finally:
        os.close(master)
        os.close(slave)


def one_hand_templates(path: Path) -> Path:
    import numpy as np

    from engine.recognition import Templates

    rng = np.random.default_rng(0)
    trial = np.tile([0.0, 0.0, 1.0], (60, 1))
    trial[20:40, 0] += 2.0 * np.sin(np.linspace(0, np.pi, 20))
    path.parent.mkdir(parents=True, exist_ok=True)
    Templates.from_trials({"straight_r": [trial + rng.normal(0, 0.01, trial.shape) for _ in range(3)]}).save(path)
    return path


def play_with_a_one_imu_board(args: Callable[[str], list[str]]) -> int:
    """`quickjab` with `args(url)`, url a serial:// port with a one-IMU board on it."""
    master, slave = os.openpty()
    tty.setraw(slave)

    def board():
        os.read(master, 1)  # the host opened the port and asked for a HELLO
        os.write(master, protocol.encode_hello(0, 0, 1, 200, 4096, 65500, 30, protocol.IMU_MPU6050, protocol.FLAG_SENSOR_A)
                 + b"".join(protocol.encode_sample(i, 5000 * i, (0, 0, 4096)) for i in range(1, 40)))

    th = threading.Thread(target=board, daemon=True)
    th.start()
    try:
        return main(args(f"serial://{os.ttyname(slave)}"))
    finally:
        th.join(5)
        os.close(master)
        os.close(slave)


def test_play_takes_a_one_imu_board_with_one_hand_templates(tmp_path, monkeypatch, capsys, graph_path):  # noqa: F811
    """A serial board's sensor count is a guess (2) until its HELLO, and `play` checked the guess
    against the templates at its start: a one-IMU board with the one-hand moves `train` made from
    it was refused ("the source has 2 sensor(s), the templates need 1")."""
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "xdg"))
    one_hand = one_hand_templates(tmp_path / "one.npz")
    rc = play_with_a_one_imu_board(lambda url: ["play", "--headless", "--frames", "40", "--graph", graph_path,
                                                "--no-sound", "--templates", str(one_hand), "--source", url])
    assert rc == 0, capsys.readouterr().err


def test_player_two_on_a_one_imu_board_plays_their_one_hand_moves(tmp_path, monkeypatch, capsys, graph_path):  # noqa: F811
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "xdg"))
    from game.userdata import profile_templates_path

    one_hand_templates(profile_templates_path("ana"))
    rc = play_with_a_one_imu_board(lambda url: ["play", "--players", "2", "--headless", "--frames", "40", "--graph",
                                                graph_path, "--no-sound", "--source", "keyboard://", "--profile2", "ana",
                                                "--source2", url])
    assert rc == 0, capsys.readouterr().err
