"""A glove recording's grasp episodes as trials: the episode a trial names, cut out with its phases.

A glove trial (:attr:`~handsim.trials.base.Trial.grasp` set) replays one grasp episode of its recording
(:func:`handsim.glove.segmentation.segment_grasps`): the recording cut to the episode's frames, from its
approach to its release, with the episode's phases (``approach``, ``closure``, ``hold``, ``release``; an
episode found from an annotation also keeps its annotated ``grasp`` phase, which is its hold). The glove
scenario reads them (:func:`handsim.sim.placement.grasp_frame.grasp_frame`): the object is placed in the
closing hand, released once the grasp has closed, and held over the whole hold (a hand closed for 33 s is
judged over 33 s, not over a flexion spike inside the closure).
"""

from __future__ import annotations

import dataclasses
import hashlib
from collections.abc import Callable

import numpy as np

from handsim.datatypes.trajectory import Phase, Trajectory
from handsim.errors import HandsimError
from handsim.glove.phases import cut
from handsim.glove.segmentation import (
    ANNOTATION,
    GRASP_PHASE,
    GraspEpisode,
    GraspSegmentation,
    segment_grasps,
)
from handsim.trials.base import Trial, TrialError
from handsim.trials.sorting import Sorting, TrialEntry

_SEGMENTATIONS: dict[str, GraspSegmentation] = {}
"""Segmentations of the recordings segmented last in this process, by :func:`_content_key`."""
_KEEP = 8
"""How many recordings' segmentations :data:`_SEGMENTATIONS` keeps."""


def _content_key(trajectory: Trajectory) -> str:
    """SHA-256 of what a segmentation reads of a recording: its name, DoFs, phases, times, targets, switch."""
    digest = hashlib.sha256()
    names = (trajectory.source, trajectory.dof_names, trajectory.phases, trajectory.targets.shape)
    digest.update(repr(names).encode())
    for array in (trajectory.times, trajectory.targets, trajectory.switch):
        if array is not None:
            digest.update(np.ascontiguousarray(array).tobytes())
    return digest.hexdigest()


def recording_segmentation(trajectory: Trajectory) -> GraspSegmentation:
    """The grasp episodes of a recording (:func:`~handsim.glove.segmentation.segment_grasps`), segmented once.

    A dataset run lists a recording's episodes, then loads each as a trial; ``handsim replay`` judges them
    one after another: each load reads the recording again, and finds its segmentation here instead of
    segmenting it again. The key is the content read, so a recording read another way (another skeleton,
    thumb rest or annotation) is segmented anew.
    """
    key = _content_key(trajectory)
    if key not in _SEGMENTATIONS:
        while len(_SEGMENTATIONS) >= _KEEP:
            del _SEGMENTATIONS[next(iter(_SEGMENTATIONS))]
        _SEGMENTATIONS[key] = segment_grasps(trajectory)
    return _SEGMENTATIONS[key]


def episode_trajectory(
    trajectory: Trajectory, index: int
) -> tuple[Trajectory, GraspEpisode, GraspSegmentation]:
    """The recording cut to one of its grasp episodes, with the phases the glove scenario reads.

    Args:
        trajectory: The glove recording as the trial replays it (with its annotated phases, if any).
        index: The episode, 1-based, in the order :func:`~handsim.glove.segmentation.segment_grasps` lists
            them (``handsim inspect`` prints it).

    Returns:
        The cut trajectory (times from 0 at the episode's first frame; its phases ``approach`` …
        ``release``), the episode and the recording's segmentation.

    Raises:
        TrialError: The recording is a calibration sequence, has no episode ``index``, or the episode is
            truncated (the file starts or ends inside it: it is never judged).
    """
    what = trajectory.source or "the recording"
    segmentation = recording_segmentation(trajectory)
    if segmentation.calibration is not None:
        raise TrialError(f"{what}: {segmentation.calibration.text()}: it holds no grasp to replay")
    episodes = segmentation.episodes
    if not 1 <= index <= len(episodes):
        listed = f"episodes 1–{len(episodes)}" if episodes else "no grasp episode"
        raise TrialError(
            f"{what}: no grasp episode {index}; the recording has {listed} (`handsim inspect` lists them)"
        )
    episode = episodes[index - 1]
    if episode.truncated:
        raise TrialError(f"{what}: grasp episode {index} is truncated ({episode.note}): it is never judged")
    part = cut(trajectory, Phase(f"episode {index}", episode.start, episode.stop))
    phases = tuple(Phase(p.name, p.start - episode.start, p.stop - episode.start) for p in episode.phases)
    if episode.source == ANNOTATION:  # the annotated grasp phase, read as an annotation is
        hold = episode.hold
        phases = (*phases, Phase(GRASP_PHASE, hold.start - episode.start, hold.stop - episode.start))
    return dataclasses.replace(part, phases=phases), episode, segmentation


