"""How a motion ends, for `DualBufferRecognizer` (a mixin, as DecisionRules is): at the null
signal, by the `complete` rule, or rejected at the end of its window. Its last events (a call-off
`reject`, the `end`), the gate learning from a motion that was only
noise, and the state after it: idle, or the discard of the handover (rules.HANDOVER_OVER)."""

from __future__ import annotations

from engine.recognition.events import RecognizerEvent
from engine.recognition.rules import DISCARD, IDLE


class MotionEnd:
    def _end_motion(self, complete: bool, events: list[RecognizerEvent]) -> None:
        """The motion under way ends on this frame (`complete`: by the complete rule)."""
        handover = False
        if self.action is not None and self._called_off():
            events.append(self._event("reject", self.action_names[self.action], None, called_off=True))
        elif self.action is not None:
            # the character's clip still plays: its end's discard begins now (HANDOVER_OVER)
            handover = complete and self._hands_over()
            if self.adapt and self.count <= max(self.window, self._extend_to):
                self._adapt()
            events.append(self._event("end", self.action_names[self.action], None, reason="complete" if complete else None))
        elif self.pending:
            events.append(self._event("reject", None, None))
        if self.action is None and self.gate.auto and not self._moved and self._peak_act_seen < self._action_bar.min():
            # Nothing has started yet and this motion, rejected and weaker than any template's
            # start, was noise crossing a gate set too low: its frames count as rest (a punch
            # no template matched, learnt as rest, raised the gate over every later punch).
            for a in self._acts[: min(self.dtw.n, self.window)]:
                self.gate.learn(float(a))
        self._after_peak = self._peak_act_seen if complete else 0.0
        self._begin_motion_state()
        self.state = DISCARD if handover else IDLE
        self._handover = handover

    def _hands_over(self) -> bool:
        """A decided motion ending by the `complete` rule goes into the discard (see HANDOVER_OVER):
        two or more sensors, a caller with a character, an action that has another hand."""
        return self._hands > 1 and self._has_character and any(self._other_hands[self.action])
