"""A hostile-input campaign: run `quickjab` commands as subprocesses on generated bad files,
URLs and arguments, and count what each run ends in.

    python -m tools.input_campaign [--only WORD] [--timeout 60] [--json] [--keep DIR]

Every case expects either a clean refusal (exit 2, one line on stderr, no traceback) or a
clean run (exit 0). A run is a *traceback* when stderr holds one, a *hang* when it outlives
the timeout, a *blow-up* when its peak RSS passes --max-rss-mb, a *silent accept* when it
exits 0 where a refusal was expected, and a *refusal* of a valid input when it exits non-zero
where a clean run was expected. Each run gets an address-space limit (--limit-mb) so that a
blow-up cannot take the machine down; its peak RSS is its VmHWM, polled from /proc every
20 ms (growth in a run's last 20 ms can be missed). Prints one line per failing run and the totals; exit
code 1 when anything failed.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import signal
import subprocess
import sys
import tempfile
import time
import zipfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
ASSETS = ROOT / "game" / "assets"
GOOD_REC = "# rate_hz: 60\nt,rx,ry,rz,lx,ly,lz,label\n" + "".join(
    f"{i / 60:.6f},0.01,0.02,1.0,0.0,0.01,0.99,\n" for i in range(120)
)


@dataclass
class Case:
    name: str
    argv: list[str]
    expect: str = "error"  # "error": exit 2, one line; "ok": exit 0; "term": ended by the SIGTERM of term_after
    stdin_none: bool = True
    env: dict[str, str] | None = None  # set over the campaign's environment (e.g. XDG_CONFIG_HOME)
    cwd: str | None = None  # where it runs (default: the repository), for relative paths in URLs
    term_after: float | None = None  # send SIGTERM this many seconds in (expect="term": it must end the run)
    names: str | None = None  # the refusal's line must name this (a file whose error named none)
    fsize_kb: int | None = None  # no file over this size can be written (a full disk), SIGXFSZ ignored
    reads_back: str | None = None  # a recording the run leaves behind that must still read (cut short, not broken)


@dataclass
class Outcome:
    case: Case
    rc: int | None
    seconds: float
    rss_mb: float
    stderr: str
    verdict: str = field(default="")


def _write(d: Path, name: str, text: str | bytes) -> str:
    p = d / name
    p.parent.mkdir(parents=True, exist_ok=True)
    if isinstance(text, bytes):
        p.write_bytes(text)
    else:
        p.write_text(text, encoding="utf-8")
    return str(p)


def _rec(rows: list[str], header: str = "t,rx,ry,rz,lx,ly,lz,label") -> str:
    return "# rate_hz: 60\n" + header + "\n" + "".join(r + "\n" for r in rows)


def bad_recordings(d: Path, big_mb: int) -> dict[str, str]:
    """name -> path of a recording that must be refused."""
    row = "0.01,0.02,1.0,0.0,0.01,0.99,"
    out = {
        "gap-1e7": _write(d, "rec/gap.csv", _rec([f"0,{row}", f"10000000,{row}"])),
        "equal-t": _write(d, "rec/equal.csv", _rec([f"1.5,{row}"] * 5)),
        "nan": _write(d, "rec/nan.csv", _rec([f"0,{row}", "0.1,nan,0,1,0,0,1,"])),
        "accel-1e300": _write(d, "rec/accel1e300.csv", _rec([f"0,{row}", "0.1,1e300,0,1,0,0,1,", f"0.2,{row}"])),
        "accel-1e154": _write(d, "rec/accel1e154.csv", _rec([f"0,{row}", "0.1,0,-1e154,1,0,0,1,", f"0.2,{row}"])),
        "inf-t": _write(d, "rec/inf.csv", _rec([f"0,{row}", f"inf,{row}"])),
        "huge-t": _write(d, "rec/huge_t.csv", _rec([f"1e300,{row}", f"1.0000001e300,{row}"])),
        "backwards": _write(d, "rec/back.csv", _rec([f"1,{row}", f"0.5,{row}"])),
        "text": _write(d, "rec/text.csv", _rec([f"0,{row}", f"abc,{row}"])),
        "long-field": _write(d, "rec/long.csv", _rec([f"0,{row}", "0.1," + "1" * 200_000 + ",0,1,0,0,1,"])),
        "long-label": _write(d, "rec/longlab.csv", _rec([f"0,{row}", "0.1,0,0,1,0,0,1," + "x" * 200_000])),
        "wide-row": _write(d, "rec/wide.csv", _rec([f"0,{row}", "0.1,0,0,1,0,0,1," + "0," * 2_000_000])),  # 4M fields, 1 field limit each
        "quote": _write(d, "rec/quote.csv", _rec([f"0,{row}", '0.1,"0,0,1,0,0,1,'])),
        "empty": _write(d, "rec/empty.csv", ""),
        "header-only": _write(d, "rec/header.csv", _rec([])),
        "no-columns": _write(d, "rec/nocol.csv", _rec(["0,1"], header="t,a")),
        "binary": _write(d, "rec/binary.csv", bytes(range(256)) * 64),
        "nul": _write(d, "rec/nul.csv", "t,rx,ry,rz\n0,1,\0,1\n"),
        "newline-name": _write(d, "rec/new\nline.csv", "x"),  # the message naming it was two lines
        "dir": str(d),
        "dev-zero": "/dev/zero",
        "missing": str(d / "rec" / "nope.csv"),
    }
    fifo = d / "rec" / "fifo.csv"
    if not fifo.exists():
        os.mkfifo(fifo)
    out["fifo"] = str(fifo)
    if big_mb:
        p = d / "rec" / f"big{big_mb}.csv"
        if not p.exists():  # a valid phone-rate recording (430 Hz, 1.5 h for 100 MB)
            line = "0.01,0.02,1.0,0.0,0.01,0.99,jab\n"
            n = big_mb * 1024 * 1024 // (len(line) + 10)
            with open(p, "w") as f:
                f.write("t,rx,ry,rz,lx,ly,lz,label\n")
                for start in range(0, n, 100_000):
                    f.write("".join(f"{i / 430:.6f},{line}" for i in range(start, min(n, start + 100_000))))
        out[f"big-{big_mb}mb"] = str(p)
        p = d / "rec" / f"big-cr{big_mb}.csv"  # two rows and a flood of bare '\r': one line end each
        if not p.exists():
            p.write_bytes(b"t,rx,ry,rz\n0,0,0,1\n" + b"\r" * (big_mb * 2**20) + b"1,0,0,1\n")
        out[f"big-cr-{big_mb}mb"] = str(p)
        p = d / "rec" / f"meta{big_mb}.csv"  # distinct `# key: value` lines: each kept, 11x the file
        if not p.exists():
            with open(p, "w") as f:
                for start in range(0, big_mb * 2**20 // 12, 100_000):
                    f.write("".join(f"#{i:x}: v\n" for i in range(start, start + 100_000)))
                f.write("t,rx,ry,rz\n0,0,0,1\n0.1,0,0,1\n")
        out[f"meta-flood-{big_mb}mb"] = str(p)
    return out


def _npz(path: Path, arrays: dict[str, np.ndarray]) -> str:
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "wb") as f:
        np.savez_compressed(f, **arrays)
    return str(path)


def _zip_bomb(path: Path, member: str, declared_gb: float) -> str:
    """An npz whose one member is a .npy header for a huge float64 array, then zeros."""
    if path.exists():
        return str(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    n = int(declared_gb * 2**30 // 8)
    header = np.lib.format.header_data_from_array_1_0(np.zeros(1))
    header["shape"] = (n,)
    import io

    buf = io.BytesIO()
    np.lib.format.write_array_header_1_0(buf, header)
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED, compresslevel=1) as z, z.open(member + ".npy", "w", force_zip64=True) as f:
        f.write(buf.getvalue())
        chunk = bytes(2**24)
        left = n * 8
        while left > 0:
            f.write(chunk[: min(left, len(chunk))])
            left -= len(chunk)
    return str(path)


def _many_members(path: Path, n: int) -> str:
    """A zip of `n` empty members (about 86 bytes each)."""
    if not path.exists():
        path.parent.mkdir(parents=True, exist_ok=True)
        with zipfile.ZipFile(path, "w", zipfile.ZIP_STORED) as z:
            for i in range(n):
                z.writestr(f"{i:x}", b"")
    return str(path)


def bad_templates(d: Path, bomb_gb: float = 1.5) -> dict[str, str]:
    with np.load(ASSETS / "templates.npz", allow_pickle=False) as z:
        good = {k: z[k] for k in z.files}
    out = {}

    def variant(name: str, **changes: np.ndarray | None) -> None:
        a = dict(good)
        for k, v in changes.items():
            if v is None:
                a.pop(k, None)
            else:
                a[k] = v
        out[name] = _npz(d / "tpl" / f"{name}.npz", a)

    g = good["gravity"]
    variant("nan-gravity", gravity=np.full_like(g, np.nan))
    variant("huge-gravity", gravity=np.full_like(g, 1e300))
    variant("signals-1e200", signals=good["signals"] * 1e200)  # finite, absurd: overflowed in the recognizer
    variant("signals-complex", signals=good["signals"] + 1j)  # cast with a ComplexWarning and read
    variant("recognizer-deep", recognizer=np.array("[" * 100_000))  # json.loads: RecursionError
    variant("nan-threshold", thresholds=np.full_like(good["thresholds"], np.nan))
    variant("neg-threshold", thresholds=-np.ones_like(good["thresholds"]))
    variant("gravity-shape", gravity=g[:, :3])
    variant("onsets-shape", onsets=good["onsets"][:2])
    variant("lengths-neg", lengths=-good["lengths"])
    variant("no-signals", signals=None)
    variant("signals-3d", signals=good["signals"][None])
    variant("actions-2d", actions=good["actions"][None])
    variant("meta-mismatch", meta_keys=np.array(["a", "b"]), meta_values=np.array(["x"]))
    variant("version-text", version=np.array("x"))
    variant("method-bad", method=np.array("nope"))
    variant("float-lengths", lengths=good["lengths"].astype(float) + 0.5)
    variant("lengths-wrap-int64", lengths=np.array([2**62] * 3 + [2**62 + len(good["signals"])]),  # sum wraps to the frame count
            actions=good["actions"][:4], gravity=g[:4], onsets=np.zeros(4, np.int64), thresholds=good["thresholds"][:4])
    variant("signals-no-columns", signals=good["signals"][:, :0], gravity=g[:, :0])  # D = 0
    variant("onsets-fraction", onsets=good["onsets"] + 0.5)  # was cut to a whole frame
    variant("recognizer-unknown", recognizer=np.array('{"gate": 0.5}'))
    variant("recognizer-type", recognizer=np.array('{"supplementary": 1e12}'))
    variant("recognizer-not-json", recognizer=np.array("{noise_g: 0.5"))
    variant("recognizer-list", recognizer=np.array("[1, 2, 3]"))
    n = 200_000  # 3-frame templates: a 0.1 MB file, 0.35 GB and 10 s once built
    variant("many-templates", actions=np.array(["jab_r"] * n), lengths=np.full(n, 3), signals=np.tile(good["signals"][:1], (3 * n, 1)),
            gravity=np.tile(g[:1], (n, 1)), onsets=np.zeros(n, np.int64), thresholds=np.ones(n))
    out["npy"] = str(d / "tpl" / "arr.npy")
    np.save(out["npy"], good["signals"])
    out["truncated"] = _write(d, "tpl/trunc.npz", (ASSETS / "templates.npz").read_bytes()[:2000])
    out["text"] = _write(d, "tpl/text.npz", "hello")
    out["zip-bomb"] = _zip_bomb(d / "tpl" / "bomb.npz", "signals", bomb_gb)
    return out


def _graph_variant_writer(d: Path, good: dict, meta: dict, out: dict[str, str]):
    """variant(name, meta_change, **changes) writes the shipped graph with its meta keys
    ("grid.n_angle": value) and arrays changed (None drops one) and records it in `out`."""

    def variant(name: str, meta_change: dict | None = None, **changes: np.ndarray | None) -> None:
        a = dict(good)
        if meta_change is not None:
            m = json.loads(json.dumps(meta))
            for k, v in meta_change.items():
                node = m
                *path, last = k.split(".")
                for p in path:
                    node = node[p]
                node[last] = v
            a["meta"] = np.array(json.dumps(m))
        for k, v in changes.items():
            if v is None:
                a.pop(k, None)
            else:
                a[k] = v
        out[name] = _npz(d / "graph" / f"{name}.npz", a)

    return variant


def _bad_meta_numbers(meta: dict, variant) -> None:
    """Each number in the meta's grid, rules and rewards made NaN, zero or negative."""
    for k, v in meta["grid"].items():
        if isinstance(v, (int, float)) and not isinstance(v, bool):
            variant(f"grid-{k}-nan", {f"grid.{k}": float("nan")})
            variant(f"grid-{k}-zero", {f"grid.{k}": 0})
            variant(f"grid-{k}-neg", {f"grid.{k}": -1})
    for k, v in meta["rules"].items():
        if isinstance(v, (int, float)) and not isinstance(v, bool):
            variant(f"rules-{k}-nan", {f"rules.{k}": float("nan")})
            variant(f"rules-{k}-neg", {f"rules.{k}": -1})
    for k, v in meta["rewards"].items():
        if isinstance(v, (int, float)) and not isinstance(v, bool):
            variant(f"rewards-{k}-nan", {f"rewards.{k}": float("nan")})


