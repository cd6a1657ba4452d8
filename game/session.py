"""A game session: every part of a match wired into the FixedStepLoop's stages.

The stages, their order, budgets (ms; issue 9 holds the loop to them and the F3 overlay shows
them) and the session state each reads and writes are one table, game/stages.py; each runs as
the method `_<name>(step, dt)` here. Once per rendered frame the view (game/session_view.py)
draws the ring, the bodies interpolated with alpha and the HUD (render, 8 ms; 4 in low power).
The attract mode's player is game/pilot.py; the HUD reads typed snapshots of the match and the
source (game/hud.py).

Nothing here reads a clock except through the loop's: with a VirtualClock and a seed a session
is reproducible to the bit (`state_hash`).
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pygame

from engine.clock import STEP_HZ, RealClock, VirtualClock
from engine.errors import InputError
from engine.frames import FrameResampler
from engine.loop import FixedStepLoop
from engine.sensors.source import KEYS, REWIND, Source, SourceState
from game.difficulty import DifficultySetting
from game.history import History
from game.hits import Hit
from game.hud import Hud, HudState, SourceSnapshot
from game.interaction import OpponentController, Situation
from game.match import Match

# the attract mode's pilot (game/pilot.py), the shared rules (game/rules.py), the stage table
# (game/stages.py) and the view (game/session_view.py); their names stay importable from here
from game.pilot import PILOT_ATTACKS, PILOT_REACH, PILOT_SETTLE_STEPS, DemoPilot  # noqa: F401
from game.render import Renderer
from game.render_low_power import LowPowerRenderer
from game.ring import DEMO_RESTART_STEPS, KNOCKDOWN_HOLD, Ring  # noqa: F401
from game.rules import (  # noqa: F401
    BLOCKED_SHARE,
    BLOW_SCALE,
    REFERENCE_SPEED,
    RING_LIMIT,
    START_GAP,
    blow_damage,
)
from game.session_view import LOW_POWER_SCALE, SessionView  # noqa: F401
from game.stages import STAGE_BUDGETS_MS, wire

HZ = STEP_HZ
RENDER_BUDGET_MS = 8.0
LOW_POWER_RENDER_BUDGET_MS = 4.0
# The CPU reads the situation from a solved table: how often it takes the best action, how late
# it sees the situation, its rest between moves and how much its blows count are its difficulty
# (game/difficulty.py), so that a human (whose moves wait for the recognizer) has a fair fight.
HOME_BUTTON = 0x0080  # Wiimote core buttons: Home
RUMBLE_MS = 120
# the states in which a source delivers nothing: the match pauses under the lost-source overlay.
# One that ended (a replay played out) does not come back by itself: the match stays paused
# (before, it went on as if the player stood still) until Enter plays a replay again (REWIND)
LOST_STATES = (SourceState.DISCONNECTED, SourceState.RECONNECTING, SourceState.CONNECTING, SourceState.ENDED)


def say_if_ended(source: Source, was_lost: bool) -> None:
    """The console's line when a source has just ended: a headless run shows no overlay."""
    if source.state == SourceState.ENDED and not was_lost:
        then = "Enter in the window plays it again" if REWIND in source.capabilities else "nothing more to play"
        print(f"quickjab play: {source.url}: the source ended ({then}); the match is paused", file=sys.stderr)


def can_play_again(source: Source) -> bool:
    """Whether `source` ended and can play again from its start (a replay played out): Enter,
    offered on the SOURCE ENDED overlay, rewinds it and starts a new match."""
    return source.state == SourceState.ENDED and REWIND in source.capabilities


def enter_starts_match(match: Match, sources: list[Source]) -> bool:
    """Whether Enter starts a new match now: after the last bell, or under SOURCE ENDED when
    the source can play again (a replay), and in both only when no source that cannot play again
    is away: the new match would wait for it, a rewound replay playing out unseen under the pause
    (and under that seat's box, which does not offer Enter, it reset the match; after the last
    bell too, where the box hides "Enter: a new match")."""
    lost = [source for source in sources if source.state in LOST_STATES]
    return (match.over or bool(lost)) and all(map(can_play_again, lost))


def rewind_ended(sources: list[Source]) -> None:
    """A new match plays the replays again from their start once one has played out (else it
    would pause at once under SOURCE ENDED): every replay, so that two players' replays start
    together again (rewinding only the one that ended left the other where it was)."""
    if any(map(can_play_again, sources)):
        for source in sources:
            if REWIND in source.capabilities:
                source.rewind()


