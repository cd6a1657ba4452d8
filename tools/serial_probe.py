"""`quickjab devices PATH...`: whether a serial IMU bridge answers on a port given by path, with
the serial protocol's HELLO (firmware_bridge/PROTOCOL.md). pyserial's port list never shows a
pty (`quickjab bridge emulate`, socat) nor a port it cannot classify, so such a port is probed
by name: opened as the `serial://` source opens it, asked for a HELLO (`?`) and read for a
while, its bytes through the protocol's own decoder. A HELLO the decoder rejects is said with
its field, and a valid one that spoils the samples (a narrow clock, a scale that makes them
implausible) with what the source will do.

pyserial, the decoder and engine.sample only (no numpy): `devices` stays light."""

from __future__ import annotations

import os
import time
from dataclasses import asdict, dataclass, field
from typing import Any

PROBE_S = 1.5  # a board answers `?` within a tick and sends a HELLO every second anyway
ASK_EVERY_S = 0.25  # as the source does: the first `?` may come before the board reads its input
SAMPLES_CHECKED = 20  # after a HELLO with a tiny scale, SAMPLEs read to see whether the source would drop them
INT16_MAX_ABS = 32768  # the largest |count| a SAMPLE holds
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
    problem: str = ""  # what keeps the game from using the board's HELLO (a refused or unusable one)

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
    hello, after, lost = None, [], ""
    try:
        hello, after = _read(port, decoder, out, seconds)
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
        out.problem = unusable(hello, after)
        out.result = hello_summary(out.hello) + (f"; but {out.problem}" if out.problem else "")
    elif decoder.bad_hello is not None:  # it answers, with a HELLO no host takes (PROTOCOL.md)
        out.problem = f"its HELLO is malformed ({decoder.bad_hello}): the source refuses it and converts no SAMPLE"
        out.result = f"a board answers (HELLO) but {out.problem}"
    else:
        out.result = lost or _silence(out, seconds, baud)
    return out


def _read(port: Any, decoder: Any, out: ProbeResult, seconds: float) -> tuple[Any, list]:
    """Ask for a HELLO and read until one naming sensors came (and, for a tiny scale, the
    SAMPLEs that tell whether the source would drop them) or `seconds` pass: the last HELLO and
    the SAMPLEs after it."""
    from firmware_bridge import protocol

    hello, after = None, []
    end, next_ask = time.monotonic() + seconds, 0.0
    while time.monotonic() < end and not _enough(hello, after):
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
                hello, after = protocol.Hello(frame), []
            elif frame.msg_type == protocol.SAMPLE and hello is not None:
                after.append(frame)
    return hello, after


def _tiny_scale(hello: Any) -> bool:
    """Counts per g so few that an int16 reaches past MAX_ACCEL_G: SAMPLEs may be dropped."""
    from engine.sample import MAX_ACCEL_G

    return MAX_ACCEL_G * hello.accel_lsb_per_g < INT16_MAX_ABS


def _enough(hello: Any, after: list) -> bool:
    return hello is not None and bool(hello.sensors) and (not _tiny_scale(hello) or len(after) >= SAMPLES_CHECKED)


def unusable(hello: Any, after: list) -> str:
    """What the serial source does with a valid HELLO that spoils the board's samples (PROTOCOL.md:
    a narrow clock, a scale that reads its counts as over MAX_ACCEL_G), or ""."""
    from engine.sample import MAX_ACCEL_G
    from firmware_bridge import protocol

    said = []
    if protocol.narrow_clock(hello.ts_bits, hello.rate_hz):
        said.append(f"ts_bits {hello.ts_bits} at {hello.rate_hz} Hz wraps t_us within two sample periods: the source takes "
                    "it (narrow_clock) but its sample times come out wrong")
    if hello.sensors and _tiny_scale(hello):
        limit = MAX_ACCEL_G * hello.accel_lsb_per_g
        over = sum(1 for f in after if any(abs(c) > limit for i, c in enumerate(f.values())
                                           if i % protocol.sample_values_per_sensor(f.flags) < 3))
        if over or not after:
            seen = f"{over} of {len(after)} SAMPLEs read" if after else "no SAMPLE came to tell; any reading"
            said.append(f"accel_lsb_per_g {hello.accel_lsb_per_g}: {seen} over {MAX_ACCEL_G:g} g, which the source drops "
                        "(implausible; an IMU gives thousands of counts per g, 4096 at +-8 g)")
    return "; ".join(said)


def _silence(out: ProbeResult, seconds: float, baud: int) -> str:
    """Why no HELLO came, as far as the bytes tell."""
    if out.frames:
        return f"protocol v1 frames ({out.frames}) but no HELLO in {seconds:g} s: a board that does not answer `?`"
    if out.bytes:
        return (f"{out.bytes} bytes in {seconds:g} s but no protocol v1 frame: another kind of device, or one sending "
                f"at another baud rate than {baud} (a USB CDC board ignores the rate)")
    return (f"nothing in {seconds:g} s: no board there, or it is not streaming (a port another program has open "
            "may lose its bytes to it; a board that restarts when its port opens may need a longer --probe-seconds)")
