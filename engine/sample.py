"""A sample: one reading of the sensors, `(t, accel)` (docs/sources.md). Its own module so that
recordings (engine/recording.py) and sources (engine/sensors) both read it without importing
each other: sources read recordings (replay, the Wiimote emulator), never the other way."""

from __future__ import annotations

from typing import TYPE_CHECKING, NamedTuple

if TYPE_CHECKING:  # numpy only names the sample's type here: `import game` need not load it
    import numpy as np


class Sample(NamedTuple):
    """One reading: host time in seconds and accel of shape (sensors, 3) in g, gravity included."""

    t: float
    accel: np.ndarray
