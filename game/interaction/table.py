"""The Interaction Graph file: one compressed .npz of plain arrays (never pickles).

In memory (GraphTable), S states and E edges grouped by source state (edge_ptr[s]:edge_ptr[s+1]
are state s's): keys (S,) int64 grid cells ascending; features (S, 3) mean distance,
bearing_self, bearing_other of the state's samples; other_action, other_frame (S,) what the
other boxer is doing; visits (S,) samples merged; best_action (S,) the solved policy; value
(S,) its value; edge_ptr (S+1,) CSR offsets; edge_dst, edge_action, edge_steps (60 Hz steps
until the next decision), edge_flip (the next decision is the other's), edge_reward (the
chooser's); fill_keys / fill_state the look-up fill (lookup.py).

On disk (version 3) the arrays are stored in forms that deflate well; every one decodes
exactly, except features (below). The tables the look-up needs are all stored: rebuilding
the fill from the keys (lookup.neighbour_fill) takes about 2 s, four times the load budget.

| name | shape, dtype | meaning |
| --- | --- | --- |
| meta | () str | JSON: format, version, grid, bout rules, rewards, build info |
| action_names | (A,) str | the bout model's actions; ids below index this |
| key_steps | (S,) narrowest int (uint32 today) | keys delta-coded (cumsum gives them; ascending, so steps > 0) |
| feature_pos | (S, 3) uint16 | each feature's position inside its own grid cell, in 1/65536 of a cell (decodes to the sub-cell's centre: within 2e-7 m / 7e-7 rad of the mean, and always inside the state's cell; a mean distance beyond the grid's distance_max is stored as the last cell's far edge) |
| other_action, other_frame | (S,) int16 | what the other boxer is doing |
| visits | (S,) int32 | samples merged into the state |
| best_action | (S,) int16 | the solved policy |
| value | (S,) float32 | its value |
| edge_count | (S,) narrowest int | edges of each state (diff of edge_ptr) |
| edge_dst_steps, edge_dst_steps_big | (E,) int8, (n,) narrowest int | edge_dst taken in action-major order (edges stably sorted by action, so one action's edges run over the states in order and land on nearby states), delta-coded; a step outside int8 is ESCAPE (-128) in the first and, in order, its value in the second (under 1 % of them) |
| edge_action | (E,) uint8 | the chooser's action |
| edge_steps | (E,) uint8 | 60 Hz steps until the next decision |
| edge_flip | (E,) bool | the next decision is the other boxer's |
| edge_reward | (E,) float32 | the chooser's reward along the edge |
| fill_key_steps | (F,) narrowest int (version 2: int64) | the look-up fill's cell keys, delta-coded (cumsum gives them, ascending) |
| fill_state_offset, fill_state_offset_big | (F,) int8, (n,) narrowest int | fill_state minus the insertion point of its key among the state keys (the nearest state is usually a neighbour in key order, so offsets are small); escaped like edge_dst_steps |

Version 2 files (plain keys, float64 features, edge_ptr, edge_dst, fill_state) still load.
"""

from __future__ import annotations

import json
import zipfile
import zlib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from engine.errors import InputError
from engine.npz_files import read_json, read_npz, write_replacing

from .bout import BoutRules, Rewards
from .state import StateGrid

FORMAT = "quickjab-interaction-graph"
VERSION = 3
READS = (2, 3)
FEATURE_SCALE = 65536      # feature_pos units per grid cell
MAX_FILE_BYTES = 512 * 2**20  # uncompressed, checked before reading; the shipped graph is 13 MB
# The wait ("guard") is an action of rules.wait_frames frames, and the bout model sizes its
# per-frame tables by the longest action: no longer than an action file may be
# (game.actions.MAX_FRAMES, not imported: loading a graph needs no skeleton). 10**12 asked for 568 TiB.
MAX_WAIT_FRAMES = 3600

