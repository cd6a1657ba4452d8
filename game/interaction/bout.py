"""The bout model: two boxers played from the action library's root motion and attack and
guard windows, many bouts at once in numpy. Sampling, edge expansion and the headless duel
all step through this one model, so the graph is solved for the same timing it is judged by.

Timing (the game's): a boxer that chooses an action plays its clip frames 0..F-1, one per
60 Hz step, and chooses again when frame F-1 (the guard) has been shown. At each step its
root moves by the clip's root_offset increment, expressed in its facing at the clip start.
A hit lands when one of the attacker's AttackWindows covers the current frame, the target's
root is within `reach` (+ body radius) ahead of the attacker and within a lateral tolerance,
and the window has not landed yet. The punch aims at the window's first target; it is
guarded when a GuardWindow of the defender covers that part at that frame (a guard covers
only attacks from the front). Clean hits cost hp and interrupt the defender into the hit
reaction hit_<part>_<side>_<light|heavy> (side: where the blow comes from, hooks from the
side of the punching hand's opposite, others from the front; heavy from `heavy_damage`);
guarded hits (block or parry) do `chip` of the damage, as the game's referee scores them; a
parry also staggers the attacker when the library has a reaction for that. As in the game's
session, every step each boxer turns `face_fraction` of the way towards the other (the library
has no turning clips; steps are sideways) and the roots stay `min_separation` apart.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field

import numpy as np

from game.rules import BLOCKED_SHARE, FACE_RATE, MAX_HEALTH

from .state import wrap_angle

HEAD, BODY = 1, 2
PART_BITS = {"head": HEAD, "body": BODY}
GUARD_NONE, GUARD_BLOCK, GUARD_PARRY = 0, 1, 2
WAIT = "guard"            # the chooser's "do nothing for a moment" action


@dataclass(frozen=True)
class BoutRules:
    """Numbers of the bout model that are not in the action library."""

    wait_frames: int = 8           # how long "guard" (waiting) lasts before choosing again
    body_radius: float = 0.20      # fist + head capsule radii: a punch lands this far past its reach
    lateral_tolerance: float = 0.30
    guard_arc_deg: float = 60.0    # guards cover attacks from within this angle of the front
    # roots never closer: the model's stand-in for the game's bodies, which keep apart by their
    # collision capsules (engine/physics), not by a rule
    min_separation: float = 0.75
    face_fraction: float = FACE_RATE  # share of the way each boxer turns to face the other per step
    chip: float = BLOCKED_SHARE    # fraction of damage a guarded hit still does (the referee's)
    heavy_damage: float = 9.0      # hits this strong play the heavy reaction
    hp: float = MAX_HEALTH

    def as_dict(self) -> dict:
        return asdict(self)


@dataclass(frozen=True)
class Rewards:
    """The reward function (per boxer; the chooser's reward is its gain minus the other's)."""

    strong_bonus: float = 0.5      # clean hits earn damage * (1 + bonus * damage / max damage)
    blocked_hit: float = 0.15      # what the attacker earns for a blocked hit, per damage
    block_credit: float = 0.3      # what the defender earns for a block, per damage
    parry_credit: float = 0.6      # ... for a parry
    far_distance: float = 1.6      # beyond this, moving further away is running away
    run_penalty: float = 15.0      # per metre moved away beyond far_distance
    discount: float = 0.99         # per 60 Hz step

    def as_dict(self) -> dict:
        return asdict(self)


def _frames_of(window) -> tuple[int, int]:
    """Inclusive first and last frame a window is active."""
    return int(window.start), int(window.end)


@dataclass
class ActionTable:
    """The action library compiled to arrays indexed by (action, frame)."""

    names: list[str]
    kinds: list[str]
    frames: np.ndarray            # (A,) clip length
    offset: np.ndarray            # (A, Fmax, 3) cumulative (dx, dz, dyaw) per frame
    window: np.ndarray            # (A, Fmax) global attack-window id or -1
    win_reach: np.ndarray         # (W,)
    win_damage: np.ndarray        # (W,)
    win_targets: np.ndarray       # (W,) bitmask HEAD|BODY
    win_slot: np.ndarray          # (W,) index of the window within its action (spent bits)
    win_end: np.ndarray           # (W,) last active frame
    guard_cover: np.ndarray       # (A, Fmax) bitmask
    guard_kind: np.ndarray        # (A, Fmax) GUARD_*
    choices: np.ndarray           # action ids a boxer may choose (ACTION_NAMES + WAIT)
    wait: int
    win_react: np.ndarray         # (W,) the reaction a clean hit of this window causes
    react_stagger: int            # -1 when the library has none
    spent_before: np.ndarray      # (A, Fmax + 1) bits of the windows over before this frame
    max_damage: float = 1.0
    attack_ids: np.ndarray = field(default_factory=lambda: np.zeros(0, int))

    def fingerprint(self) -> str:
        """A hash of everything the bout model reads from the library: a graph built from
        another library (changed timings, reaches, damage) is stale."""
        import hashlib
        h = hashlib.sha256("|".join(self.names).encode())
        for arr in (self.frames, self.offset.round(6), self.window, self.win_reach.round(6),
                    self.win_damage.round(6), self.win_targets, self.win_react, self.guard_cover,
                    self.guard_kind):
            h.update(np.ascontiguousarray(arr).tobytes())
        return h.hexdigest()[:16]

    @property
    def ready_frame(self) -> int:
        """The `other_frame` that codes "at the guard, choosing": the wait's last frame."""
        return int(self.frames[self.wait]) - 1

    def index(self, name: str) -> int:
        return self.names.index(name)

    @classmethod
    def from_library(cls, lib: dict, choosable: list[str], rules: BoutRules) -> ActionTable:
        """Compile `lib` (name -> Action). `choosable` are the names a boxer may pick."""
        # the knockdown ends a bout; it is never a state to decide in
        reactions = sorted(n for n, a in lib.items() if a.kind == "reaction" and n != "knockdown")
        names = list(choosable) + [WAIT] + [n for n in reactions if n not in choosable]
        frames = []
        for n in names:
            frames.append(rules.wait_frames if n == WAIT else max(1, int(lib[n].frames)))
        frames = np.array(frames, dtype=np.int64)
        c = _Compiled(len(names), int(frames.max()))
        kinds = []
        for i, n in enumerate(names):
            kinds.append("idle" if n == WAIT else lib.get(n).kind)
            if n == WAIT:
                c.add_idle_guard(i, int(frames[i]), lib.get(WAIT))
            else:
                c.add_action(i, n, int(frames[i]), lib.get(n))
        if not reactions:
            raise ValueError("the action library has no hit reaction (kind 'reaction')")
        win_react = [_window_reaction(c, k, reactions, names, rules) for k in range(len(c.reach))]
        damage_arr = np.array(c.damage, dtype=float)
        return cls(
            names=names, kinds=kinds, frames=frames, offset=c.offset, window=c.window,
            win_reach=np.array(c.reach, dtype=float), win_damage=damage_arr,
            win_targets=np.array(c.targets, dtype=np.int64), win_slot=np.array(c.slot, dtype=np.int64),
            win_end=np.array(c.wend, dtype=np.int64), guard_cover=c.cover, guard_kind=c.gkind,
            spent_before=c.spent_before(), choices=np.arange(len(choosable) + 1), wait=len(choosable),
            win_react=np.array(win_react, dtype=np.int64),
            react_stagger=max(_pick_reaction(reactions, names, "stagger"),
                              _pick_reaction(reactions, names, "parried")),
            max_damage=float(damage_arr.max()) if len(damage_arr) else 1.0,
            attack_ids=np.array([i for i, k in enumerate(kinds) if k == "attack"], dtype=np.int64),
        )


