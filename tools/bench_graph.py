"""Interaction Graph: build time, load time, and look-up cost against a brute-force peer.

The peer scans every state with numpy (same metric, no index) in the same run; both map the
same live situations, and the figures say how often they agree."""

from __future__ import annotations

import argparse
import json
import math
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

from engine import arguments


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--graph", default=None, type=arguments.path_argument,
                   help="time loading/looking up this file instead of building one")
    p.add_argument("--states", type=arguments.int_range(10, 1_000_000), default=60000,
                   help="states of the graph to build (at most 1000000, as graph build)")
    p.add_argument("--seed", type=arguments.seed, default=0, help="seed of the build and the look-ups (default 0)")
    p.add_argument("--lookups", type=arguments.int_range(1, 1_000_000), default=20000, help="situations to look up (at most 1000000)")
    p.add_argument("--loads", type=arguments.int_range(1, 1000), default=5, help="load repetitions (median reported)")
    p.add_argument("--json", action="store_true", help="print JSON instead of a table")


def situations(g, n: int, rng: np.random.Generator) -> list:
    """Live-like situations: sampled states' features with noise, a random other phase."""
    from game.interaction import Situation
    t = g.table
    ids = rng.integers(0, t.n_states, n)
    feat = t.features[ids].astype(float)
    d = np.abs(feat[:, 0] + rng.normal(0, 0.05, n))
    bs = feat[:, 1] + rng.normal(0, math.radians(8), n)
    bo = feat[:, 2] + rng.normal(0, math.radians(8), n)
    out = []
    for i in range(n):
        a = int(t.other_action[ids[i]])
        name = g.names[a]
        phase = float(t.other_frame[ids[i]] + rng.integers(-2, 3))
        out.append(Situation(float(d[i]), float(bs[i]), float(bo[i]), 0.0, "guard", 0.0,
                             name, max(phase, 0.0)))
    return out


def run(args: argparse.Namespace) -> int:
    from game.interaction import InteractionGraph
    fig: dict = {}
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(args.graph) if args.graph else Path(tmp) / "graph.npz"
        if not args.graph:
            from game.interaction.build import BuildParams, build_graph
            from tools.graph import load_actions
            lib = load_actions()
            t0 = time.perf_counter()
            table = build_graph(lib, BuildParams(seed=args.seed, states=args.states))
            fig["build_s"] = round(time.perf_counter() - t0, 2)
            fig["build_phases_s"] = table.build["seconds"]
            table.save(path)
        loads = []
        for _ in range(args.loads):
            t0 = time.perf_counter()
            g = InteractionGraph.load(path)
            loads.append(time.perf_counter() - t0)
        fig["file_mb"] = round(path.stat().st_size / 1e6, 2)
    fig["states"], fig["edges"] = g.n_states, g.n_edges
    fig["load_s_median"] = round(statistics.median(loads), 3)
    rng = np.random.default_rng(args.seed)
    sits = situations(g, args.lookups, rng)
    best = g.best_action
    t0 = time.perf_counter()
    for s in sits:
        best(s)
    fig["lookup_us"] = round((time.perf_counter() - t0) / len(sits) * 1e6, 2)
    # the peer: brute-force nearest state over all states, then the same table read
    n_peer = min(len(sits), 2000)
    idx = g.index
    peer_ids = []
    t0 = time.perf_counter()
    for s in sits[:n_peer]:
        aid, frame = g.other_code(s.other_action, s.other_phase)
        peer_ids.append(idx.brute_force(s.distance, s.bearing_self, s.bearing_other, aid, frame))
    fig["brute_force_us"] = round((time.perf_counter() - t0) / n_peer * 1e6, 2)
    fig["speedup_vs_brute_force"] = round(fig["brute_force_us"] / fig["lookup_us"], 1)
    agree = sum(g.state_of(s) == p for s, p in zip(sits[:n_peer], peer_ids, strict=True))
    fig["agreement_with_brute_force"] = round(agree / n_peer, 4)
    if args.json:
        print(json.dumps(fig, indent=2))
        return 0
    if "build_s" in fig:
        print(f"build            {fig['build_s']:10.2f} s   {fig['build_phases_s']}")
    print(f"graph            {fig['states']:10d} states, {fig['edges']} edges, {fig['file_mb']} MB")
    print(f"load (median)    {fig['load_s_median']:10.3f} s")
    print(f"look-up          {fig['lookup_us']:10.2f} µs   (InteractionGraph.best_action)")
    print(f"brute force peer {fig['brute_force_us']:10.2f} µs   (numpy scan of all states)")
    print(f"speed-up         {fig['speedup_vs_brute_force']:10.1f} x, agreement "
          f"{100 * fig['agreement_with_brute_force']:.1f} %")
    return 0
