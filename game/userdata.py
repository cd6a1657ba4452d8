"""Where the player's own files live: XDG_DATA_HOME/quickjab (or ~/.local/share/quickjab)."""

from __future__ import annotations

import os
from pathlib import Path

TEMPLATES_NAME = "templates.npz"
SHIPPED_TEMPLATES = Path(__file__).resolve().parent / "assets" / "templates.npz"


def data_dir() -> Path:
    base = os.environ.get("XDG_DATA_HOME") or str(Path.home() / ".local" / "share")
    return Path(base) / "quickjab"


def user_templates_path() -> Path:
    """The templates `Train your moves` saves and `play` prefers."""
    return data_dir() / TEMPLATES_NAME