def _first_moved(small: np.ndarray, big: np.ndarray, add: int) -> tuple[np.ndarray, np.ndarray]:
    """An escaped pair of a graph file (table.split_small) whose first value is `add` more."""
    small, wide = small.copy(), [int(x) for x in big]
    first = wide.pop(0) if small[0] == -128 else int(small[0])  # -128: table.ESCAPE
    small[0] = -128
    return small, np.array([first + add, *wide], dtype=np.int64)


def bad_graphs(d: Path, bomb_gb: float = 1.5) -> dict[str, str]:
    with np.load(ASSETS / "graph.npz", allow_pickle=False) as z:
        good = {k: z[k] for k in z.files}
    meta = json.loads(str(good["meta"]))
    out: dict[str, str] = {}
    variant = _graph_variant_writer(d, good, meta, out)

    S = len(good["key_steps"])
    E = len(good["edge_action"])
    variant("nan-reward", edge_reward=np.full(E, np.nan, np.float32))
    variant("meta-deep", meta=np.array("[" * 100_000))  # json.loads: RecursionError
    variant("inf-reward", edge_reward=np.full(E, np.inf, np.float32))
    variant("neg-visits", visits=-np.ones(S, np.int32))
    variant("other-action-range", other_action=np.full(S, 999, np.int16))
    variant("other-action-neg", other_action=np.full(S, -5, np.int16))
    variant("other-frame-neg", other_frame=np.full(S, -5, np.int16))
    variant("edge-flip-int", edge_flip=np.full(E, 7, np.int64))
    variant("edge-action-neg", edge_action=np.full(E, -1, np.int64))
    variant("value-text", value=np.array(["x"] * S))
    variant("action-names-int", action_names=np.arange(len(good["action_names"])))
    variant("action-names-2d", action_names=good["action_names"][None])
    variant("n-choices-neg", {"n_choices": -3})
    variant("n-choices-huge", {"n_choices": 10**6})
    variant("n-choices-text", {"n_choices": "x"})
    variant("build-list", {"build": [1]})  # graph info read its keys: AttributeError
    variant("wait-frames-huge", {"rules.wait_frames": 10**12})  # duel: a 568 TiB bout table
    _bad_meta_numbers(meta, variant)
    variant("meta-list", meta=np.array("[1, 2]"))
    variant("meta-2d", meta=np.array([[json.dumps(meta)]]))
    variant("key-steps-neg", key_steps=-good["key_steps"].astype(np.int64))
    variant("feature-pos-float", feature_pos=np.full((S, 3), np.nan))
    variant("edge-count-neg", edge_count=-good["edge_count"].astype(np.int64))
    variant("feature-pos-neg", feature_pos=-1 - good["feature_pos"].astype(np.int32))
    for name, key in (("fill-offset-wrap", "fill_state_offset"), ("edge-dst-wrap", "edge_dst_steps")):
        small, big = _first_moved(good[key], good[f"{key}_big"], 2**32)  # int32 wrapped it back
        variant(name, **{key: small, f"{key}_big": big})
    out["npy"] = str(d / "graph" / "arr.npy")
    np.save(out["npy"], good["visits"])
    out["truncated"] = _write(d, "graph/trunc.npz", (ASSETS / "graph.npz").read_bytes()[:5000])
    out["zip-bomb"] = _zip_bomb(d / "graph" / "bomb.npz", "edge_reward", bomb_gb)
    return out


