"""Commands around the recognizer: `quickjab templates build`, `quickjab recognize`,
`quickjab evaluate` (see tools/evaluate_recognition.py for the outcome groups)."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import TYPE_CHECKING

from engine import arguments
from engine.errors import InputError, refuse_other_kind, refuse_overwriting
from engine.file_kinds import is_events_head
from engine.frames import recording_frames
from engine.npz_files import is_npz_head
from engine.recognition import DualBufferRecognizer, Templates
from engine.recognition.config import layered, parse_assignments
from engine.recognition.templates import FEATURES, METHODS
from engine.recording import read_recording, say_notes
from tools.evaluation_settings import CLIP_FRAMES

if TYPE_CHECKING:
    from tools.evaluate_recognition import Summary

# Start-up (issue 14): the evaluation's modules (tools.evaluate_recognition, glove_punches,
# trial_files) are imported inside the commands that use them, so `recognize` and every `--help`
# load none of them; the parser's defaults come from tools.evaluation_settings.

MAX_BUFFER = 6000  # frames (100 s at 60 Hz): any recognizer buffer or count of frames
MAX_FOLDS = 50  # contiguous folds of one labelled stream; each needs intervals to learn from
MAX_MAINS = 120  # main-buffer sizes in one sweep


def _main_arg(text: str) -> int | str:
    if text == "auto":
        return text
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive int or 'auto', not {text!r}") from None
    if not 1 <= v <= MAX_BUFFER:
        raise argparse.ArgumentTypeError(f"main must be between 1 and {MAX_BUFFER}, not {v}")
    return v


def _noise_arg(text: str) -> float | str:
    if text == "auto":
        return text
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number of g or 'auto', not {text!r}") from None
    if not 0 <= v <= 100:
        raise argparse.ArgumentTypeError(f"the noise gate must be between 0 and 100 g, not {text}")
    return v


def _mains(text: str) -> list[int | str]:
    out: list[int | str] = []
    for part in text.split(","):
        if "-" in part:
            a, b = (_main_arg(x) for x in part.split("-", 1))
            if a == "auto" or b == "auto" or b < a:  # type: ignore[operator]
                raise argparse.ArgumentTypeError(f"expected a range like 1-12, not {part!r}")
            out += list(range(int(a), int(b) + 1))
        else:
            out.append(_main_arg(part))
        if len(out) > MAX_MAINS:
            raise argparse.ArgumentTypeError(f"at most {MAX_MAINS} sizes in one sweep")
    return out


def _users(text: str) -> str:
    """uWave users as `1-6` or `1,3`: checked here, expanded by _mains when the command runs."""
    try:
        users = _mains(text)
    except argparse.ArgumentTypeError:  # its words are the main buffer's ("... or 'auto'")
        users = ["auto"]
    if "auto" in users:
        raise argparse.ArgumentTypeError(f"expected user numbers such as 1-6 or 1,3, not {text!r}")
    return text


def _recognizer_args(p: argparse.ArgumentParser) -> None:
    # Defaults None: a flag not given leaves the setting to the lower layers (the templates'
    # saved settings, then RecognizerConfig's defaults, which the help texts quote).
    g = p.add_argument_group("recognizer")
    g.add_argument("--recognizer", action="append", default=[], metavar="NAME=VALUE",
                   help="any recognizer setting, e.g. noise_g=0.5 or adapt=0 (repeatable; docs/recognition.md lists them)")
    g.add_argument("--noise-g", type=_noise_arg, default=None,
                   help="noise gate in g, or 'auto' (default): learned from the sensor's resting noise")
    g.add_argument("--supplementary", type=arguments.int_range(1, MAX_BUFFER), default=None, help="supplementary buffer in frames (default 60)")
    g.add_argument("--null-frames", type=arguments.int_range(1, MAX_BUFFER), default=None, help="quiet frames that end a motion (default 6)")
    g.add_argument("--discard-frames", type=arguments.int_range(0, MAX_BUFFER), default=None, help="frames discarded after the character finishes (default 20)")
    g.add_argument("--no-reject", action="store_true", help="never reject (ignore the learned thresholds)")
    g.add_argument("--complete", type=arguments.float_range(0.0, 1.0), default=None, metavar="F",
                   help="also end a motion once its template is matched past this fraction and the hand "
                        "calms down: splits back-to-back punches (default 0.9; 0 = the paper's null signal only)")


# the dedicated flags -> the setting each one sets
_FLAGS = {"main": "main", "noise_g": "noise_g", "supplementary": "supplementary", "null_frames": "null_frames",
          "discard_frames": "discard_frames", "complete": "complete_fraction"}


def _cli_settings(args: argparse.Namespace) -> dict:
    """The recognizer settings given on the command line: `--recognizer NAME=VALUE`, then the
    dedicated flags (`--noise-g 0.5`); the same setting given both ways is an error."""
    settings = parse_assignments(args.recognizer)
    given = {flag: name for flag, name in _FLAGS.items() if getattr(args, flag, None) is not None}
    flags = {name: getattr(args, flag) for flag, name in given.items()}
    if args.no_reject:
        given["no_reject"] = "reject"
        flags["reject"] = False
    for flag, name in given.items():
        if name in settings:
            raise InputError(f"--recognizer {name}=... and --{flag.replace('_', '-')} set the same setting: give one")
    return {**settings, **flags}


def _rec_kwargs(args: argparse.Namespace, saved: dict | None = None) -> dict:
    """DualBufferRecognizer keywords for evaluate's sweeps (without `main`, which --mains sets):
    the defaults, `saved` (the --templates file's settings), then the command line. evaluate
    does not read the user's config file: its figures must not depend on a file on this machine.
    `--recognizer main=...` is refused: it would be dropped here, silently."""
    cli = _cli_settings(args)
    if "main" in cli:
        raise InputError(f"--recognizer main={cli['main']}: evaluate sets main with --mains (e.g. --mains {cli['main']})")
    kwargs = layered(saved or {}, cli, where=["templates", "command line"]).kwargs()
    del kwargs["main"]
    return kwargs


def register(sub: argparse._SubParsersAction) -> None:
    t = sub.add_parser("templates", help="build recognition templates from trials", description=__doc__)
    tsub = t.add_subparsers(dest="templates_command", metavar="ACTION", required=True)
    b = tsub.add_parser("build", help="build templates.npz from TRIALS_DIR/<action>/*.csv or labelled recordings",
                        description="Build recognition templates from trial recordings, one folder of CSVs per "
                        "action (TRIALS_DIR/<action>/*.csv, as `quickjab synth --trials` writes them), or from "
                        "labelled recordings (REC.csv ...: every labelled run a trial, cut as `evaluate` cuts its "
                        "training punches); `play --templates`, `recognize` and `evaluate --templates` read the file.")
    b.add_argument("trials_dir", metavar="TRIALS_DIR|REC.csv", nargs="+", type=arguments.path_argument,
                   help="a folder with one folder of trial CSVs per action (TRIALS_DIR/<action>/*.csv), or one or more "
                        "labelled recordings (a `label` per row: each labelled run is a trial of that action)")
    b.add_argument("-o", "--output", default="templates.npz", type=arguments.path_argument, help="output .npz (default templates.npz)")
    b.add_argument("--method", choices=METHODS, default=None, help="trials (default), average (Eq. 1) or dba")
    b.add_argument("--feature", choices=FEATURES, default=None, help="what DTW compares (default log)")
    b.add_argument("--mirror", action="store_true", help="mirror for a left-handed player (swap hands, flip x, swap _l/_r)")
    b.add_argument("--glob", default="*.csv", help="which trial files to use in each action folder (default *.csv)")
    b.add_argument("--keep", type=_keep, default=None,
                   help="keep each action's KEEP most representative trials, or 'usable': every trial not cut off, "
                        "odd or like another action's (as `train` does); default all")
    b.add_argument("--recognizer", action="append", default=[], metavar="NAME=VALUE",
                   help="a recognizer setting to save with the templates, e.g. noise_g=0.5 (repeatable)")
    b.add_argument("--lead", type=arguments.int_range(0, MAX_BUFFER), default=10,
                   help="labelled recordings: frames kept before each labelled run (default 10, as evaluate's --lead)")
    b.add_argument("--trials", type=arguments.int_range(1, 1000), default=None,
                   help="labelled recordings: each action's first TRIALS runs only (default all)")
    b.set_defaults(func=cmd_build)

    r = sub.add_parser("recognize", help="replay a recording through the recognizer; events as JSON lines",
                       description="Replay a recording through the recognizer, deciding as `play` does (the "
                       "templates' saved settings, your config file's [recognizer] table, then these options), "
                       "and print its events as JSON lines: start, switch, end, reject (docs/formats.md).")
    r.add_argument("recording", metavar="REC.csv", type=arguments.path_argument, help="the recording to replay (docs/formats.md; any sample rate)")
    r.add_argument("--templates", required=True, metavar="T.npz", type=arguments.path_argument,
                   help="recognition templates: `templates build` or `train -o` wrote them, or game/assets/templates.npz")
    r.add_argument("-o", "--output", default=None, type=arguments.path_argument, help="write the JSON lines here instead of stdout")
    r.add_argument("--main", type=_main_arg, default=None, help="main buffer in frames or 'auto' (default 6)")
    r.add_argument("--clip-frames", type=arguments.int_range(0, MAX_BUFFER), default=0,
                   help="replay with a character that calls character_finished() as the game's boxer does: an action "
                        "the game has plays its own clip, any other name this many frames (0, the default: no character, "
                        f"the recognizer alone; `evaluate`'s streams use {CLIP_FRAMES})")
    _recognizer_args(r)
    r.set_defaults(func=cmd_recognize)
    _register_evaluate(sub)


def _register_evaluate(sub: argparse._SubParsersAction) -> None:
    e = sub.add_parser(
        "evaluate",
        help="outcome groups per main-buffer size (Figs. 8-9)",
        description=(
            "Replay trials or labelled recordings and print, per main-buffer size, the four "
            "outcome groups, first-decision accuracy and lag from the true onset. Inputs: "
            "--templates T.npz with trial dirs or labelled CSVs; or --train TRIALS_DIR; or "
            "--uwave DIR (per user: templates from the first --trials reps of day 1, default 3, test days 2-7); or "
            "--phone-punches DIR (cross-session, per hand fast -> slow and slow -> fast); or --punchbuddy DIR "
            "(two gloves, unlabelled: punches found in the signal; across sessions and across people); or a labelled "
            "CSV alone with --folds K (templates from the other folds' intervals). The lag is counted "
            "from the true onset: the first frame 0.3 g away from the rest before the motion."
        ),
    )
    e.add_argument("inputs", nargs="*", metavar="INPUT", type=arguments.path_argument, help="trial dirs (<root>/<action>/*.csv) or labelled recording CSVs")
    e.add_argument("--templates", default=None, metavar="T.npz", type=arguments.path_argument, help="the templates to test the INPUTs with")
    e.add_argument("--train", default=None, metavar="TRIALS_DIR", type=arguments.path_argument, help="build templates from these trials")
    _data_set_args(e)
    e.add_argument("--keep", type=_keep, default=None,
                   help="templates: keep each action's KEEP most representative trials (e.g. --trials 5 --keep 3), "
                        "or 'usable': every trial not cut off, odd or like another action's (as `train` does)")
    e.add_argument("--every", type=arguments.int_range(1, 1_000_000), default=1, help="use every k-th test trial (quicker sweeps)")
    e.add_argument("--folds", type=arguments.int_range(2, MAX_FOLDS), default=2, help="labelled CSV without templates: K contiguous folds (default 2)")
    e.add_argument("--mains", type=_mains, default=_mains("1-12"), help="main-buffer sizes (default 1-12; e.g. 6 or 1-12,auto)")
    e.add_argument("--method", choices=METHODS, default=None, help="template method when building")
    e.add_argument("--feature", choices=FEATURES, default=None, help="template feature when building (default log)")
    e.add_argument("--plot", type=arguments.plot_file, default=None, metavar="PNG", help="draw Figs. 8-9 style bars")
    e.add_argument("--clip-frames", type=arguments.int_range(0, MAX_BUFFER), default=CLIP_FRAMES,
                   help=f"streams: the simulated character's clip length, then character_finished() (default {CLIP_FRAMES}; "
                        "0 = never); an action the game has plays its own clip, as the boxer does, unless --fixed-clips")
    e.add_argument("--fixed-clips", action="store_true",
                   help="streams: every action's clip --clip-frames long from the motion's start, the game's actions too "
                        "(how the figures were measured before the game's own clips)")
    e.add_argument("--json", action="store_true", help="print the rows as JSON lines instead of a table")
    _recognizer_args(e)
    e.set_defaults(func=cmd_evaluate)


def _data_set_args(e: argparse.ArgumentParser) -> None:
    """`evaluate`'s data sets and their protocols' options."""
    e.add_argument("--uwave", default=None, metavar="DIR", type=arguments.path_argument, help="the uWave protocol on DIR/U<n>/gesture<k>/d<day>-r<rep>.csv")
    e.add_argument("--users", type=_users, default="1-6", help="uWave users (default 1-6)")
    e.add_argument("--fresh", action="store_true",
                   help="trials (and --isolated): a new recognizer for every trial (no adaptation, no gate learnt from the trials before); default: one player's session")
    e.add_argument("--phone-punches", default=None, metavar="DIR", type=arguments.path_argument,
                   help="cross-session: DIR/<hand>_<punch>_<fast|slow>.csv; per hand, templates from the first "
                        "--trials punches of each kind in one set, tested on every punch of the other set, and on "
                        "the hand's recorded mixed sequences DIR/<hand>_mixed_<name>.csv when there are any")
    e.add_argument("--punchbuddy", default=None, metavar="DIR", type=arguments.path_argument,
                   help="two gloves: DIR/right-<kind>-<count>-<person>-combo-l<h|j|c|u>-<n>.csv, each punch a burst of "
                        "one glove; templates from the first --trials punches per hand of one person's session, tested "
                        "on the person's other sessions ('<person> across sessions') and from a person's sessions, "
                        "tested on another's ('<A> -> <B>')")
    e.add_argument("--trials", type=arguments.int_range(1, 1000), default=3,
                   help="--phone-punches, --punchbuddy: training trials per punch; --uwave: the first TRIALS "
                        "reps of day 1 (default 3)")
    e.add_argument("--lead", type=arguments.int_range(0, MAX_BUFFER), default=10, help="--phone-punches: frames kept before each labelled punch when templates are cut (default 10)")
    e.add_argument("--mixed", action="store_true",
                   help="--phone-punches: also the other set's punches of all kinds spliced into one shuffled stream "
                        "(as recorded; turned to one guard; and from one guard, the fist turned in as each punch starts)")
    e.add_argument("--isolated", action="store_true",
                   help="--phone-punches: also every punch of the other set as an isolated trial (with the 10 frames "
                        "before and after it), in session order through one recognizer (--fresh: a fresh one per trial)")
    e.add_argument("--draws", type=arguments.int_range(1, 100), default=1,
                   help="--phone-punches, --uwave: pool this many disjoint draws of --trials templates per kind "
                        "(punches or reps 1-3, 4-6, ...; default 1)")
    e.add_argument("--phases", type=arguments.int_range(1, 60), default=1,
                   help="pool every row over this many phases of the 60 Hz grid (the first step 0, 1/P, 2/P, ... of a "
                        "step after a recording's first sample; default 1: the first sample's instant). Where the "
                        "first sample falls between two steps is chance, and it moves a row by a few points")
    e.add_argument("--seed", type=arguments.seed, default=0, help="--mixed: the shuffle's seed (default 0)")


def cmd_build(args: argparse.Namespace) -> int:
    from tools.trial_files import (
        labelled_trials,
        load_trials_dir,
        templates_from_trials,
        trial_paths,
    )

    inputs = args.trials_dir
    for p in inputs:
        if not Path(p).exists():
            raise InputError(f"{p}: no such folder of trials (<root>/<action>/*.csv) or labelled recording")
    folders = [p for p in inputs if Path(p).is_dir()]
    if folders and len(inputs) > 1:
        raise InputError(f"{folders[0]}: a folder of trials is given alone (or give labelled recordings, one or more)")
    settings = parse_assignments(args.recognizer)
    where = folders[0] if folders else ", ".join(inputs)
    read = [f for fs in trial_paths(where, args.glob).values() for f in fs] if folders else inputs
    refuse_overwriting({"-o": args.output}, read)
    refuse_other_kind(args.output, "-o", "an .npz", is_npz_head)  # earlier templates are replaced
    trials = load_trials_dir(where, args.glob, prog="templates") if folders else labelled_trials(inputs, args.lead, args.trials)
    kwargs = {k: v for k, v in (("method", args.method), ("feature", args.feature), ("keep", args.keep)) if v}
    templates = templates_from_trials(trials, where, **kwargs)
    if args.mirror:
        templates = templates.mirrored()
    templates.recognizer = settings
    templates.save(args.output)
    n = sum(len(v) for v in trials.values())
    print(f"{args.output}: {len(templates)} templates of {len(templates.action_names)} actions from {n} trials "
          f"(method {templates.method}, feature {templates.feature}, D={templates.dim}{', mirrored' if args.mirror else ''})")
    return 0


def cmd_recognize(args: argparse.Namespace) -> int:
    refuse_overwriting({"-o": args.output}, [args.recording, args.templates])
    if args.output:  # earlier events are replaced
        refuse_other_kind(args.output, "-o", "the recognizer's events (JSON lines)", is_events_head)
    templates = Templates.load(args.templates)
    rec_file = read_recording(args.recording)
    say_notes(rec_file.notes, "recognize")
    times, frames, _ = recording_frames(rec_file)
    if frames.shape[1] != templates.dim:
        raise InputError(f"{args.recording}: {frames.shape[1]} values per frame, templates {args.templates} have D = {templates.dim}")
    from game.user_config import recognizer_settings

    # as `play` decides: the templates' saved settings, the config file, then the command line
    config = layered(templates.recognizer, recognizer_settings(), _cli_settings(args),
                     where=["templates", "config file", "command line"])
    rec = DualBufferRecognizer.from_config(templates, config)
    character = None
    if args.clip_frames:  # a boxer playing each decided action's clip, as in `play` and `evaluate`
        from tools.evaluate_recognition import SimulatedCharacter, game_clips

        character = SimulatedCharacter(game_clips(args.clip_frames))
    try:
        if args.output:  # a folder not made yet is made, as for every output
            Path(args.output).parent.mkdir(parents=True, exist_ok=True)
        out = open(args.output, "w", encoding="utf-8") if args.output else sys.stdout
        try:
            t0 = float(rec_file.t[0])  # events carry the recording's own seconds (docs/formats.md)
            for i, (t, f) in enumerate(zip(times, frames, strict=True)):
                events = rec.push(f, t=t0 + float(t))
                for e in events:
                    out.write(json.dumps(e.to_dict()) + "\n")
                if character is not None:
                    character.after_push(rec, i, events)
        finally:
            if args.output:
                out.close()
    except OSError as exc:  # a full disk: ENOSPC names no file
        if not args.output:
            raise
        raise InputError(f"{args.output}: cannot write ({exc.strerror or exc})") from None
    return 0


def cmd_evaluate(args: argparse.Namespace) -> int:
    from tools import evaluate_recognition as ev
    from tools.trial_files import grid_phase

    if args.plot:  # said before minutes of evaluation, not after
        refuse_overwriting({"--plot": args.plot}, [*args.inputs, args.templates])
        try:
            import matplotlib  # noqa: F401
        except ImportError:
            raise InputError("--plot needs matplotlib (pip install 'quickjab[dev]')") from None
    if not (args.uwave or args.phone_punches or args.punchbuddy or args.inputs):
        raise InputError("nothing to evaluate: give INPUTs, --uwave DIR, --phone-punches DIR, --punchbuddy DIR, or see --help")
    if not args.fixed_clips:  # the game's actions as the game's boxer plays them
        args.clip_frames = ev.game_clips(args.clip_frames)

    def at_phase(k: int) -> dict[str, list[ev.Summary]]:
        with grid_phase(k / args.phases):
            return _evaluate_sets(args)

    pooled = ev.pooled_draws(at_phase, args.phases, args.mains)
    results = {title: [s.row() for s in summaries] for title, summaries in pooled.items()}
    _print_results(args, results)
    if args.plot:
        ev.plot(results, args.plot)
        print(f"wrote {args.plot}")
    return 0


def _evaluate_sets(args: argparse.Namespace) -> dict[str, list[Summary]]:
    """Every set the command line names, once: {title: one Summary per main}."""
    from tools import evaluate_recognition as ev
    from tools.trial_files import load_trials_dir, templates_from_trials

    kw = _rec_kwargs(args)
    tk = {k: v for k, v in (("method", args.method), ("feature", args.feature), ("keep", args.keep)) if v}
    results: dict[str, list[Summary]] = {}
    if args.uwave:
        results.update(_evaluate_uwave(args, kw, tk))
    if args.phone_punches:
        res = ev.evaluate_phone_punches(
            args.phone_punches, args.mains, mixed=args.mixed, seed=args.seed, isolated=args.isolated, fresh=args.fresh,
            draws=args.draws,
            trials=args.trials, template_kwargs=tk, template_lead=args.lead,
            clip_frames=args.clip_frames, **kw
        )
        if not res:
            raise InputError(f"{args.phone_punches}: no <hand>_<punch>_<fast|slow>.csv recordings")
        results.update(res)
    if args.punchbuddy:
        results.update(_evaluate_punchbuddy(args, kw, tk))
    templates = Templates.load(args.templates) if args.templates else None
    source = args.templates  # what the templates came from, for messages
    if args.train:
        templates, source = templates_from_trials(load_trials_dir(args.train), args.train, **tk), f"built from {args.train}"
    if templates is not None:
        kw = _rec_kwargs(args, templates.recognizer)  # a --templates file's saved settings under the command line's
    for inp in args.inputs:
        results[Path(inp).name] = _evaluate_input(args, inp, templates, kw, tk, source)
    return results


def _keep(text: str) -> int | str:
    """--keep: a count of trials (1-1000) or `usable`."""
    if text == "usable":
        return text
    try:
        return arguments.int_range(1, 1000)(text)
    except argparse.ArgumentTypeError as exc:
        raise argparse.ArgumentTypeError(f"{exc} (or 'usable')") from None


def _evaluate_uwave(args: argparse.Namespace, kw: dict, tk: dict) -> dict[str, list[Summary]]:
    """The uWave users' rows pooled: each user's first --trials day-1 reps are the templates
    (with --draws k, the next ones too, each draw on its own), days 2-7 the tests."""
    from tools import evaluate_recognition as ev
    from tools.trial_files import load_trials_dir, templates_from_trials, trials_dim

    users = [int(u) for u in _mains(args.users)]
    pooled = None
    for u in users:
        root = Path(args.uwave) / f"U{u}"
        day1 = load_trials_dir(root, "d1-*.csv")  # in rep order
        tests = {a: ts[:: args.every] for a, ts in load_trials_dir(root, "d[2-7]-*.csv").items()}
        if untrained := sorted(set(tests) - set(day1)):  # their tests were counted as misses, unsaid
            raise InputError(f"{root}: {', '.join(untrained)}: tests on days 2-7 but no day-1 reps to make templates from")
        for d in range(args.draws):
            reps = f"d1 reps {d * args.trials + 1}-{(d + 1) * args.trials}"
            cut = {a: ts[d * args.trials : (d + 1) * args.trials] for a, ts in day1.items()}
            if any(not ts for ts in cut.values()):
                raise InputError(f"{root}: no {reps} for every gesture (--trials {args.trials} x --draws {args.draws})")
            templates = templates_from_trials(cut, f"{root} ({reps})", **tk)
            if trials_dim(tests) != templates.dim:
                raise InputError(f"{root}: the test trials d[2-7]-*.csv have {trials_dim(tests)} values per frame, "
                                 f"the templates from {reps} have D = {templates.dim} (one- and two-hand recordings mixed)")
            res = ev.evaluate_trials(templates, tests, args.mains, fresh=args.fresh, **kw)
            if pooled is None:
                pooled = res
            else:
                for p, r in zip(pooled, res, strict=True):
                    p.add(r)
    order = "fresh recognizer per trial" if args.fresh else "session order"
    return {f"uWave users {args.users}, noise_g {kw['noise_g']}, {order}": pooled}


def _evaluate_punchbuddy(args: argparse.Namespace, kw: dict, tk: dict) -> dict[str, list[Summary]]:
    """The two-glove rows (tools/glove_punches.py): across each person's sessions and across people."""
    from tools import glove_punches

    if not glove_punches.glove_files(args.punchbuddy):
        raise InputError(f"{args.punchbuddy}: no right-<kind>-<count>-<person>-combo-l<h|j|c|u>-<n>.csv recordings")
    res = glove_punches.evaluate_gloves(
        args.punchbuddy, args.mains, trials=args.trials, template_kwargs=tk, clip_frames=args.clip_frames, **kw
    )
    if not res:
        raise InputError(f"{args.punchbuddy}: no recording to test: a person's other session, or another person's, "
                         "with the punch kinds of the templates")
    return res


def _evaluate_input(args: argparse.Namespace, inp: str, templates: Templates | None, kw: dict,
                    tk: dict, source: str | None = None) -> list[Summary]:
    """One INPUT's rows: a trial directory against the templates, or a labelled recording
    against the templates or, without them, in folds that learn from the rest of it. `source`
    names the templates in messages (the --templates file, or what --train built them from)."""
    from tools import evaluate_recognition as ev
    from tools.trial_files import load_trials_dir, read_labelled_frames, trials_dim

    path = Path(inp)
    if path.is_dir():
        if templates is None:
            raise InputError(f"{inp}: trial directories need --templates or --train")
        tests = {a: ts[:: args.every] for a, ts in load_trials_dir(path).items()}
        _check_dim(inp, trials_dim(tests), templates, source)
        res = ev.evaluate_trials(templates, tests, args.mains, fresh=args.fresh, **kw)
    else:
        frames, labels = read_labelled_frames(path)
        if not any(labels):
            raise InputError(f"{inp}: no labelled intervals (label column empty)")
        if templates is None:
            res = ev.evaluate_stream_folds(
                frames, labels, args.mains, folds=args.folds, template_kwargs=tk, clip_frames=args.clip_frames,
                where=inp, **kw
            )
        else:
            _check_dim(inp, frames.shape[1], templates, source)
            res = ev.evaluate_stream(templates, frames, labels, args.mains, clip_frames=args.clip_frames, **kw)
    return res


def _check_dim(inp: str, dim: int, templates: Templates, source: str | None) -> None:
    """As `recognize` checks: the input's values per frame must be the templates' D."""
    if dim != templates.dim:
        raise InputError(f"{inp}: {dim} values per frame, templates {source} have D = {templates.dim}")


def _print_results(args: argparse.Namespace, results: dict[str, list[dict]]) -> None:
    """Each set's rows as JSON lines (--json) or a table."""
    from tools import evaluate_recognition as ev

    for title, rows in results.items():
        if args.json:
            for r in rows:
                print(json.dumps({"set": title, **r}))
        else:
            print(f"## {title}\n{ev.format_table(rows)}\n")
