"""docs/formats.md, the project's copy of the formats contract: its contract part is the agreed
text, and every example in it parses with the project's own readers (recordings through
read_recording, events as JSON lines with the documented keys, traces through
read_chrome_trace and against what engine.trace writes)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from engine.budget import FrameBudget
from engine.clock import VirtualClock
from engine.loop import FixedStepLoop
from engine.recording import read_recording
from engine.trace import chrome_trace, read_chrome_trace

REPO = Path(__file__).resolve().parent.parent
DOC = REPO / "docs" / "formats.md"
SHARED_FORMATS = REPO.parent / "shared" / "FORMATS.md"
ADDED = "## Added since"

EVENT_KINDS = {"start", "switch", "end", "reject"}
EVENT_KEYS = {  # every key docs/formats.md names for an event line
    "frame", "t", "event", "action", "score", "from_frame", "called_off",
    "speed", "direction", "peak_g", "onset_frame", "late", "reason",
}


def blocks() -> list[tuple[str, str]]:
    """(section heading, fenced block text) for every ``` block in the doc, in order."""
    out, section, inside, lines = [], "", False, []
    for line in DOC.read_text(encoding="utf-8").splitlines():
        if line.startswith("```"):
            if inside:
                out.append((section, "\n".join(lines) + "\n"))
            inside, lines = not inside, []
        elif inside:
            lines.append(line)
        elif line.startswith("#"):
            section = line.lstrip("#").strip()
    return out


def of_kind(kind: str) -> list[str]:
    return [text for section, text in blocks() if kind in section]


def test_the_doc_has_the_examples_this_test_reads():
    assert len(of_kind("Recording")) == 2 and len(of_kind("event")) == 2 and len(of_kind("trace")) == 1
    assert len(of_kind("config")) == 1
    assert len(blocks()) == 6  # a new example needs a check here


def test_the_contract_part_is_the_agreed_text():
    if not SHARED_FORMATS.is_file():
        pytest.skip(f"no agreed FORMATS.md at {SHARED_FORMATS}")
    text = DOC.read_text(encoding="utf-8")
    contract = text[text.index("# File formats"): text.index(ADDED)].rstrip("\n") + "\n"
    assert contract == SHARED_FORMATS.read_text(encoding="utf-8")


@pytest.mark.parametrize("index", [0, 1])
def test_recording_examples_read_back(tmp_path, index):
    path = tmp_path / "example.csv"
    path.write_text(of_kind("Recording")[index], encoding="utf-8")
    rec = read_recording(path)
    assert len(rec) == 2 and rec.sensors == 2
    assert rec.meta["units"] == "g" and float(rec.meta["rate_hz"]) > 0
    assert np.all(np.diff(rec.t) > 0)
    assert np.linalg.norm(rec.accel[0], axis=1) == pytest.approx([1.01, 0.98], abs=0.01)  # gravity included
    assert rec.labels[0] == ""


def test_the_recording_contract_example_labels_a_jab():
    rec_text = of_kind("Recording")[0]
    assert rec_text.splitlines()[-1].endswith(",jab")


def event_lines() -> list[dict]:
    return [json.loads(line) for text in of_kind("event") for line in text.splitlines() if line.strip()]


def test_event_examples_are_json_lines_with_documented_keys():
    events = event_lines()
    assert len(events) == 9
    doc = DOC.read_text(encoding="utf-8")
    for e in events:
        assert e["event"] in EVENT_KINDS and set(e) <= EVENT_KEYS, e
        assert isinstance(e["frame"], int) and e["frame"] >= 0 and isinstance(e["t"], float)
        assert e["action"] is None or isinstance(e["action"], str)
        if e["event"] == "switch":
            assert isinstance(e["from_frame"], int)
        for key in e:
            assert f"`{key}`" in doc, f"event key {key!r} is not documented"
    called_off = [e for e in events if e.get("called_off")]
    assert called_off and all(e["event"] == "reject" and e["action"] for e in called_off)


def small_trace() -> dict:
    clock = VirtualClock()
    # Budgets far above any real run time: on a loaded machine a stage over a 1 ms budget would
    # carry an "overrun" arg that the documented example (no overruns) does not have.
    loop = FixedStepLoop(clock=clock, auto_freeze_gc=False, budget=FrameBudget(capacity_frames=60, frame_budget_ms=1e4))

    def sense(step: int, dt: float) -> None:
        with loop.span("sense.decode"):
            pass

    loop.add_stage("sense", sense, budget_ms=1e4)
    loop.set_render(lambda alpha: None, budget_ms=1e4, name="render")
    loop.run(frames=5)
    return chrome_trace(loop.budget)


def shape(doc: dict) -> set[tuple]:
    """What kinds of events a trace has and which keys each kind carries."""
    kinds = set()
    for ev in doc["traceEvents"]:
        kind = ev.get("cat") or ev["name"]
        kinds.add((ev["ph"], kind, tuple(sorted(ev)), tuple(sorted(ev.get("args", {})))))
    return kinds


def test_trace_example_reads_back_and_has_the_shape_engine_trace_writes(tmp_path):
    (text,) = of_kind("trace")
    path = tmp_path / "example.json"
    path.write_text(text, encoding="utf-8")
    example = read_chrome_trace(path)
    written = small_trace()
    assert shape(example) == shape(written)
    assert set(example) == set(written) and set(example["otherData"]) == set(written["otherData"])
    frames = [e for e in example["traceEvents"] if e["ph"] == "X" and e["name"] == "frame"]
    assert len(frames) == 1
    frame = frames[0]
    for e in example["traceEvents"]:  # every stage and span nests inside its frame
        if e["ph"] == "X":
            assert frame["ts"] <= e["ts"] and e["ts"] + e["dur"] <= frame["ts"] + frame["dur"]


def test_config_file_example_reads_back(tmp_path):
    from engine.recognition import RecognizerConfig
    from engine.recognition.config import layered
    from game.user_config import read_config

    (path := tmp_path / "config.toml").write_text(of_kind("config")[0], encoding="utf-8")
    settings = read_config(path)["recognizer"]
    assert settings and layered(settings) != RecognizerConfig()
