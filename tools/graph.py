"""`quickjab graph`: build, inspect and evaluate the CPU opponent's Interaction Graph."""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

from engine import arguments
from engine.errors import InputError


def load_actions() -> dict:
    """The game's action library (the motion helper's game.actions)."""
    try:
        from game.actions import load_library
    except ImportError as exc:   # pragma: no cover - only before the motion work is merged
        raise InputError(f"the action library (game.actions) is not available: {exc}") from None
    return load_library()


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("graph", help="build, inspect and evaluate the Interaction Graph",
                       description=__doc__)
    cmds = p.add_subparsers(dest="graph_command", metavar="SUBCOMMAND", required=True)

    b = cmds.add_parser("build", help="sample, solve and save a graph",
                        description="Sample bouts in the bout model, merge states, expand every "
                        "action from every state, solve by value iteration, save the .npz.")
    # checked before the build (about a minute), not when the table is saved after it
    b.add_argument("-o", "--output", required=True, type=arguments.output_file, help="where to write the .npz")
    b.add_argument("--seed", type=arguments.seed, default=0, help="random seed (the build is deterministic for it)")
    b.add_argument("--states", type=arguments.int_range(10, 1_000_000), default=60000, help="states to keep (most visited cells)")
    b.add_argument("--bouts", type=arguments.int_range(1, 65_536), default=None, help="sampling bouts run at once")
    b.add_argument("--opponent-max", type=arguments.float_range(0.0, 1.0), default=None,
                   help="1 = min-max (opponent's best response), 0 = its expectation; blends between (default 0.5)")
    b.add_argument("--quiet", action="store_true", help="no progress lines")
    b.set_defaults(func=cmd_build)

    i = cmds.add_parser("info", help="states, edges, build parameters and file size",
                        description="Print what a graph file holds.")
    i.add_argument("graph", nargs="?", default=None, type=arguments.path_argument, help="the .npz (default: the shipped graph)")
    # as `graph duel --graph` and `bench graph --graph` take it; the positional keeps working
    i.add_argument("--graph", dest="graph_option", default=None, type=arguments.path_argument, metavar="GRAPH", help="the .npz, as the positional argument (as graph duel takes it)")
    i.add_argument("--json", action="store_true", help="machine-readable output")
    i.set_defaults(func=cmd_info)

    d = cmds.add_parser("duel", help="headless bouts: the graph against random / greedy, or matches per difficulty against the virtual players",
                        description="Run headless bouts of the graph opponent against a random "
                        "and/or a greedy one in the bout model; print wins, hits landed and received. "
                        "With --opponent virtual (or experienced / novice): whole matches of the game per "
                        "--difficulty against the virtual player through the real recognizer; print the "
                        "player's round win rate and rounds per match (tools/virtual_duel.py).")
    d.add_argument("--graph", default=None, type=arguments.path_argument, help="the .npz (default: the shipped graph)")
    d.add_argument("--bouts", type=arguments.int_range(1, 1_000_000), default=200, help="bouts per opponent")
    d.add_argument("--opponent", choices=["random", "greedy", "both", "virtual", "experienced", "novice"], default="both",
                   help="bout-model policies (random, greedy, both), or the virtual player in the game (virtual: experienced and novice)")
    d.add_argument("--difficulty", default="easy,normal,hard",
                   help="with a virtual opponent: comma-separated difficulties (easy, normal, hard, adaptive; default easy,normal,hard)")
    d.add_argument("--matches", type=arguments.int_range(1, 1000), default=3, help="with a virtual opponent: matches per difficulty and player (default 3)")
    d.add_argument("--jobs", type=arguments.int_range(1, 64), default=2, help="with a virtual opponent: processes (default 2)")
    d.add_argument("--player", choices=["graph", "random", "greedy"], default="graph",
                   help="who plays boxer 0 (a baseline other than the graph, for comparison)")
    d.add_argument("--seconds", type=arguments.float_range(0.0, 3600.0, lo_open=True), default=60.0, help="bout length (ends earlier by knockout)")
    d.add_argument("--seed", type=arguments.seed, default=1, help="seed of the bouts (default 1)")
    d.add_argument("--json", action="store_true", help="machine-readable output")
    d.set_defaults(func=cmd_duel)


def _graph_path(path: str | None) -> Path:
    from game.interaction import DEFAULT_GRAPH
    return Path(path) if path else DEFAULT_GRAPH


def cmd_build(args: argparse.Namespace) -> int:
    from engine.errors import refuse_other_kind
    from engine.npz_files import is_npz_head
    from game.interaction.build import BuildParams, build_graph
    refuse_other_kind(args.output, "-o", "an .npz", is_npz_head)  # an earlier graph is replaced
    if args.states < 10:
        raise InputError(f"--states {args.states}: need at least 10")
    kw = {"seed": args.seed, "states": args.states}
    if args.bouts:
        kw["bouts"] = args.bouts
    if args.opponent_max is not None:
        kw["opponent_max"] = args.opponent_max
    lib = load_actions()
    t0 = time.perf_counter()
    table = build_graph(lib, BuildParams(**kw), log=None if args.quiet else print)
    try:
        table.save(args.output)
    except OSError as exc:
        raise InputError(f"{args.output}: cannot write the graph ({exc.strerror or exc})") from None
    size = Path(args.output).stat().st_size
    print(f"wrote {args.output}: {table.n_states} states, {table.n_edges} edges, "
          f"{size / 1e6:.2f} MB, built in {time.perf_counter() - t0:.1f} s")
    return 0


