"""Loading shared by the kinds whose recordings hold the hand alone (glove scenario): GraspDB14 and scripted.

The hand is the parametric default hand unless a skeleton is given; the trial's object is placed in the hand
by :func:`handsim.sim.scenarios.glove_scene`.
"""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING

from handsim.builders import default_hand, default_skeleton
from handsim.sim.scenarios import glove_scene
from handsim.sim.specs import MetricSpec
from handsim.trials.base import LoadedTrial, Trial, build_objects
from handsim.trials.episodes import episode_note, episode_trajectory, whole_recording_verdict

if TYPE_CHECKING:
    import mujoco

    from handsim.datatypes.skeleton import Skeleton
    from handsim.datatypes.trajectory import Trajectory
    from handsim.glove.checks import RecordingChecks


def parametric_hand(trial: Trial, skeleton: Skeleton | None = None) -> tuple[Skeleton, mujoco.MjSpec, str]:
    """The parametric default hand of the trial's length: skeleton, hand spec, text for people.

    Args:
        trial: The trial (its hand length and collision shapes).
        skeleton: The parametric skeleton of that length when read already; None: made here.
    """
    skeleton = default_skeleton(trial.hand_length) if skeleton is None else skeleton
    hand = default_hand(trial.hand_length, collision=trial.collision)
    return skeleton, hand, f"parametric default hand, {trial.hand_length:g} m ({skeleton.ndof} DoFs)"


def glove_loaded(
    trial: Trial,
    hand: mujoco.MjSpec,
    hand_text: str,
    trajectory: Trajectory,
    metrics: MetricSpec | None,
    progress: bool,
    notes: tuple[str, ...] = (),
    checks: RecordingChecks | None = None,
) -> LoadedTrial:
    """The trial's object placed in the hand by the glove scenario, and the loaded trial.

    Args:
        trial: The trial (its first object is grasped).
        hand: The hand the trajectory drives.
        hand_text: The hand, for people.
        trajectory: The recording as joint targets, with its phases.
        metrics: Placement thresholds (default :class:`~handsim.sim.specs.MetricSpec`); the loaded trial
            keeps them, for its replay to use the same.
        progress: Show a progress bar while an uncached convex decomposition runs.
        notes: Notes of the hand's reader (and of the recording's checks).
        checks: What the recording's checks found (GraspDB14 recordings), or None when not checked.

    With :attr:`Trial.grasp` set, the recording is cut to that grasp episode first
    (:func:`~handsim.trials.episodes.episode_trajectory`). Without, the whole recording is replayed, and its
    hold is not judged when it holds no complete grasp episode
    (:func:`~handsim.trials.episodes.whole_recording_verdict`).
    """
    episode = unjudged = None
    if trial.grasp is not None:
        trajectory, episode, segmentation = episode_trajectory(trajectory, trial.grasp)
        notes = (*notes, episode_note(episode, segmentation))
    else:
        unjudged = whole_recording_verdict(trajectory)
    specs, objects, object_notes = build_objects(trial, progress)
    scene = glove_scene(hand, trajectory, specs[0], spec=metrics)
    if unjudged is not None:
        scene = dataclasses.replace(scene, setup=dataclasses.replace(scene.setup, unjudged=unjudged))
    return LoadedTrial(
        trial=trial,
        scene=scene,
        trajectory=trajectory,
        hand=hand_text,
        objects=objects,
        notes=(*trial.notes, *notes, *object_notes),
        checks=checks,
        episode=episode,
        metrics=metrics or MetricSpec(),
    )
