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


def test_recordings_never_import_sources():
    # sources read recordings (the replay source, the Wiimote emulator); a recording names only
    # the sample (engine/sample.py), so the two packages no longer import each other's names
    names = {name for name, _ in imported_modules(REPO / "engine" / "recording.py")}
    assert "engine.sample" in names
    assert not [n for n in names if n == "engine.sensors" or n.startswith("engine.sensors.")]


def top_level_imports(path: Path) -> set[str]:
    """The project modules a file imports when it is imported (not inside functions),
    relative imports resolved."""
    me = module_name(path)
    package = me if path.name == "__init__.py" else me.rpartition(".")[0]
    out = set()
    for node in ast.parse(path.read_text(encoding="utf-8")).body:
        if isinstance(node, ast.Import):
            out |= {a.name for a in node.names}
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                parts = package.split(".")[: len(package.split(".")) - (node.level - 1)]
                base = ".".join(parts + ([node.module] if node.module else []))
            out.add(base)
            out |= {f"{base}.{a.name}" for a in node.names}
    return {n for n in out if n in ALL_MODULES}


def import_cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Cycles of a module -> imported modules graph (depth first)."""
    state: dict[str, int] = {}
    cycles: list[list[str]] = []

    def visit(m: str, path: list[str]) -> None:
        state[m] = 1
        for d in sorted(graph.get(m, ())):
            if state.get(d) == 1:
                cycles.append(path[path.index(d):] + [d])
            elif d not in state:
                visit(d, path + [d])
        state[m] = 2

    for m in sorted(graph):
        if m not in state:
            visit(m, [m])
    return cycles


def test_no_module_imports_itself_back_at_import_time():
    paths = {module_name(p): p for pkg in PACKAGES for p in (REPO / pkg).rglob("*.py")}
    # a module importing its own package's __init__ (or the reverse) is how packages load
    graph = {m: {d for d in top_level_imports(p) if d != m and not m.startswith(d + ".")}
             for m, p in paths.items()}
    assert sum(map(len, graph.values())) > 200  # the graph is the project's, not empty
    assert import_cycles(graph) == []
    assert import_cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == [["a", "b", "c", "a"]]


def every_import(path: Path) -> set[str]:
    """The project modules a file imports anywhere: at the top, inside functions (the lazy
    imports) or under TYPE_CHECKING; `from package import module` counts the module."""
    out = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            out |= {a.name for a in node.names}
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            out.add(node.module)
            out |= {f"{node.module}.{a.name}" for a in node.names}
    return {n for n in out if n in ALL_MODULES}


def test_no_game_modules_import_each_other_even_lazily():
    """A function-level import hides a cycle from import time, not from the reader: game.play
    and game.two_player share their start-up pieces through game.launch, not each other."""
    paths = {module_name(p): p for p in (REPO / "game").rglob("*.py")}
    graph = {m: {d for d in every_import(p) if d in paths and d != m and not m.startswith(d + ".")}
             for m, p in paths.items()}
    assert "game.launch" in graph["game.two_player"] and "game.launch" in graph["game.play"]
    assert import_cycles(graph) == []
