"""The ARCTIC scene: two MANO hands following their recorded wrists, one articulated object, free.

ARCTIC's world is z-up (its capture studio's floor frame), so, unlike
:func:`handsim.sim.scenarios.recorded_scene` (camera-frame recordings have no "up"), the scene keeps the
recording's axes: gravity is world −z and nothing is snapped to an object axis. The recording is only
shifted: the object's origin at frame 0 goes above the scene's origin and its lowest collision point at
frame 0 onto the support plane (z = 0).

The world is what the recording allows (the rule is in ``docs/arctic.md``):

* **The support is a stand**, not a table: a column from the support plane down to the floor whose top is
  the object's footprint at frame 0 (:mod:`handsim.sim.scene.support`); none where the recording moves the
  object up or down from its first frame (lifted, or falling). The floor lies :data:`FLOOR_DEPTH` below the
  support plane.
* **The recorded hands pass through no static body**: every hand site (each MANO joint and fingertip) at
  every recorded frame is checked against the stand and the floor (:mod:`handsim.sim.scene.clearance`); a
  body one passes more than :data:`PASS_DEPTH` into is shrunk (the stand, cut back out of the hands' way,
  never below the disc around the object's centre of mass it needs) or moved (the floor, down to the lowest
  recorded point), with a note naming it; where no stand avoids them, the note says so and the replay is
  flagged (``static_body_in_path``).
* **Nothing starts inside anything unnoticed**: the lid starts at the angle nearest the recorded one at
  which it is not inside its base, or the contact pairs that overlap at every nearby angle are excluded (the
  hinge's stop keeps the lid out of its base) (:func:`handsim.sim.scene.settle.settle_hinge`); each hand's
  starting penetration of the object is measured and noted.

Each hand is attached under ``hand/<side>/`` (DoFs ``<side>/<dof>``), its wrist freed and welded to a mocap
body ``hand_target/<side>`` that follows the trajectory's ``hand_roots[side]``; the object is attached under
``obj/`` at its recorded pose, its hinge at the recorded articulation (clamped into the hinge's range: ARCTIC
fits may start a few degrees below the closed pose, and the notes say so).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, replace

import mujoco
import numpy as np

from handsim.builders.scene import FLOOR, STAND, add_floor, add_stand, build_scene
from handsim.datatypes.poses import compose
from handsim.datatypes.trajectory import Trajectory
from handsim.errors import TrajectoryError
from handsim.sim.scenarios import attach_welded_hands
from handsim.sim.scene.clearance import HandPaths, Passage, hand_paths, passages, recorded_qpos
from handsim.sim.scene.compiled import SceneSetup, SimScene, compile_scene
from handsim.sim.scene.model import compile_spec
from handsim.sim.scene.settle import HingeStart, hand_penetration, settle_hinge
from handsim.sim.scene.support import (
    STAND_MIN_RADIUS,
    START_MOTION,
    START_WINDOW,
    collision_points,
    footprint,
    polygon_area,
    shrink_outline,
    vertical_motion,
)

FLOOR_DEPTH = 0.75
"""The floor lies this far below the support plane, m (a table's height, as in every handsim scene), unless a
recorded hand goes lower."""
PASS_DEPTH = 0.01
"""A recorded hand passes through a static body when one of its joints or fingertips lies more than this
inside it, m: MANO's joints lie 6–10 mm under the skin, so a joint this deep puts the skin around it well
inside, past any touch."""
_CUT_CLEARANCE = 1e-5
"""A stand's cut leaves the point it clears this much (m) less than :data:`PASS_DEPTH` inside: MuJoCo stores
meshes in single precision."""


@dataclass(frozen=True)
class ObjectStart:
    """An object at its first recorded frame, in the recording's frame.

    Attributes:
        points: Its collision points, m (M, 3).
        com: Its centre of mass (both parts), m (3,).
        angle: The hinge angle used (the recorded one clamped into the hinge's range; NaN without a hinge).
    """

    points: np.ndarray
    com: np.ndarray
    angle: float


def object_at_start(obj: mujoco.MjSpec, pose: np.ndarray, articulation: float | None) -> ObjectStart:
    """An object's collision points and centre of mass at a pose and articulation.

    Args:
        obj: The object (:func:`handsim.builders.build_object`).
        pose: Its root's pose (x, y, z, qw, qx, qy, qz), metres.
        articulation: Its hinge angle, radians (clamped into the hinge's range), or None for none.
    """
    model = compile_spec(obj)
    data = mujoco.MjData(model)
    data.qpos[:7] = pose
    angle = math.nan
    hinges = [j for j in range(model.njnt) if int(model.jnt_type[j]) == int(mujoco.mjtJoint.mjJNT_HINGE)]
    if hinges and articulation is not None:
        joint = hinges[0]
        angle = float(articulation)
        if model.jnt_limited[joint]:
            angle = float(np.clip(angle, *model.jnt_range[joint]))
        data.qpos[model.jnt_qposadr[joint]] = angle
    mujoco.mj_kinematics(model, data)
    mujoco.mj_comPos(model, data)
    geoms = [g for g in range(model.ngeom) if model.geom_contype[g] or model.geom_conaffinity[g]]
    return ObjectStart(collision_points(model, data, geoms), data.subtree_com[1].copy(), angle)


def lowest_point(obj: mujoco.MjSpec, pose: np.ndarray, articulation: float | None) -> tuple[float, float]:
    """The lowest world z of an object's collision geometry at a pose and articulation.

    Args:
        obj: The object (:func:`handsim.builders.build_object`).
        pose: Its root's pose (x, y, z, qw, qx, qy, qz), metres.
        articulation: Its hinge angle, radians (clamped into the hinge's range), or None for none.

    Returns:
        The lowest z, metres, and the hinge angle used (the clamped articulation; NaN without a hinge).
    """
    start = object_at_start(obj, pose, articulation)
    return float(start.points[:, 2].min()), start.angle


def _spec(
    hands: Mapping[str, mujoco.MjSpec],
    trajectory: Trajectory,
    obj: mujoco.MjSpec,
    placed: np.ndarray,
    world: tuple[np.ndarray | None, float | None],
    excluded: Mapping[str, float],
) -> mujoco.MjSpec:
    """The scene's spec: the object at ``placed``, the stand and floor of ``world``, the welded hands.

    The object's contact pairs named in ``excluded`` are left out.
    """
    outline, floor = world
    spec = build_scene(None, [obj], object_poses=[placed], table=False)
    if floor is not None:
        add_floor(spec, floor)
        if outline is not None:
            add_stand(spec, outline, floor)
    attach_welded_hands(spec, hands, trajectory)
    for pair in list(spec.pairs):
        if pair.name in excluded:
            spec.delete(pair)
    return spec


def _passage(found: Passage) -> dict:
    return {
        "body": found.body,
        "depth_mm": found.depth * 1000.0,
        "site": found.label,
        "time_s": found.time,
        "frames": found.frames,
    }


@dataclass(frozen=True)
class _World:
    """The static bodies decided so far: the stand's top (None: no stand), the floor (None: none), notes."""

    outline: np.ndarray | None
    floor: float | None
    notes: tuple[str, ...]
    blocked: tuple[str, ...] = ()


def _fit_world(world: _World, found: dict[str, Passage], paths: HandPaths, centre: np.ndarray) -> _World:
    """Shrink the stand and lower the floor out of the recorded hands' way (see the module notes)."""
    outline, floor, notes, blocked = world.outline, world.floor, list(world.notes), []
    points = paths.points.reshape(-1, 3)
    if floor is not None and found[FLOOR].depth > PASS_DEPTH:
        lowest = float(points[:, 2].min())
        notes.append(f"the floor is moved from {floor:.3f} m to {lowest:.3f} m: {found[FLOOR].describe()}")
        floor = lowest
    if outline is not None and floor is not None and found[STAND].depth > PASS_DEPTH:
        shrunk = shrink_outline(outline, centre[:2], points, floor, PASS_DEPTH - _CUT_CLEARANCE)
        before, after = polygon_area(outline) * 1e4, polygon_area(shrunk.outline) * 1e4
        notes.append(
            f"the stand is shrunk from {before:.0f} cm² to {after:.0f} cm² ({shrunk.cuts} "
            f"cut{'' if shrunk.cuts == 1 else 's'}), out of the "
            f"recorded hands' way: {found[STAND].describe()}"
        )
        outline = shrunk.outline
        for k in shrunk.blocked[:3]:
            frame, site = divmod(k, paths.points.shape[1])
            blocked.append(f"{paths.labels[site]} at {paths.times[frame]:.2f} s")
        if shrunk.blocked:
            notes.append(
                f"no stand fits the recording: {len(shrunk.blocked)} recorded hand points pass under the "
                f"object within {STAND_MIN_RADIUS * 1000:g} mm of its centre of mass, deeper than "
                f"{PASS_DEPTH * 1000:g} mm below its resting height ({', '.join(blocked)}); the stand keeps "
                "the disc the object needs and the replay is flagged"
            )
    return _World(outline, floor, tuple(notes), tuple(blocked))


def _support(
    trajectory: Trajectory, track: str, at_start: ObjectStart, shift: np.ndarray
) -> tuple[np.ndarray | None, dict]:
    """The object's support: a stand's top (None: none) and what to record of it, with its ``note``."""
    motion = vertical_motion(trajectory.times, np.asarray(trajectory.objects[track].pose)[:, :3])
    if motion > START_MOTION:
        return None, {
            "kind": "none",
            "note": f"no support: the recording holds the object off it from its first frame (its origin "
            f"moves {motion * 1000:.1f} mm up or down within {START_WINDOW:g} s)",
        }
    outline = footprint(at_start.points + shift)
    area = polygon_area(outline) * 1e4
    return outline, {
        "kind": "stand",
        "footprint_cm2": area,
        "note": f"support: a stand under the object's footprint at frame 0 ({area:.0f} cm², from the support "
        f"plane down to the floor {FLOOR_DEPTH:g} m below)",
    }


@dataclass(frozen=True)
class _Start:
    """The recording's frame 0 in the scene: the object's start, the world shift and the first notes."""

    at_start: ObjectStart
    world: np.ndarray
    placed: np.ndarray
    notes: tuple[str, ...]


def _start(trajectory: Trajectory, obj: mujoco.MjSpec, track: str) -> _Start:
    """The object at frame 0 and the shift putting its origin above the scene's and its lowest point at z = 0.

    Raises:
        TrajectoryError: The object's track missing.
    """
    if track not in trajectory.objects:
        raise TrajectoryError(
            f"{trajectory.source or 'trajectory'}: no object track {track!r}; "
            f"it has {list(trajectory.objects)}"
        )
    recorded = trajectory.objects[track]
    start = np.asarray(recorded.pose[0], dtype=float)
    first = None if recorded.articulation is None else float(recorded.articulation[0])
    at_start = object_at_start(obj, start, first)
    lowest = float(at_start.points[:, 2].min())
    world = np.array([-start[0], -start[1], -lowest, 1.0, 0.0, 0.0, 0.0])
    notes = [
        "gravity = world −z (ARCTIC's world is z-up; no axis snapped); the recording is shifted by "
        f"{(world[:3] * 1000).round(1).tolist()} mm: the object's origin at frame 0 above the origin, the "
        "support plane (z = 0) under its lowest point at frame 0",
    ]
    if first is not None and not math.isnan(at_start.angle) and at_start.angle != first:
        notes.append(
            f"the recorded articulation at frame 0 ({math.degrees(first):.1f}°) is outside the hinge's "
            f"range: the object starts at {math.degrees(at_start.angle):.1f}°, its stop (drift is still "
            "measured against the recording)"
        )
    return _Start(at_start, world, compose(world, start), tuple(notes))


@dataclass(frozen=True)
class _Checked:
    """The scene as the checks before the run left it, and what they found."""

    scene: SimScene
    data: mujoco.MjData
    world: _World
    found: dict[str, Passage]
    hinge: HingeStart | None


def _check(
    scene: SimScene,
    build: tuple[Mapping[str, mujoco.MjSpec], Trajectory, mujoco.MjSpec],
    first: _Start,
    world: _World,
    track: str,
) -> _Checked:
    """Run the checks before the run (see the module notes) and recompile the scene where they change it.

    Args:
        scene: The scene as first built.
        build: The hands, the trajectory and the object it was built from.
        first: The recording's frame 0 in the scene.
        world: Its static bodies as first built.
        track: The object's track.

    Returns:
        The checked scene with its data at frame 0 (the hinge at its settled start), the fitted world, each
        static body's deepest recorded hand point, the hinge's start (None: no hinge or none recorded).
    """
    hands, trajectory, obj = build
    data = mujoco.MjData(scene.model)
    paths = hand_paths(scene, trajectory, data)
    found = {p.body: p for p in passages(scene, paths, PASS_DEPTH, data)}
    fitted = _fit_world(world, found, paths, first.at_start.com + first.world[:3])
    data.qpos[:] = recorded_qpos(scene, trajectory, [0], clip=True)[0]
    hinge: HingeStart | None = None
    if scene.layout.objects[0].hinge_qpos >= 0 and trajectory.objects[track].articulation is not None:
        hinge = settle_hinge(scene.model, data, scene.layout.objects[0])
    excluded = {} if hinge is None else hinge.excluded
    if fitted.notes or excluded:
        spec = _spec(hands, trajectory, obj, first.placed, (fitted.outline, fitted.floor), excluded)
        scene = compile_scene(spec, scene.setup)
        data = mujoco.MjData(scene.model)
        found = {p.body: p for p in passages(scene, paths, PASS_DEPTH, data)}
        data.qpos[:] = recorded_qpos(scene, trajectory, [0], clip=True)[0]
    if hinge is not None:
        data.qpos[scene.layout.objects[0].hinge_qpos] = hinge.angle
    return _Checked(scene, data, fitted, found, hinge)


def _penetration_note(depths: Mapping[str, tuple[float, str, str]]) -> str:
    """The note on each hand's starting penetration of the object."""
    return "starting penetration (hands at their frame-0 targets, the object at its start): " + "; ".join(
        f"{name or 'hand'} {d * 1000:.1f} mm" + (f" ({link} in {part})" if link else "")
        for name, (d, link, part) in depths.items()
    )


def _found_before_run(checked: _Checked, support: dict, depths: Mapping[str, tuple[float, str, str]]) -> dict:
    """What the checks before the run found, JSON-ready (the setup's ``checks``)."""
    found, hinge = checked.found, checked.hinge
    return {
        "support": support,
        "floor_m": checked.world.floor,
        "passages": [_passage(p) for p in found.values()],
        "pass_depth_mm": PASS_DEPTH * 1000.0,
        "world_fits": all(p.depth <= PASS_DEPTH for p in found.values()),
        "blocked": list(checked.world.blocked),
        "hinge": None if hinge is None else hinge.to_dict(),
        "start_penetration_mm": {name: d * 1000.0 for name, (d, _, _) in depths.items()},
    }


def arctic_scene(
    hands: Mapping[str, mujoco.MjSpec],
    trajectory: Trajectory,
    obj: mujoco.MjSpec,
    track: str,
    *,
    table: bool = True,
    checks: bool = True,
) -> SimScene:
    """Scene for a two-hand recording in a z-up world with one recorded object (ARCTIC).

    Args:
        hands: Hand specs by name (``"right"``, ``"left"``), their root bodies without DoFs (their world pose
            is the trajectory's ``hand_roots[name]``).
        trajectory: DoF columns ``<name>/<dof>``, a root pose per hand in ``hand_roots``, the object's track.
        obj: The object (:func:`handsim.builders.build_object`).
        track: The object's track in ``trajectory.objects``.
        table: Add the object's support (a stand under its footprint) and the floor; False: neither.
        checks: Run the checks before the run (the world against the recorded hands, the parts' and hands'
            starting overlap) and apply what they decide; False: the scene as first built, unchecked (to
            time the checks, or to see what they change).

    Returns:
        The compiled scene (scenario ``recorded``); its setup's ``checks`` hold what the checks before the
        run found, its ``start_articulation`` the hinge's settled start.

    Raises:
        TrajectoryError: A hand without a root pose, or the object's track missing.
    """
    first = _start(trajectory, obj, track)
    notes = list(first.notes)
    outline, support = (
        _support(trajectory, track, first.at_start, first.world[:3]) if table else (None, {"kind": "none"})
    )
    if "note" in support:
        notes.append(support.pop("note"))
    world = _World(outline, -FLOOR_DEPTH if table else None, ())
    setup = SceneSetup(
        scenario="recorded", world_from_recording=tuple(first.world.tolist()), object_tracks=(track,)
    )
    scene = compile_scene(
        _spec(hands, trajectory, obj, first.placed, (world.outline, world.floor), {}), setup
    )
    if not checks:
        return replace(scene, setup=replace(setup, notes=tuple(notes)))
    checked = _check(scene, (hands, trajectory, obj), first, world, track)
    if checked.hinge is not None:
        notes.append(checked.hinge.note("the object"))
    notes += checked.world.notes
    depths = hand_penetration(checked.scene.model, checked.data, checked.scene.layout)
    notes.append(_penetration_note(depths))
    if outline is not None and checked.world.outline is not None:
        support["area_cm2"] = polygon_area(checked.world.outline) * 1e4
    return replace(
        checked.scene,
        setup=replace(
            setup,
            notes=tuple(notes),
            start_articulation=() if checked.hinge is None else (checked.hinge.angle,),
            checks=_found_before_run(checked, support, depths),
        ),
    )
