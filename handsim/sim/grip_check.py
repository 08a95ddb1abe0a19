"""Whether a simulated hold is a grip: opposing contacts, no link through the object, forces a hand makes.

A simulated object can stay put for reasons a real hand does not have: a link tunnelled into it, an object
wedged between the welded palm and a finger or a wall, contact forces far beyond what the finger servos can
press with. :func:`check_grip` examines the hold window of a glove replay (or of one robustness-ensemble
member); :meth:`GripCheck.depth_failure` and :meth:`GripCheck.grip_failure` say why its outcome cannot stand:

* **Depth.** No hand link may be deeper in the object than :attr:`~handsim.sim.specs.GripSpec.max_depth`:
  the soft pad's modelled compliance (its impedance reaches full stiffness over
  :data:`~handsim.builders.surfaces.PAD_SOLIMP`'s 3 mm width) plus the placement's 2 mm penetration
  tolerance; nor deeper than the thinnest wall of the part it touches (the narrowest width of the part's
  thinnest collision geom: a divider, a mug's wall, a lid), past which it may have passed through. Deeper,
  the contact is no longer a compressed finger pad but a link inside the object, and the outcome is not
  judged ("link L is X mm inside the object"). Read per link and part from the scene's contact sensors on
  every frame from the contact frame to the window's end.
* **Opposition.** A grip holds an object by pressing on it from opposing sides: the thumb against a finger,
  or fingers against the palm. A frame has opposition when the contacts of the thumb and the fingers (or of
  the fingers and the palm), at least one of each group, are in force closure: the wrenches their friction
  cones can apply span every force and torque on the object, so the grasp quality ε of Ferrari & Canny
  ("Planning optimal grasps", ICRA 1992) is positive; with two contacts this is Nguyen's test ("Constructing
  force-closure grasps", IJRR 7(3), 1988: the line between them inside both cones). A hold needs it in at
  least :attr:`~handsim.sim.specs.GripSpec.min_opposition` of the examined frames. Contacts of one group
  alone (fingertips cradling a ball, a thumb and the palm wedging a crate's divider) do not count, however
  they hold.
* **Force.** The hand's links press on the object with the normal force the contact sensors measure. The
  finger servos can make at most ``τ_max,j / |(Jᵀn)_j|`` at a contact point (its Jacobian ``J``, normal
  ``n``; every actuated joint ``j`` of the chain at its force range), summed over the touching finger links
  (an upper bound: links of one finger share their joints). A median grip force beyond that bound plus the
  object's weight is a wedge: the object is held by the welded palm or by a joint's limit pressing through a
  penetration, not by the servos ("wedged: N newtons from T N·m").

Contacts for opposition and force come from MuJoCo's own collision detection on the recorded states
(``mj_kinematics`` and ``mj_collision`` on each examined frame's ``qpos``), so the model's sensors and the
simulation are unchanged.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import mujoco
import numpy as np
from scipy.optimize import nnls

from handsim.datatypes.fingers import finger_of
from handsim.sim.metrics import contact_slot_values
from handsim.sim.scene.compiled import SimScene
from handsim.sim.scene.layout import ObjectLayout
from handsim.sim.specs import GripSpec

FINGERS = frozenset({"index", "middle", "ring", "little"})
"""The finger groups of :func:`~handsim.datatypes.fingers.finger_of` that oppose the thumb or the palm."""
_NORMAL, _DIST = 1, 4  # offsets of the normal force and the distance in a contact sensor's slot

Contact = tuple[int, np.ndarray, np.ndarray, float]
"""A hand–object contact: the hand link's body id, the point (world), the hand's push on the object
(unit, world) and the friction coefficient."""


@dataclass(frozen=True)
class GripCheck:
    """What a hold window's grip looked like.

    Attributes:
        window: Trajectory times (start, stop) of the frames examined, s.
        frames: Frames examined for opposition and force (evenly spaced over the window; 0 when only the
            depth was examined).
        links: Hand links that touched the object in the window, in layout order.
        opposition: Share of the examined frames with an opposing pair, or None when none was examined.
        opposing_links: The opposing pair found in most frames (thumb or finger first), or None.
        deepest_link: The link deepest in the object relative to the limit there, or None when none entered
            it (read from the contact frame on: ``depth_since``).
        max_depth: Its depth, m (0 when none entered it).
        deepest_at: When, s, or None.
        depth_limit: The limit where it is, m: the spec's, or the thinnest wall of the part it touches.
        wall: The thinnest wall of that part, m (None when no link entered the object).
        grip_force: Median over the examined frames of the finger and thumb links' normal force on the
            object, N (the palm's, a reaction of the welded root, is not counted).
        force_limit: Median over the same frames of what their servos can press with at those contacts, N.
        torque_limit: The largest force range of the servos behind the touching links, N·m.
        weight: The object's weight, N.
    """

    window: tuple[float, float]
    frames: int
    links: tuple[str, ...]
    opposition: float | None
    opposing_links: tuple[str, str] | None
    deepest_link: str | None
    max_depth: float
    deepest_at: float | None
    depth_limit: float
    wall: float | None
    grip_force: float
    force_limit: float
    torque_limit: float
    weight: float

    @property
    def too_deep(self) -> bool:
        """A hand link went deeper into the object than its limit (at ``deepest_at``)."""
        return self.deepest_link is not None and self.max_depth > self.depth_limit

    def depth_failure(self, spec: GripSpec) -> str | None:
        """Why no hold outcome over this window can stand (a link through the object), or None.

        Args:
            spec: The limits.
        """
        if not self.too_deep:
            return None
        if self.wall is not None and self.wall < spec.max_depth:
            why = f"the object's wall there is {self.wall * 1000:.1f} mm thick: it may have passed through"
        else:
            why = "the pad's compliance and the placement's tolerance"
        return (
            f"not judged: link {self.deepest_link} is {self.max_depth * 1000:.1f} mm inside the object at "
            f"{self.deepest_at:.3f} s (at most {self.depth_limit * 1000:.3g} mm: {why}): a tunnelled or "
            "wedged grip"
        )

    def grip_failure(self, spec: GripSpec) -> str | None:
        """Why a *held* outcome over this window is no grip (wedged, or nothing opposing), or None.

        Args:
            spec: The limits.
        """
        if self.grip_force > self.force_limit + self.weight:
            return (
                f"not judged: wedged: {self.grip_force:.1f} N of grip force from servos of at most "
                f"{self.torque_limit:.2g} N·m, which press with at most {self.force_limit:.1f} N at these "
                f"contacts (+ the object's weight, {self.weight:.2f} N)"
            )
        share = 0.0 if self.opposition is None else self.opposition
        if share < spec.min_opposition:
            return (
                "not judged: no grip: the thumb and a finger, or fingers and the palm, press on the object "
                f"from opposing sides in {share:.0%} of the hold window (at least {spec.min_opposition:.0%} "
                f"needed); touching: {', '.join(self.links) or 'nothing'}"
            )
        return None

    def to_dict(self) -> dict:
        """JSON-ready fields (the depth in mm)."""
        result = asdict(self)
        result["window"] = list(self.window)
        result["links"] = list(self.links)
        result["opposing_links"] = None if self.opposing_links is None else list(self.opposing_links)
        result["max_depth_mm"] = result.pop("max_depth") * 1000.0
        result["depth_limit_mm"] = result.pop("depth_limit") * 1000.0
        wall = result.pop("wall")
        result["wall_mm"] = None if wall is None else wall * 1000.0
        return result


def check_grip(
    scene: SimScene,
    qpos: np.ndarray,
    sensors: np.ndarray,
    times: np.ndarray,
    window: tuple[float, float],
    spec: GripSpec,
    depth_since: float | None = None,
    object_index: int = 0,
    grip: bool = True,
) -> GripCheck:
    """Examine the grip of a run over a window.

    Args:
        scene: The scene the run simulated.
        qpos: Its state at each frame time (N, nq).
        sensors: Its sensor data at each frame time (N, nsensordata).
        times: The frame times, s (at least N).
        window: Trajectory times (start, stop) whose frames are examined for opposition and force, s;
            frames past the run's last are not examined.
        spec: How many frames to examine.
        depth_since: The links' depth is read from this time (the contact frame: a grip that starts
            inside the object is no grip) to the window's end; None: over the window only.
        object_index: Which object.
        grip: Examine the opposition and the forces (what a held outcome needs); False: the depth only
            (a lost object's), ``frames`` 0 and ``opposition`` None.
    """
    layout = scene.layout
    n = qpos.shape[0]
    t = np.asarray(times, dtype=float)[:n]
    first = int(np.searchsorted(t, window[0] - 1e-9))
    last = min(int(np.searchsorted(t, window[1] + 1e-9)), n) - 1
    obj = layout.objects[object_index]
    weight = float(scene.model.body_subtreemass[obj.root_body] * np.linalg.norm(scene.model.opt.gravity))
    if last < first:
        empty = (float(window[0]), float(window[1]))
        return GripCheck(
            empty, 0, (), None, None, None, 0.0, None, spec.max_depth, None, 0.0, 0.0, 0.0, weight
        )
    start = sum(len(o.part_bodies) for o in layout.objects[:object_index])
    parts = slice(start, start + len(obj.part_bodies))
    begin = first if depth_since is None else min(first, int(np.searchsorted(t, depth_since - 1e-9)))
    deepest, depth = _deepest(scene, sensors[begin : last + 1], t[begin : last + 1], parts, obj, spec)
    normal = contact_slot_values(scene, sensors[first : last + 1], _NORMAL)[:, :, parts].sum(axis=(2, 3))
    touching = (normal > 0).any(axis=0) | (depth[first - begin :] > 0).any(axis=0)
    count = min(spec.frames, last - first + 1) if grip else 0
    picks = np.unique(np.linspace(first, last, count).round().astype(int))
    return GripCheck(
        window=(float(t[first]), float(t[last])),
        links=tuple(name for name, on in zip(layout.link_names, touching, strict=True) if on),
        weight=weight,
        **deepest,
        **_grip_at(scene, obj, qpos[picks], normal[picks - first]),
    )


def _deepest(
    scene: SimScene, rows: np.ndarray, times: np.ndarray, parts: slice, obj: ObjectLayout, spec: GripSpec
) -> tuple[dict, np.ndarray]:
    """The link deepest in the object relative to the limit where it is, and each link's depth per frame.

    Args:
        scene: The scene.
        rows: Sensor data of the frames read (frames, nsensordata).
        times: Their times, s.
        parts: The object's parts among all objects' parts.
        obj: The object.
        spec: The depth limit.

    Returns:
        :class:`GripCheck`'s ``deepest_link``, ``max_depth``, ``deepest_at``, ``depth_limit`` and ``wall``
        by name, and the depth of each link in any part of the object per frame (frames, links), m.
    """
    depths = np.maximum(-contact_slot_values(scene, rows, _DIST)[:, :, parts], 0.0).max(axis=3)
    walls = np.array([thinnest_wall(scene.model, int(b)) for b in obj.part_bodies])
    allowed = np.maximum(np.minimum(spec.max_depth, walls), 1e-6)  # a degenerate geom still divides
    k, link, part = np.unravel_index(int(np.argmax(depths / allowed)), depths.shape)
    deepest = float(depths[k, link, part])
    fields = {
        "deepest_link": scene.layout.link_names[link] if deepest > 0.0 else None,
        "max_depth": deepest,
        "deepest_at": float(times[k]) if deepest > 0.0 else None,
        "depth_limit": float(allowed[part]),
        "wall": float(walls[part]) if deepest > 0.0 else None,
    }
    return fields, depths.max(axis=2)


def _grip_at(scene: SimScene, obj: ObjectLayout, states: np.ndarray, normal: np.ndarray) -> dict:
    """The opposition and the forces of the grip at the examined frames.

    Args:
        scene: The scene.
        obj: The object.
        states: The examined frames' ``qpos`` (frames, nq).
        normal: The normal force of each link on the object at those frames (frames, links), N.

    Returns:
        :class:`GripCheck`'s ``frames``, ``opposition``, ``opposing_links``, ``grip_force``,
        ``force_limit`` and ``torque_limit`` by name.
    """
    probe = _Probe(scene, obj)
    actuated = np.array([finger_of(name) != "palm" for name in scene.layout.link_names])
    pairs: dict[tuple[str, str], int] = {}
    forces, limits, torque = [], [], 0.0
    for state, pressed in zip(states, normal, strict=True):
        contacts = probe.contacts(state)
        pair = probe.opposing(contacts)
        if pair is not None:
            pairs[pair] = pairs.get(pair, 0) + 1
        limit, servo = probe.force_limit(contacts)
        forces.append(float(pressed[actuated].sum()))
        limits.append(limit)
        torque = max(torque, servo)
    return {
        "frames": len(states),
        "opposition": sum(pairs.values()) / len(states) if len(states) else None,
        "opposing_links": max(pairs, key=lambda p: (pairs[p], p)) if pairs else None,
        "grip_force": float(np.median(forces)) if forces else 0.0,
        "force_limit": float(np.median(limits)) if limits else 0.0,
        "torque_limit": torque,
    }


def thinnest_wall(model: mujoco.MjModel, body: int) -> float:
    """The narrowest width of a body's thinnest collision geom, m (``inf`` without one).

    A mesh geom (MuJoCo collides its convex hull) is measured across each of its faces (the width of a
    convex polytope along a face normal bounds its narrowest width; a slab's is its thickness); a box by its
    smallest side; a sphere, capsule, cylinder or ellipsoid by its smallest diameter.
    """
    mesh, box, ellipsoid = (
        int(k)
        for k in (mujoco.mjtGeom.mjGEOM_MESH, mujoco.mjtGeom.mjGEOM_BOX, mujoco.mjtGeom.mjGEOM_ELLIPSOID)
    )
    rounds = {
        int(k)
        for k in (mujoco.mjtGeom.mjGEOM_SPHERE, mujoco.mjtGeom.mjGEOM_CAPSULE, mujoco.mjtGeom.mjGEOM_CYLINDER)
    }
    widths = [math.inf]
    for g in range(model.body_geomadr[body], model.body_geomadr[body] + model.body_geomnum[body]):
        if not (model.geom_contype[g] or model.geom_conaffinity[g]):
            continue
        kind, size = int(model.geom_type[g]), model.geom_size[g]
        if kind == mesh:
            widths.append(_mesh_width(model, int(model.geom_dataid[g])))
        elif kind in (box, ellipsoid):
            widths.append(2.0 * float(size.min()))
        elif kind in rounds:
            widths.append(2.0 * float(size[0]))
    return min(widths)


def _mesh_width(model: mujoco.MjModel, mesh: int) -> float:
    """The narrowest extent of a mesh's vertices along its faces' normals, m."""
    start, count = model.mesh_vertadr[mesh], model.mesh_vertnum[mesh]
    vertices = np.asarray(model.mesh_vert[start : start + count], dtype=float)
    first, faces = model.mesh_faceadr[mesh], model.mesh_facenum[mesh]
    triangles = vertices[np.asarray(model.mesh_face[first : first + faces])]
    normals = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
    lengths = np.linalg.norm(normals, axis=1)
    keep = lengths > 1e-12
    if not keep.any():
        return math.inf
    extent = vertices @ (normals[keep] / lengths[keep, None]).T
    return float((extent.max(axis=0) - extent.min(axis=0)).min())


class _Probe:
    """MuJoCo's hand–object contacts of a state: opposing pairs, and what the servos can press with."""

    def __init__(self, scene: SimScene, obj: ObjectLayout) -> None:
        model = scene.model
        layout = scene.layout
        self.model = model
        self.data = mujoco.MjData(model)
        self.object_bodies = frozenset(int(b) for b in obj.part_bodies)
        self.root = int(obj.root_body)
        bodies = [int(b) for b in layout.link_bodies]
        self.group = {b: finger_of(name) for name, b in zip(layout.link_names, bodies, strict=True)}
        self.name = dict(zip(bodies, layout.link_names, strict=True))
        joints = model.actuator_trnid[layout.actuators, 0]
        self.dofs = model.jnt_dofadr[joints]
        limited = model.actuator_forcelimited[layout.actuators].astype(bool)
        self.torque = np.where(
            limited, np.abs(model.actuator_forcerange[layout.actuators]).max(axis=1), np.inf
        )
        self.jacp = np.zeros((3, model.nv))

    def contacts(self, qpos: np.ndarray) -> list[Contact]:
        """The hand–object contacts MuJoCo's collision detection finds at ``qpos``."""
        model, data = self.model, self.data
        data.qpos[:] = qpos
        mujoco.mj_kinematics(model, data)
        mujoco.mj_comPos(model, data)
        mujoco.mj_collision(model, data)
        found: list[Contact] = []
        for i in range(data.ncon):
            con = data.contact[i]
            b1, b2 = int(model.geom_bodyid[con.geom1]), int(model.geom_bodyid[con.geom2])
            normal = np.array(con.frame[:3])  # from geom1 towards geom2: geom1 pushes geom2 along it
            if b1 in self.group and b2 in self.object_bodies:
                found.append((b1, np.array(con.pos), normal, float(con.friction[0])))
            elif b2 in self.group and b1 in self.object_bodies:
                found.append((b2, np.array(con.pos), -normal, float(con.friction[0])))
        return found

    def opposing(self, contacts: list[Contact]) -> tuple[str, str] | None:
        """Two opposing links, thumb–finger then finger–palm, whose groups' contacts are in force closure.

        The contacts of the thumb and the fingers (or of the fingers and the palm), at least one of each,
        are in force closure when their friction cones' wrenches span every direction (:func:`_in_closure`);
        the pair named is each group's link that presses hardest along the line between the groups.
        """
        centre = self.data.xipos[self.root]
        for first, second in ((frozenset({"thumb"}), FINGERS), (FINGERS, frozenset({"palm"}))):
            a_side = [c for c in contacts if self.group[c[0]] in first]
            b_side = [c for c in contacts if self.group[c[0]] in second]
            if a_side and b_side and _in_closure([*a_side, *b_side], centre):
                return self.name[a_side[0][0]], self.name[b_side[0][0]]
        return None

    def force_limit(self, contacts: list[Contact]) -> tuple[float, float]:
        """What the servos can press with at the finger and thumb contacts, N, and their largest range, N·m.

        At a contact point the servos balance a push ``f`` along ``n`` with torques ``f · Jᵀn``; each is
        capped by its force range, so ``f ≤ min_j τ_j / |(Jᵀn)_j|``. A link's bound is that of its
        strongest contact; the links' bounds are summed.
        """
        per_link: dict[int, float] = {}
        torque = 0.0
        for body, point, push, _ in contacts:
            if self.group[body] == "palm":
                continue
            mujoco.mj_jac(self.model, self.data, self.jacp, None, point, body)
            moment = np.abs(push @ self.jacp[:, self.dofs])
            used = moment > 1e-9
            if not used.any():
                continue
            per_link[body] = max(per_link.get(body, 0.0), float(np.min(self.torque[used] / moment[used])))
            torque = max(torque, float(self.torque[used].max()))
        return float(sum(per_link.values())), torque


CONE_EDGES = 8
"""Edges of the polyhedral friction cone each contact's cone is replaced by (Ferrari & Canny 1992)."""
_ANGLES = 2.0 * np.pi * np.arange(CONE_EDGES) / CONE_EDGES
_DIRECTIONS = np.vstack([np.eye(6), -np.eye(6)])
CLOSURE_TOLERANCE = 1e-6
"""Largest distance from a unit direction of wrench space to the wrenches' cone that still counts as
reached (numerical noise: a direction the cone misses, misses it by far more)."""


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``np.cross`` of broadcast 3-vectors, bitwise the same (the same products and differences).

    Without ``np.cross``'s axis handling, which costs more than the arithmetic on a grip check's contacts.
    """
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=-1)


def _in_closure(contacts: list[Contact], centre: np.ndarray) -> bool:
    """Whether frictional point contacts hold an object in force closure (Ferrari & Canny 1992).

    Each contact's friction cone (its coefficient μ) is replaced by :data:`CONE_EDGES` unit forces on its
    surface; each force ``f`` at point ``p`` gives the wrench ``(f, (p − c) × f / r)`` about the object's
    centre of mass ``c``, torques scaled by the contacts' largest distance ``r`` from it. The contacts are
    in force closure when the origin lies strictly inside the convex hull of these wrenches: they can
    resist any force and torque on the object (the grasp quality ε of Ferrari & Canny is then positive).
    That holds exactly when the wrenches' non-negative combinations reach every direction, which is tested
    on the twelve directions ±x … of wrench space by non-negative least squares (Lawson & Hanson's NNLS, a
    few tens of µs each, where a 6-D convex hull of a hundred wrenches takes tens of ms).
    """
    arms = np.array([c[1] for c in contacts]) - centre
    normals = np.array([c[2] for c in contacts])
    normals /= np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-12)
    mu = np.array([c[3] for c in contacts])[:, None, None]
    helper = np.where(np.abs(normals[:, :1]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    t1 = _cross(normals, helper)
    t1 /= np.linalg.norm(t1, axis=1, keepdims=True)
    t2 = _cross(normals, t1)
    ring = np.cos(_ANGLES)[None, :, None] * t1[:, None] + np.sin(_ANGLES)[None, :, None] * t2[:, None]
    forces = normals[:, None] + mu * ring  # (contacts, edges, 3)
    forces /= np.linalg.norm(forces, axis=2, keepdims=True)
    scale = max(float(np.linalg.norm(arms, axis=1).max()), 1e-6)
    torques = _cross(arms[:, None], forces) / scale
    w = np.concatenate([forces, torques], axis=2).reshape(-1, 6).T  # (6, contacts × edges)
    return all(nnls(w, direction)[1] <= CLOSURE_TOLERANCE for direction in _DIRECTIONS)
