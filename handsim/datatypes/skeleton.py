"""The hand skeleton: joints, degrees of freedom, and forward kinematics.

Conventions (everything past the readers is SI):

* Positions in metres, angles in radians.
* A joint's *rest frame* is a 3x3 rotation whose columns are the joint's local x, y, z axes expressed in
  the skeleton frame, at the rest pose (all DoF angles zero).
* A DoF is a rotation about a unit axis fixed in its joint's local frame. The DoFs of one joint form a
  serial chain in the order they are listed: the first is the outermost (closest to the root). This is
  the same order in which MuJoCo applies the hinge joints of one body, so a hand built from a skeleton
  has exactly this kinematics.

Forward kinematics: for joint ``j`` with parent ``p``, rest position ``x`` and rest frame ``F``::

    R_j = R_p · (F_pᵀ F_j) · Π_k Rot(a_k, q_k)
    p_j = p_p + R_p · F_pᵀ (x_j − x_p)

which gives ``R_j = F_j`` and ``p_j = x_j`` at the rest pose.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
import numpy.typing as npt

from handsim.datatypes.rotations import rotation_about_axis
from handsim.errors import SkeletonError

_ORTHONORMAL_TOL = 1e-6


def mj_name(name: str) -> str:
    """Return ``name`` with every character other than letters, digits and ``_`` replaced by ``_``.

    This is the name a skeleton joint's site gets in a MuJoCo model (``"if-mcp"`` → ``"if_mcp"``,
    ``"RFing.0_Hand"`` → ``"RFing_0_Hand"``).

    Args:
        name: A skeleton joint or bone name.

    Returns:
        The sanitised name.
    """
    return re.sub(r"[^A-Za-z0-9_]", "_", name)


@dataclass(frozen=True)
class Dof:
    """One rotational degree of freedom of a joint.

    Attributes:
        name: Unique DoF name; the MuJoCo joint and the trajectory column carry this name.
        joint: Name of the skeleton joint it rotates.
        axis: Unit axis in the joint's local (rest) frame, shape (3,).
        lower: Lower limit in radians.
        upper: Upper limit in radians.
        kind: Anatomical role: ``"flex"`` (flexion/extension), ``"abd"`` (ab/adduction), ``"pron"``
            (pronation/axial rotation) or ``"rot"`` (any other rotation).
    """

    name: str
    joint: str
    axis: np.ndarray
    lower: float
    upper: float
    kind: str = "rot"


@dataclass(frozen=True)
class Joint:
    """A skeleton joint: the origin of the bone(s) that start at it.

    Attributes:
        name: Unique joint name as written in the source file.
        parent: Index of the parent joint in :attr:`Skeleton.joints`, ``-1`` for the root.
        position: Rest position in the skeleton frame, metres, shape (3,).
        frame: Rest local frame, shape (3, 3); columns are the local axes in the skeleton frame.
    """

    name: str
    parent: int
    position: np.ndarray
    frame: np.ndarray


@dataclass(frozen=True)
class SkinnedMesh:
    """A surface mesh bound to the skeleton by linear-blend-skinning weights, in the rest pose.

    Attributes:
        vertices: Rest-pose vertices in the skeleton frame, metres, shape (V, 3).
        faces: Triangle vertex indices, shape (F, 3).
        weights: Skinning weights, shape (V, B); rows sum to about 1.
        bones: Skeleton joint name of each weight column, length B.
    """

    vertices: np.ndarray
    faces: np.ndarray
    weights: np.ndarray
    bones: tuple[str, ...]


@dataclass(frozen=True)
class ForwardKinematics:
    """Result of :meth:`Skeleton.forward_kinematics`.

    Attributes:
        positions: Joint positions, metres, shape ``(..., njoints, 3)``.
        frames: Joint frames (columns = local axes), shape ``(..., njoints, 3, 3)``.
    """

    positions: np.ndarray
    frames: np.ndarray


@dataclass(frozen=True)
class Skeleton:
    """A kinematic tree of joints with rotational DoFs, in SI units.

    Joints are stored parents-first (a joint's parent always has a smaller index).

    Attributes:
        name: Human-readable name (usually the source file's stem).
        joints: Joints, parents first.
        dofs: DoFs; those of one joint are contiguous and ordered outermost first.
        fingertips: Names of the joints that are fingertip end effectors (thumb first where known).
        source: The file the skeleton was read from, or a description of how it was made.
        notes: Decisions and repairs made while reading, for the user to see.
        mesh: Optional skinned surface mesh (Tzionas ``.OFF`` + ``.SKIN``).
        fingertip_vertices: Optional vertex ids per finger at the fingertip (Tzionas ``.VOI``).
    """

    name: str
    joints: tuple[Joint, ...]
    dofs: tuple[Dof, ...]
    fingertips: tuple[str, ...] = ()
    source: str = ""
    notes: tuple[str, ...] = ()
    mesh: SkinnedMesh | None = None
    fingertip_vertices: tuple[tuple[int, ...], ...] | None = field(default=None)

    def __post_init__(self) -> None:
        names = [j.name for j in self.joints]
        if not names:
            raise SkeletonError(f"skeleton {self.name!r} has no joints")
        if len(set(names)) != len(names):
            dup = sorted({n for n in names if names.count(n) > 1})
            raise SkeletonError(f"skeleton {self.name!r}: duplicate joint names {dup}")
        for i, j in enumerate(self.joints):
            if i == 0 and j.parent != -1:
                raise SkeletonError(f"skeleton {self.name!r}: first joint {j.name!r} must be the root")
            if i > 0 and not 0 <= j.parent < i:
                raise SkeletonError(
                    f"skeleton {self.name!r}: joint {j.name!r} has parent index {j.parent}; "
                    f"parents must precede children"
                )
            if np.shape(j.position) != (3,) or not np.all(np.isfinite(j.position)):
                raise SkeletonError(f"joint {j.name!r}: position must be 3 finite numbers")
            f = np.asarray(j.frame)
            if f.shape != (3, 3) or not np.allclose(f.T @ f, np.eye(3), atol=_ORTHONORMAL_TOL):
                raise SkeletonError(f"joint {j.name!r}: frame must be a 3x3 rotation matrix")
            if np.linalg.det(f) < 0:
                raise SkeletonError(f"joint {j.name!r}: frame is a reflection (det < 0)")
        dof_names = [d.name for d in self.dofs]
        if len(set(dof_names)) != len(dof_names):
            dup = sorted({n for n in dof_names if dof_names.count(n) > 1})
            raise SkeletonError(f"skeleton {self.name!r}: duplicate DoF names {dup}")
        seen_joints: list[str] = []
        for d in self.dofs:
            if d.joint not in names:
                raise SkeletonError(f"DoF {d.name!r}: unknown joint {d.joint!r}; joints are {names}")
            if seen_joints and d.joint != seen_joints[-1] and d.joint in seen_joints:
                raise SkeletonError(f"DoFs of joint {d.joint!r} must be contiguous")
            seen_joints.append(d.joint)
            if not abs(np.linalg.norm(d.axis) - 1.0) < 1e-9:
                raise SkeletonError(f"DoF {d.name!r}: axis must be a unit vector, got {d.axis}")
            if not d.lower <= d.upper:
                raise SkeletonError(f"DoF {d.name!r}: lower limit {d.lower} > upper limit {d.upper}")
        for t in self.fingertips:
            if t not in names:
                raise SkeletonError(f"fingertip {t!r} is not a joint; joints are {names}")

    # ----------------------------------------------------------------------------------------------
    # Lookups

    @cached_property
    def joint_names(self) -> tuple[str, ...]:
        """Joint names in storage order."""
        return tuple(j.name for j in self.joints)

    @cached_property
    def dof_names(self) -> tuple[str, ...]:
        """DoF names in storage order (the order of a trajectory's columns)."""
        return tuple(d.name for d in self.dofs)

    @property
    def njoints(self) -> int:
        """Number of joints."""
        return len(self.joints)

    @property
    def ndof(self) -> int:
        """Number of DoFs."""
        return len(self.dofs)

    def joint_index(self, name: str) -> int:
        """Index of the joint called ``name``.

        Raises:
            SkeletonError: If there is no such joint; the message lists the valid names.
        """
        return self._lookup("joint", self.joint_names, name)

    def dof_index(self, name: str) -> int:
        """Index of the DoF called ``name``.

        Raises:
            SkeletonError: If there is no such DoF; the message lists the valid names.
        """
        return self._lookup("DoF", self.dof_names, name)

    def _lookup(self, kind: str, names: tuple[str, ...], name: str) -> int:
        try:
            return names.index(name)
        except ValueError:
            raise SkeletonError(
                f"skeleton {self.name!r} has no {kind} {name!r}; {kind}s are {list(names)}"
            ) from None

    def children(self, index: int) -> list[int]:
        """Indices of the direct children of joint ``index``."""
        return [i for i, j in enumerate(self.joints) if j.parent == index]

    def dofs_of(self, joint: str) -> list[Dof]:
        """The DoFs of ``joint``, outermost first."""
        return [d for d in self.dofs if d.joint == joint]

    @cached_property
    def rest_positions(self) -> np.ndarray:
        """Rest positions of all joints, metres, shape (njoints, 3)."""
        return np.array([j.position for j in self.joints], dtype=float)

    def bone_length(self, index: int) -> float:
        """Length of the bone from joint ``index``'s parent to it, metres (0 for the root)."""
        parent = self.joints[index].parent
        if parent < 0:
            return 0.0
        return float(np.linalg.norm(self.rest_positions[index] - self.rest_positions[parent]))

    @cached_property
    def limits(self) -> np.ndarray:
        """DoF limits in radians, shape (ndof, 2)."""
        return np.array([[d.lower, d.upper] for d in self.dofs], dtype=float).reshape(-1, 2)

    @cached_property
    def hand_length(self) -> float:
        """Largest rest distance from the root to a fingertip (or any joint), metres."""
        tips = [self.joint_index(t) for t in self.fingertips] or list(range(self.njoints))
        d = np.linalg.norm(self.rest_positions[tips] - self.rest_positions[0], axis=1)
        return float(d.max())

    # ----------------------------------------------------------------------------------------------
    # Kinematics

    def forward_kinematics(self, q: npt.ArrayLike) -> ForwardKinematics:
        """Joint positions and frames for DoF angles ``q``.

        Limits are not applied: angles outside them are used as given.

        Args:
            q: DoF angles in radians, shape (ndof,) or (T, ndof), columns in :attr:`dof_names` order.

        Returns:
            Positions ``(…, njoints, 3)`` in metres and frames ``(…, njoints, 3, 3)`` in the skeleton
            frame (root at its rest position, not moved).

        Raises:
            SkeletonError: If ``q`` has the wrong number of columns.
        """
        qa = np.asarray(q, dtype=float)
        if qa.shape[-1:] != (self.ndof,) or qa.ndim not in (1, 2):
            raise SkeletonError(
                f"forward_kinematics expects angles of shape ({self.ndof},) or (T, {self.ndof}), "
                f"got {qa.shape}"
            )
        batch = qa.shape[:-1]
        positions = np.empty((*batch, self.njoints, 3))
        frames = np.empty((*batch, self.njoints, 3, 3))
        dof_cols = {name: i for i, name in enumerate(self.dof_names)}
        for i, joint in enumerate(self.joints):
            local = np.broadcast_to(np.eye(3), (*batch, 3, 3))
            for dof in self.dofs_of(joint.name):
                local = local @ rotation_about_axis(dof.axis, qa[..., dof_cols[dof.name]])
            if joint.parent < 0:
                positions[..., i, :] = joint.position
                frames[..., i, :, :] = joint.frame @ local
                continue
            parent = self.joints[joint.parent]
            r_parent = frames[..., joint.parent, :, :]
            rel_rot = parent.frame.T @ joint.frame
            rel_pos = parent.frame.T @ (joint.position - parent.position)
            frames[..., i, :, :] = r_parent @ rel_rot @ local
            positions[..., i, :] = positions[..., joint.parent, :] + r_parent @ rel_pos
        return ForwardKinematics(positions=positions, frames=frames)

    def zero_pose(self) -> np.ndarray:
        """All-zero DoF angles (the rest pose), shape (ndof,)."""
        return np.zeros(self.ndof)
