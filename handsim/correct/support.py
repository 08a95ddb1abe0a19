"""Where a recording holds an object up with nothing: no hand link touches it and it rests on no surface.

A correction makes a simulated object follow its recorded track by changing the hand's motion a little. Where
the *recording itself* has the object hanging in the air — no recorded hand link within
:data:`TOUCH_DISTANCE` of it, its lowest point clear of every surface by more than that — for longer than
:data:`MIN_STRETCH` (a free fall drops 4.9 cm in 0.1 s), gravity takes it down in any physical motion near the
recording: the track there is not physically true, and no small correction can make it so. A correction
that loses the object in such a stretch says so, with the numbers (:mod:`handsim.correct.score`). Likewise
where the recording turns an articulated object's hinged part (a lid) by more than the track verdict's
hinge tolerance while no hand link touches that part and no surface holds it (:class:`UntouchedTurn`): the
scene's hinge holds its part by dry friction (docs/physics.md), so nothing near the recording turns it.
And where no recorded hand link comes within :data:`REACH` of an object at all (:class:`Unreachable`): no
contact is possible.

The test is kinematic, on the scene as the replay builds it: every control frame's recorded hand pose (the
root where one is recorded, the joint targets clipped to their ranges) and recorded object pose, MuJoCo's
collision detection with the objects' collision geoms given a margin of :data:`REACH` in a copy of the model,
and each contact's signed distance: to a hand link (the hand's distance; for a hinged part, the part's own),
to anything else that is not the object itself (a surface or another object: the support's distance).
"""

from __future__ import annotations

import copy
from dataclasses import asdict, dataclass

import mujoco
import numpy as np

from handsim.correct.config import CorrectionConfig
from handsim.correct.reference import Reference
from handsim.sim.specs import TrackSpec

TOUCH_DISTANCE = 0.005
"""A hand link or a surface within this of the object (m) touches or supports it: the fitted hands' own
surface error and a contact pad's few millimetres (the replay's pad compresses 1.5 mm at 1 N)."""
REACH = 0.03
"""Distances are measured up to this, m (beyond: "over 30 mm")."""
MIN_STRETCH = 0.1
"""A shorter unsupported stretch (s) is left out: capture noise across a contact, and too short to fall far
(4.9 cm in 0.1 s)."""


class _Said:
    """What the findings share: the sentence for people (``describe``) and the record's form."""

    def describe(self) -> str:
        raise NotImplementedError

    def to_dict(self) -> dict:
        """JSON-ready fields (pairs as lists), and the sentence of :meth:`describe` as ``text``."""
        fields = {k: list(v) if isinstance(v, tuple) else v for k, v in asdict(self).items()}
        return {**fields, "text": self.describe()}


@dataclass(frozen=True)
class Unsupported(_Said):
    """A stretch of the recording in which an object hangs in the air with nothing holding it.

    Attributes:
        object: The object's track name.
        start_s: Its first frame's trajectory time, s.
        stop_s: Its last frame's, s.
        frames: Control frames in it.
        share: Its share of the object's frames with a recorded pose.
        hand_mm: The nearest hand link's distance from the object, least and largest over the stretch, mm
            (:data:`REACH` where none is within it).
        height_mm: The least distance from the object to any surface over the stretch, mm (:data:`REACH`
            where none is within it).
        fall_mm: How far the object falls in the recording over the stretch (down along gravity), mm;
            free fall over the stretch would take it ``g t² / 2``.
    """

    object: str
    start_s: float
    stop_s: float
    frames: int
    share: float
    hand_mm: tuple[float, float]
    height_mm: float
    fall_mm: float

    def describe(self) -> str:
        """One clause for people: when, how long, how high and how far the hand is."""
        near = _span(self.hand_mm)
        seconds = self.stop_s - self.start_s
        when = f"from {self.start_s:.2f} s to {self.stop_s:.2f} s"
        return (
            f"the recording holds the {self.object or 'object'} in the air {when} ({self.frames} frames, "
            f"{self.share * 100:.0f} % of its track): no hand link within {TOUCH_DISTANCE * 1000:g} mm of it "
            f"(nearest {near}), {_mm(self.height_mm)} above any surface, "
            f"{'falling' if self.fall_mm >= 0 else 'rising'} {abs(self.fall_mm):.1f} mm in {seconds:.2f} s "
            f"(free fall: {_free_fall_mm(seconds):.0f} mm): no motion near the recording carries it there"
        )

    def brief(self) -> str:
        """The clause a lost track's reason gets (:meth:`describe` has the numbers)."""
        return (
            f"the recording holds the {self.object or 'object'} in the air from {self.start_s:.2f} s to "
            f"{self.stop_s:.2f} s, nothing within {TOUCH_DISTANCE * 1000:g} mm of it: no motion near the "
            "recording carries it there"
        )


