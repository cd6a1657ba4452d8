"""An IMU mounted another way than the game's sensor axes: `?axes=` on a source URL.

The game's axes are the Wiimote's as held in the fist (game/virtual_player.py: y along the
forearm towards the fist, z the forearm's upper side, x completing a right-handed frame), and
the shipped templates were made in them. A serial IMU strapped on with its own axes elsewhere
reads the same motion on other axes; `axes=-y,x,z` names, for the game's x, y and z in turn, the
IMU axis (and sign) that reads it. Only whole-axis turns and flips: any other mounting is what
`quickjab train` is for (templates recorded with the sensor as it is worn).
"""

from __future__ import annotations

import numpy as np

from engine.sensors.source import SourceError

AXIS_INDEX = {"x": 0, "y": 1, "z": 2}


class AxisMap:
    """`apply(accel)`: the (..., 3) readings on the game's axes."""

    def __init__(self, order: tuple[int, int, int], signs: tuple[float, float, float]):
        self.order = np.array(order)
        self.signs = np.array(signs)
        self.text = ",".join(("-" if sg < 0 else "") + "xyz"[i] for i, sg in zip(order, signs, strict=True))

    def __str__(self) -> str:
        return self.text

    def apply(self, accel: np.ndarray) -> np.ndarray:
        return np.asarray(accel)[..., self.order] * self.signs


def parse_axes(url: str, text: str) -> AxisMap | None:
    """`x,y,z` with each name once, each optionally signed (`-y,x,z`); None for the identity.
    A SourceError naming `url` otherwise."""
    names = [part.strip().lower() for part in text.split(",")]
    order, signs = [], []
    for name in names:
        sign = -1.0 if name.startswith("-") else 1.0
        axis = name.lstrip("+-")
        if axis not in AXIS_INDEX or len(name) - len(axis) > 1:
            order = []
            break
        order.append(AXIS_INDEX[axis])
        signs.append(sign)
    if len(order) != 3 or sorted(order) != [0, 1, 2]:
        raise SourceError(f"{url}: axes must name x, y and z once each, signed or not (e.g. axes=-y,x,z), not {text!r}")
    if order == [0, 1, 2] and signs == [1.0, 1.0, 1.0]:
        return None
    turn = AxisMap((order[0], order[1], order[2]), (signs[0], signs[1], signs[2]))
    if np.linalg.det(np.eye(3)[turn.order] * turn.signs[:, None]) < 0:
        # A sensor turned any way still has right-handed axes: this mapping is a mirror image,
        # which no mounting gives (the guard's reading cannot tell: x reads about 0 there), and the
        # punches would be recognized as their mirror images. x follows from y and z.
        fixed = AxisMap(turn.order, (-turn.signs[0], turn.signs[1], turn.signs[2]))
        raise SourceError(f"{url}: axes={text} is a mirror image (no way of strapping a sensor on gives it): "
                          f"with this y and z, x is {fixed.text.split(',')[0]} (axes={fixed})")
    return turn
