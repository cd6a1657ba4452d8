"""`quickjab devices PATH...`: whether a serial IMU bridge answers on a port given by path, with
the serial protocol's HELLO (firmware_bridge/PROTOCOL.md). pyserial's port list never shows a
pty (`quickjab bridge emulate`, socat) nor a port it cannot classify, so such a port is probed
by name: opened as the `serial://` source opens it, asked for a HELLO (`?`) and read for a
while, its bytes through the protocol's own decoder.

pyserial and the decoder only (no numpy): `devices` stays light."""

from __future__ import annotations

import os
import time
from dataclasses import asdict, dataclass, field
from typing import Any

PROBE_S = 1.5  # a board answers `?` within a tick and sends a HELLO every second anyway
ASK_EVERY_S = 0.25  # as the source does: the first `?` may come before the board reads its input
IMU_KINDS = {1: "MPU-6050", 2: "LSM6DS3", 3: "simulated"}


@dataclass
class ProbeResult:
    """What one port said. `answered`: a valid HELLO came (a board speaking protocol v1)."""

    path: str
    url: str
    answered: bool = False
    result: str = ""  # one line for people
    bytes: int = 0
    frames: int = 0  # valid frames of any type
    hello: dict[str, Any] | None = None  # the last HELLO's fields
    counts: dict[str, int] = field(default_factory=dict)  # the decoder's error counters that are not 0

    def as_dict(self) -> dict[str, Any]:
        return asdict(self)


def hello_fields(hello: Any) -> dict[str, Any]:
    """A HELLO (firmware_bridge.protocol.Hello) as plain fields, the sensors by hand."""
    from firmware_bridge import protocol

    return {"sensors": hello.sensors, "sensor_a": bool(hello.flags & protocol.FLAG_SENSOR_A),
            "sensor_b": bool(hello.flags & protocol.FLAG_SENSOR_B), "gyro": bool(hello.flags & protocol.FLAG_GYRO),
            "rate_hz": hello.rate_hz, "imu_kind": IMU_KINDS.get(hello.imu_kind, "unknown"),
            "accel_lsb_per_g": hello.accel_lsb_per_g, "ts_bits": hello.ts_bits, "boot_id": hello.boot_id}


def hello_summary(h: dict[str, Any]) -> str:
    """`hello_fields` in a few words: what the game will get from this board."""
    if not h["sensors"]:
        return "a board answers (HELLO) but has found no IMU yet; it says so again when it has"
    hands = {(True, True): "right and left hands", (True, False): "right hand only (sensor A)",
             (False, True): "left hand only (sensor B; the right hand will hold still)"}[(h["sensor_a"], h["sensor_b"])]
    gyro = ", gyro" if h["gyro"] else ""
    return f"a board answers (HELLO): {h['imu_kind']} IMU x{h['sensors']}, {hands}, {h['rate_hz']} Hz{gyro}"


def _open(name: str, baud: int) -> Any:
    import serial

    if "://" in name:  # a pyserial URL (socket://, rfc2217://), as `serial://` takes them
        return serial.serial_for_url(name, baudrate=baud, timeout=0)
    return serial.Serial(name, baudrate=baud, timeout=0, write_timeout=0)


def _ask(port: Any) -> None:
    """One `?` without waiting (a full output buffer just means no request this time)."""
    from firmware_bridge import protocol

    try:
        os.write(port.fileno(), protocol.HELLO_REQUEST)  # pyserial's write retries EAGAIN without end
    except (AttributeError, OSError, ValueError):
        try:
            port.write(protocol.HELLO_REQUEST)
        except Exception:  # noqa: BLE001 - any transport's refusal is only a request not sent
            pass


def probe(path: str, seconds: float = PROBE_S, baud: int = 115200) -> ProbeResult:
    """Open `path` (a device path or pyserial URL; a leading `serial://` is taken off), ask for a
    HELLO and read until one comes or `seconds` pass. Never raises for what the port does."""
    try:
        from termios import error as port_error  # what a tty's settings raise on a port gone
    except ImportError:  # not a POSIX system: pyserial's own errors only
        port_error = OSError
    import serial

    from firmware_bridge import protocol

    name = path.removeprefix("serial://")
    out = ProbeResult(path=path, url=f"serial://{name}")
    try:
        port = _open(name, baud)
    except (OSError, ValueError, serial.SerialException, port_error) as exc:
        out.result = f"cannot open it as a serial port ({exc})"
        return out
    decoder = protocol.Decoder()
    hello, lost = None, ""
    try:
        end, next_ask = time.monotonic() + seconds, 0.0
        while time.monotonic() < end and (hello is None or not hello.sensors):
            if hello is None and time.monotonic() >= next_ask:
                _ask(port)
                next_ask = time.monotonic() + ASK_EVERY_S
            data = port.read(port.in_waiting or 1)
            if not data:
                time.sleep(0.005)
                continue
            for frame in decoder.feed(data):
                out.frames += 1
                if frame.msg_type == protocol.HELLO:
                    hello = protocol.Hello(frame)
    except (OSError, serial.SerialException, port_error) as exc:
        lost = f"the port was lost while probing ({exc}): the other end closed, or the device went away"
    finally:
        try:
            port.close()
        except (OSError, serial.SerialException, port_error):
            pass
    out.bytes = decoder.bytes_in
    out.counts = {k: v for k, v in decoder.counts().items() if v and k not in ("frames_ok", "bytes_in")}
    if hello is not None:
        out.answered, out.hello = True, hello_fields(hello)
        out.result = hello_summary(out.hello)
    else:
        out.result = lost or _silence(out, seconds, baud)
    return out


def _silence(out: ProbeResult, seconds: float, baud: int) -> str:
    """Why no HELLO came, as far as the bytes tell."""
    if out.frames:
        return f"protocol v1 frames ({out.frames}) but no HELLO in {seconds:g} s: a board that does not answer `?`"
    if out.bytes:
        return (f"{out.bytes} bytes in {seconds:g} s but no protocol v1 frame: another kind of device, or one sending "
                f"at another baud rate than {baud} (a USB CDC board ignores the rate)")
    return (f"nothing in {seconds:g} s: no board there, or it is not streaming (a port another program has open "
            "may lose its bytes to it; a board that restarts when its port opens may need a longer --probe-seconds)")
