"""Per-frame physics-plausibility metrics of a replay, and their summary.

Everything is computed from what the stepping loop recorded: the state (``qpos``) at every frame time and
the metric sensors (:mod:`handsim.sim.scene.layout`); only the fingertips' kinematic targets need forward
kinematics here. Conventions: frame ``k`` is trajectory time ``t_k``; the
state at ``t_k`` results from the targets of frame ``k − 1``; errors compare it with the references at
``t_k``. Contact sensors are evaluated by MuJoCo in the last step's forward pass, one step (2 ms) before the
recorded state.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import mujoco
import numpy as np

from handsim.datatypes.poses import compose, inverse
from handsim.datatypes.rotations import quat_angle
from handsim.sim.control import ControlSchedule
from handsim.sim.scene.clearance import site_positions
from handsim.sim.scene.compiled import SimScene
from handsim.sim.scene.layout import CONTACT_SLOT_SIZE, CONTACT_SLOTS
from handsim.sim.self_contact import self_penetration_track


@dataclass(frozen=True)
class HoldTracks:
    """What the hold verdict reads of a replay's frames (:func:`handsim.sim.summary.hold_outcome`).

    :class:`FrameMetrics` carries the same three fields; these alone are cheap enough to compute on the
    frames of a run that is still going.

    Attributes:
        times: Trajectory time of each frame, s (N,).
        object_in_hand: Each object's origin in the (first) hand root's frame, m (N, objects, 3).
        hand_contact: Whether any hand link touches each object (N, objects).
    """

    times: np.ndarray
    object_in_hand: np.ndarray
    hand_contact: np.ndarray


@dataclass(frozen=True)
class FrameMetrics:
    """Per-frame metrics (N frames).

    Attributes:
        times: Trajectory time of each frame, s (N,).
        contact_count: Contacts per hand link × object part (N, links, parts).
        normal_force: Sum of contact normal forces per hand link × object part, N (N, links, parts); over
            :data:`~handsim.sim.scene.layout.CONTACT_SLOTS` contacts in a pair only the first are summed.
        truncated_pairs: Link × part pairs with more contacts than were summed (N,).
        penetration: Deepest hand–object penetration, m, ≥ 0 (N,).
        tracking_error: Achieved minus target joint angle, rad (N, ndof), in actuator order.
        tip_error: Distance of each fingertip from where the targets (and recorded root pose) put it,
            m (N, tips).
        object_position_error: Recorded scenario: object origin distance from the recording, m
            (N, objects); NaN where there is no track.
        object_rotation_error: Rotation between simulated and recorded object, rad (N, objects).
        articulation_error: Hinge angle minus recorded angle, rad (N, objects); NaN without a hinge.
        object_in_hand: Position of each object's origin in the hand root's frame, m (N, objects, 3).
        hand_contact: Some hand link touches the object (N, objects).
        self_penetration: Scenes without objects (hand-only sequences): the simulated hand's deepest
            penetration of itself at each frame, m (N,) (:mod:`handsim.sim.self_contact`); empty (not
            measured) in a scene with objects.
        self_penetration_pair: Its two links per frame, indices into the layout's ``link_names`` (N, 2),
            -1 where none overlap; empty with objects.
        target_self_penetration: The same for the hand put at its targets (the recording's own postures).
        target_self_penetration_pair: Its links.
        part_object: The object of each part (parts,).
        hand_names: The scene's hands (:attr:`~handsim.sim.scene.layout.HandLayout.name`; ``("",)`` for one
        hand).
        hand_penetration: Deepest penetration of each hand into any object part, m, ≥ 0 (N, hands).
        link_hand: The hand (index into ``hand_names``) of each link along the ``links`` axis (links,).
        dof_hand: The hand of each column of ``tracking_error`` (ndof,).
        tip_hand: The hand of each column of ``tip_error`` (tips,).
    """

    times: np.ndarray
    contact_count: np.ndarray
    normal_force: np.ndarray
    truncated_pairs: np.ndarray
    penetration: np.ndarray
    tracking_error: np.ndarray
    tip_error: np.ndarray
    object_position_error: np.ndarray
    object_rotation_error: np.ndarray
    articulation_error: np.ndarray
    object_in_hand: np.ndarray
    hand_contact: np.ndarray
    part_object: np.ndarray = field(repr=False, default_factory=lambda: np.zeros(0, dtype=np.int64))
    self_penetration: np.ndarray = field(default_factory=lambda: np.zeros(0))
    self_penetration_pair: np.ndarray = field(default_factory=lambda: np.zeros((0, 2), dtype=np.int64))
    target_self_penetration: np.ndarray = field(default_factory=lambda: np.zeros(0))
    target_self_penetration_pair: np.ndarray = field(default_factory=lambda: np.zeros((0, 2), dtype=np.int64))
    hand_names: tuple[str, ...] = ()
    hand_penetration: np.ndarray | None = field(repr=False, default=None)
    link_hand: np.ndarray | None = field(repr=False, default=None)
    dof_hand: np.ndarray | None = field(repr=False, default=None)
    tip_hand: np.ndarray | None = field(repr=False, default=None)


def _penetration(scene: SimScene, sensors: np.ndarray) -> np.ndarray:
    """Deepest penetration of each hand into any object part, m, ≥ 0 (N, hands)."""
    adr = np.array([h.penetration_adr for h in scene.layout.hands], dtype=np.int64)  # (hands, parts)
    n = sensors.shape[0]
    if adr.size == 0:
        return np.zeros((n, len(scene.layout.hands)))
    found, dist = sensors[:, adr], sensors[:, adr + 1]
    return np.where(found > 0, np.maximum(-dist, 0.0), 0.0).max(axis=2)


def _contact_counts(scene: SimScene, sensors: np.ndarray) -> np.ndarray:
    """Contacts per hand link × object part in each frame (N, links, parts), int32."""
    adr = scene.layout.contact_adr
    if adr.size == 0:
        return np.zeros((sensors.shape[0], *adr.shape), np.int32)
    return sensors[:, adr].astype(np.int32)  # every slot repeats the total count


def contact_slot_values(scene: SimScene, sensors: np.ndarray, offset: int) -> np.ndarray:
    """One field of every used slot of the link × part contact sensors, 0 in unused slots.

    Args:
        scene: The scene.
        sensors: Sensor rows (N, nsensordata).
        offset: The field's offset in a slot: 1 the normal force, N (≥ 0); 4 the distance, m (< 0 inside).

    Returns:
        (N, links, parts, :data:`~handsim.sim.scene.layout.CONTACT_SLOTS`).
    """
    adr = scene.layout.contact_adr
    found = sensors[:, adr]  # every slot repeats the count
    slots = adr[..., None] + CONTACT_SLOT_SIZE * np.arange(CONTACT_SLOTS) + offset
    used = np.arange(CONTACT_SLOTS) < np.minimum(found, CONTACT_SLOTS)[..., None]
    return np.where(used, sensors[:, slots], 0.0)


def _contacts(scene: SimScene, sensors: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    adr = scene.layout.contact_adr
    n = sensors.shape[0]
    found = _contact_counts(scene, sensors)
    if adr.size == 0:
        return found, np.zeros(found.shape), np.zeros(n, np.int32)
    normal = np.zeros(found.shape)
    frame, link, part = np.nonzero(found)  # contacts are sparse: read the slots of touching pairs only
    if frame.size:
        # the normal force of each slot
        slots = adr[link, part][:, None] + CONTACT_SLOT_SIZE * np.arange(CONTACT_SLOTS) + 1
        used = np.arange(CONTACT_SLOTS) < np.minimum(found[frame, link, part], CONTACT_SLOTS)[:, None]
        normal[frame, link, part] = np.where(used, sensors[frame[:, None], slots], 0.0).sum(axis=-1)
    truncated = (found > CONTACT_SLOTS).sum(axis=(1, 2)).astype(np.int32)
    return found, normal, truncated


def _kinematic_targets(scene: SimScene, schedule: ControlSchedule, qpos: np.ndarray) -> np.ndarray:
    """Qpos of each frame with the hand put where the targets (and the recorded root pose) say."""
    layout = scene.layout
    n = qpos.shape[0]
    target = qpos.copy()
    target[:, layout.dof_qpos] = np.clip(schedule.ctrl[:n], layout.ctrl_range[:, 0], layout.ctrl_range[:, 1])
    if schedule.root_poses is not None:
        welded = [h for h in layout.hands if h.mocap >= 0]
        for h, hand in enumerate(welded):
            if hand.root_free_qpos >= 0:
                target[:, hand.root_free_qpos : hand.root_free_qpos + 7] = schedule.root_poses[:n, h]
    return target


def _target_tips(scene: SimScene, qpos: np.ndarray, scratch: mujoco.MjData | None = None) -> np.ndarray:
    """Fingertip site positions (N, tips, 3) for each qpos row (kinematics only; in ``scratch`` when given).

    :func:`~handsim.sim.scene.clearance.site_positions` copies every site each row; the tips are picked once
    at the end.
    """
    return site_positions(scene.model, qpos, scratch)[:, scene.layout.tip_sites]


def _poses(sensors: np.ndarray, pos_adr: int, quat_adr: int) -> np.ndarray:
    return np.concatenate([sensors[:, pos_adr : pos_adr + 3], sensors[:, quat_adr : quat_adr + 4]], axis=1)


def _owner(members: list[np.ndarray], count: int) -> np.ndarray:
    """The index of the group each of ``count`` items belongs to (-1: none)."""
    owner = np.full(count, -1, dtype=np.int64)
    for index, items in enumerate(members):
        owner[items] = index
    return owner


def _part_object(layout) -> np.ndarray:
    """The object of each object part, in the layout's part order."""
    if not layout.objects:
        return np.zeros(0, np.int64)
    return np.concatenate([np.full(len(o.part_bodies), i) for i, o in enumerate(layout.objects)])


