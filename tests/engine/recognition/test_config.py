"""RecognizerConfig: the recognizer's keyword knobs as data (issue 18, settings as data)."""

from __future__ import annotations

import dataclasses
import inspect
import json

import numpy as np
import pytest

from engine.errors import InputError
from engine.recognition import DualBufferRecognizer, RecognizerConfig, Templates
from engine.recognition.config import (
    SETTINGS,
    RecognizerConfigError,
    check_settings,
    layered,
    parse_assignments,
)


def keyword_defaults() -> dict[str, object]:
    sig = inspect.signature(DualBufferRecognizer.__init__)
    return {n: p.default for n, p in sig.parameters.items() if n not in ("self", "templates")}


def test_fields_are_exactly_the_recognizer_keywords_with_their_defaults():
    # A knob added to (or a default changed in) DualBufferRecognizer must show up here.
    assert RecognizerConfig().kwargs() == keyword_defaults()
    assert list(SETTINGS) == list(keyword_defaults())


def test_config_is_frozen():
    with pytest.raises(dataclasses.FrozenInstanceError):
        RecognizerConfig().noise_g = 0.5  # type: ignore[misc]


@pytest.fixture(scope="module")
def session():
    """Templates and a 40 s labelled stream from the virtual player (both hands, D = 6)."""
    from game.actions import load_library
    from tools.synth import synth_session, synth_trials

    lib = load_library()
    rng = np.random.default_rng(7)
    templates = Templates.from_trials(synth_trials(lib, "experienced", 3, rng, rest=20))
    signal, _ = synth_session(lib, 40.0, "novice", rng)
    return templates, signal.reshape(len(signal), 6)


def events(rec: DualBufferRecognizer, frames: np.ndarray) -> list[str]:
    out = []
    for i, f in enumerate(frames):
        if i % 45 == 44:
            rec.character_finished()
        out += [json.dumps(e.to_dict(), sort_keys=True) for e in rec.push(f, t=i / 60)]
    return out


@pytest.mark.parametrize("changes", [{}, {"noise_g": 0.5, "main": "auto", "adapt": 0},
                                     {"supplementary": 40, "complete_fraction": 0.0, "extend": False, "reject": False}])
def test_from_config_gives_exactly_the_keyword_recognizer(session, changes):
    templates, frames = session
    by_keywords = events(DualBufferRecognizer(templates, **changes), frames)
    by_config = events(DualBufferRecognizer.from_config(templates, RecognizerConfig(**changes)), frames)
    assert by_keywords == by_config
    assert any('"start"' in e for e in by_keywords)  # the stream does exercise the recognizer


@pytest.mark.parametrize("bad", [{"noise_g": True}, {"main": 0}, {"supplementary": 0}, {"reject": 1},
                                 {"dtw_method": "fast"}, {"null_frames": 2.5}])
def test_the_keywords_refuse_what_the_config_refuses(session, bad):
    templates, _ = session
    with pytest.raises(RecognizerConfigError):
        RecognizerConfig(**bad)
    with pytest.raises(ValueError, match=f"recognizer setting {next(iter(bad))} must be"):
        DualBufferRecognizer(templates, **bad)
    DualBufferRecognizer(templates, main=np.int64(6), noise_g=np.float32(0.5))  # numpy numbers are numbers


@pytest.mark.parametrize("supplementary", [1, 3])
def test_a_window_shorter_than_the_back_dated_frames_never_breaks_push(session, supplementary):
    """The frames before the gate opened are replayed into the motion (up to BACKDATE_MAX); a
    window shorter than them ended the motion among them, and push raised a TypeError."""
    templates, frames = session
    out = events(DualBufferRecognizer(templates, supplementary=supplementary, main=1), frames[:1800])
    assert any('"start"' in e for e in out) and any('"reject"' in e or '"end"' in e for e in out)


def test_from_config_none_is_the_defaults(session):
    templates, frames = session
    assert events(DualBufferRecognizer.from_config(templates), frames[:900]) == events(DualBufferRecognizer(templates), frames[:900])


