"""The recognizer's settings as data: `RecognizerConfig`, every keyword knob of
`DualBufferRecognizer` with its default, in one frozen dataclass (the way Box2D's
`b2DefaultWorldDef()` gives a world's settings).

    config = RecognizerConfig(noise_g=0.5)
    rec = DualBufferRecognizer.from_config(templates, config)  # == DualBufferRecognizer(templates, noise_g=0.5)

Settings come in layers (docs/recognition.md): the defaults here, then the settings saved
with the templates (`Templates.recognizer`: a player's tuned gate travels with their
moves), then the user's config file, then the command line. Each layer is a plain mapping
{name: value}, checked by `check_settings`: an unknown name or a value of the wrong type or
range is a `RecognizerConfigError`, one line that says where it came from.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass

from engine.errors import InputError

MAX_FRAMES = 6000  # any frame count (100 s at 60 Hz): buffers are allocated from these
MAX_ADAPT = 100  # adopted templates per action: each one is a DTW row every frame
MAX_NOISE_G = 100.0
MAX_TILT_DEG = 45.0  # a copy turned further is another grip, not a tolerance of one
DTW_METHODS = ("auto", "scan", "loop", "jit", "native")  # engine.recognition.dtw.METHODS and "auto"
TRUE_WORDS = ("true", "yes", "on", "1")
FALSE_WORDS = ("false", "no", "off", "0")


class RecognizerConfigError(InputError):
    """A recognizer setting that is unknown or of the wrong type; the message says where it was
    set (the command line, a config file, a template file)."""


@dataclass(frozen=True)
class RecognizerConfig:
    """Every setting of the dual-buffer recognizer, with its default. The rules each one tunes
    are in engine/recognition/dual_buffer.py's docstring; the measurements behind the defaults
    are in docs/recognition.md."""

    # Main buffer (frames, or "auto"): the first decision (a `start`) is made when this many
    # frames have passed since the motion's onset. 6 (100 ms) is the paper's trade between lag
    # and accuracy (its Figs. 8-9, re-measured on our data); "auto" decides after 3 frames when
    # the best action leads clearly, else waits up to 12.
    main: int | str = 6
    # Supplementary buffer (frames): for this long from the onset a better match may still
    # `switch` the action. 60 (1 s) covers a whole punch; the paper's value.
    supplementary: int = 60
    # Noise gate (g, or "auto"): a frame is motion when the sum over sensors of |a - gravity|
    # reaches it. "auto" learns it as twice the resting noise (0.3-2 g): a fixed 1.0 g (the
    # paper's) missed gentle players, a fixed 0.3 g fired on a bouncing guard.
    noise_g: float | str = "auto"
    # Null signal (frames): this many quiet frames in a row end the motion. 6 (100 ms): short
    # enough for back-to-back punches, long enough to ride over a punch's turning point.
    null_frames: int = 6
    # Discard (frames): after the game's clip finishes (`character_finished()`), frames are
    # dropped for this long so the hand's return does not start a new action. 20: the paper's.
    discard_frames: int = 20
    # Switch margin (normalized DTW score): a later action must beat the current one by this
    # much to `switch`. 0.05: small enough to correct a wrong early guess, large enough that
    # two close actions do not flip back and forth.
    switch_margin: float = 0.05
    # Auto lead (fraction): with main="auto", decide early when the runner-up's score is this
    # much worse than the best's ((second - first) / second). 0.25: measured on the synthesized
    # players and uWave.
    auto_lead: float = 0.25
    # Rejection (on/off): refuse a motion whose best score is over its template's learned
    # threshold. Off only to study the recognizer (every motion then becomes some action).
    reject: bool = True
    # DTW implementation: "auto" picks the C kernel, else numba, else numpy's "loop"; the three
    # give the same scores to the bit (tested), so the same decisions. A name forces one:
    # "native", "jit", "scan" or "loop" ("scan" rounds differently: its decisions may differ).
    dtw_method: str = "auto"
    # Open-end progress (fraction of the motion's length): while the hand moves, the motion's n
    # frames must reach at least min_progress * n frames into a template. 0.75 lets a full
    # blow's slow start match a quick punch's template early.
    min_progress: float = 0.75
    # Complete fraction (of the template's length): a motion also ends once its action's template
    # is matched past this fraction and the hand calms down, so punches thrown back to back start
    # one action each. 0.9; 0 keeps the paper's null signal only.
    complete_fraction: float = 0.9
    # Complete frames: ... for this many frames in a row. 2: one frame is noise.
    complete_frames: int = 2
    # Closed after (frames): after this many quiet frames the motion has probably ended and whole
    # templates must match (closed end). 1: the first quiet frame; 0 = never.
    closed_after: int = 1
    # Extend (on/off): a decided motion that outlasts the supplementary buffer keeps being
    # scored, and a clearly better action becomes the final decision just before its `end`.
    # For long gestures (docs/recognition.md).
    extend: bool = True
    # Adaptation (templates per action): a confidently recognized whole motion joins its action's
    # templates; this many recent ones are kept (a player drifting from the training trials,
    # docs/recognition.md, fifth round); 0 turns adaptation off.
    adapt: int = 3
    # Tilt (degrees): three copies of each trained template, turned this far towards three
    # directions across its resting gravity, tolerate a grip that differs from the trials' (before
    # the first decision they count only where no trained template fits; engine/recognition/tilt.py).
    # 10: uWave's day 1 -> days 2-7, adaptation forgotten before each trial, 90.2 -> 92.0 % (a new
    # recognizer per trial: 91.8 %, docs/recognition.md twenty-second round); 0 turns it off.
    tilt_deg: float = 10.0

    def __post_init__(self) -> None:
        for f in dataclasses.fields(self):
            object.__setattr__(self, f.name, _check(f.name, getattr(self, f.name), "RecognizerConfig"))

    def kwargs(self) -> dict[str, object]:
        """The DualBufferRecognizer keywords this config stands for (every field)."""
        return {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}

    def updated(self, values: Mapping[str, object], where: str) -> RecognizerConfig:
        """This config with `values` (names and values checked; errors name `where`) set."""
        return dataclasses.replace(self, **check_settings(values, where))

    def changed(self) -> dict[str, object]:
        """The settings that differ from the defaults."""
        default = RecognizerConfig()
        return {k: v for k, v in self.kwargs().items() if v != getattr(default, k)}


SETTINGS = tuple(f.name for f in dataclasses.fields(RecognizerConfig))

# name -> (kind, lo, hi): what a value may be. Kinds: int, float, bool, choice (DTW_METHODS),
# and int|auto, float|auto (a number or the word "auto").
_RULES: dict[str, tuple[str, float | None, float | None]] = {
    "main": ("int|auto", 1, MAX_FRAMES),
    "supplementary": ("int", 1, MAX_FRAMES),
    "noise_g": ("float|auto", 0.0, MAX_NOISE_G),
    "null_frames": ("int", 1, MAX_FRAMES),
    "discard_frames": ("int", 0, MAX_FRAMES),
    "switch_margin": ("float", 0.0, None),
    "auto_lead": ("float", 0.0, 1.0),
    "reject": ("bool", None, None),
    "dtw_method": ("choice", None, None),
    "min_progress": ("float", 0.0, None),
    "complete_fraction": ("float", 0.0, 1.0),
    "complete_frames": ("int", 1, MAX_FRAMES),
    "closed_after": ("int", 0, MAX_FRAMES),
    "extend": ("bool", None, None),
    "adapt": ("int", 0, MAX_ADAPT),
    "tilt_deg": ("float", 0.0, MAX_TILT_DEG),
}
assert set(_RULES) == set(SETTINGS), "every setting needs a rule"


def _expected(kind: str, lo: float | None, hi: float | None) -> str:
    if kind == "bool":
        return "true or false"
    if kind == "choice":
        return "one of " + ", ".join(DTW_METHODS)
    what = "an integer" if kind.startswith("int") else "a number"
    if lo is not None and hi is not None:
        what += f" from {lo:g} to {hi:g}"
    elif lo is not None:
        what += f" >= {lo:g}"
    return what + (" or 'auto'" if kind.endswith("|auto") else "")


def _check(name: str, value: object, where: str) -> object:
    """`value` for setting `name`, normalized (an int where a number goes becomes a float), or
    a RecognizerConfigError naming `where`."""
    if name not in _RULES:
        raise RecognizerConfigError(f"{where}: unknown recognizer setting {name!r} (known: {', '.join(SETTINGS)})")
    kind, lo, hi = _RULES[name]
    ok = False
    if kind.endswith("|auto") and value == "auto":
        return value
    if kind == "bool":
        ok = isinstance(value, bool)
    elif kind == "choice":
        ok = value in DTW_METHODS
    elif kind.startswith("int"):
        ok = isinstance(value, int) and not isinstance(value, bool)
    elif kind.startswith("float"):
        ok = isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
        value = float(value) if ok else value
    if ok and lo is not None:
        ok = value >= lo and (hi is None or value <= hi)
    if not ok:
        raise RecognizerConfigError(f"{where}: recognizer setting {name} must be {_expected(kind, lo, hi)}, not {value!r}")
    return value


def check_settings(values: Mapping[str, object], where: str) -> dict[str, object]:
    """`values` checked (known names, right types and ranges) and normalized; errors name `where`."""
    if not isinstance(values, Mapping):
        raise RecognizerConfigError(f"{where}: recognizer settings must be a table of name = value")
    return {str(k): _check(str(k), v, where) for k, v in values.items()}


def parse_value(name: str, text: str, where: str) -> object:
    """A setting's value from text (the command line): numbers, true/false, 'auto', a DTW method."""
    if name not in _RULES:
        _check(name, None, where)  # raises: unknown
    kind = _RULES[name][0]
    word = text.strip().lower()
    value: object = text.strip()
    if kind.endswith("|auto") and word == "auto":
        value = "auto"
    elif kind == "bool":
        value = True if word in TRUE_WORDS else False if word in FALSE_WORDS else text
    elif kind.startswith("int"):
        try:
            value = int(word)
        except ValueError:
            value = text
    elif kind.startswith("float"):
        try:
            value = float(word)
        except ValueError:
            value = text
    return _check(name, value, where)


