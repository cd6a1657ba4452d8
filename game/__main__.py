"""`python -m game play|train ...`: the game's own two commands, as `quickjab play` and
`quickjab train`. The whole `quickjab` command lives in tools/cli.py (`python -m tools.cli`):
game never imports tools, so it cannot offer the tools' commands here."""

import argparse
import sys

from engine.errors import InputError
from game import play, training


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m game", description="QuickJab's game: play or train (every other command: quickjab)."
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    play.register(sub)
    training.register(sub)
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help()
        return 0
    try:
        return int(args.func(args) or 0)
    except (InputError, OSError) as exc:  # one line, exit 2, as quickjab does
        print(f"quickjab {args.command}: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        return 130


if __name__ == "__main__":
    sys.exit(main())