@dataclass(frozen=True)
class UntouchedTurn(_Said):
    """A stretch in which the recording turns a hinged part that no hand link touches.

    Attributes:
        object: The object's track name.
        part: The hinged part's name.
        start_s: Trajectory time of the turn's first frame (the hinge at its least or largest angle), s.
        stop_s: Of its last frame, s.
        turn_deg: How far the recording turns the part between them, degrees.
        hand_mm: The nearest hand link's distance from the part, least and largest over the turn, mm.
    """

    object: str
    part: str
    start_s: float
    stop_s: float
    turn_deg: float
    hand_mm: tuple[float, float]

    def describe(self) -> str:
        """One clause for people: what turns, when, how far, how far the hand is."""
        near = _span(self.hand_mm)
        when = f"from {self.start_s:.2f} s to {self.stop_s:.2f} s"
        return (
            f"the recording turns the {self.object or 'object'}'s {self.part} by {self.turn_deg:.0f}° {when} "
            f"with no hand link within {TOUCH_DISTANCE * 1000:g} mm of it (nearest {near}): its hinge holds "
            "it by friction, so no motion near the recording turns it"
        )

    def brief(self) -> str:
        """The clause a lost track's reason gets (:meth:`describe` has the numbers)."""
        return (
            f"the recording turns the {self.object or 'object'}'s {self.part} by {self.turn_deg:.0f}° from "
            f"{self.start_s:.2f} s to {self.stop_s:.2f} s, no hand link within {TOUCH_DISTANCE * 1000:g} mm "
            "of it: no motion near the recording turns it"
        )


@dataclass(frozen=True)
class Unreachable(_Said):
    """An object that no recorded hand link comes within :data:`REACH` of, in any frame.

    Attributes:
        object: The object's track name.
        start_s: Its first frame with a recorded pose, s.
        stop_s: Its last, s.
    """

    object: str
    start_s: float
    stop_s: float

    def describe(self) -> str:
        """One clause for people."""
        return (
            f"no contact possible: no recorded hand link comes within {REACH * 1000:g} mm of the "
            f"{self.object or 'object'} in any frame, more than the correction can bridge (its wrist moves "
            f"at most {CorrectionConfig().wrist_position_bound * 1000:g} mm by default)"
        )

    def brief(self) -> str:
        """The clause a lost track's reason gets (the same: it has no numbers to leave out)."""
        return self.describe()


def _span(values: tuple[float, float]) -> str:
    """A least-to-largest pair of distances, mm, for people ("5.2 mm to 25.3 mm"; one value when equal)."""
    return " to ".join(_mm(v) for v in dict.fromkeys(values))


def _mm(value: float) -> str:
    return f"over {REACH * 1000:g} mm" if value >= REACH * 1000 else f"{value:.1f} mm"


def _free_fall_mm(seconds: float) -> float:
    return 0.5 * 9.81 * seconds**2 * 1000.0


Finding = Unsupported | UntouchedTurn | Unreachable
"""What :func:`unsupported_stretches` finds."""


