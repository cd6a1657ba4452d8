"""Source URLs and schemes, the replay source under a virtual clock, the demo source, and the
measured sample rate."""

from __future__ import annotations

import numpy as np
import pytest

import engine.sensors.source as source_mod
from engine.clock import VirtualClock
from engine.errors import InputError
from engine.recording import Recording, RecordingError, write_recording
from engine.sensors import (
    Sample,
    Source,
    SourceError,
    SourceState,
    open_source,
    parse_source_url,
    register_scheme,
)
from engine.sensors.rate import RateMeter


def test_parse_source_url():
    assert parse_source_url("serial:///dev/ttyACM0") == ("serial", "/dev/ttyACM0", {})
    assert parse_source_url("replay://rec.csv?speed=2&loop=1") == ("replay", "rec.csv", {"speed": "2", "loop": "1"})
    assert parse_source_url("REPLAY://a/b.csv")[0] == "replay"


@pytest.mark.parametrize("name", ["take[1].csv", "x]y.csv", "a\uff0fb.csv", "\u2100x.csv"])
def test_a_file_name_urllib_takes_for_a_host_is_still_a_path(tmp_path, monkeypatch, name):
    """A relative path is the URL's host part to urlsplit: brackets read as an IPv6 address and
    characters NFKC turns into '/' or ':' made it raise ValueError (a traceback). Such a name is
    a file name like any other."""
    path, _ = write_rec(tmp_path)
    (tmp_path / name).write_bytes(path.read_bytes())
    monkeypatch.chdir(tmp_path)
    assert parse_source_url(f"replay://{name}?speed=2") == ("replay", name, {"speed": "2"})
    src = open_source(f"replay://{name}")
    assert src.sensors == 2
    src.close()
    with pytest.raises(RecordingError, match="cannot read"):
        open_source(f"replay://missing{name}")


@pytest.mark.parametrize("url", ["nosuch://x", "rec.csv", "", "replay:/x.csv"])
def test_open_source_rejects_unknown_schemes_and_non_urls(url):
    with pytest.raises(SourceError) as err:
        open_source(url)
    assert isinstance(err.value, InputError)
    assert repr(url) in str(err.value) or url.split(":")[0] in str(err.value)


def test_unknown_scheme_lists_the_known_ones():
    with pytest.raises(SourceError, match="replay"):
        open_source("nosuch://x")


def test_builtin_scheme_whose_module_is_missing_is_a_source_error(monkeypatch):
    monkeypatch.setitem(source_mod._builtin_modules, "ghost", "engine.sensors.ghost_that_is_not_there")
    with pytest.raises(SourceError, match="ghost://"):
        open_source("ghost://x")


def test_outside_packages_register_their_own_schemes(monkeypatch):
    class Const(Source):
        def poll(self) -> list[Sample]:
            return [Sample(self.clock(), np.ones((1, 3)))]

    monkeypatch.setitem(source_mod._factories, "const", None)  # restored after the test
    register_scheme("CONST", lambda url, clock: Const(url=url, sensors=1, clock=clock, state=SourceState.CONNECTED))
    src = open_source("const://", clock=lambda: 7.0)
    assert src.poll()[0].t == 7.0 and "const" in source_mod.registered_schemes()


def write_rec(tmp_path, n=10, rate=100.0, sensors=2):
    t = np.arange(n) / rate
    accel = np.arange(n * sensors * 3, dtype=float).reshape(n, sensors, 3) / 100
    path = tmp_path / "rec.csv"
    write_recording(path, Recording(t, accel, [("jab" if i >= 5 else "") for i in range(n)]))
    return path, accel


def test_replay_under_a_virtual_clock_delivers_samples_when_due(tmp_path):
    path, accel = write_rec(tmp_path)
    clock = VirtualClock(start_ns=5_000_000_000)
    src = open_source(f"replay://{path}", clock=clock.seconds)
    assert src.state is SourceState.CONNECTED and src.sensors == 2
    assert src.rate_hz == pytest.approx(100.0)
    first = src.poll()
    assert [s.t for s in first] == [5.0]  # sample 0 is due at once
    clock.advance(25_000_000)
    got = src.poll()
    assert [round(s.t - 5.0, 6) for s in got] == [0.01, 0.02]
    np.testing.assert_array_equal(got[1].accel, accel[2])
    assert src.poll() == []  # nothing new: never waits, never repeats
    clock.advance(1_000_000_000)
    last = src.poll()
    assert len(last) == 7 and all(isinstance(s.t, float) for s in last)
    assert src.state is SourceState.ENDED  # everything delivered: a state, not an exception
    assert src.poll() == []
    assert src.label_at(5.06) == "jab" and src.label_at(5.02) == ""


