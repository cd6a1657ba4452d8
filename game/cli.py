"""The `quickjab` command. Each subcommand lives in its own module, which exposes
`register(subparsers)`; this module only collects them and turns input errors into one line
on stderr and exit code 2."""

from __future__ import annotations

import argparse
import importlib
import sys

from engine import __version__
from engine.errors import InputError

# Modules that add subcommands, in the order `--help` lists them.
COMMAND_MODULES = [
    "game.play",
    "game.training",
    "tools.record",
    "tools.devices",
    "tools.scope",
    "tools.profile",
    "tools.bench",
    "tools.synth",
    "tools.soak",
    "tools.bvh_cmd",
    "tools.actions_cmd",
    "tools.graph",
    "tools.bridge",
    "tools.recognition_commands",
]


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="quickjab",
        description="QuickJab: motion-controlled boxing with a Wiimote + Nunchuk or serial IMUs.",
    )
    parser.add_argument("--version", action="version", version=f"quickjab {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in COMMAND_MODULES:
        importlib.import_module(name).register(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help()
        return 0
    try:
        return int(args.func(args) or 0)
    except InputError as exc:
        print(f"quickjab {args.command}: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:  # a file the user named cannot be read or written; str names it
        print(f"quickjab {args.command}: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        return 130


if __name__ == "__main__":
    sys.exit(main())