def unsupported_stretches(reference: Reference) -> tuple[Finding, ...]:
    """Where no motion near the recording can follow it (module docstring), in time order.

    An object no recorded hand link comes within :data:`REACH` of (:class:`Unreachable`) comes first; then
    the stretches in which the recording holds an object in the air and the turns of hinged parts nobody
    touches. A glove scene (its object placed into the hand, no recorded track) has none: ().
    """
    if reference.goal is not None or not reference.objects:
        return ()
    near = _distances(reference)
    found: list[Finding] = []
    times = reference.schedule.times
    for i, obj in enumerate(reference.objects):
        if obj.valid.any() and near.hand[obj.valid, i].min() >= REACH:
            valid = np.flatnonzero(obj.valid)
            found.append(Unreachable(obj.name, float(times[valid[0]]), float(times[valid[-1]])))
            continue  # untouched all through: the stretches below would only say it again
        free = obj.valid & (near.hand[:, i] > TOUCH_DISTANCE) & (near.surface[:, i] > TOUCH_DISTANCE)
        for start, stop in _runs(free):
            if times[stop] - times[start] >= MIN_STRETCH - 1e-9:
                found.append(_stretch(reference, i, start, stop, near.hand[:, i], near.surface[:, i]))
        if obj.hinge >= 0 and obj.articulation is not None:
            found.extend(_turns(reference, i, near.part[:, i], near.part_surface[:, i]))
    return tuple(sorted(found, key=lambda s: (s.start_s, not isinstance(s, Unreachable))))


def _turns(reference: Reference, index: int, part: np.ndarray, rest: np.ndarray) -> list[UntouchedTurn]:
    """The untouched turns of an object's hinged part beyond the track verdict's hinge tolerance.

    ``part`` and ``rest``: the nearest hand link's and the nearest surface's distance from the part per
    frame. A part resting on a surface is held by it: the angle, relative to the other part, may change
    because a hand turns the other part (or the whole object) while the surface holds this one.
    """
    obj = reference.objects[index]
    layout = next(o for o in reference.scene.layout.objects if o.free_qpos == obj.qpos)
    limit = np.radians(TrackSpec().articulation_deg)
    times = reference.schedule.times
    turns = []
    for start, stop in _runs(obj.valid & (part > TOUCH_DISTANCE) & (rest > TOUCH_DISTANCE)):
        angle = obj.articulation[start : stop + 1]
        low, high = int(np.argmin(angle)), int(np.argmax(angle))
        if angle[high] - angle[low] <= limit:
            continue
        if low < high:  # from the last frame at the least angle before the largest, and vice versa
            low = int(np.flatnonzero(angle[: high + 1] == angle[low])[-1])
        else:
            high = int(np.flatnonzero(angle[: low + 1] == angle[high])[-1])
        first, last = start + min(low, high), start + max(low, high)
        span = part[first : last + 1] * 1000
        turns.append(
            UntouchedTurn(
                object=obj.name,
                part=layout.part_names[1] if len(layout.part_names) > 1 else "part",
                start_s=float(times[first]),
                stop_s=float(times[last]),
                turn_deg=float(np.degrees(angle[high] - angle[low])),
                hand_mm=(float(span.min()), float(span.max())),
            )
        )
    return turns


def _stretch(
    reference: Reference, index: int, start: int, stop: int, hand: np.ndarray, surface: np.ndarray
) -> Unsupported:
    obj = reference.objects[index]
    gravity = np.asarray(reference.scene.model.opt.gravity, dtype=float)
    down = gravity / max(float(np.linalg.norm(gravity)), 1e-12)
    times = reference.schedule.times
    part = slice(start, stop + 1)
    return Unsupported(
        object=obj.name,
        start_s=float(times[start]),
        stop_s=float(times[stop]),
        frames=stop - start + 1,
        share=(stop - start + 1) / max(int(obj.valid.sum()), 1),
        hand_mm=(float(hand[part].min() * 1000), float(hand[part].max() * 1000)),
        height_mm=float(surface[part].min() * 1000),
        fall_mm=float((obj.pose[stop, :3] - obj.pose[start, :3]) @ down * 1000),
    )


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """First and last index of each run of True."""
    edges = np.diff(np.concatenate([[0], mask.astype(np.int8), [0]]))
    starts, stops = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1) - 1
    return [(int(a), int(b)) for a, b in zip(starts, stops, strict=True)]


