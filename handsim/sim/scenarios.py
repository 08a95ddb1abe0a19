"""Scenes for the two replay scenarios, with the choices they make written into :class:`SceneSetup`.

* **Recorded object** (:func:`recorded_scene`; Tzionas, ARCTIC): the hand's root follows its recorded pose
  through a mocap weld and each object starts at its recorded pose, free. A recording of two hands (a
  Tzionas sequence listing ``Model_Hand_R`` and ``Model_Hand_L``) attaches each under ``hand/<name>/``,
  each root welded to its own mocap body following ``hand_roots[name]`` (:func:`attach_welded_hands`).
  The recording's frame has no "up": gravity is taken as the object's face direction closest to
  ``gravity_hint`` at the first frame (where the object rests on its support), and the support plane as
  the plane under the object's lowest point along it. The scene's world puts that plane at z = 0 (the
  table top) with z up, the object's first position above the origin. A recording without objects (a
  hand-only sequence, :func:`hand_only_frame`) has nothing resting on a support: gravity is the hint
  itself, there is no table, and the (first) hand's first root position is the origin.
* **Glove only** (:func:`glove_scene`; GraspDB14): the hand's root is fixed, palm down, and the object is
  placed where it fits in the closing hand and the recorded closing grips it best
  (:mod:`handsim.sim.placement.place`), held there by a support weld that the replay switches off
  :attr:`MetricSpec.release_delay` after the grasp has closed.
"""

from __future__ import annotations

from collections.abc import Mapping

import mujoco
import numpy as np
import numpy.typing as npt

from handsim.builders.objects import object_points
from handsim.builders.scene import attach_hand, build_scene
from handsim.datatypes.poses import compose, transform_points
from handsim.datatypes.rotations import quat_multiply, quat_rotate, rotation_onto
from handsim.datatypes.trajectory import Trajectory
from handsim.errors import ModelError, TrajectoryError
from handsim.sim.control import DEFAULT_CONTROL_RATE
from handsim.sim.placement.candidates import Candidate, Placement
from handsim.sim.placement.grasp_frame import GraspFrame, grasp_frame
from handsim.sim.placement.hand_pose import hand_frame
from handsim.sim.placement.place import place_object
from handsim.sim.scene.compiled import SceneSetup, SimScene, compile_scene
from handsim.sim.specs import MetricSpec

CAMERA_DOWN = (0.0, 1.0, 0.0)
"""Image down (+y) of a pinhole camera frame, e.g. the Tzionas rigging world (extrinsics identity)."""
HOLD_HEIGHT = 0.25
"""Glove scenario: the object's lowest point starts this far above the table top, m."""


def support_frame(
    points: np.ndarray, start_pose: np.ndarray, gravity_hint: npt.ArrayLike = CAMERA_DOWN
) -> tuple[np.ndarray, np.ndarray, str]:
    """World frame for a recording whose object rests on a support at its first frame.

    Args:
        points: The object's collision points in its frame (:func:`object_points`), m.
        start_pose: The object's recorded pose at the first frame (recording frame).
        gravity_hint: Roughly "down" in the recording frame.

    Returns:
        ``world_from_recording`` pose (z up, the support plane at z = 0, the object's first position above
        the origin), the gravity direction in the recording frame, and a note.
    """
    hint = np.asarray(gravity_hint, dtype=float)
    hint = hint / np.linalg.norm(hint)
    axes = np.vstack([np.eye(3), -np.eye(3)])
    world_axes = quat_rotate(start_pose[3:], axes)
    best = int(np.argmax(world_axes @ hint))
    down = world_axes[best]
    turn = rotation_onto(down, np.array([0.0, 0.0, -1.0]))
    rotated = quat_rotate(turn, transform_points(start_pose, points))
    origin = quat_rotate(turn, start_pose[:3])
    shift = np.array([-origin[0], -origin[1], -rotated[:, 2].min()])
    tilt = np.degrees(np.arccos(np.clip(down @ hint, -1, 1)))
    label = ["+x", "+y", "+z", "-x", "-y", "-z"][best]
    note = (
        f"gravity = the object's {label} axis at the first frame, {tilt:.1f}° from the hint "
        f"{hint.round(3).tolist()}; "
        "the support plane (table top, z = 0) is under its lowest point"
    )
    return np.concatenate([shift, turn]), down, note


