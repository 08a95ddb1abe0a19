"""Trajectory → control frames: joint targets per actuator and a root pose per frame, in the scene's world.

The trajectory is resampled (linear, slerp for poses; :func:`handsim.datatypes.trajectory_ops.resample`) at
the
control rate; a control frame lasts a whole number of simulation steps, so the rate is rounded to
``1 / (substeps · timestep)`` (noted when it changes). Frame ``k`` holds the targets of time
``t0 + k / rate`` for its ``substeps`` steps; the state after frame ``k`` is compared with those targets.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from handsim.datatypes.poses import compose
from handsim.datatypes.trajectory import ObjectTrack, Trajectory
from handsim.datatypes.trajectory_ops import resample
from handsim.errors import TrajectoryError
from handsim.sim.scene.compiled import SimScene
from handsim.sim.stepper import check_controls

DEFAULT_CONTROL_RATE = 100.0
"""Hz: 5 steps of 2 ms per frame; above the GraspDB14 glove's ~60 Hz and Tzionas' 30 Hz."""


@dataclass(frozen=True)
class ControlSchedule:
    """Controls for every control frame of a replay.

    Attributes:
        times: Trajectory time of each frame, s (N,).
        ctrl: Actuator targets, radians (N, nu), in actuator order.
        root_pose: Hand root pose in the scene's world per frame (N, 7), or None (fixed root); with several
            hands, the first hand's.
        objects: Recorded object tracks in the scene's world, resampled to the frames, by scene object
            index (only objects with a track).
        substeps: Simulation steps per frame.
        frame_dt: Seconds per frame (``substeps · timestep``).
        held_dofs: Hand DoFs the trajectory has no column for: held at their initial target.
        notes: Decisions, for the user to see.
        root_poses: Every welded hand root's pose in the scene's world per frame (N, H, 7), in the order of
            the layout's hands with a mocap target, or None (no welded root).
    """

    times: np.ndarray
    ctrl: np.ndarray
    root_pose: np.ndarray | None
    objects: dict[int, ObjectTrack]
    substeps: int
    frame_dt: float
    held_dofs: tuple[str, ...]
    notes: tuple[str, ...]
    root_poses: np.ndarray | None = None

    @property
    def frames(self) -> int:
        """Number of control frames."""
        return int(self.times.shape[0])

    def frame_at(self, time: float) -> int:
        """Index of the first frame at or after trajectory time ``time`` (clamped to the frames)."""
        return int(min(np.searchsorted(self.times, time - 1e-9), self.frames - 1))


def substeps_for(rate_hz: float, timestep: float) -> int:
    """Simulation steps per control frame for a control rate (at least 1)."""
    if not (np.isfinite(rate_hz) and rate_hz > 0):
        raise ValueError(f"control rate must be a positive number of Hz, got {rate_hz}")
    return max(1, round(1.0 / (rate_hz * timestep)))


def control_schedule(scene: SimScene, trajectory: Trajectory, rate_hz: float) -> ControlSchedule:
    """Turn a trajectory into control frames for a scene.

    Args:
        scene: The compiled scene.
        trajectory: Joint targets named like the hand's DoFs; a root pose when the scene's hand follows
            one (``hand_root="weld"``); object tracks named in ``scene.setup.object_tracks``.
        rate_hz: Requested control rate, Hz.

    Returns:
        The schedule.

    Raises:
        TrajectoryError: A trajectory DoF is not a hand DoF, the hand follows a root pose the trajectory
            lacks, a named object track is missing, or a target is not finite after resampling.
    """
    setup = scene.setup
    substeps = substeps_for(rate_hz, scene.timestep)
    frame_dt = substeps * scene.timestep
    notes = []
    if abs(1.0 / frame_dt - rate_hz) > 1e-6 * rate_hz:
        notes.append(
            f"control rate {rate_hz:g} Hz rounded to {1.0 / frame_dt:g} Hz ({substeps} steps per frame)"
        )
    _check_trajectory(scene, trajectory)
    sampled = resample(trajectory, 1.0 / frame_dt) if trajectory.times.shape[0] > 1 else None
    traj = sampled.trajectory if sampled is not None else trajectory
    notes.extend(sampled.notes if sampled is not None else ())
    ctrl, held = _targets(scene, traj, trajectory.source)
    if held:
        notes.append(
            f"hand DoFs without a trajectory column, held at 0 rad (or their nearest limit): {list(held)}"
        )
    world = np.asarray(setup.world_from_recording, dtype=float)
    roots = _root_poses(scene, traj, world, trajectory.source)
    if roots is None and trajectory.root_pose is not None:
        notes.append("the trajectory's root pose is not followed: the scene's hand root is fixed")
    return ControlSchedule(
        times=np.asarray(traj.times, dtype=float),
        ctrl=ctrl,
        root_pose=None if roots is None else roots[:, 0],
        objects=_object_tracks(scene, traj, world),
        substeps=substeps,
        frame_dt=frame_dt,
        held_dofs=held,
        notes=tuple(notes),
        root_poses=roots,
    )


def _welded(scene: SimScene) -> list[str]:
    """Names of the hands whose root follows a recorded pose (on a mocap weld), in layout order."""
    return [h.name for h in scene.layout.hands if h.mocap >= 0]


def _check_trajectory(scene: SimScene, trajectory: Trajectory) -> None:
    """Check that the trajectory has what the scene follows: its DoFs, root poses and object tracks.

    Raises:
        TrajectoryError: A trajectory DoF is not a hand DoF, the hand follows a root pose the trajectory
            lacks, or a named object track is missing.
    """
    layout, source = scene.layout, trajectory.source or "trajectory"
    unknown = [n for n in trajectory.dof_names if n not in layout.dof_names]
    if unknown:
        raise TrajectoryError(
            f"{source}: DoFs {unknown} are not DoFs of the hand; the hand has {list(layout.dof_names)}"
        )
    if len(layout.hands) > 1:
        lacking = [name for name in _welded(scene) if name not in trajectory.hand_roots]
        if lacking:
            raise TrajectoryError(
                f"{source}: the hands {lacking} follow recorded root poses but "
                f"the trajectory has hand roots only for {list(trajectory.hand_roots)}"
            )
    elif layout.mocap >= 0 and trajectory.root_pose is None:
        raise TrajectoryError(
            f"{source}: the hand follows a recorded root pose (hand_root='weld') but the trajectory has none"
        )
    missing = [k for k in scene.setup.object_tracks if k and k not in trajectory.objects]
    if missing:
        raise TrajectoryError(f"{source}: no object track {missing}; it has {list(trajectory.objects)}")


def _targets(scene: SimScene, traj: Trajectory, source: str | None) -> tuple[np.ndarray, tuple[str, ...]]:
    """The actuator targets of each frame (N, nu), and the hand DoFs without a column (held at 0 rad).

    Raises:
        TrajectoryError: A target is not finite.
    """
    layout = scene.layout
    column = {name: i for i, name in enumerate(traj.dof_names)}
    held = tuple(n for n in layout.dof_names if n not in column)
    initial = np.clip(0.0, layout.ctrl_range[:, 0], layout.ctrl_range[:, 1])
    ctrl = np.tile(initial, (traj.times.shape[0], 1))
    actuators = [a for a, name in enumerate(layout.dof_names) if name in column]
    ctrl[:, actuators] = traj.targets[:, [column[layout.dof_names[a]] for a in actuators]]
    check_controls(ctrl, f"{source or 'trajectory'} targets after resampling")
    return ctrl, held


def _root_poses(
    scene: SimScene, traj: Trajectory, world: np.ndarray, source: str | None
) -> np.ndarray | None:
    """Every welded hand root's pose in the scene's world per frame (N, H, 7), or None (no welded root).

    Raises:
        TrajectoryError: A pose is not finite.
    """
    welded = _welded(scene)
    if not welded:
        return None
    recorded = [traj.hand_roots[n] for n in welded] if len(scene.layout.hands) > 1 else [traj.root_pose]
    roots = np.stack([compose(world, np.asarray(r, dtype=float)) for r in recorded], axis=1)
    check_controls(roots.reshape(len(roots), -1), f"{source or 'trajectory'} root pose")
    return roots


def _object_tracks(scene: SimScene, traj: Trajectory, world: np.ndarray) -> dict[int, ObjectTrack]:
    """The recorded object tracks in the scene's world, by scene object index (only objects with a track)."""
    objects = {}
    for index, key in enumerate(scene.setup.object_tracks):
        if key:
            track = traj.objects[key]
            objects[index] = ObjectTrack(
                pose=compose(world, np.asarray(track.pose, dtype=float)),
                articulation=track.articulation,
                valid=track.valid,
            )
    return objects
