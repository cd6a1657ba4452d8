"""Source plugins: an installed package declares a scheme in the `quickjab.sources` entry-point
group and `open_source` finds it on first use, without anything importing the package. The
example package is tests/plugin_example; it is "installed" the way an installer lays it out:
the package beside a dist-info directory whose entry_points.txt comes from its pyproject.toml."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import engine.sensors.source as source_mod
from engine.clock import VirtualClock
from engine.sensors import SourceError, SourceState, open_source, register_scheme

REPO = Path(__file__).resolve().parent.parent
EXAMPLE = REPO / "tests" / "plugin_example"


def install(site: Path, dist: str = "myimu_source", schemes: dict[str, str] | None = None,
            copy_package: bool = True) -> Path:
    """Lay the example out in `site` as an installer would; `schemes` overrides the declared
    entry points (to declare a scheme twice)."""
    project = toml_tables(EXAMPLE / "pyproject.toml")
    declared = schemes if schemes is not None else project['project.entry-points."quickjab.sources"']
    version = project["project"]["version"]
    site.mkdir(parents=True, exist_ok=True)
    if copy_package:
        shutil.copytree(EXAMPLE / "myimu_source", site / "myimu_source",
                        ignore=shutil.ignore_patterns("__pycache__"))
    info = site / f"{dist}-{version}.dist-info"
    info.mkdir()
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {dist}\nVersion: {version}\n")
    lines = [f"{name} = {target}" for name, target in declared.items()]
    (info / "entry_points.txt").write_text("[quickjab.sources]\n" + "\n".join(lines) + "\n")
    return site


def toml_tables(path: Path) -> dict[str, dict[str, str]]:
    """The `key = "string"` entries of each [table] of a simple TOML file (tomllib is 3.11+)."""
    tables: dict[str, dict[str, str]] = {}
    current = tables.setdefault("", {})
    for line in path.read_text(encoding="utf-8").splitlines():
        line = line.strip()
        if line.startswith("["):
            current = tables.setdefault(line.strip("[]"), {})
        elif "=" in line and not line.startswith("#"):
            key, value = (x.strip() for x in line.split("=", 1))
            if value.startswith('"'):
                current[key] = value.strip('"')
    return tables


@pytest.fixture
def registry(monkeypatch):
    """No test leaks the example's registration or module into the others (built-in schemes
    registered meanwhile stay: their modules are imported once)."""
    monkeypatch.delitem(sys.modules, "myimu_source", raising=False)
    source_mod._factories.pop("myimu", None)
    yield
    source_mod._factories.pop("myimu", None)
    sys.modules.pop("myimu_source", None)


def test_an_installed_plugin_opens_through_its_entry_point(tmp_path, monkeypatch, registry):
    monkeypatch.syspath_prepend(str(install(tmp_path / "site")))
    assert "myimu_source" not in sys.modules and "myimu" not in source_mod._factories
    clock = VirtualClock()
    src = open_source("myimu://?rate=100&sensors=2", clock=clock.seconds)
    assert "myimu_source" in sys.modules and "myimu" in source_mod.registered_schemes()
    assert src.state is SourceState.CONNECTED and src.sensors == 2 and src.rate_hz == 100
    clock.advance(50_000_000)
    got = src.poll()
    assert len(got) == 6 and got[0].accel.shape == (2, 3)  # samples 0..5 in 50 ms at 100 Hz
    np.testing.assert_allclose(np.linalg.norm(got[-1].accel, axis=1), 1.0)
    assert src.poll() == []  # nothing new: never waits
    src.close()
    assert src.state is SourceState.DISCONNECTED
    with pytest.raises(SourceError, match="rate"):  # the plugin's own parameter checks
        open_source("myimu://?rate=0")


def test_an_uninstalled_scheme_names_the_known_ones_including_plugins(tmp_path, monkeypatch, registry):
    monkeypatch.syspath_prepend(str(install(tmp_path / "site")))
    with pytest.raises(SourceError, match="unknown source scheme 'nosuch'.*myimu"):
        open_source("nosuch://x")
    assert "myimu_source" not in sys.modules  # listing a plugin does not import it


def test_a_scheme_declared_by_two_packages_is_an_error(tmp_path, monkeypatch, registry):
    install(tmp_path / "site")
    install(tmp_path / "site", dist="other_imu", schemes={"myimu": "other_imu:open"}, copy_package=False)
    monkeypatch.syspath_prepend(str(tmp_path / "site"))
    with pytest.raises(SourceError, match="more than one installed package"):
        open_source("myimu://")


def test_a_plugin_whose_module_is_missing_is_a_source_error(tmp_path, monkeypatch, registry):
    monkeypatch.syspath_prepend(str(install(tmp_path / "site", copy_package=False)))
    with pytest.raises(SourceError, match="myimu:// is not available here"):
        open_source("myimu://")


def test_a_plugin_naming_a_missing_factory_is_a_source_error(tmp_path, monkeypatch, registry):
    site = install(tmp_path / "site", schemes={"myimu": "myimu_source:open_nothing"})
    monkeypatch.syspath_prepend(str(site))
    with pytest.raises(SourceError, match="myimu_source:open_nothing cannot be loaded"):
        open_source("myimu://")


def test_known_schemes_never_scan_the_installed_packages(monkeypatch, registry):
    def no_scan():
        raise AssertionError("entry points scanned for a known scheme")

    monkeypatch.setattr(source_mod, "_plugin_entry_points", no_scan)
    assert open_source("demo://").state is SourceState.CONNECTED
    import game  # noqa: F401 - the game's keyboard:// is registered in-tree

    assert "keyboard" in source_mod._factories


def test_a_duplicate_registration_is_an_error_not_an_overwrite(registry):
    import game  # noqa: F401

    owner = source_mod._factories["keyboard"]
    with pytest.raises(ValueError, match="'keyboard' is already registered"):
        register_scheme("KEYBOARD", lambda url, clock: None)
    assert source_mod._factories["keyboard"] is owner
    register_scheme("keyboard", owner)  # the same factory again is harmless (a re-import)


def test_quickjab_scope_runs_an_installed_plugin(tmp_path):
    site = install(tmp_path / "site")
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(REPO), str(site)]),
           "SDL_VIDEODRIVER": "dummy", "SDL_AUDIODRIVER": "dummy"}
    out = tmp_path / "scope.png"
    r = subprocess.run([sys.executable, "-m", "tools.cli", "scope", "--headless", "--frames", "20",
                        "--source", "myimu://?rate=100&sensors=2", "--screenshot", str(out)],
                       cwd=tmp_path, env=env, capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    assert out.is_file() and out.stat().st_size > 0


@pytest.mark.parametrize("scheme", ["replay", "demo", "serial", "wiimote", "wiimote-emu"])
def test_a_built_in_scheme_not_loaded_yet_is_taken_all_the_same(scheme, monkeypatch, registry):
    # the built-in schemes are registered by their modules on first use; before that an outside
    # package registering one took it over silently (and the module's own import then failed)
    monkeypatch.setitem(source_mod._factories, scheme, None)
    source_mod._factories.pop(scheme)  # as before the module is imported; restored after the test
    with pytest.raises(ValueError, match=f"'{scheme}' is built in"):
        register_scheme(scheme, lambda url, clock: None)
    assert scheme not in source_mod._factories


def test_an_installed_package_cannot_take_the_games_keyboard_scheme(tmp_path, monkeypatch, registry):
    # keyboard:// is the game's (registered when `game` is imported); without the game imported,
    # a package declaring `keyboard` in its entry points got keyboard:// URLs
    site = install(tmp_path / "site", schemes={"keyboard": "myimu_source:open_myimu"})
    monkeypatch.syspath_prepend(str(site))
    monkeypatch.delitem(source_mod._factories, "keyboard", raising=False)
    with pytest.raises(SourceError, match="keyboard:// is the game's"):
        open_source("keyboard://")
    assert "myimu_source" not in sys.modules