def hold_keys(source: Source, paused: bool) -> None:
    """A key pressed in the step Esc paused the match: its move, not begun yet, waits for the
    resume (`KeyboardSource.held`) instead of being made under the pause, which finishes it."""
    if KEYS in source.capabilities:
        source.held = paused


def pause_on_home(source, held: int, session) -> int:
    """Toggle the pause when the source's Home button goes down (a press, not a hold: `held` is
    the buttons held at the last poll), through `session.toggle_pause()` (which keeps a match
    paused for a lost source paused); returns the buttons held now."""
    buttons = int(source.buttons or 0)
    if buttons & HOME_BUTTON and not held & HOME_BUTTON:
        session.toggle_pause()
    return buttons


@dataclass
class SessionConfig:
    seed: int = 0
    size: tuple[int, int] = (1280, 720)
    low_power: bool = False
    demo: bool = False
    keyboard_banner: bool = False
    templates: str | Path | None = None  # None: the player's trained ones, else the shipped set
    graph: str | Path | None = None
    sound: bool = True
    physics_iterations: int = 4
    left_handed: bool = False
    difficulty: str = "normal"  # easy | normal | hard | adaptive (game/difficulty.py)
    render: bool = True  # False: no render stage (headless benchmarks and reproducibility tests)
    # recognizer settings over those saved with the templates: the user's config file's, then
    # the command line's (game/user_config.py); {}: the templates' own, else the defaults
    recognizer: dict = field(default_factory=dict)


def synthesized_templates(seed: int = 0, trials: int = 3):
    """Templates from the virtual player's trials (3 per action, fixed seed): what a fresh
    install plays with when no template file is shipped or trained (~0.2 s to build)."""
    from engine.recognition import Templates
    from game.actions import ACTION_NAMES, load_library
    from game.virtual_player import synthesize_action

    lib = load_library()
    rng = np.random.default_rng(seed)
    return Templates.from_trials({
        a: [synthesize_action(lib[a], "experienced", rng, rest_before=20, rest_after=20).reshape(-1, 6)
            for _ in range(trials)]
        for a in ACTION_NAMES
    })


def load_templates(path: str | Path | None = None, left_handed: bool = False):
    """The player's own templates (Train your moves), else the shipped set, else templates
    built from the virtual player. Left-handed players (Wiimote in the left hand) get the
    mirror image of a right-handed set; their own trained set is used as it is."""
    from engine.recognition import Templates
    from engine.xdg import is_there
    from game.userdata import SHIPPED_TEMPLATES, user_templates_path

    if path is not None:
        templates = Templates.load(path)
    elif is_there(user_templates_path()):  # a data dir that cannot be looked at has none
        templates = Templates.load(user_templates_path())
    elif SHIPPED_TEMPLATES.exists():
        templates = Templates.load(SHIPPED_TEMPLATES)
    else:
        templates = synthesized_templates()
    if left_handed and templates.meta.get("left_handed") != "1":
        templates = templates.mirrored()
    return templates


def templates_in_use(path: str | Path | None = None) -> str:
    """What `load_templates(path)` loads, said for the HUD and the console: the player has to
    know when a trained set (perhaps of a few moves) is in play, and how to go back."""
    from engine.xdg import is_there
    from game.userdata import user_templates_path

    if path is not None:
        profile = _profile_of(Path(path))
        if profile is None:
            return f"templates {Path(path).name}"
        return f"your templates ({profile}: {_moves_trained(Path(path))}; `quickjab train --reset --profile {profile}` for the defaults)"
    if is_there(user_templates_path()):
        return f"your templates ({_moves_trained(user_templates_path())}; `quickjab train --reset` for the defaults)"
    return "default templates"


def _profile_of(path: Path) -> str | None:
    """The player whose trained set `path` is (`train --profile NAME`'s file), else None."""
    from game.userdata import profile_templates_path

    name = path.stem
    try:
        return name if path.absolute() == profile_templates_path(name).absolute() else None
    except InputError:  # not a profile's name
        return None


def _moves_trained(path: Path) -> str:
    """How many moves of the set at `path` the player trained: "all moves", "2 of 13 moves"."""
    from engine.recognition import Templates
    from game.actions import ACTION_NAMES

    try:
        trained = [a for a in Templates.load(path).meta.get("trained", "").split(",") if a]
    except InputError:
        trained = []
    return f"{len(trained)} of {len(ACTION_NAMES)} moves" if trained and len(trained) < len(ACTION_NAMES) else "all moves"


