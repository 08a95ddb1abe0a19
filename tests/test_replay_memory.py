"""A replay's memory estimate, and the refusal of a recording whose replay would not fit the limit."""

from __future__ import annotations

import pytest

from handsim.assets import TZIONAS_DIR
from handsim.cli import main
from handsim.sim.memory import (
    LIMIT_VARIABLE,
    PEAK_FACTOR,
    RecordingTooLongError,
    check_replay_memory,
    replay_memory_bytes,
)
from handsim.trials import load_trial

SEQ20 = TZIONAS_DIR / "Models" / "20" / "Model_Hand_R.MOTION"


@pytest.fixture(scope="module")
def seq20():
    return load_trial(SEQ20)


def test_the_estimate_is_the_per_frame_buffers_times_the_measured_peak_factor(seq20):
    model = seq20.scene.model
    assert replay_memory_bytes(model, 1000) == pytest.approx(1000 * (model.nq + model.nsensordata) * 8 * 1.5)
    assert PEAK_FACTOR >= 1.35  # the largest peak measured over the buffers (Tzionas sequence 20)


def test_a_replay_over_the_limit_is_refused_before_it_runs_naming_the_file_estimate_and_limit(
    seq20, monkeypatch
):
    monkeypatch.setenv(LIMIT_VARIABLE, "0.001")
    with pytest.raises(RecordingTooLongError) as caught:
        check_replay_memory(seq20.scene.model, 617, 100.0, str(SEQ20))
    message = str(caught.value)
    assert message.startswith(
        f"{SEQ20}: replaying 617 control frames (6 s at 100 Hz) would need about 5.3 MB"
    )
    assert "over the limit of 1.0 MB ($HANDSIM_MAX_REPLAY_GB)" in message
    assert "--grasp K" in message and "--rate" in message


def test_within_the_limit_nothing_is_said(seq20, monkeypatch):
    monkeypatch.setenv(LIMIT_VARIABLE, "0.01")
    check_replay_memory(seq20.scene.model, 617, 100.0, str(SEQ20))
    monkeypatch.delenv(LIMIT_VARIABLE)
    check_replay_memory(seq20.scene.model, 617, 100.0, str(SEQ20))  # half the machine's memory


def test_handsim_replay_exits_1_with_the_refusal(monkeypatch, capsys):
    monkeypatch.setenv(LIMIT_VARIABLE, "0.001")
    assert main(["replay", str(SEQ20)]) == 1
    err = capsys.readouterr().err.splitlines()
    assert err[0].startswith(f"handsim: error: {SEQ20}: replaying 617 control frames")


@pytest.mark.parametrize("value", ["abc", "-1", "0", "nan"])
def test_a_bad_limit_is_named(seq20, monkeypatch, value):
    monkeypatch.setenv(LIMIT_VARIABLE, value)
    with pytest.raises(
        Exception, match=rf"\$HANDSIM_MAX_REPLAY_GB='{value}': expected a positive number of GB"
    ):
        check_replay_memory(seq20.scene.model, 617, 100.0)
