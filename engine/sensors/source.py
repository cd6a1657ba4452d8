"""The source contract (ARCHITECTURE.md) and the URL scheme registry.

A source is opened from a URL, as pyserial opens ports. Built-in schemes are imported
lazily by module name so that opening `replay://` never loads hidapi or pyserial; a
package outside `engine` adds its own with `register_scheme` (the game registers
`keyboard://`).
"""

from __future__ import annotations

import importlib
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from enum import Enum
from typing import TYPE_CHECKING, NamedTuple
from urllib.parse import parse_qsl, urlsplit

from engine.errors import InputError

if TYPE_CHECKING:  # numpy only names the sample's type here: `import game` need not load it
    import numpy as np


class Sample(NamedTuple):
    """One reading: host time in seconds and accel of shape (sensors, 3) in g, gravity included."""

    t: float
    accel: np.ndarray


class SourceState(str, Enum):
    CONNECTING = "connecting"
    CONNECTED = "connected"
    RECONNECTING = "reconnecting"
    DISCONNECTED = "disconnected"
    ENDED = "ended"  # a finite source (a replay) has delivered everything


class SourceError(InputError):
    """A source URL that cannot be opened at all (unknown scheme, bad argument, missing file)."""


Clock = Callable[[], float]


@dataclass
class Source:
    """Base of every source. Subclasses implement `poll` (never waits) and `close`.

    State is data, not exceptions: a lost device sets `state` and `poll` returns [].
    `stats` counts what was received and what was dropped (malformed reports, CRC errors...).
    """

    url: str = ""
    sensors: int = 2
    clock: Clock = time.perf_counter
    state: SourceState = SourceState.CONNECTING
    battery: float | None = None  # 0..1 where the device reports it
    rate_hz: float | None = None  # nominal or measured sample rate
    description: str = ""
    stats: dict[str, int] = field(default_factory=dict)

    def poll(self) -> list[Sample]:
        raise NotImplementedError

    def close(self) -> None:
        self.state = SourceState.DISCONNECTED

    def rumble(self, ms: int) -> None:  # noqa: B027 - optional capability; silent where absent
        """Vibrate for `ms` milliseconds where the device can; a no-op elsewhere."""

    def count(self, key: str, n: int = 1) -> None:
        self.stats[key] = self.stats.get(key, 0) + n

    def __enter__(self) -> Source:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


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


def register_scheme(scheme: str, factory: SourceFactory) -> None:
    """Make `scheme://...` URLs open with `factory(url, clock)`."""
    _factories[scheme.lower()] = factory


def registered_schemes() -> list[str]:
    return sorted(set(_factories) | set(_builtin_modules))


def parse_source_url(url: str) -> tuple[str, str, dict[str, str]]:
    """Split `scheme://path?k=v` into (scheme, path, params). `serial:///dev/x` gives '/dev/x'."""
    if "://" not in url:
        raise SourceError(f"{url!r} is not a source URL (expected scheme://..., e.g. replay://rec.csv)")
    parts = urlsplit(url)
    path = parts.netloc + parts.path
    return parts.scheme.lower(), path, dict(parse_qsl(parts.query))


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
    factory = _factories.get(scheme)
    if factory is None:
        raise SourceError(
            f"unknown source scheme {scheme!r} in {url!r}; known: {', '.join(registered_schemes())}"
        )
    return factory(url, clock or time.perf_counter)