# What each array must hold (numpy dtype kinds): integers, numbers, flags, names.
_INTS = ("key_steps", "keys", "other_action", "other_frame", "visits", "best_action", "edge_count",
         "edge_ptr", "edge_dst", "edge_dst_steps", "edge_dst_steps_big", "edge_action", "edge_steps",
         "fill_key_steps", "fill_state", "fill_state_offset", "fill_state_offset_big", "feature_pos")
_NUMBERS = ("value", "edge_reward", "features")


def _bad_kinds(a: dict) -> str | None:
    """Why the arrays' dtypes or ranks are wrong, or None."""
    for k in _INTS:
        if k in a and a[k].dtype.kind not in "iu":
            return f"{k} must hold integers, not {a[k].dtype}"
    for k in _NUMBERS:
        if k in a and a[k].dtype.kind not in "iuf":
            return f"{k} must hold numbers, not {a[k].dtype}"
    if a["edge_flip"].dtype.kind not in "biu" or ((a["edge_flip"] != 0) & (a["edge_flip"] != 1)).any():
        return "edge_flip must hold 0 or 1"
    if a["action_names"].dtype.kind != "U" or a["action_names"].ndim != 1:
        return "action_names must be a list of names"
    return None


def _bad_meta(meta: dict, grid: StateGrid, rules: BoutRules, rewards: Rewards) -> str | None:
    """Why the numbers in meta are unusable (not finite, out of range), or None."""
    numbers = {**{f"grid {k}": v for k, v in grid.as_dict().items()},
               **{f"rules {k}": v for k, v in rules.as_dict().items()},
               **{f"rewards {k}": v for k, v in rewards.as_dict().items()}}
    for name, v in numbers.items():
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not np.isfinite(v):
            return f"{name} is {v!r}, not a finite number"
        if v < 0:
            return f"{name} is negative"
    if not isinstance(meta.get("build", {}), dict):  # `graph info` reads its keys
        return f"build is {type(meta['build']).__name__}, not an object"
    n = meta.get("n_choices")
    if isinstance(n, bool) or not isinstance(n, int) or n < 1:
        return f"n_choices is {n!r}"
    if not (grid.distance_step > 0 and 0 < grid.angle_step_deg <= 360 and grid.distance_max > 0
            and isinstance(grid.phase_step, int) and isinstance(grid.max_frames, int)
            and grid.phase_step >= 1 and grid.max_frames >= 1):
        return "grid steps must be positive"
    if grid.n_distance > 1_000_000 or grid.n_angle > 100_000 or grid.n_phase > 100_000:
        return "grid too fine"
    if not (isinstance(rules.wait_frames, int) and 1 <= rules.wait_frames <= MAX_WAIT_FRAMES and rules.hp > 0
            and 0 < rewards.discount <= 1):
        return f"wait_frames (at most {MAX_WAIT_FRAMES}), hp and discount must be positive (discount at most 1)"
    return None


def action_major(edge_action: np.ndarray) -> np.ndarray:
    """Edge order grouped by action, states ascending within an action (a stable sort)."""
    return np.argsort(np.asarray(edge_action), kind="stable")


def _angle_axes_wrap(x: np.ndarray, n_angle: int) -> np.ndarray:
    """Offsets (S, 3) in grid units with the two angle axes wrapped to [-n/2, n/2)."""
    x = x.copy()
    x[:, 1:] = (x[:, 1:] + n_angle / 2) % n_angle - n_angle / 2
    return x


def encode_features(grid: StateGrid, keys: np.ndarray, features: np.ndarray) -> np.ndarray:
    """(S, 3) uint16: where each feature lies inside its state's cell, in 1/FEATURE_SCALE of
    a cell (clipped into the cell: a mean beyond distance_max shares the last cell)."""
    _, db, sb, ob = grid.split_key(keys)
    f = np.asarray(features, dtype=np.float64).reshape(-1, 3)
    pos = grid.normalized(f[:, 0], f[:, 1], f[:, 2])
    off = _angle_axes_wrap(pos - np.stack([db, sb, ob], axis=-1), grid.n_angle)
    return np.clip(np.floor(off * FEATURE_SCALE), 0, FEATURE_SCALE - 1).astype(np.uint16)


