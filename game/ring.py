"""The ring both game modes share (game/session.py: one player against the CPU;
game/two_player.py: two people): two boxers in the physics world at their marks, the physics,
hits and match stages (game/stages.py), what a recognizer's event does to a boxer (`_act_on`),
the referee's blows, the knockdown hold, the corners between rounds, the view and the state
hash. A pause freezes the ring: no physics step, no contacts (`_physics`), no clip steps (the
sessions' boxer stages); a motion begun under it, the count or the break does nothing (`_act_on`). The session
around it brings the input, the recognition and the opponent: it sets `config`, `match`,
`hud_state`, `sounds`, `view`, `events_log`, `blows_log` and `loop`, and says what a blow does
(`damage_of`), its rumble, a decided round (`_rounds_over`), the source line (`_show_sources`)
and a new match mean in its mode."""

from __future__ import annotations

import math

import numpy as np
import pygame

from engine.clock import STEP_HZ
from engine.state_hash import state_hash
from game.hits import Hit, hits_from_contacts
from game.rules import START_GAP

KNOCKDOWN_HOLD = 0.55  # the fraction of the knockdown clip held while the referee counts
DEMO_RESTART_STEPS = 8 * STEP_HZ  # the attract mode shows the result, then boxes again


# Under the pause the picture changes only when something happens (a key, the source's state):
# it is drawn PAUSED_REDRAW_HZ times a second and after any event, not every frame: a paused
# match took half a core at 1280x720 under a software display, as much as the match itself.
# With the F3 overlay up every frame is drawn (its figures are of the frames it shows).
PAUSED_REDRAW_HZ = 10


