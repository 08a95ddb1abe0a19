"""The glove placement search never throws a feasible pose away: no "no pose" while one was seen.

The cases the issue named, where the old search raised although thousands of coarse poses were feasible (a
thin long pen and a bottle crate in the default hand on ``r_01_11…`` without its annotation beside it), and
the fallback when no feasible pose touches the hand at all.
"""

from __future__ import annotations

import shutil

import pytest

from handsim.sim.specs import MetricSpec, PlacementSpec
from handsim.trials import load_trial

TRIAL = "r_01_11_ex03-rad-004-grasp-su04.txt"


@pytest.mark.slow
@pytest.mark.parametrize(("obj", "skeleton"), [("pen", False), ("pen", True), ("bottle_crate", False)])
def test_a_recording_without_its_annotation_places_a_hard_object_without_raising(
    graspdb_dir, tmp_path, obj, skeleton
):
    shutil.copy(graspdb_dir / TRIAL, tmp_path / TRIAL)  # no _annot- file beside it: the peak-flexion window
    loaded = load_trial(
        tmp_path / TRIAL, obj=obj, skeleton=str(graspdb_dir / "default.xmlskel") if skeleton else None
    )
    placement = loaded.scene.setup.placement
    assert placement["grasp"]["source"] == "peak flexion"
    assert placement["feasible"] is True and placement["feasible_poses"] > 0
    assert placement["penetration_m"] <= MetricSpec().placement.penetration
    assert placement["links"] and placement["grip_tests"] >= 1
    assert any(note.startswith("object placed where it fits at frame") for note in loaded.scene.setup.notes)


def test_when_no_feasible_pose_touches_the_hand_the_one_nearest_the_fingertips_is_kept():
    from handsim.assets import ASSETS_DIR

    spec = MetricSpec(placement=PlacementSpec(penetration=1e-6, touch=1e-6))  # touching = penetrating
    loaded = load_trial(ASSETS_DIR / "demo" / "tennis_ball.grasp.json", metrics=spec)
    placement = loaded.scene.setup.placement
    assert placement["feasible"] is True and placement["feasible_poses"] > 0
    assert placement["penetration_m"] == 0.0 and placement["links"] == []
    assert placement["grip_tests"] == 1
    assert (
        "no object pose within 0.001 mm of penetration touches the hand on the closing ramp: placed nearest "
        f"the fingertips' centre without penetration ({placement['candidates']} poses tried)"
    ) in loaded.scene.setup.notes


def _placements(monkeypatch) -> list:
    """The placements ``load_trial`` makes from now on, each searched afresh (the cache bypassed)."""
    import handsim.sim.scenarios as scenarios

    placed, original = [], scenarios.place_object

    def uncached(*args, **kwargs):
        placed.append(original(*args, **kwargs, use_cache=False))
        return placed[-1]

    monkeypatch.setattr(scenarios, "place_object", uncached)
    return placed


@pytest.mark.parametrize(
    ("recording", "grip_tests", "threads"),
    [
        ("01_ex01-rad-002-grasp-su01.txt", 15, "2"),  # every ranked candidate tested
        ("r_01_11_ex03-rad-004-grasp-su04.txt", 3, "3"),  # stops after 3: two more drawn ahead, dropped
    ],
)
def test_the_search_on_threads_places_as_on_one_thread(
    graspdb_dir, monkeypatch, recording, grip_tests, threads
):
    """Fit-frame queries and grip tests spread over threads (handsim.sim.parallel): the same placement,
    bit for bit, as one thread — the number of poses tried included, when the grip tests stop before the
    candidates drawn ahead of them (``map_until``) are needed."""
    import pickle

    import handsim.sim.placement.place as placement

    placed, drawn = _placements(monkeypatch), []
    original_until = placement.map_until

    def counted(run, items, enough, threads=None):
        def counting():
            for item in items:
                drawn[-1] += 1
                yield item

        drawn.append(0)
        return original_until(run, counting(), enough, threads)

    monkeypatch.setattr(placement, "map_until", counted)
    for count in ("1", threads):
        monkeypatch.setenv("HANDSIM_THREADS", count)
        load_trial(graspdb_dir / recording)
    alone, threaded = placed
    assert threaded.grip_tests == alone.grip_tests == grip_tests
    assert drawn[0] == grip_tests  # one thread draws no candidate it does not test
    if recording.startswith("r_"):
        assert drawn[1] > grip_tests  # the threads drew candidates that were never needed…
    assert pickle.dumps(threaded) == pickle.dumps(alone)  # …and they left no trace


