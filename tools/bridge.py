"""`quickjab bridge emulate|faults`: the serial bridge's device emulator on a pty, and the
protocol's fault-injection figures."""

from __future__ import annotations

import argparse
import json
import math
import signal as sig
import sys
import time
from dataclasses import asdict

from engine.arguments import int_range, output_file, path_argument, seed
from engine.errors import InputError

MAX_COUNT = 100_000_000  # the most frames, corrupted frames or events `bridge faults` takes


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("bridge", help="serial IMU bridge: device emulator and fault figures", description=__doc__)
    cmds = p.add_subparsers(dest="bridge_command", metavar="COMMAND", required=True)

    e = cmds.add_parser(
        "emulate", help="emulate a bridge board on a pty (prints the port path)",
        description="Run the firmware's sampling loop against a simulated IMU on a pseudo-terminal. "
        "Then: quickjab record --source serial:///dev/pts/N -o out.csv (or the --link path, which "
        "survives --unplug-at).")
    e.add_argument("--replay", metavar="REC.CSV", type=path_argument, help="feed the simulated IMU from this recording (looped)")
    e.add_argument("--player", choices=PLAYER_PROFILES, default=None,
                   help="feed it a virtual player's boxing instead (random actions with rests, both hands, on the "
                   "game's axes, a minute looped): `play` and `recognize` take its punches as a player's; "
                   "the default signal is a bare pulse on x over gravity on z, for testing the link")
    e.add_argument("--seconds", type=float, default=None, help="stop after this long (default: Ctrl-C)")
    e.add_argument("--rate", type=int, default=200, help="sample rate in Hz (default 200)")
    e.add_argument("--sensors", type=int, choices=(1, 2), default=None, help="sensors (default: the recording's, or 2)")
    e.add_argument("--link", type=output_file, default=None,
                   help="keep a symlink to the current pty here (stable across replugs)")
    e.add_argument("--ticks-start", type=int, default=None,
                   help="device microsecond counter at boot (e.g. 1073000000 to see the 30-bit wrap soon); "
                   "default: the host's monotonic clock")
    e.add_argument("--garbage-every", type=float, default=0.0, metavar="S", help="a random garbage burst every S seconds")
    e.add_argument("--garbage-len", type=int, default=32, help="longest garbage burst in bytes")
    e.add_argument("--flip-every", type=float, default=0.0, metavar="S", help="flip one bit every S seconds")
    e.add_argument("--drop-every", type=float, default=0.0, metavar="S", help="drop one byte every S seconds")
    e.add_argument("--stall-at", type=float, action="append", default=[], metavar="T", help="the device hangs at T s (repeatable)")
    e.add_argument("--stall-s", type=float, default=0.5, help="how long a stall lasts")
    e.add_argument("--reboot-at", type=float, action="append", default=[], metavar="T", help="the device reboots at T s (repeatable)")
    e.add_argument("--unplug-at", type=float, action="append", default=[], metavar="T",
                   help="the port vanishes at T s and comes back (a new pty) after --unplug-s (repeatable)")
    e.add_argument("--unplug-s", type=float, default=1.0, help="how long an unplug lasts")
    e.add_argument("--seed", type=int, default=None,
                   help="make boot ids, faults and noise reproducible (default: a random boot id per boot)")
    e.add_argument("--quiet", action="store_true", help="print only port paths")
    e.set_defaults(func=run_emulate)

    f = cmds.add_parser(
        "faults", help="fault-injection figures for the wire protocol",
        description="False accepts over random bytes and corrupted frames; frames lost per dropped frame, "
        "garbage burst, bit flip and dropped byte (ground truth and the decoder's own count).")
    f.add_argument("--random-mb", type=float, default=1.0, help="MiB of random bytes (default 1)")
    f.add_argument("--corrupted", type=int_range(0, MAX_COUNT), default=100_000, help="corrupted frames (default 100000)")
    f.add_argument("--frames", type=int_range(0, MAX_COUNT), default=20_000, help="frames per loss experiment")
    f.add_argument("--events", type=int_range(0, MAX_COUNT), default=1000, help="faults per loss experiment")
    f.add_argument("--seed", type=seed, default=0, help="seed of the random bytes and faults (default 0)")
    f.add_argument("--json", action="store_true", help="print JSON")
    f.set_defaults(func=run_faults)


# `emulate --player`: game.virtual_player's profiles (named here: the CLI's parsers load no game
# module; a test holds the two equal), and the minute of boxing the emulator loops
PLAYER_PROFILES = ("experienced", "novice")
PLAYER_SECONDS = 60.0
MAX_SECONDS = 1e7  # ~116 days: any longer is a typo, and time.sleep overflows on some values


def _check(name: str, value: float | None, low: float, high: float, *, low_open: bool = False) -> None:
    """One-line InputError unless `value` is None or a finite number in [low, high] ((low, high]
    with low_open)."""
    if value is None:
        return
    ok = math.isfinite(value) and (value > low if low_open else value >= low) and value <= high
    if not ok:
        bound = f"({low:g}" if low_open else f"[{low:g}"
        raise InputError(f"{name} {value}: must be a number in {bound}, {high:g}]")


