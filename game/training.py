"""Train your moves: `quickjab train`.

Walks the player through the 13 actions. For each: the boxer shows the action (looping
animation), then five trials: "get ready" (the hands still, so the trial starts at rest),
"GO!" and a recording window of the active source's 60 Hz frames. Then the trials build the
player's templates (engine.recognition.Templates.from_trials, paper section III) from every
usable trial of each action (`keep="usable"`: a cut-off trial, a warm-up unlike the others and a
trial that looks like another action are dropped; keeping all the good ones beats keeping the 3
most representative, docs/recognition.md, twentieth round), saved in the user's data directory where `quickjab play` finds them from
then on. The "get ready" rest before each trial also tells the recognizer the sensor's resting
noise (its automatic gate, Templates.rest_noise).

With the keyboard source a key press (any action key, Space or Enter) performs the action being
trained with the virtual player; `keyboard://?auto=1` (and `--demo`) performs it by itself.
Left-handed players (`--left-handed`) see the animations mirrored; the templates hold their
own motions as recorded, marked left-handed so `play` does not mirror them again.
"""

from __future__ import annotations

import argparse
import os
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from engine import arguments
from engine.clock import STEP_HZ
from engine.errors import InputError, refuse_overwriting
from engine.interrupt import ends_as_ctrl_c
from engine.sensors.source import PLAYABLE, SourceState, missing_in_short, missing_part
from game.launch import (
    KEYBOARD_SOURCE,
    headless_env,
    init_pygame,
    open_on_run_clock,
    open_player_source,
    open_window,
    parse_window_size,
    save_screenshot,
)

if TYPE_CHECKING:  # pygame loads only when the screen opens (the CLI imports this module)
    import pygame

    from engine.sample import Sample

HZ = STEP_HZ
TRIALS = 5
SHOW_STEPS = 90  # the animation alone before the first trial of an action
READY_STEPS = 60  # "get ready": the hands held still
LEAD_IN = 30  # frames of the ready phase kept at the start of a trial (the rest before)
RECORD_STEPS = 96  # the recording window after GO
LOST_GIVE_UP_STEPS = 10 * HZ  # headless: a source lost this long is not coming back
NO_SAMPLE_YET = "no sample yet: connected, but nothing comes in"  # the trials wait for the first
SELF_CHECK_GOOD = 0.9  # under this share of the new trials recognized, the player is told which moves to redo

SHOW, READY, RECORD, DONE = "show", "ready", "record", "done"
# the live signal: one colour per hand (as the contact sheet: right red, left blue), x y z in
# three shades of it
TRACE_COLOURS = (((255, 150, 140), (235, 80, 70), (170, 40, 35)),
                 ((150, 190, 255), (80, 130, 240), (40, 70, 170)))

MIRROR_JOINT = {}  # joint index -> the mirrored joint's index (filled below)


def mirror_posture(posture: np.ndarray) -> np.ndarray:
    """A (17, 3) local posture seen in a mirror: x negated, left and right joints swapped."""
    from game.skeleton import JOINTS

    if not MIRROR_JOINT:
        for i, name in enumerate(JOINTS):
            other = name[:-2] + ("_r" if name.endswith("_l") else "_l") if name[-2:] in ("_l", "_r") else name
            MIRROR_JOINT[i] = JOINTS.index(other)
    out = posture[[MIRROR_JOINT[i] for i in range(len(posture))]].copy()
    out[:, 0] *= -1.0
    return out


