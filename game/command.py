"""Running a parsed command the way every QuickJab command line does: input the user can fix
(an InputError, or an OSError naming a file that cannot be read or written) is one line on
stderr and exit code 2, never a traceback; Ctrl-C is exit 130; no command shows the help.
`quickjab` (tools/cli.py) and `python -m game` (game/__main__.py) both run their commands
through it; it lives in game because game never imports tools."""

from __future__ import annotations

import argparse
import os
import sys

from engine.errors import InputError


def one_line(text: str) -> str:
    """`text` with each character that is not printable (a line break in a file name: the
    message would be two lines) written as its escape, as repr() writes it."""
    return "".join(c if c.isprintable() else repr(c)[1:-1] for c in text)


def run_command(parser: argparse.ArgumentParser, args: argparse.Namespace) -> int:
    """Run the command `parser` parsed into `args` (its `func`); the exit code."""
    if not getattr(args, "func", None):
        parser.print_help()
        return 0
    try:
        return int(args.func(args) or 0)
    except BrokenPipeError:
        # the reader of our output went away (`quickjab recognize ... | head`): quiet, as a command
        # ended by SIGPIPE is; stdout to /dev/null, or the interpreter's last flush fails again
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 141  # 128 + SIGPIPE, what a shell reports for it
    except (InputError, OSError) as exc:  # OSError: str names the file
        print(f"quickjab {args.command}: {one_line(str(exc))}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        return 130
