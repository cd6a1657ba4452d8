"""game/training.py: a source lost or ended during `quickjab train`."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from game.training import (
    LEAD_IN,
    NO_SAMPLE_YET,
    READY_STEPS,
    RECORD,
    RECORD_STEPS,
    SHOW_STEPS,
    Trainer,
)
from tools.cli import main

REST = np.array([0.0, 0.0, 1.0, 0.0, 0.0, 1.0])


def test_a_trial_during_which_the_source_was_lost_is_recorded_again():
    """The trainer went on through GO and RECORD with no samples (the resampler holds the last
    one): a lost source's trial was kept as a flat line, then saved as the player's move."""
    tr = Trainer(["hook_r"], trials=1)
    for _ in range(SHOW_STEPS + READY_STEPS):
        tr.step(REST)
    assert tr.phase == RECORD
    for _ in range(10):
        tr.step(REST + 0.5)
    for _ in range(RECORD_STEPS):
        tr.step(REST, live=False)  # the last frame held while the source is away
    assert not tr.recorded and not tr.done and tr.waiting
    for _ in range(READY_STEPS + RECORD_STEPS):
        tr.step(REST + 0.1)  # back: "get ready" again, then the trial
    assert tr.done and len(tr.recorded["hook_r"]) == 1
    trial = tr.recorded["hook_r"][0]
    assert len(trial) == LEAD_IN + RECORD_STEPS and np.allclose(trial, REST + 0.1)


def test_training_from_a_source_that_ends_saves_nothing_over_the_players_set(tmp_path, monkeypatch, capsys):
    """A replay that ended after 2 s: every later trial was its last sample held, and the
    trained moves were saved as flat lines over the player's templates, exit 0."""
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "xdg"))
    from game.session import synthesized_templates
    from game.userdata import user_templates_path

    mine = user_templates_path()
    mine.parent.mkdir(parents=True)
    synthesized_templates(trials=1).save(mine)
    before = mine.read_bytes()
    rec = tmp_path / "short.csv"
    rec.write_text("t,rx,ry,rz,lx,ly,lz\n" + "".join(f"{i / 60:.5f},0,0,1,0,0,1\n" for i in range(120)))
    assert main(["train", "--headless", "--source", f"replay://{rec}", "--actions", "hook_r", "--size", "320x180"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert "ended" in err[-1] and "nothing saved" in err[-1], err
    assert mine.read_bytes() == before


def test_training_waits_for_a_missing_nunchuk_and_saves_nothing_without_it(tmp_path, monkeypatch, capsys):
    """A Wiimote streaming without its Nunchuk: the left hand read a still 1 g, and the trials
    were saved as the player's left-hand moves. Now the trials wait for it, as for a lost
    source (the screen says NO NUNCHUK); a headless run gives up after 10 s, nothing saved."""
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "xdg"))
    from game.userdata import user_templates_path

    rec = tmp_path / "s.csv"
    assert main(["synth", "--session", "4", "--seed", "2", "-o", str(rec)]) == 0
    url = f"wiimote-emu://{rec}?nunchuk=0"
    assert main(["train", "--headless", "--source", url, "--actions", "hook_l", "--size", "320x180"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert "no Nunchuk (waited 10 s) after 0 trials; nothing saved" in err[-1], err
    assert not user_templates_path().exists()


def test_the_training_screen_says_what_part_its_trials_wait_for():
    import pygame

    from game.actions import load_library
    from game.training import TrainingScreen

    pygame.init()
    tr = Trainer(["hook_l"], trials=1)
    tr.step(REST, live=False)
    screen = TrainingScreen(load_library(), tr, "wiimote://")
    screen.missing = "no Nunchuk: plug it in for left-hand moves"
    screen.layout = []
    screen.draw(pygame.Surface((960, 540)))
    said = [text for text, _, _ in screen.layout]
    assert "NO NUNCHUK" in said and "SOURCE LOST" not in said, said
    assert "plug it in for left-hand moves: the trial starts again when it is back" in said


def test_a_one_hand_source_trains_one_hand_moves_that_play_takes(tmp_path, monkeypatch, capsys):
    """A one-hand source never sent a second sensor, so it is not a board that lost one (waited
    for, as a missing Nunchuk is). Its trials are one sensor wide: they were recorded two wide,
    the second hand held still, and `play` with the same source refused the saved set."""
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "xdg"))
    from engine.recognition import Templates
    from game.userdata import user_templates_path

    rec = tmp_path / "one.csv"
    rec.write_text("t,rx,ry,rz\n" + "".join(f"{i / 60:.5f},0,{0.5 * (i % 90 > 60):.1f},1\n" for i in range(600)))
    play = ["play", "--headless", "--source", f"replay://{rec}", "--frames", "60", "--size", "320x180"]
    assert main(play) == 2  # the default moves read two sensors
    assert capsys.readouterr().err.strip().endswith(f"train moves for this source: quickjab train --source replay://{rec}")
    assert main(["train", "--headless", "--source", f"replay://{rec}?loop=1", "--actions", "straight_r",
                 "--size", "320x180"]) == 0, capsys.readouterr().err
    saved = Templates.load(user_templates_path())
    assert saved.dim == 3 and saved.action_names == ["straight_r"]
    assert "only the moves trained now are kept" in capsys.readouterr().err  # the defaults read two
    assert main(play) == 0, capsys.readouterr().err