@dataclass
class Trainer:
    """The walk through the actions, one step at a time; knows nothing about drawing."""

    actions: list[str]
    trials: int = TRIALS
    index: int = 0
    trial: int = 0
    phase: str = SHOW
    phase_step: int = 0
    recorded: dict[str, list[np.ndarray]] = field(default_factory=dict)
    _ring: list[np.ndarray] = field(default_factory=list)
    _buffer: list[np.ndarray] = field(default_factory=list)
    go: bool = False  # True on the step GO is given (the keyboard source performs then)
    dropped: dict[str, tuple[int, int]] = field(default_factory=dict)  # action -> (trials dropped, recorded)
    waiting: bool = False  # the source is away: the walk holds, the trial under way starts again
    named: bool = False  # --actions named these moves (a one-hand source then trains every one)

    @property
    def action(self) -> str:
        return self.actions[min(self.index, len(self.actions) - 1)]

    @property
    def done(self) -> bool:
        return self.phase == DONE

    def progress(self) -> float:
        total = len(self.actions) * self.trials
        return sum(len(v) for v in self.recorded.values()) / total

    def step(self, frame: np.ndarray | None, live: bool = True) -> None:
        """Advance one 60 Hz step with this step's frame (None before the source delivers);
        `live` False while the source is not connected (its frame is the last sample held)."""
        self.go = False
        if self.phase == DONE:
            return
        if not live:
            self._lose()
            return
        self.waiting = False
        self.phase_step += 1
        if frame is not None:
            if self.phase == RECORD:
                self._buffer.append(frame.copy())
            else:
                self._ring.append(frame.copy())
                del self._ring[:-LEAD_IN]
        if self.phase == SHOW and self.phase_step >= SHOW_STEPS:
            self._enter(READY)
        elif self.phase == READY and self.phase_step >= READY_STEPS:
            self._buffer = list(self._ring)
            self._enter(RECORD)
            self.go = True
        elif self.phase == RECORD and self.phase_step >= RECORD_STEPS:
            if len(self._buffer) >= LEAD_IN:
                self.recorded.setdefault(self.action, []).append(np.array(self._buffer))
                self.trial += 1
            self._buffer = []
            if self.trial >= self.trials:
                self.index += 1
                self.trial = 0
                self._enter(SHOW if self.index < len(self.actions) else DONE)
            else:
                self._enter(READY)

    def _lose(self) -> None:
        """The source is away: the walk holds; a trial under way is dropped (no motion came)
        and starts again from "get ready" once the source is back."""
        self.waiting = True
        self._ring.clear()
        if self.phase in (READY, RECORD):
            self._buffer = []
            self._enter(READY)

    def _enter(self, phase: str) -> None:
        self.phase = phase
        self.phase_step = 0

    def templates(self, left_handed: bool = False, base=None, recognizer: dict | None = None):
        """The player's templates from the recorded trials. With `base` (the set in use: the
        player's file, else the defaults) only the actions trained now are replaced; the
        others are kept, so training one move never loses the rest. The recognizer settings
        saved with `base` are kept too, `recognizer`'s (`train --recognizer`) set over them."""
        from engine.recognition import Templates
        from engine.recognition.templates import usable_trials

        # keep="usable", looking for look-alikes among the moves kept from `base` too; the player
        # is told what was dropped
        kept = self.kept = usable_trials(self.recorded, others=_moves(base, left_handed))
        self.dropped = {a: (len(ts) - len(kept[a]), len(ts)) for a, ts in self.recorded.items() if len(kept[a]) < len(ts)}
        templates = Templates.from_trials(kept)
        trained = set(self.recorded)
        if base is not None:
            if base.meta.get("source") == "quickjab train":
                trained |= _trained_moves(base, left_handed)
            templates = merge_templates(base, templates, left_handed)
        templates.meta["trained"] = ",".join(sorted(trained))  # the actions that are the player's own
        templates.meta["source"] = "quickjab train"
        templates.meta["left_handed"] = "1" if left_handed else "0"
        templates.recognizer = {**(base.recognizer if base is not None else {}), **(recognizer or {})}
        return templates


def _other_hand(base, left_handed: bool) -> bool:
    """`base` was trained with the other handedness than `left_handed`."""
    return (base.meta.get("left_handed") == "1") != left_handed


def _oriented(base, left_handed: bool):
    """`base` as the player holds the sensors: a set of the other handedness mirrored (the file
    holds the player's own motions)."""
    return base.mirrored() if _other_hand(base, left_handed) else base


def _trained_moves(base, left_handed: bool) -> set[str]:
    """The moves of `base` the player trained, named as `_oriented` has them: a set of the other
    handedness is mirrored, and its straight_r is then the player's straight_l."""
    from engine.recognition.templates import mirrored_name

    names = set(filter(None, base.meta.get("trained", "").split(",")))
    return {mirrored_name(a) for a in names} if _other_hand(base, left_handed) else names


def _moves(base, left_handed: bool) -> dict[str, list[np.ndarray]]:
    """`base`'s templates by action (None: none), oriented for the player."""
    out: dict[str, list[np.ndarray]] = {}
    if base is not None:
        base = _oriented(base, left_handed)
        for action, signal in zip(base.actions, base.signals, strict=True):
            out.setdefault(action, []).append(signal)
    return out


class SelfCheckRun:
    """How well the moves trained now tell each other apart: each kept trial through the game's
    recognizer without its own template (engine/recognition/self_check.py), a trial a `step()`
    so that the training window keeps answering (the whole check blocked it 1-5 s); `finish()`
    does the rest at once. Then the console says the figure and the moves taken for others, and
    `line` is the figure in short, for the screen."""

    def __init__(self, trainer: Trainer, templates) -> None:
        from engine.recognition.self_check import SelfCheck, leave_one_out_steps
        from game.user_config import read_config

        try:  # the settings `play` runs with: the config file's [recognizer] table over the saved ones
            settings = {**templates.recognizer, **read_config().get("recognizer", {})}
        except InputError:  # a bad file: `play` says so; the check goes on with the saved settings
            settings = dict(templates.recognizer)
        new = sum(len(ts) for ts in trainer.kept.values())  # merge_templates puts them last
        self.steps = leave_one_out_steps(templates, len(templates) - new, trainer.kept, settings)
        self.check, self.total, self.done_trials, self.line = SelfCheck(), new, 0, ""
        self.done = False

    def step(self) -> None:
        """One held-out trial; the last says what was found."""
        if self.done:
            return
        try:
            self.check = next(self.steps)
            self.done_trials += 1
            self.line = f"checking your moves against each other: {self.done_trials} of {self.total}"
        except StopIteration:
            self._say()
        except (InputError, ValueError) as exc:  # saved already: a check that cannot run is no failure
            self._say(f"no self check ({exc})")

    def finish(self) -> str:
        while not self.done:
            self.step()
        return self.line

    def _say(self, failed: str = "") -> None:
        from engine.recognition.self_check import said

        self.done, check = True, self.check
        self.line = ""
        if failed:
            print(f"quickjab train: {failed}", file=sys.stderr)
            return
        for line in said(check):
            print(f"quickjab train: {line}", file=sys.stderr)
        confused = sorted({a for a, _ in check.taken_for} | {t for _, t in check.taken_for if t})
        if check.trials and check.right < SELF_CHECK_GOOD * check.trials:
            print(f"quickjab train: throw these more differently, or train them again: quickjab train --actions "
                  f"{','.join(confused)}", file=sys.stderr)
        if check.trials:
            self.line = f"{check.right} of {check.trials} trials recognized without their own template"


