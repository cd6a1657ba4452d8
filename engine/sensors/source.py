"""The source contract (docs/sources.md) and the URL scheme registry.

A source is opened from a URL, as pyserial opens ports. Built-in schemes are imported
lazily by module name so that opening `replay://` never loads hidapi or pyserial; a
package outside `engine` adds its own with `register_scheme` (the game registers
`keyboard://`), or, installed on its own, declares it as an entry point of the
`quickjab.sources` group (`myimu = "myimu_pkg:open_myimu"`), loaded the first time a URL
names a scheme nobody registered (docs/sources.md). A scheme has one owner: registering it
twice is an error, not a silent overwrite.
"""

from __future__ import annotations

import importlib
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from enum import Enum
from typing import ClassVar
from urllib.parse import parse_qsl, urlsplit

from engine.errors import InputError
from engine.sample import Sample  # noqa: F401 - sources' names: engine.sensors.Sample


class SourceState(str, Enum):
    CONNECTING = "connecting"
    CONNECTED = "connected"
    RECONNECTING = "reconnecting"
    DISCONNECTED = "disconnected"
    ENDED = "ended"  # a finite source (a replay) has delivered everything


class SourceError(InputError):
    """A source URL that cannot be opened at all (unknown scheme, bad argument, missing file)."""


Clock = Callable[[], float]

# What a source can do beyond poll/close/rumble/buttons/battery, declared in its `capabilities`
# (callers test membership, never hasattr; docs/sources.md):
PLAYABLE = "playable"  # press(action) performs a move; busy while it does; profile, auto: a
#                        virtual player (the attract mode's pilot and the trainer drive it)
KEYS = "keys"  # press_key(name) -> action or None, keymap {key name: action}: keys drive it
REWIND = "rewind"  # rewind(): a finite source that ENDED plays again from its start (a replay)


@dataclass
class Source:
    """Base of every source. Subclasses implement `poll` (never waits) and `close`.

    State is data, not exceptions: a lost device sets `state` and `poll` returns [].
    `stats` counts what was received and what was dropped (malformed reports, CRC errors...).
    """

    url: str = ""
    sensors: int = 2
    sensors_known: bool = True  # False while `sensors` is a guess (a serial board before its first HELLO)
    clock: Clock = time.perf_counter
    state: SourceState = SourceState.CONNECTING
    battery: float | None = None  # 0..1 where the device reports it
    rate_hz: float | None = None  # nominal or measured sample rate
    description: str = ""
    stats: dict[str, int] = field(default_factory=dict)
    buttons: int = 0  # buttons held (the Wiimote's core bits, Home 0x0080); 0 where there are none
    # what the reader of the file the source replays left out (a cut last row; Recording.notes),
    # said once opened (engine.recording.say_notes); the Wiimote driver's own `notes` are another list
    file_notes: list[str] = field(default_factory=list)
    capabilities: ClassVar[frozenset[str]] = frozenset()  # PLAYABLE, KEYS, REWIND: what else it can do

    def poll(self) -> list[Sample]:
        raise NotImplementedError

    def close(self) -> None:
        self.state = SourceState.DISCONNECTED

    def missing(self) -> str:
        """A part the source should have and has not now, and what that costs, in a few words
        (the Wiimote's Nunchuk: "no Nunchuk: ..."); "" when it is whole. The game shows it: the
        device is connected and streaming, so nothing else on screen would say so."""
        return ""

    def rumble(self, ms: int) -> None:  # noqa: B027 - optional capability; silent where absent
        """Vibrate for `ms` milliseconds where the device can; a no-op elsewhere."""

    def count(self, key: str, n: int = 1) -> None:
        self.stats[key] = self.stats.get(key, 0) + n

    def __enter__(self) -> Source:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def missing_part(source: Source, sensors: int | None = None) -> str:
    """What the connected `source` misses (`Source.missing`), or, read as `sensors` sensors,
    the ones a board that rebooted with fewer no longer sends (their readings hold still); ""."""
    missing = source.missing()
    if not missing and sensors and source.state == SourceState.CONNECTED and 0 < source.sensors < sensors:
        missing = f"{source.sensors} of {sensors} sensors: the other hand holds still"
    return missing


