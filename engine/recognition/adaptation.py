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

    def _usable(self, scores: np.ndarray) -> np.ndarray:
        """The scores the decisions see. An adopted motion brings the player's present style
        (speed, strength, grip) to its own action alone: against an action that has no adopted
        templates, a motion of that action in the present style is nearer the adopted ones (full
        blows against templates from quick punches: the one kind adopted took the others'
        punches). So an action with adopted templates is weighed against an action without them
        by the trained templates: its adopted ones are left out where its best trained template
        is worse than the best of an action without adopted ones. Among actions that both have
        them, all templates count. For switches and the end; the first decision has its own rule
        for adopted templates (rules.ADOPTED_LEAD)."""
        if not self._adapted:
            return scores
        adopted = np.zeros(len(self._action_starts), dtype=bool)
        adopted[self._tmpl_action[self._is_adapted]] = True
        if adopted.all():
            return scores
        trained = np.minimum.reduceat(np.where(self._is_adapted, np.inf, scores), self._action_starts)
        behind = adopted & (trained > trained[~adopted].min())
        if not behind.any():
            return scores
        return np.where(self._is_adapted & behind[self._tmpl_action], np.inf, scores)

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
