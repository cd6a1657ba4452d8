"""The XDG base directories (the XDG Base Directory Specification): $XDG_CONFIG_HOME,
$XDG_DATA_HOME, $XDG_CACHE_HOME when set to an absolute path, else their defaults under the home
directory. The spec: a relative path in these variables is invalid and must be ignored (a
relative one put the player's templates under whatever directory `quickjab train` ran in, where
`play` from another one did not find them; "~/x" is not expanded by the shell in quotes, and
made a directory named "~")."""

from __future__ import annotations

import os
from pathlib import Path


def home() -> Path:
    """$HOME when it is an absolute path, else the account's home directory: an empty HOME put
    the player's files under /, a relative one under the current directory."""
    value = os.environ.get("HOME", "")
    if os.path.isabs(value):
        return Path(value)
    try:
        import pwd

        return Path(pwd.getpwuid(os.getuid()).pw_dir)
    except (ImportError, KeyError):  # no pwd (Windows), or this uid has no account entry
        return Path.home()


def base_dir(variable: str, *default: str) -> Path:
    """$`variable` if it is an absolute path, else home()/`default` (e.g. ".local", "share")."""
    value = os.environ.get(variable, "")
    return Path(value) if os.path.isabs(value) else home().joinpath(*default)


def is_there(path: Path) -> bool:
    """Whether `path` is there. One that cannot be looked at is not: Path.exists() answers False
    under a file but raises for a name too long for the file system (ENAMETOOLONG: a long
    $XDG_DATA_HOME, $QUICKJAB_CACHE_DIR), so a user file or a cache there was one line with the
    errno, not naming the variable, where an unusable directory is passed over."""
    try:
        return path.exists()
    except OSError:
        return False
