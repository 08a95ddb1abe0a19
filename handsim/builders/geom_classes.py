"""The default geom classes every handsim model shares: ``visual`` (group 2) and ``collision`` (group 3)."""

from __future__ import annotations

from collections.abc import Sequence

import mujoco

from handsim.builders.surfaces import CONTACT_CONDIM, Surface


def add_geom_classes(
    spec: mujoco.MjSpec,
    *,
    surface: Surface,
    visual_rgba: Sequence[float],
    collision_rgba: Sequence[float],
    density: float | None = None,
) -> tuple[mujoco.MjsDefault, mujoco.MjsDefault]:
    """Set the main class's contact parameters and add the ``visual`` and ``collision`` classes.

    Args:
        spec: The model being built.
        surface: The contact parameters of the collision geoms (:mod:`handsim.builders.surfaces`).
        visual_rgba: Colour of visual geoms.
        collision_rgba: Colour of collision geoms (group 3, hidden by default in viewers).
        density: Density of every geom in kg/m³ (0: mass comes from explicit inertials), or None to keep
            MuJoCo's default for collision geoms.

    Returns:
        The ``visual`` and ``collision`` default classes. Visual geoms never collide and weigh nothing.
    """
    main = spec.default
    main.geom.friction = surface.friction
    main.geom.condim = CONTACT_CONDIM
    if density is not None:
        main.geom.density = density
    visual = spec.add_default("visual", main)
    visual.geom.group = 2
    visual.geom.contype = 0
    visual.geom.conaffinity = 0
    visual.geom.density = 0
    visual.geom.rgba = list(visual_rgba)
    collision = spec.add_default("collision", main)
    collision.geom.group = 3
    collision.geom.rgba = list(collision_rgba)
    collision.geom.priority = surface.priority
    if surface.solref is not None:
        collision.geom.solref = list(surface.solref)
    if surface.solimp is not None:
        collision.geom.solimp = list(surface.solimp)
    if surface.margin:
        collision.geom.margin = surface.margin
    return visual, collision