def test_a_players_own_moves_for_another_sensor_count_are_kept_aside_not_lost(tmp_path, monkeypatch, capsys):
    """Training one move from a one-hand source over the player's own two-sensor set saved the
    one move alone: the thirteen moves trained with the Wiimote were gone (merge_templates keeps
    nothing of another sensor layout). The old file is kept aside, and `train` says where."""
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "xdg"))
    from engine.recognition import Templates
    from game.userdata import user_templates_path

    assert main(["train", "--headless", "--demo", "--actions", "straight_r", "--size", "320x180"]) == 0
    theirs = Templates.load(user_templates_path())
    assert theirs.dim == 6
    rec = tmp_path / "one.csv"
    rec.write_text("t,rx,ry,rz\n" + "".join(f"{i / 60:.5f},0,{0.5 * (i % 90 > 60):.1f},1\n" for i in range(600)))
    capsys.readouterr()
    assert main(["train", "--headless", "--source", f"replay://{rec}?loop=1", "--actions", "hook_r",
                 "--size", "320x180"]) == 0, capsys.readouterr().err
    assert Templates.load(user_templates_path()).dim == 3
    aside = user_templates_path().with_name(f"{user_templates_path().stem}-2-sensors{user_templates_path().suffix}")
    kept = Templates.load(aside)
    assert kept.dim == 6 and kept.action_names == theirs.action_names
    assert f"yours for 2 sensor(s) are kept in {aside} (play --templates {aside})" in capsys.readouterr().err


def test_a_second_set_kept_aside_does_not_replace_the_first(tmp_path):
    """2 -> 1 -> 2 -> 1 sensors: the second move aside renamed over the first kept set."""
    from game.training import _keep_aside

    output = tmp_path / "templates.npz"
    asides = []
    for text in ("first two-sensor set", "second two-sensor set"):
        output.write_text(text)
        asides.append(_keep_aside(output, 2))
    assert [a.name for a in asides] == ["templates-2-sensors.npz", "templates-2-sensors-2.npz"]
    assert [a.read_text() for a in asides] == ["first two-sensor set", "second two-sensor set"]
    assert not output.exists() and _keep_aside(output, 2) is None


def test_the_trials_take_the_width_of_the_first_samples_not_a_boards_guess():
    """A serial board is connected once its port opens, its sensor count a guess (2) until its
    HELLO; its samples wait for the HELLO, so the first of them says how many sensors it has."""
    import pygame

    from engine.clock import VirtualClock
    from engine.frames import FrameResampler
    from engine.loop import FixedStepLoop
    from engine.sample import Sample
    from engine.sensors.source import Source, SourceState
    from game.actions import load_library
    from game.training import TrainingScreen, _TrainingStages

    class OneImuBoard(Source):
        def __init__(self):
            super().__init__(url="serial:///dev/ttyACM0", sensors=2, state=SourceState.CONNECTED)
            self.batches = [[], [Sample(0.0, np.array([[0.0, 0.0, 1.0]]))], [Sample(0.01, np.array([[0.0, 1.0, 0.0]]))]]

        def poll(self):
            if self.batches and self.batches[0] and self.sensors == 2:
                self.sensors = 1  # the HELLO came with the samples
            return self.batches.pop(0) if self.batches else []

    pygame.init()
    board, trainer = OneImuBoard(), Trainer(["straight_r"], trials=1)
    stages = _TrainingStages(FixedStepLoop(VirtualClock()), board, False, False, trainer,
                             TrainingScreen(load_library(), trainer, board.url), FrameResampler(sensors=2), 0.0, None,
                             False, {})
    stages.input(0, 1 / 60)
    assert stages.frame is None and stages.resampler.dim == 6  # nothing sent yet: nothing decided
    stages.input(1, 1 / 60)
    stages.input(2, 1 / 60)
    assert stages.resampler.dim == 3 and stages.frame.tolist() == [0.0, 1.0, 0.0]


