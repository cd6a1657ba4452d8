"""Cost of the motion layer: synthesizing one virtual-player trial, and one game step of two
boxers (two PlayerController steps + root + PD targets + the physics step), with peers
measured in the same run: the trial's own duration (real time), the physics step alone, and
the 16.7 ms frame budget.
"""

from __future__ import annotations

import argparse
import math
import statistics
import time

import numpy as np

from engine.clock import STEP_DT

DT = STEP_DT


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--trials", type=int, default=200, help="trials synthesized per timed run")
    p.add_argument("--steps", type=int, default=600, help="game steps per timed run")
    p.add_argument("--repeats", type=int, default=5, help="timed runs per figure (min and median shown)")
    p.add_argument("--action", default="hook_r", help="action to synthesize (default hook_r)")


def _time(fn, n: int, repeats: int) -> tuple[float, float]:
    """(min, median) seconds per call over `repeats` runs of n calls."""
    per = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        for _ in range(n):
            fn()
        per.append((time.perf_counter() - t0) / n)
    return min(per), statistics.median(per)


def run(args: argparse.Namespace) -> int:
    from engine.physics import World
    from game.actions import load_library
    from game.boxer import Boxer, hits_from_contacts
    from game.virtual_player import synthesize_action

    lib = load_library()
    if args.action not in lib:
        from engine.errors import InputError

        raise InputError(f"unknown action {args.action!r}")
    action = lib[args.action]
    rng = np.random.default_rng(0)
    print(f"virtual player, one {args.action} trial ({action.frames} frames = {action.frames / 60 * 1e3:.0f} ms of motion):")
    for profile in ("experienced", "novice"):
        lo, med = _time(lambda p=profile: synthesize_action(action, p, rng, library=lib), args.trials, args.repeats)
        real = action.frames / 60.0
        print(f"  {profile:12s} min {lo * 1e3:7.3f} ms  median {med * 1e3:7.3f} ms   "
              f"{real / med:8.0f}x faster than performing it")  # fmt: skip

    world = World()
    a = Boxer(world, lib, z=-0.45, yaw=0.0)
    b = Boxer(world, lib, z=0.45, yaw=math.pi)
    moves = ["straight_l", "hook_r", "block", "uppercut_r", "step_forward", "step_back"]
    parts = {"boxers": [], "physics": [], "hits": []}
    clock = time.perf_counter
    i = 0
    for _ in range(args.repeats):
        acc = dict.fromkeys(parts, 0.0)
        for _ in range(args.steps):
            i += 1
            if i % 25 == 0:  # both throw or move every 25 steps: contacts, switches, blends
                a.controller.play(moves[(i // 25) % len(moves)])
                b.controller.play(moves[(i // 25 + 3) % len(moves)])
            t0 = clock()
            a.step(DT)
            b.step(DT)
            t1 = clock()
            contacts = world.step(DT)
            t2 = clock()
            hits_from_contacts(contacts, [a, b])
            t3 = clock()
            acc["boxers"] += t1 - t0
            acc["physics"] += t2 - t1
            acc["hits"] += t3 - t2
        for k in parts:
            parts[k].append(acc[k] / args.steps)
    med = {k: statistics.median(v) for k, v in parts.items()}
    total = sum(med.values())
    print("one 60 Hz game step, two 17-particle boxers sparring at 0.9 m (medians of the runs):")
    labels = {"boxers": "two Boxer.step (controller, root, PD targets)",
              "physics": "World.step (the physics helper's engine: peer)",
              "hits": "hits_from_contacts"}  # fmt: skip
    for k, label in labels.items():
        print(f"  {label:48s} {med[k] * 1e6:8.1f} us  min {min(parts[k]) * 1e6:8.1f} us")
    print(f"  {'whole step':48s} {total * 1e6:8.1f} us  = {total / DT * 100:.2f} % of the 16.7 ms frame")
    print(f"  motion layer / physics: {(med['boxers'] + med['hits']) / med['physics']:.2f}")
    return 0