def bad_traces(d: Path) -> dict[str, str]:
    frame = {"ph": "X", "name": "frame", "ts": 0, "dur": 100, "args": {"steps": 1}}
    stage = {"ph": "X", "name": "physics", "ts": 1, "dur": 10}

    def tr(name: str, obj: object) -> tuple[str, str]:
        text = obj if isinstance(obj, str) else json.dumps(obj)
        return name, _write(d, f"trace/{name}.json", text)

    def ev(**kw: object) -> dict:
        return {"traceEvents": [{**frame, **kw}, stage]}

    cases = [
        tr("args-int", ev(args=5)),
        tr("args-list", ev(args=[1])),
        tr("steps-text", ev(args={"steps": "x"})),
        tr("steps-inf", '{"traceEvents": [{"ph": "X", "name": "frame", "ts": 0, "dur": 1, "args": {"steps": Infinity}}]}'),
        tr("steps-nan", '{"traceEvents": [{"ph": "X", "name": "frame", "ts": 0, "dur": 1, "args": {"steps": NaN}}]}'),
        tr("dur-nan", '{"traceEvents": [{"ph": "X", "name": "frame", "ts": 0, "dur": NaN}]}'),
        tr("dur-inf", '{"traceEvents": [{"ph": "X", "name": "frame", "ts": 0, "dur": Infinity}]}'),
        tr("ts-nan", '{"traceEvents": [{"ph": "X", "name": "frame", "ts": NaN, "dur": 1}]}'),
        tr("ts-huge", ev(ts=1e308, dur=1e308)),
        tr("wait-text", ev(args={"wait_us": "x"})),
        tr("wait-list", ev(args={"wait_us": [1]})),
        tr("dropped-text", ev(args={"dropped": "x"})),
        tr("depth-text", {"traceEvents": [frame, {**stage, "args": {"depth": [1]}}]}),
        tr("name-list", {"traceEvents": [frame, {**stage, "name": ["a"]}]}),
        tr("name-int", {"traceEvents": [frame, {**stage, "name": 5}]}),
        tr("ph-list", {"traceEvents": [frame, {**stage, "ph": ["X"]}]}),
        tr("other-list", {"traceEvents": [frame], "otherData": [1]}),
        tr("budget-text", {"traceEvents": [frame], "otherData": {"frame_budget_ms": "x"}}),
        tr("budget-zero", {"traceEvents": [frame], "otherData": {"frame_budget_ms": 0, "frame_period_ms": -1}}),
        tr("budget-inf", '{"traceEvents": [{"ph": "X", "name": "frame", "ts": 0, "dur": 1}], "otherData": {"frame_budget_ms": Infinity}}'),
        tr("stages-list", {"traceEvents": [frame], "otherData": {"stages": [1]}}),
        tr("stage-budget-text", {"traceEvents": [frame, stage], "otherData": {"stages": {"physics": {"budget_ms": "x"}}}}),
        tr("deep", "[" * 100_000 + "]" * 100_000),
        tr("deep-obj", '{"traceEvents": ' + "[" * 50_000 + "]" * 50_000 + "}"),
        tr("bool-ts", ev(ts=True, dur=False)),
        # another writer's dropped-steps counter: int(Infinity) and a sort of "5" with 6 were tracebacks
        tr("counter-inf", '{"traceEvents": [{"ph": "X", "name": "frame", "ts": 0, "dur": 1}, '
                          '{"ph": "C", "name": "dropped_steps", "ts": 1, "args": {"dropped": Infinity}}]}'),
        tr("counter-ts-text", {"traceEvents": [frame, {"ph": "C", "name": "dropped_steps", "ts": "5", "args": {"dropped": 1}},
                                               {"ph": "C", "name": "dropped_steps", "ts": 6, "args": {"dropped": 2}}]}),
        tr("empty", ""),
        tr("number", "5"),
        tr("no-frame", {"traceEvents": [stage]}),
        tr("bad-utf8", b"\xff\xfe{}".decode("latin-1")),
        # integers no float holds: np.isfinite raised TypeError
        tr("dropped-400-digits", '{"traceEvents": [{"ph": "X", "name": "frame", "ts": 0, "dur": 1, "args": {"dropped": 1' + "0" * 400 + '}}]}'),
        tr("budget-400-digits", '{"traceEvents": [{"ph": "X", "name": "frame", "ts": 0, "dur": 1}], "otherData": {"frame_budget_ms": 1' + "0" * 400 + '}}'),
    ]
    out = dict(cases)
    out["bad-bytes"] = _write(d, "trace/bytes.json", b"\xff\xfe\x00{")
    fifo = d / "trace" / "fifo.json"
    if not fifo.exists():
        os.mkfifo(fifo)
    out["fifo"] = str(fifo)
    return out


BVH_HEAD = """HIERARCHY
ROOT Hips
{
  OFFSET 0 0 0
  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
  JOINT Chest
  {
    OFFSET 0 5 0
    CHANNELS 3 Zrotation Xrotation Yrotation
    End Site
    {
      OFFSET 0 5 0
    }
  }
}
MOTION
"""


def bad_bvh(d: Path) -> dict[str, str]:
    row = "0 90 0 0 0 0 0 0 0"

    def bvh(name: str, frames: str, ftime: str, rows: list[str]) -> tuple[str, str]:
        text = BVH_HEAD + f"Frames: {frames}\nFrame Time: {ftime}\n" + "\n".join(rows) + "\n"
        return name, _write(d, f"bvh/{name}.bvh", text)

    cases = [
        bvh("frames-text", "abc", "0.0166667", [row] * 3),
        bvh("frames-neg", "-5", "0.0166667", [row] * 3),
        bvh("frames-huge", "1000000000", "0.0166667", [row] * 3),
        bvh("ftime-nan", "3", "nan", [row] * 3),
        bvh("ftime-inf", "3", "inf", [row] * 3),
        bvh("ftime-1e9", "3", "1e9", [row] * 3),
        bvh("ftime-zero", "3", "0", [row] * 3),
        bvh("ftime-neg", "3", "-0.01", [row] * 3),
        bvh("ftime-tiny", "3", "1e-300", [row] * 3),
        bvh("pose-nan", "3", "0.0166667", [row, "0 nan 0 0 0 0 0 0 0", row]),
        bvh("pose-inf", "3", "0.0166667", [row, "0 inf 0 0 0 0 0 0 0", row]),
        bvh("pose-text", "3", "0.0166667", [row, "0 x 0 0 0 0 0 0 0", row]),
        bvh("pose-short", "3", "0.0166667", [row, "0 0", row]),
        bvh("pose-huge", "3", "0.0166667", [row, "0 1e308 0 0 0 1e308 0 0 0", row]),
    ]
    out = dict(cases)
    out["empty"] = _write(d, "bvh/empty.bvh", "")
    out["no-motion"] = _write(d, "bvh/nomotion.bvh", BVH_HEAD.replace("MOTION\n", ""))
    out["deep"] = _write(d, "bvh/deep.bvh", "HIERARCHY\nROOT a\n" + "{\nJOINT b\n" * 20000 + "}\n" * 20000)
    out["channels-huge"] = _write(d, "bvh/chan.bvh", BVH_HEAD.replace("CHANNELS 3", "CHANNELS 100000000"))
    out["binary"] = _write(d, "bvh/binary.bvh", bytes(range(256)) * 16)
    out["joints-10001"] = _write(d, "bvh/joints.bvh", "HIERARCHY\nROOT a\n{\n" + "JOINT b\n{\n}\n" * 10_001 + "}\nMOTION\n")
    out["end-site-outside"] = _write(d, "bvh/endsite.bvh", "HIERARCHY\nEnd Site\n{\nOFFSET 0 0 0\n}\n")
    unmapped = d / "bvh" / "unmapped.bvh"  # 24 MB of motion under a hierarchy without our joints
    if not unmapped.exists():  # (read as Python floats before map_joints refused it: 0.9 GB)
        rows = 1_300_000
        unmapped.write_text(BVH_HEAD + f"Frames: {rows}\nFrame Time: 0.001\n" + "0 0 0 0 0 0 0 0 0\n" * rows)
    out["unmapped-24mb"] = str(unmapped)
    fifo = d / "bvh" / "fifo.bvh"
    if not fifo.exists():
        os.mkfifo(fifo)
    out["fifo"] = str(fifo)
    return out


