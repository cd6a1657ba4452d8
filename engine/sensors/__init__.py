"""Sensor sources: every source yields samples `(t, accel)` and is opened from a URL."""

from engine.sensors.source import (
    Sample,
    Source,
    SourceError,
    SourceState,
    open_source,
    parse_source_url,
    register_scheme,
    registered_schemes,
)

__all__ = [
    "Sample",
    "Source",
    "SourceError",
    "SourceState",
    "open_source",
    "parse_source_url",
    "register_scheme",
    "registered_schemes",
]
