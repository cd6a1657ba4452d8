"""The hostile-input campaign (tools/input_campaign.py), a sample of it: real `quickjab`
subprocesses on bad files, URLs and arguments end in one line and exit 2, never a traceback,
a hang or a blow-up; valid inputs still run. The whole campaign is
`python -m tools.input_campaign` (a few minutes)."""

from __future__ import annotations

import os
import tempfile

import pytest

from tools.input_campaign import ROOT, build_cases, judge, run_case

SAMPLE = [  # one or two per input kind
    "rec/gap-1e7/recognize", "rec/equal-t/wiimote-emu", "rec/fifo/scope",
    "tpl/zip-bomb/recognize", "tpl/nan-gravity/recognize",
    "graph/grid-distance_step-zero/info", "graph/meta-deep/info", "tpl/recognizer-deep/own-play", "trace/deep/profile", "trace/args-int/profile",
    "bvh/ftime-1e9/cut", "bvh/unmapped-24mb/info", "bvh/end-site-outside/info", "url/demo-rate-1e9/record", "url/emu-drop-2/record",
    "arg/eval-folds-huge", "arg/play-screenshot-under-a-file", "arg/synth-session-nan", "ok/record-emu-400k",
    "config/wrong-type/play", "config/fifo/recognize", "config/dev-zero/play", "tpl/recognizer-unknown/recognize", "arg/play-recognizer-unknown",
    "rec/accel-1e300/recognize", "tpl/signals-1e200/evaluate", "eval/pp-unlabelled", "eval/stream-all-label/folds",
    "eval/trials-huge/build", "eval/accel-1e306/bridge-emulate",
    "same/recognize-o-recording", "full/play-screenshot", "full/record", "url/bracket-missing/record", "actions/not-object/list",
    "arg/record-o-dev-full", "ok/bvh-export-guard", "ok/evaluate-still-trial", "eval/uw-nod1",
]


@pytest.fixture(scope="module")
def cases(tmp_path_factory):
    # bombs of 0.6 GB: over both the template and the graph limits, quick to build
    return {c.name: c for c in build_cases(tmp_path_factory.mktemp("campaign"), big_mb=0, bomb_gb=0.6)}


@pytest.mark.parametrize("name", SAMPLE)
def test_bad_input_gets_one_line_and_exit_2(cases, name):
    env = {**os.environ, "PYTHONPATH": str(ROOT), "SDL_VIDEODRIVER": "dummy", "SDL_AUDIODRIVER": "dummy",
           "XDG_DATA_HOME": tempfile.mkdtemp(prefix="qj-campaign-test-")}
    outcome = run_case(cases[name], timeout=90, limit_mb=3072, env=env)
    verdict = judge(outcome, max_rss_mb=600)
    assert verdict == "ok", (verdict, outcome.rc, outcome.stderr[-400:])