def bad_action_dirs(d: Path) -> dict[str, str]:
    """Copies of the shipped action library with one file made bad."""
    import shutil

    out = {}
    good = json.loads((ASSETS / "actions" / "hook_r.json").read_text())
    for name, change in (("nan-root", {"root": [[0, float("nan"), 0, 0]]}), ("frames-huge", {"frames": 10**9}),
                         ("damage-inf", {"attacks": [{**good["attacks"][0], "damage": float("inf")}]}),
                         ("deep", None), ("fifo", None),
                         ("frames-inf", {"frames": float("inf")}),  # int(Infinity): OverflowError
                         ("name-list", {"name": ["hook_r"]}),  # unhashable in the library: TypeError
                         ("pose-1e307", {"keyframes": [{**good["keyframes"][0],
                                                        "pose": [[1e307] * 3] * len(good["keyframes"][0]["pose"])},
                                                       *good["keyframes"][1:]]}),  # loaded; the sheet overflowed
                         ("not-object", None),  # a JSON list: AttributeError
                         ("dup-name", None)):  # a second hook_r file: it replaced the first, exit 0
        folder = d / "actions" / name
        if folder.exists():
            shutil.rmtree(folder)
        shutil.copytree(ASSETS / "actions", folder)
        target = folder / "hook_r.json"
        if name == "deep":
            target.write_text("[" * 100_000 + "]" * 100_000)
        elif name == "fifo":
            target.unlink()
            os.mkfifo(target)
        elif name == "not-object":
            target.write_text(json.dumps([good]))
        elif name == "dup-name":
            (folder / "zz_hook_r_v2.json").write_text(json.dumps({**good, "description": "a copy"}))
        else:
            target.write_text(json.dumps({**good, **change}))
        out[name] = str(folder)
    return out


def bad_mocap(d: Path, mocap: Path) -> dict[str, str]:
    """A real, mappable BVH with its header or one pose made bad: these reach retargeting."""
    lines = mocap.read_text(encoding="utf-8", errors="replace").splitlines()
    at = next(i for i, ln in enumerate(lines) if ln.strip().lower().startswith("frames:"))
    out = {}
    for name, frames, ftime, pose in (
        ("frames-text", "abc", None, None), ("frames-neg", "-5", None, None), ("frames-zero", "0", None, None),
        ("ftime-nan", None, "nan", None), ("ftime-inf", None, "inf", None), ("ftime-1e9", None, "1e9", None),
        ("ftime-zero", None, "0", None), ("pose-nan", None, None, "nan"), ("pose-inf", None, None, "inf"),
        ("pose-1e300", None, None, "1e300"), ("pose-1e30", None, None, "1e30"),
    ):
        new = list(lines)
        if frames is not None:
            new[at] = f"Frames: {frames}"
        if ftime is not None:
            new[at + 1] = f"Frame Time: {ftime}"
        if pose is not None:
            vals = new[at + 10].split()
            vals[3:6] = [pose] * 3
            new[at + 10] = " ".join(vals)
        out[name] = _write(d, f"mocap/{name}.bvh", "\n".join(new) + "\n")
    return out


def bad_config_files(d: Path) -> dict[str, str]:
    """XDG_CONFIG_HOME directories whose quickjab/config.toml is bad (game/user_config.py)."""
    files: dict[str, str | bytes | None] = {
        "not-toml": "[recognizer\nnoise_g = 0.5\n",
        "unknown-key": "[recognizer]\ngate = 0.5\n",
        "unknown-table": "[recogniser]\nnoise_g = 0.5\n",
        "wrong-type": "[recognizer]\nnoise_g = true\n",
        "huge-buffer": "[recognizer]\nsupplementary = 100000000000\n",
        "nan": "[recognizer]\nnoise_g = nan\n",
        "deep": "[recognizer]\nnoise_g = " + "[" * 100_000 + "]" * 100_000 + "\n",  # tomllib: RecursionError
        "bigint": "[recognizer]\nmain = " + "1" * 5000 + "\n",  # tomllib's int(): a plain ValueError
        "binary": b"\xff\xfe\x00[recognizer]",
        "big": "# " + "x" * (2 << 20) + "\n",
        "directory": None,
        "fifo": None,  # size 0: passes the size limit, and opening it blocks
        "dev-zero": None,  # a symlink to /dev/zero: size 0, and reading it never ends
        "link-loop": None,  # a symlink to itself: exists() said no file, and it was ignored
    }
    out = {}
    for name, content in files.items():
        path = d / "config" / name / "quickjab" / "config.toml"
        path.parent.mkdir(parents=True, exist_ok=True)
        if name == "fifo":
            if not path.exists():
                os.mkfifo(path)
        elif name == "dev-zero":
            if not path.is_symlink():
                path.symlink_to("/dev/zero")
        elif name == "link-loop":
            if not path.is_symlink():
                path.symlink_to(path.name)
        elif content is None:
            path.mkdir(exist_ok=True)
        elif isinstance(content, bytes):
            path.write_bytes(content)
        else:
            path.write_text(content, encoding="utf-8")
        out[name] = str(d / "config" / name)
    return out


def build_cases(d: Path, big_mb: int, bomb_gb: float = 1.5) -> list[Case]:
    q = ["-m", "tools.cli"]
    good_rec = _write(d, "good.csv", GOOD_REC)
    tpl = str(ASSETS / "templates.npz")
    out = d / "out"
    out.mkdir(exist_ok=True)
    recs, tpls, graphs = bad_recordings(d, big_mb), bad_templates(d, bomb_gb), bad_graphs(d, bomb_gb)
    cases = _recording_cases(q, d, recs, tpl, out)
    cases += _bad_file_cases(q, d, tpls, graphs, good_rec, tpl, out)
    cases += _url_cases(q, good_rec, out)
    cases += [Case(f"eval/{name}", q + argv) for name, argv in bad_evaluate_inputs(d, tpl, out).items()]
    args = {**_bad_game_args(q, d, good_rec, tpl, out), **_bad_tool_args(q, d, out)}
    for name, argv in args.items():
        cases.append(Case(f"arg/{name}", argv, names="/dev/full" if "dev-full" in name else None))
    cases += _same_file_cases(q, d)
    # a full disk (files stop at 8 KB): pygame.image.save ignored the failed write and said "wrote"
    for name, argv, path in (("play-screenshot", ["play", "--headless", "--frames", "2", "--screenshot"], out / "full.png"),
                             ("actions-sheet", ["actions", "sheet", "-o"], out / "sheet.png"),
                             ("profile-plot", ["profile", _write(d, "trace/ok.json", '{"traceEvents": [{"ph": "X", "name": "frame", "ts": 0, "dur": 9}]}'),
                                               "--plot"], out / "plot.png")):
        cases.append(Case(f"full/{name}", q + argv + [str(path)], names=str(path), fsize_kb=8))
    # a recording cut short by a full disk: it ended in half a row, and no reader took the file
    full_rec = str(out / "full.csv")
    cases.append(Case("full/record", q + ["record", "--source", f"replay://{good_rec}?speed=1000&loop=1", "--seconds", "10",
                                          "-o", full_rec], names=full_rec, fsize_kb=4, reads_back=full_rec))
    # SDL turned SIGTERM into a quit event nothing in a soak reads: only SIGKILL ended it
    cases.append(Case("signal/soak-sigterm", q + ["soak", "--minutes", "10", "--quiet"], expect="term", term_after=8.0))
    if big_mb:  # ~12,000 empty members a MB: zipfile read them all (6.7x the file) before the count was checked
        many = _many_members(d / "tpl" / f"members{big_mb}.npz", big_mb * 12_000)
        cases += [Case("tpl/many-members/recognize", q + ["recognize", good_rec, "--templates", many]),
                  Case("graph/many-members/info", q + ["graph", "info", many])]
    cases += _valid_cases(q, d, good_rec, tpl, out)
    return cases


def _bump_rows(label: str = "", hands: int = 2, amp: float = 3.0) -> list[str]:
    """Rows of 20 frames of rest, a 24-frame punch of `amp` g on the right hand (labelled), 20 of rest."""
    rows = []
    for i in range(64):
        x = amp * float(np.sin(np.pi * (i - 20) / 24)) if 20 <= i < 44 else 0.0
        left = ",0.0,0.01,0.99" if hands == 2 else ""
        rows.append(f"{i / 60:.6f},{x:.4f},0.02,{1.0 + x:.4f}{left},{label if 20 <= i < 44 else ''}")
    return rows


