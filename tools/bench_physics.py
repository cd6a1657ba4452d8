"""Cost of one physics step for two 17-particle boxers, against a pure-Python per-stick peer.

Figures (all measured in this run, µs per step unless said):
- engine.physics World.step, two bodies at sparring distance (no contact), and in a clinch
  (capsule contacts every step), default solver (Jacobi) and graph-coloured Gauss-Seidel;
- the peer: the same system stepped in pure Python (Jakobsen's loop: Verlet + the same
  implicit PD pull per particle, then each stick relaxed in turn, ground), no collision;
- one relaxation iteration alone (numpy Jacobi, numpy coloured Gauss-Seidel, pure Python), and
  how far each solver gets in a fixed time: the reason Jacobi is the default.
The two bodies are the game's boxer bodies (game.body) in the guard posture of the action
library.
"""

from __future__ import annotations

import argparse
import json
import math
import time
from typing import TYPE_CHECKING

import numpy as np

from engine import arguments
from engine.clock import STEP_DT
from engine.errors import InputError

if TYPE_CHECKING:
    from engine.physics import World

DT = STEP_DT


# A run costs about steps x repeats x (iterations + 8) x 45 us of CPU here (a step's work outside the
# relaxation is some 8 iterations'): --iterations 100000000 ran for hours. The bounds keep the
# largest run near 45 s on a desktop core, a few minutes on a Raspberry Pi-class board.
MAX_STEPS = 100_000
MAX_REPEATS = 100
MAX_ITERATIONS = 100  # the game steps with 4 (2 in low power); the scramble study goes to 40
STEP_IN_ITERATIONS = 8
MAX_WORK = 1_000_000


def check_work(steps: int, repeats: int, iterations: int) -> None:
    """InputError, before the run, for a run over MAX_WORK (each bound alone allows one)."""
    work = steps * repeats * (iterations + STEP_IN_ITERATIONS)
    if work > MAX_WORK:
        raise InputError(f"--steps {steps} x --repeats {repeats} x (--iterations {iterations} + {STEP_IN_ITERATIONS}) "
                         f"is {work:,}, over {MAX_WORK:,} (about 45 s of CPU on a desktop core): give fewer")


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--steps", type=arguments.int_range(1, MAX_STEPS), default=500, help=f"steps per timed run (default 500; at most {MAX_STEPS})")
    p.add_argument("--repeats", type=arguments.int_range(1, MAX_REPEATS), default=5,
                   help=f"timed runs per configuration, taken in turn (default 5; at most {MAX_REPEATS})")
    p.add_argument("--iterations", type=arguments.int_range(1, MAX_ITERATIONS), default=4,
                   help=f"relaxation iterations per step (default 4; at most {MAX_ITERATIONS}); "
                   f"steps x repeats x (iterations + {STEP_IN_ITERATIONS}) at most {MAX_WORK:,}")
    p.add_argument("--json", action="store_true", help="print JSON instead of a table")


def _world(gap: float, iterations: int, solver: str = "jacobi") -> tuple[World, list]:
    """Two humanoids facing each other, roots `gap` metres apart, pulled to their guard."""
    from engine.physics import World
    from game.actions import load_library
    from game.body import add_boxer_body
    from game.skeleton import local_to_world

    guard = load_library()["guard"].posture(0)
    w = World(iterations=iterations, solver=solver)
    roots = [(0.0, -gap / 2, 0.0), (0.02, gap / 2, math.pi)]
    targets = []
    for root in roots:
        posture = local_to_world(guard, root)
        targets.append((add_boxer_body(w, posture), posture))
    return w, targets


def _time_worlds(configs: dict, steps: int, repeats: int) -> dict:
    """For each named (world, targets): µs per step (set_targets for both bodies + step), the
    minimum and the median over `repeats` runs taken in turn (so load from other processes
    hits every configuration alike; the minimum is the least disturbed), and contacts/step."""
    def one(w: World, targets: list) -> int:
        for bid, t in targets:
            w.set_targets(bid, t, 6.0)
        return len(w.step(DT))
    for w, targets in configs.values():
        for _ in range(120):  # settle (and, in the clinch, press together)
            one(w, targets)
    runs = {name: [] for name in configs}
    contacts = dict.fromkeys(configs, 0)
    for _ in range(repeats):
        for name, (w, targets) in configs.items():
            t0 = time.process_time_ns()
            for _ in range(steps):
                contacts[name] += one(w, targets)
            runs[name].append((time.process_time_ns() - t0) / steps / 1000)
    return {name: {"min": float(np.min(r)), "median": float(np.median(r)),
                   "contacts_per_step": contacts[name] / (steps * repeats)} for name, r in runs.items()}