class _Compiled:
    """The per-(action, frame) arrays and per-window lists `ActionTable.from_library` fills."""

    def __init__(self, n_actions: int, fmax: int):
        self.fmax = fmax
        self.offset = np.zeros((n_actions, fmax, 3))
        self.window = np.full((n_actions, fmax), -1, dtype=np.int64)
        self.cover = np.zeros((n_actions, fmax), dtype=np.int64)
        self.gkind = np.zeros((n_actions, fmax), dtype=np.int64)
        self.reach, self.damage, self.targets, self.slot, self.wend, self.win_action = [], [], [], [], [], []
        self.win_hand, self.win_hook = [], []

    def add_idle_guard(self, i: int, F: int, guard) -> None:
        """The wait: covered by the library's idle guards held for the whole idle clip."""
        for g in (guard.guards if guard is not None else []):
            s, e = _frames_of(g)
            if s <= 0 and e >= guard.frames - 1:
                self.cover[i, :F] |= sum(PART_BITS.get(p, 0) for p in g.covers)
                self.gkind[i, :F] = GUARD_PARRY if g.kind == "parry" else GUARD_BLOCK

    def add_action(self, i: int, n: str, F: int, a) -> None:
        """Root motion, attack windows and guards of action `a` (named `n`, row `i`)."""
        self.offset[i, :F] = [np.asarray(a.root_offset(float(f)), dtype=float)[:3] for f in range(F)]
        self.offset[i, F:] = self.offset[i, F - 1]
        for k, w in enumerate(a.attacks):
            s, e = _frames_of(w)
            s, e = max(0, s), min(F - 1, e)
            self.window[i, s:e + 1] = len(self.reach)
            self.reach.append(float(w.reach))
            self.damage.append(float(w.damage))
            self.targets.append(PART_BITS.get(w.targets[0], HEAD) if len(w.targets) else HEAD)
            self.win_hand.append(w.hand)
            self.win_hook.append("hook" in n)
            self.slot.append(k)
            self.wend.append(e)
            self.win_action.append(i)
        for g in a.guards:
            s, e = _frames_of(g)
            s, e = max(0, s), min(F - 1, e)
            self.cover[i, s:e + 1] |= sum(PART_BITS.get(p, 0) for p in g.covers)
            self.gkind[i, s:e + 1] = np.maximum(self.gkind[i, s:e + 1],
                                                GUARD_PARRY if g.kind == "parry" else GUARD_BLOCK)

    def spent_before(self) -> np.ndarray:
        """(A, Fmax + 1) bits of the windows over before each frame."""
        out = np.zeros((self.offset.shape[0], self.fmax + 1), dtype=np.int64)
        for wid in range(len(self.reach)):
            out[self.win_action[wid], self.wend[wid] + 1:] |= 1 << self.slot[wid]
        return out