def test_a_boards_guessed_count_is_not_what_its_trials_wait_for():
    """A serial board's HELLO may come a poll before its first samples. Its guessed count (2),
    read before the HELLO, counted as the board having sent both sensors: at the HELLO (one IMU)
    the trials waited for "1 of 2 sensors: the other hand holds still" until the samples came."""
    import pygame

    from engine.clock import VirtualClock
    from engine.frames import FrameResampler
    from engine.loop import FixedStepLoop
    from engine.sample import Sample
    from engine.sensors.source import Source, SourceState
    from game.actions import load_library
    from game.training import TrainingScreen, _TrainingStages

    class OneImuBoard(Source):
        def __init__(self):
            super().__init__(url="serial:///dev/ttyACM0", sensors=2, sensors_known=False, state=SourceState.CONNECTED)
            self.polls = 0

        def poll(self):
            self.polls += 1
            if self.polls == 2:  # the HELLO, alone in its poll
                self.sensors, self.sensors_known = 1, True
            return [Sample(self.polls / 100, np.array([[0.0, 0.0, 1.0]]))] if self.polls >= 3 else []

    pygame.init()
    board, trainer = OneImuBoard(), Trainer(["straight_r"], trials=1)
    screen = TrainingScreen(load_library(), trainer, board.url)
    stages = _TrainingStages(FixedStepLoop(VirtualClock()), board, False, False, trainer, screen,
                             FrameResampler(sensors=2), 0.0, None, False, {})
    for step in range(4):
        stages.input(step, 1 / 60)
        stages.train(step, 1 / 60)
        # before its first samples the trials wait for them, never for a sensor it does not have
        assert screen.missing == ("" if step >= 2 else NO_SAMPLE_YET), (step, screen.missing)
    assert stages.resampler.dim == 3 and not trainer.waiting


def test_a_headless_run_gives_up_on_a_source_connected_that_sends_nothing():
    """A serial board is connected once its port opens; one that never sends a sample (no HELLO,
    or a HELLO naming no IMU) held `train --headless` in its walk for ever: the trials never
    start, and only a lost source was given up on."""
    import pygame

    from engine.clock import VirtualClock
    from engine.frames import FrameResampler
    from engine.loop import FixedStepLoop
    from engine.sensors.source import Source, SourceState
    from game.actions import load_library
    from game.training import TrainingScreen, _TrainingStages

    class SilentBoard(Source):
        def poll(self):
            return []

    pygame.init()
    board = SilentBoard(url="serial:///dev/ttyACM0", sensors_known=False, state=SourceState.CONNECTED)
    trainer = Trainer(["straight_r"], trials=1)
    stages = _TrainingStages(FixedStepLoop(VirtualClock()), board, False, False, trainer,
                             TrainingScreen(load_library(), trainer, board.url), FrameResampler(sensors=2), 0.0, None,
                             False, {})
    stages.give_up_after = 60
    for step in range(62):
        stages.input(step, 1 / 60)
        stages.train(step, 1 / 60)
    assert stages.stopped_why == "no sample yet (waited 1 s)", stages.stopped_why
    # and with a window the trials wait, the screen saying why (they went round empty, unsaid)
    assert trainer.waiting and trainer.trial == 0
    stages.screen_view.layout = []
    stages.screen_view.draw(pygame.Surface((960, 540)))
    said = [text for text, _, _ in stages.screen_view.layout]
    assert "NO SAMPLE YET" in said and "connected, but nothing comes in: the trial starts again when it is back" in said