def bad_evaluate_inputs(d: Path, tpl: str, out: Path) -> dict[str, list[str]]:
    """name -> the quickjab arguments of a bad input to `evaluate` (and the commands next to it):
    data it cannot build templates from, or whose values per frame are not the templates' D,
    or values no sensor reads. Each must end in one line naming the file or folder, exit 2."""
    e = d / "eval"
    one_hand = "t,rx,ry,rz,label"
    stream_1 = _write(e, "stream-1-label.csv", _rec(["0,0,0,1,0,0,1,jab_r"]))
    stream_all = _write(e, "stream-all-label.csv", _rec([f"{i / 60:.6f},0,0,1,0,0,1,jab_r" for i in range(120)]))
    stream_1h = _write(e, "stream-onehand.csv", _rec(_bump_rows("straight_r", hands=1), header=one_hand))
    for action in ("straight_r", "hook_r"):
        _write(e, f"trials-ok/{action}/1.csv", _rec(_bump_rows(action)))
        _write(e, f"trials-one-row/{action}/1.csv", _rec([f"0,0,0,1,0,0,1,{action}"]))
        _write(e, f"trials-onehand/{action}/1.csv", _rec(_bump_rows(action, hands=1), header=one_hand))
        _write(e, f"trials-huge/{action}/1.csv", _rec(_bump_rows(action, amp=1e300 if action == "hook_r" else 3.0)))
    pp = {  # phone-punches folders: right_jab_fast.csv, right_jab_slow.csv
        "unlabelled": (_rec(_bump_rows()), _rec(_bump_rows("jab"))),
        "otherlabel": (_rec(_bump_rows("hook")), _rec(_bump_rows("jab"))),
        "onerow": (_rec(["0,0,0,1,0,0,1,jab"]), _rec(["0,0,0,1,0,0,1,jab"])),
        "onehand": (_rec(_bump_rows("jab", hands=1), header=one_hand), _rec(_bump_rows("jab"))),
    }
    for name, (fast, slow) in pp.items():
        _write(e, f"pp-{name}/right_jab_fast.csv", fast)
        _write(e, f"pp-{name}/right_jab_slow.csv", slow)
    for n in (1, 2):  # two gloves, one row: a punch (9 g) of one frame
        _write(e, f"pb-onerow/right-hook-50-a-combo-lh-{n}.csv", _rec(["0,9,0,1,9,0,1,"]))
    _write(e, "uw-onerow/U1/gesture1/d1-r01.csv", _rec(["0,0,0,1,x"], header=one_hand))
    _write(e, "uw-onerow/U1/gesture1/d2-r01.csv", _rec(_bump_rows("x", hands=1), header=one_hand))
    _write(e, "uw-mismatch/U1/gesture1/d1-r01.csv", _rec(_bump_rows("x", hands=1), header=one_hand))
    _write(e, "uw-mismatch/U1/gesture1/d2-r01.csv", _rec(_bump_rows("x")))
    for g, days in (("gesture1", (1, 2)), ("gesture2", (2,))):  # gesture2: tests, no day-1 reps (counted as misses, exit 0)
        for day in days:
            _write(e, f"uw-nod1/U1/{g}/d{day}-r01.csv", _rec(_bump_rows("x", hands=1), header=one_hand))
    accel = _write(e, "accel-1e306.csv", _rec([f"{i / 60:.5f},1e306,0,1,0,0,1," for i in range(3)]))
    m6 = ["--mains", "6"]
    return {
        "stream-1-label/folds": ["evaluate", stream_1, *m6],
        "stream-all-label/folds": ["evaluate", stream_all, *m6],
        "train-one-row": ["evaluate", str(e / "trials-ok"), "--train", str(e / "trials-one-row"), *m6],
        "stream-onehand/templates": ["evaluate", stream_1h, "--templates", tpl, *m6],
        "trials-onehand/templates": ["evaluate", str(e / "trials-onehand"), "--templates", tpl, *m6],
        "trials-onehand/train": ["evaluate", str(e / "trials-onehand"), "--train", str(e / "trials-ok"), *m6],
        **{f"pp-{name}": ["evaluate", "--phone-punches", str(e / f"pp-{name}"), *m6] for name in pp},
        "pb-onerow": ["evaluate", "--punchbuddy", str(e / "pb-onerow"), *m6],
        "uw-onerow": ["evaluate", "--uwave", str(e / "uw-onerow"), "--users", "1", *m6],
        "uw-mismatch": ["evaluate", "--uwave", str(e / "uw-mismatch"), "--users", "1", *m6],
        "uw-nod1": ["evaluate", "--uwave", str(e / "uw-nod1"), "--users", "1", *m6],
        "trials-huge/build": ["templates", "build", str(e / "trials-huge"), "-o", str(out / "huge.npz")],
        "trials-huge/train": ["evaluate", str(e / "trials-ok"), "--train", str(e / "trials-huge"), *m6],
        "accel-1e306/bridge-emulate": ["bridge", "emulate", "--replay", accel, "--seconds", "2"],
    }


def _recording_cases(q: list[str], d: Path, recs: dict[str, str], tpl: str, out: Path) -> list[Case]:
    """Bad recordings through recognize, record, evaluate, wiimote-emu, scope and templates build."""
    cases: list[Case] = []
    for name, path in recs.items():
        if name.startswith("big"):  # valid: read whole (memory is the figure), replayed briefly
            cases.append(Case(f"ok/{name}/record-replay", q + ["record", "--source", f"replay://{path}?speed=1000", "--seconds", "0.5", "-o", str(out / "b.csv")], expect="ok"))
            continue
        cases.append(Case(f"rec/{name}/recognize", q + ["recognize", path, "--templates", tpl]))
        cases.append(Case(f"rec/{name}/record-replay", q + ["record", "--source", f"replay://{path}", "--seconds", "0.3", "-o", str(out / "r.csv")]))
        cases.append(Case(f"rec/{name}/evaluate", q + ["evaluate", path, "--mains", "6"]))
    for name in ("gap-1e7", "equal-t", "fifo", "long-field"):
        path = recs[name]
        cases.append(Case(f"rec/{name}/wiimote-emu", q + ["record", "--source", f"wiimote-emu://{path}", "--seconds", "0.3", "-o", str(out / "r.csv")]))
        cases.append(Case(f"rec/{name}/scope", q + ["scope", "--headless", "--frames", "3", "--source", f"replay://{path}"]))
    trials = d / "trials" / "jab"
    trials.mkdir(parents=True, exist_ok=True)
    (trials / "1.csv").write_text(_rec(["0,0,0,1,0,0,1,", "10000000,0,0,1,0,0,1,"]))
    cases.append(Case("rec/gap/templates-build", q + ["templates", "build", str(d / "trials"), "-o", str(out / "t.npz")]))
    return cases


def _bad_file_cases(q: list[str], d: Path, tpls: dict[str, str], graphs: dict[str, str], good_rec: str,
                    tpl: str, out: Path) -> list[Case]:
    """Bad templates, config files, graphs, traces, BVH files and action folders, each
    through the commands that read it."""
    cases: list[Case] = []
    for name, path in tpls.items():
        cases.append(Case(f"tpl/{name}/recognize", q + ["recognize", good_rec, "--templates", path]))
    for name in ("nan-gravity", "zip-bomb", "npy", "recognizer-unknown", "signals-1e200"):
        cases.append(Case(f"tpl/{name}/play", q + ["play", "--headless", "--frames", "2", "--templates", tpls[name]]))
    labelled = _write(d, "labelled.csv", _rec(_bump_rows("straight_r")))
    for name in ("signals-1e200", "huge-gravity"):
        cases.append(Case(f"tpl/{name}/evaluate", q + ["evaluate", labelled, "--templates", tpls[name], "--mains", "6"]))
    own = d / "data" / "recognizer-deep"  # the player's own templates, which play loads unasked
    (own / "quickjab").mkdir(parents=True, exist_ok=True)
    (own / "quickjab" / "templates.npz").write_bytes(Path(tpls["recognizer-deep"]).read_bytes())
    cases.append(Case("tpl/recognizer-deep/own-play", q + ["play", "--headless", "--frames", "2"], env={"XDG_DATA_HOME": str(own)}))
    for name, home in bad_config_files(d).items():
        cases.append(Case(f"config/{name}/play", q + ["play", "--headless", "--frames", "2"], env={"XDG_CONFIG_HOME": home}))
        cases.append(Case(f"config/{name}/recognize", q + ["recognize", good_rec, "--templates", tpl], env={"XDG_CONFIG_HOME": home}))
    for name, path in graphs.items():
        cases.append(Case(f"graph/{name}/info", q + ["graph", "info", path]))
    for name in ("nan-reward", "zip-bomb", "npy", "other-action-range"):
        cases.append(Case(f"graph/{name}/duel", q + ["graph", "duel", "--graph", graphs[name], "--bouts", "1", "--seconds", "2"]))
    for name, path in bad_traces(d).items():
        cases.append(Case(f"trace/{name}/profile", q + ["profile", path]))
    for name, path in bad_bvh(d).items():
        cases.append(Case(f"bvh/{name}/info", q + ["bvh", "info", path]))
        if name.startswith(("pose", "ftime")):
            cases.append(Case(f"bvh/{name}/cut", q + ["bvh", "cut", path, "--start", "0", "--end", "2", "--name", "x", "-o", str(out / "a.json")]))
    mocap = ROOT.parent / "shared" / "data" / "mocap" / "cmu_02_05_punch_strike.bvh"
    if mocap.exists():
        for name, path in bad_mocap(d, mocap).items():
            cases.append(Case(f"mocap/{name}/info", q + ["bvh", "info", path]))
            cases.append(Case(f"mocap/{name}/cut", q + ["bvh", "cut", path, "--start", "0", "--end", "20", "--name", "x", "-o", str(out / "m.json")]))
    for name, folder in bad_action_dirs(d).items():
        cases.append(Case(f"actions/{name}/list", q + ["actions", "list", "--dir", folder]))
    return cases