def _pick_reaction(reactions: list[str], names: list[str], *words: str) -> int:
    """The first reaction whose name has all these words (else fewer of them); -1 if none."""
    for k in range(len(words), 0, -1):
        for n in reactions:
            if all(w in n.split("_") for w in words[:k]):
                return names.index(n)
    return -1


def _window_reaction(c: _Compiled, k: int, reactions: list[str], names: list[str], rules: BoutRules) -> int:
    """The reaction a clean hit of window `k` causes: its part, the side it comes from, its strength."""
    part = "head" if c.targets[k] == HEAD else "body"
    side = ("left" if c.win_hand[k] == "r" else "right") if c.win_hook[k] else "front"
    strength = "heavy" if c.damage[k] >= rules.heavy_damage else "light"
    r = _pick_reaction(reactions, names, part, side, strength)
    return r if r >= 0 else names.index(reactions[0])


class Bouts:
    """B bouts of two boxers each, as arrays (index [:, 0] and [:, 1] for the two boxers)."""

    def __init__(self, table: ActionTable, n: int):
        self.table = table
        self.n = n
        self.pos = np.zeros((n, 2, 2))          # root (x, z)
        self.base_yaw = np.zeros((n, 2))        # facing at the clip start (+ turns since)
        self.act = np.full((n, 2), table.wait, dtype=np.int64)
        self.frame = np.full((n, 2), table.ready_frame, dtype=np.int64)
        self.spent = np.zeros((n, 2), dtype=np.int64)   # bits: windows of this clip that landed
        self.hp = np.zeros((n, 2))

    @property
    def yaw(self) -> np.ndarray:
        f = np.clip(self.frame, 0, None)
        return self.base_yaw + self.table.offset[self.act, f, 2]

    def done(self) -> np.ndarray:
        """(B, 2) bool: this boxer showed its clip's last frame and chooses now."""
        return self.frame >= self.table.frames[self.act] - 1

    def start(self, rows: np.ndarray, who, action) -> None:
        """Boxer `who` of these rows starts `action` (shown from frame 0 on the next step)."""
        yaw = self.yaw[rows, who]
        self.act[rows, who] = action
        self.frame[rows, who] = -1
        self.base_yaw[rows, who] = yaw - self.table.offset[action, 0, 2]
        self.spent[rows, who] = 0

    def place(self, distance, bearing_self, bearing_other) -> None:
        """Put boxer 0 at the origin facing +z and boxer 1 at this relative pose."""
        self.pos[:, 0] = 0.0
        self.base_yaw[:, 0] = 0.0
        bs = np.asarray(bearing_self, dtype=float)
        self.pos[:, 1, 0] = distance * np.sin(bs)
        self.pos[:, 1, 1] = distance * np.cos(bs)
        self.base_yaw[:, 1] = wrap_angle(bs + math.pi - np.asarray(bearing_other))

    def set_action(self, who: int, action, frame) -> None:
        """Boxer `who` is `frame` frames into `action` (its yaw kept as set by `place`)."""
        t = self.table
        action = np.asarray(action, dtype=np.int64)
        frame = np.asarray(frame, dtype=np.int64)
        self.base_yaw[:, who] -= t.offset[action, np.clip(frame, 0, None), 2]
        self.act[:, who] = action
        self.frame[:, who] = frame
        # windows already over are taken as spent: the state does not say whether they landed
        self.spent[:, who] = t.spent_before[action, np.clip(frame, 0, t.spent_before.shape[1] - 1)]

    def pose(self, who, rows: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(distance, bearing_self, bearing_other) seen by boxer `who` ((B,) int or int),
        for all bouts or only these rows (then `who` is per row or one int)."""
        if rows is None:
            rows = np.arange(self.n)
        who = np.broadcast_to(np.asarray(who), rows.shape)
        me, other = self.pos[rows, who], self.pos[rows, 1 - who]
        act, base = self.act[rows], self.base_yaw[rows]
        f = np.clip(self.frame[rows], 0, None)
        yaw = base + self.table.offset[act, f, 2]
        k = np.arange(len(rows))
        dv = other - me
        dist = np.hypot(dv[:, 0], dv[:, 1])
        head = np.arctan2(dv[:, 0], dv[:, 1])
        bs = wrap_angle(head - yaw[k, who])
        bo = wrap_angle(head + math.pi - yaw[k, 1 - who])
        return dist, bs, bo

    def select(self, rows: np.ndarray) -> Bouts:
        """A copy of some rows."""
        out = Bouts.__new__(Bouts)
        out.table, out.n = self.table, len(rows)
        for k in ("pos", "base_yaw", "act", "frame", "spent", "hp"):
            setattr(out, k, getattr(self, k)[rows].copy())
        return out


@dataclass
class StepResult:
    gain: np.ndarray        # (B, 2) reward earned by each boxer this step
    landed: np.ndarray      # (B, 2) clean hits landed
    blocked: np.ndarray     # (B, 2) hits this boxer blocked or parried
    damage: np.ndarray      # (B, 2) hp this boxer took off the other


def step(b: Bouts, rules: BoutRules, rewards: Rewards) -> StepResult:
    """Advance every bout by one 60 Hz step (call `start` for choosing boxers first)."""
    prev_pos = b.pos.copy()
    f = _advance_clips(b, rules)
    _keep_apart(b, rules)
    yaw = b.yaw
    gain = np.zeros((b.n, 2))
    gain -= _running_away(b, prev_pos, rewards)
    landed, blocked, damage = _resolve_hits(b, f, yaw, rules, rewards, gain)
    return StepResult(gain=gain, landed=landed, blocked=blocked, damage=damage)


def _advance_clips(b: Bouts, rules: BoutRules) -> np.ndarray:
    """Turn each boxer towards the other, show the next frame and move the roots by the
    clip's root motion. Returns the frame shown, clipped to the table's length."""
    t = b.table
    prev_f = np.clip(b.frame, 0, None)
    # every step each boxer turns part of the way to face the other (the game does the same)
    dv = b.pos[:, 1] - b.pos[:, 0]
    head0 = np.arctan2(dv[:, 0], dv[:, 1])
    heads = np.stack([head0, head0 + math.pi], axis=1)
    b.base_yaw += rules.face_fraction * wrap_angle(heads - b.yaw)
    b.frame += 1
    f = np.minimum(b.frame, t.offset.shape[1] - 1)
    # root motion: the clip's increment, in the facing at the clip start (plus turns since)
    delta = t.offset[b.act, f] - t.offset[b.act, prev_f]
    delta[b.frame == 0] = 0.0
    c, s = np.cos(b.base_yaw), np.sin(b.base_yaw)
    b.pos[..., 0] += delta[..., 0] * c + delta[..., 1] * s
    b.pos[..., 1] += -delta[..., 0] * s + delta[..., 1] * c
    return f


def _keep_apart(b: Bouts, rules: BoutRules) -> None:
    """The roots keep apart (the bodies clinch, they do not merge)."""
    dv = b.pos[:, 1] - b.pos[:, 0]
    dist = np.hypot(dv[:, 0], dv[:, 1])
    push = np.maximum(rules.min_separation - dist, 0.0) / 2
    unit = dv / np.maximum(dist, 1e-9)[:, None]
    unit[dist < 1e-9] = (0.0, 1.0)
    b.pos[:, 0] -= unit * push[:, None]
    b.pos[:, 1] += unit * push[:, None]


def _running_away(b: Bouts, prev_pos: np.ndarray, rewards: Rewards) -> np.ndarray:
    """(B, 2) penalty for moving further off when already far."""
    prev_dv = prev_pos[:, 1] - prev_pos[:, 0]
    prev_d = np.hypot(prev_dv[:, 0], prev_dv[:, 1])
    away_dir = np.stack([-prev_dv, prev_dv], axis=1) / np.maximum(prev_d, 1e-9)[:, None, None]
    away = np.einsum("bik,bik->bi", b.pos - prev_pos, away_dir)
    return rewards.run_penalty * np.maximum(away, 0.0) * (prev_d > rewards.far_distance)[:, None]


def _resolve_hits(b: Bouts, f: np.ndarray, yaw: np.ndarray, rules: BoutRules, rewards: Rewards,
                  gain: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Both attackers against the pre-hit state (simultaneous hits both land): hp, rewards
    (added to `gain`) and reactions. Returns (landed, blocked, damage), each (B, 2)."""
    t = b.table
    n = b.n
    w = t.window[b.act, f]
    slot = np.where(w >= 0, t.win_slot[np.maximum(w, 0)], 0)
    live = (w >= 0) & (((b.spent >> slot) & 1) == 0)
    zeros = (np.zeros((n, 2)), np.zeros((n, 2)), np.zeros((n, 2)))
    if not live.any():
        return zeros
    rel = b.pos[:, ::-1] - b.pos
    wi = np.maximum(w, 0)
    hit = live & _in_reach(t, rel, yaw, wi, rules)
    if not hit.any():
        return zeros
    oact, of = b.act[:, ::-1], f[:, ::-1]
    cover = t.guard_cover[oact, of]
    kind = t.guard_kind[oact, of]
    # a guard covers only attacks from the front of the defender
    defender_bearing = wrap_angle(np.arctan2(-rel[..., 0], -rel[..., 1]) - yaw[:, ::-1])
    cover = np.where(np.abs(defender_bearing) <= math.radians(rules.guard_arc_deg), cover, 0)
    open_ = t.win_targets[wi] & ~cover
    clean = hit & (open_ != 0)
    guarded = hit & (open_ == 0)
    parried = guarded & (kind == GUARD_PARRY)
    dmg = t.win_damage[wi]
    took = np.where(clean, dmg, np.where(guarded, rules.chip * dmg, 0.0))
    b.hp -= took[:, ::-1]
    strong = 1.0 + rewards.strong_bonus * dmg / max(t.max_damage, 1e-9)
    gain += np.where(clean, dmg * strong, 0.0)
    gain += np.where(guarded & ~parried, rewards.blocked_hit * dmg, 0.0)
    gain += np.where(guarded & ~parried, rewards.block_credit * dmg, 0.0)[:, ::-1]
    gain += np.where(parried, rewards.parry_credit * dmg, 0.0)[:, ::-1]
    b.spent |= np.where(hit, 1 << slot, 0)
    _react(b, t.win_react[wi], clean, parried)
    return clean.astype(float), guarded[:, ::-1].astype(float), took


def _in_reach(t: ActionTable, rel: np.ndarray, yaw: np.ndarray, wi: np.ndarray, rules: BoutRules) -> np.ndarray:
    """(B, 2) bool: the other boxer is ahead within this window's reach and the lateral band."""
    fwd = np.stack([np.sin(yaw), np.cos(yaw)], axis=-1)
    right = np.stack([np.cos(yaw), -np.sin(yaw)], axis=-1)
    ahead = np.einsum("bik,bik->bi", rel, fwd)
    side = np.einsum("bik,bik->bi", rel, right)
    return (ahead > 0) & (ahead <= t.win_reach[wi] + rules.body_radius) & (
        np.abs(side) <= rules.lateral_tolerance)


def _react(b: Bouts, react: np.ndarray, clean: np.ndarray, parried: np.ndarray) -> None:
    """A clean hit interrupts the defender, a parry staggers the attacker."""
    t = b.table
    for i in (0, 1):
        o = 1 - i
        r = np.flatnonzero(clean[:, i])
        if len(r):
            _interrupt(b, r, o, react[r, i])
        if t.react_stagger >= 0:
            r = np.flatnonzero(parried[:, i])
            if len(r):
                _interrupt(b, r, i, t.react_stagger)


def _interrupt(b: Bouts, rows: np.ndarray, who: int, action) -> None:
    """Boxer `who` of these rows cuts to `action`, shown from frame 0 in this very step."""
    t = b.table
    yaw = b.yaw[rows, who]
    b.act[rows, who] = action
    b.frame[rows, who] = 0
    b.base_yaw[rows, who] = yaw - t.offset[action, 0, 2]
    b.spent[rows, who] = 0


def greedy_choice(b: Bouts, who: int, rows: np.ndarray, rules: BoutRules) -> np.ndarray:
    """The greedy opponent: the most damaging attack whose reach covers the other now,
    otherwise a step forward."""
    t = b.table
    dist, bs, _ = b.pose(who, rows)
    ahead = dist * np.cos(bs)
    side = np.abs(dist * np.sin(bs))
    step_fwd = t.index("step_forward") if "step_forward" in t.names else t.wait
    out = np.full(len(rows), step_fwd, dtype=np.int64)
    best = np.full(len(rows), -1.0)
    for a in t.attack_ids:
        ws = np.unique(t.window[a][t.window[a] >= 0])
        if len(ws) == 0:
            continue
        reach = t.win_reach[ws].max()
        dmg = t.win_damage[ws].sum()
        ok = (ahead > 0) & (ahead <= reach + rules.body_radius) & (side <= rules.lateral_tolerance)
        better = ok & (dmg > best)
        out[better] = a
        best[better] = dmg
    return out
