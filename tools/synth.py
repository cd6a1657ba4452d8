"""`quickjab synth`: recordings from the virtual player (game.virtual_player).

  quickjab synth --player experienced --trials 3 -o DIR    DIR/<action>/<n>.csv trial files
  quickjab synth --session 120 -o rec.csv                  a labelled continuous recording of
                                                           random actions separated by rests
  quickjab synth --templates -o game/assets/templates.npz  the shipped default templates, built
                                                           with engine.recognition from 3
                                                           synthesized experienced trials/action
Both are written in the recording CSV of docs/formats.md; `--seed` makes them reproducible.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from engine import arguments
from engine.errors import InputError
from engine.recording import MAX_DURATION_S, Recording, recording_bytes, write_recording
from game.actions import ACTION_NAMES, Action, load_library
from game.virtual_player import FPS, PROFILES, synthesize_action, synthesize_rest

SOURCE = "virtual player (game.virtual_player)"


def synth_trials(
    lib: dict[str, Action],
    profile: str,
    trials: int,
    rng: np.random.Generator,
    actions: list[str] | None = None,
    rest: int = 0,
) -> dict[str, list[np.ndarray]]:
    """{action: [trial (n, 6) in g, ...]}; columns rx, ry, rz, lx, ly, lz."""
    out: dict[str, list[np.ndarray]] = {}
    for name in actions or ACTION_NAMES:
        out[name] = [
            synthesize_action(lib[name], profile, rng, rest, rest, library=lib).reshape(-1, 6)
            for _ in range(trials)
        ]
    return out


def _to_recording(signal: np.ndarray, labels: list[str], meta: dict[str, str]) -> Recording:
    n = len(signal)
    return Recording(np.arange(n) / FPS, signal.reshape(n, 2, 3), labels, meta)


def write_keeping(path: Path, rec: Recording, unread: bool = False) -> Path | None:
    """Write `rec` to `path`; a non-empty file there that holds anything else is moved aside
    first, as `record -o` does (tools.record.aside_unless_same; `unread`: to a name a trial
    folder's readers pass over): a trial or a recording may be a player's. Where it went, else None."""
    from tools.record import aside_unless_same

    data = recording_bytes(rec)
    aside = aside_unless_same(path, data, unread)
    write_recording(path, data)
    return aside


def write_trials(directory: str | Path, trials: dict[str, list[np.ndarray]], profile: str, seed,
                 moved: list[tuple[Path, Path]] | None = None) -> list[Path]:
    """DIR/<action>/<n>.csv for every trial; the files moved aside to make room are added to
    `moved` as (file, where it went)."""
    directory = Path(directory)
    written = []
    for name, signals in trials.items():
        folder = directory / name
        folder.mkdir(parents=True, exist_ok=True)
        for i, sig in enumerate(signals, start=1):
            path = folder / f"{i}.csv"
            meta = {"source": f"{SOURCE}, profile {profile}", "action": name, "seed": str(seed)}
            aside = write_keeping(path, _to_recording(sig, [name] * len(sig), meta), unread=True)
            if aside is not None and moved is not None:
                moved.append((path, aside))
            written.append(path)
    return written


def say_moved(moved: list[tuple[Path, Path]], directory: str) -> None:
    """One line for the trial files moved aside (the first three named), to names `templates
    build`, which reads every *.csv of an action folder as a trial, passes over."""
    if not moved:
        return
    named = ", ".join(f"{path} -> {aside.name}" for path, aside in moved[:3])
    more = f" and {len(moved) - 3} more" if len(moved) > 3 else ""
    print(f"synth: {len(moved)} trial file(s) under {directory} were not empty, moved aside: {named}{more} "
          "(no longer read as trials)", file=sys.stderr)


def synth_session(
    lib: dict[str, Action],
    seconds: float,
    profile: str,
    rng: np.random.Generator,
    rest_s: tuple[float, float] = (0.5, 1.5),
    actions: list[str] | None = None,
) -> tuple[np.ndarray, list[str]]:
    """A continuous (n, 2, 3) signal of random actions separated by rests, and per-frame labels
    ('' while resting). Stops before `seconds` is exceeded (ends with a rest)."""
    guard = lib["guard"]
    total = int(round(seconds * FPS))
    parts: list[np.ndarray] = []
    labels: list[str] = []
    n = 0
    names = actions or list(ACTION_NAMES)
    while True:
        rest = int(round(rng.uniform(*rest_s) * FPS))
        name = names[int(rng.integers(len(names)))]
        sig = synthesize_action(lib[name], profile, rng, library=lib)
        if n + rest + len(sig) > total:
            break
        parts += [synthesize_rest(rest, guard, profile, rng), sig]
        labels += [""] * rest + [name] * len(sig)
        n += rest + len(sig)
    parts.append(synthesize_rest(total - n, guard, profile, rng))
    labels += [""] * (total - n)
    return np.concatenate(parts), labels


DEFAULT_TEMPLATE_SEED = 0  # the shipped game/assets/templates.npz is rebuilt from this seed


def build_default_templates(path: str | Path, seed: int = DEFAULT_TEMPLATE_SEED, trials: int = 3,
                            profile: str = "experienced") -> Path:
    """Build recognition templates from synthesized trials (the paper's 3 per action, Eq. 1)
    with engine.recognition and save them to `path` (npz, no pickles)."""  # fmt: skip
    import tempfile

    try:
        from engine.recognition import Templates
        from tools.trial_files import load_trials_dir
    except ImportError:
        raise InputError("engine.recognition.Templates is not available in this tree") from None
    lib = load_library()
    trial_sets = synth_trials(lib, profile, trials, np.random.default_rng(seed))
    # through the trial files, exactly as `quickjab synth --trials 3 --seed 0 -o DIR` followed by
    # `quickjab templates build DIR` (the CSV keeps 4 decimals), so both routes give one file
    with tempfile.TemporaryDirectory() as tmp:
        write_trials(tmp, trial_sets, profile, seed)
        templates = Templates.from_trials(load_trials_dir(tmp))
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    templates.save(str(path))
    return path


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("synth", help="synthesize trials or a labelled session from the virtual player",
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)  # fmt: skip
    p.add_argument("--player", default="experienced", choices=sorted(PROFILES), help="player profile")
    mode = p.add_mutually_exclusive_group(required=True)
    mode.add_argument("--trials", type=arguments.int_range(1, 1000), help="trials per action, written to DIR/<action>/<n>.csv")
    mode.add_argument("--session", type=arguments.float_range(0.0, MAX_DURATION_S, lo_open=True), metavar="SECONDS", help="length of a continuous recording")
    mode.add_argument("--templates", action="store_true",
                      help="build recognition templates (-o NPZ) from 3 synthesized trials per action")
    p.add_argument("-o", "--output", required=True, type=arguments.path_argument,
                   help="DIR for --trials, a .csv file for --session, an .npz for --templates")
    p.add_argument("--seed", type=arguments.seed, default=None,
                   help=f"random seed (default 0; {DEFAULT_TEMPLATE_SEED} for --templates)")
    p.add_argument("--actions", default=None, help="comma-separated subset of actions (default: all 13)")
    p.add_argument("--rest", type=arguments.int_range(0, 600), default=0, help="frames of still guard before and after each trial")
    p.set_defaults(func=run)


def _parse_actions(text: str | None) -> list[str] | None:
    if text is None:
        return None
    names = [t.strip() for t in text.split(",") if t.strip()]
    if not names:  # `--actions ,` or `--actions ""` synthesized all 13, as if not given
        raise InputError(f"--actions {text!r}: names no action; actions: {', '.join(ACTION_NAMES)}")
    bad = [n for n in names if n not in ACTION_NAMES]
    if bad:
        raise InputError(f"unknown action(s) {', '.join(bad)}; actions: {', '.join(ACTION_NAMES)}")
    return names


def run(args: argparse.Namespace) -> int:
    try:
        return _run(args)
    except OSError as exc:  # an output we cannot write: one line naming it
        raise InputError(f"{exc.filename or args.output}: cannot write ({exc.strerror or exc})") from None


def _run(args: argparse.Namespace) -> int:
    if args.templates:
        from engine.errors import refuse_other_kind
        from engine.npz_files import is_npz_head

        refuse_other_kind(args.output, "-o", "an .npz", is_npz_head)  # earlier templates are replaced
        seed = DEFAULT_TEMPLATE_SEED if args.seed is None else args.seed
        path = build_default_templates(args.output, seed, profile=args.player)
        print(f"wrote templates for {len(ACTION_NAMES)} actions to {path} (seed {seed})")
        return 0
    if args.seed is None:
        args.seed = 0
    lib = load_library()
    rng = np.random.default_rng(args.seed)
    actions = _parse_actions(args.actions)
    if args.trials is not None:
        if args.trials < 1:
            raise InputError("--trials must be at least 1")
        trials = synth_trials(lib, args.player, args.trials, rng, actions, max(args.rest, 0))
        moved: list[tuple[Path, Path]] = []
        written = write_trials(args.output, trials, args.player, args.seed, moved)
        say_moved(moved, args.output)
        print(f"wrote {len(written)} trial files under {args.output}")
        return 0
    if not args.session or args.session <= 0:
        raise InputError("--session needs a positive number of seconds")
    out = Path(args.output)
    if out.is_dir():
        raise InputError(f"{out}: is a directory; --session writes one CSV file")
    signal, labels = synth_session(lib, args.session, args.player, rng, actions=actions)
    meta = {"source": f"{SOURCE}, profile {args.player}", "seed": str(args.seed)}
    out.parent.mkdir(parents=True, exist_ok=True)
    aside = write_keeping(out, _to_recording(signal, labels, meta))
    if aside is not None:
        print(f"{out} was not empty: moved to {aside}", file=sys.stderr)
    count = sum(1 for i, lab in enumerate(labels) if lab and (i == 0 or labels[i - 1] != lab))
    print(f"wrote {len(signal)} frames ({len(signal) / FPS:.1f} s, {count} actions) to {out}")
    return 0