def hand_only_frame(
    root_pose: np.ndarray, gravity_hint: npt.ArrayLike = CAMERA_DOWN
) -> tuple[np.ndarray, str]:
    """World frame for a recording without objects: gravity along the hint, the first root at the origin.

    Nothing in such a recording rests on a support, so no object face or support plane can say where "down"
    is; the hint (image down of the camera frame for a Tzionas sequence) is taken as it is.

    Args:
        root_pose: The hand root's recorded pose at the first frame (recording frame; x, y, z, qw … qz).
        gravity_hint: "Down" in the recording frame.

    Returns:
        ``world_from_recording`` pose (z up, gravity along the hint, the first root position at the origin)
        and a note.
    """
    hint = np.asarray(gravity_hint, dtype=float)
    hint = hint / np.linalg.norm(hint)
    turn = rotation_onto(hint, np.array([0.0, 0.0, -1.0]))
    origin = quat_rotate(turn, np.asarray(root_pose, dtype=float)[:3])
    note = (
        f"no object: gravity along the hint {hint.round(3).tolist()} (nothing rests on a support to say "
        "where down is); no table; the hand's root at the first frame is the world origin"
    )
    return np.concatenate([-origin, turn]), note


def attach_welded_hands(
    spec: mujoco.MjSpec, hands: Mapping[str, mujoco.MjSpec], trajectory: Trajectory
) -> None:
    """Attach several hands to a scene, each root welded to its mocap body following ``hand_roots[name]``.

    Args:
        spec: The scene (changed in place).
        hands: Hand specs by name (``"right"``, ``"left"``), their root bodies without DoFs; attached under
            ``hand/<name>/`` (DoFs ``<name>/<dof>``) in this order.
        trajectory: The recording; it must hold a root pose for each hand in ``hand_roots``.

    Raises:
        TrajectoryError: A hand without a root pose.
    """
    lacking = [name for name in hands if name not in trajectory.hand_roots]
    if lacking:
        raise TrajectoryError(
            f"{trajectory.source or 'trajectory'}: no root pose for the hands {lacking}; it has "
            f"{list(trajectory.hand_roots)}"
        )
    for name, hand in hands.items():
        attach_hand(spec, hand, name=name, root="weld")


def recorded_scene(
    hand: mujoco.MjSpec | Mapping[str, mujoco.MjSpec],
    trajectory: Trajectory,
    objects: Mapping[str, mujoco.MjSpec],
    *,
    gravity_hint: npt.ArrayLike = CAMERA_DOWN,
    table: bool = True,
) -> SimScene:
    """Scene for a recording with object tracks: the hand follows its root pose, the objects are free.

    Without objects (a hand-only sequence) the world comes from :func:`hand_only_frame` and there is no
    table.

    Args:
        hand: The hand (root without DoFs of its own; its root body's world pose is the trajectory's
            ``root_pose``), or several hands by name (:func:`attach_welded_hands`: each root's world pose is
            the trajectory's ``hand_roots[name]``; a hand-only recording's world comes from the first).
        trajectory: With ``root_pose`` (``hand_roots`` for several hands) and a track in ``objects`` for
            each key of ``objects``.
        objects: Object specs (:func:`handsim.builders.build_object`) by track name; the first defines the
            support plane. Empty for a hand-only sequence.
        gravity_hint: Roughly "down" in the recording frame (default: image down of a camera frame).
        table: Add the table under the support plane (never without objects).

    Returns:
        The compiled scene (scenario ``recorded``).

    Raises:
        TrajectoryError: No root pose (for a hand), or an object without a track.
        ModelError: ``hand`` is an empty mapping.
    """
    several = not isinstance(hand, mujoco.MjSpec)
    if several and not hand:
        raise ModelError("recorded_scene needs a hand; got an empty mapping of hands")
    if not several and trajectory.root_pose is None:
        raise TrajectoryError(f"{trajectory.source or 'trajectory'}: no root pose to follow")
    if not objects:
        if several:
            spec = build_scene(None, [], table=False)
            attach_welded_hands(spec, hand, trajectory)
            root = trajectory.hand_roots[next(iter(hand))]
        else:
            spec = build_scene(hand, [], hand_pos=(0.0, 0.0, 0.0), table=False, hand_root="weld")
            root = trajectory.root_pose
        world, note = hand_only_frame(np.asarray(root[0], dtype=float), gravity_hint)
        setup = SceneSetup(scenario="recorded", world_from_recording=tuple(world.tolist()), notes=(note,))
        return compile_scene(spec, setup)
    missing = [k for k in objects if k not in trajectory.objects]
    if missing:
        raise TrajectoryError(
            f"{trajectory.source or 'trajectory'}: no track for objects {missing}; "
            f"tracks: {list(trajectory.objects)}"
        )
    keys = list(objects)
    first = np.asarray(trajectory.objects[keys[0]].pose[0], dtype=float)
    world, _, note = support_frame(object_points(objects[keys[0]]), first, gravity_hint)
    end_note = _end_rest_note(object_points(objects[keys[0]]), trajectory.objects[keys[0]].pose[-1], world)
    poses = [compose(world, np.asarray(trajectory.objects[k].pose[0], dtype=float)) for k in keys]
    specs = [objects[k] for k in keys]
    if several:
        spec = build_scene(None, specs, object_poses=poses, table=table)
        attach_welded_hands(spec, hand, trajectory)
    else:
        spec = build_scene(
            hand, specs, hand_pos=(0.0, 0.0, 0.0), object_poses=poses, table=table, hand_root="weld"
        )
    setup = SceneSetup(
        scenario="recorded",
        world_from_recording=tuple(world.tolist()),
        object_tracks=tuple(keys),
        notes=(note, end_note),
    )
    return compile_scene(spec, setup)


