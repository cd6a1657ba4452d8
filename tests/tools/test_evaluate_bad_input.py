"""`quickjab evaluate` (and `templates build`, `bridge emulate --replay`) on data it cannot use:
templates that cannot be built from it (a labelled interval or trial of one frame, no interval
left for a fold, a phone-punches file without its punch's label), values per frame that are not
the templates' D, accelerations no sensor reads. Each is one line naming the file or folder at
fault and exit code 2: no traceback, no numpy warning, no file written with thresholds of inf.
The inputs are the hostile-input campaign's (tools/input_campaign.py `bad_evaluate_inputs`)."""

from __future__ import annotations

import numpy as np
import pytest

from engine.errors import InputError
from engine.recognition import Templates
from tools.cli import main
from tools.input_campaign import ASSETS, bad_evaluate_inputs

# case -> (the file or folder the message names, relative to the inputs' folder; what it says)
EXPECT = {
    "stream-1-label/folds": ("eval/stream-1-label.csv", "a trial must be (n >= 2"),
    "stream-all-label/folds": ("eval/stream-all-label.csv", "fold 1 of 2 has no labelled interval"),
    "train-one-row": ("eval/trials-one-row", "a trial must be (n >= 2"),
    "stream-onehand/templates": ("eval/stream-onehand.csv", "3 values per frame, templates"),
    "trials-onehand/templates": ("eval/trials-onehand", "3 values per frame, templates"),
    "trials-onehand/train": ("eval/trials-onehand", "templates built from"),
    "pp-unlabelled": ("eval/pp-unlabelled/right_jab_fast.csv", "no row labelled 'jab'"),
    "pp-otherlabel": ("eval/pp-otherlabel/right_jab_fast.csv", "no row labelled 'jab'"),
    "pp-onerow": ("eval/pp-onerow/right_*_fast.csv", "a trial must be (n >= 2"),
    "pp-onehand": ("eval/pp-onehand/right_jab_slow.csv", "6 values per frame, right_jab_fast.csv has 3"),
    "pb-onerow": ("eval/pb-onerow/right-hook-50-a-combo-lh-1.csv", "a trial must be (n >= 2"),
    "uw-onerow": ("eval/uw-onerow/U1", "a trial must be (n >= 2"),
    "uw-mismatch": ("eval/uw-mismatch/U1", "6 values per frame"),
    "uw-nod1": ("eval/uw-nod1/U1", "gesture2: tests on days 2-7 but no day-1 reps"),
    "trials-huge/build": ("eval/trials-huge/hook_r/1.csv:", "over the 1000 g"),
    "trials-huge/train": ("eval/trials-huge/hook_r/1.csv:", "over the 1000 g"),
    "accel-1e306/bridge-emulate": ("eval/accel-1e306.csv:", "over the 1000 g"),
}


@pytest.fixture(scope="module")
def inputs(tmp_path_factory):
    d = tmp_path_factory.mktemp("evaluate-bad")
    out = d / "out"
    out.mkdir()
    return d, bad_evaluate_inputs(d, str(ASSETS / "templates.npz"), out)


def test_every_case_has_an_expectation(inputs):
    assert set(inputs[1]) == set(EXPECT)


@pytest.mark.filterwarnings("error::RuntimeWarning")  # an overflow warning is a failure, not noise
@pytest.mark.parametrize("name", sorted(EXPECT))
def test_bad_input_is_one_line_naming_it_and_exit_2(inputs, name, capsys):
    d, cases = inputs
    assert main(cases[name]) == 2
    captured = capsys.readouterr()
    err = captured.err.strip().splitlines()
    where, what = EXPECT[name]
    assert len(err) == 1 and "Traceback" not in captured.err, captured.err
    assert err[0].startswith(f"quickjab {cases[name][0]}: {d / where}") and what in err[0], err[0]
    if name == "trials-huge/build":  # was written, with thresholds of inf
        assert not (d / "out" / "huge.npz").exists()


def test_templates_with_accelerations_no_sensor_reads_are_refused(tmp_path):
    """signals x 1e200 and gravity of 1e300 are finite: they loaded, then overflowed in the
    recognizer (RuntimeWarnings, NaN activity). Refused as the recording reader refuses them."""
    with np.load(ASSETS / "templates.npz", allow_pickle=False) as z:
        good = {k: z[k] for k in z.files}
    for name, change in (("signals", good["signals"] * 1e200), ("gravity", np.full_like(good["gravity"], 1e300))):
        path = tmp_path / f"{name}.npz"
        np.savez_compressed(path, **{**good, name: change})
        with pytest.raises(InputError, match=r"over the 1000 g") as err:
            Templates.load(path)
        assert str(path) in str(err.value)
    Templates.load(ASSETS / "templates.npz")  # the shipped set: a few g


@pytest.mark.filterwarnings("error::RuntimeWarning")
def test_recognize_refuses_such_templates_in_one_line(tmp_path, capsys):
    with np.load(ASSETS / "templates.npz", allow_pickle=False) as z:
        good = {k: z[k] for k in z.files}
    path = tmp_path / "big.npz"
    np.savez_compressed(path, **{**good, "signals": good["signals"] * 1e200})
    rec = tmp_path / "rec.csv"
    rec.write_text("t,rx,ry,rz,lx,ly,lz\n" + "".join(f"{i / 60:.5f},0,0,1,0,0,1\n" for i in range(30)))
    assert main(["recognize", str(rec), "--templates", str(path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and str(path) in err[0] and "1000 g" in err[0]
