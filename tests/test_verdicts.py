"""Pinned verdicts: the bundled demo's scripted grasps and a grasp episode of every real GraspDB14 recording.

The outcomes are the measured tables of ``docs/replay.md`` (``scripts/recordings_table.py``) and
``docs/stability.md`` (``scripts/scripted_sweep.py``): held / not held / not judged and ``hold_robustness``
exactly as measured on the project's machine, so that a change of physics, placement or judging that moves
any verdict fails here and the docs get updated with it.
"""

from __future__ import annotations

import json

import pytest

from handsim.assets import ASSETS_DIR
from handsim.sim.replay import replay
from handsim.sim.specs import MetricSpec
from handsim.trials import load_trial

DEMO_DIR = ASSETS_DIR / "demo"
NOT_JUDGED_SHORT = "not judged: the hold window after release lasts {length} s, less than the 0.3 s"


def _verdict(path, **options) -> dict:
    loaded = load_trial(path, **options)
    result = replay(loaded.scene, loaded.trajectory)
    return result.summary


NO_GRIP = "not judged: no grip: the thumb and a finger, or fingers and the palm, press on the object"

# (grasp, held, hold_robustness, grip directions held): each demo grasp's one episode, docs/stability.md
DEMO = [
    ("tennis_ball.grasp.json", True, 16 / 17, 6),
    ("cube.grasp.json", None, None, 2),  # resting on the fingertips, the thumb at its side: no grip
    ("cylinder_25mm.grasp.json", True, 19 / 21, 6),
]


@pytest.mark.slow
@pytest.mark.parametrize(("grasp", "held", "robustness", "directions"), DEMO)
def test_each_demo_scripted_grasp_gets_its_documented_verdict(grasp, held, robustness, directions):
    summary = _verdict(DEMO_DIR / grasp, grasp=1)
    assert summary["warnings"] == 0 and summary["valid"]
    assert summary["held"] is held and summary["hold_robustness"] == robustness
    assert summary["grip_directions_held"] == directions
    if held is None:
        assert summary["hold_reason"].startswith(NO_GRIP)


# (recording, episode, hand, held, hold_robustness, grip directions held): docs/replay.md, "every grasp
# episode"; each recording's first complete episode (the fk_oracle 01_11 excerpt has 13)
RECORDINGS = [
    ("r_01_11_ex03-rad-004-grasp-su04.txt", 1, "default", None, None, 6),  # the fingertips alone: no grip
    ("r_01_11_ex03-rad-004-grasp-su04.txt", 1, "xmlskel", True, 1.0, 6),
    ("01_ex01-rad-002-grasp-su01.txt", 1, "default", True, 10 / 11, 3),
    ("01_ex01-rad-002-grasp-su01.txt", 1, "xmlskel", True, 2 / 3, 6),
    ("04_ex01-rad-045-grasp-su03.txt", 1, "default", None, None, 2),  # no thumb–finger closure: no grip
    ("04_ex01-rad-045-grasp-su03.txt", 1, "xmlskel", False, 0.0, 1),
    ("fk_oracle/01_11_ex03-rad-004-grasp-su04.txt", 1, "default", False, 0.0, 0),
    ("fk_oracle/01_11_ex03-rad-004-grasp-su04.txt", 1, "xmlskel", False, 0.0, 0),
    ("fk_oracle/16_14_ex01-rad-004-grasp-su06", 1, "default", False, 0.0, 0),
    ("fk_oracle/16_14_ex01-rad-004-grasp-su06", 1, "xmlskel", False, 0.0, 0),
]


@pytest.mark.slow
@pytest.mark.parametrize(("recording", "episode", "hand", "held", "robustness", "directions"), RECORDINGS)
def test_each_real_recording_gets_its_documented_verdict(
    graspdb_dir, recording, episode, hand, held, robustness, directions
):
    skeleton = str(graspdb_dir / "default.xmlskel") if hand == "xmlskel" else None
    summary = _verdict(graspdb_dir / recording, skeleton=skeleton, grasp=episode)
    assert summary["warnings"] == 0 and not summary["diverged"]
    assert summary["held"] is held
    assert summary["hold_robustness"] == robustness
    assert summary["grip_directions_held"] == directions
    if held is None:
        assert summary["hold_reason"].startswith(NO_GRIP)
    if held is False:
        assert summary["hold_reason"].startswith("slipped ")


def test_a_grasp_released_less_than_the_minimum_window_before_its_end_is_not_judged_end_to_end(tmp_path):
    fields = json.loads((DEMO_DIR / "tennis_ball.grasp.json").read_text(encoding="utf-8"))
    fields["hold_s"] = 0.2  # the release (closed + 0.1 s) leaves less than 0.3 s of the grasp phase
    path = tmp_path / "short.grasp.json"
    path.write_text(json.dumps(fields), encoding="utf-8")
    loaded = load_trial(path)
    result = replay(loaded.scene, loaded.trajectory)
    assert result.hold.held is None and result.summary["held"] is None
    window = result.hold.window[1] - result.hold.released_at
    assert 0.0 < window < MetricSpec().min_hold_window
    assert result.summary["hold_reason"].startswith(NOT_JUDGED_SHORT.format(length=f"{window:.3f}"))
    assert result.summary["time_held_s"] == 0.0
    assert result.robustness is None and result.summary["hold_robustness"] is None
