"""handsim's parametric right-hand skeleton, laid out like the GraspDB14 skeleton so glove data drives it.

Plain data from a table: a :class:`~handsim.datatypes.skeleton.Skeleton` built from published hand
proportions (no MuJoCo); :func:`handsim.builders.default_hand` builds its MuJoCo spec, and a scripted grasp
(:mod:`handsim.io.scripted`) takes its DoFs as columns.

Segment lengths are fractions of the hand length (wrist crease to the middle fingertip) from Buchholz,
Armstrong & Goldstein, "Anthropometric data for describing the kinematics of the human hand",
Ergonomics 35(3):261–273, 1992 (Table 2, mean segment-length coefficients). Lateral joint positions are
fractions of the hand breadth chosen to match the GraspDB14 default skeleton's knuckle spread. Joint
ranges follow the GraspDB14 default skeleton (Stollenwerk et al., 2018), with anatomical wrist ranges
(flexion 80°, extension 70°, radial 20°, ulnar 30°, pronation/supination 80°; AAOS normal values).

Frame (as GraspDB14): x towards the thumb, fingers along −y, palm facing −z; the root is the wrist.
Joint names, DoF names and local frames are those of :func:`handsim.io.graspdb.xmlskel.read_xmlskel`, so a
trajectory read for the GraspDB14 skeleton drives this hand without renaming.
"""

from __future__ import annotations

import math

import numpy as np

from handsim.datatypes.skeleton import Dof, Joint, Skeleton, mj_name
from handsim.errors import SkeletonError
from handsim.io.graspdb.xmlskel import AXIS_KINDS, AXIS_TAGS, DOF_CHAIN_ORDER, local_frame

DEFAULT_HAND_LENGTH_M = 0.19
DEFAULT_BREADTH_RATIO = 0.45

# Buchholz et al. 1992: metacarpal, proximal, (middle,) distal lengths / hand length.
SEGMENT_RATIOS = {
    "th": (0.251, 0.196, 0.158),
    "if": (0.374, 0.265, 0.143, 0.097),
    "mf": (0.373, 0.277, 0.170, 0.108),
    "rf": (0.336, 0.259, 0.165, 0.107),
    "lf": (0.295, 0.206, 0.117, 0.093),
}
# Lateral (x) position of the carpometacarpal and metacarpophalangeal joints / hand breadth.
CMC_X = {"if": 0.16, "mf": 0.0, "rf": -0.13, "lf": -0.21}
MCP_X = {"if": 0.25, "mf": 0.0, "rf": -0.22, "lf": -0.40}
THUMB_CMC = (0.32, -0.155)  # (x / breadth, y / length)
THUMB_ANGLE_DEG = 31.0  # thumb direction from −y towards +x in the flat hand

# Ranges in degrees per (joint suffix, axis tag).
RANGES_DEG: dict[tuple[str, str], tuple[float, float]] = {
    ("root", "rotz"): (-30.0, 20.0),
    ("root", "roty"): (-80.0, 80.0),
    ("root", "rotx"): (-70.0, 80.0),
    ("th-tmc", "rotz"): (-30.0, 60.0),
    ("th-tmc", "roty"): (-30.0, 120.0),
    ("th-tmc", "rotx"): (-25.0, 35.0),
    ("th-mcp", "rotz"): (-30.0, 60.0),
    ("th-mcp", "rotx"): (-10.0, 80.0),
    ("th-ip", "rotx"): (-15.0, 80.0),
    ("if-mcp", "rotz"): (-15.0, 42.0),
    ("mf-mcp", "rotz"): (-8.0, 35.0),
    ("rf-cmc", "roty"): (0.0, 15.0),
    ("rf-mcp", "rotz"): (-20.0, 14.0),
    ("lf-cmc", "roty"): (0.0, 30.0),
    ("lf-mcp", "rotz"): (-40.0, 19.0),
    ("mcp", "rotx"): (0.0, 90.0),
    ("pip", "rotx"): (0.0, 100.0),
    ("if-dip", "rotx"): (-10.0, 90.0),
    ("mf-dip", "rotx"): (-10.0, 90.0),
    ("rf-dip", "rotx"): (-20.0, 90.0),
    ("lf-dip", "rotx"): (-30.0, 90.0),
}


