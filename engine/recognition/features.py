"""Per-frame features: templates.features() for one frame, into a reused buffer. Mixed into
DualBufferRecognizer (its `feature`, `_feat` buffer and the onset gravity `_g0`)."""

from __future__ import annotations

import numpy as np

from engine.recognition.templates import LOG_SCALE_G, grip_features


class FrameFeatures:
    """One frame in the recognizer's feature space."""

    def _features(self, x: np.ndarray) -> np.ndarray:
        """templates.features() for one frame, into a reused buffer (same values)."""
        out = self._feat
        if self.feature == "log":
            np.abs(x, out=out)
            out *= 1.0 / LOG_SCALE_G
            np.log1p(out, out=out)
            np.copysign(out, x, out=out)
        elif self.feature == "dynamic":
            np.subtract(x, self._g0, out=out)
        elif self.feature == "grip":
            out[:] = grip_features(x[None], self._g0)[0]
        else:
            out[:] = x
        return out
