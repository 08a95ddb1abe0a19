"""Start states without overlap: an articulated object's parts, and how deep the hands start in the object.

A recording's first frame can put a lid a few millimetres inside its base: the template's parts are
decimated meshes collided as convex hulls, and the fitted angle has its own error. Started there, the
lid–base contacts push the parts apart at once, and the lid flies open before any hand touches it.
:func:`settle_hinge` chooses the start instead (MuJoCo's own collision detection on the compiled scene, the
parts' explicit contact pairs):

1. the recorded angle, when no pair overlaps by more than :data:`PART_OVERLAP_TOLERANCE` there;
2. else the angle nearest the recorded one, within :data:`SETTLE_MAX_TURN` and the hinge's range, at which
   none does (searched in steps of :data:`SETTLE_STEP`);
3. else (the hulls overlap at every such angle, as they do next to the hinge, where the parts meet) the
   angle that leaves the fewest contact pairs overlapping beyond the tolerance (the nearest of those), and
   each pair still overlapping there is excluded: those two hulls do not collide. Nothing is lost by it:
   the hinge's range never goes below the closed pose
   (:func:`handsim.builders.arctic_objects.arctic_hinge_range`), so its stop keeps the lid out of its base;
   the other pairs still collide. The overlap so excluded is the meshes' error, reported.
   (A negative contact margin cannot absorb it: between convex meshes MuJoCo reports a contact's distance
   shifted by the pair's margin, so the contact still pushes from the true surface, measured.)

:func:`hand_penetration` measures how deep each hand starts inside the objects (MuJoCo's contact depths).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import mujoco
import numpy as np

from handsim.sim.scene.layout import ObjectLayout, SceneLayout

PART_OVERLAP_TOLERANCE = 0.001
"""Largest overlap of two parts of an object at the start, m: MuJoCo's default ``solimp`` width (the parts'
contact pairs keep MuJoCo's default impedance), over which a contact's impedance rises to its full value; the
push-out of 1 mm turns a 10 cm lid by less than 0.6°."""
SETTLE_MAX_TURN = math.radians(5.0)
"""Farthest the start angle may move from the recorded one to clear an overlap, rad: a few degrees, the
error of ARCTIC's articulation fits (they start closed lids up to a few degrees below the closed pose)."""
SETTLE_STEP = math.radians(0.25)
"""Angle step of the search, rad (a 30 cm lid's free edge moves 1.3 mm per step)."""


@dataclass(frozen=True)
class HingeStart:
    """Where an articulated object's hinge starts, and the parts' overlap there.

    Attributes:
        recorded: The recorded angle at frame 0, clamped into the hinge's range, rad.
        angle: The start angle chosen, rad.
        recorded_overlap: The parts' deepest overlap at the recorded angle, m.
        overlap: Their deepest overlap at the start angle, m (excluded pairs included).
        excluded: Contact pairs excluded (overlapping beyond the tolerance at every angle searched), pair
            name → its overlap at the start, m.
        residual: The deepest overlap at the start of the pairs still colliding, m.
    """

    recorded: float
    angle: float
    recorded_overlap: float
    overlap: float
    excluded: dict[str, float] = field(default_factory=dict)
    residual: float = 0.0

    def note(self, name: str) -> str:
        """One line for the scene's notes (``name``: the object)."""
        at = f"{math.degrees(self.recorded):.1f}°"
        if self.angle == self.recorded and not self.excluded:
            return (
                f"{name}: its parts start {self.overlap * 1000:.1f} mm inside each other at the recorded "
                f"articulation {at} (tolerance {PART_OVERLAP_TOLERANCE * 1000:g} mm)"
            )
        text = (
            f"{name}: its parts overlap by {self.recorded_overlap * 1000:.1f} mm at the recorded "
            f"articulation {at}; the object starts at {math.degrees(self.angle):.2f}° "
            f"({self.overlap * 1000:.1f} mm)"
        )
        if self.excluded:
            pairs = ", ".join(f"{k} {v * 1000:.1f} mm" for k, v in sorted(self.excluded.items()))
            text += (
                f"; no angle within {math.degrees(SETTLE_MAX_TURN):g}° of the recorded one clears these part "
                "pairs, which overlap there (the meshes' error) and do not collide, the hinge's stop keeping "
                f"the lid out of its base: {pairs}; residual overlap {self.residual * 1000:.2f} mm"
            )
        else:
            text += (
                ", the nearest angle at which no part is more than "
                f"{PART_OVERLAP_TOLERANCE * 1000:g} mm inside another"
            )
        return text

    def to_dict(self) -> dict:
        """JSON-ready fields (degrees and millimetres)."""
        return {
            "recorded_deg": math.degrees(self.recorded),
            "start_deg": math.degrees(self.angle),
            "recorded_overlap_mm": self.recorded_overlap * 1000.0,
            "overlap_mm": self.overlap * 1000.0,
            "excluded_pairs_mm": {k: v * 1000.0 for k, v in sorted(self.excluded.items())},
            "residual_overlap_mm": self.residual * 1000.0,
        }


def _pair_index(model: mujoco.MjModel) -> dict[tuple[int, int], int]:
    """Explicit contact pairs by their (sorted) geom ids."""
    return {
        tuple(sorted((int(model.pair_geom1[i]), int(model.pair_geom2[i])))): i for i in range(model.npair)
    }