def load_graph(path: str | Path | None = None, lib: dict | None = None):
    """The Interaction Graph: `path`, else the shipped table, else one cached in the user's
    data directory, else a small one built now (~3 s) and cached there. A match needs the
    policy and the look-up, not the edges: they stay compressed in the file. A graph built from
    another action library than `lib` (default the game's) is a GraphFileError naming the file
    before the match (its first look-up of an action the library lacks raised KeyError); a
    cached one is built again."""
    import sys

    from game.actions import load_library
    from game.interaction import DEFAULT_GRAPH
    from game.userdata import data_dir

    lib = load_library() if lib is None else lib
    if path is not None:
        return _graph_for(path, lib)
    if DEFAULT_GRAPH.exists():
        return _graph_for(DEFAULT_GRAPH, lib)
    cached = data_dir() / "graph-small.npz"
    why = f"no shipped Interaction Graph; building a small one in {cached} (once)"
    if cached.is_file():
        try:
            return _graph_for(cached, lib)
        except InputError as exc:  # a cache: a broken or stale one (cut short, a disk error) is built again
            why = f"{exc}; building it again"
    from game.interaction.build import BuildParams, build_graph

    print(f"quickjab: {why}", file=sys.stderr)  # one line: the first build, or a broken cache's
    cached.parent.mkdir(parents=True, exist_ok=True)
    build_graph(lib, BuildParams(states=3000, bouts=256)).save(cached)
    return _graph_for(cached, lib)


def _graph_for(path: str | Path, lib: dict):
    """The graph at `path` (policy and look-up), refused when built from another library than `lib`."""
    from game.interaction import GraphFileError, InteractionGraph

    graph = InteractionGraph.load(path, edges=False)
    why = graph.library_mismatch(lib)
    if why is not None:
        raise GraphFileError(f"{path}: {why}")
    return graph


LOG_KEPT = 1024  # recent recognizer events / blows kept in memory (an hour makes ~7,000-12,000 events)


def _event_key(ev: dict) -> tuple:
    """What of a recognizer event the state hash covers: its decision, not its scores."""
    return (ev.get("frame"), ev.get("event"), ev.get("action"), ev.get("from_frame"))