def test_from_config_takes_a_mapping_of_settings(session):
    # a dict (say Templates.recognizer, the settings saved with templates) was taken while empty
    # and failed with "AttributeError: 'dict' object has no attribute 'kwargs'" once not: it is
    # the same as the RecognizerConfig of those settings, and a bad one names itself
    templates, frames = session
    a = DualBufferRecognizer.from_config(templates, {"noise_g": 0.5, "main": 4})
    b = DualBufferRecognizer.from_config(templates, RecognizerConfig(noise_g=0.5, main=4))
    assert events(a, frames[:900]) == events(b, frames[:900])
    assert events(DualBufferRecognizer.from_config(templates, {}), frames[:900]) == events(DualBufferRecognizer(templates), frames[:900])
    with pytest.raises(RecognizerConfigError, match="from_config settings.*gate"):
        DualBufferRecognizer.from_config(templates, {"gate": 0.5})
    with pytest.raises(TypeError, match="mapping of settings"):
        DualBufferRecognizer.from_config(templates, [("noise_g", 0.5)])  # type: ignore[arg-type]


def test_settings_change_the_events(session):
    # the test above could pass with a config that is ignored; this one could not
    templates, frames = session
    assert events(DualBufferRecognizer.from_config(templates, RecognizerConfig(noise_g=2.0, main=12)), frames) != \
        events(DualBufferRecognizer(templates), frames)


def test_unknown_setting_is_one_line_naming_where():
    with pytest.raises(RecognizerConfigError) as err:
        check_settings({"noise": 0.5}, "config.toml")
    msg = str(err.value)
    assert isinstance(err.value, InputError) and "\n" not in msg
    assert msg.startswith("config.toml: unknown recognizer setting 'noise'") and "noise_g" in msg


@pytest.mark.parametrize("name, value, says", [
    ("main", 0, "an integer from 1 to 6000 or 'auto'"),
    ("main", "soon", "or 'auto'"),
    ("main", 6.5, "an integer"),
    ("noise_g", "loud", "a number from 0 to 100 or 'auto'"),
    ("noise_g", float("nan"), "a number"),
    ("reject", "yes", "true or false"),
    ("reject", 1, "true or false"),
    ("supplementary", True, "an integer"),
    ("dtw_method", "fast", "one of auto, scan"),
    ("complete_fraction", 1.5, "from 0 to 1"),
    ("adapt", -1, "an integer from 0"),
])
def test_wrong_type_or_range_is_refused(name, value, says):
    with pytest.raises(RecognizerConfigError) as err:
        check_settings({name: value}, "here")
    assert f"here: recognizer setting {name} must be" in str(err.value) and says in str(err.value)
    with pytest.raises(RecognizerConfigError):
        RecognizerConfig(**{name: value})


def test_numbers_are_normalized_so_equal_configs_compare_equal():
    assert RecognizerConfig(noise_g=1, min_progress=1) == RecognizerConfig(noise_g=1.0, min_progress=1.0)
    assert isinstance(RecognizerConfig(noise_g=1).noise_g, float)


def test_key_value_texts():
    got = parse_assignments(["noise_g=0.5", "main=auto", "reject=off", "adapt=0", "dtw_method=scan", "noise_g=auto"])
    assert got == {"noise_g": "auto", "main": "auto", "reject": False, "adapt": 0, "dtw_method": "scan"}
    for bad, says in [("noise_g", "expected NAME=VALUE"), ("=3", "expected NAME=VALUE"),
                      ("nois=1", "unknown recognizer setting 'nois'"), ("main=x", "main must be")]:
        with pytest.raises(RecognizerConfigError, match=says) as err:
            parse_assignments([bad])
        assert str(err.value).startswith("--recognizer")