def hold_tracks(
    scene: SimScene, schedule: ControlSchedule, sensors: np.ndarray, count: np.ndarray | None = None
) -> HoldTracks:
    """The hold verdict's tracks of the frames recorded so far (``sensors``: their first n rows).

    Args:
        scene: The replayed scene.
        schedule: Its control schedule.
        sensors: Sensor data at each frame time (n, nsensordata).
        count: The frames' contact counts when already read (:class:`FrameMetrics`'s ``contact_count``).
    """
    layout = scene.layout
    n, nobj = sensors.shape[0], len(layout.objects)
    count = _contact_counts(scene, sensors) if count is None else count
    hand_root = _poses(sensors, *layout.root_pose_adr)
    part_object = _part_object(layout)
    in_hand = np.empty((n, nobj, 3))
    touching = np.zeros((n, nobj), dtype=bool)
    for i in range(nobj):
        pose = _poses(sensors, *layout.object_pose_adr[i])
        in_hand[:, i] = compose(inverse(hand_root), pose)[:, :3]
        touching[:, i] = count[:, :, part_object == i].sum(axis=(1, 2)) > 0
    return HoldTracks(schedule.times[:n], in_hand, touching)


def frame_metrics(
    scene: SimScene,
    schedule: ControlSchedule,
    qpos: np.ndarray,
    sensors: np.ndarray,
    scratch: mujoco.MjData | None = None,
) -> FrameMetrics:
    """Compute the per-frame metrics of a replay.

    Args:
        scene: The replayed scene.
        schedule: Its control schedule (N frames).
        qpos: State at each frame time (n ≤ N, nq); fewer rows when the run stopped early.
        sensors: Sensor data at each frame time (n, nsensordata).
        scratch: An ``MjData`` of the scene's model (or of a copy of it) whose contents may be overwritten,
            for the fingertips' kinematic targets (the finished run's own data saves allocating one);
            None: a new one.

    Returns:
        The metrics of the n recorded frames; in a scene without objects also the hand's self-penetration
        (simulated and at the targets).
    """
    layout = scene.layout
    n = qpos.shape[0]
    count, normal, truncated = _contacts(scene, sensors)
    hand_penetration = _penetration(scene, sensors)
    penetration = hand_penetration.max(axis=1) if hand_penetration.shape[1] else np.zeros(n)
    targets = schedule.ctrl[:n]
    tracking = qpos[:, layout.dof_qpos] - np.clip(targets, layout.ctrl_range[:, 0], layout.ctrl_range[:, 1])
    target_qpos = _kinematic_targets(scene, schedule, qpos)
    target_tips = _target_tips(scene, target_qpos, scratch)
    tips = sensors[:, layout.tip_adr[:, None] + np.arange(3)]
    tip_error = np.linalg.norm(tips - target_tips, axis=-1)

    nobj = len(layout.objects)
    pos_err = np.full((n, nobj), np.nan)
    rot_err = np.full((n, nobj), np.nan)
    art_err = np.full((n, nobj), np.nan)
    tracks = hold_tracks(scene, schedule, sensors, count)
    for i, obj in enumerate(layout.objects):
        track = schedule.objects.get(i)
        if track is None:
            continue
        pose = _poses(sensors, *layout.object_pose_adr[i])
        pos_err[:, i] = np.linalg.norm(pose[:, :3] - track.pose[:n, :3], axis=1)
        rot_err[:, i] = quat_angle(pose[:, 3:], track.pose[:n, 3:])
        if track.articulation is not None and obj.hinge_qpos >= 0:
            art_err[:, i] = qpos[:, obj.hinge_qpos] - track.articulation[:n]
    hand_only = {}
    if not nobj:
        depth, pair = self_penetration_track(scene, qpos)
        target_depth, target_pair = self_penetration_track(scene, target_qpos)
        hand_only = {
            "self_penetration": depth,
            "self_penetration_pair": pair,
            "target_self_penetration": target_depth,
            "target_self_penetration_pair": target_pair,
        }
    return FrameMetrics(
        times=schedule.times[:n],
        contact_count=count,
        normal_force=normal,
        truncated_pairs=truncated,
        penetration=penetration,
        tracking_error=tracking,
        tip_error=tip_error,
        object_position_error=pos_err,
        object_rotation_error=rot_err,
        articulation_error=art_err,
        object_in_hand=tracks.object_in_hand,
        hand_contact=tracks.hand_contact,
        part_object=_part_object(layout),
        **hand_only,
        hand_names=tuple(h.name for h in layout.hands),
        hand_penetration=hand_penetration,
        link_hand=_owner([h.links for h in layout.hands], len(layout.link_names)),
        dof_hand=_owner([h.dofs for h in layout.hands], len(layout.dof_names)),
        tip_hand=_owner([h.tips for h in layout.hands], len(layout.tip_names)),
    )