def _url_cases(q: list[str], good_rec: str, out: Path) -> list[Case]:
    """Source URLs with bad parameters, through record and scope."""
    cases: list[Case] = []
    emu = f"wiimote-emu://{good_rec}"
    # two samples a nanosecond apart, looped: a billion a second owed at every poll (a hang, 6 GB)
    one_ns = _write(Path(good_rec).parent, "rec/one-ns.csv", "t,rx,ry,rz\n0,0,0,1\n1e-9,0,0,1\n")
    urls = {
        "demo-rate-1e9": "demo://?rate=1e9",
        "demo-rate-nan": "demo://?rate=nan",
        "demo-rate-inf": "demo://?rate=inf",
        "demo-rate-tiny": "demo://?rate=1e-300",
        "emu-drop-2": emu + "?drop=2",
        "emu-drop-nan": emu + "?drop=nan",
        "emu-latency-1e9": emu + "?latency_ms=1e9",
        "emu-latency-neg": emu + "?latency_ms=-5",
        "emu-jitter-nan": emu + "?jitter_ms=nan",
        "emu-jitter-1e9": emu + "?jitter_ms=1e9",
        "emu-pad-neg": emu + "?pad=-1",
        "emu-pad-huge": emu + "?pad=100000000",
        "emu-seed-neg": emu + "?seed=-1",
        "emu-start-nan": emu + "?start=nan",
        "emu-start-inf": emu + "?start=inf",
        "emu-player-9": emu + "?player=9",
        "emu-unplug-nan": emu + "?unplug_at=nan",
        "keyboard-seed-neg": "keyboard://?seed=-1",
        "keyboard-seed-text": "keyboard://?seed=x",
        "keyboard-profile": "keyboard://?profile=nope",
        "replay-speed-nan": f"replay://{good_rec}?speed=nan",
        "replay-speed-inf": f"replay://{good_rec}?speed=inf",
        "replay-speed-tiny": f"replay://{good_rec}?speed=1e-300",
        "replay-speed-huge": f"replay://{good_rec}?speed=1e300",
        "replay-loop-1ns": f"replay://{one_ns}?loop=1",
        "serial-retry-nan": "serial:///dev/quickjab-none?retry=nan",  # never reopened a lost port
        "serial-window-inf": "serial:///dev/quickjab-none?window=inf",  # the clock's deque never shrank
        "unknown": "nope://x",
        "no-scheme": "x.csv",
    }
    for name, url in urls.items():
        cases.append(Case(f"url/{name}/record", q + ["record", "--source", url, "--seconds", "0.3", "-o", str(out / "u.csv")]))
    for name in ("demo-rate-1e9", "emu-drop-2", "keyboard-seed-neg"):
        cases.append(Case(f"url/{name}/scope", q + ["scope", "--headless", "--frames", "3", "--source", urls[name]]))
    # a relative path is urlsplit's host part: '[' (IPv6) or a character NFKC turns into '/' raised ValueError
    rec_dir = str(Path(good_rec).parent)
    for name, file in (("bracket", "[x.csv"), ("nfkc-slash", "a\uff0fb.csv")):
        cases.append(Case(f"url/{name}-missing/record", q + ["record", "--source", f"replay://{file}", "--seconds", "0.3",
                                                              "-o", str(out / "u.csv")], cwd=rec_dir))
        _write(Path(rec_dir), f"named/{file}", GOOD_REC)
        cases.append(Case(f"ok/url-{name}-name/record", q + ["record", "--source", f"replay://{file}", "--seconds", "0.3",
                                                             "-o", str(out / "u.csv")], expect="ok", cwd=str(Path(rec_dir) / "named")))
    return cases


def _bad_game_args(q: list[str], d: Path, good_rec: str, tpl: str, out: Path) -> dict[str, list[str]]:
    """Bad options of play, train, scope, evaluate, recognize and the --recognizer settings."""
    ev_base = q + ["evaluate", good_rec]
    return {
        "play-seed-neg": q + ["play", "--headless", "--frames", "2", "--seed", "-1"],
        "play-size-huge": q + ["play", "--headless", "--frames", "2", "--size", "20000x20000"],
        "play-size-text": q + ["play", "--headless", "--frames", "2", "--size", "abc"],
        "play-size-zero": q + ["play", "--headless", "--frames", "2", "--size", "0x0"],
        "play-frames-neg": q + ["play", "--headless", "--frames", "-1"],
        "train-seed-neg": q + ["train", "--headless", "--frames", "2", "--seed", "-1"],
        "train-size-huge": q + ["train", "--headless", "--frames", "2", "--size", "20000x20000"],
        "scope-size-huge": q + ["scope", "--headless", "--frames", "2", "--size", "20000x20000"],
        "scope-seconds-nan": q + ["scope", "--headless", "--frames", "2", "--seconds", "nan"],
        "scope-seconds-zero": q + ["scope", "--headless", "--frames", "2", "--seconds", "0"],
        "eval-folds-1": ev_base + ["--folds", "1"],
        "eval-folds-huge": ev_base + ["--folds", "100000"],
        "eval-every-0": q + ["evaluate", str(d / "trials"), "--templates", tpl, "--every", "0"],
        "eval-supp-0": ev_base + ["--supplementary", "0"],
        "eval-noise-neg": ev_base + ["--noise-g", "-1"],
        "eval-noise-nan": ev_base + ["--noise-g", "nan"],
        "eval-null-0": ev_base + ["--null-frames", "0"],
        "eval-discard-neg": ev_base + ["--discard-frames", "-1"],
        "eval-complete-nan": ev_base + ["--complete", "nan"],
        "eval-mains-0": ev_base + ["--mains", "0"],
        "eval-mains-text": ev_base + ["--mains", "a-b"],
        "eval-mains-huge": ev_base + ["--mains", "1-100000000"],
        "eval-clip-0": ev_base + ["--clip-frames", "0"],
        "eval-users-text": q + ["evaluate", "--uwave", str(d), "--users", "x"],
        "recognize-main-huge": q + ["recognize", good_rec, "--templates", tpl, "--main", "100000000"],
        "recognize-recognizer-huge": q + ["recognize", good_rec, "--templates", tpl, "--recognizer", "supplementary=100000000"],
        "recognize-recognizer-nan": q + ["recognize", good_rec, "--templates", tpl, "--recognizer", "noise_g=nan"],
        "recognize-recognizer-twice": q + ["recognize", good_rec, "--templates", tpl, "--main", "3", "--recognizer", "main=4"],
        "play-recognizer-unknown": q + ["play", "--headless", "--frames", "2", "--recognizer", "gate=0.5"],
        "play-recognizer-no-value": q + ["play", "--headless", "--frames", "2", "--recognizer", "noise_g"],
        "train-recognizer-type": q + ["train", "--headless", "--frames", "2", "--recognizer", "reject=maybe"],
        "templates-build-recognizer-bad": q + ["templates", "build", str(d / "trials"), "-o", str(out / "t.npz"), "--recognizer", "adapt=-1"],
        "evaluate-recognizer-unknown": ev_base + ["--recognizer", "x=1"],
        "evaluate-plot-xyz": ev_base + ["--mains", "6", "--plot", str(out / "fig.xyz")],
        # a missing folder is made (as for every output); one under a file cannot be
        "play-screenshot-under-a-file": q + ["play", "--headless", "--frames", "2", "--screenshot",
                                             _write(d, "plain/file", "x") + "/no/s.png"],
        "play-trace-a-dir": q + ["play", "--headless", "--frames", "2", "--trace", str(out)],
        "scope-screenshot-under-a-file": q + ["scope", "--headless", "--frames", "2", "--screenshot",
                                              _write(d, "plain/file", "x") + "/no/s.png"],
        # /dev/full passes the folder check and takes nothing (a full disk): pygame.error, or ENOSPC naming no file
        "play-screenshot-dev-full": q + ["play", "--headless", "--frames", "2", "--screenshot", "/dev/full"],
        "play-trace-dev-full": q + ["play", "--headless", "--frames", "2", "--trace", "/dev/full"],
        "record-o-dev-full": q + ["record", "--source", "demo://", "--seconds", "0.8", "-o", "/dev/full"],
        "templates-build-o-dev-full": q + ["templates", "build", str(d / "eval" / "trials-ok"), "-o", "/dev/full"],
        "bvh-export-o-dev-full": q + ["bvh", "export", "--play", "straight_l", "-o", "/dev/full"],
        "recognize-o-dev-full": q + ["recognize", _write(d, "rec/punch.csv", _rec(_bump_rows())), "--templates", tpl, "-o", "/dev/full"],
        # found only once the trials were done, the session lost: refused before it
        "train-o-dir": q + ["train", "--headless", "--demo", "--frames", "2", "-o", str(out)],
        "train-o-corrupt": q + ["train", "--headless", "--demo", "--frames", "2", "-o", _write(d, "tpl/corrupt.npz", "x")],
    }