class Ring:
    """The shared half of a session (see the module docstring); never built on its own."""

    def _build_ring(self, cfg) -> None:
        """The physics world and the two boxers at their marks; the per-step buffers the
        stages pass on (frame, contacts, joints for the render)."""
        from engine.physics import World, WorldDef
        from game.actions import load_library
        from game.boxer import Boxer

        self.lib = load_library()
        self.world = World.from_def(WorldDef(gravity=(0.0, -9.81, 0.0), ground_y=0.0, damping=0.01,
                                             iterations=max(1, cfg.physics_iterations // (2 if cfg.low_power else 1))))
        self.boxers = (Boxer(self.world, self.lib, x=0.0, z=-START_GAP / 2, yaw=0.0),
                       Boxer(self.world, self.lib, x=0.0, z=START_GAP / 2, yaw=math.pi))
        self.player, self.opponent = self.boxers
        self.frame_vec: np.ndarray | None = None  # frames -> recognize
        self.contacts: list = []  # physics -> hits
        self.prev_joints = [b.joint_positions().copy() for b in self.boxers]  # physics -> render
        self.curr_joints = [j.copy() for j in self.prev_joints]
        self._paused_frames, self._redraw_now = 0, False  # render: the paused picture held

    # -- the view's parts, under the names tools and tests read ------------------------------
    @property
    def renderer(self):
        return self.view.renderer

    @property
    def hud(self):
        return self.view.hud

    @property
    def _low_power_surface(self) -> pygame.Surface | None:
        return self.view.low_power_surface

    def target_surface(self) -> pygame.Surface:
        return self.view.target_surface()

    def rumble(self, target: int) -> None:
        """The boxer who was hit: the session makes its player feel it (_show_blow)."""

    def _act_on(self, i: int, recognizer, ev: dict) -> None:
        """Boxer i acts on its recognizer's event while blows count. A motion that starts while
        they do not (the pause, the count, the break between rounds) is over for the boxer there
        and then (`character_finished`: the rest of it is discarded): its second half, the hand
        coming back, or a switch of it started a punch once the boxing went on, the boxer never
        having played the first to discard it."""
        if self.match.fighting:
            self.boxers[i].controller.on_event(ev)
            clip = self.lib.get(ev.get("action") or "")
            if ev.get("event") == "start" and clip is not None and clip.kind == "attack":
                self.sounds.play("punch", 0.5)
        elif ev.get("event") == "start":
            recognizer.character_finished()

    def _hold_knockdown(self, i: int) -> None:
        """While the referee counts, the downed boxer stays down (the clip's low frame)."""
        ctrl = self.boxers[i].controller
        clip = self.lib.get("knockdown")
        if i in self.match.downed and clip is not None:
            hold = int(clip.frames * KNOCKDOWN_HOLD)
            if ctrl.action != "knockdown" or ctrl.frame > hold:
                ctrl.play("knockdown", from_frame=min(ctrl.frame, hold) if ctrl.action == "knockdown" else 0)

    def _physics(self, step: int, dt: float) -> None:
        if self.match.paused:
            # the pause freezes the ring: no step, no contacts (a fist that touched under the
            # pause spent its hand on a blow the paused referee did not count), a still picture
            self.contacts = []
            self.prev_joints = self.curr_joints
            return
        self.contacts = self.world.step(dt)
        self.prev_joints, self.curr_joints = self.curr_joints, [b.joint_positions().copy() for b in self.boxers]
        self.renderer.step_effects()

    def _hits(self, step: int, dt: float) -> None:
        # no blow counts during the count or the break: a fist's touch then spends no hand (it
        # spent it on a blow the referee did not count)
        if self.match.fighting:
            self._land(step, hits_from_contacts(self.contacts, list(self.boxers)))

    def _land(self, step: int, hits: list[Hit]) -> None:
        """Every blow of the step lands before the referee decides who goes down (the first
        contact's knockdown used to end the exchange: the order of the contacts decided it);
        then the counted ones' reaction, flash, sound, rumble."""
        landed = [(hit, self.damage_of(hit)) for hit in hits]
        counted = [(hit, damage) for hit, damage in landed if self.match.land(1 - hit.attacker, damage)]
        self.match.settle_knockdowns()
        for hit, damage in counted:
            self._show_blow(step, hit, damage)

    def damage_of(self, hit: Hit) -> float:
        """What the blow does to the other boxer (the session's mode says: game.rules.blow_damage,
        the CPU's scaled by its difficulty)."""
        raise NotImplementedError

    def apply_hit(self, step: int, hit: Hit | dict) -> None:
        """One blow on its own (game.hits.Hit, or a dict of its keys), landed as a step's are."""
        self._land(step, [Hit.of(hit)])

    def _show_blow(self, step: int, hit: Hit, damage: float) -> None:
        """A blow the referee counted: logged; reaction (unless it floored the boxer), flash,
        sound, rumble (both modes)."""
        target = 1 - hit.attacker
        self.blows_log.append((step, hit.attacker, hit.target, hit.blocked, round(damage, 4)))
        point = hit.point
        if point is None:
            point = self.boxers[target].joint_positions()[4]
        self.renderer.add_flash(point, strong=damage >= 8, blocked=hit.blocked)
        if hit.blocked:
            self.sounds.play("block")
        else:
            self.sounds.play("hit" if damage >= 8 else "hit_light")
            if target not in self.match.downed:
                self.boxers[target].react(hit)
        self.rumble(target)

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
        self.hud_state.match = self.match.snapshot()
        self._show_sources()
        self.hud_state.tick()
        self._step = step

    def _to_corners(self) -> None:
        """Both boxers back to their marks, at the guard (a new round)."""
        for boxer, z, yaw in ((self.player, -START_GAP / 2, 0.0), (self.opponent, START_GAP / 2, math.pi)):
            boxer.controller.play("guard", blend=False)
            boxer.controller.output = self.lib["guard"].posture(0)
            boxer.place(0.0, z, yaw)
        self.prev_joints = [b.joint_positions().copy() for b in self.boxers]
        self.curr_joints = [j.copy() for j in self.prev_joints]

    # -- rendering and reproducibility ---------------------------------------------------------
    def render(self, alpha: float) -> None:
        if self._paused_picture_holds():
            return
        self.view.draw(alpha, self.prev_joints, self.curr_joints, self.hud_state, self.loop.budget)

    def redraw(self) -> None:
        """Draw the next frame even under the pause (an event came: a key, the window shown)."""
        self._redraw_now = True

    def _paused_picture_holds(self) -> bool:
        """Whether this frame keeps the picture on screen: under the pause (F3's overlay down)
        the first frame is drawn, then PAUSED_REDRAW_HZ a second, and the frame after an event."""
        if not self.match.paused or self.hud_state.show_budget:
            self._paused_frames = 0
            return False
        self._paused_frames += 1
        if self._redraw_now:
            self._redraw_now = False
            return False
        every = max(1, round(self.loop.render_hz / PAUSED_REDRAW_HZ))  # 6 frames at 60 Hz, 3 at 30
        return (self._paused_frames - 1) % every != 0

    def state_hash(self) -> str:
        """The simulation's state: bodies, controllers, match, recognizer decisions."""
        ctrls = [(b.controller.action, round(float(b.controller.frame), 6), tuple(np.round(b.root, 9))) for b in self.boxers]
        return state_hash(self.world.x, self.match.state(), ctrls, self.events_log.total, self.events_log.digest(),
                          self.blows_log.total, self.blows_log.digest())
