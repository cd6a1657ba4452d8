"""A sample: one reading of the sensors, `(t, accel)` (docs/sources.md). Its own module so that
recordings (engine/recording.py) and sources (engine/sensors) both read it without importing
each other: sources read recordings (replay, the Wiimote emulator), never the other way."""

from __future__ import annotations

from typing import TYPE_CHECKING, NamedTuple

if TYPE_CHECKING:  # numpy only names the sample's type here: `import game` need not load it
    import numpy as np

# |acceleration| in g: no sensor a player wears reads more (wearable IMUs saturate at 16 g, high-g
# ones at 200-400 g); a larger value is a file not in g or a corrupt one, and squares near 1e300
# overflow in the recognizer (thresholds of inf, NaN activity). Here, not in engine/recording.py
# (which has it too), so that `quickjab devices` can judge a board's scale without numpy.
MAX_ACCEL_G = 1000.0


class Sample(NamedTuple):
    """One reading: host time in seconds and accel of shape (sensors, 3) in g, gravity included."""

    t: float
    accel: np.ndarray