class Session(Ring):
    """Build with a source and a surface to draw on; `loop.run(...)` plays."""

    def __init__(self, source: Source, config: SessionConfig | None = None,
                 clock: RealClock | VirtualClock | None = None,
                 surface_provider: Callable[[], pygame.Surface] | None = None):
        from game.sound import Sounds

        self.config = cfg = config or SessionConfig()
        self.clock = clock or RealClock()
        self.source = source
        self._build_ring(cfg)
        self.graph = load_graph(cfg.graph, self.lib)
        self.difficulty = DifficultySetting(cfg.difficulty)
        self._rest_next = self.difficulty.current.rest_steps  # its rest after the move it plays
        self.opponent_ai = OpponentController(self.graph, self.lib, controller=self.opponent.controller,
                                              rng=np.random.default_rng(cfg.seed + 2))
        self._cpu_rest = 0
        self._over_steps = 0
        self.pilot = DemoPilot(self.graph, self.lib, np.random.default_rng(cfg.seed + 1))
        self._build_recognition(cfg, source)
        self.match = Match()
        self._rounds_seen = 0
        self.hud_state = self._new_hud_state(cfg, source)
        self._apply_difficulty()
        hud = Hud()
        self.sounds = Sounds(enabled=cfg.sound, seed=cfg.seed)
        # low power: flat shading (game/render_low_power.py: half the render time of detailed=False)
        renderer = LowPowerRenderer(cfg.size) if cfg.low_power else Renderer(cfg.size)
        self.view = SessionView(cfg.size, cfg.low_power, renderer, hud, surface_provider)
        self.on_toggle_fullscreen: Callable[[], None] | None = None
        self._t0: float | None = None
        self._buttons = 0
        self._auto_paused = False
        self._step = 0
        self.loop = self._build_loop(STAGE_BUDGETS_MS)
        self.sounds.play("bell")

    def _build_recognition(self, cfg: SessionConfig, source: Source) -> None:
        """Templates, the recognizer and the resampler for this source; the event logs."""
        from engine.recognition import DualBufferRecognizer
        from engine.recognition.config import layered

        self.templates = load_templates(cfg.templates, cfg.left_handed)
        if source.sensors_known and source.sensors * 3 != self.templates.dim:  # else its HELLO will say (missing_part)
            raise InputError(f"{source.url}: the source has {source.sensors} sensor(s), the templates need "
                             f"{self.templates.dim // 3} (a Wiimote + Nunchuk, or two IMUs); train moves for this source: "
                             f"quickjab train --source {source.url}")
        self.recognizer = DualBufferRecognizer.from_config(self.templates, layered(self.templates.recognizer, cfg.recognizer))
        self.resampler = FrameResampler(sensors=self.templates.dim // 3)
        # recognizer events and blows (step, attacker, target, blocked, damage), in order: the
        # recent ones kept (tests, HUD), all of them counted and in the state hash (game/history.py)
        self.events_log: History = History(LOG_KEPT, key=_event_key)
        self.blows_log: History = History(LOG_KEPT)

    def _new_hud_state(self, cfg: SessionConfig, source: Source) -> HudState:
        rec = self.recognizer
        hud = HudState(source=SourceSnapshot(url=source.url), keyboard_banner=cfg.keyboard_banner,
                       demo=cfg.demo, mode="LOW POWER" if cfg.low_power else "",
                       main_size=int(rec.main) if rec.main != "auto" else 6, supp_size=rec.supplementary,
                       message="ROUND 1", templates=templates_in_use(cfg.templates))
        if KEYS in source.capabilities:
            from game.keyboard_source import key_help

            hud.keys = key_help(source.keymap)  # keyboard://?keys=left: that half
        return hud

    def _build_loop(self, budgets_ms: dict[str, float]) -> FixedStepLoop:
        """The fixed-step loop with the stages of game/stages.py, each against its budget."""
        cfg = self.config
        loop = FixedStepLoop(self.clock, hz=HZ, render_hz=HZ // 2 if cfg.low_power else HZ)
        wire(loop, self, budgets_ms)
        if cfg.render:
            loop.set_render(self.render, LOW_POWER_RENDER_BUDGET_MS if cfg.low_power else RENDER_BUDGET_MS)
        return loop

    def templates_lines(self) -> list[str]:
        """Which template set is in use, for the console (the HUD shows it under the source)."""
        return [self.hud_state.templates]

    # -- stages (game/stages.py) ---------------------------------------------------------
    def _input(self, step: int, dt: float) -> None:
        if pygame.display.get_init():
            for event in pygame.event.get():
                self.handle_event(event)
                self.redraw()
        if self.config.demo:
            self.pilot.step(self.source, self.match.fighting, self.player, self.opponent)
        hold_keys(self.source, self.match.paused)
        samples = self.source.poll()
        self._buttons = pause_on_home(self.source, self._buttons, self)
        self.resampler.push(samples)
        self._watch_connection()

    def _watch_connection(self) -> None:
        """A lost source pauses the match; back, the recognizer learns gravity afresh."""
        disconnected = self.source.state in LOST_STATES
        say_if_ended(self.source, self.hud_state.disconnected)
        if disconnected:
            if not self.match.paused:  # held every step (a new match under the overlay too)
                self.match.toggle_pause()
                self._auto_paused = True
        elif not disconnected and self.hud_state.disconnected:
            # back: the controller may sit differently in the hand; learn gravity afresh
            self.recognizer.reset()
            if self._auto_paused and self.match.paused:
                self.match.toggle_pause()
            self._auto_paused = False
        self.hud_state.disconnected = disconnected

    def handle_event(self, event: pygame.event.Event) -> None:
        if event.type == pygame.QUIT:
            self.loop.stop()
        elif event.type == pygame.KEYDOWN:
            if event.key == pygame.K_ESCAPE:
                self.toggle_pause()
            elif event.key == pygame.K_F3:
                self.hud_state.show_budget = not self.hud_state.show_budget
            elif event.key == pygame.K_F11:
                if self.on_toggle_fullscreen is not None:
                    self.on_toggle_fullscreen()
            elif event.key == pygame.K_RETURN and enter_starts_match(self.match, self.sources()):
                self.new_match()
            elif event.key == pygame.K_d and (self.match.paused or self.match.over):
                if not self.source_lost():  # the pause menu; not shown under the lost-source overlay
                    self.cycle_difficulty()
            elif KEYS in self.source.capabilities and not self.match.paused:
                self.source.press_key(pygame.key.name(event.key))

    def toggle_pause(self) -> None:
        """Esc or Home: pause, or resume; not while a source is lost: the overlay says the match
        resumes when it is back (resumed under it, the clock ran and the CPU boxed on)."""
        if not (self.match.paused and self.source_lost()):
            self.match.toggle_pause()

    def source_lost(self) -> bool:
        """Whether the player's source is away (the lost-controller overlay is up)."""
        return self.hud_state.disconnected

    def sources(self) -> list[Source]:
        """The players' sources (one here; a seat's each with two players)."""
        return [self.source]

    def _frames(self, step: int, dt: float) -> None:
        if self._t0 is None:
            # the step grid is anchored when the loop starts, not when the session was built
            # (loading takes a moment; anchoring earlier would read the sensors that late)
            self._t0 = self.clock.seconds() - step * dt
        self.frame_vec = self.resampler.frame_at(self._t0 + step * dt)

    def _recognize(self, step: int, dt: float) -> None:
        if self.frame_vec is None:
            return
        events = self.recognizer.push(self.frame_vec, t=step * dt)
        for ev in events:
            self.events_log.append(ev)
            self.pilot.saw(ev)
            self.hud_state.mark(ev)
            self._act_on(0, self.recognizer, ev)
        rec = self.recognizer
        active = rec.state == "active"
        self.hud_state.main_fill = min(rec.count, self.hud_state.main_size) if active else 0
        self.hud_state.supp_fill = min(rec.count, rec.supplementary) if active else 0

    def _player(self, step: int, dt: float) -> None:
        if self.match.paused:
            return  # the pause freezes the ring (Ring._physics)
        self._hold_knockdown(0)
        ox, oz, _ = self.opponent.root
        self.player.turn_towards(ox, oz)
        self.player.keep_inside(RING_LIMIT)
        self.player.step(dt)
        if self.player.controller.finished_action():
            self.recognizer.character_finished()

    def _apply_difficulty(self) -> None:
        d = self.difficulty.current
        self.opponent_ai.set_policy(d.best_share, d.reaction_steps)
        self.hud_state.difficulty = self.difficulty.label

    def cycle_difficulty(self) -> None:
        """The pause menu's D: the next difficulty, from now on."""
        self.difficulty = self.difficulty.next()
        self._apply_difficulty()

    def _opponent(self, step: int, dt: float) -> None:
        if self.match.paused:
            return  # its clip and its rest wait with the match (the rest ran on under the pause)
        self._hold_knockdown(1)
        if self.match.fighting:
            me, them = self.opponent.controller, self.player.controller
            situation = Situation.from_roots(self.opponent.root, me.action, me.frame,
                                             self.player.root, them.action, them.frame)
            if self._cpu_rest > 0:
                self._cpu_rest -= 1
                self.opponent_ai.observe(situation)  # its reaction delay reads these later
            else:
                d = self.difficulty.current
                lead = self.match.round_damage[1] - self.match.round_damage[0]
                self.opponent_ai.best_share, self._rest_next = d.eased(lead)
                self.opponent_ai.decide(situation)
        elif self._cpu_rest > 0:
            self._cpu_rest -= 1
        px, pz, _ = self.player.root
        self.opponent.turn_towards(px, pz)
        self.opponent.keep_inside(RING_LIMIT)
        self.opponent.step(dt)
        if self.opponent.controller.finished_action():
            self._cpu_rest = self._rest_next

    def damage_of(self, hit: Hit) -> float:
        """A blow's damage (blow_damage), the CPU's scaled by its difficulty."""
        damage = blow_damage(hit)
        if hit.attacker == 1:
            damage *= self.difficulty.current.damage
        return damage

    def rumble(self, target: int) -> None:
        """The boxer who was hit: its player feels it (the CPU has no controller)."""
        if target == 0:
            self.source.rumble(RUMBLE_MS)

    def _rounds_over(self, m: Match) -> None:
        """Each round decided since the last step: the adaptive difficulty follows the player."""
        while self._rounds_seen < len(m.round_winners):
            winner = m.round_winners[self._rounds_seen]
            self._rounds_seen += 1
            self.difficulty.round_over(0 if winner is None else (1 if winner == 0 else -1))
            self._apply_difficulty()

    def _show_sources(self) -> None:
        """The HUD's snapshot of the source: URL, state, battery, a part it misses."""
        self.hud_state.source = SourceSnapshot.of(self.source, sensors=self.resampler.dim // 3)

    def new_match(self) -> None:
        """A fresh match (Enter after the last bell or under SOURCE ENDED; by itself in the
        attract mode)."""
        rewind_ended(self.sources())
        self.difficulty.form.abandon_round()  # mid-round (Enter under SOURCE ENDED): not the player's blows
        self.match = Match()
        self._rounds_seen = 0
        self._over_steps = 0
        self._to_corners()
        self.recognizer.reset()
        self.pilot.settle()
        self.hud_state.message, self.hud_state.message_age = "ROUND 1", 0
        self.sounds.play("bell")