def check_emulate_args(args: argparse.Namespace) -> None:
    """Every option, before anything starts (nan or a negative duration would hang or crash the
    run later)."""
    if args.rate <= 0 or args.rate > 1000:
        raise InputError(f"--rate {args.rate}: must be 1..1000 Hz")
    _check("--seconds", args.seconds, 0, MAX_SECONDS, low_open=True)
    for name in ("garbage_every", "flip_every", "drop_every"):
        _check("--" + name.replace("_", "-"), getattr(args, name), 0, MAX_SECONDS)
    _check("--garbage-len", args.garbage_len, 1, 4096)
    for name in ("stall_s", "unplug_s"):
        _check("--" + name.replace("_", "-"), getattr(args, name), 0, 3600)
    for name in ("stall_at", "reboot_at", "unplug_at"):
        for v in getattr(args, name):
            _check("--" + name.replace("_", "-"), v, 0, MAX_SECONDS)
    if args.ticks_start is not None and not 0 <= args.ticks_start < (1 << 30):
        raise InputError(f"--ticks-start {args.ticks_start}: must be 0..{(1 << 30) - 1} (a 30-bit counter)")
    if args.seed is not None and args.seed < 0:
        raise InputError(f"--seed {args.seed}: must be 0 or more")
    if args.replay and args.player:
        raise InputError("--replay and --player: give one signal for the simulated IMU, not both")


def player_motion(profile: str, seed: int):
    """A virtual player's minute of boxing (tools.synth: random actions with rests, in the game's
    axes, 60 Hz) as the emulator's looped signal, and its sensor count."""
    from types import SimpleNamespace

    import numpy as np

    from firmware_bridge.emulator import recording_motion
    from game.actions import load_library
    from tools.synth import synth_session

    accel, _ = synth_session(load_library(), PLAYER_SECONDS, profile, np.random.default_rng(seed))
    session = SimpleNamespace(t=np.arange(len(accel)) / 60.0, accel=accel, sensors=accel.shape[1])
    return recording_motion("virtual player", lambda _: session)


def _read_saying_notes(path: str):
    """read_recording, saying what it left out (a cut last row), as every other reader does."""
    from engine.recording import read_recording, say_notes

    rec = read_recording(path)
    say_notes(rec.notes, "bridge")
    return rec


def run_emulate(args: argparse.Namespace) -> int:
    from firmware_bridge.emulator import (
        Emulator,
        EmulatorDef,
        Faults,
        recording_motion,
        synthetic_motion,
    )

    check_emulate_args(args)
    if args.replay:
        signal, sensors = recording_motion(args.replay, _read_saying_notes)  # RecordingError names the file
    elif args.player:
        signal, sensors = player_motion(args.player, args.seed or 0)
    else:
        signal, sensors = synthetic_motion(args.sensors or 2, args.seed or 0), args.sensors or 2
    sensors = min(args.sensors or sensors, sensors)
    faults = Faults(garbage_every=args.garbage_every, garbage_len=args.garbage_len,
                    flip_every=args.flip_every, drop_every=args.drop_every, stall_at=args.stall_at,
                    stall_s=args.stall_s, reboot_at=args.reboot_at, unplug_at=args.unplug_at,
                    unplug_s=args.unplug_s)

    def on_port(path: str) -> None:
        extra = f" (link {args.link})" if args.link else ""
        print(f"port: {path}{extra}", flush=True)
        if not args.quiet:
            print(f"  try: quickjab record --source serial://{args.link or path} -o out.csv", file=sys.stderr, flush=True)

    def on_event(what: str) -> None:
        if not args.quiet:
            print(f"[{time.strftime('%H:%M:%S')}] {what}", file=sys.stderr, flush=True)

    board = EmulatorDef(sensors, rate_hz=args.rate, ticks_start=args.ticks_start, seed=args.seed)
    emu = Emulator.from_def(signal, board, faults=faults, link=args.link, on_port=on_port, on_event=on_event)
    # `kill` ends it as Ctrl-C does: the port closes and the --link symlink goes (left behind, it
    # pointed at a pty number another terminal may get)
    previous = sig.signal(sig.SIGTERM, _interrupt)
    try:
        stats = emu.run(args.seconds)
    except KeyboardInterrupt:
        emu.stop()
        stats = emu.stats
    finally:
        sig.signal(sig.SIGTERM, previous)
    if not args.quiet:
        print("emulator: " + " ".join(f"{k}={v}" for k, v in asdict(stats).items()), file=sys.stderr)
    return 0


def _interrupt(signum: int, frame: object) -> None:
    raise KeyboardInterrupt


def run_faults(args: argparse.Namespace) -> int:
    from firmware_bridge import faults

    _check("--random-mb", args.random_mb, 0, 1024)
    if args.events * 3 > args.frames:
        raise InputError(f"--events {args.events}: at most --frames/3 ({args.frames // 3})")
    t0 = time.perf_counter()
    outcomes = faults.run_all(args.random_mb, args.corrupted, args.frames, args.events, args.seed)
    took = time.perf_counter() - t0
    if args.json:
        print(json.dumps([o.as_dict() for o in outcomes], indent=2))
        return 0
    print(f"{'experiment':32} {'events':>9} {'sent':>8} {'decoded':>8} {'false acc':>9} {'lost':>6} {'decoder lost':>12} {'lost/event':>10}")
    for o in outcomes:
        print(f"{o.name:32} {o.events:9d} {o.frames_sent:8d} {o.frames_decoded:8d} {o.false_accepts:9d} "
              f"{o.lost:6d} {o.decoder_lost:12d} {o.lost_per_event:10.3f}")
    false = outcomes[0].false_accepts + outcomes[1].false_accepts
    dropped = outcomes[2]
    print(f"false accepts: {false} over {outcomes[0].events} random bytes and {outcomes[1].events} corrupted frames")
    print(f"dropped frames: {dropped.events} dropped, decoder counted {dropped.decoder_lost} lost "
          f"({'equal' if dropped.decoder_lost == dropped.events else 'DIFFERENT'})")
    print(f"({took:.1f} s)")
    return 0 if false == 0 and dropped.decoder_lost == dropped.events else 1
