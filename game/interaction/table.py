"""The Interaction Graph file: one compressed .npz of plain arrays (never pickles).

Arrays (S states, E edges grouped by source state, edge_ptr[s]:edge_ptr[s+1] are state s's):

| name | shape, dtype | meaning |
| --- | --- | --- |
| meta | () str | JSON: format, version, grid, bout rules, rewards, build info |
| action_names | (A,) str | the bout model's actions; ids below index this |
| keys | (S,) int64 | grid cell of each state (state.StateGrid.key), ascending |
| features | (S, 3) float64 | mean distance, bearing_self, bearing_other of its samples (float64: each stays inside its own cell) |
| other_action, other_frame | (S,) int16 | what the other boxer is doing |
| visits | (S,) int32 | samples merged into the state |
| best_action | (S,) int16 | the solved policy |
| value | (S,) float32 | its value |
| edge_ptr | (S+1,) int32 | CSR offsets |
| edge_dst | (E,) int32 | state the edge ends in |
| edge_action | (E,) uint8 | the chooser's action |
| edge_steps | (E,) uint8 | 60 Hz steps until the next decision |
| edge_flip | (E,) bool | the next decision is the other boxer's |
| edge_reward | (E,) float32 | the chooser's reward along the edge |
| fill_key_steps | (F,) int64 | the look-up fill's cell keys, delta-coded (cumsum gives them, ascending) |
| fill_state | (F,) int32 | the nearest state of each of those cells (lookup.py) |
"""

from __future__ import annotations

import json
import zipfile
import zlib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from engine.errors import InputError

from .bout import BoutRules, Rewards
from .state import StateGrid

FORMAT = "quickjab-interaction-graph"
VERSION = 2


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
        with open(path, "wb") as fh:   # a file object: savez would otherwise append ".npz"
            np.savez_compressed(
                fh,
                meta=np.array(json.dumps(self.meta(), sort_keys=True)),
                action_names=np.array(self.action_names, dtype=str),
                keys=self.keys.astype(np.int64),
                features=self.features.astype(np.float64),
                other_action=self.other_action.astype(np.int16),
                other_frame=self.other_frame.astype(np.int16),
                visits=self.visits.astype(np.int32),
                best_action=self.best_action.astype(np.int16),
                value=self.value.astype(np.float32),
                edge_ptr=self.edge_ptr.astype(np.int32),
                edge_dst=self.edge_dst.astype(np.int32),
                edge_action=self.edge_action.astype(np.uint8),
                edge_steps=np.minimum(self.edge_steps, 255).astype(np.uint8),
                edge_flip=self.edge_flip.astype(bool),
                edge_reward=self.edge_reward.astype(np.float32),
                fill_key_steps=np.diff(self.fill_keys.astype(np.int64), prepend=0),
                fill_state=self.fill_state.astype(np.int32),
            )

    @classmethod
    def load(cls, path: str | Path) -> GraphTable:
        path = Path(path)
        try:
            with np.load(path, allow_pickle=False) as z:
                arrays = {k: z[k] for k in z.files}
        except FileNotFoundError:
            raise GraphFileError(f"{path}: no such Interaction Graph file") from None
        except (OSError, ValueError, zipfile.BadZipFile, zlib.error, EOFError, KeyError) as exc:
            raise GraphFileError(f"{path}: not a readable Interaction Graph file ({exc})") from None
        return cls._from_arrays(path, arrays)

    @classmethod
    def _from_arrays(cls, path: Path, a: dict) -> GraphTable:
        def bad(why: str) -> GraphFileError:
            return GraphFileError(f"{path}: corrupt Interaction Graph file: {why}")

        need = ["meta", "action_names", "keys", "features", "other_action", "other_frame",
                "visits", "best_action", "value", "edge_ptr", "edge_dst", "edge_action",
                "edge_steps", "edge_flip", "edge_reward", "fill_key_steps", "fill_state"]
        missing = [k for k in need if k not in a]
        if missing:
            raise bad(f"missing {', '.join(missing)}")
        try:
            meta = json.loads(str(a["meta"]))
            if meta.get("format") != FORMAT:
                raise bad(f"format is {meta.get('format')!r}, expected {FORMAT!r}")
            if meta.get("version") != VERSION:
                raise bad(f"version {meta.get('version')}, this program reads {VERSION}")
            grid = StateGrid(**meta["grid"])
            rules = BoutRules(**meta["rules"])
            rewards = Rewards(**meta["rewards"])
        except GraphFileError:
            raise
        except (ValueError, TypeError, KeyError) as exc:
            raise bad(f"bad meta ({exc})") from None
        S = len(a["keys"])
        E = len(a["edge_dst"])
        A = len(a["action_names"])
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
            raise bad("array shapes disagree")
        if S == 0:
            raise bad("no states")
        if "guard" not in [str(x) for x in a["action_names"]]:
            raise bad("action_names lacks 'guard'")
        ptr = a["edge_ptr"].astype(np.int64)
        if ptr[0] != 0 or ptr[-1] != E or (np.diff(ptr) < 0).any():
            raise bad("edge offsets out of order")
        if E and (a["edge_dst"].min() < 0 or a["edge_dst"].max() >= S):
            raise bad("an edge points outside the states")
        if a["best_action"].min() < 0 or a["best_action"].max() >= A or \
                (E and a["edge_action"].max() >= A):
            raise bad("an action id outside action_names")
        steps = a["fill_key_steps"].astype(np.int64)
        if (np.diff(a["keys"]) <= 0).any() or (steps[1:] <= 0).any() or (steps[:1] < 0).any():
            raise bad("keys not strictly ascending")
        if len(a["fill_state"]) and (a["fill_state"].min() < 0 or a["fill_state"].max() >= S):
            raise bad("the look-up fill points outside the states")
        if not (np.isfinite(a["value"]).all() and np.isfinite(a["features"]).all()):
            raise bad("non-finite numbers")
        return cls(
            action_names=[str(x) for x in a["action_names"]], n_choices=int(meta["n_choices"]),
            keys=a["keys"].astype(np.int64), features=a["features"],
            other_action=a["other_action"].astype(np.int64),
            other_frame=a["other_frame"].astype(np.int64), visits=a["visits"],
            best_action=a["best_action"].astype(np.int64), value=a["value"],
            edge_ptr=ptr, edge_dst=a["edge_dst"], edge_action=a["edge_action"],
            edge_steps=a["edge_steps"], edge_flip=a["edge_flip"], edge_reward=a["edge_reward"],
            fill_keys=np.cumsum(steps), fill_state=a["fill_state"],
            grid=grid, rules=rules, rewards=rewards, build=meta.get("build", {}))
