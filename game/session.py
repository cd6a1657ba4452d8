"""A game session: every part of a match wired into the FixedStepLoop's stages.

Stages, in order each 60 Hz step, with their declared budgets (ms; issue 9 holds the loop to
them and the F3 overlay shows them):

    input      0.30  pygame events (keys, pause, F3, F11), source.poll()
    frames     0.10  samples -> this step's 60 Hz frame (engine.frames.FrameResampler)
    recognize  1.00  the frame through the dual-buffer recognizer -> player controller events
    player     0.50  player controller + body targets; tells the recognizer when a clip ended
    opponent   0.50  Interaction Graph look-up when at the guard; opponent body targets
    physics    3.00  Verlet step of both bodies, contacts
    hits       0.20  contacts -> blows (referee) -> damage, reactions, flashes, sound, rumble
    match      0.10  round clock, count, winner; HUD state
    render     8.00  (once per rendered frame) ring, bodies interpolated with alpha, HUD

Nothing here reads a clock except through the loop's: with a VirtualClock and a seed a session
is reproducible to the bit (`state_hash`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pygame

from engine.clock import STEP_HZ, RealClock, VirtualClock
from engine.errors import InputError
from engine.frames import FrameResampler
from engine.loop import FixedStepLoop
from engine.sensors.source import Source, SourceState
from engine.state_hash import state_hash
from game.difficulty import DifficultySetting
from game.history import History
from game.hits import Hit, hits_from_contacts
from game.hud import Hud, HudState
from game.interaction import OpponentController, Situation
from game.match import Match
from game.render import Renderer
from game.render_low_power import LowPowerRenderer

# the shared rules (game/rules.py); BLOCKED_SHARE, BLOW_SCALE, REFERENCE_SPEED and blow_damage
# stay importable from here
from game.rules import (  # noqa: F401
    BLOCKED_SHARE,
    BLOW_SCALE,
    REFERENCE_SPEED,
    RING_LIMIT,
    START_GAP,
    blow_damage,
)

HZ = STEP_HZ
STAGE_BUDGETS_MS = {
    "input": 0.30, "frames": 0.10, "recognize": 1.00, "player": 0.50, "opponent": 0.50,
    "physics": 3.00, "hits": 0.20, "match": 0.10,
}  # fmt: skip
RENDER_BUDGET_MS = 8.0
LOW_POWER_RENDER_BUDGET_MS = 4.0
LOW_POWER_SCALE = 0.5  # the low-power mode renders at half size and scales up
# The CPU reads the situation from a solved table: how often it takes the best action, how late
# it sees the situation, its rest between moves and how much its blows count are its difficulty
# (game/difficulty.py), so that a human (whose moves wait for the recognizer) has a fair fight.
HOME_BUTTON = 0x0080  # Wiimote core buttons: Home
RUMBLE_MS = 120
DEMO_RESTART_STEPS = 8 * HZ  # the attract mode shows the result, then boxes again
PILOT_SETTLE_STEPS = 90  # the pilot's hands rest first: the recognizer learns gravity at rest
PILOT_VARIETY = 0.4
# how the virtual player boxes, by its profile (keyboard://?profile=...): how often it picks a
# move other than the graph's best for its side, and the steps its hands rest between motions
PILOT_STYLE = {"experienced": (PILOT_VARIETY, 12), "novice": (PILOT_VARIETY, 12)}
PILOT_REACH = 1.0
PILOT_ATTACKS = ("straight_l", "straight_r", "hook_l", "hook_r", "uppercut_l", "uppercut_r", "block", "step_left", "step_right")
KNOCKDOWN_HOLD = 0.55  # the fraction of the knockdown clip held while the referee counts


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
    from game.userdata import SHIPPED_TEMPLATES, user_templates_path

    if path is not None:
        templates = Templates.load(path)
    elif user_templates_path().exists():
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
    from engine.recognition import Templates
    from game.actions import ACTION_NAMES
    from game.userdata import user_templates_path

    if path is not None:
        return f"templates {Path(path).name}"
    if user_templates_path().exists():
        try:
            trained = [a for a in Templates.load(user_templates_path()).meta.get("trained", "").split(",") if a]
        except InputError:
            trained = []
        mine = f"{len(trained)} of {len(ACTION_NAMES)} moves" if trained and len(trained) < len(ACTION_NAMES) else "all moves"
        return f"your templates ({mine}; `quickjab train --reset` for the defaults)"
    return "default templates"


def load_graph(path: str | Path | None = None):
    """The Interaction Graph: `path`, else the shipped table, else one cached in the user's
    data directory, else a small one built now (~3 s) and cached there. A match needs the
    policy and the look-up, not the edges: they stay compressed in the file."""
    import sys

    from game.interaction import DEFAULT_GRAPH, InteractionGraph
    from game.userdata import data_dir

    if path is not None:
        return InteractionGraph.load(path, edges=False)
    if DEFAULT_GRAPH.exists():
        return InteractionGraph.load(DEFAULT_GRAPH, edges=False)
    cached = data_dir() / "graph-small.npz"
    if not cached.exists():
        from game.actions import load_library
        from game.interaction.build import BuildParams, build_graph

        print(f"quickjab: no shipped Interaction Graph; building a small one in {cached} (once)", file=sys.stderr)
        cached.parent.mkdir(parents=True, exist_ok=True)
        build_graph(load_library(), BuildParams(states=3000, bouts=256)).save(cached)
    return InteractionGraph.load(cached, edges=False)


LOG_KEPT = 1024  # recent recognizer events / blows kept in memory (an hour makes ~7,000-12,000 events)


def _event_key(ev: dict) -> tuple:
    """What of a recognizer event the state hash covers: its decision, not its scores."""
    return (ev.get("frame"), ev.get("event"), ev.get("action"), ev.get("from_frame"))


class Session:
    """Build with a source and a surface to draw on; `loop.run(...)` plays."""

    def __init__(self, source: Source, config: SessionConfig | None = None,
                 clock: RealClock | VirtualClock | None = None,
                 surface_provider: Callable[[], pygame.Surface] | None = None):
        from engine.physics import World
        from engine.recognition import DualBufferRecognizer
        from game.actions import load_library
        from game.boxer import Boxer
        from game.sound import Sounds

        self.config = cfg = config or SessionConfig()
        self.clock = clock or RealClock()
        self.source = source
        self.lib = load_library()
        self.world = World(gravity=(0.0, -9.81, 0.0), ground_y=0.0, damping=0.01,
                           iterations=max(1, cfg.physics_iterations // (2 if cfg.low_power else 1)))
        self.boxers = (Boxer(self.world, self.lib, x=0.0, z=-START_GAP / 2, yaw=0.0),
                       Boxer(self.world, self.lib, x=0.0, z=START_GAP / 2, yaw=math.pi))
        self.player, self.opponent = self.boxers
        graph = load_graph(cfg.graph)
        self.graph = graph
        self.difficulty = DifficultySetting(cfg.difficulty)
        self._rest_next = self.difficulty.current.rest_steps  # its rest after the move it plays
        self.opponent_ai = OpponentController(graph, self.lib, controller=self.opponent.controller,
                                              rng=np.random.default_rng(cfg.seed + 2))
        self._pilot_wait = PILOT_SETTLE_STEPS
        self._cpu_rest = 0
        self._over_steps = 0
        self._pilot_seen = True
        self._pilot_rng = np.random.default_rng(cfg.seed + 1)
        self.templates = load_templates(cfg.templates, cfg.left_handed)
        if source.sensors * 3 != self.templates.dim:
            raise InputError(f"{source.url}: the source has {source.sensors} sensor(s), the templates need "
                             f"{self.templates.dim // 3} (a Wiimote + Nunchuk, or two IMUs)")
        self.recognizer = DualBufferRecognizer(self.templates)
        self.resampler = FrameResampler(sensors=self.templates.dim // 3)
        self.match = Match()
        self.hud_state = HudState(keys=[], source_url=source.url, keyboard_banner=cfg.keyboard_banner,
                                  demo=cfg.demo, mode="LOW POWER" if cfg.low_power else "",
                                  main_size=int(self.recognizer.main) if self.recognizer.main != "auto" else 6,
                                  supp_size=self.recognizer.supplementary)
        self.hud_state.message = "ROUND 1"
        self.hud_state.templates = templates_in_use(cfg.templates)
        self._apply_difficulty()
        self._rounds_seen = 0
        if hasattr(source, "press_key"):
            from game.keyboard_source import key_help

            self.hud_state.keys = key_help(getattr(source, "keymap", None))  # keyboard://?keys=left: that half
        self.hud = Hud()
        self.sounds = Sounds(enabled=cfg.sound, seed=cfg.seed)
        # low power: flat shading (game/render_low_power.py: half the render time of detailed=False)
        self.renderer = LowPowerRenderer(cfg.size) if cfg.low_power else Renderer(cfg.size)
        self._surface_provider = surface_provider
        self._offscreen: pygame.Surface | None = None
        self._low_power_surface: pygame.Surface | None = None
        # recognizer events and blows (step, attacker, target, blocked, damage), in order: the
        # recent ones kept (tests, HUD), all of them counted and in the state hash (game/history.py)
        self.events_log: History = History(LOG_KEPT, key=_event_key)
        self.blows_log: History = History(LOG_KEPT)
        self.on_toggle_fullscreen: Callable[[], None] | None = None
        self._t0: float | None = None
        self._buttons = 0
        self._auto_paused = False
        self._step = 0
        self.prev_joints = [b.joint_positions().copy() for b in self.boxers]
        self.curr_joints = [j.copy() for j in self.prev_joints]
        self.frame_vec: np.ndarray | None = None

        self.loop = self._build_loop(STAGE_BUDGETS_MS)
        self.sounds.play("bell")

    def _build_loop(self, budgets_ms: dict[str, float]) -> FixedStepLoop:
        """The fixed-step loop with the stages in their order, each against its budget."""
        cfg = self.config
        loop = FixedStepLoop(self.clock, hz=HZ, render_hz=HZ // 2 if cfg.low_power else HZ)
        for name, fn in (("input", self._input), ("frames", self._frames), ("recognize", self._recognize),
                         ("player", self._player), ("opponent", self._opponent), ("physics", self._physics),
                         ("hits", self._hits), ("match", self._match)):
            loop.add_stage(name, fn, budgets_ms[name])
        if cfg.render:
            loop.set_render(self.render, LOW_POWER_RENDER_BUDGET_MS if cfg.low_power else RENDER_BUDGET_MS)
        return loop

    def templates_lines(self) -> list[str]:
        """Which template set is in use, for the console (the HUD shows it under the source)."""
        return [self.hud_state.templates]

    # -- surfaces ------------------------------------------------------------------------
    def target_surface(self) -> pygame.Surface:
        if self._surface_provider is not None:
            return self._surface_provider()
        if self._offscreen is None:
            self._offscreen = pygame.Surface(self.config.size)
        return self._offscreen

    # -- stages --------------------------------------------------------------------------
    def _input(self, step: int, dt: float) -> None:
        if pygame.display.get_init():
            for event in pygame.event.get():
                self.handle_event(event)
        if self.config.demo:
            self._pilot()
        samples = self.source.poll()
        buttons = int(getattr(self.source, "buttons", 0) or 0)
        if buttons & HOME_BUTTON and not self._buttons & HOME_BUTTON:
            self.match.toggle_pause()
        self._buttons = buttons
        self.resampler.push(samples)
        disconnected = self.source.state in (SourceState.DISCONNECTED, SourceState.RECONNECTING, SourceState.CONNECTING)
        if disconnected and not self.hud_state.disconnected:
            if not self.match.paused:
                self.match.toggle_pause()
                self._auto_paused = True
        elif not disconnected and self.hud_state.disconnected:
            # back: the controller may sit differently in the hand; learn gravity afresh
            self.recognizer.reset()
            if self._auto_paused and self.match.paused:
                self.match.toggle_pause()
            self._auto_paused = False
        self.hud_state.disconnected = disconnected

    def _pilot(self) -> None:
        """The attract mode's player: the Interaction Graph picks the player's move from the
        player's side, the virtual player performs it on the keyboard source, and the REAL
        recognizer has to recognize it before the boxer moves."""
        if not hasattr(self.source, "press") or self.source.busy or not self.match.fighting:
            return
        if self.player.controller.action != "guard":
            return
        if self._pilot_wait > 0:
            self._pilot_wait -= 1
            return
        me, them = self.player.controller, self.opponent.controller
        situation = Situation.from_roots(self.player.root, me.action, me.frame,
                                         self.opponent.root, them.action, them.frame)
        action = self.graph.best_action(situation)
        unrecognized = not self._pilot_seen  # the last motion started nothing: try another
        variety, rest = PILOT_STYLE.get(getattr(self.source, "profile", ""), PILOT_STYLE["experienced"])
        if unrecognized or self._pilot_rng.random() < variety:
            # an attract mode that only ever throws the one best punch is dull to watch: now
            # and then a different move (closing in when out of reach)
            near = situation.distance < PILOT_REACH
            choices = PILOT_ATTACKS if near else ("step_forward",)
            action = choices[int(self._pilot_rng.integers(len(choices)))]
        if action in self.lib and action != "guard":
            self.source.press(action)
            self._pilot_seen = False
            self._pilot_wait = rest  # the hands come back to rest before the next motion
        else:
            self._pilot_wait = 8

    def handle_event(self, event: pygame.event.Event) -> None:
        if event.type == pygame.QUIT:
            self.loop.stop()
        elif event.type == pygame.KEYDOWN:
            if event.key == pygame.K_ESCAPE:
                self.match.toggle_pause()
            elif event.key == pygame.K_F3:
                self.hud_state.show_budget = not self.hud_state.show_budget
            elif event.key == pygame.K_F11:
                if self.on_toggle_fullscreen is not None:
                    self.on_toggle_fullscreen()
            elif event.key == pygame.K_RETURN and self.match.over:
                self.new_match()
            elif event.key == pygame.K_d and (self.match.paused or self.match.over):
                self.cycle_difficulty()  # the pause menu
            elif hasattr(self.source, "press_key") and not self.match.paused:
                self.source.press_key(pygame.key.name(event.key))

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
            self._pilot_seen |= ev.get("event") == "start"
            self.hud_state.mark(ev)
            # a whole-motion switch is the recognizer's final word on a motion already over:
            # a label for the record, too late for the character to act on
            if self.match.fighting and not ev.get("whole_motion"):
                self.player.controller.on_event(ev)
                clip = self.lib.get(ev.get("action") or "")
                if ev.get("event") == "start" and clip is not None and clip.kind == "attack":
                    self.sounds.play("punch", 0.5)
        rec = self.recognizer
        active = rec.state == "active"
        self.hud_state.main_fill = min(rec.count, self.hud_state.main_size) if active else 0
        self.hud_state.supp_fill = min(rec.count, rec.supplementary) if active else 0

    def _player(self, step: int, dt: float) -> None:
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
        if hasattr(self, "hud_state"):  # not yet while the session is being built
            self.hud_state.difficulty = self.difficulty.label

    def cycle_difficulty(self) -> None:
        """The pause menu's D: the next difficulty, from now on."""
        self.difficulty = self.difficulty.next()
        self._apply_difficulty()

    def _opponent(self, step: int, dt: float) -> None:
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

    def _hold_knockdown(self, i: int) -> None:
        """While the referee counts, the downed boxer stays down (the clip's low frame)."""
        ctrl = self.boxers[i].controller
        clip = self.lib.get("knockdown")
        if self.match.down == i and clip is not None:
            hold = int(clip.frames * KNOCKDOWN_HOLD)
            if ctrl.action != "knockdown" or ctrl.frame > hold:
                ctrl.play("knockdown", from_frame=min(ctrl.frame, hold) if ctrl.action == "knockdown" else 0)

    def _physics(self, step: int, dt: float) -> None:
        self.contacts = self.world.step(dt)
        self.prev_joints, self.curr_joints = self.curr_joints, [b.joint_positions().copy() for b in self.boxers]
        self.renderer.step_effects()

    def _hits(self, step: int, dt: float) -> None:
        for hit in hits_from_contacts(self.contacts, list(self.boxers)):
            self.apply_hit(step, hit)

    def apply_hit(self, step: int, hit: Hit | dict) -> None:
        """A hit (game.hits.Hit, or a dict of its keys): the blow's damage (blow_damage), the
        CPU's scaled by its difficulty, then land it."""
        hit = Hit.of(hit)
        damage = blow_damage(hit)
        if hit.attacker == 1:
            damage *= self.difficulty.current.damage
        self.land_blow(step, hit, damage)

    def land_blow(self, step: int, hit: Hit, damage: float) -> None:
        """The referee counts the blow; reaction, flash, sound, rumble (both modes)."""
        target = 1 - hit.attacker
        if not self.match.hit(target, damage):
            return
        self.blows_log.append((step, hit.attacker, hit.target, hit.blocked, round(damage, 4)))
        point = hit.point
        if point is None:
            point = self.boxers[target].joint_positions()[4]
        self.renderer.add_flash(point, strong=damage >= 8, blocked=hit.blocked)
        if hit.blocked:
            self.sounds.play("block")
        else:
            self.sounds.play("hit" if damage >= 8 else "hit_light")
            if self.match.down != target:
                self.boxers[target].react(hit)
        self.rumble(target)

    def rumble(self, target: int) -> None:
        """The boxer who was hit: its player feels it (the CPU has no controller)."""
        if target == 0:
            self.source.rumble(RUMBLE_MS)

    def _match(self, step: int, dt: float) -> None:
        m = self.match
        m.step()
        for kind, who in m.drain_events():
            if kind == "bell":
                self.sounds.play("bell")
                if m.phase == "fight":
                    self.hud_state.message, self.hud_state.message_age = f"ROUND {m.round}", 0
                    self._to_corners()
            elif kind == "knockdown":
                self.boxers[who].controller.play("knockdown")
            elif kind == "rise":
                self.boxers[who].controller.play("guard")
        self._rounds_over(m)
        if m.over:
            self._over_steps += 1
            if self.config.demo and self._over_steps >= DEMO_RESTART_STEPS:
                self.new_match()  # the attract mode goes on
        h = self.hud_state
        h.health = list(m.health)
        h.round, h.rounds = m.round, m.rounds
        h.seconds_left = m.seconds_left()
        h.phase, h.count, h.down = m.phase, m.count, m.down
        h.knockdowns = list(m.knockdowns)
        h.winner, h.result, h.paused = m.winner, m.result, m.paused
        self._show_sources()
        h.tick()
        self._step = step

    def _rounds_over(self, m: Match) -> None:
        """Each round decided since the last step: the adaptive difficulty follows the player."""
        while self._rounds_seen < len(m.round_winners):
            winner = m.round_winners[self._rounds_seen]
            self._rounds_seen += 1
            self.difficulty.round_over(0 if winner is None else (1 if winner == 0 else -1))
            self._apply_difficulty()

    def _show_sources(self) -> None:
        """The source line's fields of the HUD: URL, state, battery."""
        h = self.hud_state
        h.source_url, h.source_state = self.source.url, self.source.state.value
        h.battery = self.source.battery

    def _to_corners(self) -> None:
        """Both boxers back to their marks, at the guard (a new round)."""
        for boxer, z, yaw in ((self.player, -START_GAP / 2, 0.0), (self.opponent, START_GAP / 2, math.pi)):
            boxer.controller.play("guard", blend=False)
            boxer.controller.output = self.lib["guard"].posture(0)
            boxer.place(0.0, z, yaw)
        self.prev_joints = [b.joint_positions().copy() for b in self.boxers]
        self.curr_joints = [j.copy() for j in self.prev_joints]

    def new_match(self) -> None:
        """A fresh match (Enter after the last bell; by itself in the attract mode)."""
        self.match = Match()
        self._rounds_seen = 0
        self._over_steps = 0
        self._to_corners()
        self.recognizer.reset()
        self._pilot_wait = PILOT_SETTLE_STEPS
        self.hud_state.message, self.hud_state.message_age = "ROUND 1", 0
        self.sounds.play("bell")

    # -- rendering -----------------------------------------------------------------------
    def render(self, alpha: float) -> None:
        target = self.target_surface()
        if self.config.low_power:
            w, h = target.get_size()
            size = (max(1, int(w * LOW_POWER_SCALE)), max(1, int(h * LOW_POWER_SCALE)))
            # its own surface: the headless target is self._offscreen, which must keep its size
            if self._low_power_surface is None or self._low_power_surface.get_size() != size:
                self._low_power_surface = pygame.Surface(size)
            surf = self._low_power_surface
        else:
            surf = target
        bodies = [self.prev_joints[i] + (self.curr_joints[i] - self.prev_joints[i]) * alpha for i in (0, 1)]
        self.renderer.draw(surf, bodies)
        if surf is not target:
            # the scene at half size, scaled up; the HUD's text drawn sharp at full size
            pygame.transform.scale(surf, target.get_size(), target)
        self.hud.draw(target, self.hud_state, self.loop.budget)
        if self._surface_provider is not None and pygame.display.get_init() and pygame.display.get_surface() is target:
            pygame.display.flip()

    # -- reproducibility ------------------------------------------------------------------
    def state_hash(self) -> str:
        """The simulation's state: bodies, controllers, match, recognizer decisions."""
        ctrls = [(b.controller.action, round(float(b.controller.frame), 6), tuple(np.round(b.root, 9))) for b in self.boxers]
        return state_hash(self.world.x, self.match.state(), ctrls, self.events_log.total, self.events_log.digest(),
                          self.blows_log.total, self.blows_log.digest())
