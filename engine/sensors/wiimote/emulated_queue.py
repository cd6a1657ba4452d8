"""Input reports on their way from the emulated remote to the host, and the host's buffer:
Linux's hidraw keeps 64 reports per reader, and when nobody reads the newest are lost."""

from __future__ import annotations

import heapq
from dataclasses import dataclass, field
from typing import Any

HOST_BUFFER = 64  # Linux hidraw keeps 64 reports per reader


@dataclass(order=True)
class _Pending:
    due: float
    seq: int
    data: bytes = field(compare=False)
    sent: Any = field(compare=False, default=None)  # the emulator's SentData record, if a data report


class ReportQueue:
    """Reports by the time they reach the host (then in the order sent); each padded to `pad`
    bytes when shorter (0: no padding). `count(key)` counts the reports lost to a full buffer."""

    def __init__(self, pad: int, count) -> None:
        self.pad = pad
        self.count = count
        self._queue: list[_Pending] = []
        self._seq = 0

    def push(self, data: bytes, due: float, sent: Any = None) -> None:
        if self.pad and len(data) < self.pad:
            data = data + bytes(self.pad - len(data))
        self._seq += 1
        heapq.heappush(self._queue, _Pending(due, self._seq, data, sent))

    def drop_all(self) -> None:
        """The link went down: everything in flight is lost (data reports marked dropped)."""
        for item in self._queue:
            if item.sent is not None:
                item.sent.dropped = True
        self._queue.clear()

    def pop(self, now: float) -> bytes | None:
        """The next report the host has received by `now`, or None."""
        if not self._queue or self._queue[0].due > now:
            return None
        due_count = sum(1 for item in self._queue if item.due <= now)
        if due_count > HOST_BUFFER:  # the buffer filled while nobody read: newest lost
            keep = heapq.nsmallest(HOST_BUFFER, (i for i in self._queue if i.due <= now))
            lost = [i for i in self._queue if i.due <= now and i not in keep]
            for item in lost:
                if item.sent is not None:
                    item.sent.dropped = True
                self.count("overflow")
            self._queue = [i for i in self._queue if i.due > now] + keep
            heapq.heapify(self._queue)
        item = heapq.heappop(self._queue)
        if item.sent is not None:
            item.sent.read_at = now
        return item.data