def merge_templates(base, new, left_handed: bool = False):
    """`base`'s templates for the actions `new` does not have, then all of `new`'s. A base of
    the other handedness is mirrored first (`_oriented`)."""
    from engine.recognition import Templates

    base = _oriented(base, left_handed)
    if base.dim != new.dim:
        return new  # another sensor layout: nothing of the old set fits
    trained = set(new.action_names)
    keep = [i for i, a in enumerate(base.actions) if a not in trained]
    return Templates(
        [base.actions[i] for i in keep] + list(new.actions),
        [base.signals[i] for i in keep] + list(new.signals),
        np.vstack([base.gravity[keep], new.gravity]),
        np.concatenate([base.onsets[keep], new.onsets]),
        np.concatenate([base.thresholds[keep], new.thresholds]),
        new.method,
        new.feature,
        {**base.meta, **new.meta},
        rest_noise=new.rest_noise,  # the gate noise measured during this training's rests
    )


class TrainingScreen:
    """Draws the trainer: the animated boxer on the left, the checklist and a live plot right."""

    def __init__(self, lib: dict, trainer: Trainer, source_url: str, left_handed: bool = False):
        from game.hud import TextCache
        from game.render import Renderer

        self.lib = lib
        self.trainer = trainer
        self.source_url = source_url
        self.left_handed = left_handed
        self.text = TextCache()
        self.renderer: Renderer | None = None
        self.history: list[np.ndarray] = []
        self.anim_frame = 0.0
        self.saved_to: str = ""
        self.missing = ""  # a part the source misses (Source.missing): the trials wait for it
        self.self_check = ""  # how well the new moves told each other apart (SelfCheckRun)
        # tests: a list to collect every text drawn (text, rectangle, panel: "stage", "list", "plot")
        self.layout: list | None = None
        self.panels: dict = {}

    def push_frame(self, frame: np.ndarray | None) -> None:
        if frame is not None:
            self.history.append(frame.copy())
            del self.history[:-150]

    def draw(self, surf: pygame.Surface) -> None:
        import pygame

        from game.camera import Camera
        from game.render import Renderer
        from game.skeleton import local_to_world

        w, h = surf.get_size()
        u = self.text.for_window(h)
        stage = pygame.Rect(0, 0, int(w * 0.58), h)
        if self.renderer is None or self.renderer.camera.size != stage.size:
            self.renderer = Renderer(stage.size)
            self.renderer.camera = Camera(stage.size, eye=(2.2, 2.2, 3.6), target=(0.0, 0.95, 0.0), fov_deg=40)
        tr = self.trainer
        clip = self.lib[tr.action]
        # SHOW loops the move; READY holds the guard; RECORD plays it in time with GO
        if tr.phase == SHOW:
            self.anim_frame = (self.anim_frame + 1) % (clip.frames + 20)
        elif tr.phase == READY:
            self.anim_frame = 0
        else:
            self.anim_frame = tr.phase_step
        posture = clip.posture(min(self.anim_frame, clip.frames - 1))
        if self.left_handed:
            posture = mirror_posture(posture)
        root = clip.root_offset(min(self.anim_frame, clip.frames - 1))
        body = local_to_world(posture, (float(root[0]), float(root[1]), float(root[2])))
        sub = surf.subsurface(stage)
        self.renderer.draw(sub, [body])
        # right panel: the checklist, the progress and the live signal
        self.panels = {"stage": stage}
        self._checklist(surf, pygame.Rect(stage.right, 0, w - stage.right, h), u)
        # the instruction over the stage
        self._instruction(surf, stage, u)

    def _checklist(self, surf: pygame.Surface, panel: pygame.Rect, u: float) -> None:
        """The actions with their trials, the progress bar and the live plot, in `panel`. Its text
        stops shrinking at game.hud_style's minimum, and so does its layout."""
        import pygame

        from game.hud import action_label
        from game.hud_style import text_scale

        h = surf.get_height()
        tr = self.trainer
        self.panels["list"] = panel
        pygame.draw.rect(surf, (18, 18, 26), panel)
        u0, u = u, text_scale(u)
        x = panel.left + int(24 * u)
        title, size = self.text.fit("TRAIN YOUR MOVES", int(40 * u), panel.right - x - int(8 * u))  # a window narrow for its height
        self._text(surf, title, size, (x, 20 * u), (242, 240, 232))
        source, size = self.text.fit(f"source {self.source_url}" + ("   left-handed" if self.left_handed else ""), int(20 * u),
                                     panel.right - x - int(8 * u))
        self._text(surf, source, size, (x, 58 * u), (170, 166, 160))
        y = 88 * u
        row = 24 * max(u0, 0.75)  # the checklist's line (18 px at least: its 16 px text and a gap)
        for i, a in enumerate(tr.actions):
            done = len(tr.recorded.get(a, []))
            current = i == tr.index and not tr.done
            col = (255, 200, 40) if current else ((90, 220, 120) if done >= tr.trials else (200, 196, 190))
            self._text(surf, action_label(a), int(row), (x + 18 * u, y), col)
            for k in range(tr.trials):
                c = (int(x + 190 * u + k * 16 * u), int(y + 9 * u))
                pygame.draw.circle(surf, (90, 220, 120) if k < done else (70, 70, 80), c, int(5 * u))
            if current:
                pygame.draw.polygon(surf, col, [(x, y + 3 * u), (x + 10 * u, y + 9 * u), (x, y + 15 * u)])
            y += row
        # progress bar
        bar = pygame.Rect(x, int(y + 10 * u), panel.width - int(48 * u), int(12 * u))
        pygame.draw.rect(surf, (60, 60, 70), bar)
        pygame.draw.rect(surf, (90, 220, 120), (bar.left, bar.top, int(bar.width * tr.progress()), bar.height))
        # live signal plot
        plot = pygame.Rect(x, bar.bottom + int(16 * u), bar.width, h - bar.bottom - int(30 * u))
        self._plot(surf, plot, int(row * 2 / 3))  # the legend two thirds of the checklist's size

    def _instruction(self, surf: pygame.Surface, stage: pygame.Rect, u: float) -> None:
        import pygame

        from game.hud import action_label

        tr = self.trainer
        if tr.waiting and self.missing:
            short, then = missing_in_short(self.missing)
            title, sub = short.upper(), f"{then or 'waiting for it'}: the trial starts again when it is back"
        elif tr.waiting:
            title, sub = "SOURCE LOST", "waiting for it: the trial starts again when it is back"
        elif tr.done:
            title, sub = "ALL DONE", (f"templates saved to {self.saved_to}" if self.saved_to else "building templates...")
            # the figure first: a line too long for the window loses the middle of the path, not it
            sub = f"{self.self_check}; {sub}" if self.self_check else sub
        elif tr.phase == SHOW:
            title, sub = action_label(tr.action).upper(), "watch the move, then throw it as you will in a fight"
        elif tr.phase == READY:
            secs = int(np.ceil((READY_STEPS - tr.phase_step) / HZ))
            title, sub = f"GET READY {secs}", f"trial {tr.trial + 1} of {tr.trials}: hold your guard still"
        else:
            title, sub = "GO!", f"trial {tr.trial + 1} of {tr.trials}: {action_label(tr.action)}"
        col = (255, 200, 40) if tr.phase == RECORD else (242, 240, 232)
        title, size = self.text.fit(title, int(64 * u), stage.width - int(16 * u))  # a window narrow for its height
        img = self.text.render(title, size, col)
        self._put(surf, img, img.get_rect(midtop=(stage.centerx, int(24 * u))), title, "stage")
        sub, size = self.text.fit(sub, int(26 * u), stage.width - int(16 * u))  # a long saved-to path
        img2 = self.text.render(sub, size, (220, 216, 210))
        self._put(surf, img2, img2.get_rect(midtop=(stage.centerx, int(24 * u) + img.get_height() + 4)), sub, "stage")
        if tr.phase == RECORD:
            pygame.draw.circle(surf, (235, 50, 50), (int(stage.left + 30 * u), int(stage.bottom - 30 * u)), int(10 * u))
            self._text(surf, "REC", int(26 * u), (stage.left + 46 * u, stage.bottom - 40 * u), (235, 50, 50), "stage")

    def _plot(self, surf: pygame.Surface, rect: pygame.Rect, legend_px: int = 16) -> None:
        import pygame

        pygame.draw.rect(surf, (10, 10, 14), rect)
        self.panels["plot"] = rect
        if rect.height < 20:
            return
        mid = rect.centery
        pygame.draw.line(surf, (50, 50, 60), (rect.left, mid), (rect.right, mid))
        if len(self.history) < 2:
            return
        data = np.array(self.history)
        xs = rect.left + np.arange(len(data)) * rect.width / 149.0
        for d in range(min(6, data.shape[1])):
            ys = mid - np.clip(data[:, d] / 3.0, -1, 1) * rect.height * 0.45
            pygame.draw.lines(surf, TRACE_COLOURS[d // 3][d % 3], False, np.stack([xs, ys], axis=1).tolist(), 2)
        # the legend in each hand's colour: its three axes are shades of it (x light, z dark)
        x = rect.left + 6
        hands = ("right hand x y z", "left hand x y z")[: max(1, data.shape[1] // 3)]  # a one-hand source: one
        for hand, name in enumerate(hands):  # a Wiimote and Nunchuk, or IMUs
            img = self.text.render(name, legend_px, TRACE_COLOURS[hand][1])
            self._put(surf, img, img.get_rect(topleft=(x, rect.top + 4)), name, "plot")
            x += img.get_width() + legend_px

    def _text(self, surf: pygame.Surface, text: str, size: int, pos, color, panel: str = "list") -> None:
        img = self.text.render(text, size, color)
        self._put(surf, img, img.get_rect(topleft=(int(pos[0]), int(pos[1]))), text, panel)

    def _put(self, surf: pygame.Surface, img: pygame.Surface, rect: pygame.Rect, text: str, panel: str) -> None:
        surf.blit(img, rect)
        if self.layout is not None:
            self.layout.append((text, rect, panel))


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("train", help="Train your moves: record 5 trials of each action, build your templates from the usable ones",
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--source", default=None, help="source URL (default: the first Wiimote, else the keyboard)")
    p.add_argument("--demo", action="store_true", help="the virtual player performs every move by itself")
    p.add_argument("--left-handed", action="store_true", help="mirror the animations for a left-handed player")
    p.add_argument("--actions", default=None,
                   help="comma-separated subset of actions (default: all 13); the others keep the templates you have")
    p.add_argument("--reset", action="store_true",
                   help="delete your trained templates (play goes back to the default set) and exit")
    p.add_argument("-o", "--output", default=None, type=arguments.path_argument, help="where to save the templates (default: your data directory)")
    p.add_argument("--profile", default=None, metavar="NAME", help="save as this player's templates (`play --profile NAME`; default: your default set)")
    p.add_argument("--headless", action="store_true", help="no window: SDL dummy driver, virtual clock (a live serial:// or wiimote:// device: the real clock)")
    p.add_argument("--frames", type=arguments.positive_int, default=None, help="stop after N rendered frames")
    p.add_argument("--screenshot", type=arguments.image_file, metavar="PNG", help="save the last frame to this PNG")
    p.add_argument("--seed", type=arguments.seed, default=0, help="seed of the virtual player's moves (default 0)")
    p.add_argument("--size", default="1280x720", help="window size WxH (default 1280x720; under 640x360 the text is hard to read)")
    p.add_argument("--recognizer", action="append", default=[], metavar="NAME=VALUE",
                   help="a recognizer setting to save with your templates, e.g. noise_g=0.5 (repeatable; "
                        "docs/recognition.md); the settings your file already holds are kept")
    p.set_defaults(func=run)


def base_templates(output: Path):
    """The set newly trained actions are merged into: the file being written if it exists,
    else the default set `play` uses without one (merge_templates mirrors it if needed)."""
    from engine.recognition import Templates
    from game.session import synthesized_templates
    from game.userdata import SHIPPED_TEMPLATES

    if output.exists():
        return Templates.load(output)
    return Templates.load(SHIPPED_TEMPLATES) if SHIPPED_TEMPLATES.exists() else synthesized_templates()


def _keep_aside(output: Path, sensors: int) -> Path | None:
    """The player's own set at `output`, for `sensors` sensors, moved to a file beside it named
    for that count before a set of another width replaces it (nothing of it could be merged:
    a one-hand source's training would lose the moves trained with two). None: no file."""
    if not output.exists():
        return None  # the default set: nothing of the player's is lost
    aside = output.with_name(f"{output.stem}-{sensors}-sensors{output.suffix}")
    n = 1
    while aside.exists():  # one moved aside before (2 -> 1 -> 2 -> 1 sensors): keep both
        n += 1
        aside = output.with_name(f"{output.stem}-{sensors}-sensors-{n}{output.suffix}")
    os.replace(output, aside)
    return aside


def _kept_elsewhere(templates, output: Path, exc: Exception) -> tuple[Path, str]:
    """A session's moves whose file cannot be written when its trials are done (the folder
    removed or made read-only meanwhile, a full disk): saved in the temporary directory, not
    lost; (that file, the line train ends with). A failure there too is the first error."""
    import tempfile

    name = ""
    try:
        fd, name = tempfile.mkstemp(prefix="quickjab-templates-", suffix=".npz")
        os.close(fd)
        templates.save(name)
    except (OSError, InputError):
        if name:
            Path(name).unlink(missing_ok=True)
        raise exc from None
    why = exc if isinstance(exc, InputError) else f"{output}: cannot save the templates ({exc.strerror or exc})"
    return Path(name), f"{why}; your moves are saved in {name} instead (play --templates {name}, or move it there)"


def reset_templates(path: Path, named: bool = False) -> int:
    """`train --reset`: remove the player's templates; `play` uses the default set again. The
    data directory's file (the default set, a profile's) is removed even when it no longer loads
    (what --reset is for); a file named with -o (`named`) only if it is a template set: a typo
    (`-o notes.txt`) must not delete a document or a recording."""
    from engine.recognition import Templates

    if path.is_dir():
        raise InputError(f"{path}: a directory; --reset removes a templates file, not removed")
    if not os.path.lexists(path):
        print(f"quickjab train: no trained templates at {path}; play already uses the default set", file=sys.stderr)
        return 0
    if named:
        try:
            Templates.load(path)
        except InputError as exc:
            raise InputError(f"{exc}; not removed (-o names a template set)") from None
    path.unlink()
    print(f"quickjab train: removed {path}; play uses the default templates again", file=sys.stderr)
    return 0


def _chosen_actions(args: argparse.Namespace) -> list[str]:
    """--actions, checked against the library's names (all of them by default)."""
    from game.actions import ACTION_NAMES

    actions = list(ACTION_NAMES)
    if args.actions is not None:
        actions = [a.strip() for a in args.actions.split(",") if a.strip()]
        if not actions:  # `--actions ,` ended in an IndexError traceback, `--actions ""` trained all 13
            raise InputError(f"--actions {args.actions!r}: names no action; known: {', '.join(ACTION_NAMES)}")
        unknown = [a for a in actions if a not in ACTION_NAMES]
        if unknown:
            raise InputError(f"--actions: unknown {', '.join(unknown)}; known: {', '.join(ACTION_NAMES)}")
    return actions


def _open_source(args: argparse.Namespace, clock):
    """The player's source, said on the console; (source, playable, auto): whether a virtual
    player behind it performs the moves, and whether it does so by itself. `--demo` without
    `--source` is the virtual player (keyboard://): it never looks for a Wiimote, which would
    train from the Wiimote instead when one is connected."""
    url = KEYBOARD_SOURCE if args.demo and args.source is None else args.source
    source, fallback = open_player_source(url, False, args.seed, clock.seconds)
    if args.demo:
        print("quickjab train: demo: the virtual player performs every move by itself", file=sys.stderr)
    elif fallback:
        print(f"quickjab train: {fallback}: training from the keyboard (press a key to perform)", file=sys.stderr)
    from engine.recording import say_notes

    say_notes(source.file_notes, "train")  # a replayed recording's row left out (a cut last row)
    playable = PLAYABLE in source.capabilities  # a virtual player performs the moves
    auto = args.demo or (playable and bool(source.auto))
    if playable:
        source.auto = False  # the trainer decides when the virtual player performs
    return source, playable, auto


def _output(args: argparse.Namespace) -> Path:
    """The templates file train saves (--reset removes): -o, else --profile's set, else the
    default player's. --profile with -o is said ignored, not silently dropped."""
    from game.userdata import profile_templates_path

    if args.output:
        if getattr(args, "profile", None) is not None:
            print("quickjab train: --profile ignored with -o: -o names the templates file", file=sys.stderr)
        note = arguments.backslash_note(args.output)
        if note:
            print(f"quickjab train: -o {note}", file=sys.stderr)
        return Path(args.output)
    return profile_templates_path(getattr(args, "profile", None))  # None: the default player's


def _check_files(args: argparse.Namespace, output: Path) -> None:
    """Before the session, not when its trials are done (minutes of a player's moves lost): the
    templates file can be written, and read if it is there (the set the new moves join); no
    output over an input or over another output."""
    import os

    from engine.recognition import Templates
    from engine.sensors.source import url_file

    replayed = url_file(args.source) if args.source else None
    refuse_overwriting({"--screenshot": args.screenshot}, [output, replayed])
    refuse_overwriting({"-o": output, "--screenshot": args.screenshot}, [replayed])
    try:
        output.exists()
    except OSError as exc:  # a name too long for the file system (ENAMETOOLONG): said with whose name it is
        whose = "" if args.output else " (the data directory: $XDG_DATA_HOME/quickjab, else ~/.local/share/quickjab)"
        raise InputError(f"{output}: cannot save the templates there: {exc.strerror}{whose}") from None
    if output.is_dir():
        raise InputError(f"{output}: a directory; the templates are saved to a file (-o FILE.npz)")
    if output.exists():
        theirs = Templates.load(output)  # not a template file: said now
        was_left = theirs.meta.get("left_handed") == "1"
        if theirs.meta.get("source") == "quickjab train" and _other_hand(theirs, bool(args.left_handed)):
            print(f"quickjab train: your set at {output} was trained {'left' if was_left else 'right'}-handed; it is "
                  f"saved mirrored for the {'right' if was_left else 'left'} hand"
                  + (" (--left-handed keeps it left-handed)" if was_left else ""), file=sys.stderr)
        return
    folder = next(p for p in output.absolute().parents if p.exists())  # the rest is created on saving
    if not folder.is_dir():
        raise InputError(f"{output}: cannot save the templates there: {folder} is not a directory")
    if not os.access(folder, os.W_OK | os.X_OK):
        raise InputError(f"{output}: cannot save the templates there: cannot write in {folder}")


def _open_window(args: argparse.Namespace, size: tuple[int, int], source) -> None:
    import pygame

    init_pygame(sound=False)  # training plays no sound
    try:
        open_window(size, pygame.RESIZABLE, args.headless, "train")
    except InputError:
        source.close()
        pygame.quit()
        raise
    pygame.display.set_caption("QuickJab - Train your moves")


class _TrainingStages:
    """`quickjab train`'s stages on the loop: input (keys, the source's samples -> this step's
    frame) and train (the trainer, saving the templates when it is done), and the render."""

    def __init__(self, loop, source, playable: bool, auto: bool, trainer: Trainer, screen_view: TrainingScreen,
                 resampler, t0: float, output: Path, left_handed: bool, settings: dict):
        self.loop, self.source, self.playable, self.auto = loop, source, playable, auto
        self.trainer, self.screen_view, self.resampler, self.t0 = trainer, screen_view, resampler, t0
        self.output, self.left_handed, self.settings = output, left_handed, settings
        self.frame = None
        self.lost_steps = 0  # steps since the source was last connected
        self.had_all = False  # the source has sent every sensor the trials read (once connected)
        self.sized = False  # the trials' width set from the source's first sample
        self.checking: SelfCheckRun | None = None  # the saved moves checked against each other
        self.give_up_after: int | None = None  # headless: stop when lost this long (no one to wait for it)
        self.stopped_why = ""  # why the walk stopped before its end (the source ended, or never came back)
        self.unsaved = ""  # the output could not be written: where the moves are instead (exit 2)

    def perform(self) -> None:
        # the virtual player behind the keyboard has no handedness: it performs the move itself
        if self.playable:
            self.source.press(self.trainer.action)

    def input(self, step: int, dt: float) -> None:
        import pygame

        for event in pygame.event.get():
            if event.type == pygame.QUIT or (event.type == pygame.KEYDOWN and event.key == pygame.K_ESCAPE):
                self.loop.stop()
            elif event.type == pygame.KEYDOWN and self.trainer.phase in (READY, RECORD):
                self.perform()
        samples = self.source.poll()
        if samples and not self.sized:
            self._size_to(samples[0])
        self.resampler.push(samples)
        self.frame = self.resampler.frame_at(self.t0 + step * dt)

    def _size_to(self, first: Sample) -> None:
        """The trials take the width of the first sample the source sends. A one-hand source (one
        IMU on the bridge, a one-hand replay) was read as two sensors, the second held still, and
        `play` refused the saved set with that source; now it trains one-hand moves `play` takes.
        (A serial board's sensor count is only a guess until its HELLO, and its samples wait for
        the HELLO.) A source that later sends fewer sensors than that is waited for
        (`_source_live`)."""
        self.sized = True
        sensors = np.size(first.accel) // 3
        if sensors >= 1 and 3 * sensors != self.resampler.dim:
            from engine.frames import FrameResampler

            self.resampler = FrameResampler(sensors=sensors)
        left = [a for a in self.trainer.actions if a.endswith("_l")]
        if sensors == 1 and left and not self.trainer.named and not self.trainer.recorded:
            # the one sensor is the right hand (docs/sources.md): trials of the left hand's moves
            # would be flat, saved as templates and then named by the self check as moves to redo
            self.trainer.actions = [a for a in self.trainer.actions if a not in left]
            print(f"quickjab train: one sensor, the right hand: the left hand's moves are left out ({', '.join(left)}); "
                  "--actions trains them anyway", file=sys.stderr)

    def train(self, step: int, dt: float) -> None:
        trainer = self.trainer
        was_done = trainer.done
        live = self._source_live()
        if self.stopped_why:
            self.loop.stop()
            return
        trainer.step(self.frame, live)
        self.screen_view.push_frame(self.frame if live else None)
        if trainer.go and self.auto:
            self.perform()
        if trainer.done and not was_done:
            self.save()
        elif self.checking is not None and not self.checking.done:  # a held-out trial a step
            self.checking.step()
            self.screen_view.self_check = self.checking.line

    def walk_over(self) -> bool:
        """Every trial recorded, the moves saved and checked (a headless run stops here, so its
        screenshot shows the figure)."""
        return self.trainer.done and self.checking is not None and self.checking.done

    def _source_live(self) -> bool:
        """Whether the source delivers now; a source that ended (a replay played out), or that a
        headless run has waited for too long, stops the walk before anything is saved."""
        state, want = self.source.state, self.resampler.dim // 3
        # a trial without the Nunchuk (or with a sensor the board lost) would hold that hand
        # still in the template: it waits for the part as for a lost source. Fewer sensors count
        # only once the source has sent all (a one-hand source trains as it always did), as its
        # count says once known: a serial board's guess (2) before its HELLO is not that
        self.had_all |= state == SourceState.CONNECTED and self.source.sensors_known and self.source.sensors >= want
        missing = missing_part(self.source, want if self.had_all else None)
        if not missing and state == SourceState.CONNECTED and not self.sized:
            # connected with no sample yet (a serial board's port opened, its HELLO not come):
            # waited for as a missing part, said on the screen (the trials went round empty)
            missing = NO_SAMPLE_YET
        self.screen_view.missing = missing
        live = state == SourceState.CONNECTED and not missing
        self.lost_steps = 0 if live else self.lost_steps + 1
        if self.trainer.done:
            return live
        if state == SourceState.ENDED:
            self.stopped_why = "the source ended"
        elif self.give_up_after is not None and self.lost_steps > self.give_up_after:
            waited = f"{self.lost_steps / HZ:.0f} s"
            missing = missing_in_short(self.screen_view.missing)[0]
            self.stopped_why = f"{missing} (waited {waited})" if missing else f"the source was lost for {waited}"
        return live

    def save(self) -> None:
        """The trials done: build the player's templates, save them, say what was dropped."""
        trainer, output = self.trainer, self.output
        base = base_templates(output)
        templates = trainer.templates(self.left_handed, base=base, recognizer=self.settings)
        if base is not None and base.dim != templates.dim:
            aside = _keep_aside(output, base.dim // 3)
            print(f"quickjab train: the moves you had were for {base.dim // 3} sensor(s), these trials have "
                  f"{templates.dim // 3}: only the moves trained now are kept"
                  + (f"; yours for {base.dim // 3} sensor(s) are kept in {aside} (play --templates {aside})" if aside else ""),
                  file=sys.stderr)
        try:
            output.parent.mkdir(parents=True, exist_ok=True)
            templates.save(output)
        except (OSError, InputError) as exc:  # writable at the start (_check_files), not now
            output, self.unsaved = _kept_elsewhere(templates, output, exc)
        self.screen_view.saved_to = str(output)
        for action, (n, of) in trainer.dropped.items():
            print(f"quickjab train: {action}: dropped {n} of {of} trials (cut off, unlike the others, or like another move)",
                  file=sys.stderr)
        print(f"quickjab train: saved {len(templates)} templates to {output}", file=sys.stderr)
        self.checking = SelfCheckRun(trainer, templates)  # over the next steps (train)

    def render(self, alpha: float) -> None:
        import pygame

        self.screen_view.draw(pygame.display.get_surface())
        pygame.display.flip()


@ends_as_ctrl_c  # before pygame starts: SDL made SIGTERM a closed window
def run(args: argparse.Namespace) -> int:
    size = parse_window_size(args.size, args.headless, "train")
    from engine.recognition.config import parse_assignments
    from game.actions import load_library

    settings = parse_assignments(getattr(args, "recognizer", None) or ())

    if args.reset:  # --profile NAME resets NAME's set
        return reset_templates(_output(args), named=bool(args.output))
    actions = _chosen_actions(args)
    output = _output(args)
    _check_files(args, output)
    if args.headless:
        headless_env()
    import pygame

    from engine.frames import FrameResampler
    from engine.loop import FixedStepLoop

    clock, (source, playable, auto) = open_on_run_clock("train", args.headless, lambda c: _open_source(args, c),
                                                        lambda opened: [opened[0]])
    lib = load_library()
    trainer = Trainer(actions, named=bool(args.actions))
    _open_window(args, size, source)
    screen_view = TrainingScreen(lib, trainer, source.url, args.left_handed)
    resampler = FrameResampler(sensors=2)
    t0 = clock.seconds()
    loop = FixedStepLoop(clock)
    stages = _TrainingStages(loop, source, playable, auto, trainer, screen_view, resampler, t0, output,
                             args.left_handed, settings)
    if args.headless:
        stages.give_up_after = LOST_GIVE_UP_STEPS
    loop.add_stage("input", stages.input, 0.3)
    loop.add_stage("train", stages.train, 1.0)
    loop.set_render(stages.render, 8.0)
    try:
        loop.run(frames=args.frames, until=lambda: stages.walk_over() and args.frames is None and args.headless)
    finally:
        try:
            if args.screenshot:
                save_screenshot(args.screenshot)
                print(f"quickjab train: wrote {args.screenshot}", file=sys.stderr)
        finally:
            source.close()
            pygame.quit()
    if stages.stopped_why:
        n = sum(len(v) for v in trainer.recorded.values())
        raise InputError(f"{source.url}: {stages.stopped_why} after {n} trial{'' if n == 1 else 's'}; nothing saved")
    if stages.checking is not None:
        stages.checking.finish()  # closed before the check was through: the rest at once
    if stages.unsaved:
        raise InputError(stages.unsaved)
    if not trainer.done:
        print(f"quickjab train: stopped after {sum(len(v) for v in trainer.recorded.values())} trials; nothing saved", file=sys.stderr)
    return 0
