"""The ARCTIC-shaped benchmark scene: two mean-shape MANO hands carry a box, then one opens its lid.

A synthetic recording shaped like ARCTIC's grab and use sequences (10 s at 30 fps, z-up, the object's pose
and articulation in the recording's world), whose object track is what the hands do, as ARCTIC's fits are:

* **Carry** (0–5 s): both hands, flat (every joint target 0), come in from 2 cm beside the box's long sides
  and press them between palms and fingers (the wrists :data:`GRIP` from the box's mid-plane; a flat hand
  touches at about 108 mm, the sides are at 80 mm), lift the box 10 cm, carry it 5 cm sideways (along y,
  across the palms) and back, set it down on its stand and let go. The recorded box moves exactly as the
  wrists do while they hold it.
* **Lid** (5–10 s): the right hand goes round the box's free end, turns palm up with its fingers pointing
  at the box, slides its fingertips under the lid's lip (the lid overhangs its base by :data:`LIP` at the
  free end, as a box lid does where it is lifted) and lifts the lid :data:`OPENING` about the hinge, rotating
  with it. The recorded articulation is the hand's rotation about the hinge: the fingertips stay where they
  touch the lid. The lid's own weight keeps it on them.

The box is the benchmark's template (ARCTIC's layout: millimetres, canonical +y up, hinge on z, closed at
0): a 120 × 60 × 160 mm base and a 150 × 10 × 160 mm lid hinged on its top edge, stood upright with its base
on the support plane. Both parts' masses are ARCTIC's box's (0.75 kg, spread by volume).
"""

from __future__ import annotations

import itertools
import math
import tempfile
from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np
import numpy.typing as npt
import trimesh

from handsim.builders.arctic_objects import arctic_object
from handsim.builders.mano_hand import build_mano_hand, mano_hand_skeleton
from handsim.builders.objects import build_object
from handsim.datatypes.poses import compose
from handsim.datatypes.rotations import matrix_to_quat, quat_about, quat_rotate, slerp
from handsim.datatypes.trajectory import ObjectTrack, Trajectory
from handsim.sim.arctic_scene import arctic_scene
from handsim.sim.scene.compiled import SimScene

FPS = 30.0
FRAMES = 300
TRACK = "box"
UPRIGHT = (math.cos(math.pi / 4), math.sin(math.pi / 4), 0.0, 0.0)
"""The box's orientation: canonical +y (its lid's normal) → world +z, the hinge axis → world +y."""
BOX_ORIGIN = np.array([0.0, 0.0, 0.06])
"""The box's origin at rest, m: the lid's hinge, on the base's top edge at x = 0 (its bottom at z = 0)."""
HINGE_AXIS = np.array([0.0, 1.0, 0.0])
"""The hinge's axis in the world at rest: positive angles lift the lid's free end (x = −150 mm)."""
LIP = 30.0
"""How far the lid overhangs its base at the free end, mm: room under it for three fingertips."""
GRIP = 0.098
"""The wrists' distance from the box's mid-plane while they hold it, m: a flat hand touches at about 0.108,
so the palms press by about as much as the soft pads give (the replay follows the box at 0.098 and 0.100;
at 0.102 it turns out of the palms while carried)."""
GRIP_X = 0.0
"""The wrists' x while they hold the box, m: at the hinge end, so the flat hands (19 cm from wrist to middle
fingertip) lie along the 12 cm box with its centre of mass (x = −60 mm) under their middle; with the wrists
40 mm further out the box turns out of the grip while carried."""
LIFT = 0.10
"""How high the hands lift the box, m."""
CARRY = 0.05
"""How far along y (towards the right hand, across the palms) the hands carry the box while it is lifted
(and back), m."""
OPENING = math.radians(60.0)
"""How far the right hand opens the lid, radians."""
FLAT_RIGHT = (1.0, 0.0, 0.0, 0.0)
"""The right wrist's orientation holding the box: palm towards −y (the box), fingers along −x, thumb up."""
FLAT_LEFT = (0.0, 0.0, 0.0, 1.0)
"""The left wrist's orientation holding the box: palm towards +y, fingers along −x, thumb up (the mirror of
the right hand's)."""
PALM_UP = tuple(matrix_to_quat(np.array([[-1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, -1.0, 0.0]])))
"""The right wrist's orientation under the lid: palm up, fingers along +x (at the box), thumb towards −y."""
UNDER_LID = np.array([-0.312, -0.01, 0.0468])
"""The right wrist under the lid, m: the middle fingertip 4 mm from the base's end wall, the three longest
fingertips' pads touching the lid's lip from below (measured on the compiled hand, 0.5 mm in)."""

Key = tuple[float, npt.ArrayLike, npt.ArrayLike]
"""A keyframe: time (s), wrist position (m), wrist orientation (w, x, y, z)."""

CARRIED: tuple[tuple[float, tuple[float, float, float]], ...] = (
    (0.6, (0.0, 0.0, 0.0)),
    (1.0, (0.0, 0.0, 0.0)),
    (1.8, (0.0, 0.0, LIFT)),
    (2.6, (0.0, CARRY, LIFT)),
    (3.4, (0.0, 0.0, LIFT)),
    (4.2, (0.0, 0.0, 0.0)),
    (4.4, (0.0, 0.0, 0.0)),
)
"""The box's displacement from rest while the hands hold it: (time s, (x, y, z) m); in from 0 to 0.6 s."""
LID_LIFT = (8.0, 9.3)
"""When the right hand lifts the lid from closed to :data:`OPENING`, s."""