def test_a_one_hand_source_leaves_out_the_left_hands_moves_unless_named(capsys):
    """Its one sensor is the right hand: the left hand's moves were recorded flat, saved, and then
    named by the self check as moves to throw again."""
    import pygame

    from engine.clock import VirtualClock
    from engine.frames import FrameResampler
    from engine.loop import FixedStepLoop
    from engine.sample import Sample
    from engine.sensors.source import Source, SourceState
    from game.actions import ACTION_NAMES, load_library
    from game.training import TrainingScreen, _TrainingStages

    class OneImu(Source):
        def poll(self):
            return [Sample(0.0, np.array([[0.0, 0.0, 1.0]]))]

    pygame.init()
    walks = {}
    for named in (False, True):
        trainer = Trainer(list(ACTION_NAMES), named=named)
        board = OneImu(url="myimu://", sensors=1, state=SourceState.CONNECTED)
        stages = _TrainingStages(FixedStepLoop(VirtualClock()), board, False, False, trainer,
                                 TrainingScreen(load_library(), trainer, board.url), FrameResampler(sensors=2), 0.0,
                                 None, False, {})
        stages.input(0, 1 / 60)
        walks[named] = trainer.actions
    assert walks[True] == list(ACTION_NAMES)
    assert walks[False] == [a for a in ACTION_NAMES if not a.endswith("_l")] and "block" in walks[False]
    err = capsys.readouterr().err
    assert err.count("the left hand's moves are left out (straight_l, uppercut_l, hook_l, parry_l)") == 1


def test_the_plot_names_only_the_hands_the_source_sends():
    import pygame

    from game.actions import load_library
    from game.training import TrainingScreen

    pygame.init()
    said = {}
    for frame in (REST[:3], REST):
        screen = TrainingScreen(load_library(), Trainer(["straight_r"], trials=1), "replay://one.csv")
        for _ in range(3):
            screen.push_frame(frame)
        screen.layout = []
        screen.draw(pygame.Surface((960, 540)))
        said[len(frame)] = {text for text, _, panel in screen.layout if panel == "plot"}
    assert said[3] == {"right hand x y z"}
    assert said[6] == {"right hand x y z", "left hand x y z"}


def test_a_board_that_comes_back_with_a_sensor_fewer_is_waited_for():
    from engine.clock import VirtualClock
    from engine.frames import FrameResampler
    from engine.loop import FixedStepLoop
    from engine.sensors.source import Source, SourceState
    from game.actions import load_library
    from game.training import TrainingScreen, _TrainingStages

    board = Source(url="serial:///dev/ttyACM0", sensors=2, state=SourceState.CONNECTED)
    trainer = Trainer(["hook_l"], trials=1)
    screen = TrainingScreen(load_library(), trainer, board.url)
    stages = _TrainingStages(FixedStepLoop(VirtualClock()), board, False, False, trainer, screen,
                             FrameResampler(sensors=2), 0.0, None, False, {})
    stages.sized = True  # it has sent samples of both sensors
    assert stages._source_live() and screen.missing == ""
    board.sensors = 1  # rebooted with one IMU fewer: its readings would hold still in the trials
    assert not stages._source_live() and screen.missing.startswith("1 of 2 sensors")
    board.sensors = 2
    assert stages._source_live()


def test_train_says_how_well_the_new_moves_tell_each_other_apart(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "xdg"))
    assert main(["train", "--headless", "--demo", "--actions", "straight_r,hook_r", "--size", "320x180"]) == 0
    err = capsys.readouterr().err.splitlines()
    (line,) = [x for x in err if "each new trial against the rest" in x]
    right, of = (int(w) for w in line.split(": ")[-1].split()[::2][:2])  # "N of M recognized"
    assert of == 10 and right >= 9, err  # the virtual player's moves, told apart


def test_moves_taken_for_each_other_are_named_for_training_again(capsys):
    from types import SimpleNamespace

    from engine.recognition import Templates
    from game.training import SelfCheckRun
    from tests.engine.recognition.test_self_check import trials_of

    trials = trials_of(["straight_r", "hook_r"])
    trials["hook_r"] = [t + 0.01 for t in trials["straight_r"]]  # thrown as the straights
    SelfCheckRun(SimpleNamespace(kept=trials), Templates.from_trials(trials)).finish()
    err = capsys.readouterr().err.splitlines()
    assert err[-1] == "quickjab train: throw these more differently, or train them again: quickjab train --actions hook_r,straight_r", err


