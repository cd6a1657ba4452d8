"""Wiimote and Nunchuk accelerometer counts to g with each one's calibration."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from engine.sensors.wiimote import protocol as p

REST = np.array([0.0, 0.0, 1.0])  # what a still, level sensor reads


def calibration_arrays(cal: p.Calibration) -> tuple[np.ndarray, np.ndarray]:
    """(zero, one g - zero) of a calibration as float arrays: counts to g is (raw - zero) / span."""
    zero = np.asarray(cal.zero, dtype=np.float64)
    return zero, np.asarray(cal.one_g, dtype=np.float64) - zero


class CalibratedAccel:
    """The two calibrations as arrays (None until read), and the Nunchuk's last value, held
    while no Nunchuk is plugged (REST until one ever was)."""

    def __init__(self) -> None:
        self._rz = self._rs = self._nz = self._ns = None  # calibration as arrays: zero, span
        self._left = REST.copy()

    @property
    def ready(self) -> bool:
        """The Wiimote's calibration is known."""
        return self._rs is not None

    def set_wiimote(self, cal: p.Calibration) -> None:
        self._rz, self._rs = calibration_arrays(cal)

    def set_nunchuk(self, cal: p.Calibration | None) -> None:
        if cal is None:
            self._nz = self._ns = None
        else:
            self._nz, self._ns = calibration_arrays(cal)

    def rows(self, rep: p.Report, count: Callable[[str], None]) -> tuple[np.ndarray, p.Nunchuk | None]:
        """(2, 3) in g from a data report with accel (row 0 the Wiimote, row 1 the Nunchuk),
        and the Nunchuk report decoded from it if any."""
        accel = np.empty((2, 3))
        accel[0] = (np.asarray(rep.accel, dtype=np.float64) - self._rz) / self._rs
        nun = None
        if self._ns is not None and rep.extension is not None and len(rep.extension) >= 6:
            nun = p.decode_nunchuk(rep.extension)
            if nun is not None:
                self._left = (np.asarray(nun.accel, dtype=np.float64) - self._nz) / self._ns
        else:
            count("samples_without_nunchuk")
        accel[1] = self._left  # held while no Nunchuk is plugged (REST until one ever was)
        return accel, nun
