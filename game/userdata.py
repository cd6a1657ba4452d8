"""Where the player's own files live: XDG_DATA_HOME/quickjab (or ~/.local/share/quickjab)."""

from __future__ import annotations

from pathlib import Path

from engine.xdg import base_dir

TEMPLATES_NAME = "templates.npz"
SHIPPED_TEMPLATES = Path(__file__).resolve().parent / "assets" / "templates.npz"


def data_dir() -> Path:
    return base_dir("XDG_DATA_HOME", ".local", "share") / "quickjab"  # a relative one is ignored (the XDG spec)


def user_templates_path() -> Path:
    """The templates `Train your moves` saves and `play` prefers."""
    return data_dir() / TEMPLATES_NAME


DEFAULT_PROFILE = "default"
# names Windows keeps for devices, in any case and whatever follows the dot: `con.npz` opens
# the console there, not a file
RESERVED_PROFILES = frozenset({"con", "prn", "aux", "nul", *(f"{port}{n}" for port in ("com", "lpt") for n in range(10))})


def profile_templates_path(profile: str | None = None, option: str = "--profile") -> Path:
    """The templates of a named player (`train --profile NAME`, `play --profile NAME`). The
    default profile is the file `train` has always saved, so existing sets keep working. A bad
    name is an error naming `option` (player 2's is --profile2)."""
    import re

    from engine.errors import InputError

    if profile is None or profile == DEFAULT_PROFILE:
        return user_templates_path()
    if not re.fullmatch(r"[A-Za-z0-9][A-Za-z0-9_-]{0,39}", profile):
        raise InputError(f"{option} {profile!r}: letters, digits, _ and - only (up to 40)")
    if profile.lower() in RESERVED_PROFILES:
        raise InputError(f"{option} {profile!r}: a device name reserved on Windows (CON, PRN, AUX, NUL, COM0-9, LPT0-9); "
                         "choose another name")
    folder = data_dir() / "profiles"
    _refuse_another_case(folder, profile, option)
    return folder / f"{profile}.npz"


def _refuse_another_case(folder: Path, profile: str, option: str) -> None:
    """InputError when `profile` has no file of its own but a saved profile's name differs from
    it only in case: on macOS and Windows that is the same file (train would replace that
    player's moves, --reset delete them, play load them). A profile's own name always works."""
    from engine.errors import InputError

    try:
        saved = sorted(p.stem for p in folder.glob("*.npz"))  # the names as stored, whatever the file system
    except OSError:  # no folder yet (or one that cannot be listed: said when it is written)
        return
    if profile in saved:
        return
    other = next((name for name in saved if name.lower() == profile.lower()), None)
    if other is not None:
        raise InputError(f"{option} {profile!r}: differs only in case from the saved profile {other!r} "
                         f"(one file on macOS and Windows); use {option} {other}, or another name")