def missing_in_short(missing: str) -> tuple[str, str]:
    """A `missing` text's two halves: what is missing ("no Nunchuk", for a source line or a
    title) and what that costs or what to do ("plug it in for left-hand moves"; may be "")."""
    short, _, then = missing.partition(": ")
    return short, then


SourceFactory = Callable[[str, Clock], Source]

_factories: dict[str, SourceFactory] = {}
# Schemes whose module registers them on import; loaded on first use only.
_builtin_modules: dict[str, str] = {
    "replay": "engine.sensors.replay",
    "wiimote": "engine.sensors.wiimote",
    "wiimote-emu": "engine.sensors.wiimote",
    "serial": "engine.sensors.serial_source",
    "demo": "engine.sensors.demo",
}
# Schemes a package outside engine owns and registers on import: never an entry point's.
_taken_elsewhere: dict[str, str] = {
    "keyboard": "the game's: importing the game package registers it",
}


ENTRY_POINT_GROUP = "quickjab.sources"


def register_scheme(scheme: str, factory: SourceFactory) -> None:
    """Make `scheme://...` URLs open with `factory(url, clock)`. Raises ValueError when another
    factory already owns the scheme (registering the same factory again is harmless)."""
    scheme = scheme.lower()
    owner = _factories.get(scheme)
    home = _builtin_modules.get(scheme)
    if owner is None and home is not None and getattr(factory, "__module__", None) != home:
        # a built-in scheme is taken even before its module is loaded (on first use)
        raise ValueError(f"source scheme {scheme!r} is built in ({home}); {_name_of(factory)} cannot register it")
    if owner is not None and owner is not factory:
        raise ValueError(
            f"source scheme {scheme!r} is already registered by {_name_of(owner)}; "
            f"{_name_of(factory)} cannot register it too"
        )
    _factories[scheme] = factory


def _name_of(factory: object) -> str:
    return f"{getattr(factory, '__module__', '?')}.{getattr(factory, '__qualname__', repr(factory))}"


def _plugin_entry_points() -> list:
    """The installed `quickjab.sources` entry points. Read only when a URL names a scheme nobody
    registered, so that start-up never scans the installed packages."""
    from importlib.metadata import entry_points

    return list(entry_points(group=ENTRY_POINT_GROUP))


def _load_plugin(scheme: str) -> None:
    """Register `scheme` from its entry point, if an installed package declares one."""
    if scheme in _taken_elsewhere:
        raise SourceError(f"{scheme}:// is {_taken_elsewhere[scheme]}; no installed package can declare it")
    declared = {ep.value: ep for ep in _plugin_entry_points() if ep.name.lower() == scheme}
    if not declared:
        return
    if len(declared) > 1:
        raise SourceError(f"source scheme {scheme!r} is declared by more than one installed package: "
                          f"{', '.join(sorted(declared))}")
    (ep,) = declared.values()
    try:
        factory = ep.load()
    except (ImportError, AttributeError) as exc:  # the package, or the name in it, is missing
        raise SourceError(f"{scheme}:// is not available here: {ep.value} cannot be loaded ({exc})") from None
    if not callable(factory):
        raise SourceError(f"{scheme}://: entry point {ep.value} is not a source factory (url, clock) -> Source")
    if _factories.get(scheme) is None:  # the module may have registered it on import
        register_scheme(scheme, factory)


def registered_schemes(*, plugins: bool = False) -> list[str]:
    """Known schemes; with `plugins`, also those installed packages declare (scans them)."""
    names = set(_factories) | set(_builtin_modules)
    if plugins:
        names |= {ep.name.lower() for ep in _plugin_entry_points()}
    return sorted(names)


def parse_source_url(url: str) -> tuple[str, str, dict[str, str]]:
    """Split `scheme://path?k=v` into (scheme, path, params). `serial:///dev/x` gives '/dev/x'."""
    if "://" not in url:
        raise SourceError(f"{url!r} is not a source URL (expected scheme://..., e.g. replay://rec.csv)")
    try:
        parts = urlsplit(url)
    except ValueError:
        # a relative path is the URL's host part to urlsplit, which refuses a host with '[' or
        # ']' (IPv6) or characters NFKC turns into '/', '?', '#', '@' or ':': split it the same
        # way without those checks, so `replay://take[1].csv` names its file like any other
        scheme, rest = url.split("://", 1)
        rest, _, query = rest.partition("#")[0].partition("?")
        return scheme.lower(), rest, dict(parse_qsl(query))
    path = parts.netloc + parts.path
    return parts.scheme.lower(), path, dict(parse_qsl(parts.query))


