"""Where the player's files live: the XDG base directories. The XDG spec: a relative path in
XDG_CONFIG_HOME, XDG_DATA_HOME or XDG_CACHE_HOME is invalid and ignored; an empty or relative
HOME is not where a player's templates go either (an empty HOME put them under /)."""

from __future__ import annotations

import os

import pytest

from engine import native
from game.user_config import config_path
from game.userdata import data_dir


@pytest.fixture
def home(tmp_path, monkeypatch):
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    monkeypatch.delenv(native.CACHE_ENV, raising=False)
    monkeypatch.chdir(tmp_path)
    return tmp_path / "home"


@pytest.mark.parametrize("value", ["", "relative/dir", "./x", "~/x"])
def test_a_relative_or_empty_xdg_variable_is_ignored(home, monkeypatch, value):
    for name in ("XDG_CONFIG_HOME", "XDG_DATA_HOME", "XDG_CACHE_HOME"):
        monkeypatch.setenv(name, value)
    assert config_path() == home / ".config" / "quickjab" / "config.toml"
    assert data_dir() == home / ".local" / "share" / "quickjab"
    assert native.cache_dir() == home / ".cache" / "quickjab"


def test_an_absolute_xdg_variable_is_used(home, tmp_path, monkeypatch):
    for name in ("XDG_CONFIG_HOME", "XDG_DATA_HOME", "XDG_CACHE_HOME"):
        monkeypatch.setenv(name, str(tmp_path / name))
    assert config_path() == tmp_path / "XDG_CONFIG_HOME" / "quickjab" / "config.toml"
    assert data_dir() == tmp_path / "XDG_DATA_HOME" / "quickjab"
    assert native.cache_dir() == tmp_path / "XDG_CACHE_HOME" / "quickjab"


@pytest.mark.parametrize("value", ["", "relative"])
def test_an_empty_or_relative_home_is_not_used(monkeypatch, tmp_path, value):
    import pwd

    monkeypatch.setenv("HOME", value)
    monkeypatch.delenv("XDG_DATA_HOME", raising=False)
    monkeypatch.chdir(tmp_path)
    assert data_dir() == type(data_dir())(pwd.getpwuid(os.getuid()).pw_dir) / ".local" / "share" / "quickjab"
    assert data_dir().is_absolute()


def test_a_data_dir_too_long_to_look_at_is_passed_over_by_play_and_named_by_train(tmp_path, monkeypatch, capsys):
    """A name too long for the file system: Path.exists() raised ENAMETOOLONG, and `play` ended
    with the errno (not naming the variable) where a data dir under a file is passed over: it
    has no trained templates, and plays the default ones. `train`, which must save there, says
    so in one line naming the variable."""
    from tools.cli import main

    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / ("x" * 300)))
    for profile in ([], ["--profile", "bob"]):
        assert main(["play", "--headless", "--frames", "2", "--source", "keyboard://", "--no-sound", *profile]) == 0
        assert "default templates" in capsys.readouterr().err
    assert main(["train", "--demo", "--headless", "--actions", "straight_r"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "cannot save the templates there" in err[0] and "$XDG_DATA_HOME" in err[0], err
