"""Set-up scripts: generators that yield the reply they wait for (a `Wait`), driven one reply
per poll by a `ScriptRunner`, so the slow parts of a Wiimote's set-up never block the loop."""

from __future__ import annotations

from collections.abc import Callable, Generator
from typing import Any

from engine.sensors.wiimote import protocol as p

REPLY_TIMEOUT_S = 0.15  # a live Wiimote answers within a few tens of ms
REPLY_RETRIES = 2


class ReplyTimeout(Exception):
    """Thrown into a script when the reply it waits for does not come in time."""


class DeviceGone(Exception):
    """A write failed: the connection is already marked lost."""


class SetupFailed(Exception):
    """A script gave up (no reply after retries)."""


class Wait:
    """What a script waits for: a report matching `match`, within `timeout` seconds."""

    __slots__ = ("match", "timeout")

    def __init__(self, match: Callable[[p.Report], bool], timeout: float = REPLY_TIMEOUT_S):
        self.match = match
        self.timeout = timeout


Script = Generator[Wait, Any, Any]


class ScriptRunner:
    """Runs one script at a time: hands it the report it waits for, or a ReplyTimeout when its
    time is up. `send(report)` writes (raising DeviceGone on a lost link), `count(key)` counts,
    `on_failed(now, reason)` is told when a script gives up."""

    def __init__(self, send: Callable[[bytes], None], count: Callable[[str], None],
                 on_failed: Callable[[float, str], None]) -> None:
        self.send = send
        self.count = count
        self.on_failed = on_failed
        self.script: Script | None = None
        self.wait: Wait | None = None
        self.deadline = 0.0

    @property
    def running(self) -> bool:
        return self.script is not None

    def start(self, script: Script, now: float) -> None:
        self.script = script
        self.advance(now, None)

    def stop(self) -> None:
        self.script = None
        self.wait = None

    def advance(self, now: float, value: Any, error: BaseException | None = None) -> None:
        script = self.script
        if script is None:
            return
        try:
            wait = script.throw(error) if error is not None else script.send(value)
        except (StopIteration, DeviceGone):  # done, or the connection is already marked lost (or closed)
            if self.script is script:
                self.stop()
            return
        except SetupFailed as exc:
            self.count("setup_failures")
            self.on_failed(now, str(exc))
            return
        if self.script is script:
            self.wait = wait
            self.deadline = now + wait.timeout

    def offer(self, rep: p.Report, now: float) -> None:
        """A report arrived: the script goes on if it was the one it waits for."""
        if self.wait is not None and self.wait.match(rep):
            self.wait = None
            self.advance(now, rep)

    def expire(self, now: float) -> None:
        """The awaited reply is late: throw ReplyTimeout into the script."""
        if self.wait is not None and now >= self.deadline:
            self.wait = None
            self.advance(now, None, ReplyTimeout())

    # ---- what scripts wait for ----------------------------------------------------------

    def request(self, report: bytes, match: Callable[[p.Report], bool], what: str) -> Script:
        for _ in range(REPLY_RETRIES + 1):
            self.send(report)
            try:
                return (yield Wait(match))
            except ReplyTimeout:
                self.count("timeouts")
        raise SetupFailed(f"no reply to {what}")

    def write_register(self, address: int, data: bytes) -> Script:
        """Write and wait for the 0x22 ack; returns its error code."""
        rep = yield from self.request(
            p.build_write(address, data),
            lambda r: r.report_id == p.IN_ACK and r.acked_report == p.OUT_WRITE_MEMORY,
            f"write at {address:06X}",
        )
        return rep.error

    def read_memory(self, address: int, size: int) -> Script:
        """Read `size` bytes in 16-byte replies; returns the bytes, or None on a read error."""
        for _ in range(REPLY_RETRIES + 1):
            buf = bytearray()
            self.send(p.build_read(address, size))
            try:
                while len(buf) < size:
                    offset = (address + len(buf)) & 0xFFFF
                    rep = yield Wait(lambda r, o=offset: r.report_id == p.IN_READ_REPLY and r.address == o)
                    if rep.error:
                        self.count("read_errors")
                        return None
                    buf += rep.payload
                return bytes(buf[:size])
            except ReplyTimeout:
                self.count("timeouts")
        raise SetupFailed(f"no reply to a read at {address:06X}")
