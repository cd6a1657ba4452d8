"""A hash of simulation state, to check that two runs are identical to the bit."""

from __future__ import annotations

import hashlib
from typing import Any

import numpy as np


def state_hash(*parts: Any) -> str:
    """Hex digest over arrays (dtype, shape and bytes) and plain values (their repr)."""
    h = hashlib.blake2b(digest_size=16)
    for part in parts:
        if isinstance(part, np.ndarray):
            a = np.ascontiguousarray(part)
            h.update(f"{a.dtype.str}{a.shape}".encode())
            h.update(a.tobytes())
        else:
            h.update(repr(part).encode())
        h.update(b"\x00")
    return h.hexdigest()
