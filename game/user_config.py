"""The user's config file, $XDG_CONFIG_HOME/quickjab/config.toml (else ~/.config/quickjab/...):
settings a player keeps on this machine. Today one table, the recognizer's
(engine/recognition/config.py names every setting):

    [recognizer]
    noise_g = 0.5      # g, or "auto"
    main = "auto"

Where the recognizer's settings come from, the later winning: the defaults, the settings saved
with the templates (`quickjab train --recognizer ...`), this file, the command line
(`quickjab play --recognizer noise_g=0.5`). A file that cannot be read, is not TOML or sets
an unknown name or a wrong value is one line naming the file (exit 2), never a traceback.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path

from engine.errors import InputError, not_a_regular_file
from engine.recognition.config import check_settings, parse_assignments
from engine.xdg import base_dir

CONFIG_NAME = "config.toml"
TABLES = ("recognizer",)
MAX_CONFIG_BYTES = 1 << 20  # a settings file is a few lines; never read a huge one whole


def config_path() -> Path:
    return base_dir("XDG_CONFIG_HOME", ".config") / "quickjab" / CONFIG_NAME  # a relative one is ignored


def read_config(path: str | os.PathLike | None = None) -> dict[str, dict[str, object]]:
    """{table: {name: value}} from the config file, checked; {} when there is no file."""
    path = Path(path) if path is not None else config_path()
    if not os.path.lexists(path):  # exists() is False for a link that loops or dangles: that is a bad file
        return {}
    tomllib = _toml_reader(path)
    try:
        st = path.stat()
        why = not_a_regular_file(st)  # a FIFO would hang here, /dev/zero fill the memory
        if why:
            raise InputError(f"{path}: cannot read the config file: {why}")
        if st.st_size > MAX_CONFIG_BYTES:
            raise InputError(f"{path}: a config file of over {MAX_CONFIG_BYTES >> 20} MiB; expected a few lines")
        with open(path, "rb") as f:
            data = tomllib.load(f)
    except tomllib.TOMLDecodeError as exc:
        if _starts_with_bom(path):  # tomllib: "Invalid statement (at line 1, column 1)", nothing to see there
            raise InputError(f"{path}: not a valid TOML file (it starts with a byte-order mark: save it as UTF-8 without BOM)") from None
        raise InputError(f"{path}: not a valid TOML file ({exc})") from None
    except UnicodeDecodeError:
        raise InputError(f"{path}: not a valid TOML file (not UTF-8 text)") from None
    except RecursionError:  # tomllib recurses per nesting level: `[` x 100,000 is within the size limit
        raise InputError(f"{path}: not a valid TOML file (nested too deeply)") from None
    except ValueError:  # tomllib's int() of an integer over Python's 4300-digit limit (not a TOMLDecodeError)
        raise InputError(f"{path}: not a valid TOML file (an integer of over 4300 digits)") from None
    except OSError as exc:
        raise InputError(f"{path}: cannot read the config file ({exc.strerror or exc})") from None
    unknown = [k for k in data if k not in TABLES]
    if unknown:
        raise InputError(f"{path}: unknown setting or table {unknown[0]!r} (known tables: "
                         + ", ".join(f"[{t}]" for t in TABLES) + ")")
    table = data.get("recognizer", {})
    if not isinstance(table, dict):
        raise InputError(f"{path}: 'recognizer' must be a table ([recognizer] then name = value lines)")
    return {"recognizer": check_settings(table, f"{path} [recognizer]")}


def _starts_with_bom(path: Path) -> bool:
    """Notepad's "UTF-8 with BOM"; TOML has no byte-order mark."""
    try:
        with open(path, "rb") as f:
            return f.read(3) == b"\xef\xbb\xbf"
    except OSError:
        return False


def _toml_reader(path: Path):
    """The standard library's TOML reader (Python 3.11+; the project supports 3.10, where the
    same API may come from `tomli` if installed)."""
    try:
        import tomllib
    except ImportError:
        try:
            import tomli as tomllib
        except ImportError:
            raise InputError(f"{path}: reading a config file needs Python 3.11 or newer (tomllib)") from None
    return tomllib


def recognizer_settings(assignments: Sequence[str] = (), path: str | os.PathLike | None = None) -> dict[str, object]:
    """The recognizer settings set on this machine: the config file's [recognizer] table, then
    the command line's `--recognizer NAME=VALUE` (which win). They go over the settings saved
    with the templates (engine.recognition.config.layered)."""
    return {**read_config(path).get("recognizer", {}), **parse_assignments(assignments)}
