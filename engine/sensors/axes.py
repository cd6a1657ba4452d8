"""An IMU mounted another way than the game's sensor axes: `?axes=` on a source URL.

The game's sensor axes are the virtual player's, which made the shipped templates
(game/virtual_player.py `sensor_frames`): y along the forearm towards the fist, z the forearm's
upper side, x = y cross z computed in the game's world (x right, y up, z forward), so that with
y pointing forward and z up, x points to the wearer's LEFT: a left-handed frame. An IMU chip's axes
are right-handed (the MPU-6050's and LSM6DS3's datasheets), so the mapping from a chip to the
game's axes always mirrors one axis: `axes=` names, for the game's x, y and z in turn, the IMU axis
(and sign) that reads it, and one that keeps the chip's axes right-handed is refused with the x
that fits. Only whole-axis turns: any other mounting is what `quickjab train` is for (templates
recorded with the sensor as it is worn, in its own axes, need no mapping).
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


def parse_axes(url: str, text: str) -> AxisMap:
    """`x,y,z` with each name once, each optionally signed (`-y,x,z`), mirroring the chip's
    handedness (the module docstring). A SourceError naming `url` otherwise."""
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
        raise SourceError(f"{url}: axes must name x, y and z once each, signed or not (e.g. axes=-x,y,z), not {text!r}")
    turn = AxisMap((order[0], order[1], order[2]), (signs[0], signs[1], signs[2]))
    if np.linalg.det(np.eye(3)[turn.order] * turn.signs[:, None]) > 0:
        # The chip's axes are right-handed and the game's left-handed (the module docstring): a
        # mapping that keeps the handedness would hand the recognizer every punch as its mirror
        # image (a mirrored session: 10 of 42 actions recognized, against 42 of 42), and the
        # guard's reading cannot tell (x reads about 0 there). x follows from y and z.
        fixed = AxisMap(turn.order, (-turn.signs[0], turn.signs[1], turn.signs[2]))
        raise SourceError(f"{url}: axes={text} keeps the IMU's right-handed axes right-handed, but the game's are "
                          f"left-handed (x to the left when y points to the fist and z up): with this y and z, x is "
                          f"{fixed.text.split(',')[0]} (axes={fixed})")
    return turn