def _info_graph(args: argparse.Namespace) -> str | None:
    """graph info's file: the positional or --graph; both naming different files is refused."""
    given, option = args.graph, args.graph_option
    if given is not None and option is not None and Path(given).absolute() != Path(option).absolute():
        raise InputError(f"info: {given} and --graph {option}: give the graph once")
    return given if given is not None else option


def cmd_info(args: argparse.Namespace) -> int:
    from game.interaction import InteractionGraph
    path = _graph_path(_info_graph(args))
    g = InteractionGraph.load(path)
    info = g.info()
    if args.json:
        print(json.dumps(info, indent=2, sort_keys=True))
        return 0
    print(f"{path}: {info['states']} states, {info['edges']} edges, "
          f"{info.get('file_bytes', 0) / 1e6:.2f} MB")
    for line in _build_lines(info["build"]):
        print(f"  {line}")
    print(f"  grid: {json.dumps(info['grid'])}")
    print(f"  rules: {json.dumps(info['rules'])}")
    print(f"  rewards: {json.dumps(info['rewards'])}")
    return 0


NOT_RECORDED = "not recorded"


def _recorded(build: dict, key: str, form: str = "{}") -> str:
    """`form` of the build's `key`, or "not recorded": the loader takes `build` as optional and
    reads none of its fields, so a field may be missing or of any type (its plain text then), on
    one line."""
    from game.command import one_line

    value = build.get(key)
    if value is None:
        return NOT_RECORDED
    try:
        return one_line(form.format(value))
    except (TypeError, ValueError):
        return one_line(str(value))


def _build_lines(build: dict) -> list[str]:
    """graph info's lines on how the graph was built. A missing or odd field was a traceback
    (formatting None, .get on a string)."""
    seconds = build.get("seconds")
    total = {"total": seconds.get("total") if isinstance(seconds, dict) else seconds}
    return [f"build: library {_recorded(build, 'library')}, seed {_recorded(build, 'seed')}, "
            f"{_recorded(build, 'samples')} samples in {_recorded(build, 'cells_sampled')} cells, "
            f"opponent_max {_recorded(build, 'opponent_max')}, time {_recorded(total, 'total', '{} s')}",
            f"value iteration: {_recorded(build, 'vi_iterations')} iterations, "
            f"residual {_recorded(build, 'vi_residual', '{:.2g}')}"]


def cmd_virtual_duel(args: argparse.Namespace) -> int:
    from concurrent.futures.process import BrokenProcessPool

    from engine.interrupt import stop_signals_as_ctrl_c
    from game.difficulty import CHOICES
    from tools.virtual_duel import PROFILES, virtual_duel

    difficulties = [d.strip() for d in args.difficulty.split(",") if d.strip()]
    bad = [d for d in difficulties if d not in CHOICES]
    if not difficulties or bad:
        raise InputError(f"--difficulty {args.difficulty!r}: choose from {', '.join(CHOICES)}")
    if args.matches < 1 or args.jobs < 1:
        raise InputError("--matches and --jobs must be at least 1")
    profiles = list(PROFILES) if args.opponent == "virtual" else [args.opponent]
    graph = str(_graph_path(args.graph)) if args.graph else None
    t0 = time.perf_counter()
    # `kill` and a closed terminal end the matches as Ctrl-C does: the workers ended, exit 130
    with stop_signals_as_ctrl_c():
        try:
            summaries = virtual_duel(difficulties, profiles, args.matches, seed=args.seed, jobs=args.jobs, graph=graph)
        except BrokenProcessPool:
            raise InputError("duel: a match's worker process ended before its match did (killed?)") from None
    results = [s.as_dict() for s in summaries]
    if args.json:
        print(json.dumps(results, indent=2))
        return 0
    for d in results:
        print(f"{d['difficulty']:8s} vs {d['player']:11s}: player won {d['rounds_won']}/{d['rounds']} rounds "
              f"({100 * d['round_win_rate']:.0f} %), lost {d['rounds_lost']}; {d['rounds_per_match']:.2f} rounds per match; "
              f"matches won {d['matches_won']}/{d['matches']} ({', '.join(f'{k} {v}' for k, v in d['results'].items())})")
    print(f"({len(results) * args.matches} matches in {time.perf_counter() - t0:.0f} s)")
    return 0


def cmd_duel(args: argparse.Namespace) -> int:
    from game.interaction import InteractionGraph
    from game.interaction.duel import duel
    if args.opponent in ("virtual", "experienced", "novice"):
        return cmd_virtual_duel(args)
    if args.bouts < 1:
        raise InputError(f"--bouts {args.bouts}: need at least 1")
    g = InteractionGraph.load(_graph_path(args.graph))
    lib = load_actions()
    opponents = ["random", "greedy"] if args.opponent == "both" else [args.opponent]
    results = []
    for opp in opponents:
        t0 = time.perf_counter()
        try:
            r = duel(g, lib, opp, bouts=args.bouts, seconds=args.seconds, seed=args.seed,
                     us=args.player)
        except ValueError as exc:
            raise InputError(f"{g.path}: {exc}") from None
        d = r.as_dict()
        d["player"] = args.player
        d["seconds"] = round(time.perf_counter() - t0, 2)
        results.append(d)
    if args.json:
        print(json.dumps(results, indent=2))
        return 0
    for d in results:
        print(f"{d['player']} vs {d['opponent']:6s}: {d['wins']}/{d['bouts']} wins ({100 * d['win_rate']:.1f} %), "
              f"{d['losses']} losses, {d['draws']} draws, {d['knockouts']} KOs; hits landed "
              f"{d['hits_landed']}, received {d['hits_received']}; damage {d['damage_dealt']:.0f} "
              f"dealt, {d['damage_taken']:.0f} taken ({d['seconds']} s)")
    return 0
