"""Compiling specs and describing the compiled model."""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from handsim.errors import ModelError


def compile_spec(spec: mujoco.MjSpec) -> mujoco.MjModel:
    """Compile ``spec``, turning MuJoCo's compile errors into :class:`ModelError`.

    Raises:
        ModelError: With MuJoCo's message and the model name.
    """
    try:
        return spec.compile()
    except ValueError as exc:  # MjSpec.compile raises ValueError with the compiler's message
        raise ModelError(f"model {spec.modelname!r} does not compile: {exc}") from exc


@dataclass(frozen=True)
class ModelSummary:
    """Counts and sizes of a compiled model.

    Attributes:
        name: Model name.
        bodies: Bodies, the world body excluded.
        dofs: Degrees of freedom (``nv``).
        joints: Joints.
        actuators: Actuators.
        geoms: Geoms; ``collision_geoms`` of them take part in contacts.
        collision_geoms: Geoms with non-zero contype or conaffinity.
        sites: Sites.
        mass: Total mass, kg.
        bbox_min: Lower corner of the axis-aligned bounding box of all geoms but planes at qpos0, metres.
        bbox_max: Upper corner, metres.
    """

    name: str
    bodies: int
    dofs: int
    joints: int
    actuators: int
    geoms: int
    collision_geoms: int
    sites: int
    mass: float
    bbox_min: np.ndarray
    bbox_max: np.ndarray

    def lines(self) -> list[str]:
        """Human-readable lines for the CLI."""
        size = (self.bbox_max - self.bbox_min) * 1000
        lo, hi = np.round(self.bbox_min, 4).tolist(), np.round(self.bbox_max, 4).tolist()
        return [
            f"model      {self.name}",
            f"bodies     {self.bodies}",
            f"DoFs       {self.dofs} ({self.joints} joints)",
            f"actuators  {self.actuators}",
            f"geoms      {self.geoms} ({self.collision_geoms} collision)",
            f"sites      {self.sites}",
            f"mass       {self.mass:.3f} kg",
            "bbox       " + " × ".join(f"{v:.1f}" for v in size) + f" mm  (min {lo} m, max {hi} m)",
        ]


def summarize(model: mujoco.MjModel) -> ModelSummary:
    """Summarise a compiled model (bounding box at the reference configuration ``qpos0``)."""
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    corners = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], dtype=float)
    points = []
    for g in range(model.ngeom):
        if model.geom_type[g] == mujoco.mjtGeom.mjGEOM_PLANE:
            continue  # an infinite floor has no extent
        mesh = model.geom_dataid[g] if model.geom_type[g] == mujoco.mjtGeom.mjGEOM_MESH else -1
        if mesh >= 0:  # the mesh's own vertices: tighter than its box in the (rotated) inertial frame
            start = model.mesh_vertadr[mesh]
            local = model.mesh_vert[start : start + model.mesh_vertnum[mesh]]
        else:
            center, half = model.geom_aabb[g, :3], model.geom_aabb[g, 3:]
            local = center + corners * half
        points.append(data.geom_xpos[g] + local @ data.geom_xmat[g].reshape(3, 3).T)
    allpts = np.vstack(points) if points else np.zeros((1, 3))
    collision = int(np.sum((model.geom_contype != 0) | (model.geom_conaffinity != 0)))
    name = bytes(model.names).split(b"\0", 1)[0].decode()
    return ModelSummary(
        name=name,
        bodies=model.nbody - 1,
        dofs=model.nv,
        joints=model.njnt,
        actuators=model.nu,
        geoms=model.ngeom,
        collision_geoms=collision,
        sites=model.nsite,
        mass=float(model.body_subtreemass[0]),
        bbox_min=allpts.min(axis=0),
        bbox_max=allpts.max(axis=0),
    )