def test_a_replay_that_ended_rewinds_to_its_start(tmp_path, monkeypatch):
    """rewind() (the REWIND capability: the game's Enter under SOURCE ENDED) plays the recording
    again from its first sample, stamped from now, without reading the file again."""
    import engine.sensors.replay as replay
    from engine.sensors.source import REWIND

    path, accel = write_rec(tmp_path)
    clock = VirtualClock(start_ns=5_000_000_000)
    src = open_source(f"replay://{path}", clock=clock.seconds)
    assert REWIND in src.capabilities
    clock.advance(1_000_000_000)
    first = src.poll()
    assert src.state is SourceState.ENDED
    monkeypatch.setattr(replay, "read_recording", lambda *a: pytest.fail("the file read again"))
    clock.advance(500_000_000)
    src.rewind()
    assert src.state is SourceState.CONNECTED
    clock.advance(1_000_000_000)
    again = src.poll()
    assert [round(s.t - 6.5, 6) for s in again] == [round(s.t - 5.0, 6) for s in first]
    np.testing.assert_array_equal(np.array([s.accel for s in again]), accel)
    assert src.state is SourceState.ENDED


def test_replay_speed_and_loop(tmp_path):
    path, _ = write_rec(tmp_path)
    clock = VirtualClock()
    fast = open_source(f"replay://{path}?speed=2", clock=clock.seconds)
    looped = open_source(f"replay://{path}?loop=1", clock=clock.seconds)
    clock.advance(45_000_000)
    assert len(fast.poll()) == 10  # 90 ms of recording in 45 ms
    clock.advance(200_000_000)
    times = [s.t for s in looped.poll()]
    assert len(times) == 25 and np.all(np.diff(times) > 0)  # 2.5 loops, time keeps increasing
    assert looped.state is SourceState.CONNECTED


def test_a_loop_of_a_recording_faster_than_any_sensor_is_refused(tmp_path):
    """Two samples a nanosecond apart, looped: every poll owed a billion samples a second of
    replay (`record --seconds 0.3` ran past a minute and 6 GB). Once through, it is two samples."""
    path = tmp_path / "tiny.csv"
    path.write_text("t,rx,ry,rz\n0,0,0,1\n0.000000001,0,0,1\n")
    with pytest.raises(SourceError, match=r"tiny.csv\?loop=1: looped .* over the 1e\+06 a second"):
        open_source(f"replay://{path}?loop=1", clock=VirtualClock().seconds)
    clock = VirtualClock()
    once = open_source(f"replay://{path}", clock=clock.seconds)
    clock.advance(1_000_000)
    assert len(once.poll()) == 2
    rec, _ = write_rec(tmp_path)  # 100 Hz, as fast as a replay goes: still looped
    assert open_source(f"replay://{rec}?loop=1&speed=1000", clock=clock.seconds).rate_hz == pytest.approx(100)


@pytest.mark.parametrize("url,match", [("replay://{p}?speed=0", "speed"), ("replay://{p}?speed=x", "speed"), ("replay://", "no file"),
                                       # a typo played at the default with no word said
                                       ("replay://{p}?sped=4", r"unknown parameter\(s\) sped \(known: speed, loop\)"),
                                       ("replay://{p}?axes=-y,x,z", "unknown parameter"),
                                       ("demo://?rat=50", r"demo://\?rat=50: unknown parameter\(s\) rat \(known: rate\)")])
def test_replay_bad_arguments(tmp_path, url, match):
    path, _ = write_rec(tmp_path)
    with pytest.raises(SourceError, match=match):
        open_source(url.format(p=path))


