"""`keyboard://`: the keyboard as a virtual Wiimote + Nunchuk.

A key per action. A key press synthesizes that action's accelerometer signal with the virtual
player (game.virtual_player) and plays it out as samples at 60 Hz on the source's clock, so
the REAL recognizer sees it: early guesses, switches and rejections happen as they would with
a Wiimote. Between motions the source reads hands resting at the guard (gravity and sensor
noise): game.virtual_player.VirtualPlayerStream does the synthesis. A press during a motion
cuts it and starts the new one, as a player changing their mind would.

URL options: `keyboard://?profile=novice&seed=3` (virtual player profile, noise seed),
`keyboard://?auto=1` performs random actions by itself. (`play --demo` drives the source from
the Interaction Graph instead: see game.session.) `keyboard://?keys=left` (or `right`) answers
only that half of the keyboard: two players on one keyboard (`play --players 2`).
"""

from __future__ import annotations

import numpy as np

from engine.clock import STEP_HZ
from engine.sensors.source import (
    KEYS,
    PLAYABLE,
    Clock,
    Sample,
    Source,
    SourceError,
    SourceState,
    parse_source_url,
    url_number,
    url_params_known,
)

HZ = STEP_HZ

# A key per action: left hand on the left of the keyboard, right hand on the right, guard on
# space, footwork on the arrows. Values are pygame key names (pygame.key.key_code).
KEYMAP: dict[str, str] = {
    "q": "straight_l", "w": "hook_l", "e": "uppercut_l", "r": "parry_l",
    "u": "parry_r", "i": "uppercut_r", "o": "hook_r", "p": "straight_r",
    "space": "block",
    "up": "step_forward", "down": "step_back", "left": "step_left", "right": "step_right",
}  # fmt: skip

# Two players on one keyboard: one half each (play --players 2). The left player's hands on the
# top and home rows, footwork on the bottom row; the right player's mirror them, footwork on the
# arrows; each blocks with their shift key.
KEYMAP_LEFT: dict[str, str] = {
    "q": "straight_l", "w": "hook_l", "e": "uppercut_l", "r": "parry_l",
    "a": "straight_r", "s": "hook_r", "d": "uppercut_r", "f": "parry_r",
    "left shift": "block",
    "c": "step_forward", "x": "step_back", "z": "step_left", "v": "step_right",
}  # fmt: skip
KEYMAP_RIGHT: dict[str, str] = {
    "p": "straight_r", "o": "hook_r", "i": "uppercut_r", "u": "parry_r",
    ";": "straight_l", "l": "hook_l", "k": "uppercut_l", "j": "parry_l",
    "right shift": "block",
    "up": "step_forward", "down": "step_back", "left": "step_left", "right": "step_right",
}  # fmt: skip
KEYMAPS = {"all": KEYMAP, "left": KEYMAP_LEFT, "right": KEYMAP_RIGHT}

KEY_LABELS = {"space": "Space", "up": "Up", "down": "Down", "left": "Left", "right": "Right",
              "left shift": "LShift", "right shift": "RShift"}

# The attract mode picks among these (weights: mostly punches, some defence and footwork)
AUTO_ACTIONS = ("straight_l", "straight_r", "hook_l", "hook_r", "uppercut_l", "uppercut_r",
                "block", "parry_l", "parry_r", "step_forward", "step_back", "step_left", "step_right")
AUTO_WEIGHTS = np.array([4, 4, 3, 3, 2, 2, 1, 1, 1, 3, 1, 1, 1], dtype=np.float64)
AUTO_P = AUTO_WEIGHTS / AUTO_WEIGHTS.sum()


def key_help(keymap: dict[str, str] | None = None) -> list[tuple[str, str]]:
    """(key label, action) pairs in the order the HUD shows them."""
    return [(KEY_LABELS.get(k, k.upper()), a) for k, a in (keymap or KEYMAP).items()]