def episode_note(episode: GraspEpisode, segmentation: GraspSegmentation) -> str:
    """For people: which episode a trial replays, where it lies in the recording, how it was found."""
    times = segmentation.times
    hold = episode.hold
    return (
        f"grasp episode {episode.index} of {len(segmentation.episodes)} ({len(segmentation.complete)} "
        f"complete; {segmentation.source}): frames {episode.start}–{episode.stop - 1} of the recording "
        f"({times[episode.start]:.2f}–{times[episode.stop - 1]:.2f} s), hold "
        f"{times[hold.start]:.2f}–{times[hold.stop - 1]:.2f} s; times below are the episode's own, from 0"
    )


def whole_recording_verdict(trajectory: Trajectory) -> str | None:
    """Why a whole recording's hold is not judged (no complete grasp episode in it), or None.

    A recording whose grasps are all cut off by its start or end (or that holds none) has no hold to judge:
    its replay still measures the hand, but its hold outcome is this reason. One without any grasp episode
    (a hand that never closes, or never moves) says "no grasp" first, plainly.
    """
    segmentation = recording_segmentation(trajectory)
    if segmentation.complete:
        return None
    if segmentation.calibration is not None:
        return f"not judged: {segmentation.calibration.text()}"
    if not segmentation.episodes:
        return f"not judged: no grasp in the recording ({segmentation.note})"
    cut_off = "; ".join(f"episode {e.index}: {e.note}" for e in segmentation.episodes if e.truncated)
    return (
        "not judged: the recording holds no complete grasp episode (" + (cut_off or segmentation.note) + ")"
    )


def episode_id(recording_id: str, index: int) -> str:
    """The id of a recording's grasp episode in a dataset run: ``<recording>#<episode>``."""
    return f"{recording_id}#{index}"


def add_episodes(sorting: Sorting, entry: TrialEntry, read: Callable[[Trial], Trajectory]) -> None:
    """Add a glove recording to a dataset as one entry per complete grasp episode (id ``<file>#<k>``).

    A recording that cannot be read, or that holds no complete episode, stays one entry (its replay reports
    why, or measures the hand and says why its hold is not judged); a calibration sequence becomes a
    companion that says so, as does each truncated episode.

    Args:
        sorting: The discovery's sorting.
        entry: The whole recording's entry.
        read: Its kind's reader (:attr:`~handsim.trials.kind.TrialKind.read`).
    """
    try:
        segmentation = recording_segmentation(read(entry.trial))
    except HandsimError:
        sorting.add(entry)
        return
    if segmentation.calibration is not None:
        sorting.companions[entry.id] = segmentation.calibration.text()
        return
    if not segmentation.complete:
        sorting.add(entry)  # replayed whole: the hand is measured, its hold not judged (and says why)
    for episode in segmentation.episodes:
        if episode.truncated:
            sorting.companions[episode_id(entry.id, episode.index)] = (
                f"grasp episode {episode.index} of {entry.id}, truncated ({episode.note}): never judged"
            )
            continue
        trial = dataclasses.replace(entry.trial, grasp=episode.index)
        sorting.add(dataclasses.replace(entry, id=episode_id(entry.id, episode.index), trial=trial))