def _range(joint: str, tag: str) -> tuple[float, float] | None:
    if (joint, tag) in RANGES_DEG:
        return RANGES_DEG[(joint, tag)]
    suffix = joint.split("-")[-1]
    if joint[:2] != "th" and (suffix, tag) in RANGES_DEG:
        return RANGES_DEG[(suffix, tag)]
    return None


def _chain(start: np.ndarray, direction: np.ndarray, lengths: list[float]) -> list[np.ndarray]:
    points = [start]
    for length in lengths:
        points.append(points[-1] + length * direction)
    return points


def default_skeleton(
    hand_length_m: float = DEFAULT_HAND_LENGTH_M, hand_breadth_m: float | None = None
) -> Skeleton:
    """The parametric right-hand skeleton.

    Args:
        hand_length_m: Wrist crease to middle fingertip, metres (adult range about 0.15–0.23).
        hand_breadth_m: Breadth across the metacarpals, metres; 0.45 × length by default.

    Returns:
        A 25-joint skeleton with GraspDB14 joint names and DoFs.

    Raises:
        SkeletonError: If a size is outside the plausible range for a human hand.
    """
    length = float(hand_length_m)
    breadth = DEFAULT_BREADTH_RATIO * length if hand_breadth_m is None else float(hand_breadth_m)
    if not 0.08 <= length <= 0.30:
        raise SkeletonError(f"hand length {length} m is outside 0.08–0.30 m (is it in mm?)")
    if not 0.3 * length <= breadth <= 0.7 * length:
        raise SkeletonError(f"hand breadth {breadth} m is implausible for a {length} m long hand")

    names = ["root"]
    points: list[np.ndarray] = [np.zeros(3)]
    parents = [-1]
    angle = math.radians(THUMB_ANGLE_DEG)
    thumb_dir = np.array([math.sin(angle), -math.cos(angle), 0.0])
    thumb_start = np.array([THUMB_CMC[0] * breadth, THUMB_CMC[1] * length, 0.0])
    thumb = _chain(thumb_start, thumb_dir, [r * length for r in SEGMENT_RATIOS["th"]])
    for k, suffix in enumerate(("tmc", "mcp", "ip", "tip")):
        names.append(f"th-{suffix}")
        points.append(thumb[k])
        parents.append(0 if k == 0 else len(names) - 2)
    cmc_y = -(1.0 - sum(SEGMENT_RATIOS["mf"])) * length
    for finger in ("if", "mf", "rf", "lf"):
        mc, *phalanges = (r * length for r in SEGMENT_RATIOS[finger])
        cmc = np.array([CMC_X[finger] * breadth, cmc_y, 0.0])
        dx = (MCP_X[finger] - CMC_X[finger]) * breadth
        direction = np.array([dx, -math.sqrt(mc**2 - dx**2), 0.0]) / mc
        for k, point in enumerate(_chain(cmc, direction, [mc, *phalanges])):
            names.append(f"{finger}-{('cmc', 'mcp', 'pip', 'dip', 'tip')[k]}")
            points.append(point)
            parents.append(0 if k == 0 else len(names) - 2)

    joints = []
    dofs = []
    for name, point, parent in zip(names, points, parents, strict=True):
        if parent < 0 or name == "th-tmc":
            frame = np.eye(3)
        else:
            frame = local_frame(point - points[parent])
        joints.append(Joint(name, parent, point, frame))
        for tag in DOF_CHAIN_ORDER:
            rng = _range(name, tag)
            if rng is None:
                continue
            kind = AXIS_KINDS[tag]
            axis = np.eye(3)[AXIS_TAGS.index(tag)]
            dofs.append(Dof(f"{mj_name(name)}_{kind}", name, axis, *np.radians(rng), kind))
    tips = tuple(n for n in names if n.endswith("-tip"))
    return Skeleton(
        name="handsim_default_hand",
        joints=tuple(joints),
        dofs=tuple(dofs),
        fingertips=tips,
        source=f"handsim parametric hand: length {length:.3f} m, breadth {breadth:.3f} m "
        "(proportions of Buchholz et al. 1992)",
    )


__all__ = [
    "DEFAULT_BREADTH_RATIO",
    "DEFAULT_HAND_LENGTH_M",
    "RANGES_DEG",
    "SEGMENT_RATIOS",
    "default_skeleton",
]
