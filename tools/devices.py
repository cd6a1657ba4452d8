"""`quickjab devices`: list the Wiimotes (model, path) and serial ports this machine can see,
with the source URL to open each. `quickjab devices PATH...` also probes those ports (a pty from
`quickjab bridge emulate` or socat, which the list never shows) for a board answering with the
serial protocol's HELLO; exit status 1 when one does not, or answers with a HELLO the game cannot
use (malformed, or spoiling its samples: tools/serial_probe.py)."""

from __future__ import annotations

import argparse
import json
import sys

from engine import arguments


def no_device_hint(url: str) -> str:
    """What to check when `url` never connected (`record`, `scope`): a Wiimote is paired and woken,
    a serial board plugged in; the advice for the device the URL names."""
    scheme = url.split(":", 1)[0].lower()
    if scheme == "wiimote":
        return ("check that the Wiimote is paired and awake (press 1 and 2; `quickjab devices` lists the ones found; "
                "docs/wiimote.md)")
    if scheme == "serial":
        port = url.split("://", 1)[-1].split("?", 1)[0]
        probe = "" if port == "auto" else f"; `quickjab devices {port}` says whether a board answers there"
        return ("check the port (`quickjab devices` lists USB serial ports; an emulator's is the path `quickjab bridge "
                f"emulate` printed, or its --link{probe}) and that the board is plugged in")
    return "check that the device is connected (`quickjab devices` lists Wiimotes and serial ports)"


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("devices", help="list Wiimotes and serial ports", description=__doc__)
    p.add_argument("--json", action="store_true", help="print one JSON object instead of text")
    p.add_argument("paths", nargs="*", metavar="PATH", type=arguments.path_argument,
                   help="serial ports to probe for a board (e.g. /dev/pts/5, which the list never shows): each is "
                        "opened, asked for a HELLO and read for --probe-seconds; opening a port may reset an Arduino-"
                        "style board, and a port another program has open loses bytes to the probe")
    p.add_argument("--probe-seconds", type=arguments.float_range(0.0, 60.0, lo_open=True), default=None, metavar="S",
                   help="how long to wait for each probed port's HELLO (default 1.5; a board sends one every second)")
    p.set_defaults(func=run)


def find_wiimotes() -> tuple[list[dict[str, str]], str]:
    """(Wiimotes as dicts, a problem to report or '')."""
    from engine.sensors.wiimote.transport import BackendMissing, hid_backend, list_wiimotes

    try:
        backend = hid_backend()
    except BackendMissing as exc:
        return [], str(exc)
    found = [
        {
            "model": w.model,
            "path": w.path_str,
            "name": w.product_string,
            "serial": w.serial,
            "kernel_driver": w.kernel_driver or "",
            "url": f"wiimote://{w.path_str}",
        }
        for w in list_wiimotes(backend)
    ]
    return found, ""


def find_serial_ports() -> tuple[list[dict[str, str]], str]:
    try:
        from serial.tools import list_ports
    except ImportError as exc:
        return [], f"pyserial is not usable ({exc})"
    ports = sorted(list_ports.comports(), key=lambda port: port.device)
    return [
        {"path": port.device, "description": port.description or "", "hwid": port.hwid or "", "url": f"serial://{port.device}"}
        for port in ports
    ], ""


def run(args: argparse.Namespace) -> int:
    from engine.sensors.wiimote import PAIRING_STEPS, WAIT_HINT

    wiimotes, wproblem = find_wiimotes()
    ports, sproblem = find_serial_ports()
    probed = probe_paths(args.paths, args.probe_seconds)
    status = 1 if any(not r["answered"] or r["problem"] for r in probed) else 0  # a board the game cannot use too
    if args.json:
        listing = {"wiimotes": wiimotes, "serial_ports": ports, "problems": [x for x in (wproblem, sproblem) if x]}
        if args.paths:  # a key of its own, only when asked: the listing's keys stay as they were
            listing["probed"] = probed
        json.dump(listing, sys.stdout, indent=2)
        print()
        return status
    print("Wiimotes:")
    for w in wiimotes:
        extra = f"  (kernel driver: {w['kernel_driver']}, see docs/wiimote.md)" if w["kernel_driver"] == "wiimote" else ""
        print(f"  {w['model']:<14} {w['path']:<20} {w['serial']:<18} {w['url']}{extra}")
    if not wiimotes:
        print(f"  none found{': ' + wproblem if wproblem else ''}")
        print(f"  ({PAIRING_STEPS} {WAIT_HINT})")  # PAIRING_HELP less its pointer to this very list
    print("Serial ports:")
    for s in ports:
        print(f"  {s['path']:<20} {s['description']:<30} {s['url']}")
    if not ports:
        print(f"  none found{': ' + sproblem if sproblem else ''}")
    if args.paths:
        print("Probed:")
        for r in probed:
            print(f"  {r['path']:<20} {r['result']}" + (f"  {r['url']}" if r["answered"] else ""))
    return status


def probe_paths(paths: list[str], seconds: float | None) -> list[dict]:
    """Each path's probe (tools.serial_probe) as a dict, in the order given."""
    if not paths:
        return []
    from tools.serial_probe import PROBE_S, probe

    return [probe(path, seconds or PROBE_S).as_dict() for path in paths]
