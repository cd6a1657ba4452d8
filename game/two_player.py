"""A local two-player match: two people, two controllers, two recognizers (`play --players 2`).

Each player has a seat: their source (any mix of wiimote://, serial://, keyboard://), their own
templates (a profile), their own dual-buffer recognizer and frame resampler, and their own HUD
panel. Both boxers are driven the same way: the seat's recognizer events go to that boxer's
PlayerController. No Interaction Graph: the opponent is the other person.

The stages are the one-player session's (game/session.py) with every per-player stage done
for both seats; `player` steps boxer 1, `opponent` boxer 2, so the F3 overlay and
`bench frame --players 2` read the same. A seat whose source drops pauses the match for both
until it is back. The camera looks at the boxers side-on (game/render_two_player.py): player 1
on the left, player 2 on the right, neither hiding the other.

`--demo`: a pilot per seat presses random moves on a keyboard source (a virtual player each),
so two real recognizers decide what they were: tests, screenshots and the benchmark.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pygame

from engine.arguments import SEED_MAX
from engine.clock import RealClock, VirtualClock
from engine.errors import InputError
from engine.frames import FrameResampler
from engine.sensors.source import KEYS, PLAYABLE, Source
from game.difficulty import DifficultySetting
from game.history import History
from game.hits import Hit
from game.hud import HudState, SourceSnapshot
from game.hud_two_player import TwoPlayerHud
from game.launch import DEMO_SOURCE, run_session, wants_sound
from game.match import Match
from game.pilot import PILOT_ATTACKS, PILOT_REACH, PILOT_SETTLE_STEPS
from game.rules import RING_LIMIT, blow_damage
from game.session import (
    LOG_KEPT,
    LOST_STATES,
    RUMBLE_MS,
    Session,
    SessionConfig,
    _event_key,
    enter_starts_match,
    hold_keys,
    load_templates,
    pause_on_home,
    rewind_ended,
    say_if_ended,
    templates_in_use,
)
from game.session_view import SessionView
from game.stages import STAGE_BUDGETS_MS

# Two recognizers, two sources, two resamplers: those stages get more than the one-player budget
TWO_PLAYER_BUDGETS_MS = {**STAGE_BUDGETS_MS, "input": 0.40, "frames": 0.20, "recognize": 2.00}
NAMES = ("P1", "P2")
PILOT_PAUSE_STEPS = 12  # the pilot's hands come back to rest before its next motion


@dataclass
class Seat:
    """One player: source, templates, recognizer, frames, HUD panel, demo pilot."""

    index: int
    source: Source
    templates: object
    recognizer: object
    resampler: FrameResampler
    hud: HudState
    frame_vec: np.ndarray | None = None
    buttons: int = 0
    pilot_wait: int = PILOT_SETTLE_STEPS
    pilot_seen: bool = True
    pilot_rng: np.random.Generator = field(default_factory=lambda: np.random.default_rng(0))

    @property
    def disconnected(self) -> bool:
        return self.source.state in LOST_STATES


def _seat_event_key(item: tuple[int, dict]) -> tuple:
    seat, ev = item
    return (seat, *_event_key(ev))


def build_recognizer(templates, settings: dict | None = None):
    """A seat's recognizer: the settings saved with its templates, then `settings` (the config
    file's and the command line's, shared by both seats) over them."""
    from engine.recognition import DualBufferRecognizer
    from engine.recognition.config import layered

    return DualBufferRecognizer.from_config(templates, layered(templates.recognizer, settings or {}))


class TwoPlayerSession(Session):
    """Two seats, two boxers, one match. Reuses the one-player session's physics, knockdown
    hold, corners, rendering and state hash; its own input, recognition, boxers, hits and HUD."""

    def __init__(self, sources: Sequence[Source], config: SessionConfig | None = None,
                 clock: RealClock | VirtualClock | None = None,
                 surface_provider: Callable[[], pygame.Surface] | None = None,
                 templates: Sequence[str | Path | None] = (None, None)):
        from game.render_two_player import SideOnLowPowerRenderer, SideOnRenderer
        from game.sound import Sounds

        if len(sources) != 2:
            raise InputError(f"a two-player match needs two sources, got {len(sources)}")
        self.config = cfg = config or SessionConfig()
        self.clock = clock or RealClock()
        self._build_ring(cfg)
        self.graph = None  # the opponent is a person: no Interaction Graph
        self.seats: list[Seat] = [self._new_seat(i, source, tmpl)
                                  for i, (source, tmpl) in enumerate(zip(sources, templates, strict=True))]
        # the one-player names, for what the shared methods and tools read (player 1's)
        self.source = self.seats[0].source
        self.templates = self.seats[0].templates
        self.recognizer = self.seats[0].recognizer
        self.resampler = self.seats[0].resampler
        # what the one-player methods it inherits read (cycle_difficulty, _match...): no CPU
        # here, so no opponent_ai and a difficulty that sets nothing (_apply_difficulty)
        self.difficulty = DifficultySetting(cfg.difficulty)
        self.opponent_ai = None
        self.pilot = None  # each seat has its own (_pilot_seat)
        self._rounds_seen = self._cpu_rest = self._rest_next = self._buttons = 0
        self.match = Match()
        self.hud_state = self.seats[0].hud  # player 1's panel carries the match state
        self.hud_state.names = NAMES
        self.hud_state.mode = "LOW POWER" if cfg.low_power else ""
        self.hud_state.message = "ROUND 1"
        hud = TwoPlayerHud(self.seats[1].hud)
        self.sounds = Sounds(enabled=cfg.sound, seed=cfg.seed)
        # side-on, following the boxers' line (game/render_two_player.py)
        renderer = SideOnLowPowerRenderer(cfg.size) if cfg.low_power else SideOnRenderer(cfg.size)
        self.view = SessionView(cfg.size, cfg.low_power, renderer, hud, surface_provider)
        self.events_log: History = History(LOG_KEPT, key=_seat_event_key)  # (seat, event)
        self.blows_log: History = History(LOG_KEPT)
        self.on_toggle_fullscreen: Callable[[], None] | None = None
        self._t0: float | None = None
        self._auto_paused = False
        self._over_steps = 0
        self._step = 0
        self.loop = self._build_loop(TWO_PLAYER_BUDGETS_MS)
        self.sounds.play("bell")

    def _new_seat(self, i: int, source: Source, tmpl: str | Path | None) -> Seat:
        """Player i's seat: templates (handedness is player 1's option, the one-player flag;
        player 2 plays right-handed), recognizer, resampler, HUD panel, pilot."""
        cfg = self.config
        t = load_templates(tmpl, cfg.left_handed and i == 0)
        if source.sensors_known and source.sensors * 3 != t.dim:
            raise InputError(f"{source.url}: the source has {source.sensors} sensor(s), player {i + 1}'s "
                             f"templates need {t.dim // 3} (a Wiimote + Nunchuk, or two IMUs); train moves for this source: "
                             f"quickjab train --source {source.url} --profile NAME, then --profile{'2' if i else ''} NAME")
        rec = build_recognizer(t, cfg.recognizer)
        hud = HudState(source=SourceSnapshot(url=f"{NAMES[i]} {source.url}"), demo=cfg.demo,
                       main_size=int(rec.main) if rec.main != "auto" else 6, supp_size=rec.supplementary,
                       templates=templates_in_use(tmpl))
        if KEYS in source.capabilities:
            from game.keyboard_source import key_help

            hud.keys = key_help(source.keymap)
        return Seat(i, source, t, rec, FrameResampler(sensors=t.dim // 3), hud,
                    pilot_rng=np.random.default_rng(cfg.seed + 1 + 7919 * i))

    def templates_lines(self) -> list[str]:
        return [f"{NAMES[seat.index]} {seat.hud.templates}" for seat in self.seats]

    # -- stages --------------------------------------------------------------------------
    def _input(self, step: int, dt: float) -> None:
        if pygame.display.get_init():
            for event in pygame.event.get():
                self.handle_event(event)
                self.redraw()
        for seat in self.seats:
            if self.config.demo:
                self._pilot_seat(seat)
            hold_keys(seat.source, self.match.paused)
            samples = seat.source.poll()
            seat.buttons = pause_on_home(seat.source, seat.buttons, self)
            seat.resampler.push(samples)
            lost = seat.disconnected
            say_if_ended(seat.source, seat.hud.disconnected)
            if not lost and seat.hud.disconnected:
                # back: the controller may sit differently in the hand; learn gravity afresh
                seat.recognizer.reset()
            seat.hud.disconnected = lost
        # either player's controller lost pauses the match for both; it resumes when both are back
        lost_any = any(s.hud.disconnected for s in self.seats)
        if lost_any and not self.match.paused:
            self.match.toggle_pause()
            self._auto_paused = True
        elif not lost_any and self._auto_paused:
            if self.match.paused:
                self.match.toggle_pause()
            self._auto_paused = False

    def source_lost(self) -> bool:
        """Whether either player's source is away (Esc and Home do not resume the match then)."""
        return any(seat.hud.disconnected for seat in self.seats)

    def sources(self) -> list[Source]:
        return [seat.source for seat in self.seats]

    def _pilot_seat(self, seat: Seat) -> None:
        """The demo's player at this seat: a random move (an attack when within reach, else a
        step in), performed by the virtual player on the keyboard source; the seat's REAL
        recognizer must recognize it before the boxer moves."""
        source = seat.source
        if PLAYABLE not in source.capabilities or source.busy or not self.match.fighting:
            return
        if self.boxers[seat.index].controller.action != "guard":
            return
        if seat.pilot_wait > 0:
            seat.pilot_wait -= 1
            return
        me, them = self.boxers[seat.index].root, self.boxers[1 - seat.index].root
        near = math.hypot(me[0] - them[0], me[1] - them[1]) < PILOT_REACH
        choices = PILOT_ATTACKS if near else ("step_forward",)
        source.press(choices[int(seat.pilot_rng.integers(len(choices)))])
        seat.pilot_seen = False
        seat.pilot_wait = PILOT_PAUSE_STEPS

    def handle_event(self, event: pygame.event.Event) -> None:
        # Esc, F3, F11 and Enter (a new match after the last bell, or a played-out replay
        # again) are the one-player keys; every other key is a seat's
        if event.type == pygame.KEYDOWN and event.key not in (pygame.K_ESCAPE, pygame.K_F3, pygame.K_F11) \
                and not (event.key == pygame.K_RETURN and enter_starts_match(self.match, self.sources())):
            if not self.match.paused:
                name = pygame.key.name(event.key)
                for seat in self.seats:  # each keyboard seat answers only its half of the keys
                    if KEYS in seat.source.capabilities:
                        seat.source.press_key(name)
            return
        super().handle_event(event)

    def _frames(self, step: int, dt: float) -> None:
        if self._t0 is None:
            self._t0 = self.clock.seconds() - step * dt
        t = self._t0 + step * dt
        for seat in self.seats:
            seat.frame_vec = seat.resampler.frame_at(t)
        self.frame_vec = self.seats[0].frame_vec

    def _recognize(self, step: int, dt: float) -> None:
        for seat in self.seats:
            if seat.frame_vec is None:
                continue
            rec, hud = seat.recognizer, seat.hud
            for ev in rec.push(seat.frame_vec, t=step * dt):
                self.events_log.append((seat.index, ev))
                seat.pilot_seen |= ev.get("event") == "start"
                hud.mark(ev)
                self._act_on(seat.index, rec, ev)
            active = rec.state == "active"
            hud.main_fill = min(rec.count, hud.main_size) if active else 0
            hud.supp_fill = min(rec.count, rec.supplementary) if active else 0

    def _step_boxer(self, i: int, dt: float) -> None:
        if self.match.paused:
            return  # the pause freezes the ring (Ring._physics)
        self._hold_knockdown(i)
        me, other = self.boxers[i], self.boxers[1 - i]
        ox, oz, _ = other.root
        me.turn_towards(ox, oz)
        me.keep_inside(RING_LIMIT)
        me.step(dt)
        if me.controller.finished_action():
            self.seats[i].recognizer.character_finished()

    def _player(self, step: int, dt: float) -> None:
        self._step_boxer(0, dt)

    def _opponent(self, step: int, dt: float) -> None:
        self._step_boxer(1, dt)

    def damage_of(self, hit: Hit) -> float:
        """The one-player session's blow (blow_damage), but a fair fight: no CPU difficulty on top."""
        return blow_damage(hit)

    def rumble(self, target: int) -> None:
        """The player who was hit feels it in their own controller."""
        self.seats[target].source.rumble(RUMBLE_MS)

    def _rounds_over(self, m: Match) -> None:
        """No CPU whose difficulty follows the rounds: two people box."""

    def _apply_difficulty(self) -> None:
        """No CPU to set (the pause menu's D, cycle_difficulty, changes nothing here)."""

    def _show_sources(self) -> None:
        # each seat's source line (its URL is set once, at the seat's making)
        for seat in self.seats:
            seat.hud.source = SourceSnapshot.of(seat.source, url=seat.hud.source.url, sensors=seat.resampler.dim // 3)
        self.seats[1].hud.tick()  # player 2's marks age as player 1's (hud_state.tick)

    def new_match(self) -> None:
        """A fresh match (Enter after the last bell or under SOURCE ENDED; by itself in the
        demo); a seat's replay that played out starts again."""
        rewind_ended(self.sources())
        self.match = Match()
        self._over_steps = 0
        self._to_corners()
        for seat in self.seats:
            seat.recognizer.reset()
            seat.pilot_wait = PILOT_SETTLE_STEPS
        self.hud_state.message, self.hud_state.message_age = "ROUND 1", 0
        self.sounds.play("bell")


# -- `quickjab play --players 2` --------------------------------------------------------------
def _with_param(url: str, key: str, value: str) -> str:
    """url with ?key=value added unless it already names that key."""
    from engine.sensors.source import parse_source_url

    if key in parse_source_url(url)[2]:
        return url
    return url + ("&" if "?" in url else "?") + f"{key}={value}"


def seat_seed(seed: int, i: int) -> int:
    """Seat i's keyboard seed: seed + i, wrapped into the seeds a URL takes (0..SEED_MAX)."""
    return (seed + i) % (SEED_MAX + 1)


def source_urls(url1: str | None, url2: str | None, demo: bool, seed: int,
                wiimotes: Callable[[], list[str]] | None = None) -> tuple[list[str], list[str]]:
    """The two seats' source URLs and notes for the player. Default: the first two Wiimotes
    found (a seat without one plays from its half of the keyboard). Two keyboard seats split
    the keyboard (keys=left / keys=right) unless their URLs say otherwise."""
    notes: list[str] = []
    if demo:
        return [f"{DEMO_SOURCE}&seed={seat_seed(seed, i)}&keys={half}" for i, half in enumerate(("left", "right"))], notes
    urls = [url1, url2]
    if any(u is None or u.rstrip("/") == "wiimote:" for u in urls):
        # `wiimote://` would open the first remote found for both seats: give each its own
        found = list(wiimotes() if wiimotes is not None else _wiimote_paths())
        for i, u in enumerate(urls):
            if u is None or u.rstrip("/") == "wiimote:":
                if found:
                    urls[i] = f"wiimote://{found.pop(0)}?player={i + 1}"
                elif u is None:
                    urls[i] = "keyboard://"
                    notes.append(f"player {i + 1}: no Wiimote found, playing from the keyboard")
                elif any(x is not None and x.startswith("wiimote:///") for x in urls):
                    raise InputError(f"player {i + 1}: {u}: only one Wiimote found; each player needs their own")
                # else none at all: opening wiimote:// says so, with the pairing help
    if _same_device(urls[0], urls[1]):
        raise InputError(f"--source and --source2 are the same device ({urls[0]}): each player needs their own")
    keyboards = [i for i, u in enumerate(urls) if u.startswith("keyboard://")]
    for i in keyboards:
        urls[i] = _with_param(urls[i], "seed", str(seat_seed(seed, i)))
        if len(keyboards) == 2:
            urls[i] = _with_param(urls[i], "keys", ("left", "right")[i])
    if len(keyboards) == 2:
        _check_own_keys(urls)
    return urls, notes


def _same_device(a: str, b: str) -> bool:
    """Whether two seats' URLs open one device: the same URL, or the same scheme on the same
    path however spelled (serial:///dev/x?baud=230400, a link to /dev/x; wiimote:///dev/hidraw3
    with another ?player). The keyboard is shared by halves (_check_own_keys); serial://auto
    names no port."""
    from engine.errors import same_file
    from engine.sensors.source import SourceError, parse_source_url

    if a.startswith("keyboard://") or b.startswith("keyboard://"):
        return False
    if a == b:
        return True
    try:
        (scheme_a, path_a, _), (scheme_b, path_b, _) = parse_source_url(a), parse_source_url(b)
    except SourceError:  # not a URL: opening it says so
        return False
    return scheme_a == scheme_b and path_a not in ("", "auto") and path_b not in ("", "auto") and same_file(path_a, path_b)


def _check_own_keys(urls: list[str]) -> None:
    """Two keyboard players must not answer the same keys (both keys=left: one key, two boxers)."""
    from engine.sensors.source import parse_source_url
    from game.keyboard_source import KEYMAPS

    halves = [parse_source_url(u)[2].get("keys", "all") for u in urls]
    if all(h in KEYMAPS for h in halves) and set(KEYMAPS[halves[0]]) & set(KEYMAPS[halves[1]]):
        # (an unknown half is the source's own error, naming the choices)
        raise InputError(f"--source and --source2 share keys of the keyboard (keys={halves[0]}, keys={halves[1]}): "
                         "give each player their own half, keys=left and keys=right")


def seat_label(i: int, given: str | None) -> str:
    """Player i's name in a message, with the option that set their source when one did."""
    return f"player {i + 1}" + (f" ({('--source', '--source2')[i]})" if given is not None else "")


def _wiimote_paths() -> list[str]:
    """Paths of the Wiimotes this machine sees (none when the HID backend is missing)."""
    try:
        from engine.sensors.wiimote import list_wiimotes

        return [w.path.decode() if isinstance(w.path, bytes) else str(w.path) for w in list_wiimotes()]
    except Exception:  # noqa: BLE001 - no backend, no permission: no Wiimotes, the keyboard plays
        return []


def seat_templates(profile: str | None, templates: str | None, option: str = "--profile",
                   who: str = "") -> tuple[Path | str | None, str | None]:
    """A seat's templates: --templates, else the profile's trained set, else the default chain
    (the default profile's file, the shipped set...), with a note when a named profile has none.
    A bad name is an error naming `option`; `who` ("player 2: ") starts the note."""
    from engine.xdg import is_there
    from game.userdata import DEFAULT_PROFILE, profile_templates_path

    if templates is not None:
        return templates, None
    path = profile_templates_path(profile, option)
    if profile in (None, DEFAULT_PROFILE):
        return None, None
    if is_there(path):
        return path, None
    return None, (f"{who}profile {profile!r} has no trained templates yet (quickjab train --profile {profile}); "
                  "using the default profile's templates")


def run_match(args) -> int:
    """`quickjab play --players 2`: both seats' templates and sources, then play as one
    player does (game.launch.run_session: headless frames, window check, screenshot, trace)."""
    from engine.recording import say_notes
    from engine.sensors import open_source
    from game.user_config import recognizer_settings

    settings = recognizer_settings(getattr(args, "recognizer", None) or ())  # a bad file or value: before any window
    templates, notes = [], []
    for i, (option, profile) in enumerate((("--profile", args.profile), ("--profile2", args.profile2))):
        path, note = seat_templates(profile, args.templates, option, f"player {i + 1}: ")
        templates.append(path)
        if note:
            notes.append(note)
    urls, url_notes = source_urls(args.source, args.source2, args.demo, args.seed)
    profiles = [opt for opt, value in (("--profile", args.profile), ("--profile2", args.profile2)) if value is not None]
    if profiles and args.templates is not None:
        notes.append(f"{' and '.join(profiles)} ignored with --templates: both players use that set")
    cpu_options = [opt for opt, value in (("--difficulty", args.difficulty), ("--graph", args.graph)) if value is not None]
    if cpu_options:
        notes.append(f"{' and '.join(cpu_options)} ignored with --players 2: they set the CPU, and two people box")
    say_notes(url_notes + notes, "play")

    def sources(clock) -> list[Source]:
        import game.keyboard_source  # noqa: F401 - registers keyboard://

        opened: list[Source] = []
        try:
            for i, url in enumerate(urls):
                try:
                    opened.append(open_source(url, clock=clock.seconds))
                except (InputError, OSError) as exc:  # which player's source, in the one line
                    raise InputError(f"{seat_label(i, (args.source, args.source2)[i])}: {exc}") from None
                # a replayed recording's row left out, as one player's play says it, after the player's name
                seat = seat_label(i, (args.source, args.source2)[i])
                say_notes([f"{seat}: {note}" for note in opened[-1].file_notes], "play")
        except BaseException:
            for source in opened:
                source.close()
            raise
        return opened

    def session(sources: list[Source], clock, size: tuple[int, int], surface_provider) -> TwoPlayerSession:
        config = SessionConfig(seed=args.seed, size=size, low_power=args.low_power, demo=args.demo,
                               sound=wants_sound(args), left_handed=args.left_handed,
                               recognizer=settings)
        return TwoPlayerSession(sources, config, clock=clock, surface_provider=surface_provider, templates=templates)

    return run_session(args, "QuickJab - two players", sources, session)
