"""`python -m game play|train ...`: the game's own two commands, as `quickjab play` and
`quickjab train`. The whole `quickjab` command lives in tools/cli.py (`python -m tools.cli`):
game never imports tools, so it cannot offer the tools' commands here."""

import sys

from engine.arguments import OneLineErrorParser
from game import play, training
from game.command import run_command


def main(argv: list[str] | None = None) -> int:
    parser = OneLineErrorParser(
        prog="python -m game", description="QuickJab's game: play or train (every other command: quickjab)."
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    play.register(sub)
    training.register(sub)
    return run_command(parser, parser.parse_args(argv))  # one line, exit 2, as quickjab does


if __name__ == "__main__":
    sys.exit(main())
