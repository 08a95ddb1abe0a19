"""What a correction starts from: the recording at the control rate, and where its residuals act.

A correction changes two things of a recording, frame by frame at the control rate, and nothing else:

* **finger targets**: each actuator the recording drives gets ``recorded + δ`` (rad), ``|δ| ≤ finger_bound``;
* **wrist targets** (a hand whose root follows its recorded pose through a mocap weld): the recorded root
  pose, in the recording's frame, moved by ``Δp`` (m) and turned by the rotation vector ``Δr`` (rad) about
  the root's own origin: ``p' = p + Δp``, ``q' = exp(Δr) ⊗ q``.

A residual vector per frame holds the finger corrections in actuator order, then ``Δp, Δr`` per welded hand.
The corrected recording is the recording resampled at the control rate (as
:func:`~handsim.sim.control.control_schedule` resamples it) with those columns replaced, so that the replay
core turns it back into exactly the targets the correction simulated: resampling a recording already at the
control rate returns its samples (weights 0), and the wrist poses go through the same normalisation and
world transform (:func:`world_roots`).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from handsim.correct.config import CorrectionConfig, CorrectionError
from handsim.correct.hold import HoldGoal, hold_goal, is_hold_scene
from handsim.datatypes.poses import compose
from handsim.datatypes.rotations import axis_angle_to_quat, quat_multiply
from handsim.datatypes.trajectory import Trajectory
from handsim.datatypes.trajectory_ops import resample
from handsim.sim.control import ControlSchedule, control_schedule
from handsim.sim.drive import ScenarioSwitches, scenario_switches
from handsim.sim.scene.compiled import SimScene
from handsim.sim.specs import MetricSpec


@dataclass(frozen=True)
class ObjectReference:
    """One recorded object as the cost reads it.

    Attributes:
        name: The trajectory's track name.
        qpos: Address of its free joint in ``qpos``.
        hinge: Address of its hinge in ``qpos``, or -1 (rigid).
        pose: Recorded pose in the scene's world per frame (F, 7).
        valid: Frames with a usable recorded pose (F,).
        articulation: Recorded hinge angle per frame (F,), or None.
    """

    name: str
    qpos: int
    hinge: int
    pose: np.ndarray
    valid: np.ndarray
    articulation: np.ndarray | None


@dataclass(frozen=True)
class Reference:
    """The recording at the control rate, and the layout of the residual vector.

    Attributes:
        scene: The scene.
        schedule: The recording's control schedule (what pure replay drives).
        resampled: The recording resampled at the control rate, in the recording's frame (the corrected
            recording replaces its columns).
        actuators: The actuators the recording drives (its DoF columns), in actuator order.
        columns: Their columns in ``resampled.targets``.
        welded: Names of the hands whose roots follow recorded poses through mocap welds (``""`` for a
            scene's only hand), in the layout's order.
        mocap: Their mocap body ids.
        hands: The welded hands whose wrists are corrected: all of ``welded``, or none without wrist
            correction.
        objects: The recorded objects.
        ctrl_range: The corrected actuators' joint ranges, rad (fingers, 2).
        bounds: Bounds of the residual vector's parts (D,): per finger element its largest absolute value;
            per wrist ``Δp`` and ``Δr`` (all three elements alike) the largest norm of the 3-vector
            (:meth:`clip`).
        switches: When the scene switches contacts on and releases its supports (as the replay does).
        goal: A glove scene's hold goal (:mod:`handsim.correct.hold`; its object's "track" is its placed
            pose over the hold), or None where the objects follow recorded tracks.
        plan_start: First frame planned from (earlier frames keep the recording).
        plan_stop: Last frame planned (later frames keep the recording).
    """

    scene: SimScene
    schedule: ControlSchedule
    resampled: Trajectory
    actuators: np.ndarray
    columns: np.ndarray
    welded: tuple[str, ...]
    mocap: np.ndarray
    hands: tuple[str, ...]
    objects: tuple[ObjectReference, ...]
    ctrl_range: np.ndarray
    bounds: np.ndarray
    switches: ScenarioSwitches
    goal: HoldGoal | None
    plan_start: int
    plan_stop: int

    @property
    def frames(self) -> int:
        """Control frames F."""
        return self.schedule.frames

    @property
    def fingers(self) -> int:
        """Finger elements of the residual vector."""
        return int(self.actuators.shape[0])

    @property
    def size(self) -> int:
        """Elements of the residual vector D."""
        return self.fingers + 6 * len(self.hands)

    def clip(self, residual: np.ndarray) -> np.ndarray:
        """Residuals (..., D) within the bounds: fingers element by element, wrist vectors by their norm.

        A wrist's ``Δp`` longer than ``wrist_position_bound`` is shortened to it along its direction, and
        ``Δr`` likewise, so a bound is a distance and an angle, whatever the direction.
        """
        nf = self.fingers
        out = np.array(residual, dtype=float)
        out[..., :nf] = np.clip(out[..., :nf], -self.bounds[:nf], self.bounds[:nf])
        if self.hands:
            vectors = out[..., nf:].reshape((*out.shape[:-1], -1, 3))
            limit = self.bounds[nf::3].reshape(-1)
            norm = np.linalg.norm(vectors, axis=-1)
            scale = np.minimum(1.0, limit / np.maximum(norm, 1e-300))
            out[..., nf:] = (vectors * scale[..., None]).reshape(out[..., nf:].shape)
        return out

    def in_range(self, residual: np.ndarray, frames: np.ndarray) -> np.ndarray:
        """Finger residuals (..., h, D) at ``frames`` (h,) that keep each target within its joint's range.

        A corrected target beyond the joint's range would be clamped by the actuator: a correction that
        moves nothing. So ``recorded + δ`` is kept within the range, or at the recording where the recording
        itself lies beyond it (a correction never pushes a target further out than the recording has it).
        """
        ctrl = self.schedule.ctrl[frames][:, self.actuators]
        low = np.minimum(self.ctrl_range[:, 0], ctrl)
        high = np.maximum(self.ctrl_range[:, 1], ctrl)
        out = np.array(residual, dtype=float)
        out[..., : self.fingers] = np.clip(ctrl + out[..., : self.fingers], low, high) - ctrl
        return out

    def recorded_roots(self) -> np.ndarray:
        """Recorded root poses of the welded hands in the recording's frame (F, welded, 7)."""
        traj = self.resampled
        if not self.welded:
            return np.zeros((self.frames, 0, 7))
        if self.welded == ("",):
            return np.asarray(traj.root_pose, dtype=float)[:, None]
        return np.stack([np.asarray(traj.hand_roots[h], dtype=float) for h in self.welded], axis=1)

    def corrected(self, residual: np.ndarray) -> Trajectory:
        """The recording with ``residual`` (F, D) applied: finger columns and wrist poses replaced.

        Rows of ``residual`` that are zero give back the recorded targets exactly (the wrist's up to its
        quaternion's normalisation).
        """
        traj = self.resampled
        targets = np.array(traj.targets, dtype=float)
        targets[:, self.columns] = self.schedule.ctrl[:, self.actuators] + residual[:, : self.fingers]
        if not self.hands:
            return dataclasses.replace(traj, targets=targets)
        roots = moved_roots(self.recorded_roots(), residual[:, self.fingers :])
        if self.hands == ("",):
            return dataclasses.replace(traj, targets=targets, root_pose=roots[:, 0])
        hand_roots = dict(traj.hand_roots)
        hand_roots.update({h: roots[:, i] for i, h in enumerate(self.hands)})
        return dataclasses.replace(traj, targets=targets, hand_roots=hand_roots)


