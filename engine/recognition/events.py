"""What the recognizer decides: one typed event per decision (docs/formats.md, "Recognizer events").

`to_dict()` is the JSON-lines form, key for key and in the same order as the contract. The event
also reads like that dict (`ev["action"]`, `ev.get("from_frame", 0)`, `"score" in ev`), so code
written against the dicts keeps working; new code reads the attributes."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from engine.recognition.speed import SpeedEstimate

# The flags an event may carry, each only when true (one at most per event).
FLAGS = ("reason", "late", "called_off")


@dataclass(frozen=True, slots=True)
class RecognizerEvent:
    """`event` is start, switch, end or reject; `action` the action decided (None for a reject of
    a motion nothing fitted); `frame` the recognizer's frame count when it was decided."""

    event: str
    action: str | None
    frame: int
    t: float | None = None  # the frame's time stamp, when push() was given one
    from_frame: int | None = None  # switch: the clip frames the character has already played (n_p)
    score: float | None = None  # start, switch and score-rejects: the best template's DTW score
    speed: float | None = None  # start and switch: the motion estimate so far
    direction: tuple[float, float, float] | None = None
    peak_g: float | None = None
    onset_frame: int | None = None
    reason: str | None = None  # end: "complete" or "character_finished"
    late: bool = False  # start: decided after the main buffer (the supplementary buffer)
    called_off: bool = False  # reject: a started motion that never reached its action's strength

    def to_dict(self) -> dict[str, Any]:
        """The JSON-lines form: event, action, frame, then each field that is set, in contract order."""
        out: dict[str, Any] = {"event": self.event, "action": self.action, "frame": self.frame}
        if self.t is not None:
            out["t"] = self.t
        if self.from_frame is not None:
            out["from_frame"] = self.from_frame
        if self.score is not None:
            out["score"] = self.score
        if self.event in ("start", "switch"):
            out["speed"] = self.speed
            out["direction"] = list(self.direction or ())
            out["peak_g"] = self.peak_g
            out["onset_frame"] = self.onset_frame
        for name in FLAGS:
            value = getattr(self, name)
            if value:
                out[name] = value
        return out

    @classmethod
    def decided(cls, kind: str, action: str | None, frame: int, t: float | None, score: float | None,
                speed: SpeedEstimate, onset_frame: int, from_frame: int | None = None, **flags: Any) -> RecognizerEvent:
        """The recognizer's event, rounded as the contract writes it; a start or switch carries
        the motion estimate (`speed`) and the onset so far."""
        motion = kind in ("start", "switch")
        return cls(
            kind, action, frame,
            t=None if t is None else round(float(t), 4),
            from_frame=None if from_frame is None else int(from_frame),
            score=None if score is None else round(score, 5),
            speed=round(speed.peak_speed, 3) if motion else None,
            direction=tuple(round(v, 3) for v in speed.peak_dir) if motion else None,
            peak_g=round(speed.peak_g, 3) if motion else None,
            onset_frame=onset_frame if motion else None,
            **flags,
        )

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> RecognizerEvent:
        """The event a JSON line describes (the inverse of to_dict). `whole_motion`, which files
        written before the twenty-eighth round may hold on a `switch`, is no event field now."""
        fields = dict(d)
        fields.pop("whole_motion", None)
        if fields.get("direction") is not None:
            fields["direction"] = tuple(fields["direction"])
        return cls(**fields)

    # -- read like the dict ----------------------------------------------------------------------
    def __getitem__(self, key: str) -> Any:
        return self.to_dict()[key]

    def __contains__(self, key: object) -> bool:
        return key in self.to_dict()

    def get(self, key: str, default: Any = None) -> Any:
        return self.to_dict().get(key, default)

    def __iter__(self):
        return iter(self.to_dict())

    def __len__(self) -> int:
        return len(self.to_dict())

    def keys(self):
        return self.to_dict().keys()

    def items(self):
        return self.to_dict().items()
