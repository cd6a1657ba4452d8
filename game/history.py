"""A log that keeps only its recent past: the session's recognizer events and blows.

An hour of play is ~12,000 recognizer events; kept as dicts they are ~5 MB of a heap that only
grows (`quickjab soak` measured it). The tests and the HUD need the recent ones and the state
hash needs all of them, so the log keeps the last `maxlen` items, counts every item appended and
folds each one's key into a running digest that the state hash uses instead of the items.
"""

from __future__ import annotations

import hashlib
from collections import deque
from collections.abc import Callable
from typing import Any


class History(deque):
    """deque(maxlen) of the most recent items + `total` appended + a running `digest()`."""

    def __init__(self, maxlen: int, key: Callable[[Any], Any] = lambda item: item):
        super().__init__(maxlen=maxlen)
        self.total = 0
        self._key = key
        self._hash = hashlib.blake2b(digest_size=16)

    def append(self, item: Any) -> None:
        super().append(item)
        self.total += 1
        self._hash.update(repr(self._key(item)).encode())
        self._hash.update(b"\x00")

    def digest(self) -> str:
        """Hex digest over the keys of every item ever appended, in order."""
        return self._hash.hexdigest()
