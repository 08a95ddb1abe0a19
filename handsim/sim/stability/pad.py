"""A finger pad's force–penetration relation, measured the way the literature measures a fingertip's.

A fingertip's pulp stiffness is measured by pressing it on a rigid flat surface (Serina et al. 1997;
Pawluk & Howe 1999). :func:`pad_force_curve` does the same with a built hand: a fixed rigid sphere of
radius :data:`SURFACE_RADIUS` (flat on the pad's scale) is placed against a link's collision geom, along the
direction the link's joint moves it, so that it penetrates by each depth asked; the force is MuJoCo's static
soft-contact law for that contact,

    F = K · d(r) · r / R,   R = (1 − d(r)) / d(r) · Â,

with ``K`` and the impedance ``d(r)`` from the geom's ``solref``/``solimp`` and ``Â`` the contact's
approximate inverse effective mass (MuJoCo's ``efc_KBIP`` and ``efc_R``): the force at which that
penetration is at rest. MuJoCo scales a contact's stiffness with the effective mass of the bodies it
joins, so against a free light object the same penetration carries less force; ``docs/physics.md`` gives
the measured factor for the catalogue's objects.
"""

from __future__ import annotations

import mujoco
import numpy as np
import numpy.typing as npt

from handsim.errors import ModelError

SURFACE_RADIUS = 0.005
"""Radius of the rigid sphere the pad is pressed on, m: small, so that it touches no other link. MuJoCo's
contact force depends on the penetration depth alone, not on the contact's area or curvature."""


def _pad_geom(model: mujoco.MjModel, link: str) -> int:
    body = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, link)
    if body < 0:
        names = [model.body(i).name for i in range(1, model.nbody)]
        raise ModelError(f"the hand has no link {link!r}; its links are {names}")
    geoms = [g for g in range(model.ngeom) if model.geom_bodyid[g] == body and model.geom_contype[g]]
    if not geoms:
        raise ModelError(f"link {link!r} has no collision geom")
    return geoms[0]


def _press_direction(model: mujoco.MjModel, geom: int) -> np.ndarray:
    """The direction the geom's centre moves when its body's first joint turns (unit, world frame)."""
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    body = int(model.geom_bodyid[geom])
    joint = int(model.body_jntadr[body])
    if joint < 0:
        raise ModelError(f"link {model.body(body).name!r} has no joint to press its pad with")
    centre0 = data.geom_xpos[geom].copy()
    data.qpos[model.jnt_qposadr[joint]] += 1e-4
    mujoco.mj_kinematics(model, data)
    normal = data.geom_xpos[geom] - centre0
    return normal / np.linalg.norm(normal)


def _pressed(hand: mujoco.MjSpec, centre: np.ndarray) -> tuple[mujoco.MjModel, mujoco.MjData]:
    """The hand with the fixed sphere at ``centre``: a static body added last, so its geom is the last one."""
    spec = hand.copy()
    body = spec.worldbody.add_body(pos=centre.tolist())
    body.add_geom(type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[SURFACE_RADIUS, 0, 0])
    model = spec.compile()
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    return model, data


def pad_force_curve(hand: mujoco.MjSpec, link: str, depths: npt.ArrayLike) -> np.ndarray:
    """Static normal force of a link's collision geom pressed on a rigid surface, per penetration depth.

    Args:
        hand: A hand spec (:func:`handsim.builders.build_hand`), in its rest pose; not modified.
        link: The link (body name), e.g. ``"if_dip"`` for the index finger's distal phalanx.
        depths: Penetration depths into the collision geometry, m (> 0; ≥ 0 for a skin with a rest offset,
            :data:`handsim.builders.surfaces.FITTED_SKIN`, whose force counts from its rest surface).

    Returns:
        The forces, N, one per depth.

    Raises:
        ModelError: No such link, or it has no collision geom or no joint.
    """
    depths = np.asarray(depths, dtype=float)
    model = hand.copy().compile()
    geom = _pad_geom(model, link)
    normal = _press_direction(model, geom)
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    far = data.geom_xpos[geom] + normal * (model.geom_rbound[geom] + SURFACE_RADIUS + 0.01)
    clear, clear_data = _pressed(hand, far)
    gap = mujoco.mj_geomDistance(clear, clear_data, geom, clear.ngeom - 1, 1.0, None)
    forces = np.empty(depths.shape)
    for i, depth in enumerate(depths.ravel()):
        shift = gap + depth
        for _ in range(3):  # the contact normal is nearly the press direction: a few corrections
            pressed, state = _pressed(hand, far - normal * shift)
            row = _normal_row(pressed, state, geom)
            shift += depth + state.efc_pos[row]
        k, _, impedance, _ = state.efc_KBIP[row]
        violation = state.efc_pos[row] - state.efc_margin[row]  # from the skin's rest surface (margin)
        forces.flat[i] = k * impedance * -violation / state.efc_R[row]
    return forces


def _normal_row(model: mujoco.MjModel, data: mujoco.MjData, geom: int) -> int:
    surface = model.ngeom - 1
    for c in range(data.ncon):
        contact = data.contact[c]
        if {int(contact.geom1), int(contact.geom2)} == {geom, surface}:
            return int(contact.efc_address)
    raise ModelError("the pad does not touch the surface: the depth is too small")