def test_all_done_shows_how_many_trials_were_recognized():
    import pygame

    from game.actions import load_library
    from game.training import DONE, TrainingScreen

    pygame.init()
    tr = Trainer(["hook_l"], trials=1)
    tr.phase = DONE
    screen = TrainingScreen(load_library(), tr, "keyboard://")
    screen.saved_to, screen.self_check = "mine.npz", "9 of 10 trials recognized without their own template"
    screen.layout = []
    screen.draw(pygame.Surface((1280, 720)))
    said = [text for text, _, _ in screen.layout]
    assert "9 of 10 trials recognized without their own template; templates saved to mine.npz" in said, said


def _recorded(actions, n=5, seed=0, spoil=()):
    from game.actions import load_library
    from game.virtual_player import synthesize_action

    lib, rng = load_library(), np.random.default_rng(seed)
    out = {a: [synthesize_action(lib[a], "experienced", rng, rest_before=LEAD_IN, rest_after=30).reshape(-1, 6)
               for _ in range(n)] for a in actions}
    for a in out:
        for i in spoil:  # cut off: dropped by usable_trials
            out[a][i] = out[a][i][:LEAD_IN + 10]
    return out


def test_the_kept_trials_line_up_with_their_templates_whatever_the_base(capsys):
    """Every base `train` merges into (the defaults, a player's set of the other handedness
    mirrored, one of another sensor count), trials dropped: the new templates are the last ones,
    one per kept trial in order, so the self check holds each one out and never stops."""
    from pathlib import Path

    from engine.recognition.templates import trim_rest
    from game.training import SelfCheckRun, base_templates

    defaults = base_templates(Path("/nonexistent/templates.npz"))
    lefty = Trainer(["straight_r", "hook_l"])
    lefty.recorded = _recorded(lefty.actions, n=3, seed=1)
    one_sensor = Trainer(["hook_r"])
    one_sensor.recorded = {a: [t[:, :3] for t in ts] for a, ts in _recorded(["hook_r"], n=2, seed=2).items()}
    for base, left_handed in [(defaults, False), (defaults, True), (lefty.templates(True, base=defaults), False),
                              (one_sensor.templates(False, base=None), False)]:
        tr = Trainer(["straight_r", "hook_r"])
        tr.recorded = _recorded(tr.actions, spoil=(1, 3))
        templates = tr.templates(left_handed, base=base)
        assert tr.dropped == {"straight_r": (2, 5), "hook_r": (2, 5)}
        flat = [(a, t) for a, ts in tr.kept.items() for t in ts]
        assert templates.actions[-len(flat):] == [a for a, _ in flat]
        assert all(np.array_equal(trim_rest(t)[0], s) for (_, t), s in zip(flat, templates.signals[-len(flat):], strict=True))
        assert SelfCheckRun(tr, templates).finish() == "6 of 6 trials recognized without their own template"
    assert "no self check" not in capsys.readouterr().err


def test_the_self_check_runs_with_the_settings_play_would_use(tmp_path, monkeypatch, capsys):
    from engine.recognition import Templates, self_check
    from game.training import SelfCheckRun

    seen = []
    monkeypatch.setattr(self_check, "leave_one_out_steps", lambda t, first, trials, settings: iter(seen.append(settings) or ()))
    monkeypatch.setenv("XDG_CONFIG_HOME", str(tmp_path))
    trials = _recorded(["straight_r"], n=2)
    templates = Templates.from_trials(trials)
    templates.recognizer = {"main": 4, "noise_g": 0.5}
    (tmp_path / "quickjab").mkdir()
    (tmp_path / "quickjab" / "config.toml").write_text("[recognizer]\nnoise_g = 0.2\n")
    SelfCheckRun(SimpleNamespace(kept=trials), templates).finish()
    (tmp_path / "quickjab" / "config.toml").write_text("not toml [")
    SelfCheckRun(SimpleNamespace(kept=trials), templates).finish()
    assert seen == [{"main": 4, "noise_g": 0.2}, {"main": 4, "noise_g": 0.5}]  # the file's over the saved; a bad file: the saved


def test_a_self_check_that_cannot_run_does_not_fail_the_saved_training(capsys):
    from engine.recognition import Templates
    from game.training import SelfCheckRun

    trials = _recorded(["straight_r", "hook_r"], n=2)
    templates = Templates.from_trials(trials)
    assert SelfCheckRun(SimpleNamespace(kept={"hook_r": trials["hook_r"]}), templates.mirrored()).finish() == ""
    assert "quickjab train: no self check (template 2 is " in capsys.readouterr().err


