"""`quickjab actions`: the action library.

  quickjab actions list                          every action, kind, duration, windows
  quickjab actions sheet [-o actions.png]        a contact sheet of key frames (pygame)
  quickjab actions author [-o DIR]               rewrite the shipped JSON from tools/author_actions.py
"""

from __future__ import annotations

import argparse
import os
import sys

from engine import arguments
from game.actions import load_library


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("actions", help="list, draw or re-author the action library", description=__doc__,
                       formatter_class=argparse.RawDescriptionHelpFormatter)  # fmt: skip
    cmds = p.add_subparsers(dest="actions_command", metavar="SUBCOMMAND", required=True)
    ls = cmds.add_parser("list", help="every action with its kind, duration and windows",
                         description="Every action with its kind, duration, attack windows, reach and damage.")
    ls.add_argument("--dir", default=None, type=arguments.path_argument, help="action folder (default: the shipped library)")
    ls.set_defaults(func=run_list)
    sheet = cmds.add_parser("sheet", help="draw a contact sheet PNG of every action's key frames",
                            description="Draw a contact sheet PNG of every action's key frames (pygame).")
    # in the current folder, as templates build's templates.npz: docs/img/actions.png made a
    # docs/img/ wherever it ran; the repository's figure is `-o docs/img/actions.png` (docs/motion.md)
    sheet.add_argument("-o", "--output", default="actions.png", type=arguments.image_file,
                       help="PNG to write (default actions.png in the current folder)")
    sheet.add_argument("--dir", default=None, type=arguments.path_argument, help="action folder (default: the shipped library)")
    sheet.add_argument("--add", action="append", default=[], metavar="JSON_OR_DIR", type=arguments.path_argument,
                       help="also draw these actions (e.g. cut with `quickjab bvh cut`; a file or a folder of *.json; repeatable)")
    sheet.set_defaults(func=run_sheet)
    author = cmds.add_parser("author", help="regenerate the action JSON files",
                             description="Regenerate the action JSON files from tools/author_actions.py.")
    author.add_argument("-o", "--output", default=None, type=arguments.path_argument,
                        help="folder (default: game/assets/actions, rewritten); there, files that differ from what would be written are left and named")
    author.set_defaults(func=run_author)


def run_list(args: argparse.Namespace) -> int:
    lib = load_library(args.dir)
    for name, a in sorted(lib.items(), key=lambda kv: (kv[1].kind, kv[0])):
        windows = [f"{w.hand}:{w.start}-{w.end} reach {w.reach:.2f} m dmg {w.damage:g}" for w in a.attacks]
        windows += [f"{g.kind} {'+'.join(g.covers)}:{g.start}-{g.end}" for g in a.guards]
        end = a.root_offset(a.frames - 1)
        move = f" root ({end[0]:+.2f}, {end[1]:+.2f})" if abs(end[:2]).max() > 1e-6 else ""
        print(f"{name:22s} {a.kind:8s} {a.frames:4d} f {a.frames / 60:5.2f} s{move} {'; '.join(windows)}")
    return 0


def run_sheet(args: argparse.Namespace) -> int:
    os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
    from pathlib import Path

    from game.actions import ActionError, load_action
    from tools.contact_sheet import write_sheet

    lib = load_library(args.dir)
    for item in args.add:
        files = sorted(Path(item).glob("*.json")) if Path(item).is_dir() else [Path(item)]
        if not files:
            raise ActionError(f"{item}: no action files (*.json)")
        for f in files:
            a = load_action(f)
            lib[a.name] = a  # a cut action of a library name is drawn instead of the library's
    path = write_sheet(lib, args.output)
    print(f"wrote {path}")
    return 0


def run_author(args: argparse.Namespace) -> int:
    """The shipped library (no -o) is rewritten: it is this script's output, kept in git. In a
    folder of -o, a file that differs from what would be written is someone's edit: left as it is
    and named, not replaced (moving it aside in the folder would give the library two files of
    one action, which load_library refuses)."""
    from pathlib import Path

    from tools.author_actions import write_library

    kept: list[Path] | None = None if args.output is None else []
    written = write_library(args.output, kept)
    folder = Path(args.output) if args.output is not None else (written[0].parent if written else None)
    if kept:
        print(f"quickjab actions author: left {len(kept)} file(s) in {folder} that differ from what would be written: "
              f"{', '.join(p.name for p in kept)} (remove them to write them again)", file=sys.stderr)
    print(f"wrote {len(written)} action files to {folder}")
    return 0