@dataclass
class _Near:
    """Distances per control frame and recorded object (F, objects), m, capped at :data:`REACH`.

    ``hand``: the nearest hand link to the object; ``surface``: the nearest anything else but the object;
    ``part``, ``part_surface``: the same two for its hinged part.
    """

    hand: np.ndarray
    surface: np.ndarray
    part: np.ndarray
    part_surface: np.ndarray


def _distances(reference: Reference) -> _Near:
    """The distances of :class:`_Near` at every control frame's recorded pose."""
    scene = reference.scene
    layout = scene.layout
    model = copy.deepcopy(scene.model)
    data = mujoco.MjData(model)
    objects = [next(o for o in layout.objects if o.free_qpos == ref.qpos) for ref in reference.objects]
    owner = np.full(model.nbody, -1)
    hinged = np.zeros(model.nbody, bool)
    for i, obj in enumerate(objects):
        owner[list(obj.part_bodies)] = i
        hinged[list(obj.part_bodies[1:])] = obj.hinge_qpos >= 0
        model.geom_margin[list(obj.collision_geoms)] = REACH
        model.geom_gap[list(obj.collision_geoms)] = 0.0
    hand_bodies = np.zeros(model.nbody, bool)
    hand_bodies[np.asarray(layout.link_bodies, dtype=np.int64)] = True
    schedule = reference.schedule
    low, high = np.asarray(layout.ctrl_range, dtype=float).T
    roots = [h.root_free_qpos for h in layout.hands if h.mocap >= 0]
    near = _Near(*(np.full((schedule.frames, len(objects)), REACH) for _ in range(4)))
    joints = np.asarray(layout.dof_qpos)
    hinges = [_hinge_range(model, ref.hinge) for ref in reference.objects]
    for f in range(schedule.frames):
        data.qpos[:] = model.qpos0
        data.qpos[joints] = np.clip(schedule.ctrl[f], low, high)
        for k, adr in enumerate(roots):
            if adr >= 0 and schedule.root_poses is not None:
                data.qpos[adr : adr + 7] = schedule.root_poses[f, k]
        for ref, (low_angle, high_angle) in zip(reference.objects, hinges, strict=True):
            if not ref.valid[f]:  # no recorded pose (its distances are not read): left where the model has it
                continue
            data.qpos[ref.qpos : ref.qpos + 7] = ref.pose[f]
            if ref.hinge >= 0 and ref.articulation is not None:  # within its stops, as the replay sets it
                data.qpos[ref.hinge] = np.clip(ref.articulation[f], low_angle, high_angle)
        mujoco.mj_fwdPosition(model, data)
        _nearest(model, data, (owner, hinged, hand_bodies), near, f)
    return near


def _hinge_range(model: mujoco.MjModel, qpos: int) -> tuple[float, float]:
    """The stops of the hinge at ``qpos`` (unbounded where it has none, or where there is no hinge)."""
    joints = np.flatnonzero(model.jnt_qposadr == qpos) if qpos >= 0 else ()
    if len(joints) == 0 or not model.jnt_limited[joints[0]]:
        return -np.inf, np.inf
    low, high = model.jnt_range[joints[0]]
    return float(low), float(high)


def _nearest(
    model: mujoco.MjModel, data: mujoco.MjData, bodies: tuple[np.ndarray, ...], near: _Near, frame: int
) -> None:
    """Lower ``near``'s row ``frame`` to the distances of this pose's contacts.

    ``bodies``: per body, the recorded object it belongs to (-1: none), whether it is a hinged part, whether
    it is a hand link.
    """
    owner, hinged, hand_bodies = bodies
    for contact in data.contact[: data.ncon]:
        pair = model.geom_bodyid[contact.geom1], model.geom_bodyid[contact.geom2]
        for mine, other in (pair, pair[::-1]):
            i = owner[mine]
            if i < 0 or owner[other] == i:
                continue
            dist = max(float(contact.dist), 0.0)
            target = near.hand if hand_bodies[other] else near.surface
            target[frame, i] = min(target[frame, i], dist)
            if hinged[mine]:
                target = near.part if hand_bodies[other] else near.part_surface
                target[frame, i] = min(target[frame, i], dist)