def moved_roots(recorded: np.ndarray, wrist: np.ndarray) -> np.ndarray:
    """Root poses moved by wrist residuals.

    Args:
        recorded: Root poses in the recording's frame (..., hands, 7).
        wrist: ``Δp, Δr`` per hand, flattened (..., 6 · hands).

    Returns:
        ``(p + Δp, exp(Δr) ⊗ q)`` (..., hands, 7), not renormalised.
    """
    delta = wrist.reshape((*wrist.shape[:-1], -1, 6))
    out = np.empty(np.broadcast_shapes(recorded.shape, (*delta.shape[:-1], 7)))
    out[..., :3] = recorded[..., :3] + delta[..., :3]
    out[..., 3:] = quat_multiply(axis_angle_to_quat(delta[..., 3:]), recorded[..., 3:])
    return out


def world_roots(world: np.ndarray, roots: np.ndarray) -> np.ndarray:
    """Root poses in the scene's world, as :func:`~handsim.sim.control.control_schedule` computes them.

    The quaternion is normalised as resampling does at a sample's own time, then the recording-to-world
    transform is composed on the left.
    """
    out = np.array(roots, dtype=float)
    out[..., 3:] = out[..., 3:] / np.linalg.norm(out[..., 3:], axis=-1, keepdims=True)
    return compose(world, out)


