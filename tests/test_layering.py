"""The layering: tools -> game -> engine -> firmware_bridge, never the other way.
Every module's imports are read from its source (ast), wherever they sit: at the top, inside a
function (the lazy imports that keep start-up light) or under TYPE_CHECKING. A string that names
a module of a forbidden package exactly (an importlib.import_module table) counts too."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parent.parent
PACKAGES = ("engine", "game", "tools", "firmware_bridge")
FORBIDDEN = {  # package -> packages it must never import
    "engine": {"game", "tools"},
    "game": {"tools"},
    "firmware_bridge": {"engine", "game", "tools"},
}


def module_name(path: Path) -> str:
    parts = path.relative_to(REPO).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


ALL_MODULES = {module_name(p) for pkg in PACKAGES for p in (REPO / pkg).rglob("*.py")}


def imported_modules(path: Path) -> set[tuple[str, int]]:
    """(module, line) for every absolute import in the file, and every string constant that is
    exactly the name of one of the project's modules."""
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found |= {(alias.name, node.lineno) for alias in node.names}
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            found.add((node.module, node.lineno))
        elif isinstance(node, ast.Constant) and isinstance(node.value, str) and node.value in ALL_MODULES:
            found.add((node.value, node.lineno))
    return found


def violations(package: str) -> list[str]:
    out = []
    for path in sorted((REPO / package).rglob("*.py")):
        for name, line in sorted(imported_modules(path)):
            top = name.split(".")[0]
            if top in FORBIDDEN[package]:
                out.append(f"{path.relative_to(REPO)}:{line} imports {name}")
    return out


@pytest.mark.parametrize("package", sorted(FORBIDDEN))
def test_no_package_imports_a_layer_above_it(package):
    assert violations(package) == []


def test_the_check_sees_lazy_imports_and_import_tables(tmp_path):
    # the check is not vacuous: the shapes of the leaks it replaced are found
    sample = tmp_path / "leak.py"
    sample.write_text(
        "def f():\n    from engine.recording import read_recording\n"
        "COMMANDS = {'record': ('tools.record', 'help')}\n"
        "import tools.cli as cli\n"
    )
    assert {name for name, _ in imported_modules(sample)} == {"engine.recording", "tools.record", "tools.cli"}
    assert len(ALL_MODULES) > 100 and "tools.cli" in ALL_MODULES and "engine.recording" in ALL_MODULES