def url_params_known(url: str, params: dict[str, str], known: tuple[str, ...]) -> None:
    """A SourceError naming `url` for a parameter the source does not take: a typo (`replay://
    rec.csv?sped=4`) played at the default with no word said."""
    unknown = sorted(set(params) - set(known))
    if unknown:
        raise SourceError(f"{url}: unknown parameter(s) {', '.join(unknown)} (known: {', '.join(known) or 'none'})")


_FILE_ESCAPES = {"%23": "#", "%3f": "?", "%25": "%"}
RECORDING_SCHEMES = ("replay", "wiimote-emu")  # sources whose URL path names a recording file


def file_path(path: str) -> str:
    """The path of a URL that names a recording file (RECORDING_SCHEMES) as a file name: %23 is '#', %3F '?' and %25 '%' (any case), the
    characters a URL keeps for itself, so `replay://a%23b%3Fc=1.csv` reads `a#b?c=1.csv`. Only
    these: a name with another '%' (`50%.csv`, `a%41.csv`) is read as it is written."""
    if "%" not in path:
        return path
    out, i = [], 0
    while i < len(path):
        decoded = _FILE_ESCAPES.get(path[i:i + 3].lower()) if path[i] == "%" else None
        out.append(decoded or path[i])
        i += 3 if decoded else 1
    return "".join(out)


def url_file(url: str) -> str | None:
    """The file a source URL reads (replay://rec.csv: rec.csv), None when it names none or is no
    URL: what a command writing files must not write over."""
    try:
        scheme, path, _ = parse_source_url(url)
    except SourceError:
        return None
    return (file_path(path) if scheme in RECORDING_SCHEMES else path) or None


def url_flag(params: dict[str, str], key: str, default: str = "0") -> bool:
    """A yes/no URL parameter: 1, true, yes or on (any case) is yes."""
    return params.get(key, default).lower() in ("1", "true", "yes", "on")


def url_number(
    url: str,
    params: dict[str, str],
    key: str,
    default: float,
    lo: float | None = None,
    hi: float | None = None,
    *,
    integer: bool = False,
    lo_open: bool = False,
) -> float:
    """A numeric URL parameter, finite and in [lo, hi] ((lo, hi] with lo_open); an int when
    `integer`. Raises SourceError naming the URL, the key and the range otherwise."""
    text = params.get(key)
    if text is None:
        return default
    kind = "an integer" if integer else "a number"

    def bound(x: float) -> str:  # an int bound as written: 2**63 - 1, not 9.22337e+18
        return str(x) if isinstance(x, int) else f"{x:g}"

    if lo is not None and hi is not None:
        kind += f" {'above' if lo_open else 'from'} {bound(lo)} {'up ' if lo_open else ''}to {bound(hi)}"
    elif lo is not None:
        kind += f" {'above' if lo_open else 'from'} {bound(lo)}"
    try:
        v: float = int(text) if integer else float(text)
    except ValueError:
        raise SourceError(f"{url}: {key} must be {kind}, not {text!r}") from None
    if not math.isfinite(v) or (lo is not None and (v <= lo if lo_open else v < lo)) or (hi is not None and v > hi):
        raise SourceError(f"{url}: {key} must be {kind}, not {text!r}")
    return v


def open_source(url: str, *, clock: Clock | None = None) -> Source:
    """Open a source by URL. Raises SourceError for a URL that can never work."""
    scheme, _, _ = parse_source_url(url)
    if scheme not in _factories and scheme in _builtin_modules:
        try:
            importlib.import_module(_builtin_modules[scheme])
        except ModuleNotFoundError as exc:
            # a scheme whose module (or the library it needs, e.g. hidapi) is not installed
            raise SourceError(f"{scheme}:// is not available here: module {exc.name!r} is missing") from None
    if scheme not in _factories and scheme not in _builtin_modules:
        _load_plugin(scheme)
    factory = _factories.get(scheme)
    if factory is None:
        raise SourceError(
            f"unknown source scheme {scheme!r} in {url!r}; known: {', '.join(registered_schemes(plugins=True))}"
        )
    return factory(url, clock or time.perf_counter)