class KeyboardSource(Source):
    """Samples synthesized from key presses. `press(action)` is what a key does."""

    capabilities = frozenset({PLAYABLE, KEYS})

    def __init__(self, url: str, clock: Clock, lib: dict, profile: str = "experienced", seed: int = 0,
                 auto: bool = False, keys: str = "all"):
        super().__init__(url=url, sensors=2, clock=clock, state=SourceState.CONNECTED,
                         rate_hz=float(HZ), description="keyboard (virtual player)")
        from game.virtual_player import VirtualPlayerStream  # the motion helper's module

        self.lib = lib
        self.profile = profile
        self.rng = np.random.default_rng(seed)
        self.auto = auto
        # the virtual player: rests at the guard (with sensor noise) until told to perform
        self.stream = VirtualPlayerStream(lib, profile=profile, rng=self.rng)
        self._next_t: float | None = None
        self._auto_wait = 0
        self.pressed: list[str] = []  # actions pressed, for tests and the HUD
        self.keymap = KEYMAPS[keys]  # the whole keyboard, or one half of it (two players)
        # the match is paused (the session sets it): a move pressed but not begun yet waits for
        # the resume, the hands resting (a key pressed just before Esc was all made under the
        # pause, which finished it for the boxer)
        self.held = False

    def press(self, action: str) -> None:
        """Start performing `action` from the next sample on (cutting one under way)."""
        if action not in self.lib:
            raise KeyError(f"unknown action {action!r}")
        self.stream.perform(action)
        self.pressed.append(action)

    def press_key(self, key_name: str) -> str | None:
        """A key by its pygame name; returns the action it pressed, or None for other keys."""
        action = self.keymap.get(key_name)
        if action is not None:
            self.press(action)
        return action

    @property
    def busy(self) -> bool:
        return self.stream.performing is not None

    def poll(self) -> list[Sample]:
        """Samples up to now, one per 1/60 s: the motion being played, else the rest."""
        if self.state != SourceState.CONNECTED:
            self._next_t = None
            return []
        now = self.clock()
        if self._next_t is None:
            self._next_t = now
        out: list[Sample] = []
        # after a stall, skip ahead rather than flood the resampler with a backlog
        if now - self._next_t > 0.5:
            self._next_t = now - 0.5
        while self._next_t <= now + 1e-9:
            if self.auto and not self.busy:
                self._auto_step()
            held = self.held and self.stream.waiting
            out.append(Sample(self._next_t, self.stream.rest_frame() if held else self.stream.next_frame()))
            self._next_t += 1.0 / HZ
        self.count("samples", len(out))
        return out

    def _auto_step(self) -> None:
        if self._auto_wait > 0:
            self._auto_wait -= 1
            return
        action = AUTO_ACTIONS[int(self.rng.choice(len(AUTO_ACTIONS), p=AUTO_P))]
        self.press(action)
        self._auto_wait = int(self.rng.integers(20, 70))  # rest between motions, in samples

    # a lost keyboard is not a thing, but tests and the overlay exercise the states through these
    def disconnect(self) -> None:
        self.state = SourceState.DISCONNECTED

    def reconnect(self) -> None:
        self.state = SourceState.CONNECTED


def open_keyboard(url: str, clock: Clock) -> KeyboardSource:
    from game.actions import load_library

    _, _, params = parse_source_url(url)
    url_params_known(url, params, ("profile", "seed", "auto", "keys"))
    profile = params.get("profile", "experienced")
    seed = int(url_number(url, params, "seed", 0, 0, 2**63 - 1, integer=True))
    from game.virtual_player import PROFILES

    if profile not in PROFILES:
        raise SourceError(f"{url}: profile must be one of {', '.join(PROFILES)}")
    auto = params.get("auto", "0").lower() in ("1", "true", "yes", "on")
    keys = params.get("keys", "all")
    if keys not in KEYMAPS:
        raise SourceError(f"{url}: keys must be one of {', '.join(KEYMAPS)}")
    return KeyboardSource(url, clock, load_library(), profile=profile, seed=seed, auto=auto, keys=keys)


# keyboard:// is registered once, by game/__init__.py (which imports this module lazily):
# a scheme has one owner.