def part_overlaps(model: mujoco.MjModel, data: mujoco.MjData, obj: ObjectLayout) -> dict[int, float]:
    """How deep the object's parts overlap through each of their contact pairs at ``data.qpos``, m.

    Runs ``mj_kinematics`` and ``mj_collision`` on ``data`` (its contacts are overwritten).

    Returns:
        Pair id → its deepest contact's depth (≥ 0), for the pairs joining two of the object's parts.
    """
    mujoco.mj_kinematics(model, data)
    mujoco.mj_collision(model, data)
    pairs = _pair_index(model)
    geoms = set(obj.collision_geoms)
    depth: dict[int, float] = {}
    for contact in data.contact[: data.ncon]:
        a, b = int(contact.geom1), int(contact.geom2)
        pair = pairs.get((min(a, b), max(a, b)))
        if pair is None or a not in geoms or b not in geoms:
            continue
        depth[pair] = max(depth.get(pair, 0.0), -float(contact.dist))
    return depth


def settle_hinge(model: mujoco.MjModel, data: mujoco.MjData, obj: ObjectLayout) -> HingeStart:
    """Choose an articulated object's start angle (and pairs to exclude) so its parts start without overlap.

    See the module notes for the rule.

    Args:
        model: The compiled scene's model (not changed).
        data: Its data at the start state (the hinge at the recorded angle, clamped); its ``qpos`` is
            restored, its contacts overwritten.
        obj: The object (with a hinge).

    Returns:
        The start angle, the overlaps and the contact pairs to exclude.

    Raises:
        ValueError: The object has no hinge.
    """
    if obj.hinge_qpos < 0:
        raise ValueError(f"{obj.prefix}: the object has no hinge to settle")
    adr = obj.hinge_qpos
    joint = int(np.flatnonzero(model.jnt_qposadr == adr)[0])
    low, high = model.jnt_range[joint] if model.jnt_limited[joint] else (-math.inf, math.inf)
    recorded = float(data.qpos[adr])

    def overlaps(angle: float) -> dict[int, float]:
        data.qpos[adr] = angle
        return part_overlaps(model, data, obj)

    start = overlaps(recorded)
    first = max(start.values(), default=0.0)
    tried = [(first, 0.0, recorded, start)]
    if first > PART_OVERLAP_TOLERANCE:
        for k in range(1, round(SETTLE_MAX_TURN / SETTLE_STEP) + 1):
            found = []
            for angle in (recorded + k * SETTLE_STEP, recorded - k * SETTLE_STEP):
                if low <= angle <= high:
                    depth = overlaps(angle)
                    found.append((max(depth.values(), default=0.0), k * SETTLE_STEP, angle, depth))
            tried += found
            if any(d <= PART_OVERLAP_TOLERANCE for d, *_ in found):
                break

    def excess(depths: dict[int, float]) -> int:  # pairs overlapping beyond the tolerance
        return sum(d > PART_OVERLAP_TOLERANCE for d in depths.values())

    best = min(tried, key=lambda t: (excess(t[3]), t[1]))  # fewest pairs to exclude, then nearest
    depth, _, angle, pairs = best
    data.qpos[adr] = recorded
    mujoco.mj_kinematics(model, data)
    excluded = {model.pair(p).name: d for p, d in pairs.items() if d > PART_OVERLAP_TOLERANCE}
    residual = max((d for p, d in pairs.items() if model.pair(p).name not in excluded), default=0.0)
    return HingeStart(recorded, angle, first, depth, excluded, residual)


def hand_penetration(
    model: mujoco.MjModel, data: mujoco.MjData, layout: SceneLayout
) -> dict[str, tuple[float, str, str]]:
    """How deep each hand lies inside the objects at ``data.qpos`` (MuJoCo's contact depths).

    Runs ``mj_kinematics`` and ``mj_collision`` on ``data`` (its contacts are overwritten).

    Args:
        model: The compiled scene's model.
        data: Its data at the state to measure.
        layout: The scene's layout.

    Returns:
        Per hand (its layout name; "" for a scene's only hand): the deepest penetration into any object part
        (m, 0 when none), the hand body and the object body of that contact ("" when none).
    """
    mujoco.mj_kinematics(model, data)
    mujoco.mj_collision(model, data)
    body = model.geom_bodyid
    hand_of = {}
    for hand in layout.hands:
        for b in np.flatnonzero(model.body_rootid == model.body_rootid[hand.root_body]):
            hand_of[int(b)] = hand.name
    objects = {int(g) for o in layout.objects for g in o.collision_geoms}
    deepest = {hand.name: (0.0, "", "") for hand in layout.hands}
    for contact in data.contact[: data.ncon]:
        a, b = int(contact.geom1), int(contact.geom2)
        if b in objects and int(body[a]) in hand_of:
            a, b = b, a
        if a not in objects or int(body[b]) not in hand_of:
            continue
        name = hand_of[int(body[b])]
        depth = -float(contact.dist)
        if depth > deepest[name][0]:
            deepest[name] = (depth, model.body(int(body[b])).name, model.body(int(body[a])).name)
    return deepest
