"""Adaptation to the player (beyond the paper; see engine/recognition/dual_buffer.py): a
confidently recognized whole motion joins its action's templates (TemplateSet._adopt).
Mixed into DualBufferRecognizer."""

from __future__ import annotations

import numpy as np

# Template adaptation (`_adapt`): a whole motion that fits its action better than any other
# action's template by this margin joins that action's templates; this many are kept per action.
ADAPT_MARGIN = 0.4
ADAPT_PER_ACTION = 3


class Adaptation:
    """When a motion ends: adopt it as one of its action's templates if it fits confidently."""

    def _adapt(self) -> None:
        """A player drifts from the trials the templates came from (uWave: day-1 templates, days
        2-7 tested). When a motion ends whose whole, up to where the hand stopped, fits its final
        action's template better by ADAPT_MARGIN than any other action's, it becomes one of that
        action's templates; the `adapt` most recent ones per action are kept beside the trained
        ones (the uWave paper's template adaptation, driven by confident decisions instead of
        the user's feedback). Motions ended by `character_finished()` are partial: never used."""
        n = self._stop_n if self._stopped else self.dtw.n
        if n < 2:
            return
        scores = self._stop_scores if self._stopped else self.dtw.closed_scores()
        lo, hi = int(self._action_starts[self.action]), int(self._action_ends[self.action])  # its templates
        k = lo + int(np.argmin(scores[lo:hi]))
        best, other = float(scores[k]), float(min(scores[:lo].min(initial=np.inf), scores[hi:].min(initial=np.inf)))
        if not best < (1.0 - ADAPT_MARGIN) * other or best > self.thresholds[k]:
            return
        self._adopt(self._motion[:n].copy(), self._peaks(self._acts[:n]))
