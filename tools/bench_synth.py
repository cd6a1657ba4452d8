"""Cost of the motion layer: synthesizing one virtual-player trial, and one game step of two
boxers (two PlayerController steps + root + PD targets + the physics step), with peers
measured in the same run: the trial's own duration (real time), the physics step alone, and
the 16.7 ms frame budget.
"""

from __future__ import annotations

import argparse
import json
import math
import statistics
import time

import numpy as np

from engine import arguments
from engine.clock import STEP_DT

DT = STEP_DT


def add_arguments(p: argparse.ArgumentParser) -> None:
    # 0 was a division by zero, a negative count an empty min(): both tracebacks
    p.add_argument("--trials", type=arguments.int_range(1, 100_000), default=200, help="trials synthesized per timed run")
    p.add_argument("--steps", type=arguments.int_range(1, 1_000_000), default=600, help="game steps per timed run")
    p.add_argument("--repeats", type=arguments.int_range(1, 1000), default=5, help="timed runs per figure (min and median shown)")
    p.add_argument("--action", default="hook_r", help="action to synthesize (default hook_r)")
    p.add_argument("--json", action="store_true", help="print JSON instead of a table")


def _time(fn, n: int, repeats: int) -> tuple[float, float]:
    """(min, median) seconds per call over `repeats` runs of n calls."""
    per = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        for _ in range(n):
            fn()
        per.append((time.perf_counter() - t0) / n)
    return min(per), statistics.median(per)


def _trial_figures(lib, action, trials: int, repeats: int) -> dict[str, dict[str, float]]:
    """Per profile: min and median seconds of one synthesized trial."""
    from game.virtual_player import synthesize_action

    rng = np.random.default_rng(0)
    out = {}
    for profile in ("experienced", "novice"):
        lo, med = _time(lambda p=profile: synthesize_action(action, p, rng, library=lib), trials, repeats)
        out[profile] = {"min": lo, "median": med}
    return out


def _step_figures(lib, steps: int, repeats: int) -> dict[str, list[float]]:
    """Seconds per game step of each part (boxers, physics, hits), one figure per run."""
    from engine.physics import World
    from game.boxer import Boxer, hits_from_contacts

    world = World()
    a = Boxer(world, lib, z=-0.45, yaw=0.0)
    b = Boxer(world, lib, z=0.45, yaw=math.pi)
    moves = ["straight_l", "hook_r", "block", "uppercut_r", "step_forward", "step_back"]
    parts: dict[str, list[float]] = {"boxers": [], "physics": [], "hits": []}
    clock = time.perf_counter
    i = 0
    for _ in range(repeats):
        acc = dict.fromkeys(parts, 0.0)
        for _ in range(steps):
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
            parts[k].append(acc[k] / steps)
    return parts


def _json_figures(args: argparse.Namespace, action, trial: dict, parts: dict[str, list[float]]) -> dict:
    """--json: the table's figures, in the units the table shows them."""
    real = action.frames / 60.0
    med = {k: statistics.median(v) for k, v in parts.items()}
    total = sum(med.values())
    return {
        "action": args.action, "action_frames": action.frames, "trials": args.trials, "steps": args.steps,
        "repeats": args.repeats, "timer": "wall clock (perf_counter), min and median over repeats",
        "trial_ms": {p: {"min": f["min"] * 1e3, "median": f["median"] * 1e3} for p, f in trial.items()},
        "trial_faster_than_performing": {p: real / f["median"] for p, f in trial.items()},
        "step_us": {k: {"min": min(v) * 1e6, "median": med[k] * 1e6} for k, v in parts.items()},
        "whole_step_us": total * 1e6,
        "frame_share_percent": total / DT * 100,
        "motion_over_physics": (med["boxers"] + med["hits"]) / med["physics"],
    }


def run(args: argparse.Namespace) -> int:
    from game.actions import load_library

    lib = load_library()
    if args.action not in lib:
        from engine.errors import InputError

        raise InputError(f"unknown action {args.action!r}")
    action = lib[args.action]
    trial = _trial_figures(lib, action, args.trials, args.repeats)
    parts = _step_figures(lib, args.steps, args.repeats)
    fig = _json_figures(args, action, trial, parts)
    if args.json:  # the one JSON object is all of stdout
        print(json.dumps(fig, indent=2))
        return 0
    print(f"virtual player, one {args.action} trial ({action.frames} frames = {action.frames / 60 * 1e3:.0f} ms of motion):")
    for profile, f in fig["trial_ms"].items():
        print(f"  {profile:12s} min {f['min']:7.3f} ms  median {f['median']:7.3f} ms   "
              f"{fig['trial_faster_than_performing'][profile]:8.0f}x faster than performing it")  # fmt: skip
    print("one 60 Hz game step, two 17-particle boxers sparring at 0.9 m (medians of the runs):")
    labels = {"boxers": "two Boxer.step (controller, root, PD targets)",
              "physics": "World.step (the physics helper's engine: peer)",
              "hits": "hits_from_contacts"}  # fmt: skip
    for k, label in labels.items():
        print(f"  {label:48s} {fig['step_us'][k]['median']:8.1f} us  min {fig['step_us'][k]['min']:8.1f} us")
    print(f"  {'whole step':48s} {fig['whole_step_us']:8.1f} us  = {fig['frame_share_percent']:.2f} % of the 16.7 ms frame")
    print(f"  motion layer / physics: {fig['motion_over_physics']:.2f}")
    return 0