def _bad_tool_args(q: list[str], d: Path, out: Path) -> dict[str, list[str]]:
    """Bad options of synth, soak, graph, record and bvh."""
    return {
        "synth-session-nan": q + ["synth", "--session", "nan", "-o", str(out / "s.csv")],
        "synth-session-neg": q + ["synth", "--session", "-1", "-o", str(out / "s.csv")],
        "synth-session-huge": q + ["synth", "--session", "1e12", "-o", str(out / "s.csv")],
        "synth-trials-0": q + ["synth", "--trials", "0", "-o", str(out / "st")],
        "synth-trials-neg": q + ["synth", "--trials", "-1", "-o", str(out / "st")],
        "synth-rest-neg": q + ["synth", "--trials", "1", "--rest", "-1", "-o", str(out / "st")],
        "synth-seed-neg": q + ["synth", "--trials", "1", "--seed", "-1", "-o", str(out / "st")],
        "soak-steps-neg": q + ["soak", "--steps", "-1", "--quiet"],
        "soak-minutes-nan": q + ["soak", "--minutes", "nan", "--quiet"],
        "soak-render-neg": q + ["soak", "--steps", "10", "--render-every", "-1", "--quiet"],
        "soak-sample-0": q + ["soak", "--steps", "10", "--sample-seconds", "0", "--quiet"],
        "soak-seed-neg": q + ["soak", "--steps", "10", "--seed", "-1", "--quiet"],
        "graph-build-states-0": q + ["graph", "build", "-o", str(out / "g.npz"), "--states", "0", "--quiet"],
        "graph-build-seed-neg": q + ["graph", "build", "-o", str(out / "g.npz"), "--seed", "-1", "--quiet"],
        "graph-build-bouts-0": q + ["graph", "build", "-o", str(out / "g.npz"), "--bouts", "0", "--quiet"],
        "graph-duel-bouts-0": q + ["graph", "duel", "--bouts", "0"],
        "graph-duel-bouts-neg": q + ["graph", "duel", "--bouts", "-1"],
        "graph-duel-seconds-nan": q + ["graph", "duel", "--bouts", "1", "--seconds", "nan"],
        "graph-duel-seconds-huge": q + ["graph", "duel", "--bouts", "1", "--seconds", "1e12"],
        "graph-duel-seed-neg": q + ["graph", "duel", "--bouts", "1", "--seconds", "2", "--seed", "-1"],
        "record-seconds-nan": q + ["record", "--source", "demo://", "--seconds", "nan", "-o", str(out / "x.csv")],
        "record-seconds-neg": q + ["record", "--source", "demo://", "--seconds", "-1", "-o", str(out / "x.csv")],
        "actions-sheet-o-dir": q + ["actions", "sheet", "-o", str(out)],  # pygame.error: a traceback
        "bvh-export-gap-nan": q + ["bvh", "export", "--play", "guard", "--gap", "nan", "-o", str(out / "x.bvh")],
        "bvh-cut-start-neg": q + ["bvh", "cut", _write(d, "bvh/ok.bvh", BVH_HEAD + "Frames: 3\nFrame Time: 0.0166667\n" + "0 90 0 0 0 0 0 0 0\n" * 3), "--start", "-5", "--end", "1", "--name", "x", "-o", str(out / "a.json")],
    }


def _same_file_cases(q: list[str], d: Path) -> list[Case]:
    """An output that is one of the command's inputs: each destroyed its input and exited 0
    (recognize emptied the recording, bvh cut wrote JSON over the capture). Own copies each."""
    s = d / "same"
    rec = lambda name: _write(s, name, GOOD_REC)  # noqa: E731
    trial = _write(s, "trials/jab/1.csv", GOOD_REC.replace(",\n", ",jab\n"))
    tpl = str(s / "t.npz")
    Path(tpl).write_bytes((ASSETS / "templates.npz").read_bytes())
    mocap = ROOT.parent / "shared" / "data" / "mocap" / "cmu_02_05_punch_strike.bvh"  # mappable: cut writes
    bvh = _write(s, "m.bvh", mocap.read_bytes() if mocap.exists() else BVH_HEAD)
    r1, r2, r3 = rec("r1.csv"), rec("r2.csv"), rec("r3.csv")
    argvs = {
        "recognize-o-recording": ["recognize", r1, "--templates", str(ASSETS / "templates.npz"), "-o", r1],
        "build-o-trial": ["templates", "build", str(s / "trials"), "-o", trial],
        "bvh-cut-o-file": ["bvh", "cut", bvh, "--start", "0", "--end", "20", "--name", "x", "-o", bvh],
        "record-o-replayed": ["record", "--source", f"replay://{r2}", "--seconds", "0.3", "-o", r2],
        "play-screenshot-templates": ["play", "--headless", "--frames", "2", "--templates", tpl, "--screenshot", tpl],
        "scope-trace-replayed": ["scope", "--headless", "--frames", "2", "--source", f"replay://{r3}", "--trace", r3],
    }
    return [Case(f"same/{name}", q + argv) for name, argv in argvs.items()]


