"""The session's stages: the one table of what runs each 60 Hz step, in order, with its budget
and the session state it reads and writes. Adding a stage is one row here and the session's
method of the same name (`_<name>(step, dt)`); `wire` registers them all with the loop, so the
order, the budgets (issue 9 holds the loop to them; F3 shows them) and the wiring cannot drift
apart. tests/game/test_stages.py checks that every stage reads only what an earlier stage (or
the session's set-up) provides and that the names are the session's own attributes.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

from engine.loop import FixedStepLoop


@dataclass(frozen=True)
class StageSpec:
    name: str
    budget_ms: float
    reads: tuple[str, ...]  # session attributes the stage reads
    writes: tuple[str, ...]  # session attributes it changes (what later stages may read)
    does: str


STAGES: tuple[StageSpec, ...] = (
    StageSpec("input", 0.30, ("source", "match"), ("resampler", "match", "hud_state"),
              "pygame events (keys, pause, F3, F11), the demo pilot, source.poll() into the resampler, "
              "Home and a lost source pause"),
    StageSpec("frames", 0.10, ("resampler",), ("frame_vec",),
              "samples -> this step's 60 Hz frame (engine.frames.FrameResampler)"),
    StageSpec("recognize", 1.00, ("frame_vec", "match"), ("events_log", "boxers", "hud_state"),
              "the frame through the dual-buffer recognizer -> the player controller's events"),
    StageSpec("player", 0.50, ("boxers", "match"), ("boxers",),
              "player controller + body targets; tells the recognizer when a clip ended"),
    StageSpec("opponent", 0.50, ("boxers", "match"), ("boxers",),
              "Interaction Graph look-up when at the guard; opponent body targets"),
    StageSpec("physics", 3.00, ("boxers", "match"), ("contacts", "curr_joints"),
              "Verlet step of both bodies, contacts (none under the pause: the ring stands still)"),
    StageSpec("hits", 0.20, ("contacts", "boxers"), ("match", "blows_log", "boxers"),
              "contacts -> blows (referee) -> damage, reactions, flashes, sound, rumble"),
    StageSpec("match", 0.10, ("match", "source"), ("match", "boxers", "hud_state"),
              "round clock, count, winner; the HUD's snapshot of the match and the source"),
)
STAGE_BUDGETS_MS: dict[str, float] = {s.name: s.budget_ms for s in STAGES}
# what the session provides before the first stage runs (built in __init__)
SESSION_INPUTS = ("source", "match", "resampler", "boxers", "hud_state")


def wire(loop: FixedStepLoop, owner: object, budgets_ms: Mapping[str, float] = STAGE_BUDGETS_MS) -> None:
    """Register every stage of STAGES, in order, as `owner._<name>` against its budget."""
    for spec in STAGES:
        loop.add_stage(spec.name, getattr(owner, f"_{spec.name}"), budgets_ms[spec.name])
