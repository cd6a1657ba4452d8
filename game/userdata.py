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
    return data_dir() / "profiles" / f"{profile}.npz"