class PurePythonWorld:
    """The peer: the same particles, sticks, limits and PD pull stepped with Python floats and
    a per-stick loop (no numpy, no collision)."""

    def __init__(self, w: World) -> None:
        self.x = w.x.tolist()
        self.xp = w.x_prev.tolist()
        self.t = w.targets.tolist()
        self.w2 = w._w2.tolist()
        self.c = w._c.tolist()
        self.g = w.gravity.tolist()
        self.damping = w.damping
        self.ground = w.ground_y
        inv = w.inv_mass
        self.sticks = []
        for (i, j), lo, hi in zip(w.constraints.pairs.tolist(), w.constraints.lo.tolist(), w.constraints.hi.tolist(), strict=True):
            s = inv[i] + inv[j]
            self.sticks.append((i, j, lo, hi, inv[i] / s, inv[j] / s))

    def step(self, dt: float, iterations: int) -> None:
        keep = 1.0 - self.damping
        gx, gy, gz = self.g
        for p, (xi, pi, ti) in enumerate(zip(self.x, self.xp, self.t, strict=True)):
            cdt, w2dt = self.c[p] * dt, self.w2[p] * dt
            den = 1.0 + cdt + w2dt * dt
            vx = (xi[0] - pi[0]) / dt * keep + gx * dt
            vy = (xi[1] - pi[1]) / dt * keep + gy * dt
            vz = (xi[2] - pi[2]) / dt * keep + gz * dt
            vx += (w2dt * (ti[0] - xi[0]) - (cdt + w2dt * dt) * vx) / den
            vy += (w2dt * (ti[1] - xi[1]) - (cdt + w2dt * dt) * vy) / den
            vz += (w2dt * (ti[2] - xi[2]) - (cdt + w2dt * dt) * vz) / den
            pi[0], pi[1], pi[2] = xi[0], xi[1], xi[2]
            xi[0] += vx * dt
            xi[1] += vy * dt
            xi[2] += vz * dt
        for _ in range(iterations):
            self.relax()
            for xi in self.x:
                if xi[1] < self.ground:
                    xi[1] = self.ground

    def relax(self) -> None:
        x = self.x
        for i, j, lo, hi, ki, kj in self.sticks:
            a, b = x[i], x[j]
            dx, dy, dz = b[0] - a[0], b[1] - a[1], b[2] - a[2]
            length = math.sqrt(dx * dx + dy * dy + dz * dz)
            target = lo if length < lo else hi if length > hi else length
            if length > 1e-12 and target != length:
                f = (length - target) / length
                a[0] += ki * f * dx
                a[1] += ki * f * dy
                a[2] += ki * f * dz
                b[0] -= kj * f * dx
                b[1] -= kj * f * dy
                b[2] -= kj * f * dz


def _time_python(w: World, steps: int, repeats: int, iterations: int) -> dict:
    peer = PurePythonWorld(w)
    runs = []
    for _ in range(repeats):
        t0 = time.process_time_ns()
        for _ in range(steps):
            peer.step(DT, iterations)
        runs.append((time.process_time_ns() - t0) / steps / 1000)
    return {"min": float(np.min(runs)), "median": float(np.median(runs))}


