"""Collision geometry and mass distribution of a hand, computed from its skeleton (no MuJoCo here).

* Each bone (joint → child) becomes a capsule. Its radius is an anthropometric fraction of the hand
  breadth, reduced where needed so that capsules of different fingers do not touch in the rest pose.
* The palm is the convex hull of the root, the joints rigidly attached to it, the base of the thumb and
  the carpometacarpal and metacarpophalangeal joints of the other fingers, thickened along the palm
  normal. The metacarpals of the fingers lie inside it and get no capsule (a small palm-arch DoF of a
  metacarpal, as in the Tzionas hand, then moves the finger but not that part of the palm); the thumb's
  metacarpal does get one. Fingertips are listed thumb first.
* The whole-hand mass is split over the collision shapes in proportion to their volumes.

Anthropometric constants: hand mass 0.6 % of body mass (Winter, *Biomechanics and Motor Control of
Human Movement*, 4th ed., 2009, Table 4.1; 0.45 kg for a 75 kg adult whose hand is 0.19 m long, scaled
with the cube of hand length); finger breadths ≈ 0.19–0.24 × hand breadth at the proximal phalanx
(Garrett, "The adult human hand: some anthropometric and biomechanical considerations", Human Factors
13(2), 1971); palm thickness ≈ 0.33 × hand breadth.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.spatial import ConvexHull, QhullError

from handsim.datatypes.skeleton import Skeleton

REFERENCE_HAND_LENGTH_M = 0.19
REFERENCE_HAND_MASS_KG = 0.45
BREADTH_TO_LENGTH = 0.45  # typical adult hand breadth / hand length
PALM_THICKNESS_TO_BREADTH = 0.33
# Capsule radius / hand breadth, by position of the bone along its finger (proximal first).
FINGER_RADIUS_TO_BREADTH = (0.11, 0.10, 0.09)
THUMB_RADIUS_TO_BREADTH = (0.13, 0.12, 0.11)
REST_CLEARANCE = 0.92  # capsules of different fingers keep this fraction of half their rest distance


@dataclass(frozen=True)
class Capsule:
    """A bone capsule in the skeleton frame.

    Attributes:
        joint: Index of the joint whose body carries it (the bone's proximal joint).
        child: Index of the bone's distal joint.
        start: Proximal end, skeleton frame, metres.
        end: Distal end, skeleton frame, metres.
        radius: Radius in metres.
        collides: False for a finger metacarpal that has a DoF: it lies inside the palm, so it only
            carries the link's mass.
    """

    joint: int
    child: int
    start: np.ndarray
    end: np.ndarray
    radius: float
    collides: bool = True

    @property
    def volume(self) -> float:
        """Volume in m³."""
        length = float(np.linalg.norm(self.end - self.start))
        return math.pi * self.radius**2 * length + 4.0 / 3.0 * math.pi * self.radius**3


@dataclass(frozen=True)
class HandGeometry:
    """Collision shapes of a hand in the skeleton frame.

    Attributes:
        capsules: One per bone outside the palm.
        palm_vertices: Vertices of the convex palm (skeleton frame), shape (N, 3); empty if none.
        palm_volume: Volume of the palm hull, m³.
        rigid_to_root: Indices of joints rigidly attached to the root (no DoF on the path), root included.
        palm_links: Indices of the first two joints of every finger chain (metacarpal and proximal
            phalanx bodies), which touch the palm by construction.
        breadth: Hand breadth used for sizing, metres.
    """

    capsules: tuple[Capsule, ...]
    palm_vertices: np.ndarray
    palm_volume: float
    rigid_to_root: frozenset[int]
    palm_links: frozenset[int]
    breadth: float


def default_hand_mass(hand_length: float) -> float:
    """Anthropometric whole-hand mass (kg) for a hand of ``hand_length`` metres."""
    return REFERENCE_HAND_MASS_KG * (hand_length / REFERENCE_HAND_LENGTH_M) ** 3


def rigid_to_root(skeleton: Skeleton) -> frozenset[int]:
    """Joints connected to the root without any DoF in between (the root included)."""
    has_dof = {d.joint for d in skeleton.dofs}
    rigid = {0}
    for i, j in enumerate(skeleton.joints[1:], start=1):
        if j.parent in rigid and j.name not in has_dof:
            rigid.add(i)
    return frozenset(rigid)


def finger_chains(skeleton: Skeleton) -> list[list[int]]:
    """Each fingertip's chain of joints from the first joint after the root to the tip."""
    chains = []
    for tip in skeleton.fingertips:
        chain = [skeleton.joint_index(tip)]
        while skeleton.joints[chain[-1]].parent > 0:
            chain.append(skeleton.joints[chain[-1]].parent)
        chains.append(chain[::-1])
    return chains


def estimate_breadth(skeleton: Skeleton) -> float:
    """Hand breadth (m): spread of the finger bases (widened by one finger) or 0.45 × hand length."""
    chains = finger_chains(skeleton)
    length_based = BREADTH_TO_LENGTH * skeleton.hand_length
    if len(chains) < 4:
        return length_based
    rigid = rigid_to_root(skeleton)
    bases = []
    for chain in chains:
        first_moving = next((i for i in chain if i not in rigid), chain[-1])
        bases.append(skeleton.rest_positions[first_moving])
    bases_arr = np.array(bases[1:])  # without the thumb-most chain, which starts far from the others
    spread = float(np.max(np.linalg.norm(bases_arr[:, None] - bases_arr[None], axis=-1)))
    across = spread * len(bases_arr) / max(len(bases_arr) - 1, 1)
    return across if 0.5 * length_based < across < 1.5 * length_based else length_based


def _segment_distance(a0: np.ndarray, a1: np.ndarray, b0: np.ndarray, b1: np.ndarray) -> float:
    s = np.linspace(0.0, 1.0, 16)
    pa = a0 + s[:, None] * (a1 - a0)
    pb = b0 + s[:, None] * (b1 - b0)
    return float(np.min(np.linalg.norm(pa[:, None] - pb[None], axis=-1)))


def _palm(skeleton: Skeleton, chains: list[list[int]], breadth: float) -> tuple[np.ndarray, float]:
    idx = set(rigid_to_root(skeleton))
    for f, chain in enumerate(chains):
        idx.update(chain[:1] if f == 0 else chain[:2])
    points = skeleton.rest_positions[sorted(idx)]
    if len(points) < 3:
        return np.zeros((0, 3)), 0.0
    centred = points - points.mean(axis=0)
    normal = np.linalg.svd(centred)[2][-1]
    half = 0.5 * PALM_THICKNESS_TO_BREADTH * breadth
    vertices = np.vstack([points + half * normal, points - half * normal])
    try:
        hull = ConvexHull(vertices)
    except QhullError:
        return np.zeros((0, 3)), 0.0
    return vertices[hull.vertices], float(hull.volume)


def hand_geometry(skeleton: Skeleton, breadth: float | None = None) -> HandGeometry:
    """Capsules and palm of a hand built from ``skeleton``.

    Args:
        skeleton: The hand skeleton.
        breadth: Hand breadth in metres; estimated from the skeleton when None.

    Returns:
        The collision shapes in the skeleton frame.
    """
    b = estimate_breadth(skeleton) if breadth is None else breadth
    chains = finger_chains(skeleton)
    finger_of = {i: f for f, chain in enumerate(chains) for i in chain}
    thumb = 0 if chains else -1  # fingertips are listed thumb first
    pos = skeleton.rest_positions
    bones = []
    capsules = []
    rigid = rigid_to_root(skeleton)
    for f, chain in enumerate(chains):
        first = 0 if f == thumb else 1  # finger metacarpals lie inside the palm
        table = THUMB_RADIUS_TO_BREADTH if f == thumb else FINGER_RADIUS_TO_BREADTH
        for k, (i, child) in enumerate(zip(chain[first:-1], chain[first + 1 :], strict=True)):
            bones.append((i, child, table[min(k, len(table) - 1)] * b))
        if first == 1 and chain[0] not in rigid and len(chain) > 1:
            i, child = chain[0], chain[1]
            capsules.append(Capsule(i, child, pos[i].copy(), pos[child].copy(), table[0] * b, collides=False))
    for i, child, radius in bones:
        r = radius
        for j, other_child, other_radius in bones:
            if finger_of.get(j) == finger_of.get(i):
                continue
            gap = _segment_distance(pos[i], pos[child], pos[j], pos[other_child])
            r = min(r, REST_CLEARANCE * gap * radius / (radius + other_radius))
        capsules.append(Capsule(i, child, pos[i].copy(), pos[child].copy(), r))
    palm_vertices, palm_volume = _palm(skeleton, chains, b)
    palm_links = frozenset(i for chain in chains for i in chain[:2])
    return HandGeometry(tuple(capsules), palm_vertices, palm_volume, rigid, palm_links, b)