def build_reference(
    scene: SimScene, trajectory: Trajectory, config: CorrectionConfig, metrics: MetricSpec | None = None
) -> Reference:
    """The reference of a trial: its schedule, its recording at the control rate and the residual layout.

    Args:
        scene: The scene.
        trajectory: The recording.
        config: The correction's parameters.
        metrics: The replay's metric parameters (its release delay places a glove scene's release); default
            :class:`~handsim.sim.specs.MetricSpec`.

    Raises:
        CorrectionError: The scene has no recorded object to follow and no hold to judge (the message names
            the recording).
        TrajectoryError: The trajectory does not fit the scene (:func:`control_schedule`).
    """
    source = trajectory.source or "the trajectory"
    schedule = control_schedule(scene, trajectory, config.control_rate)
    switches = scenario_switches(scene, schedule, (metrics or MetricSpec()).release_delay)
    layout = scene.layout
    hold = not schedule.objects and is_hold_scene(scene)
    if not schedule.objects and not hold:
        what = "no object" if not layout.objects else "objects without a recorded track and no hold to judge"
        raise CorrectionError(
            f"{source}: the scene has {what}; a correction makes a recorded object follow its track, or a "
            "placed object stay in the hand, so it needs a trial whose objects are recorded (a Tzionas "
            "sequence with an object, an ARCTIC sequence) or a glove grasp (GraspDB14, a scripted grasp)"
        )
    if trajectory.times.shape[0] < 2:
        raise CorrectionError(f"{source}: one sample; a correction needs a motion of at least two frames")
    resampled = resample(trajectory, 1.0 / schedule.frame_dt).trajectory
    column = {name: i for i, name in enumerate(resampled.dof_names)}
    actuators = np.array([a for a, n in enumerate(layout.dof_names) if n in column], dtype=np.int64)
    columns = np.array([column[layout.dof_names[a]] for a in actuators], dtype=np.int64)
    welded = [h for h in layout.hands if h.mocap >= 0]
    hands = tuple(h.name for h in welded) if config.wrist else ()
    goal = hold_goal(scene, schedule, switches, source) if hold else None
    bounds = np.concatenate(
        [
            np.full(actuators.shape[0], config.finger_bound),
            np.tile([config.wrist_position_bound] * 3 + [config.wrist_rotation_bound] * 3, len(hands)).astype(
                float
            ),
        ]
    )
    return Reference(
        scene=scene,
        schedule=schedule,
        resampled=resampled,
        actuators=actuators,
        columns=columns,
        welded=tuple(h.name for h in welded),
        mocap=np.array([h.mocap for h in welded], dtype=np.int64),
        hands=hands,
        objects=_objects(scene, schedule) if goal is None else (_held_object(goal, schedule.frames),),
        ctrl_range=np.asarray(layout.ctrl_range, dtype=float)[actuators],
        bounds=bounds,
        switches=switches,
        goal=goal,
        plan_start=0 if goal is None else goal.plan_start,
        plan_stop=schedule.frames - 1 if goal is None else goal.plan_stop,
    )


def _objects(scene: SimScene, schedule: ControlSchedule) -> tuple[ObjectReference, ...]:
    """The recorded objects of a scene whose objects follow recorded tracks."""
    layout = scene.layout
    objects = []
    for index, track in schedule.objects.items():
        obj = layout.objects[index]
        frames = track.pose.shape[0]
        objects.append(
            ObjectReference(
                name=scene.setup.object_tracks[index],
                qpos=obj.free_qpos,
                hinge=obj.hinge_qpos if track.articulation is not None else -1,
                pose=np.asarray(track.pose, dtype=float),
                valid=np.ones(frames, bool) if track.valid is None else np.asarray(track.valid, bool),
                articulation=None if track.articulation is None else np.asarray(track.articulation, float),
            )
        )
    return tuple(objects)


def _held_object(goal: HoldGoal, frames: int) -> ObjectReference:
    """A glove scene's object as the cost reads it: its placed pose is its track over the hold."""
    return ObjectReference(
        name="",
        qpos=goal.qpos,
        hinge=-1,
        pose=np.broadcast_to(goal.placed, (frames, 7)),
        valid=goal.valid,
        articulation=None,
    )
