"""`quickjab devices`: list the Wiimotes (model, path) and serial ports this machine can see,
with the source URL to open each."""

from __future__ import annotations

import argparse
import json
import sys


def no_device_hint(url: str) -> str:
    """What to check when `url` never connected (`record`, `scope`): a Wiimote is paired and woken,
    a serial board plugged in; the advice for the device the URL names."""
    scheme = url.split(":", 1)[0].lower()
    if scheme == "wiimote":
        return ("check that the Wiimote is paired and awake (press 1 and 2; `quickjab devices` lists the ones found; "
                "docs/wiimote.md)")
    if scheme == "serial":
        return ("check the port (`quickjab devices` lists USB serial ports; an emulator's is the path `quickjab bridge "
                "emulate` printed, or its --link) and that the board is plugged in")
    return "check that the device is connected (`quickjab devices` lists Wiimotes and serial ports)"


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("devices", help="list Wiimotes and serial ports", description=__doc__)
    p.add_argument("--json", action="store_true", help="print one JSON object instead of text")
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
    if args.json:
        json.dump({"wiimotes": wiimotes, "serial_ports": ports, "problems": [x for x in (wproblem, sproblem) if x]}, sys.stdout, indent=2)
        print()
        return 0
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
    return 0