@dataclass(frozen=True)
class ArcticCase:
    """The benchmark scene and what it is built from.

    Attributes:
        scene: The compiled scene (:func:`handsim.sim.arctic_scene.arctic_scene`).
        trajectory: The synthetic recording.
        hands: The two mean-shape MANO hands' specs, by side.
        box: The box's spec.
    """

    scene: SimScene
    trajectory: Trajectory
    hands: dict[str, mujoco.MjSpec]
    box: mujoco.MjSpec


def box_template(folder: Path) -> Path:
    """Write the box's template (two OBJ parts, mm, ARCTIC's layout) under ``folder/box`` and return it."""
    out = folder / "box"
    out.mkdir()
    for name, x, y in (("bottom", (-120.0, 0.0), (-60.0, 0.0)), ("top", (-120.0 - LIP, 0.0), (0.0, 10.0))):
        box = trimesh.creation.box(extents=(x[1] - x[0], y[1] - y[0], 160.0))
        box.apply_translation([(x[0] + x[1]) / 2, (y[0] + y[1]) / 2, 0.0])
        box.export(out / f"{name}.obj")
    return out


def ramp(t: np.ndarray, start: float, end: float) -> np.ndarray:
    """0 before ``start``, 1 after ``end``, a half cosine between (no jump in speed at either end)."""
    return 0.5 * (1.0 - np.cos(np.pi * np.clip((t - start) / (end - start), 0.0, 1.0)))


def keyframed(t: np.ndarray, keys: list[Key]) -> np.ndarray:
    """Wrist poses (T, 7) through ``keys``: each leg eased by :func:`ramp`, orientations by slerp."""
    poses = np.empty((len(t), 7))
    poses[:, :3], poses[:, 3:] = keys[0][1], keys[0][2]
    for (t0, p0, q0), (t1, p1, q1) in itertools.pairwise(keys):
        leg = t >= t0
        w = ramp(t[leg], t0, t1)
        start, end = np.asarray(p0, dtype=float), np.asarray(p1, dtype=float)
        poses[leg, :3] = start + w[:, None] * (end - start)
        poses[leg, 3:] = slerp(np.broadcast_to(q0, (leg.sum(), 4)), np.broadcast_to(q1, (leg.sum(), 4)), w)
    return poses


def about_hinge(poses: np.ndarray, angles: np.ndarray) -> np.ndarray:
    """Poses (T, 7) turned by ``angles`` (T,) about the box's hinge at rest (what the lid does)."""
    turn = quat_about(HINGE_AXIS, angles)
    return compose(np.column_stack([BOX_ORIGIN - quat_rotate(turn, BOX_ORIGIN), turn]), poses)


def _hand_keys(side: str, half_grip: float = GRIP) -> list[Key]:
    """The wrist's keyframes: in, the carry (holding the box as it moves), out; the right hand to the lid.

    ``half_grip``: the wrists' distance from the box's mid-plane while they carry it, m.
    """
    sign, flat = (1.0, FLAT_RIGHT) if side == "right" else (-1.0, FLAT_LEFT)
    grip = np.array([GRIP_X, sign * half_grip, 0.04])
    out = np.array([0.0, sign * 0.02, 0.0])
    keys: list[Key] = [(0.0, grip + out, flat)]
    keys += [(time, grip + np.asarray(moved), flat) for time, moved in CARRIED]
    keys += [(5.0, grip + out, flat), (5.5, grip + 5 * out, flat)]
    if side == "right":  # round the box's free end, turning palm up, then in under the lip and up to it
        keys += [
            (6.1, np.array([-0.40, 0.2, 0.04]), flat),
            (7.2, UNDER_LID + np.array([-0.05, 0.0, -0.025]), PALM_UP),
            (7.5, UNDER_LID + np.array([0.0, 0.0, -0.025]), PALM_UP),
            (7.8, UNDER_LID, PALM_UP),
        ]
    return keys


def recording(half_grip: float = GRIP) -> tuple[Trajectory, dict[str, mujoco.MjSpec]]:
    """The synthetic recording and the two mean-shape MANO hands (built with fixed roots) it drives.

    ``half_grip``: the wrists' distance from the box's mid-plane in the carry (:data:`GRIP`; 0.102 m, 4 mm
    out, is a recording the replay does not carry: a capture error of the kind a correction should mend).
    """
    t = np.arange(FRAMES) / FPS
    opening = OPENING * ramp(t, *LID_LIFT)
    pose = np.tile([*BOX_ORIGIN, *UPRIGHT], (FRAMES, 1))
    still = np.array([1.0, 0.0, 0.0, 0.0])
    pose[:, :3] += keyframed(t, [(time, moved, still) for time, moved in CARRIED])[:, :3]
    columns: list[str] = []
    roots, hands = {}, {}
    for side in ("right", "left"):
        hands[side] = build_mano_hand(side=side, root="fixed")
        columns += [f"{side}/{d}" for d in mano_hand_skeleton(side=side).dof_names]
        roots[side] = keyframed(t, _hand_keys(side, half_grip))
    roots["right"] = about_hinge(roots["right"], opening)
    trajectory = Trajectory(
        t,
        tuple(columns),
        np.zeros((FRAMES, len(columns))),
        np.ones((FRAMES, len(columns)), bool),
        objects={TRACK: ObjectTrack(pose=pose, articulation=opening)},
        hand_roots=roots,
    )
    return trajectory, hands


def arctic_case_scene(half_grip: float = GRIP) -> ArcticCase:
    """The benchmark's ARCTIC-shaped scene, built from :func:`recording` and :func:`box_template`."""
    trajectory, hands = recording(half_grip)
    with tempfile.TemporaryDirectory() as folder:
        model = arctic_object(box_template(Path(folder)), articulation=trajectory.objects[TRACK].articulation)
        box = build_object(model)
    return ArcticCase(arctic_scene(hands, trajectory, box, TRACK), trajectory, hands, box)