def _end_rest_note(points: np.ndarray, end_pose: np.ndarray, world: np.ndarray) -> str:
    lowest = transform_points(compose(world, np.asarray(end_pose, dtype=float)), points)[:, 2].min()
    return f"at the last frame the object's lowest point is {lowest * 1000:+.1f} mm from the support plane"


AXES = {
    "+x": np.array([1.0, 0.0, 0.0]),
    "-x": np.array([-1.0, 0.0, 0.0]),
    "+y": np.array([0.0, 1.0, 0.0]),
    "-y": np.array([0.0, -1.0, 0.0]),
    "+z": np.array([0.0, 0.0, 1.0]),
    "-z": np.array([0.0, 0.0, -1.0]),
}
"""The grip test's gravity directions in the placement search's world (the hand fingers +x, palm −z)."""
PALM_DOWN = "-z"
PALM_UP = "+z"
"""Gravity into the palm: an object lying on an open hand is no grasp (Feix et al. 2016, "The GRASP taxonomy
of human grasp types", IEEE Trans Hum-Mach Syst 46(1): "gravity-dependent grasps such as an object lying in
equilibrium on a flat hand" are ruled out; GraspDB14's report §3.6 adopts that definition), so the hold is
never judged palm up."""


def hold_down(placed: Candidate, orientation: str) -> tuple[str, str]:
    """Which of the grip test's gravity directions becomes "down" for the hold, and a note saying why.

    Args:
        placed: The placement's winner (with its grip test).
        orientation: :attr:`MetricSpec.hold_orientation`.

    Returns:
        A key of :data:`AXES` and the note.
    """
    why = "GraspDB14's objects are picked up from a table; the hand's orientation is not recorded"
    if orientation == "palm down" or placed.grip is None:
        return PALM_DOWN, f"hand palm down ({why})"
    results = {d.direction: d for d in placed.grip.stability.directions}
    if results[PALM_DOWN].success:
        return PALM_DOWN, f"hand palm down ({why}; its grip resists gravity that way)"
    held = sorted(
        (d.displacement, d.direction) for d in results.values() if d.success and d.direction != PALM_UP
    )
    if not held:
        return PALM_DOWN, (
            f"hand palm down ({why}; its grip resists gravity in no direction but into the palm, and an "
            "object lying on an open hand is no grasp)"
            if results[PALM_UP].success
            else f"hand palm down ({why}; its grip resists gravity in no direction)"
        )
    down = held[0][1]
    return down, (
        f"hand turned so that gravity pulls along the grip's {down} (the direction it resists best: "
        f"{held[0][0] * 1000:.1f} mm in the grip test), not palm down, which it does not resist ({why})"
    )


