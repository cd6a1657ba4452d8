"""The boxing game: actions and motion graph, controllers, the Interaction Graph at run time,
match rules, rendering (the `quickjab` command is tools/cli.py)."""

# The game's own source scheme, keyboard://, is registered when the package loads (it needs the
# action library and the virtual player, so it lives here rather than in engine.sensors). Its
# module (numpy, the virtual player) is imported when a keyboard:// URL is first opened, so
# `import game` (every `quickjab` command) stays light.
from engine.sensors.source import register_scheme as _register_scheme


def _open_keyboard(url, clock):
    from game.keyboard_source import open_keyboard

    return open_keyboard(url, clock)


_register_scheme("keyboard", _open_keyboard)