def test_replay_of_a_bad_file_names_it(tmp_path):
    bad = tmp_path / "bad.csv"
    bad.write_text("t,rx,ry,rz\n0,1,2,3\n0.1,x,2,3\n")
    with pytest.raises(RecordingError, match="bad.csv:3"):
        open_source(f"replay://{bad}")


def test_demo_source_is_deterministic_and_two_handed():
    runs = []
    for _ in range(2):
        clock = VirtualClock()
        src = open_source("demo://?rate=200", clock=clock.seconds)
        got = []
        for _ in range(90):
            clock.advance(16_666_667)
            got += src.poll()
        runs.append(got)
    a, b = runs
    assert len(a) == len(b) == 301  # samples 0..300 at 200 Hz in 1.5 s
    assert all(x.t == y.t and np.array_equal(x.accel, y.accel) for x, y in zip(a, b, strict=True))
    acc = np.array([s.accel for s in a])
    assert acc.shape == (301, 2, 3)
    assert np.abs(acc[:, :, 2].mean() - 1.0) < 0.2  # gravity on z at rest
    assert acc[:, 0, 0].max() > 1.5 and acc[:, 1, 0].max() > 1.5  # both hands punch
    with pytest.raises(SourceError):
        open_source("demo://?rate=-1")


def test_rate_meter_measures_samples_per_second():
    m = RateMeter(window_s=1.0)
    assert m.rate_hz() == 0.0
    m.add([Sample(i / 430, None) for i in range(1000)])
    assert m.rate_hz() == pytest.approx(430, rel=0.01)
    assert m.rate_hz(now=1000 / 430 + 5) == 0.0  # gone quiet
    jitter = np.cumsum(np.random.default_rng(0).uniform(0.02, 0.06, 200))  # ~25 Hz gloves
    m2 = RateMeter()
    m2.add([Sample(float(t), None) for t in jitter])
    assert m2.rate_hz() == pytest.approx(25, rel=0.2)


def test_replay_announces_the_rate_its_file_states_when_its_times_agree(tmp_path):
    # a 60 Hz file's times written to 6 decimals: 1 / the median interval was 59.9988 Hz, and
    # `record --source replay://` wrote that as the recording's rate
    t = np.arange(120) / 60.0
    accel = np.tile([0.0, 0.0, 1.0], (120, 1, 1))
    path = tmp_path / "sixty.csv"
    write_recording(path, Recording(t, accel, [""] * 120, {"rate_hz": "60"}))
    assert open_source(f"replay://{path}", clock=VirtualClock().seconds).rate_hz == 60.0
    lying = tmp_path / "lying.csv"
    write_recording(lying, Recording(t, accel, [""] * 120, {"rate_hz": "100"}))  # its times say 60
    assert open_source(f"replay://{lying}", clock=VirtualClock().seconds).rate_hz == pytest.approx(60.0, rel=1e-3)


def test_a_replay_path_names_a_file_with_hash_or_question_mark_percent_escaped(tmp_path):
    """The tester: `replay:///path/a#b?c=1.csv` cannot name its file (the URL takes '#' and '?').
    %23, %3F and %25 stand for '#', '?' and '%'; any other '%' is the file name's own."""
    from engine.sensors.source import url_file

    path, _ = write_rec(tmp_path)
    for name in ("a#b?c=1.csv", "50%.csv", "a%41.csv", "x%y.csv"):
        (tmp_path / name).write_bytes(path.read_bytes())
    for url, name in ((f"replay://{tmp_path}/a%23b%3fc=1.csv?speed=2", "a#b?c=1.csv"),
                      (f"replay://{tmp_path}/50%25.csv", "50%.csv"), (f"replay://{tmp_path}/50%.csv", "50%.csv"),
                      (f"replay://{tmp_path}/a%41.csv", "a%41.csv"), (f"replay://{tmp_path}/x%y.csv", "x%y.csv")):
        assert url_file(url) == str(tmp_path / name), url
        src = open_source(url)
        assert src.sensors == 2
        src.close()
    assert url_file("serial:///dev/a%23b") == "/dev/a%23b"  # only the paths of recording files are decoded
    emu = f"wiimote-emu://{tmp_path}/a%23b%3fc=1.csv?seconds=1"  # a recording file too: decoded alike
    assert url_file(emu) == str(tmp_path / "a#b?c=1.csv")
    open_source(emu).close()