def decode_features(grid: StateGrid, keys: np.ndarray, pos: np.ndarray) -> np.ndarray:
    """(S, 3) float64 features back from `encode_features`: the centre of the sub-cell."""
    _, db, sb, ob = grid.split_key(keys)
    g = np.stack([db, sb, ob], axis=-1) + (pos.astype(np.float64) + 0.5) / FEATURE_SCALE
    out = np.empty_like(g)
    out[:, 0] = g[:, 0] * grid.distance_step
    out[:, 1:] = g[:, 1:] * grid.angle_step - np.pi
    return out


def narrow(x: np.ndarray) -> np.ndarray:
    """Integers in the narrowest standard dtype that holds them exactly (deflates better)."""
    x = np.asarray(x, dtype=np.int64)
    if len(x) == 0:
        return x.astype(np.int8)
    return x.astype(np.result_type(np.min_scalar_type(int(x.min())),
                                   np.min_scalar_type(int(x.max()))))


ESCAPE = -128              # an int8 step that stands for the next value of the "_big" array


def split_small(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(int8 with ESCAPE where a value does not fit, those values in order): nearly all the
    delta-coded steps fit a byte, and a byte deflates far better than the wide few."""
    x = np.asarray(x, dtype=np.int64)
    fits = (x > ESCAPE) & (x <= 127)
    return np.where(fits, x, ESCAPE).astype(np.int8), narrow(x[~fits])


def join_small(small: np.ndarray, big: np.ndarray) -> np.ndarray | None:
    """Inverse of `split_small`; None when the escapes and the big values disagree."""
    out = small.astype(np.int64)
    esc = out == ESCAPE
    if big.ndim != 1 or int(esc.sum()) != len(big):
        return None
    out[esc] = big
    return out


def _as_int32(x: np.ndarray) -> np.ndarray:
    """State indices as int32 (a start-up's memory), or left as they are when one does not fit:
    the cast would wrap it (2**32 past a state onto that state) and the range check after
    decoding would pass it."""
    if len(x) and (x.min() < np.iinfo(np.int32).min or x.max() > np.iinfo(np.int32).max):
        return x
    return x.astype(np.int32)


def _no_edges(a: dict) -> dict:
    """Empty edge arrays (every state with no edge) standing in for a file's edges."""
    n = len(a["keys"] if "keys" in a else a.get("key_steps", ()))
    out = {k: np.zeros(0, dtype=dt) for k, dt in (
        ("edge_dst_steps", np.int8), ("edge_dst_steps_big", np.int8), ("edge_action", np.uint8),
        ("edge_steps", np.uint8), ("edge_flip", bool), ("edge_reward", np.float32),
        ("edge_dst", np.int32))}
    out["edge_count"] = np.zeros(n, dtype=np.int8)
    out["edge_ptr"] = np.zeros(n + 1, dtype=np.int64)
    return out


def fill_keys_of(a: dict) -> np.ndarray:
    """The look-up fill's keys (int64, ascending) from a file's delta-coded fill_key_steps."""
    return np.cumsum(a["fill_key_steps"], dtype=np.int64)  # = cumsum of .astype(int64), no copy


class GraphFileError(InputError):
    """An Interaction Graph file that cannot be read; the message names the file."""


@dataclass
class GraphTable:
    action_names: list[str]
    n_choices: int
    keys: np.ndarray
    features: np.ndarray
    other_action: np.ndarray
    other_frame: np.ndarray
    visits: np.ndarray
    best_action: np.ndarray
    value: np.ndarray
    edge_ptr: np.ndarray
    edge_dst: np.ndarray
    edge_action: np.ndarray
    edge_steps: np.ndarray
    edge_flip: np.ndarray
    edge_reward: np.ndarray
    fill_keys: np.ndarray
    fill_state: np.ndarray
    grid: StateGrid = field(default_factory=StateGrid)
    rules: BoutRules = field(default_factory=BoutRules)
    rewards: Rewards = field(default_factory=Rewards)
    build: dict = field(default_factory=dict)

    @property
    def n_states(self) -> int:
        return len(self.keys)

    @property
    def n_edges(self) -> int:
        return len(self.edge_dst)

    def meta(self) -> dict:
        return {"format": FORMAT, "version": VERSION, "n_choices": self.n_choices,
                "grid": self.grid.as_dict(), "rules": self.rules.as_dict(),
                "rewards": self.rewards.as_dict(), "build": self.build}

    def save(self, path: str | Path) -> None:
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        arrays = self.to_arrays()
        # a file object: savez would otherwise append ".npz"; written beside and renamed over,
        # as templates are: a kill mid-write left a truncated graph-small.npz, the cache `play`
        # then refused every time (it is built only when missing)
        write_replacing(path, lambda fh: np.savez_compressed(fh, **arrays))

    def to_arrays(self) -> dict[str, np.ndarray]:
        """The version-3 arrays of the file (see the module docstring)."""
        keys = self.keys.astype(np.int64)
        fill_keys = self.fill_keys.astype(np.int64)
        dst = self.edge_dst.astype(np.int64)
        offset = self.fill_state.astype(np.int64) - np.searchsorted(keys, fill_keys)
        dst_steps, dst_big = split_small(np.diff(dst[action_major(self.edge_action)], prepend=0))
        fill_offset, fill_big = split_small(offset)
        return dict(
            meta=np.array(json.dumps(self.meta(), sort_keys=True)),
            action_names=np.array(self.action_names, dtype=str),
            key_steps=narrow(np.diff(keys, prepend=0)),
            feature_pos=encode_features(self.grid, keys, self.features),
            other_action=self.other_action.astype(np.int16),
            other_frame=self.other_frame.astype(np.int16),
            visits=self.visits.astype(np.int32),
            best_action=self.best_action.astype(np.int16),
            value=self.value.astype(np.float32),
            edge_count=narrow(np.diff(self.edge_ptr)),
            edge_dst_steps=dst_steps, edge_dst_steps_big=dst_big,
            edge_action=self.edge_action.astype(np.uint8),
            edge_steps=np.minimum(self.edge_steps, 255).astype(np.uint8),
            edge_flip=self.edge_flip.astype(bool),
            edge_reward=self.edge_reward.astype(np.float32),
            fill_key_steps=narrow(np.diff(fill_keys, prepend=0)),
            fill_state_offset=fill_offset, fill_state_offset_big=fill_big,
        )

    @classmethod
    def load(cls, path: str | Path, edges: bool = True) -> GraphTable:
        """The table in `path`. `edges=False` reads the policy and the look-up only (what a
        match uses): the 840,000 edges are left compressed in the file, n_edges is 0, and a
        start-up saves their decoding (~40 MB of peak memory, ~0.1 s)."""
        path = Path(path)
        try:
            arrays = read_npz(path, MAX_FILE_BYTES, keep=None if edges else lambda k: not k.startswith("edge_"))
            if not edges:
                arrays.update(_no_edges(arrays))
        except FileNotFoundError:
            raise GraphFileError(f"{path}: no such Interaction Graph file") from None
        except (OSError, ValueError, zipfile.BadZipFile, zlib.error, EOFError, KeyError) as exc:
            raise GraphFileError(f"{path}: not a readable Interaction Graph file ({exc})") from None
        return cls._from_arrays(path, arrays)

    @staticmethod
    def _decode_v3(a: dict, grid: StateGrid, bad) -> dict:
        """The version-2 arrays (plain keys, features, edge_ptr, edge_dst, fill_state) from
        the version-3 ones; shapes checked here where decoding needs them, ranges later."""
        keys = np.cumsum(a["key_steps"].astype(np.int64))
        S = len(keys)
        E = len(a["edge_action"])
        if a["feature_pos"].shape != (S, 3) or a["edge_count"].shape != (S,) or \
                a["edge_dst_steps"].shape != (E,) or a["edge_action"].ndim != 1 or \
                a["fill_state_offset"].shape != a["fill_key_steps"].shape:
            raise bad("array shapes disagree")
        dst_steps = join_small(a["edge_dst_steps"], a["edge_dst_steps_big"])
        fill_offset = join_small(a["fill_state_offset"], a["fill_state_offset_big"])
        if dst_steps is None or fill_offset is None:
            raise bad("escaped steps disagree with their wide values")
        edge_ptr = np.concatenate([[0], np.cumsum(a["edge_count"].astype(np.int64))])
        edge_dst = np.empty(E, dtype=np.int64)
        edge_dst[action_major(a["edge_action"])] = np.cumsum(dst_steps)
        # the fill's ~900,000 cells: each int64 temporary is 7 MB of a start-up's peak memory,
        # so the keys are summed in int64 directly and the offsets become the states in place
        fill_keys = fill_keys_of(a)
        fill_offset += np.searchsorted(keys, fill_keys)
        out = dict(a, keys=keys, features=decode_features(grid, keys, a["feature_pos"]),
                   edge_ptr=edge_ptr, edge_dst=_as_int32(edge_dst),
                   fill_keys=fill_keys, fill_state=_as_int32(fill_offset))
        return out

    @classmethod
    def _from_arrays(cls, path: Path, a: dict) -> GraphTable:
        def bad(why: str) -> GraphFileError:
            return GraphFileError(f"{path}: corrupt Interaction Graph file: {why}")

        meta, grid, rules, rewards = _read_meta(a, bad)
        why = _missing_arrays(a, meta["version"]) or _bad_kinds(a)
        if why:
            raise bad(why)
        if meta["version"] == 3:
            a = cls._decode_v3(a, grid, bad)
        else:
            a = dict(a, fill_keys=fill_keys_of(a))
        why = _bad_shapes(a) or _bad_contents(a, meta)
        if why:
            raise bad(why)
        return cls(
            action_names=[str(x) for x in a["action_names"]], n_choices=int(meta["n_choices"]),
            keys=a["keys"].astype(np.int64), features=a["features"],
            other_action=a["other_action"].astype(np.int64),
            other_frame=a["other_frame"].astype(np.int64), visits=a["visits"],
            best_action=a["best_action"].astype(np.int64), value=a["value"],
            edge_ptr=a["edge_ptr"].astype(np.int64), edge_dst=a["edge_dst"],
            edge_action=a["edge_action"], edge_steps=a["edge_steps"], edge_flip=a["edge_flip"],
            edge_reward=a["edge_reward"], fill_keys=a["fill_keys"],
            fill_state=a["fill_state"], grid=grid, rules=rules, rewards=rewards,
            build=meta.get("build", {}))


def _read_meta(a: dict, bad) -> tuple[dict, StateGrid, BoutRules, Rewards]:
    """The file's meta record and the grid, rules and rewards it names; raises `bad(why)`."""
    if "meta" not in a:
        raise bad("missing meta")
    try:
        meta = read_json(a["meta"])
        if meta.get("format") != FORMAT:
            raise bad(f"format is {meta.get('format')!r}, expected {FORMAT!r}")
        version = meta.get("version")
        if version not in READS:
            raise bad(f"version {version}, this program reads {', '.join(map(str, READS))}")
        grid = StateGrid(**meta["grid"])
        rules = BoutRules(**meta["rules"])
        rewards = Rewards(**meta["rewards"])
        why = _bad_meta(meta, grid, rules, rewards)
        if why:
            raise bad(why)
    except GraphFileError:
        raise
    except (ValueError, TypeError, KeyError, AttributeError) as exc:
        raise bad(f"bad meta ({exc})") from None
    return meta, grid, rules, rewards


def _missing_arrays(a: dict, version: int) -> str | None:
    """Which arrays this file's version needs and it lacks, or None."""
    common = ["action_names", "other_action", "other_frame", "visits", "best_action",
              "value", "edge_action", "edge_steps", "edge_flip", "edge_reward",
              "fill_key_steps"]
    own = (["keys", "features", "edge_ptr", "edge_dst", "fill_state"] if version == 2 else
           ["key_steps", "feature_pos", "edge_count", "edge_dst_steps", "edge_dst_steps_big",
            "fill_state_offset", "fill_state_offset_big"])
    missing = [k for k in common + own if k not in a]
    return f"missing {', '.join(missing)}" if missing else None


def _bad_shapes(a: dict) -> str | None:
    """Why the decoded arrays' shapes disagree with the state and edge counts, or None."""
    S = len(a["keys"])
    E = len(a["edge_dst"])
    shapes_ok = (
        a["features"].shape == (S, 3)
        and all(a[k].shape == (S,) for k in ("other_action", "other_frame", "visits",
                                              "best_action", "value"))
        and a["edge_ptr"].shape == (S + 1,)
        and all(a[k].shape == (E,) for k in ("edge_action", "edge_steps", "edge_flip",
                                              "edge_reward"))
        and a["fill_key_steps"].ndim == 1 and a["fill_state"].shape == a["fill_key_steps"].shape
    )
    if not shapes_ok:
        return "array shapes disagree"
    if S == 0:
        return "no states"
    if "guard" not in [str(x) for x in a["action_names"]]:
        return "action_names lacks 'guard'"
    return None


def _bad_contents(a: dict, meta: dict) -> str | None:
    """Why the decoded arrays' values are out of range or out of order, or None."""
    S = len(a["keys"])
    E = len(a["edge_dst"])
    A = len(a["action_names"])
    ptr = a["edge_ptr"].astype(np.int64)
    if ptr[0] != 0 or ptr[-1] != E or (np.diff(ptr) < 0).any():
        return "edge offsets out of order"
    if E and (a["edge_dst"].min() < 0 or a["edge_dst"].max() >= S):
        return "an edge points outside the states"
    if a["best_action"].min() < 0 or a["best_action"].max() >= A or \
            (E and a["edge_action"].max() >= A):
        return "an action id outside action_names"
    steps = a["fill_key_steps"]  # compared in its own dtype (no 7 MB int64 copy), except
    if steps.dtype == np.uint64:  # uint64: read as the decode reads it, past 2**63 negative
        steps = steps.astype(np.int64)
    if (np.diff(a["keys"]) <= 0).any() or (steps[1:] <= 0).any() or (steps[:1] < 0).any():
        return "keys not strictly ascending"
    if len(a["fill_state"]) and (a["fill_state"].min() < 0 or a["fill_state"].max() >= S):
        return "the look-up fill points outside the states"
    pos = a.get("feature_pos")  # version 3: inside its own cell, or the state's features are not
    if pos is not None and len(pos) and (pos.min() < 0 or pos.max() >= FEATURE_SCALE):
        return f"feature_pos must count 0 to {FEATURE_SCALE - 1} (1/{FEATURE_SCALE} of a cell)"
    if not (np.isfinite(a["value"]).all() and np.isfinite(a["features"]).all()
            and np.isfinite(a["edge_reward"]).all()):
        return "non-finite numbers"
    if meta["n_choices"] > A or (a["other_action"] < 0).any() or a["other_action"].max() >= A or \
            (E and a["edge_action"].min() < 0):
        return "an action id outside action_names"
    if (a["other_frame"] < 0).any() or (a["visits"] < 0).any():
        return "negative frames or visits"
    if len(set(a["action_names"].tolist())) != A:
        return "action_names repeat"
    return None
