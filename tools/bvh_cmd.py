"""`quickjab bvh`: motion capture in and out.

  quickjab bvh info FILE.bvh                           joints, frames, what maps onto ours
  quickjab bvh cut FILE.bvh --start S --end E --name NAME -o NAME.json
                                                       retarget and cut an action (60 Hz frames)
  quickjab bvh export --play straight_l,hook_r -o out.bvh
                                                       play actions and write a BVH for Blender
  quickjab bvh export --play straight_l,hook_r --opponent block,straight_r -o bout.bvh
                                                       simulate a bout of two physics boxers and
                                                       write bout_boxer0.bvh and bout_boxer1.bvh
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from engine import arguments
from engine.errors import InputError, refuse_other_kind, refuse_overwriting
from engine.npz_files import write_replacing
from game.actions import KINDS, NAME_MAX_CHARS, load_library, name_problem
from game.bvh import (
    MAX_BOUT_S,
    boxer_paths,
    cut_action,
    is_bvh_head,
    map_joints,
    played_positions,
    read_bvh,
    retarget,
    simulate_bout,
    write_bvh,
)


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("bvh", help="import, cut and export BVH motion capture", description=__doc__,
                       formatter_class=argparse.RawDescriptionHelpFormatter)  # fmt: skip
    cmds = p.add_subparsers(dest="bvh_command", metavar="SUBCOMMAND", required=True)
    info = cmds.add_parser("info", help="what a BVH file holds and how it maps onto our skeleton",
                           description="What a BVH file holds (joints, frames, rate) and which of its joints "
                           "drive each of our skeleton's.")
    info.add_argument("file", metavar="FILE.bvh", type=arguments.path_argument, help="the BVH file")
    info.set_defaults(func=run_info)
    cut = cmds.add_parser("cut", help="retarget a BVH and cut an action from a frame range",
                          description="Retarget a BVH onto our skeleton at 60 Hz and cut frames --start..--end "
                          "into an action JSON (preview it: quickjab actions sheet --add NAME.json).")
    cut.add_argument("file", metavar="FILE.bvh", type=arguments.path_argument, help="the BVH file")
    cut.add_argument("--start", type=arguments.non_negative_int, required=True, help="first frame (60 Hz, after resampling)")
    cut.add_argument("--end", type=arguments.non_negative_int, required=True, help="last frame (inclusive)")
    cut.add_argument("--name", required=True, type=_action_name,
                     help=f"action name: 1 to {NAME_MAX_CHARS} letters, digits, '_' and '-' (as the action loader takes)")
    cut.add_argument("--kind", default="attack", choices=KINDS, help="what the action is in the game (default attack)")
    cut.add_argument("--no-guard-blend", action="store_true", help="do not blend the ends into the guard")
    cut.add_argument("-o", "--output", required=True, type=arguments.path_argument, help="action JSON to write")
    cut.set_defaults(func=run_cut)
    exp = cmds.add_parser("export", help="play actions of the library and write them as BVH",
                          description="Play actions of the library and write them as BVH (Blender opens it); "
                          "with --opponent, simulate a bout of two physics boxers and write one BVH per boxer.")
    exp.add_argument("--play", required=True, help="comma-separated action names, played in order")
    exp.add_argument("--opponent", default=None,
                     help="actions of a second boxer: simulate both in the physics world (a bout)")
    exp.add_argument("--gap", type=arguments.float_range(0.0, 100.0, lo_open=True), default=0.85, help="distance between the boxers in a bout (m)")
    exp.add_argument("-o", "--output", required=True, type=arguments.path_argument, help="BVH file to write")
    exp.set_defaults(func=run_export)


def _action_name(text: str) -> str:
    """An argparse type for `bvh cut --name`: a name the action loader takes (name_problem);
    `--name ""` wrote a file the loader then refused."""
    if why := name_problem(text):
        raise argparse.ArgumentTypeError(f"the action name {why}")
    return text


_action_name.__name__ = "action name"


def run_info(args: argparse.Namespace) -> int:
    bvh = read_bvh(args.file, mappable=True)
    print(f"{args.file}: {len(bvh.joints)} joints, {bvh.frames} frames at {1 / bvh.frame_time:.1f} Hz")
    idx = map_joints(bvh)
    from game.skeleton import JOINTS

    for ours, j in zip(JOINTS, idx, strict=True):
        print(f"  {ours:11s} <- {bvh.joints[j].name}")
    return 0


def run_cut(args: argparse.Namespace) -> int:
    from tools.record import aside_unless_same

    refuse_overwriting({"-o": args.output}, [args.file])
    bvh = read_bvh(args.file, mappable=True)
    motion = retarget(bvh)
    guard = None if args.no_guard_blend else load_library()["guard"].posture(0)
    action = cut_action(motion, args.start, args.end, args.name, args.kind, guard)
    Path(args.output).parent.mkdir(parents=True, exist_ok=True)
    data = (json.dumps(action.to_json(), indent=1) + "\n").encode("utf-8")
    # a file there may be an action someone made: moved aside as `record -o` does, and said
    aside = aside_unless_same(args.output, data, unread=True)  # not one more action of its folder
    if aside is not None:
        print(f"{args.output} was not empty: moved to {aside}", file=sys.stderr)
    try:
        write_replacing(args.output, lambda f: f.write(data))  # whole, or the file it replaces as it was
    except OSError as exc:  # a full disk: ENOSPC names no file
        raise InputError(f"{args.output}: cannot write ({exc.strerror or exc})") from None
    print(f"wrote {args.name} ({action.frames} frames) to {args.output}; "
          f"preview: quickjab actions sheet --add {args.output} -o sheet.png")
    return 0


def _names(text: str, lib: dict) -> list[str]:
    names = [n.strip() for n in text.split(",") if n.strip()]
    bad = [n for n in names if n not in lib]
    if not names or bad:
        raise InputError(f"unknown action(s) {', '.join(bad) or '(none given)'}; see game/assets/actions")
    return names


def run_export(args: argparse.Namespace) -> int:
    lib = load_library()
    names = _names(args.play, lib)
    opponent = None if args.opponent is None else _names(args.opponent, lib)
    for path in boxer_paths(args.output, 1 if opponent is None else 2):  # an earlier BVH is replaced
        refuse_other_kind(path, "-o", "a BVH", is_bvh_head)
    if opponent is not None:
        rec, hits = simulate_bout(lib, names, opponent, args.gap)
        paths = rec.write(args.output, rest=lib["guard"].posture(0))
        if rec.unplayed:
            asked = (len(names), len(opponent))
            begun = " and ".join(f"{a - u} of {a}" for a, u in zip(asked, rec.unplayed, strict=True))
            print(f"quickjab bvh export: the bout is cut at the {MAX_BOUT_S:g} s cap: asked for {asked[0]} and "
                  f"{asked[1]} actions, {begun} began; wrote {len(rec.frames) / rec.fps:.1f} s", file=sys.stderr)
        print(f"simulated {len(rec.frames)} steps, {len(hits)} hit(s); wrote {', '.join(map(str, paths))}")
        return 0
    positions = played_positions(lib, names)
    write_bvh(args.output, positions, rest=lib["guard"].posture(0))
    print(f"wrote {len(positions)} frames to {args.output}")
    return 0