def _relaxation(steps: int) -> dict:
    """One relaxation iteration alone, per solver, on two scrambled humanoids; and the largest
    stick error each reaches within the time of 4 Jacobi iterations."""
    out = {}
    rng = np.random.default_rng(0)
    w0, _ = _world(1.2, 4)
    x0 = w0.x + rng.normal(0.0, 0.03, w0.x.shape)
    for solver in ("jacobi", "gauss_seidel"):
        w, _ = _world(1.2, 4, solver)
        c = w.constraints
        x = x0.copy()
        t0 = time.process_time_ns()
        for _ in range(steps):
            c.relax(x)
        us = (time.process_time_ns() - t0) / steps / 1000
        errs = []
        x = x0.copy()
        for _ in range(40):
            c.relax(x)
            errs.append(float(c.errors(x).max()))
        out[solver] = {"us_per_iteration": us, "max_error_mm_after": {k: 1000 * errs[k - 1] for k in (1, 2, 4, 8, 16, 40)}}
    peer = PurePythonWorld(w0)
    peer.x = x0.tolist()
    t0 = time.process_time_ns()
    for _ in range(max(steps // 4, 1)):
        peer.relax()
    out["pure_python"] = {"us_per_iteration": (time.process_time_ns() - t0) / max(steps // 4, 1) / 1000}
    budget = 4 * out["jacobi"]["us_per_iteration"]
    for solver in ("jacobi", "gauss_seidel"):
        n = max(1, int(budget / out[solver]["us_per_iteration"]))
        x = x0.copy()
        c = _world(1.2, 4, solver)[0].constraints
        for _ in range(n):
            c.relax(x)
        out[solver]["iterations_in_4_jacobi_times"] = n
        out[solver]["max_error_mm_in_4_jacobi_times"] = 1000 * float(c.errors(x).max())
    return out


def run(args: argparse.Namespace) -> int:
    check_work(args.steps, args.repeats, args.iterations)
    it = args.iterations
    configs = {
        "apart": _world(1.2, it), "clinch": _world(0.45, it),
        "apart_gauss_seidel": _world(1.2, it, "gauss_seidel"), "clinch_gauss_seidel": _world(0.45, it, "gauss_seidel"),
    }
    steps = _time_worlds(configs, args.steps, args.repeats)
    w = configs["apart"][0]
    peer = _time_python(_world(1.2, it)[0], max(args.steps // 4, 50), args.repeats, it)
    relax = _relaxation(args.steps)
    fig = {
        "particles": int(len(w.x)), "constraints": len(w.constraints), "capsule_pairs": len(w.pairs),
        "iterations": it, "timer": "process CPU time, us per step (min and median over repeats)",
        "step_us": steps,
        "peer_pure_python_step_us": peer,
        "speedup_vs_pure_python_apart": peer["min"] / steps["apart"]["min"],
        "relaxation": relax,
    }
    if args.json:
        print(json.dumps(fig, indent=2))
        return 0
    st = steps
    print(f"two bodies: {fig['particles']} particles, {fig['constraints']} sticks+limits, "
          f"{fig['capsule_pairs']} capsule pairs, {it} iterations, dt 1/60 s; "
          f"CPU us per step, min (median) of {args.repeats} runs")
    print(f"World.step, sparring distance (no contact):  {st['apart']['min']:7.1f} ({st['apart']['median']:.1f}) us"
          "   target < 300 us")
    print(f"World.step, clinch ({st['clinch']['contacts_per_step']:.1f} contacts/step):      "
          f"{st['clinch']['min']:7.1f} ({st['clinch']['median']:.1f}) us")
    print(f"  the same with coloured Gauss-Seidel:        {st['apart_gauss_seidel']['min']:7.1f} us apart, "
          f"{st['clinch_gauss_seidel']['min']:.1f} us clinch")
    print(f"peer: pure-Python per-stick step, no collision: {peer['min']:6.1f} ({peer['median']:.1f}) us"
          f"   -> numpy {peer['min'] / st['apart']['min']:.1f}x faster apart, "
          f"{peer['min'] / st['clinch']['min']:.1f}x in the clinch (which the peer does not even collide)")
    r = relax
    print("one relaxation iteration: "
          f"numpy Jacobi {r['jacobi']['us_per_iteration']:.1f} us, numpy coloured Gauss-Seidel "
          f"{r['gauss_seidel']['us_per_iteration']:.1f} us, pure Python {r['pure_python']['us_per_iteration']:.1f} us")
    for s in ("jacobi", "gauss_seidel"):
        e = r[s]["max_error_mm_after"]
        print(f"  {s:12s} max stick error (mm) after 1/2/4/8/16/40 iterations from a 3 cm scramble: "
              + " / ".join(f"{e[k]:.1f}" for k in (1, 2, 4, 8, 16, 40)))
    print(f"  in the time of 4 Jacobi iterations: Jacobi {r['jacobi']['max_error_mm_in_4_jacobi_times']:.1f} mm, "
          f"Gauss-Seidel ({r['gauss_seidel']['iterations_in_4_jacobi_times']} iteration(s)) "
          f"{r['gauss_seidel']['max_error_mm_in_4_jacobi_times']:.1f} mm")
    return 0