@pytest.mark.parametrize("threads", ["1", "2"])
def test_grip_tests_that_cannot_match_an_earlier_grip_stop_and_leave_the_placement_unchanged(
    graspdb_dir, monkeypatch, threads
):
    """A grip test stops once its grip can no longer resist as many directions as an earlier candidate's:
    such a candidate is neither the winner nor an alternative, nor does it resist all six. The placement is
    the one of whole tests, bit for bit (the ball's first candidate resists all six, the 14 after it fewer:
    with one thread each of those stops at its first failed direction, or skips ObMan's run)."""
    import pickle

    from handsim.sim.placement.grip import GripBench

    placed, stopped = _placements(monkeypatch), []
    original_grip = GripBench.grip

    def whole(self, *args, needed=0, first=(), **kwargs):
        return original_grip(self, *args, **kwargs)

    def watched(self, *args, **kwargs):
        result = original_grip(self, *args, **kwargs)
        runs = (*result.stability.directions, result.stability.obman)
        stopped.append(any(d.failure.startswith("not run") for d in runs))
        return result

    monkeypatch.setenv("HANDSIM_THREADS", threads)
    monkeypatch.setattr(GripBench, "grip", whole)
    load_trial(graspdb_dir / "01_ex01-rad-002-grasp-su01.txt")
    monkeypatch.setattr(GripBench, "grip", watched)
    load_trial(graspdb_dir / "01_ex01-rad-002-grasp-su01.txt")
    unstopped, pruned = placed
    assert pruned.grip_tests == unstopped.grip_tests == len(stopped) == 15
    assert pickle.dumps(pruned) == pickle.dumps(unstopped)
    if threads == "1":
        assert stopped == [False] + [True] * 14


@pytest.mark.slow
@pytest.mark.parametrize("threads", ["1", "2"])
def test_poses_the_probe_settles_as_too_deep_leave_the_placement_unchanged(graspdb_dir, monkeypatch, threads):
    """The mug's search settles many poses with the collider's probe (one geom pair's MuJoCo contacts)
    instead of the full query: the placement, the number of poses tried included, is the one of full
    queries, bit for bit."""
    import pickle

    import handsim.sim.placement.collide as collide

    placed, settled = _placements(monkeypatch), []
    original_init = collide.HandObjectCollider.__init__
    original_depth_links = collide.HandObjectCollider.depth_links

    def unprobed(self, *args, **kwargs):
        original_init(self, *args, **kwargs)
        self._probes = False

    def counted(self, *args, **kwargs):
        depths, links = original_depth_links(self, *args, **kwargs)
        settled.append(sum(d == float("inf") for d in depths))
        return depths, links

    monkeypatch.setattr(collide.HandObjectCollider, "depth_links", counted)
    monkeypatch.setenv("HANDSIM_THREADS", threads)
    with monkeypatch.context() as patch:
        patch.setattr(collide.HandObjectCollider, "__init__", unprobed)
        load_trial(graspdb_dir / "04_ex01-rad-045-grasp-su03.txt")
    assert sum(settled) == 0
    load_trial(graspdb_dir / "04_ex01-rad-045-grasp-su03.txt")
    full, probed = placed
    assert sum(settled) > 10_000  # of the mug's ~45 000 queries
    assert pickle.dumps(probed) == pickle.dumps(full)
