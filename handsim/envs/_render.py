"""Headless rendering for the environments: MuJoCo's offscreen renderer, never a window.

The backend choice and the renderer itself are :mod:`handsim.viz.headless`'s; this module adds the cameras and
a renderer that is created on first use and dropped when pickled.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import mujoco

from handsim.errors import RenderError
from handsim.viz.headless import offscreen_renderer

__all__ = ["OffscreenRenderer", "RenderError", "camera_id"]

if TYPE_CHECKING:
    import numpy as np


def camera_id(model: mujoco.MjModel, camera: str | None) -> int:
    """Id of a named camera of ``model``; None is MuJoCo's free camera (-1).

    Raises:
        ValueError: No camera of that name; the message lists the model's cameras.
    """
    if camera is None:
        return -1
    cam = int(mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_CAMERA, camera))
    if cam < 0:
        names = [model.camera(i).name for i in range(model.ncam)]
        raise ValueError(f"unknown camera {camera!r}; the scene's cameras are {names} (or None: free camera)")
    return cam


class OffscreenRenderer:
    """RGB frames of a scene from one camera through :class:`mujoco.Renderer`, created on first use.

    Picklable: the GL context is not pickled; a copy creates its own on its first frame.

    Args:
        model: The model (only checked here: the offscreen buffer must hold ``width`` × ``height``).
        width: Image width, pixels.
        height: Image height, pixels.
        camera: A camera name of the model, or None for the free camera.

    Raises:
        ValueError: Non-positive size, a size larger than the model's offscreen buffer, or an unknown camera.
    """

    def __init__(self, model: mujoco.MjModel, width: int, height: int, camera: str | None) -> None:
        width, height = int(width), int(height)
        if width < 1 or height < 1:
            raise ValueError(f"width and height must be ≥ 1 pixel, got {width} × {height}")
        buffer = (int(model.vis.global_.offwidth), int(model.vis.global_.offheight))
        if width > buffer[0] or height > buffer[1]:
            raise ValueError(
                f"image {width} × {height} is larger than the scene's offscreen buffer "
                f"{buffer[0]} × {buffer[1]} (visual/global offwidth, offheight)"
            )
        self.width, self.height = width, height
        self.camera = camera
        self._camera_id = camera_id(model, camera)
        self._renderer: mujoco.Renderer | None = None

    def render(self, model: mujoco.MjModel, data: mujoco.MjData) -> np.ndarray:
        """The current frame, (height, width, 3) uint8.

        Raises:
            RenderError: No OpenGL context could be created.
        """
        if self._renderer is None:
            self._renderer = offscreen_renderer(model, self.width, self.height)
        self._renderer.update_scene(data, camera=self._camera_id)
        return self._renderer.render()

    def close(self) -> None:
        """Free the GL context (idempotent)."""
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None

    def __getstate__(self) -> dict:
        state = self.__dict__.copy()
        state["_renderer"] = None
        return state
