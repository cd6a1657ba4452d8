"""The boxing game: actions and motion graph, controllers, the Interaction Graph at run time,
match rules, rendering, and the `quickjab` command."""

# The game's own source scheme, keyboard://, is registered when the package loads (it needs the
# action library and the virtual player, so it lives here rather than in engine.sensors).
from game import keyboard_source as _keyboard_source  # noqa: E402,F401