def test_the_self_check_takes_a_trial_a_step_so_the_window_keeps_answering(capsys):
    from engine.recognition import Templates
    from game.training import SelfCheckRun

    trials = _recorded(["straight_r", "hook_r"], n=3)
    run = SelfCheckRun(SimpleNamespace(kept=trials), Templates.from_trials(trials))
    lines = []
    while not run.done:
        run.step()
        lines.append(run.line)
    assert lines[:6] == [f"checking your moves against each other: {k} of 6" for k in range(1, 7)]
    assert len(lines) == 7 and lines[-1].endswith("of 6 trials recognized without their own template")
    assert "each new trial against the rest" in capsys.readouterr().err  # said once, at the end
    assert run.finish() == lines[-1]


def test_actions_naming_no_action_is_one_line_and_exit_2(tmp_path, capsys):
    """The review: `train --actions ,` ended in an IndexError traceback from the screen, and
    `--actions ""` trained all 13 moves."""
    for value in (",", "", " , "):
        assert main(["train", "--headless", "--demo", "--actions", value, "--size", "320x180",
                     "-o", str(tmp_path / "t.npz")]) == 2, value
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and err[0].startswith(f"quickjab train: --actions {value!r}: names no action; known: straight_l"), err
    assert not (tmp_path / "t.npz").exists()


def test_the_moves_a_player_trained_keep_their_names_when_the_set_is_mirrored():
    """A set trained left-handed (straight_r, hook_l), then one move trained without
    --left-handed: the set is mirrored to the player's hands, so the moves they trained are now
    straight_l and hook_r; the file's `trained` list still said straight_r and hook_l (a move
    never trained counted as theirs: "4 of 13 moves" for 3)."""
    from pathlib import Path

    from game.training import base_templates

    defaults = base_templates(Path("/nonexistent/templates.npz"))
    lefty = Trainer(["straight_r", "hook_l"])
    lefty.recorded = _recorded(lefty.actions, n=3, seed=1)
    theirs = lefty.templates(True, base=defaults)
    assert theirs.meta["trained"] == "hook_l,straight_r"
    tr = Trainer(["straight_l"])
    tr.recorded = _recorded(tr.actions, n=3, seed=2)
    templates = tr.templates(False, base=theirs)
    assert templates.meta["trained"] == "hook_r,straight_l" and templates.meta["left_handed"] == "0"
    assert tr.templates(True, base=theirs).meta["trained"] == "hook_l,straight_l,straight_r"


def test_training_without_the_handedness_of_the_players_set_says_it_is_mirrored(tmp_path, capsys):
    """A set trained with --left-handed, `train --actions block` without it: the whole set was
    mirrored to the right hand without a word (the player had forgotten the flag)."""
    from game.session import synthesized_templates
    from game.training import _check_files

    out = tmp_path / "mine.npz"
    t = synthesized_templates(trials=1)
    t.meta.update({"source": "quickjab train", "left_handed": "1"})
    t.save(out)
    _check_files(SimpleNamespace(source=None, screenshot=None, left_handed=True), out)
    assert "mirror" not in capsys.readouterr().err
    _check_files(SimpleNamespace(source=None, screenshot=None, left_handed=False), out)
    err = capsys.readouterr().err
    assert str(out) in err and "trained left-handed" in err and "--left-handed" in err


def test_train_ended_by_sigterm_exits_130_as_ctrl_c_does(tmp_path, sigterm_when_running) -> None:
    """SDL turned SIGTERM into a quit event: `kill` ended a training as its window closed
    ("stopped after N trials", exit 0). Now it ends as Ctrl-C does: exit 130."""
    import os
    from pathlib import Path

    env = {**os.environ, "PYTHONPATH": str(Path(__file__).resolve().parents[2]), "SDL_VIDEODRIVER": "dummy",
           "SDL_AUDIODRIVER": "dummy", "XDG_DATA_HOME": str(tmp_path / "data"), "XDG_CONFIG_HOME": str(tmp_path / "config")}
    code, _, err = sigterm_when_running(["train", "--headless", "--demo", "--frames", "100000000",
                                         "-o", str(tmp_path / "t.npz")], env)  # the walk runs
    assert code == 130, err
    assert "Traceback" not in err, err