def glove_scene(
    hand: mujoco.MjSpec,
    trajectory: Trajectory,
    obj: mujoco.MjSpec,
    *,
    grasp: GraspFrame | None = None,
    spec: MetricSpec | None = None,
    control_rate: float = DEFAULT_CONTROL_RATE,
) -> SimScene:
    """Scene for a glove recording: hand fixed palm down, the object where the recorded closing grips it.

    Args:
        hand: The hand the trajectory drives (its root fixed; wrist DoFs stay hinges).
        trajectory: Joint targets named like the hand's DoFs.
        obj: The object (:func:`handsim.builders.build_object`).
        grasp: The grasp frames and hold window; default
            :func:`~handsim.sim.placement.grasp_frame.grasp_frame` (the
            ``grasp`` phase, else peak flexion).
        spec: Placement, release and robustness parameters (default :class:`MetricSpec`).
        control_rate: Control frames per second of the replays the placement's grip tests reproduce.

    Returns:
        The compiled scene (scenario ``glove``) with the object on an active support. Its setup's
        ``placement`` holds the search's result and the robustness ensemble's poses in the scene's world.
    """
    spec = spec or MetricSpec()
    grasp = grasp or grasp_frame(trajectory)
    quat, placement = _placed(hand, trajectory, obj, grasp, spec, control_rate)
    best = placement.best
    down, down_note = hold_down(best, spec.hold_orientation)
    turn = rotation_onto(AXES[down], np.array([0.0, 0.0, -1.0]))
    world = _hold_world(best, turn, placement.object_points)  # search world → scene world
    scene = build_scene(
        hand, obj, hand_pos=tuple(world[:3]), hand_quat=quat_multiply(turn, quat),
        object_poses=[compose(world, best.pose)], object_support=True,
    )  # fmt: skip
    times = trajectory.times
    setup = SceneSetup(
        scenario="glove",
        contact_time=float(times[best.contact_frame]),
        release_time=float(times[grasp.closed]),
        grasp_time=float(times[grasp.frame]),
        hold_window=(float(times[grasp.window[0]]), float(times[grasp.window[1]])),
        placement={
            **placement.to_dict(),
            "grasp": grasp.to_dict(),
            "contact_trajectory_frame": best.contact_frame,
            "ensemble": _ensemble(placement, world, times),
            "gravity_along": down,
        },
        notes=(
            grasp.note,
            placement.note,
            _contact_note(best, times),
            f"{down_note}; the object's lowest point {HOLD_HEIGHT} m up",
        ),
    )
    return compile_scene(scene, setup)


def _placed(
    hand: mujoco.MjSpec,
    trajectory: Trajectory,
    obj: mujoco.MjSpec,
    grasp: GraspFrame,
    spec: MetricSpec,
    control_rate: float,
) -> tuple[np.ndarray, Placement]:
    """The hand's orientation in the placement search's world (fingers +x, palm −z) and the placement."""
    probe = compile_scene(build_scene(hand, table=False))  # the hand alone: its frame needs no object
    quat = hand_frame(probe)
    search = compile_scene(
        build_scene(hand, obj, hand_quat=quat, hand_pos=(0.0, 0.0, 0.0), table=False, object_support=True)
    )
    placement = place_object(
        search,
        trajectory,
        grasp,
        spec.placement,
        spec.release_delay,
        control_rate,
        shift=spec.robustness_shift,
        turn_deg=spec.robustness_turn_deg,
    )
    return quat, placement


def _hold_world(best: Candidate, turn: np.ndarray, object_points: np.ndarray) -> np.ndarray:
    """The search world's pose in the scene's world: turned by ``turn``, the object :data:`HOLD_HEIGHT` up."""
    lowest = transform_points(compose(np.concatenate([[0.0, 0.0, 0.0], turn]), best.pose), object_points)
    return np.concatenate([[0.0, 0.0, HOLD_HEIGHT - lowest[:, 2].min()], turn])


def _ensemble(placement: Placement, world: np.ndarray, times: np.ndarray) -> list[dict]:
    """The robustness ensemble's poses in the scene's world: the alternatives, then the perturbations."""
    return [
        {
            "label": label,
            "pose": compose(world, c.pose).tolist(),
            "contact_time": float(times[c.contact_frame]),
        }
        for label, c in (
            *((f"alternative {i + 1}", c) for i, c in enumerate(placement.alternatives)),
            *placement.perturbations,
        )
    ]


def _contact_note(best: Candidate, times: np.ndarray) -> str:
    """When the hand–object contacts start acting, and how deep the hand is in the object just before."""
    if best.contact_frame > 0:
        return (
            f"hand–object contacts act from frame {best.contact_frame} ({times[best.contact_frame]:.3f} s); "
            f"at frame {best.contact_frame - 1} the hand at its targets is "
            f"{best.depth_before_contact * 1000:.1f} mm inside the placed object"
        )
    return "the hand is clear of the placed object from frame 0"
