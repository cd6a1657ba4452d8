"""Per-frame features: templates.features() for one frame, into a reused buffer. DualBufferRecognizer
owns one (`self.frame_features`), of its templates' feature kind."""

from __future__ import annotations

import numpy as np

from engine.recognition.templates import LOG_SCALE_G, grip_features


class FrameFeatures:
    """One frame in the recognizer's feature space (the same values as templates.features())."""

    def __init__(self, kind: str, dim: int):
        self.kind = kind
        self._out = np.empty(dim)

    def of(self, x: np.ndarray, g0: np.ndarray | None) -> np.ndarray:
        """Frame `x` (gravity included) as features; `g0` is the onset's gravity ("dynamic",
        "grip"). The buffer is reused: copy it to keep it."""
        out = self._out
        if self.kind == "log":
            np.abs(x, out=out)
            out *= 1.0 / LOG_SCALE_G
            np.log1p(out, out=out)
            np.copysign(out, x, out=out)
        elif self.kind == "dynamic":
            np.subtract(x, g0, out=out)
        elif self.kind == "grip":
            out[:] = grip_features(x[None], g0)[0]
        else:
            out[:] = x
        return out
