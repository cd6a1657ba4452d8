"""A thin, non-blocking wrapper over the `hid` / `hidraw` modules of the hidapi package.

On Linux the `hid` module talks to libusb, which cannot see Bluetooth devices; the `hidraw`
module (same API, same package) can, so it is preferred where importable. A backend is any
object with `enumerate(vendor_id, product_id)` and `device()` returning something shaped like
`hid.device`: the emulator provides one, so the driver runs the same code against both.
"""

from __future__ import annotations

import importlib
import os
import sys
from dataclasses import dataclass
from typing import Any

from engine.sensors.wiimote.protocol import OUTPUT_REPORT_LENGTH, VENDOR_ID, model_name

READ_SIZE = 64  # larger than any Wiimote report; hidapi truncates to what we ask


class TransportError(OSError):
    """The device is gone or refused an operation."""


class BackendMissing(ImportError):
    """Neither hidraw nor hid could be imported."""


def hid_backend() -> Any:
    """`hidraw` on Linux where importable (sees Bluetooth), else `hid`."""
    names = ["hidraw", "hid"] if sys.platform.startswith("linux") else ["hid"]
    errors = []
    for name in names:
        try:
            return importlib.import_module(name)
        except ImportError as exc:  # the module, or its shared library (libhidapi-hidraw)
            errors.append(f"{name}: {exc}")
    raise BackendMissing("hidapi is not usable (" + "; ".join(errors) + "); pip install hidapi")


def path_text(path: bytes | str) -> str:
    """A device path as text (hidapi gives bytes)."""
    return path.decode(errors="replace") if isinstance(path, bytes) else str(path)


@dataclass(frozen=True)
class WiimoteInfo:
    path: bytes
    model: str  # RVL-CNT-01 or RVL-CNT-01-TR
    product_id: int
    product_string: str
    serial: str  # the Bluetooth address on hidraw
    kernel_driver: str | None  # e.g. 'wiimote' when Linux's hid-wiimote is bound

    @property
    def path_str(self) -> str:
        return path_text(self.path)


def kernel_driver(path: bytes | str) -> str | None:
    """The Linux kernel HID driver bound to a /dev/hidrawN node ('wiimote', 'hid-generic'), or
    None when unknown (other OSes, other paths)."""
    p = path_text(path)
    if not p.startswith("/dev/hidraw"):
        return None
    link = f"/sys/class/hidraw/{os.path.basename(p)}/device/driver"
    try:
        return os.path.basename(os.readlink(link))
    except OSError:
        return None


def list_wiimotes(backend: Any | None = None) -> list[WiimoteInfo]:
    """Wiimotes the backend can see, Wii U Pro Controllers and Balance Boards excluded."""
    backend = backend if backend is not None else hid_backend()
    found: list[WiimoteInfo] = []
    seen: set[bytes] = set()
    try:
        entries = backend.enumerate(VENDOR_ID, 0)
    except OSError:
        return []
    driver_of = getattr(backend, "kernel_driver", kernel_driver)
    for d in entries:
        model = model_name(int(d.get("product_id", 0)), d.get("product_string") or "")
        path = d.get("path", b"")
        if model is None or path in seen:
            continue
        seen.add(path)
        found.append(
            WiimoteInfo(
                path=path,
                model=model,
                product_id=int(d["product_id"]),
                product_string=d.get("product_string") or "",
                serial=d.get("serial_number") or "",
                kernel_driver=driver_of(path),
            )
        )
    return found


class HidTransport:
    """One open Wiimote: non-blocking reads of whole reports, writes of whole reports.

    `write_length`: pad every output report to this many bytes. Windows' own Bluetooth stack
    wants the device's output report length (22 for a Wiimote) from WriteFile; hidapi's Windows
    backend pads to it already, so this is for stacks that take the exact size.
    """

    def __init__(self, backend: Any, path: bytes, write_length: int | None = None):
        self.backend = backend
        self.path = path
        self.write_length = write_length
        self._dev: Any = None

    @staticmethod
    def default_write_length() -> int | None:
        return OUTPUT_REPORT_LENGTH if sys.platform == "win32" else None

    def open(self) -> None:
        dev = self.backend.device()
        try:
            dev.open_path(self.path)
            dev.set_nonblocking(1)
        except (OSError, ValueError) as exc:
            raise TransportError(f"cannot open {self.path!r}: {exc}") from None
        self._dev = dev

    @property
    def is_open(self) -> bool:
        return self._dev is not None

    def read(self) -> bytes | None:
        """One input report, or None when none is waiting. Raises TransportError when gone."""
        if self._dev is None:
            raise TransportError("not open")
        try:
            data = self._dev.read(READ_SIZE)
        except (OSError, ValueError) as exc:
            raise TransportError(f"read from {self.path!r} failed: {exc}") from None
        return bytes(data) if data else None

    def write(self, report: bytes) -> None:
        if self._dev is None:
            raise TransportError("not open")
        if self.write_length and len(report) < self.write_length:
            report = report + bytes(self.write_length - len(report))
        try:
            n = self._dev.write(report)
        except (OSError, ValueError) as exc:
            raise TransportError(f"write to {self.path!r} failed: {exc}") from None
        if n is None or n < 0:
            raise TransportError(f"write to {self.path!r} failed")

    def close(self) -> None:
        dev, self._dev = self._dev, None
        if dev is not None:
            try:
                dev.close()
            except (OSError, ValueError):
                pass