def test_layers_later_wins_and_changed_lists_only_what_differs():
    config = layered({"noise_g": 0.4, "main": 8}, {"noise_g": 0.6}, {}, where=["saved", "file", "cli"])
    assert (config.noise_g, config.main) == (0.6, 8)
    assert config.changed() == {"noise_g": 0.6, "main": 8}
    assert RecognizerConfig().changed() == {}
    with pytest.raises(RecognizerConfigError, match="^file: unknown"):
        layered({}, {"x": 1}, where=["saved", "file"])


# -- saved beside the templates: the optional `recognizer` key of the templates npz ------------


def small_templates() -> Templates:
    rng = np.random.default_rng(0)
    g = np.array([0.0, 0.0, 1.0])

    def trial(axis):
        x = np.tile(g, (40, 1))
        x[6:30, axis] += 3.0 * np.sin(np.linspace(0, 2 * np.pi, 24)) + rng.normal(0, 0.02, 24)
        return x

    return Templates.from_trials({"jab": [trial(0) for _ in range(3)], "upper": [trial(2) for _ in range(3)]})


def test_settings_round_trip_through_the_npz(tmp_path):
    t = small_templates()
    t.recognizer = {"noise_g": 0.45, "main": "auto", "reject": False}
    t.save(tmp_path / "t.npz")
    u = Templates.load(tmp_path / "t.npz")
    assert u.recognizer == {"noise_g": 0.45, "main": "auto", "reject": False}
    assert u.mirrored().recognizer == u.recognizer  # a left-handed player keeps the tuned gate
    assert layered(u.recognizer).noise_g == 0.45


def test_no_settings_saved_is_the_defaults(tmp_path):
    t = small_templates()
    t.save(tmp_path / "t.npz")
    assert Templates.load(tmp_path / "t.npz").recognizer == {}
    assert "recognizer" not in np.load(tmp_path / "t.npz").files  # the keys a file always had


def test_an_older_file_without_the_key_loads(tmp_path):
    t = small_templates()
    t.recognizer = {"adapt": 0}
    t.save(tmp_path / "t.npz")
    data = dict(np.load(tmp_path / "t.npz"))
    del data["recognizer"]
    with open(tmp_path / "old.npz", "wb") as f:
        np.savez_compressed(f, **data)
    assert Templates.load(tmp_path / "old.npz").recognizer == {}


@pytest.mark.parametrize("saved, says", [
    ('{"gate": 0.5}', "unknown recognizer setting 'gate'"),
    ('{"noise_g": "loud"}', "recognizer setting noise_g must be"),
    ('[1, 2]', "must be a table"),
    ('{not json', "not JSON"),
])
def test_bad_saved_settings_are_an_error_naming_the_file(tmp_path, saved, says):
    t = small_templates()
    t.recognizer = {"adapt": 0}
    t.save(tmp_path / "t.npz")
    data = dict(np.load(tmp_path / "t.npz"))
    data["recognizer"] = np.array(saved)
    with open(tmp_path / "bad.npz", "wb") as f:
        np.savez_compressed(f, **data)
    with pytest.raises(InputError) as err:
        Templates.load(tmp_path / "bad.npz")
    assert str(err.value).startswith(f"{tmp_path / 'bad.npz'}: ") and says in str(err.value)


def test_main_auto_on_two_hands_raises_no_warning(session):
    """main="auto" measures the best action's lead over the second; the second can be at inf
    (left out by the moving hand's rule, or no template of it fitting yet), and inf / inf printed
    a RuntimeWarning on stderr (`recognize --recognizer main=auto`)."""
    import warnings

    from game.actions import load_library
    from tools.synth import synth_session, synth_trials

    lib, rng = load_library(), np.random.default_rng(1)
    three = synth_trials(lib, "experienced", 3, rng, ["hook_l", "straight_r", "uppercut_r"])  # no rest
    signal, _ = synth_session(lib, 10.0, "experienced", rng)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        out = events(DualBufferRecognizer(Templates.from_trials(three), main="auto"), signal.reshape(len(signal), 6))
    assert any('"start"' in e for e in out)
