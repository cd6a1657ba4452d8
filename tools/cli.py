"""The `quickjab` command. Each subcommand lives in its own module, which exposes
`register(subparsers)`; this module only collects them; game/command.py runs the one asked for
and turns input errors into one line on stderr and exit code 2.

Start-up (issue 14): a command imports only its own module. COMMANDS names every command with
its module and one-line help, so `quickjab --help` lists them without importing any, and
`quickjab play ...` imports game.play alone (not the recorder, the plots or the benchmarks)."""

from __future__ import annotations

import argparse
import importlib
import sys

from engine import __version__
from engine.arguments import OneLineErrorParser

# command -> (module whose register() adds it, the one line `--help` shows), in `--help` order.
# A module may add several commands (tools.recognition_commands: templates, recognize, evaluate).
COMMANDS: dict[str, tuple[str, str]] = {
    "play": ("game.play", "box: a match against the CPU, or two players with --players 2 (Wiimote, serial IMUs or the keyboard)"),
    "train": ("game.training", "Train your moves: record 5 trials of each action, build your templates from the usable ones"),
    "record": ("tools.record", "record a source to a CSV file"),
    "devices": ("tools.devices", "list Wiimotes and serial ports"),
    "scope": ("tools.scope", "show a source's acceleration live (sensor oscilloscope)"),
    "profile": ("tools.profile", "summarize a frame-budget Chrome trace (table, --plot, --json)"),
    "bench": ("tools.bench", "run a benchmark and print figures"),
    "synth": ("tools.synth", "synthesize trials or a labelled session from the virtual player"),
    "soak": ("tools.soak", "an hour of simulated play headless: memory, events, no exception"),
    "bvh": ("tools.bvh_cmd", "import, cut and export BVH motion capture"),
    "actions": ("tools.actions_cmd", "list, draw or re-author the action library"),
    "graph": ("tools.graph", "build, inspect and evaluate the Interaction Graph"),
    "bridge": ("tools.bridge", "serial IMU bridge: device emulator and fault figures"),
    "templates": ("tools.recognition_commands", "build recognition templates from trials"),
    "recognize": ("tools.recognition_commands", "replay a recording through the recognizer; events as JSON lines"),
    "evaluate": ("tools.recognition_commands", "outcome groups per main-buffer size (Figs. 8-9)"),
}  # fmt: skip

# Modules that add subcommands, in the order `--help` lists them.
COMMAND_MODULES = list(dict.fromkeys(module for module, _ in COMMANDS.values()))


def _base_parser() -> tuple[argparse.ArgumentParser, argparse._SubParsersAction]:
    parser = OneLineErrorParser(
        prog="quickjab",
        description="QuickJab: motion-controlled boxing with a Wiimote + Nunchuk or serial IMUs.",
    )
    parser.add_argument("--version", action="version", version=f"quickjab {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    return parser, sub


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The whole parser (every command module imported), or, given a command of COMMANDS, a
    parser with only the commands of that command's module."""
    parser, sub = _base_parser()
    modules = COMMAND_MODULES if command is None else [COMMANDS[command][0]]
    for name in modules:
        importlib.import_module(name).register(sub)
    return parser


def listing_parser() -> argparse.ArgumentParser:
    """Every command from COMMANDS with its help line, none imported: for `--help`, no command
    and a mistyped one (argparse lists the choices)."""
    parser, sub = _base_parser()
    for name, (_, help_line) in COMMANDS.items():
        sub.add_parser(name, help=help_line)
    return parser


def command_word(argv: list[str]) -> str | None:
    """The command named in argv: the first word that is not an option (the top level has
    only flags without values), if it is one of COMMANDS."""
    for word in argv:
        if not word.startswith("-"):
            return word if word in COMMANDS else None
    return None


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    command = command_word(argv)
    parser = build_parser(command) if command is not None else listing_parser()
    args = parser.parse_args(argv)  # `--help`, `--version` and a bad argument exit here
    # imported after parsing: `import game` registers keyboard:// (engine.sensors.source), which
    # `quickjab --help` does not need
    from game.command import run_command

    return run_command(parser, args)


if __name__ == "__main__":
    sys.exit(main())