def _valid_cases(q: list[str], d: Path, good_rec: str, tpl: str, out: Path) -> list[Case]:
    """Valid inputs that must keep working."""
    cases: list[Case] = []
    emu = f"wiimote-emu://{good_rec}"
    cases.append(Case("ok/recognize-good", q + ["recognize", good_rec, "--templates", tpl], expect="ok"))
    cases.append(Case("ok/graph-info-shipped", q + ["graph", "info"], expect="ok"))
    still = _write(d, "eval/trials-still/straight_r/1.csv", GOOD_REC)  # every frame alike: its onset was an IndexError
    cases.append(Case("ok/evaluate-still-trial", q + ["evaluate", str(Path(still).parent.parent), "--train",
                                                      str(d / "eval" / "trials-ok"), "--mains", "6"], expect="ok"))
    stages = [{"ph": "X", "name": f"s{i}", "ts": 1, "dur": 1} for i in range(50_000)]  # a band each: minutes to draw
    many = _write(d, "trace/stages50000.json", json.dumps({"traceEvents": [{"ph": "X", "name": "frame", "ts": 0, "dur": 9}, *stages]}))
    cases.append(Case("ok/profile-plot-50000-stages", q + ["profile", many, "--plot", str(out / "p.png")], expect="ok"))
    # the guard loops and never returns to the guard: export stepped it for ever, memory growing
    cases.append(Case("ok/bvh-export-guard", q + ["bvh", "export", "--play", "guard", "-o", str(out / "g.bvh")], expect="ok"))
    cases.append(Case("ok/record-demo", q + ["record", "--source", "demo://?rate=100", "--seconds", "0.3", "-o", str(out / "d.csv")], expect="ok"))
    cases.append(Case("ok/record-emu", q + ["record", "--source", emu, "--seconds", "0.5", "-o", str(out / "e.csv")], expect="ok"))
    # bytes that are not UTF-8 in an argument or a file name (lone surrogates): UnicodeEncodeError
    odd = _write(d, "rec/\udcff.csv", GOOD_REC)
    cases.append(Case("ok/record-label-not-utf8", q + ["record", "--source", "demo://?rate=100", "--seconds", "0.3",
                                                       "--label", "\udcff", "-o", str(out / "d.csv")], expect="ok"))
    cases.append(Case("ok/record-name-not-utf8", q + ["record", "--source", f"replay://{odd}", "--seconds", "0.3",
                                                      "-o", str(out / "d.csv")], expect="ok"))
    long_rec = d / "rec" / "long400k.csv"
    if not long_rec.exists():  # 400k rows at 100 Hz: wiimote-emu's poll must not depend on the length
        long_rec.write_text("t,rx,ry,rz,lx,ly,lz\n" + "".join(f"{i / 100:.2f},0.1,0,1,0,0.1,1\n" for i in range(400_000)))
    cases.append(Case("ok/record-emu-400k", q + ["record", "--source", f"wiimote-emu://{long_rec}", "--seconds", "1", "-o", str(out / "e.csv")], expect="ok"))
    data = ROOT.parent / "shared" / "data"
    if (data / "phone-boxing" / "train.csv").exists():
        cases.append(Case("ok/replay-phone", q + ["record", "--source", f"replay://{data / 'phone-boxing' / 'train.csv'}?speed=100", "--seconds", "0.3", "-o", str(out / "p.csv")], expect="ok"))
    if (data / "mocap").is_dir():
        for bvh in sorted((data / "mocap").glob("*.bvh")):
            cases.append(Case(f"ok/bvh-info-{bvh.stem}", q + ["bvh", "info", str(bvh)], expect="ok"))
    return cases


def _limit(limit_mb: int, fsize_kb: int | None = None):
    def apply() -> None:
        os.setpgrp()
        if fsize_kb:  # a write past it fails with EFBIG, as one on a full disk with ENOSPC
            signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
            resource.setrlimit(resource.RLIMIT_FSIZE, (fsize_kb * 1024, fsize_kb * 1024))
        if limit_mb:
            resource.setrlimit(resource.RLIMIT_AS, (limit_mb * 2**20, limit_mb * 2**20))
        os.nice(10)

    return apply


def _peak_rss_mb(pid: int, marker: str) -> float | None:
    """The child's high-water RSS from /proc, once it runs our command (before its exec the
    child is a copy of this process, whose size says nothing; ru_maxrss keeps that copy's)."""
    try:
        if marker not in Path(f"/proc/{pid}/cmdline").read_bytes().decode("utf-8", "replace"):
            return None
        for line in Path(f"/proc/{pid}/status").read_text().splitlines():
            if line.startswith("VmHWM:"):
                return int(line.split()[1]) / 1024
    except OSError:
        pass
    return None


def run_case(case: Case, timeout: float, limit_mb: int, env: dict) -> Outcome:
    with tempfile.TemporaryFile() as err, tempfile.TemporaryFile() as so:
        start = time.monotonic()
        p = subprocess.Popen([sys.executable, *case.argv], stdin=subprocess.DEVNULL, stdout=so, stderr=err,
                             cwd=case.cwd or ROOT, env={**env, **(case.env or {})}, preexec_fn=_limit(limit_mb, case.fsize_kb))
        rc = None
        rss = 0.0
        term_at = case.term_after
        marker = case.argv[1] if len(case.argv) > 1 else sys.executable
        while True:
            rss = max(rss, _peak_rss_mb(p.pid, marker) or 0.0)
            pid, status, _ = os.wait4(p.pid, os.WNOHANG)
            if pid:
                rc = os.waitstatus_to_exitcode(status)
                break
            if term_at is not None and time.monotonic() - start > term_at:
                os.kill(p.pid, signal.SIGTERM)
                term_at = None  # once
            if time.monotonic() - start > timeout:
                os.killpg(p.pid, signal.SIGKILL)
                os.wait4(p.pid, 0)
                break
            time.sleep(0.02)
        p.returncode = rc if rc is not None else -9  # reaped by wait4 already
        seconds = time.monotonic() - start
        err.seek(0)
        text = err.read().decode("utf-8", "replace")
    return Outcome(case, rc, seconds, rss, text)


def judge(o: Outcome, max_rss_mb: float) -> str:
    if o.rc is None:
        return "hang"
    if "Traceback" in o.stderr:
        return "memory" if "MemoryError" in o.stderr else "traceback"
    if o.rss_mb > max_rss_mb:
        return "memory"
    if o.case.expect == "term":
        return "ok" if o.rc == -signal.SIGTERM else f"exit-{o.rc}"
    if o.case.expect == "ok":
        return "ok" if o.rc == 0 else "refused-valid"
    if o.rc == 0:
        return "silent-accept"
    lines = [ln for ln in o.stderr.splitlines() if ln.strip()]
    if o.rc != 2:
        return f"exit-{o.rc}"
    # the refusal is the last line: "quickjab CMD: ..." or argparse's "quickjab CMD: error: ..."
    # (status lines such as "no Wiimote found: playing from the keyboard" may come before it)
    if not (lines and lines[-1].startswith("quickjab")):
        return "no-message"
    if o.case.names and o.case.names not in lines[-1]:
        return "unnamed"
    return "unreadable-output" if o.case.reads_back and not _reads_back(o.case.reads_back) else "ok"


def _reads_back(path: str) -> bool:
    from engine.recording import RecordingError, read_recording

    try:
        read_recording(path)
    except RecordingError:
        return False
    return True


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--only", action="append", default=[], help="run the cases whose name contains this (repeatable)")
    ap.add_argument("--timeout", type=float, default=120.0, help="seconds before a run counts as a hang (default 120)")
    ap.add_argument("--limit-mb", type=int, default=3072, help="address-space limit per run (default 3072)")
    ap.add_argument("--max-rss-mb", type=float, default=600.0, help="peak RSS that counts as a blow-up (default 600)")
    ap.add_argument("--big-mb", type=int, default=100, help="size of the big-CSV case (0: none)")
    ap.add_argument("--keep", default=None, help="build the inputs here (default: a temporary directory)")
    ap.add_argument("--json", action="store_true", help="one JSON line per run")
    args = ap.parse_args(argv)
    env = {**os.environ, "PYTHONPATH": str(ROOT), "SDL_VIDEODRIVER": "dummy", "SDL_AUDIODRIVER": "dummy",
           "XDG_DATA_HOME": tempfile.mkdtemp(prefix="qj-campaign-data-"),
           "XDG_CONFIG_HOME": tempfile.mkdtemp(prefix="qj-campaign-config-")}  # never the user's own file
    tmp = tempfile.TemporaryDirectory() if args.keep is None else None
    d = Path(args.keep or tmp.name)  # type: ignore[union-attr]
    d.mkdir(parents=True, exist_ok=True)
    cases = build_cases(d, args.big_mb)
    if args.only:
        cases = [c for c in cases if any(w in c.name for w in args.only)]
    counts: dict[str, int] = {}
    peak = 0.0
    for c in cases:
        o = run_case(c, args.timeout, args.limit_mb, env)
        o.verdict = judge(o, args.max_rss_mb)
        counts[o.verdict] = counts.get(o.verdict, 0) + 1
        peak = max(peak, o.rss_mb)
        last = (o.stderr.strip().splitlines() or [""])[-1][:160]
        if args.json:
            print(json.dumps({"case": c.name, "verdict": o.verdict, "rc": o.rc, "s": round(o.seconds, 2),
                              "rss_mb": round(o.rss_mb, 1), "stderr": last}), flush=True)
        elif o.verdict != "ok":
            print(f"{o.verdict:<14} {c.name:<44} rc={o.rc} {o.seconds:6.1f}s {o.rss_mb:7.0f}MB  {last}", flush=True)
    bad = sum(v for k, v in counts.items() if k != "ok")
    print(f"{len(cases)} runs: " + ", ".join(f"{k} {v}" for k, v in sorted(counts.items())) + f"; peak RSS {peak:.0f} MB")
    if tmp is not None:
        tmp.cleanup()
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
