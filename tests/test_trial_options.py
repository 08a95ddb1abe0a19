"""One list of trial options: the fields of TrialOptions carry their labels and flags, and all reads them.

The kinds name its fields, ``find_trial`` takes them as keywords, the CLI builds its flags from their metadata
and reads them back, and a loaded glove trial replays only with the thresholds it was loaded with.
"""

from __future__ import annotations

import argparse
import dataclasses
import inspect
import re

import numpy as np
import pytest

from handsim.assets import ASSETS_DIR
from handsim.cli import build_parser
from handsim.cli._common import Parser, add_trial_options, trial_options_from_args
from handsim.cli.replay import replay_options
from handsim.datatypes.trajectory import Trajectory
from handsim.sim.replay import ReplayConfig
from handsim.sim.specs import MetricSpec
from handsim.trials import (
    KINDS,
    LoadedTrial,
    Trial,
    TrialError,
    TrialOptions,
    find_trial,
    load_trial,
    replay_trial,
)
from handsim.trials import episodes as episodes_module
from handsim.trials.options import SPEC, OptionSpec, given_options, option_names, option_spec
from handsim.trials.registry import check_metrics

GRASP = ASSETS_DIR / "demo" / "tennis_ball.grasp.json"


def _subparser(parser: argparse.ArgumentParser, *path: str) -> argparse.ArgumentParser:
    for name in path:
        [commands] = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
        parser = commands.choices[name]
    return parser


def test_every_trial_option_field_carries_its_label_flag_and_help():
    for f in dataclasses.fields(TrialOptions):
        spec = f.metadata[SPEC]
        assert isinstance(spec, OptionSpec), f.name
        assert spec.label and spec.help, f.name
        assert spec.flag.startswith("--"), f.name


def test_the_flags_of_the_trial_options_are_distinct():
    flags = [option_spec(n).flag for n in option_names()]
    assert len(set(flags)) == len(flags)


def test_every_kind_takes_only_trial_options_chosen_per_kind():
    per_kind = {n for n in option_names() if option_spec(n).per_kind}
    for kind in KINDS:
        assert kind.options <= per_kind, kind.name


def test_find_trial_takes_the_trial_options_as_keywords_in_their_order():
    parameters = inspect.signature(find_trial).parameters
    assert tuple(parameters) == ("path", *option_names())
    assert all(parameters[n].kind is inspect.Parameter.KEYWORD_ONLY for n in option_names())


def test_find_trial_raises_error_for_a_keyword_that_is_no_trial_option():
    with pytest.raises(TypeError, match=re.escape("find_trial() got unknown option(s) ['sequence']")):
        find_trial(GRASP, sequence=1)


def test_an_unknown_option_name_is_refused_listing_the_options():
    with pytest.raises(KeyError, match="no trial option 'sequence'; expected one of"):
        option_spec("sequence")


def test_given_options_are_those_not_left_at_their_default():
    assert given_options(TrialOptions()) == ()
    assert given_options(TrialOptions(obj="mug", force=True, hand_length=0.0)) == (
        "obj",
        "hand_length",
        "force",
    )


def test_handsim_replay_has_exactly_the_flags_the_trial_options_declare():
    replay = _subparser(build_parser(), "replay")
    flags = {a.dest: a.option_strings for a in replay._actions if a.dest in option_names()}
    assert sorted(flags) == sorted(option_names())
    assert sorted(replay_options()) == sorted(option_names())
    for name, strings in flags.items():
        assert strings == [option_spec(name).flag], name
    helps = {a.dest: a.help for a in replay._actions}
    assert helps["grasp"] == option_spec("grasp").help
    assert helps["mass"] == f"{option_spec('mass').help} without --force"


def test_handsim_report_takes_the_arctic_trial_options():
    report = _subparser(build_parser(), "report")
    assert {a.dest for a in report._actions} & set(option_names()) == {"mano_dir", "templates"}


def test_the_command_line_gives_back_the_trial_options_it_parsed():
    args = build_parser().parse_args(
        [
            "replay",
            "rec.txt",
            "--object",
            "mug",
            "--mass",
            "0.2",
            "--force",
            "--thumb-rest",
            "20,10",
            "--grasp",
            "2",
        ]
    )
    assert trial_options_from_args(args) == TrialOptions(
        obj="mug", mass=0.2, force=True, thumb_rest=(20.0, 10.0), grasp=2
    )


def test_a_command_with_no_trial_options_gives_none():
    parser = Parser(prog="handsim x")
    assert trial_options_from_args(parser.parse_args([])) == TrialOptions()


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--thumb-rest", "20"], "argument --thumb-rest: expected ABD,FLEX: two angles in degrees, got '20'"),
        (["--grasp", "0"], "argument --grasp: expected a grasp episode number ≥ 1, got 0"),
        (["--hand-length", "-1"], "argument --hand-length: expected a finite number > 0, got -1"),
        (["--units", "cm"], "argument --units: invalid choice: 'cm'"),
    ],
)
def test_a_bad_trial_option_value_is_a_usage_error_with_its_parsers_message(capsys, argv, message):
    parser = Parser(prog="handsim x")
    add_trial_options(parser)
    with pytest.raises(SystemExit) as exc:
        parser.parse_args(argv)
    assert exc.value.code == 2
    assert message in capsys.readouterr().err


def _loaded(metrics: MetricSpec | None) -> LoadedTrial:
    trial = Trial(kind="scripted", trajectory_path="a.grasp.json", skeleton_path=None, objects=())
    return LoadedTrial(trial=trial, scene=None, trajectory=None, hand="", objects=(), metrics=metrics)


def test_check_metrics_raises_error_naming_the_thresholds_that_differ():
    with pytest.raises(
        TrialError,
        match=re.escape(
            "a.grasp.json: its scene was built with other metrics than it is replayed with (release_delay: "
            "0.2 loaded, 0.1 replayed); load it with metrics=config.metrics"
        ),
    ):
        check_metrics(_loaded(MetricSpec(release_delay=0.2)), MetricSpec())


def test_check_metrics_accepts_the_same_thresholds_or_a_scene_that_does_not_depend_on_them():
    check_metrics(_loaded(MetricSpec()), MetricSpec())
    check_metrics(_loaded(None), MetricSpec(release_delay=0.2))


def test_a_glove_trial_keeps_its_thresholds_and_refuses_a_replay_with_others():
    loaded = load_trial(GRASP, metrics=MetricSpec(release_delay=0.2))
    assert loaded.metrics == MetricSpec(release_delay=0.2)
    with pytest.raises(TrialError, match=re.escape("release_delay: 0.2 loaded, 0.1 replayed")):
        replay_trial(loaded, ReplayConfig())


def _glove(shift: float = 0.0) -> Trajectory:
    times = np.arange(10) / 10.0
    targets = np.full((10, 1), shift)
    return Trajectory(times, ("if_mcp_flex",), targets, np.ones((10, 1), dtype=bool), source="x.txt")


def test_a_recording_is_segmented_once_however_many_episodes_are_loaded(monkeypatch):
    calls = []
    monkeypatch.setattr(episodes_module, "segment_grasps", lambda t: calls.append(t) or object())
    monkeypatch.setattr(episodes_module, "_SEGMENTATIONS", {})
    first = episodes_module.recording_segmentation(_glove())
    assert episodes_module.recording_segmentation(_glove()) is first
    assert len(calls) == 1
    episodes_module.recording_segmentation(_glove(0.5))  # other content: segmented anew
    assert len(calls) == 2