def parse_assignments(texts: Iterable[str], where: str = "--recognizer") -> dict[str, object]:
    """{name: value} from `key=value` texts (`--recognizer noise_g=0.5`); later ones win."""
    out: dict[str, object] = {}
    for text in texts:
        name, eq, value = text.partition("=")
        if not eq or not name.strip():
            raise RecognizerConfigError(f"{where} {text!r}: expected NAME=VALUE, e.g. noise_g=0.5")
        out[name.strip()] = parse_value(name.strip(), value, f"{where} {text}")
    return out


def config_or_defaults(config: RecognizerConfig | Mapping[str, object] | None) -> RecognizerConfig:
    """`DualBufferRecognizer.from_config`'s argument: a RecognizerConfig; None for the defaults; or
    a mapping of settings (e.g. `Templates.recognizer`, the settings saved with templates), checked
    and set over the defaults as `layered` does (a bad one is a RecognizerConfigError naming it).
    Anything else is a TypeError."""
    if config is None:
        return RecognizerConfig()
    if isinstance(config, Mapping):
        return layered(config, where=["from_config settings"])
    if not isinstance(config, RecognizerConfig):
        raise TypeError(f"from_config takes a RecognizerConfig, a mapping of settings or None, not {type(config).__name__}")
    return config


def layered(*layers: Mapping[str, object], where: Iterable[str] = ()) -> RecognizerConfig:
    """The defaults with each layer's settings set in turn (later layers win): e.g. the
    templates' saved settings, then the config file's, then the command line's. `where`
    names the layers for errors (a layer may already be checked)."""
    config = RecognizerConfig()
    names = list(where)
    for i, layer in enumerate(layers):
        config = config.updated(layer, names[i] if i < len(names) else "recognizer settings")
    return config
